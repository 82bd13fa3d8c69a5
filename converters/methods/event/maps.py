"""The event method's period map and return map of an LCS (exact, with exact Jacobians)."""
from __future__ import annotations

import math
from typing import Literal, cast, overload

import numpy as np
import numpy.typing as npt

from ..base import PeriodMap
from .machine import _Machine


class EventReturnMap(PeriodMap):
    """x -> x at the ``crossings``-th next switching into ``config`` (exact, with the exact Jacobian of
    the Poincare map). ``period`` holds the return time of the last evaluation."""

    def __init__(self, machine: _Machine, config: int, crossings: int) -> None:
        super().__init__()
        self.machine, self.config, self.crossings = machine, config, crossings
        self.period = math.nan

    @overload                  # the Jacobian is there when it is asked for
    def _run(self, x0: npt.NDArray[np.float64],
             jacobian: Literal[True]) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]: ...
    @overload
    def _run(self, x0: npt.NDArray[np.float64],
             jacobian: bool) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64] | None]: ...

    def _run(self, x0: npt.NDArray[np.float64],
             jacobian: bool) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64] | None]:
        self.evaluations += 1
        solution, jac, stop = self.machine.run(x0, record=False, jacobian=jacobian, stop_config=self.config,
                                               stop_count=self.crossings)
        self.period = cast(float, stop) - self.machine.problem.t_span[0]       # a stop_config's run stops or raises
        return solution.x_end, jac

    def end(self, x0: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
        return self._run(x0, False)[0]

    def __call__(self, x0: npt.NDArray[np.float64]) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
        return self._run(x0, True)
