"""Time-stepping methods: validated option holders, separate from the problem they solve."""
from __future__ import annotations

from dataclasses import dataclass

from .errors import ParameterError
from .validate import check_positive, parse_value


@dataclass(frozen=True)
class Theta:
    """The theta-method (Moreau): x_{k+1} = x_k + h [theta f(x_{k+1}) + (1 - theta) f(x_k)] + h B u_{k+1}.

    The complementarity multiplier u is taken fully implicitly (an impulse over the step), so
    each step is one LCP(q, M) with M = D + h C W B, W = (I - h theta A)^-1.

    Parameters
    ----------
    h : float
        Step size in s (> 0). Steps are split at the schedule's switching instants.
    theta : float
        In [0.5, 1]: 1 is backward Euler (order 1, L-stable), 0.5 the trapezoidal rule (order 2
        on smooth stretches).
    """

    h: float
    theta: float = 0.5

    def __post_init__(self):
        object.__setattr__(self, "h", check_positive("h", self.h, "s"))
        theta = parse_value("theta", self.theta)
        if not 0.5 <= theta <= 1.0:
            raise ParameterError(f"theta must be in [0.5, 1]; got {theta!r}")
        object.__setattr__(self, "theta", theta)

    @property
    def name(self) -> str:
        return "backward-euler" if self.theta == 1.0 else f"theta({self.theta:g})"


def BackwardEuler(h: float) -> Theta:
    """Backward Euler, the seed's Algorithm 1: ``Theta(h, theta=1)``."""
    return Theta(h=h, theta=1.0)
