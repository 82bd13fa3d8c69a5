"""Time-stepping methods: validated option holders, separate from the problem they solve."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

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


@dataclass(frozen=True)
class EventDriven:
    """The exact event-driven method (:mod:`converters.event`) for LCS with one complementarity pair.

    Parameters
    ----------
    event_tol : float
        Events (zero crossings of the watched complementarity variable) are located to
        ``event_tol`` times the switching period (Brent's method on the exact flow). Default 1e-13.
    sample_fraction : float
        The watched variable is sampled at most ``sample_fraction`` T apart when looking for sign
        changes (two crossings closer than that could be missed). Default 1/32.
    output_step : float or None
        Spacing of the output samples in s (events are always added); None: T/1000.
    max_events : int
        Refuse runs with more events than this (Zeno behaviour). Default 10^7.
    """

    event_tol: float = 1e-13
    sample_fraction: float = 1.0 / 32.0
    output_step: float | None = None
    max_events: int = 10_000_000

    def __post_init__(self):
        tol = parse_value("event_tol", self.event_tol)
        if not 0.0 < tol <= 1e-2:
            raise ParameterError(f"event_tol must be in (0, 1e-2] (fraction of the period); got {tol!r}")
        object.__setattr__(self, "event_tol", tol)
        frac = parse_value("sample_fraction", self.sample_fraction)
        if not 0.0 < frac <= 1.0:
            raise ParameterError(f"sample_fraction must be in (0, 1]; got {frac!r}")
        object.__setattr__(self, "sample_fraction", frac)
        if self.output_step is not None:
            object.__setattr__(self, "output_step", check_positive("output_step", self.output_step, "s"))
        if not (isinstance(self.max_events, (int, np.integer)) and self.max_events >= 1):
            raise ParameterError(f"max_events must be an integer >= 1; got {self.max_events!r}")

    @property
    def name(self) -> str:
        return "event"


@dataclass(frozen=True)
class Smoothing:
    """The ideal diode replaced by a smooth law (:mod:`converters.smoothing`), integrated by a stiff solver.

    The complementarity pair 0 <= u _|_ y >= 0 becomes u = eps log(1 + exp(-y / eps^2)) (SI units,
    V or A): the penalty max(0, -y) / eps with its corner rounded over |y| ~ eps^2, exponential like
    a real diode's law. A held pair sits at y ~ -eps u, a free one carries u ~ eps exp(-y / eps^2).

    Parameters
    ----------
    eps : float
        Smoothing width in the units of y (> 0; smaller is closer to the ideal diode and stiffer).
    rtol, atol : float
        Tolerances of scipy's solve_ivp (atol default 1e-3 rtol).
    solver : str
        A stiff solve_ivp method: 'Radau', 'BDF' or 'LSODA'.
    output_step : float or None
        Spacing of the output samples (s); None: the solver's own steps.
    """

    eps: float = 1e-4
    rtol: float = 1e-6
    atol: float | None = None
    solver: str = "Radau"
    output_step: float | None = None

    def __post_init__(self):
        object.__setattr__(self, "eps", check_positive("eps", self.eps))
        rtol = parse_value("rtol", self.rtol)
        if not 1e-13 <= rtol <= 0.1:
            raise ParameterError(f"rtol must be in [1e-13, 0.1]; got {rtol!r}")
        object.__setattr__(self, "rtol", rtol)
        if self.atol is not None:
            object.__setattr__(self, "atol", check_positive("atol", self.atol))
        if self.solver not in ("Radau", "BDF", "LSODA"):
            raise ParameterError(f"solver must be one of Radau, BDF, LSODA; got {self.solver!r}")
        if self.output_step is not None:
            object.__setattr__(self, "output_step", check_positive("output_step", self.output_step, "s"))

    @property
    def name(self) -> str:
        return f"smooth({self.eps:g})"
