"""The one result type of every method (and of ngspice): a labelled trajectory, convertible to pandas.

SI units throughout (s, A, V). A trajectory holds what a method computed (times, states, the
complementarity pairs, the configuration of each step) and, when a model labelled it, the model's
named signals (``vout``, ``switch``, ...) and its conduction-mode labels. Measures over a window
(mean, RMS, ripple, mode fractions) are taken here, once, by the rule that suits how the samples
were produced (``rule``):

    ``end``     each step counts with its end-point value (backward Euler's own rule: its discrete
                volt-second and charge balances hold exactly with it)
    ``linear``  the exact integral of the piecewise-linear interpolant through the samples
                (trapezoidal rule for means; exact RMS of the interpolant, dt (a^2 + a b + b^2) / 3 per
                piece: the trapezoidal rule on y^2 would add its own error, 3e-4 at T/100 on a DCM
                buck's current, more than the methods' own)
    ``exact``   Gauss-Legendre quadrature on the exact pieces of the event-driven solution

A stepper that moves its states by the pair variables at each step's end (the theta method's h B u_{k+1}:
``pair_rule = "end"``) has its signals' means taken in two parts: the part that reads the state by ``rule``,
the part that reads the pair variables by the end-point rule. The discrete charge and flux balances hold with
that rule, and the state's own accuracy carries over to the mean. The linear rule on the pairs' samples would
add half a step of every jump: a Cockcroft-Walton diode's current, 0.287 A at its edge, read 4.5 % high.
"""
from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Iterable, Iterator, Mapping
from dataclasses import dataclass, field, replace
from enum import Enum
from typing import TYPE_CHECKING, Any, ClassVar, Protocol, TypeAlias, Union, cast

import numpy as np
import numpy.typing as npt

from .errors import SignalError

if TYPE_CHECKING:
    import pandas as pd
    from matplotlib.figure import Figure

    from .problems import LCSProblem
    from .problems.mechanical import MechanicalProblem

RULES = ("end", "linear", "exact")


@dataclass(frozen=True)
class Samples:
    """Rows of a trajectory (or quadrature nodes): what a model's signal and mode laws read."""

    t: np.ndarray
    x: np.ndarray
    u: np.ndarray | None
    y: np.ndarray | None
    config: np.ndarray | None
    relay: np.ndarray | None = None
    held: np.ndarray | None = None


#: Which rows a view of a trajectory reads: a slice, or an index array (positions, or a mask).
Rows: TypeAlias = Union[slice, npt.NDArray[np.integer[Any]], npt.NDArray[np.bool_]]
#: One block of a quadrature: its nodes and their weights.
QuadratureBlock: TypeAlias = tuple[Samples, npt.NDArray[np.float64]]
#: A run's events as data: columns ``time``, ``step``, ``pair``, ``kind`` (and ``config``), or a DataFrame of them.
EventColumns: TypeAlias = "Mapping[str, npt.NDArray[Any]] | pd.DataFrame"


def parabola_peak(t: npt.NDArray[np.float64], w: npt.NDArray[np.float64], config: npt.NDArray[Any] | None,
                  j: int, held: npt.NDArray[np.bool_] | None = None) -> float:
    """The largest of w around its sample j: the vertex of the parabola through samples j-1, j, j+1 where they are
    of one configuration, strictly ordered in time, rise then fall, and the vertex gains at most a quarter of the
    larger drop to a neighbour (as a parabola sampled around its peak does) - a sampled smooth peak is O(h^2) short
    of it, the vertex O(h^3); else w[j]. A kink inside one configuration (a gate's ramp leaving its level) is no
    peak: a vertex through it had read a PULSE gate's 0 V as -2.1 mV. ``held``: the pairs' held flags per sample,
    where known (an exact run's nodes): a diode's event changes them and not the configuration, and a vertex across
    it had read a forward's output current 1.2e-3 below its minimum at the end of a commutation."""
    best = float(w[j])
    if held is not None and 0 < j < w.size - 1 and not (held[j - 1] == held[j]).all() & (held[j] == held[j + 1]).all():
        return best
    if 0 < j < w.size - 1 and config is not None and config[j - 1] == config[j] == config[j + 1]:
        t0, t1, t2 = t[j - 1], t[j], t[j + 1]
        if t0 < t1 < t2:
            a, b, c = w[j - 1], w[j], w[j + 1]
            d01, d12 = (b - a) / (t1 - t0), (c - b) / (t2 - t1)
            curvature = (d12 - d01) / (t2 - t0)
            if d01 > 0.0 > d12:
                # Newton form: p(s) = a + d01 (s - t0) + curvature (s - t0)(s - t1)
                ts = 0.5 * (t0 + t1) - d01 / (2 * curvature)
                vertex = float(a + d01 * (ts - t0) + curvature * (ts - t0) * (ts - t1))
                if t0 <= ts <= t2 and vertex - b <= 0.25 * max(b - a, b - c):
                    best = max(best, vertex)
    return best


def locate_pair_change(t: npt.NDArray[np.float64], u: npt.NDArray[np.float64], y: npt.NDArray[np.float64],
                       config: npt.NDArray[np.int_], j: int, kind: str) -> float:
    """The instant in (t[j], t[j+1]] where the pair changed (``j``: the event's step, its last sample before
    the change): the vanishing quantity (y before it is held, u before it is released) extrapolated to zero
    from samples j-1, j (same configuration as the step); else the newly growing one (u after, y after)
    back from samples j+1, j+2; else t[j+1]."""
    a, b = t[j], t[j + 1]
    before = y if kind == "held" else u
    after = u if kind == "held" else y
    # (a jump's two rows share their instant: no slope between them)
    if j >= 1 and config[j - 1] == config[j] == config[j + 1] and before[j - 1] != before[j] and t[j] > t[j - 1]:
        slope = (before[j] - before[j - 1]) / (t[j] - t[j - 1])
        if slope < 0:
            return float(min(max(a - before[j] / slope, a), b))
    if j + 2 < t.size and config[j + 2] == config[j + 1] and after[j + 2] > after[j + 1] > 0 and t[j + 2] > t[j + 1]:
        slope = (after[j + 2] - after[j + 1]) / (t[j + 2] - t[j + 1])
        return float(min(max(b - after[j + 1] / slope, a), b))
    return float(b)


@dataclass(frozen=True)
class IntegrationPoints:
    """Where :meth:`Trajectory.integral` reads a function over a window: the exact method's quadrature ``blocks``, or
    the window's ``rows`` (their spacings ``dt``) and, for the linear rule, the positions of the steps that start at a
    switching edge (``edges``) with those steps' own first samples (``edge_starts``). Taken once, several functions
    integrate at the same :class:`Samples` (a caller may keep what it reads at them)."""

    rule: str
    blocks: list[QuadratureBlock] | None = None
    rows: Samples | None = None
    dt: npt.NDArray[np.float64] | None = None
    edges: npt.NDArray[np.int_] | None = None
    edge_starts: Samples | None = None


class ExactSolution(Protocol):
    """The exact pieces of an event-driven run (:attr:`Trajectory.exact`): the Gauss-Legendre nodes and weights of
    a window, at once or a block at a time (a long window's nodes are not all held at once)."""

    def quadrature(self, t0: float, t1: float) -> QuadratureBlock: ...

    def quadrature_blocks(self, t0: float, t1: float) -> Iterator[QuadratureBlock]: ...


class SignalLabels(Protocol):
    """Any model's laws bound to its parameters (:attr:`Trajectory.labels`): the signals it names and their values
    at a :class:`Samples`' points. What some models give beside is read where present: ``model`` (its
    ``signal_units``), ``mode_labels_of(samples)`` (modes from the run's state: mechanical models, circuits)."""

    @property
    def signal_names(self) -> tuple[str, ...]: ...

    def signal(self, name: str, samples: Samples) -> npt.NDArray[Any]: ...


class Labels(SignalLabels, Protocol):
    """A converter model's labels: also which device of each pair conducts, and its conduction-mode rule (what
    :meth:`Trajectory.conducting` and :meth:`Trajectory.modes` read; a mechanical model's labels have neither)."""

    def conducting(self, samples: Samples) -> npt.NDArray[np.bool_]: ...

    def modes(self, conducting: npt.NDArray[np.bool_], switch: npt.NDArray[Any],
              x: npt.NDArray[np.float64]) -> npt.NDArray[Any]: ...


class ReturnCode(str, Enum):
    """How a run ended without raising (:attr:`Trajectory.retcode`), as DifferentialEquations.jl's ``sol.retcode``:
    ``SUCCESS``, or ``NOT_CONVERGED`` where the run returns what it reached short of what was asked. A ``str``
    enum: it compares equal to its value (``tr.retcode == "success"``) and writes as it into JSON."""

    SUCCESS = "success"
    NOT_CONVERGED = "not_converged"

    def __str__(self) -> str:
        return self.value


#: The return codes' values (:class:`ReturnCode`).
RETCODES = tuple(code.value for code in ReturnCode)


class Algorithm(Protocol):
    """What a trajectory and its readers know of the method that made it (:class:`converters.methods.base.Method`
    gives it; the trajectory sits below the methods, which return it)."""

    key: ClassVar[str]
    counts: ClassVar[str]
    exact: ClassVar[bool]
    fixed_step: ClassVar[bool]

    @property
    def order(self) -> float: ...

    def options(self) -> dict[str, object]: ...


@dataclass(frozen=True)
class Stats:
    """What a run cost (:attr:`Trajectory.stats`): ``steps`` in its method's unit (``unit``: steps, segments,
    factorisations), the wall seconds, the events, and the steps whose LCP went to the general solver.
    ``stats["steps"]`` reads as ``stats.steps`` (the mapping form of earlier releases)."""

    steps: int
    unit: str
    wall_s: float
    events: int
    general_solves: int

    def __getitem__(self, name: str) -> int | float | str:
        if name not in self.__dataclass_fields__:
            raise KeyError(name)
        value: int | float | str = getattr(self, name)
        return value

    def as_dict(self) -> dict[str, int | float | str]:
        return {name: getattr(self, name) for name in self.__dataclass_fields__}


#: Measured tables that are no signal: per point and device (a mode label, each diode conducting, each switch closed).
PER_DEVICE = ("conducting", "mode", "closed")


@dataclass(frozen=True)
class Trajectory:
    """Time series of one run.

    Attributes
    ----------
    t : ndarray, shape (N,)
        Time points (s).
    x : ndarray, shape (N, n)
        States, columns named by ``state_names``.
    u, y : ndarray, shape (N, k), or None
        Complementarity pairs (0 <= u _|_ y >= 0); row 0 holds the consistent initial pair.
        None for a trajectory measured by another simulator.
    config : ndarray of int, shape (N,), or None
        Configuration of the step that arrived at each point (row 0: of the first step).
    relay : ndarray, shape (N,), or None
        The relay law's blend z in [0, 1] per point (problems switched by a Relay).
    held : ndarray of bool, shape (N, k), or None
        The held pairs of the mode each point belongs to, where the method knows them exactly (the event
        method: its segments' modes, free of the rounding of u and y at an event); None: u > y.
    method : str
        Registry name of the method (``lcp``, ``event``, ``smooth``, ``spice``).
    steps : int
        Steps, segments or solver factorisations (method-dependent; see ``metadata``).
    wall_s : float
        Seconds spent building and running the simulation.
    rule : str
        How integrals over the samples are taken (module docstring).
    exact : object or None
        The exact piecewise solution (event method): ``quadrature(t0, t1) -> (Samples, weights)`` and
        ``quadrature_blocks(t0, t1)``, the same nodes a block at a time.
    events : pandas.DataFrame (property)
        Columns ``time``, ``step``, ``pair`` (-1 for switching-law events) and ``kind`` (``activate``,
        ``release``, ``impulse``, ``switch``, ``jump``); switching-law events also give ``config`` (the
        configuration entered).
        Built on first access from ``event_columns`` (data, or a function giving it: computed when first read).
    labels : object or None
        The model's laws bound to its parameters (``signal_names``, ``signal(name, samples)``,
        ``conducting(samples)``, ``modes(conducting, switch, x)``); None for a bare LCS run.
    measured : dict
        Signals measured by another simulator (name -> array; ``switch`` among them), and optionally
        ``conducting`` (N, k) bool: they take the place of the model's laws.
    period : float
        The switching period T (s) when there is one (windows of "the last m periods"); inf otherwise.
    resolved_from : float
        Every step is stored from this time on (s); before it only the output samples (:meth:`thinned`), and a
        measure reaching before it is refused.
    problem : LCSProblem or None
        The problem :func:`converters.simulate.simulate` solved (of a run in phases: its first phase's); None for
        a trajectory measured by another simulator.
    algorithm : Method or None
        The method object that solved it, with its options (``method`` is its registry name): what a check of the
        run's accuracy re-runs at another step.
    stats : Stats (property)
        What the run cost: ``steps`` (the method's unit: ``counts``), ``wall_s``, ``events``, ``general_solves``.
    retcode : ReturnCode
        How the run ended: ``success``, or ``not_converged`` where it returns what it reached short
        of what was asked (accuracy on request whose rtol was not met; ngspice's steady state not settled within
        its periods): the summary's warnings say by how much. A run that cannot give an answer raises instead
        (SimulationError, LCPError, ResourceError, ParameterError).
    """

    t: np.ndarray
    x: np.ndarray
    state_names: tuple[str, ...]
    u: np.ndarray | None = None
    y: np.ndarray | None = None
    config: np.ndarray | None = None
    pair_names: tuple[str, ...] = ()
    config_names: tuple[str, ...] = ()
    relay: np.ndarray | None = None
    held: np.ndarray | None = None
    method: str = ""
    steps: int = 0
    wall_s: float = 0.0
    rule: str = "linear"
    #: How the pair variables' share of a signal's mean is integrated: ``rule``'s way (``"linear"``: also a
    #: smoothed run's u, a smooth function of y), or ``"end"`` where the method moves the states by the pairs at
    #: each step's end (module docstring).
    pair_rule: str = "linear"
    exact: ExactSolution | None = None
    event_columns: EventColumns | Callable[[], EventColumns | None] | None = None
    labels: SignalLabels | None = None
    measured: dict[str, npt.NDArray[Any]] = field(default_factory=dict)
    period: float = float("inf")
    general_solves: int = 0
    metadata: dict[str, Any] = field(default_factory=dict, compare=False)
    #: Rows before this time were kept at an output spacing only (:meth:`thinned`): measures need every step.
    resolved_from: float = float("-inf")
    problem: "LCSProblem | MechanicalProblem | None" = field(default=None, compare=False, repr=False)
    algorithm: Algorithm | None = field(default=None, compare=False, repr=False)
    retcode: ReturnCode = ReturnCode.SUCCESS
    #: The jumps of the state (a switch closing across charged capacitances, :class:`~converters.problems.Jump`):
    #: ((time, energy lost in J), ...) in time order, as the method took them (a run's start among them where its
    #: state is not on the first configuration's loops).
    jumps: tuple[tuple[float, float], ...] = ()

    def __post_init__(self) -> None:
        if not isinstance(self.retcode, ReturnCode):
            if self.retcode not in RETCODES:
                raise ValueError(f"retcode must be one of {', '.join(RETCODES)}; got {self.retcode!r}")
            object.__setattr__(self, "retcode", ReturnCode(self.retcode))

    @property
    def stats(self) -> Stats:
        """What the run cost: steps (in the unit of its method's ``counts``), wall seconds, events, and the steps
        whose LCP went to the general solver."""
        unit = self.algorithm.counts if self.algorithm is not None else "steps"
        return Stats(steps=int(self.steps), unit=unit, wall_s=float(self.wall_s), events=len(self.events),
                     general_solves=int(self.general_solves))

    # --- raw views -----------------------------------------------------------------------------------

    def samples(self, rows: Rows = slice(None)) -> Samples:
        pick: Callable[[npt.NDArray[Any] | None], npt.NDArray[Any] | None] = (
            lambda a: None if a is None else a[rows])
        return Samples(self.t[rows], self.x[rows], pick(self.u), pick(self.y), pick(self.config), pick(self.relay),
                       pick(self.held))

    @property
    def events(self) -> pd.DataFrame:
        import pandas as pd
        frame = self.__dict__.get("_events_frame")
        if frame is None:
            columns = self.event_table()
            if columns is None:
                columns = {"time": np.empty(0), "step": np.empty(0, dtype=np.int64),
                           "pair": np.empty(0, dtype=np.int64), "kind": np.empty(0, dtype=object)}
            frame = columns if isinstance(columns, pd.DataFrame) else pd.DataFrame(columns)
            object.__setattr__(self, "_events_frame", frame)
        return frame

    def event_table(self) -> EventColumns | None:
        """The event columns as data: ``event_columns``, or what it gives when it is a function (a method may
        defer locating its events until they are read; computed once)."""
        columns = self.event_columns
        if callable(columns):
            columns = columns()
            object.__setattr__(self, "event_columns", columns)
        return columns

    @property
    def active(self) -> np.ndarray:
        """Complementarity mode flags, shape (N, k): the held pairs (u carries the pair; u > y)."""
        if self.held is not None:
            return self.held
        assert self.u is not None and self.y is not None        # an LCS run's flags: it has its pairs
        return self.u > self.y

    def state(self, name: str) -> np.ndarray:
        try:
            return self.x[:, self.state_names.index(name)]
        except ValueError:
            raise SignalError(f"state must be one of {', '.join(self.state_names)}; got {name!r}") from None

    # --- labelled signals and modes ------------------------------------------------------------------

    @property
    def signal_names(self) -> tuple[str, ...]:
        """States, then the model's signals (``vout``, ``switch``, ...), then measured ones."""
        names = list(self.state_names)
        if self.labels is not None:
            names += [s for s in self.labels.signal_names if s not in names]
        names += [s for s in self.measured if s not in names and s not in PER_DEVICE]
        return tuple(names)

    def signal(self, name: str, rows: Rows = slice(None)) -> np.ndarray:
        """A named signal (a state, a model signal such as ``vout`` or ``switch``, or a measured one)."""
        if name in self.measured:
            return np.asarray(self.measured[name])[rows]
        if name in self.state_names:
            return self.x[rows, self.state_names.index(name)]
        if self.labels is None or name not in self.labels.signal_names:
            raise SignalError(f"signal must be one of {', '.join(self.signal_names)}; got {name!r}")
        whole = isinstance(rows, slice) and rows == slice(None)
        cache: dict[str, npt.NDArray[Any]] = self.__dict__.setdefault("_signal_cache", {})
        if whole and name in cache:
            return cache[name]
        value = np.asarray(self.labels.signal(name, self.samples(rows)))
        if whole:
            cache[name] = value
        return value

    def conducting(self, rows: Rows = slice(None)) -> np.ndarray:
        """Per point and pair: True where the pair's device conducts (shape (N, k))."""
        if "conducting" in self.measured:
            return np.asarray(self.measured["conducting"])[rows]
        return np.asarray(cast("Labels", self.labels).conducting(self.samples(rows)))

    def modes(self, rows: Rows = slice(None)) -> np.ndarray:
        """Conduction-mode label per point (e.g. CCM-ON, CCM-OFF, DCM, GDCM-OFF), from the model's rule."""
        if "mode" in self.measured:
            return np.asarray(self.measured["mode"])[rows]
        if self.labels is None:
            raise SignalError("modes need a model's labels (this trajectory has none)")
        if hasattr(self.labels, "mode_labels_of"):             # mechanical models read the mode from the run's state
            return cast("npt.NDArray[Any]", self.labels.mode_labels_of(self.samples(rows)))
        return cast("Labels", self.labels).modes(self.conducting(rows), self.signal("switch", rows), self.x[rows])

    # --- windows and measures ------------------------------------------------------------------------

    def window(self, periods: float | None = None, t0: float | None = None,
               t1: float | None = None) -> tuple[float, float]:
        """(t0, t1) of the last ``periods`` switching periods, or of the given times (default: the run)."""
        for label, value in (("periods", periods), ("t0", t0), ("t1", t1)):     # NaN had meant the whole run
            if value is not None and (isinstance(value, (bool, str)) or not isinstance(value, (int, float, np.number))
                                      or not math.isfinite(value)):
                raise ValueError(f"{label} must be a finite number; got {value!r}")
        if periods is not None and not periods > 0:
            raise ValueError(f"periods must be > 0; got {periods!r}")
        end = self.t[-1] if t1 is None else min(float(t1), self.t[-1])
        if periods is not None:
            if not np.isfinite(self.period):
                raise ValueError("a window in periods needs a switching period; give t0 instead")
            start = max(self.t[0], end - periods * self.period)
        else:
            start = self.t[0] if t0 is None else max(self.t[0], float(t0))
        if not end > start:
            raise ValueError(f"the window [{start:g}, {end:g}] s holds no time of the run [{self.t[0]:g}, {self.t[-1]:g}] s")
        return start, end

    def rows_between(self, t0: float, t1: float) -> np.ndarray:
        """Indices of the samples in [t0, t1]; at least the two around a window shorter than a step."""
        span = max(t1 - t0, 1e-300)
        if t0 < self.resolved_from - 1e-9 * span:
            raise SignalError(f"the window [{t0:.6g}, {t1:.6g}] s starts before {self.resolved_from:.6g} s, where this "
                              "run kept its output samples only (--output-step): measures need every step; measure "
                              "a later window, or run with a finer --output-step")
        # t is non-decreasing: the window's rows by bisection (a scan would cost O(N) per window)
        first = int(np.searchsorted(self.t, t0 - 1e-12 * span, side="left"))
        last = int(np.searchsorted(self.t, t1 + 1e-12 * span, side="right"))
        # an end within a thousandth of a step of a row outside the window takes that row: a window whose end is a
        # switching instant's neighbour (a run's grid holds the instant, 5e-9 T from the period's start) would
        # otherwise lose that step (a window of whole periods: a latched boost's current rise 0.1 % short)
        if (0 < first < self.t.size and t0 - self.t[first - 1] < 1e-3 * (self.t[first] - self.t[first - 1])
                and self.t[first - 1] >= self.resolved_from):
            first -= 1
        if 0 < last < self.t.size and self.t[last] - t1 < 1e-3 * (self.t[last] - self.t[last - 1]):
            last += 1
        rows = np.arange(first, last)
        if rows.size < 2:
            last = min(max(int(np.searchsorted(self.t, t1)), 1), self.t.size - 1)
            rows = np.array([last - 1, last])
        return rows

    def _integrate(self, name: str, power: int, t0: float, t1: float) -> float:
        """Integral of signal**power over [t0, t1] by the trajectory's rule."""
        if self.rule == "exact" and self.exact is not None and name not in self.measured:
            if name not in self.state_names and (self.labels is None or name not in self.labels.signal_names):
                raise SignalError(f"signal must be one of {', '.join(self.signal_names)}; got {name!r}")
            cache: dict[tuple[float, float], tuple[QuadratureBlock, ...]] = self.__dict__.setdefault(
                "_quadrature_cache", {})
            if (t0, t1) not in cache:
                cache.clear()                    # one window at a time, and only one that fits a block
                blocks = self.exact.quadrature_blocks(t0, t1)
                first = next(blocks)
                rest = next(blocks, None)
                if rest is None:
                    cache[(t0, t1)] = (first,)
                else:                            # a long window: read block by block at each measure
                    return self._integrate_blocks(name, power, itertools.chain((first, rest), blocks))
            return self._integrate_blocks(name, power, cache[(t0, t1)])
        rows = self.rows_between(t0, t1)
        t, v = self.t[rows], self.signal(name, self._all_or(rows))
        dt = np.diff(t)
        if self.rule == "end":
            return float(dt @ v[1:] ** power)
        a, b = v[:-1], v[1:]
        if name not in self.state_names and name not in self.measured:
            labels = cast("SignalLabels", self.labels)
            algebraic = self._algebraic_part(name) if power == 1 else None
            if algebraic is not None:
                own = algebraic(self.samples(rows))
                starts = self._step_starts(algebraic, rows, own[:-1])
                return float(dt @ (0.5 * (starts + own[1:])) + dt @ (v - own)[1:])
            a = self._step_starts(lambda samples: labels.signal(name, samples), rows, a)
        if power == 1:
            return float(dt @ (0.5 * (a + b)))
        return float(dt @ ((a * a + a * b + b * b) / 3.0))

    def _integrate_blocks(self, name: str, power: int, blocks: Iterable[QuadratureBlock]) -> float:
        return self._integrals_of_blocks((name,), blocks)[name][power - 1]

    def _integrals_of_blocks(self, names: Iterable[str], blocks: Iterable[QuadratureBlock]) -> dict[str, list[float]]:
        """{name: (integral of the signal, of its square, its least and its largest value)} over quadrature blocks,
        each block read once: the extremes at the nodes, refined between them (:func:`parabola_peak`)."""
        totals = {name: [0.0, 0.0, math.inf, -math.inf] for name in names}
        for nodes, weights in blocks:
            for name in names:
                if name in self.state_names:
                    values = nodes.x[:, self.state_names.index(name)]
                else:
                    values = np.asarray(cast("SignalLabels", self.labels).signal(name, nodes), dtype=float)
                total = totals[name]
                total[0] += float(weights @ values)
                total[1] += float(weights @ (values * values))
                if values.size:
                    total[2] = min(total[2], -parabola_peak(nodes.t, -values, nodes.config, int(np.argmin(values)),
                                                            nodes.held))
                    total[3] = max(total[3], parabola_peak(nodes.t, values, nodes.config, int(np.argmax(values)),
                                                           nodes.held))
        return totals

    def _measures(self, names: list[str], t0: float, t1: float) -> dict[str, tuple[float, float, float, float]]:
        """{name: (mean, rms, least, largest)} over [t0, t1]: of an exact run, one pass over its quadrature for every
        name (a long window's nodes are computed once, not once per measure), its extremes between the samples as
        well (the nodes follow the flow's stiffest mode: a stored sample grid missed a snubbed diode's peak by 1.8 %);
        of a sampled run, the extremes are inf (the samples' own are read by the caller)."""
        if self.rule == "exact" and self.exact is not None and not any(n in self.measured for n in names):
            span = self._span(t0, t1)
            cached = self.__dict__.get("_quadrature_cache", {}).get((t0, t1))
            totals = self._integrals_of_blocks(names, cached or self.exact.quadrature_blocks(t0, t1))
            return {n: (one / span, float(np.sqrt(two / span)), low, high)
                    for n, (one, two, low, high) in totals.items()}
        return {n: (self.mean(n, t0=t0, t1=t1), self.rms(n, t0=t0, t1=t1), math.inf, -math.inf) for n in names}

    def integral(self, function: Callable[[Samples], npt.ArrayLike], t0: float, t1: float,
                 points: IntegrationPoints | None = None) -> float:
        """The integral over [t0, t1] of ``function(samples)`` (values at a :class:`Samples`' points: a product of
        signals, an element's power) by the trajectory's own rule: the exact method's quadrature on its exact
        pieces, the end-point rule, or the linear rule with each step that starts at a switching edge read in its
        own configuration (a function of several signals is not split into its pairs' share: :meth:`mean` reads a
        signal's share that moves the state by the end-point rule, ``pair_rule``); at ``points``
        (:meth:`integration_points` of the same window) where given."""
        if points is None and self.rule == "exact" and self.exact is not None:      # a long window: block by block
            return sum(float(weights @ np.asarray(function(nodes), dtype=float))
                       for nodes, weights in self.exact.quadrature_blocks(t0, t1))
        points = points or self.integration_points(t0, t1)
        if points.blocks is not None:
            return sum(float(weights @ np.asarray(function(nodes), dtype=float)) for nodes, weights in points.blocks)
        assert points.rows is not None and points.dt is not None and points.edges is not None
        v = np.asarray(function(points.rows), dtype=float)
        if points.rule == "end":
            return float(points.dt @ v[1:])
        starts = v[:-1]
        if points.edges.size:
            starts = np.array(starts, dtype=float)
            starts[points.edges] = np.asarray(function(cast(Samples, points.edge_starts)), dtype=float)
        return float(points.dt @ (0.5 * (starts + v[1:])))

    def integration_points(self, t0: float, t1: float) -> IntegrationPoints:
        """Where :meth:`integral` reads over [t0, t1] (:class:`IntegrationPoints`; an exact run's blocks all kept)."""
        if self.rule == "exact" and self.exact is not None:
            return IntegrationPoints("exact", blocks=list(self.exact.quadrature_blocks(t0, t1)))
        rows = self.rows_between(t0, t1)
        rule = "end" if self.rule == "end" else "linear"
        edges, _, first = self.edges(rows) if rule == "linear" and self.labels is not None else (
            np.zeros(0, dtype=int), None, self.samples(rows[:0]))
        return IntegrationPoints(rule, rows=self.samples(rows), dt=np.diff(self.t[rows]), edges=edges,
                                 edge_starts=first)

    def pair_moved(self, names: Iterable[str]) -> list[str]:
        """Those of ``names`` whose mean reads a share of the pair variables by the end-point rule (``pair_rule``
        "end": the share that moves the state), where it is not zero: what a page that integrates the samples by
        the linear rule alone reads differently."""
        moved = []
        for name in names:
            algebraic = self._algebraic_part(name) if name not in self.state_names and name not in self.measured \
                else None
            if algebraic is not None:
                whole = np.asarray(self.signal(name), dtype=float)
                share = whole - algebraic(self.samples())
                if np.abs(share).max(initial=0.0) > 1e-9 * max(np.abs(whole).max(initial=0.0), 1e-300):
                    moved.append(name)     # (a share at rounding, 2e-16 of a signal, moves nothing)
        return moved

    def _algebraic_part(self, name: str) -> Callable[[Samples], npt.NDArray[Any]] | None:
        """The signal ``name`` with the pair variables' state-moving share taken out (:meth:`_moving_pairs`), as a
        function of samples; None where the run's pairs are not integrated apart (``pair_rule`` "linear")."""
        moving = self._moving_pairs() if self.pair_rule == "end" and self.labels is not None else None
        if moving is None or not self._moves_state(name, moving):
            return None
        labels = cast("SignalLabels", self.labels)

        def algebraic(samples: Samples) -> npt.NDArray[Any]:
            u = np.asarray(samples.u, dtype=float)
            kept = u - np.einsum("nij,nj->ni", moving[np.asarray(samples.config, dtype=np.int64)], u)
            return np.asarray(labels.signal(name, replace(samples, u=kept)), dtype=float)
        return algebraic

    def _moves_state(self, name: str, moving: npt.NDArray[np.float64]) -> bool:
        """Whether signal ``name`` has a share in the pair directions that move the state in some configuration:
        the signal is affine in u, so its response to each unit pair and to each projected one, at x = 0, says so
        (once per name and run; a signal with none, a node voltage or an inductor's current, is read by the linear
        rule at the cost of one evaluation, not two a mean)."""
        cache: dict[str, bool] = self.__dict__.setdefault("_state_moving_names", {})
        if name not in cache:
            configs, k = moving.shape[0], moving.shape[1]
            units = np.concatenate([np.zeros((1, k)), np.eye(k)])                 # u = 0, then each e_i
            u = np.concatenate([np.concatenate([units, units[1:] @ moving[c].T]) for c in range(configs)])
            per = 2 * k + 1
            rows = configs * per
            samples = Samples(np.zeros(rows), np.zeros((rows, self.x.shape[1])), u, np.zeros((rows, k)),
                              np.repeat(np.arange(configs), per))
            try:
                values = np.asarray(cast("SignalLabels", self.labels).signal(name, samples), dtype=float)
            except (ValueError, ArithmeticError, IndexError, SignalError):
                cache[name] = True                  # not read at these points: split, as for any signal
                return True
            values = values.reshape(configs, per)
            raw = np.abs(values[:, 1:k + 1] - values[:, :1]).max(initial=0.0)
            projected = np.abs(values[:, k + 1:] - values[:, :1]).max(initial=0.0)
            cache[name] = bool(projected > 1e-9 * raw)
        return cache[name]

    def _moving_pairs(self) -> npt.NDArray[np.float64] | None:
        """Per configuration, the projector onto the pair directions that move the state (the row space of B,
        (configs, k, k)): the share of a signal the stepper's h B u_{k+1} integrates, by the end-point rule
        (module docstring). The rest of u (a diode's current that the inductor's fixes, B's null space) is
        algebraic: the linear rule reads it. None where the run has no pairs or no problem to read B from."""
        if "_moving" in self.__dict__:
            return cast("npt.NDArray[np.float64] | None", self.__dict__["_moving"])
        projectors = None
        configurations = getattr(self.problem, "configurations", None)
        if self.u is not None and self.u.shape[1] and self.config is not None and configurations is not None:
            stack = []
            for c in configurations:
                B = np.asarray(c.B, dtype=float)
                _, sigma, vt = np.linalg.svd(B)
                rank = int((sigma > 1e-12 * sigma.max(initial=0.0)).sum()) if sigma.size else 0
                stack.append(vt[:rank].T @ vt[:rank])
            projectors = np.array(stack)
            if int(self.config.max(initial=0)) >= len(stack):
                projectors = None                   # a run in phases whose later problems have more configurations
        self.__dict__["_moving"] = projectors
        return projectors

    def _step_starts(self, function: Callable[[Samples], npt.ArrayLike], rows: np.ndarray,
                     starts: np.ndarray) -> np.ndarray:
        """The value each step of ``rows`` starts from, for the linear rule: a step that starts at a switching
        edge reads its first point in its own configuration (with its own pair, the one it ends with), not in
        the one the point ended: a switch current that jumps to zero there would otherwise be integrated over
        half the step after the edge, a first-order error whose size follows the split step's length, not h
        (a buck's input power 5.5e-5 off at every h from T/1600 to T/12800)."""
        if self.labels is None:
            return starts
        edges, _, first = self.edges(rows)
        if edges.size == 0:
            return starts
        starts = np.array(starts, dtype=float)
        starts[edges] = np.asarray(function(first), dtype=float)
        return starts

    def edges(self, rows: npt.NDArray[np.integer[Any]]) -> tuple[npt.NDArray[np.int_], Samples, Samples]:
        """The switching edges among ``rows`` (positions k in ``rows`` where the configuration of row k + 1 differs:
        row k, at the edge's instant, still holds the configuration it ends), and the samples at each edge in the
        configuration before it (row k itself) and after it (row k's state, the next row's configuration and pair
        variables: the state is continuous across a switching, the pair variables are the new configuration's)."""
        if self.config is None or self.u is None:
            none = np.empty(0, dtype=int)
            return none, self.samples(none), self.samples(none)
        config = self.config[rows]
        edges = np.flatnonzero(config[1:] != config[:-1])
        assert self.y is not None                    # a run with pairs has both u and y
        left, right = rows[edges], rows[edges + 1]
        pick: Callable[[npt.NDArray[Any] | None], npt.NDArray[Any] | None] = (
            lambda a: None if a is None else a[right])
        u, y, _ = self._pairs_after_edges(left, right)
        after = Samples(self.t[left], self.x[left], u, y, self.config[right], pick(self.relay), pick(self.held))
        return edges, self.samples(left), after

    def edge_limits(self, rows: npt.NDArray[np.integer[Any]]) -> Samples | None:
        """The samples just after each switching edge among ``rows`` (the right limits: the edge's state in the new
        configuration with its pair variables solved there), where that LCP's solution is unique at every edge;
        None if there are none, or if one edge's is not (a diode at zero current and voltage as a square wave
        falls: which way it goes is its derivatives', so that edge's limit is unknown, and an extremum over the
        others would hide its miss from the check at h and 2h). A stepper's samples miss the value a switch
        takes at the instant it closes onto a snubber (vout / Rs + iL = 8.35 A; the next sample, a step later,
        6.43 A): an extremum is taken over them too."""
        if self.config is None or self.u is None or not rows.size:
            return None
        edges = np.flatnonzero(self.config[rows][1:] != self.config[rows][:-1])
        left, right = rows[edges], rows[edges + 1]
        stepped = self.t[right] > self.t[left]          # a jump's second row is the limit there: a sample already
        left, right = left[stepped], right[stepped]
        u, y, solved = self._pairs_after_edges(left, right)
        if not solved.size or not solved.all():
            return None
        pick: Callable[[npt.NDArray[Any] | None], npt.NDArray[Any] | None] = (
            lambda a: None if a is None else a[right[solved]])
        return Samples(self.t[left[solved]], self.x[left[solved]], u[solved], y[solved], self.config[right[solved]],
                       pick(self.relay), pick(self.held))

    def event_limits(self, rows: npt.NDArray[np.integer[Any]]) -> Samples | None:
        """The samples at each pair event inside a step among ``rows`` (a diode that starts or stops conducting
        between two samples): located where its vanishing quantity reaches zero (:func:`locate_pair_change`), the
        state, pairs and inputs extrapolated there from the two samples before it in one configuration (O(h^2)): the
        value a signal reaches at the event before it turns or jumps, which the samples miss (a bridge rectifier's
        node at the end of its diodes' conduction had read 0.87 V high, 7x its estimate, at h = T/1000); None if there
        is none."""
        columns = self.event_table()
        if columns is None or self.config is None or self.u is None or self.y is None or rows.size < 3:
            return None
        steps = np.asarray(columns["step"], dtype=np.int64)
        pairs = np.asarray(columns["pair"], dtype=np.int64)
        kinds = np.asarray(columns["kind"]).astype(str)
        t, config = self.t, self.config
        found: list[tuple[int, float]] = []
        for k in np.flatnonzero((pairs >= 0) & (steps > rows[0]) & (steps < rows[-1])):
            j, pair = int(steps[k]), int(pairs[k])
            if config[j - 1] != config[j] or not t[j] > t[j - 1]:
                continue
            kind = "held" if kinds[k].startswith("act") else "released"
            instant = locate_pair_change(t, self.u[:, pair], self.y[:, pair], config, j, kind)
            if t[j] < instant < t[j + 1]:
                found.append((j, instant))
        if not found:
            return None
        at = np.array([j for j, _ in found])
        share = np.array([(instant - t[j]) / (t[j] - t[j - 1]) for j, instant in found])[:, None]

        def ahead(a: npt.NDArray[Any]) -> npt.NDArray[Any]:
            return cast("npt.NDArray[Any]", a[at] + (a[at] - a[at - 1]) * share)
        pick: Callable[[npt.NDArray[Any] | None], npt.NDArray[Any] | None] = (
            lambda a: None if a is None else a[at])
        return Samples(np.array([instant for _, instant in found]), ahead(self.x), ahead(self.u), ahead(self.y),
                       config[at], pick(self.relay), pick(self.held))

    #: An instantaneous pair is taken where each pair's u + y exceeds this fraction of its scale (strictly
    #: complementary) and the held pairs' D block is this far from singular: the LCP's solution is then unique
    #: near it; elsewhere (a diode whose current is an inductor's, D = 0 and q = 0) the step's own pair stands.
    _INSTANT_RTOL = 1e-9

    def _pairs_after_edges(self, left: npt.NDArray[np.integer[Any]],
                           right: npt.NDArray[np.integer[Any]]
                           ) -> tuple[npt.NDArray[Any], npt.NDArray[Any], npt.NDArray[np.bool_]]:
        """The pair variables at each switching edge in the configuration after it: the new configuration's LCP,
        0 <= u _|_ D u + C x + F >= 0, at the edge's own state x[left], where its solution is unique there; else
        the step's end (row ``right``, solved at the state a step later). A stepper's end pair at the other state
        had put the synchronous buck's inductor current, 12.036 A a step after the dead time starts against
        12.025 A at its start, into its idle body diode (-0.011 A: rms 1.4e-4 A at T/1000, 3.0e-4 at T/500, where
        it is 0). The problem's configuration is used only where it reproduces the step's end pair (a run in
        phases holds its first phase's problem)."""
        assert self.u is not None and self.y is not None and self.config is not None
        u, y = self.u[right].copy(), self.y[right].copy()
        solved = np.zeros(left.size, dtype=bool)
        problem = self.problem
        if not left.size or getattr(problem, "configuration_at", None) is None:
            return u, y, solved
        cache: dict[int, tuple[npt.NDArray[Any], npt.NDArray[Any]] | None] = self.__dict__.setdefault(
            "_edge_pairs", {})
        for i, (a, b) in enumerate(zip(left.tolist(), right.tolist())):
            if self.t[b] == self.t[a]:      # a jump's two rows: row b is the new configuration's own sample there
                solved[i] = True
                continue
            if a not in cache:
                cache[a] = self._instant_pair(problem, a, b)
            found = cache[a]
            if found is not None:
                u[i], y[i] = found
                solved[i] = True
        return u, y, solved

    def _instant_pair(self, problem: Any, a: int, b: int) -> tuple[npt.NDArray[Any], npt.NDArray[Any]] | None:
        assert self.u is not None and self.y is not None and self.config is not None
        if getattr(problem.configurations[int(self.config[b])], "jump", None) is not None:
            return None                     # its state jumps on entry: x[a] is the state before the jump
        at_end = problem.configuration_at(int(self.config[b]), float(self.t[b]))     # the step's LCP: F at its end
        c = problem.configuration_at(int(self.config[b]), float(self.t[a]))
        tol = self._INSTANT_RTOL
        end = at_end.D @ self.u[b] + at_end.C @ self.x[b] + at_end.F
        end_scale = np.abs(at_end.D) @ np.abs(self.u[b]) + np.abs(at_end.C) @ np.abs(self.x[b]) + np.abs(at_end.F)
        if (np.abs(end - self.y[b]) > 1e-6 * end_scale + 1e-300).any():      # not this run's configuration
            return None
        q = c.C @ self.x[a] + c.F
        from .lcp import solve_lcp             # imported here: a run that integrates no edge never pays it
        result = solve_lcp(c.D, q, method="lemke")
        if not result.solved:
            return None
        z = np.maximum(result.z, 0.0)
        w = c.D @ z + q
        scale = np.abs(c.D) @ np.abs(z) + np.abs(c.C) @ np.abs(self.x[a]) + np.abs(c.F) + 1e-300
        # z is in u's units and w in y's (amperes and volts): z's scale is w's through the pair's own D_ii (a diode
        # behind 1 Gohm carries 3.9 nA where its terms are 10 V, and had read as degenerate against the volts)
        diagonal = np.abs(np.diag(c.D))
        z_scale = np.where(diagonal > 0.0, scale / np.where(diagonal > 0.0, diagonal, 1.0), scale)
        if ((z <= tol * z_scale) & (np.maximum(w, 0.0) <= tol * scale)).any() or (w < -tol * scale).any():
            return None                            # degenerate, or not a solution: the step's own pair
        held = z > tol * z_scale
        block = c.D[np.ix_(held, held)]
        if held.any() and np.linalg.cond(block) > 1.0 / tol:
            return None
        return z * held, np.where(held, 0.0, w)

    def _span(self, t0: float, t1: float) -> float:
        if self.rule == "exact" and self.exact is not None:
            return t1 - t0
        rows = self.rows_between(t0, t1)
        return float(self.t[rows[-1]] - self.t[rows[0]])

    def mean(self, name: str, periods: float | None = None, t0: float | None = None, t1: float | None = None) -> float:
        """Time average of a signal over the window (the last ``periods`` periods, or [t0, t1])."""
        a, b = self.window(periods, t0, t1)
        return self._integrate(name, 1, a, b) / self._span(a, b)

    def rms(self, name: str, periods: float | None = None, t0: float | None = None, t1: float | None = None) -> float:
        a, b = self.window(periods, t0, t1)
        return float(np.sqrt(self._integrate(name, 2, a, b) / self._span(a, b)))

    def ripple(self, name: str, periods: float | None = None, t0: float | None = None, t1: float | None = None) -> float:
        """Peak-to-peak value over the window (on the samples)."""
        a, b = self.window(periods, t0, t1)
        return float(np.ptp(self.signal(name, self._all_or(self.rows_between(a, b)))))

    def _all_or(self, rows: np.ndarray) -> Rows:
        """``rows`` (consecutive, from :meth:`rows_between`), or every row where they are: a signal of the whole
        run is computed once (:meth:`signal`'s cache), however many measures read it."""
        return slice(None) if rows.size == self.t.size else rows

    def plot(self, periods: float | None = None, signals: Iterable[str] | None = None,
             title: str | None = None) -> Figure:
        """The run's waveforms over the last periods and its mode timeline: a matplotlib Figure
        (:func:`converters.plotting.plot`)."""
        from .plotting import plot
        figure: Figure = plot(self, periods, signals, title)
        return figure

    def measurements(self, periods: float | None = None, t0: float | None = None,
                     t1: float | None = None) -> pd.DataFrame:
        """Every state and signal over the window (default: the whole run): mean, RMS, min, max and
        peak-to-peak ripple, with its unit (A, V, s; 1 for the switch command), as a DataFrame indexed by
        signal. Means and RMS by the run's own rule (exact quadrature for the event method); min, max and
        ripple on the samples."""
        import pandas as pd
        rows = self.measurement_rows(periods, t0, t1)
        return pd.DataFrame([{"signal": name, **row} for name, row in rows.items()]).set_index("signal")

    def measurement_rows(self, periods: float | None = None, t0: float | None = None, t1: float | None = None,
                         names: Iterable[str] | None = None) -> dict[str, dict[str, str | float]]:
        """:meth:`measurements` as plain data, {signal: {unit, mean, rms, min, max, ripple}} (no pandas: the JSON
        summary of a fresh process does not pay for importing it); of ``names`` only, where given."""
        a, b = self.window(periods, t0, t1)
        rows = self.rows_between(a, b)
        units = dict(getattr(getattr(self.labels, "model", None), "signal_units", {}) or {})
        sampled: dict[str, npt.NDArray[np.float64]] = {}
        chosen = None if names is None else set(names)
        for name in self.signal_names:
            if name == "mode" or (chosen is not None and name not in chosen):
                continue
            values = np.asarray(self.signal(name, rows), dtype=float)
            if np.isfinite(values).any():                     # else not measured in this run (ngspice: no pairs)
                sampled[name] = values
        measures = self._measures(list(sampled), a, b)
        if self.labels is not None and self.rule != "exact" and rows[0] == 0:
            sampled = self._first_row_solved(sampled)
        if self.labels is not None and self.rule != "exact":
            # the values just after the switching edges and at the pair events between samples belong to the
            # waveform too
            own = set(self.labels.signal_names) - set(self.measured)
            for limits in (self.edge_limits(rows), self.event_limits(rows)):
                if limits is not None:
                    sampled = {name: np.concatenate([values, np.asarray(self.labels.signal(name, limits), dtype=float)])
                               if name in own else values for name, values in sampled.items()}
        out: dict[str, dict[str, str | float]] = {}
        exact = getattr(self.labels, "waveform_measures", None)
        for name, values in sampled.items():
            mean, rms, low, high = measures[name]
            low, high = min(low, float(values.min())), max(high, float(values.max()))
            known = exact(name, a, b) if exact is not None and name not in self.measured else None
            if known is not None:       # a source's waveform alone: its own corners, not the run's samples
                mean, rms, low, high = known
            out[name] = {"unit": signal_unit(units, name), "mean": mean, "rms": rms, "min": low, "max": high,
                         "ripple": high - low}
        return out

    def _first_row_solved(self, sampled: dict[str, npt.NDArray[np.float64]]) -> dict[str, npt.NDArray[np.float64]]:
        """``sampled`` (each signal over rows from the run's first) with the first row's values at its pairs solved:
        a stepper's first row is its start state with no pairs (u = y = 0), so a signal a pair sets read 0 there (a
        bridge rectifier's diode-held node, 0 V beside its 252 V minimum, in both runs the check compares: its
        estimate then blind to the minimum). The pairs are the LCP's at that state in the first step's configuration
        where its solution is unique; else the first row is left out of the signals the model computes."""
        assert self.labels is not None
        if self.u is None or self.y is None or self.t.size < 2 or self.u[0].any() or self.y[0].any() \
                or not self.u.shape[1]:
            return sampled
        problem = self.problem
        found = (self._instant_pair(problem, 0, 1) if self.t[1] > self.t[0]
                 and getattr(problem, "configuration_at", None) is not None else None)
        own = set(self.labels.signal_names) - set(self.measured) - set(self.state_names)
        if found is None:
            return {name: values[1:] if name in own else values for name, values in sampled.items()}
        pick: Callable[[npt.NDArray[Any] | None], npt.NDArray[Any] | None] = (
            lambda a: None if a is None else a[:1])
        assert self.config is not None
        first = Samples(self.t[:1], self.x[:1], found[0][None, :], found[1][None, :], self.config[1:2],
                        pick(self.relay), pick(self.held))
        return {name: np.concatenate([np.asarray(self.labels.signal(name, first), dtype=float), values[1:]])
                if name in own else values for name, values in sampled.items()}

    def jump_losses(self, periods: float | None = None, t0: float | None = None,
                    t1: float | None = None) -> tuple[int, float]:
        """(jumps, energy in J) of the charge redistributions in the window [t0, t1) (default: the run):
        :attr:`jumps` (each entry of a configuration whose closed switches tie charged capacitors loses
        1/2 dv^T C dv)."""
        if not self.jumps:
            return 0, 0.0
        a, b = self.window(periods, t0, t1)
        slack = 1e-9 * (b - a)              # a window of whole periods meets a jump at its start, not at its end
        inside = [energy for t, energy in self.jumps if a - slack <= t < b - slack]
        return len(inside), float(sum(inside))

    def mode_fractions(self, periods: float | None = 1, t0: float | None = None,
                       t1: float | None = None) -> dict[str, float]:
        """Fraction of the window spent in each mode (each step counted by the label of its end point)."""
        a, b = self.window(periods, t0, t1)
        rows = self.rows_between(a, b)
        labels = np.asarray(self.modes(rows)).astype(str)[1:]
        dt = np.diff(self.t[rows])
        total = dt.sum()
        return {str(label): float(dt[labels == label].sum() / total) for label in sorted(set(labels))}

    def thinned(self, spacing: float, until: float, origin: float = 0.0) -> "Trajectory":
        """The run with its rows before ``until`` kept at ``spacing`` (s): the first sample at or after each
        multiple of it from ``origin``, as SPICE's output step keeps points (the steps' own values, not
        interpolated); every row from the last one before ``until`` on. Chunks of one run thinned with the same
        origin keep one sample per slot across their joints (the first row, the joint :func:`concatenate` drops,
        counts for its slot). Events keep their times and point at the kept row at or after their step. The exact
        pieces of an event-driven run stay whole (they are few)."""
        if not spacing > 0.0:
            raise ValueError(f"spacing must be positive; got {spacing!r}")
        t = self.t
        heads = int(np.searchsorted(t, until, side="left"))          # rows before ``until``
        slot = np.floor((t[:heads] - origin) / spacing + 1e-9)
        keep = np.ones(t.size, dtype=bool)
        keep[1:heads] = slot[1:] != slot[:-1]
        resolved = self.resolved_from
        if heads < t.size and heads > 0:          # the row before ``until`` too: a window starting there is whole
            keep[heads - 1] = True
            resolved = max(resolved, float(t[heads - 1]))
        rows = np.flatnonzero(keep)
        pick: Callable[[npt.NDArray[Any] | None], npt.NDArray[Any] | None] = (
            lambda a: None if a is None else a[rows])
        columns = self.event_table()
        if columns is not None:
            import pandas as pd
            columns = pd.DataFrame(columns).copy()
            columns["step"] = np.minimum(np.searchsorted(rows, np.asarray(columns["step"], dtype=np.int64)),
                                         rows.size - 1)
        measured = {k: np.asarray(v)[rows] for k, v in self.measured.items()}
        return replace(self, t=t[rows], x=self.x[rows], u=pick(self.u), y=pick(self.y), config=pick(self.config),
                       relay=pick(self.relay), held=pick(self.held), event_columns=columns, measured=measured,
                       resolved_from=resolved)

    # --- tables --------------------------------------------------------------------------------------

    def to_pandas(self, columns: str | Iterable[str] | None = None) -> pd.DataFrame:
        """Columns: time, one per state, the model's signals, ``switch`` and ``mode`` (labelled runs),
        then u_<pair>, y_<pair>, active_<pair> and ``config`` (LCS runs). ``columns`` picks a subset."""
        import pandas as pd
        data = {"time": self.t}
        for i, name in enumerate(self.state_names):
            data[name] = self.x[:, i]
        if self.labels is not None or self.measured:
            for name in self.signal_names:
                if name not in data:
                    data[name] = self.signal(name)
            data["mode"] = np.asarray(self.modes()).astype(str)
        if self.u is not None:
            assert self.y is not None                # a run with pairs has both u and y
            active = self.active
            for i, name in enumerate(self.pair_names):
                data[f"u_{name}"] = self.u[:, i]
                data[f"y_{name}"] = self.y[:, i]
                data[f"active_{name}"] = active[:, i]
        if self.config is not None:
            names = list(self.config_names) or [str(c) for c in range(int(self.config.max()) + 1)]
            # configurations a model names alike (its name need not say every level it holds) stay apart
            names = [name if names.count(name) == 1 else f"{name}#{i}" for i, name in enumerate(names)]
            data["config"] = pd.Categorical.from_codes(self.config, categories=names)
        frame = pd.DataFrame(data)
        if columns is None:
            return frame
        unknown = [c for c in (columns if not isinstance(columns, str) else [columns]) if c not in frame.columns]
        if unknown:
            raise SignalError(f"columns must be among {', '.join(frame.columns)}; got {unknown[0]!r}")
        return frame[[columns] if isinstance(columns, str) else list(columns)]

    def waveforms(self) -> pd.DataFrame:
        """The waveform table of the command line: time, states, the model's signals, mode (a signal the run
        does not measure, all NaN, is left out: an ngspice run has no pair variables to read element signals
        from)."""
        declared = self.labels.signal_names if self.labels is not None else ()
        names = list(self.state_names) + [s for s in declared if s not in self.state_names]
        frame = self.to_pandas(["time", *names, "mode"])
        unmeasured = [c for c in names if c not in self.state_names and frame[c].dtype.kind == "f"
                      and frame[c].isna().all()]
        return frame.drop(columns=unmeasured)


def concatenate(parts: list[Trajectory]) -> Trajectory:
    """One trajectory from consecutive runs (the end point of each part is the start of the next)."""
    first = parts[0]
    if len(parts) == 1:
        return first

    import pandas as pd

    def stack(name: str) -> npt.NDArray[Any] | None:
        arrays = [getattr(p, name) for p in parts]
        if any(a is None for a in arrays):
            return None
        return np.concatenate([arrays[0]] + [a[1:] for a in arrays[1:]])
    offsets = np.cumsum([0] + [p.t.size - 1 for p in parts[:-1]])
    events: list[pd.DataFrame] = []
    for part, offset in zip(parts, offsets):
        frame = part.events.copy()
        frame["step"] = frame["step"] + offset
        events.append(frame)
    exact = (JoinedExact(tuple((float(p.t[0]), float(p.t[-1]), cast(ExactSolution, p.exact)) for p in parts))
             if all(p.rule == "exact" and p.exact is not None for p in parts) else None)
    # every part has times and states: only the optional columns stack to None
    return replace(first, t=cast(np.ndarray, stack("t")), x=cast(np.ndarray, stack("x")), u=stack("u"),
                   y=stack("y"), config=stack("config"),
                   relay=stack("relay"), held=stack("held"), steps=sum(p.steps for p in parts), wall_s=sum(p.wall_s for p in parts),
                   event_columns=pd.concat(events, ignore_index=True), exact=exact,
                   rule="linear" if first.rule == "exact" and exact is None else first.rule,
                   general_solves=sum(p.general_solves for p in parts), jumps=sum((p.jumps for p in parts), ()),
                   resolved_from=max(p.resolved_from for p in parts))


@dataclass(frozen=True)
class JoinedExact:
    """The exact pieces of consecutive event-driven runs (a run split at a load step): a window's quadrature is
    each part's over its share, so a current that jumps at a switching instant is integrated as exactly across
    the parts as within one (the linear rule on the samples had put 3.5e-4 into a buck's input power)."""

    parts: tuple[tuple[float, float, ExactSolution], ...]     # (t0, t1, exact) per part, in time order

    def quadrature_blocks(self, t0: float | None = None, t1: float | None = None) -> Iterator[QuadratureBlock]:
        t0 = self.parts[0][0] if t0 is None else t0
        t1 = self.parts[-1][1] if t1 is None else t1
        for a, b, exact in self.parts:
            if min(b, t1) > max(a, t0):
                yield from exact.quadrature_blocks(max(a, t0), min(b, t1))

    def quadrature(self, t0: float | None = None, t1: float | None = None) -> QuadratureBlock:
        t0 = self.parts[0][0] if t0 is None else t0
        t1 = self.parts[-1][1] if t1 is None else t1
        pieces = [exact.quadrature(max(a, t0), min(b, t1)) for a, b, exact in self.parts if min(b, t1) > max(a, t0)]
        if len(pieces) == 1:
            return pieces[0]
        join: Callable[[str], npt.NDArray[Any] | None] = lambda name: (      # noqa: E731
            None if getattr(pieces[0][0], name) is None else np.concatenate([getattr(q, name) for q, _ in pieces]))
        samples = Samples(cast(np.ndarray, join("t")), cast(np.ndarray, join("x")), join("u"), join("y"),
                          join("config"), join("relay"), join("held"))
        return samples, np.concatenate([w for _, w in pieces])


def signal_unit(units: Mapping[str, str], name: str) -> str:
    """A signal's or state's unit: a model's ``signal_units`` where it says, else by the name (vout V, the switch
    command 1, a current i... A, a voltage v... V)."""
    return units.get(name, {"vout": "V", "switch": "1", "iref": "A"}.get(
        name, "A" if name.startswith("i") else "V" if name.startswith("v") else ""))
