"""A family of periodic orbits along a parameter path: its orbits, their test functions and bifurcations, the
branches they form."""
from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt

from ...errors import ParameterError
from ..periodic import PeriodicOrbit, multipliers_of, newton_orbit

if TYPE_CHECKING:
    import pandas as pd

    from ...methods.base import Method, PeriodMap

KINDS = ("period-doubling", "fold", "neimark-sacker", "border-collision", "grazing-sliding", "crossing-sliding",
         "switching-sliding", "adding-sliding")
TEST_NAMES = {"period-doubling": "det(J + I)", "fold": "det(J - I)",
              "neimark-sacker": "max |mu| - 1 over the complex pairs"}


def test_functions(jacobian: np.ndarray, multipliers: np.ndarray) -> dict:
    """The bifurcation test functions of one orbit (None where one does not apply)."""
    n = jacobian.shape[0]
    complex_pairs = multipliers[np.abs(multipliers.imag) > 1e-9 * (1.0 + np.abs(multipliers))]
    return {"period-doubling": float(np.linalg.det(jacobian + np.eye(n))),
            "fold": float(np.linalg.det(jacobian - np.eye(n))),
            "neimark-sacker": float(np.abs(complex_pairs).max() - 1.0) if complex_pairs.size else None}


@dataclass(frozen=True)
class OrbitPoint:
    """One orbit of a branch.

    Attributes
    ----------
    value : float
        The parameter value.
    x0 : ndarray, shape (n,)
        State at the orbit's start t0.
    samples : ndarray, shape (k, n)
        x(t0 + m T), m = 0 .. k-1 (the points of the stroboscopic map on the orbit).
    jacobian : ndarray, shape (n, n)
        d P^k / d x at x0 (the monodromy matrix).
    multipliers : ndarray, shape (n,)
        Floquet multipliers, largest modulus first.
    signature : tuple
        The orbit's events over one of its periods: (kind, pair, config), as a cyclic sequence.
    """

    value: float
    x0: np.ndarray
    samples: np.ndarray
    jacobian: np.ndarray
    multipliers: np.ndarray
    signature: tuple
    #: The same events with their times, as (fraction of the orbit's period from the window's start, kind,
    #: pair, config): what a classifier of border collisions reads (which new segment is short).
    timed_events: tuple = ()

    @property
    def spectral_radius(self) -> float:
        return float(np.abs(self.multipliers).max())

    @property
    def stable(self) -> bool:
        return self.spectral_radius < 1.0

    @property
    def tests(self) -> dict:
        return test_functions(self.jacobian, self.multipliers)


@dataclass(frozen=True)
class Bifurcation:
    """A bifurcation located on a branch of orbits of ``period`` switching periods.

    ``value`` is the parameter at the bifurcation (a smooth one: the secant zero of its test function in
    the final bracket; a border collision: the bracket's midpoint), ``width`` the final bracket's width in
    the parameter, ``multipliers`` the Floquet multipliers of the orbit at the bracket's end nearest to
    the bifurcation (for a border collision: just before it, ``multipliers_after`` just after, in the
    direction of increasing parameter), ``stable_before`` / ``stable_after`` the orbit's stability just
    below and just above ``value``."""

    kind: str
    value: float
    period: int
    multipliers: np.ndarray
    x0: np.ndarray
    located_by: str
    width: float
    stable_before: bool
    stable_after: bool
    multipliers_after: np.ndarray | None = None
    detail: str = ""

    @property
    def loses_stability(self) -> bool:
        return self.stable_before and not self.stable_after

    def to_dict(self) -> dict:
        def pairs(values: npt.NDArray[np.complex128]) -> list[list[float]]:
            return [[float(m.real), float(m.imag)] for m in values]
        out = {"type": self.kind, "value": self.value, "period": self.period, "multipliers": pairs(self.multipliers),
               "stable_before": self.stable_before, "stable_after": self.stable_after, "x0": self.x0.tolist(),
               "located_by": self.located_by, "bracket_width": self.width, "detail": self.detail}
        if self.multipliers_after is not None:
            out["multipliers_after"] = pairs(self.multipliers_after)
        return out


@dataclass
class Branch:
    """The orbits of one period followed along the path, with the bifurcations located on them.
    ``message`` says why the branch stopped before the path's end (what it found is kept);
    ``parent``: the period-doubling it was born at (None for the first branch)."""

    period: int
    points: list[OrbitPoint] = field(default_factory=list)
    bifurcations: list[Bifurcation] = field(default_factory=list)
    message: str = ""
    parent: Bifurcation | None = None

    @property
    def complete(self) -> bool:
        return not self.message

    def values(self) -> np.ndarray:
        return np.array([pt.value for pt in self.points])

    def to_frame(self, state_names: Sequence[str] | None = None) -> pd.DataFrame:
        """One row per orbit and sample m: value, m, the states at t0 + m T, stable, spectral radius."""
        import pandas as pd
        rows = []
        for pt in self.points:
            names = state_names or [f"x{i}" for i in range(pt.x0.size)]
            for m, sample in enumerate(pt.samples):
                rows.append({"period": self.period, "value": pt.value, "m": m, **dict(zip(names, sample)),
                             "stable": pt.stable, "spectral_radius": pt.spectral_radius})
        return pd.DataFrame(rows)


class OrbitFamily:
    """The orbits of period k (in switching periods) of ``problem_of(value)`` under ``method``.

    ``problem_of`` returns the problem at a parameter value (only its start time is used); its switching
    law must have a period T (a schedule, or a state-driven law with a ramp)."""

    def __init__(self, problem_of: Callable[[float], Any], method: Method, periods: int = 1,
                 classify: Callable[[OrbitPoint, OrbitPoint], tuple[str, str] | None] | None = None):
        if not (isinstance(periods, (int, np.integer)) and periods >= 1):
            raise ParameterError(f"periods (of the orbit, in switching periods) must be an integer >= 1; got {periods!r}")
        self.problem_of, self.method, self.periods = problem_of, method, int(periods)
        #: classify(below, above) -> (kind, detail) or None: names a change of signature between the orbits just
        #: below and just above a border collision (e.g. the sliding bifurcations of :mod:`.sliding`); None
        #: keeps it a plain border collision.
        self.classify = classify
        self._maps: dict = {}
        #: The last refusal of a parameter value or state by the model or the method (why a correction failed).
        self.refusal = ""

    def doubled(self) -> "OrbitFamily":
        return OrbitFamily(self.problem_of, self.method, 2 * self.periods, self.classify)

    def problem(self, value: float, periods: int | None = None) -> Any:
        problem = self.problem_of(value)
        T = problem.period
        if not np.isfinite(T):
            raise ParameterError("continuation needs a periodic switching law (a schedule or a ramp); this problem's "
                                 "law has no period")
        t0 = problem.t_span[0]
        return replace(problem, t_span=(t0, t0 + (periods or self.periods) * T))

    def period_map(self, value: float, periods: int | None = None) -> PeriodMap:
        key = (float(value), periods or self.periods)
        cached = self._maps.get(key)
        if cached is None:
            if len(self._maps) >= 32:
                self._maps.pop(next(iter(self._maps)))
            cached = self._maps[key] = self.method.period_map(self.problem(value, periods))
        return cached

    def residual(self, value: float, x: npt.NDArray[np.float64]) -> tuple[np.ndarray, np.ndarray]:
        """F = P^k(x) - x and J = d P^k / d x."""
        px, jac = self.period_map(value)(x)
        return px - x, jac

    def parameter_derivative(self, value: float, x: npt.NDArray[np.float64], step: float) -> np.ndarray:
        """d F / d p by a central difference of half-width ``step``."""
        return (self.period_map(value + step).end(x) - self.period_map(value - step).end(x)) / (2.0 * step)

    def orbit(self, value: float, x_guess: npt.ArrayLike, tol: float = 1e-10, max_iter: int = 30) -> PeriodicOrbit:
        """The orbit at a fixed parameter value (Newton shooting, :func:`.periodic.newton_orbit`)."""
        return newton_orbit(self.period_map(value), x_guess, tol=tol, max_iter=max_iter)

    def _events(self, value: float, x0: npt.NDArray[np.float64]) -> Sequence[tuple[float, str, int, int]]:
        events = self.period_map(value).events(x0)
        if events is None:                              # a method whose map does not record events
            from ...simulate import simulate
            table = simulate(self.problem(value), self.method, x0=x0).events
            config = table["config"] if "config" in table else np.full(len(table), -1)
            events = list(zip(table["time"], table["kind"], table["pair"], config))
        return events

    def event_times(self, value: float, x0: npt.NDArray[np.float64], kind: str) -> np.ndarray:
        """The instants of the events of ``kind`` ("impact", "detach", ...) of the orbit from x0, in time order."""
        return np.array([e[0] for e in self._events(value, x0) if e[1] == kind], dtype=float)

    def signature(self, value: float, x0: npt.NDArray[np.float64]) -> tuple:
        """(kind, pair, config) of every event over one orbit, as a cyclic sequence (its smallest rotation)."""
        return self.timed_signature(value, x0)[0]

    def timed_signature(self, value: float, x0: npt.NDArray[np.float64]) -> tuple[tuple, tuple]:
        """(signature, timed events). The orbit's events are read over two of its periods, in a window of one
        period that starts in the middle of the largest gap between them: an event at the orbit's start t0
        (a held state that begins right there, say) is then counted once, whichever side of t0 it falls on."""
        first = self._events(value, x0)
        if not first:
            return (), ()
        span = self.periods * self.problem_of(value).period
        x1 = self.period_map(value).end(x0)
        shifted = [(t + span, kind, pair, config) for t, kind, pair, config in self._events(value, x1)]
        times = sorted(float(e[0]) for e in first)
        gaps = np.diff(times + [times[0] + span])
        widest = int(np.argmax(gaps))
        cut = times[widest] + 0.5 * gaps[widest]
        window = sorted((e for e in list(first) + shifted if cut <= e[0] < cut + span), key=lambda e: e[0])
        timed = tuple(((float(t) - cut) / span, str(kind), int(pair), int(config)) for t, kind, pair, config in window)
        sequence = tuple(e[1:] for e in timed)
        return min((sequence[i:] + sequence[:i] for i in range(len(sequence))), default=()), timed

    def point(self, value: float, x0: npt.ArrayLike, jacobian: npt.NDArray[np.float64]) -> OrbitPoint:
        x0 = np.array(x0, dtype=float)
        samples = [x0]
        if self.periods > 1:
            one = self.period_map(value, 1)
            for _ in range(self.periods - 1):
                samples.append(one.end(samples[-1]))
        signature, timed = self.timed_signature(value, x0)
        return OrbitPoint(float(value), x0, np.array(samples), np.array(jacobian), multipliers_of(jacobian),
                          signature, timed)

    def event_names(self, value: float) -> tuple[tuple[str, ...], tuple[str, ...]]:
        problem = self.problem_of(value)
        configs = getattr(problem, "config_names", None) or tuple(c.name or f"config{i}"
                                                                  for i, c in enumerate(problem.configurations))
        return problem.pair_names, tuple(configs)



def check_path(name: str, start: float, stop: float, low: float, high: float, low_open: bool = True,
               high_open: bool = True) -> None:
    """A path inside the parameter's valid range, or one clear line."""
    def outside(v: float) -> bool:
        return (v <= low if low_open else v < low) or (v >= high if high_open else v > high)
    if outside(start) or outside(stop):
        lb, rb = "(" if low_open else "[", ")" if high_open else "]"
        raise ParameterError(f"the path of {name} must lie in {lb}{low:g}, {high:g}{rb}; got {start:g}:{stop:g}")
    if start == stop:
        raise ParameterError(f"the path of {name} must have START != STOP; got {start:g}:{stop:g}")
