"""The event method's period map and return map of an LCS (exact, with exact Jacobians)."""
from __future__ import annotations

import math

from ..base import PeriodMap
from .machine import _Machine


class EventReturnMap(PeriodMap):
    """x -> x at the ``crossings``-th next switching into ``config`` (exact, with the exact Jacobian of
    the Poincare map). ``period`` holds the return time of the last evaluation."""

    def __init__(self, machine: _Machine, config: int, crossings: int):
        super().__init__()
        self.machine, self.config, self.crossings = machine, config, crossings
        self.period = math.nan

    def _run(self, x0, jacobian):
        self.evaluations += 1
        solution, jac, stop = self.machine.run(x0, record=False, jacobian=jacobian, stop_config=self.config,
                                               stop_count=self.crossings)
        self.period = stop - self.machine.problem.t_span[0]
        return solution.x_end, jac

    def end(self, x0):
        return self._run(x0, False)[0]

    def __call__(self, x0):
        return self._run(x0, True)
