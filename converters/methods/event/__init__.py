"""Exact event-driven simulation of piecewise-linear LCS with any number of complementarity pairs (and,
through :mod:`.mechanical`, of mechanical problems with friction and impacts).

Between events the LCS is linear with constant inputs. A *mode* is a configuration and a held set J
of pairs (y_J = 0, u_J free to be positive; every other pair has u = 0 and y free to be positive).
On J the multipliers follow from keeping y_J at zero: with R, N orthonormal bases of the range and
the left null space of D_JJ,

    R^T (D_JJ u_J + C_J x + F_J) = 0        (pairs whose y depends on u: algebraic)
    N^T C_J (A x + B_J u_J + E) = 0         (pairs whose y is a function of the state: y' = 0)

solved for u_J = U x + u0 (least norm), so the flow is x' = (A + B_J U) x + E + B_J u0; the state
stays on N^T (C_J x + F_J) = 0 (the GDCM flow of one pair is the case J = {i}, D_ii = 0). In
augmented form x~ = [x; 1], x(t0 + tau) = expm(tau Z) x~, exact up to rounding.

A mode ends when a watched quantity crosses zero downwards: y_i of a free pair, u_i of a held pair,
and under a state-driven law (:class:`~converters.problems.switching.StateSwitching`) the distance
of the switching function to the level that ends the configuration (band - s, or s + band; a ramp
adds a term linear in time). Sign changes are looked for on samples at most ``sample_fraction`` T
apart (and 0.25 / ||Z|| apart); the crossing is located by Brent's method on the watched quantity's
Taylor polynomial (exact to rounding) to ``event_tol`` T. Time-driven configuration changes happen at
the schedule's instants; ramp resets are such instants too.

At every event the new mode is the solution of the mode-selection LCP, resolved lexicographically:
the held sets J are tried nearest to the pair that triggered the event first, and J is taken when,
along its flow, every watched quantity's first non-vanishing derivative (value, first, second, ...)
is positive. A state entering a configuration with y_K < 0 on pairs whose y is a function of the
state takes Moreau's impulse x+ = x + B_K lambda, 0 <= lambda _|_ C_K (x + B_K lambda) + F_K >= 0.

Jacobians (period maps, Floquet multipliers): the state-transition matrix of each segment is
expm(tau Z) restricted to x; at an event triggered by g(x, t) = 0 the saltation matrix
S = I + (f+ - f-) n^T / (n^T f- + dg/dt) (n the gradient of g) carries the change of vector field;
an impulse contributes I - B_K (C_K B_K)^-1 C_K.

Integrals over a run (means, RMS) use 8-point Gauss-Legendre quadrature on pieces no longer than 2 / |Z|
(the flow's norm): exact to rounding for these exponential pieces, read a block of pieces at a time.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np
import numpy.typing as npt

from ...errors import ParameterError
from ...problems import LCSProblem, StateSwitching
from ...problems.mechanical import MechanicalProblem
from ...trajectory import Trajectory
from ...validate import check_positive, parse_value
from . import machine as lcs_engine
from . import mechanical as event_mechanical
from ..base import ErrorKind, Method, PeriodMap
from .machine import _Machine
from .maps import EventReturnMap


class _Engine(Protocol):
    """An engine module's entry points (each takes the problems of its own type: Any here)."""

    def supports(self, problem: Any, options: EventDriven) -> None: ...

    def solve(self, problem: Any, options: EventDriven, x0: npt.NDArray[np.float64]) -> Trajectory: ...

    def period_map(self, problem: Any, options: EventDriven) -> PeriodMap: ...


#: One engine per problem type (as Siconos has one integrator per dynamical-system type), each a module with
#: ``supports``, ``solve`` and ``period_map`` over the core (:mod:`.core`): the exact flows of an LCS, and DOP853
#: between the events of a mechanical problem with friction and impacts.
ENGINES: tuple[tuple[type, _Engine], ...] = ((MechanicalProblem, event_mechanical), (LCSProblem, lcs_engine))


def _engine(problem: object) -> _Engine:
    for kind, engine in ENGINES:
        if isinstance(problem, kind):
            return engine
    raise ParameterError(f"the event-driven method solves an LCSProblem or a MechanicalProblem; got "
                         f"{type(problem).__name__}")


@dataclass(frozen=True)
class EventDriven(Method, key="event"):
    """The exact event-driven method for piecewise-linear LCS (module docstring).

    Parameters
    ----------
    event_tol : float
        Events are located to ``event_tol`` times the switching period (Brent's method on the exact
        flow). Default 1e-13.
    sample_fraction : float
        Watched quantities are sampled at most ``sample_fraction`` T apart when looking for sign
        changes (two crossings closer than that could be missed). Default 1/32.
    output_step : float or None
        Spacing of the output samples in s (events are always added); None: T/1000.
    max_events : int
        Refuse runs with more events than this (Zeno behaviour). Default 10^7.
    ode_rtol : float
        Mechanical (nonlinear) problems only: the relative tolerance of the DOP853 integration of each smooth
        phase (:mod:`.mechanical`; the LCS flows are exact). Default 1e-9 (event times within 1e-9 s of
        those at 1e-10 on the friction oscillator, measured).
    chatter_fraction : float
        Mechanical problems with impacts: a chattering sequence whose remaining accumulation time is below this
        fraction of the time scale (or whose bounces rise less than 1e-12 of the state) is completed in closed
        form, exactly for a constant relative acceleration. Default 1e-6.
    """

    counts = "segments"
    error_kind = ErrorKind.EXACT

    event_tol: float = 1e-13
    sample_fraction: float = 1.0 / 32.0
    output_step: float | None = None
    max_events: int = 10_000_000
    ode_rtol: float = 1e-9
    chatter_fraction: float = 1e-6
    step_option = "output_step"
    description = "exact event-driven: matrix exponentials per mode, events by root finding, any number of pairs"
    domains = ("lcs", "mechanical")

    def __post_init__(self) -> None:
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
        for name, low, high in (("ode_rtol", 1e-14, 1e-3), ("chatter_fraction", 0.0, 1e-3)):
            value = parse_value(name, getattr(self, name))
            if not low <= value <= high:
                raise ParameterError(f"{name} must be in [{low:g}, {high:g}]; got {value!r}")
            object.__setattr__(self, name, value)

    @property
    def order(self) -> float:
        return math.inf

    def supports(self, problem: LCSProblem | MechanicalProblem) -> None:
        _engine(problem).supports(problem, self)

    def solve(self, problem: LCSProblem | MechanicalProblem, x0: np.ndarray) -> Trajectory:
        return _engine(problem).solve(problem, self, x0)

    def period_map(self, problem: LCSProblem | MechanicalProblem) -> PeriodMap:
        """The exact map over ``problem.t_span`` with its exact Jacobian (state-transition matrices and
        saltation matrices)."""
        self.supports(problem)
        return _engine(problem).period_map(problem, self)

    def engine(self, problem: LCSProblem) -> _Machine:
        """The LCS engine of ``problem``: its modes' flows (``flow(config, held)``), its switching law's guard rows
        (``switch_row``), Moreau's impulse (``enter``), its runs (``run``) and ``timeline(x0)``: the run as typed
        records (:mod:`.timeline`), what a linearisation about it reads (:mod:`converters.analysis.smallsignal`)."""
        self.supports(problem)
        if not isinstance(problem, LCSProblem):
            raise ParameterError(f"the LCS engine takes an LCSProblem; got {type(problem).__name__}")
        return _Machine(problem, self)

    def return_map(self, problem: LCSProblem, config: int, crossings: int = 1) -> PeriodMap:
        """For autonomous state-switched problems: x (at a switching into ``config``) -> x at the
        ``crossings``-th next switching into ``config``, with its exact Jacobian; ``period`` of the map is
        the return time of its last call (a Poincare map: the section is the switching surface)."""
        self.supports(problem)
        if not isinstance(problem.switching, StateSwitching):
            raise ParameterError("a return map needs one state-driven switching law (a StateSwitching); several "
                                 "comparators without a clock each cycle on their own, with no common section: "
                                 "run a transient")
        return EventReturnMap(_Machine(problem, self), config, crossings)


