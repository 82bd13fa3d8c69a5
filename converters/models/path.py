"""A model's problems along one of its parameters: what a branch of periodic orbits, a brute-force diagram and a
sweep of steady states are computed on."""
from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ..errors import ParameterError
from .base import Model

if TYPE_CHECKING:
    from ..problems import LCSProblem
    from ..problems.mechanical import MechanicalProblem


def check_no_step(model: Model, p: dict) -> None:
    """A periodic orbit (a steady state, a branch of orbits) is no answer for a run with a load or input step."""
    if model.step_times(p):
        raise ParameterError("a periodic steady state (--steady, gdcm, bifurcation, compare's start on the orbit) "
                             "needs a periodic circuit; a run with a step (t_step, a switch driven by a PWL or PULSE "
                             "that does not repeat, or a PWL source in the power circuit) is not periodic: run "
                             "--periods N (or --t-end) from rest")


@dataclass(frozen=True)
class ParameterPath:
    """A model's problems along one of its parameters (picklable: workers rebuild each problem).

    ``path(value)`` is the problem over one switching (or forcing) period from the model's start state (an
    autonomous model: over its time unit), with every other parameter as in ``params``; each value is
    validated against the parameter's range."""

    model: Model
    params: dict
    name: str

    def __post_init__(self) -> None:
        # a netlist's names are case-insensitive (Model.parameter_name); a mechanical model's are as typed
        object.__setattr__(self, "name", getattr(self.model, "parameter_name", str)(self.name))
        known = [p.name for p in self.model.parameters]
        if self.name not in known:
            raise ParameterError(f"unknown parameter {self.name!r} for {self.model.key}; valid names: {', '.join(known)}")
        if getattr(self.model, "step_times", None) is not None:       # the path's orbits are periodic ones
            check_no_step(self.model, self.model.resolve(self.params))

    def resolve(self, value: float | str) -> dict:
        return self.model.resolve({**self.params, self.name: value})

    def __call__(self, value: float | str) -> LCSProblem | MechanicalProblem:
        p = self.resolve(value)
        span = self.model.period(p)
        if not np.isfinite(span):                     # an autonomous model: one of its own time units
            span = self.model.time_scale(p)      # type: ignore[attr-defined]  # a netlist's, a mechanical model's
        return self.model.problem(p, span)
