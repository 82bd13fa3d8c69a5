"""The method contract: every way of solving a problem is a small, validated, immutable object.

A method (DifferentialEquations.jl's algorithm, diffrax's ``AbstractSolver``, scipy's ``OdeSolver``)
holds only its options, validated when it is made, and declares

* ``key``: its name in :data:`METHODS` (``lcp``, ``event``, ``smooth``; the command line's ``--method``);
* ``order``: its declared order of convergence in its step (``inf`` for an exact method); the tests
  check the measured order against it;
* ``error_kind`` (an :class:`ErrorKind`): how its error is estimated (``step``: Richardson's from a twin at twice
  the step, :meth:`Method.coarsened`; ``exact``; ``model``: its model's, not a step's), and the traits it gives,
  ``fixed_step`` and ``exact``: the accuracy checks read these, never the key;
* ``supports(problem)``: the problems it can solve (a clear error otherwise, before any step);
* ``solve(problem, x0) -> Trajectory``;
* ``period_map(problem)``: the map x(t0) -> x(t0 + span) over ``problem.t_span`` with its Jacobian,
  for the periodic-orbit engine (:mod:`converters.analysis.periodic`). The base class gives the
  finite-difference map (labelled as such); methods with an exact Jacobian override it.

:func:`converters.simulate.simulate` is the one entry point; nothing dispatches on a method's type.
"""
from __future__ import annotations

import dataclasses
from abc import ABC, abstractmethod
from collections.abc import Callable, Iterable, Sequence
from enum import Enum
from typing import TYPE_CHECKING, Any, ClassVar, Protocol, cast

import numpy as np
import numpy.typing as npt

from ..errors import ParameterError

if TYPE_CHECKING:
    from _typeshed import DataclassInstance

    from ..trajectory import Trajectory

#: Segments (events and integrator pieces) a run stores per forcing or switching period, generously: the
#: size estimate of a run without an output grid (the converters have 2-6, the friction oscillator ~40).
SEGMENTS_PER_PERIOD = 64

#: Method classes by their command-line name, filled as each method module is imported.
METHODS: dict[str, type["Method"]] = {}
#: The method a run takes when none is named (the LCP time-stepper).
DEFAULT_METHOD = "lcp"


class ErrorKind(str, Enum):
    """How a method's error is estimated (:attr:`Method.error_kind`); a ``str`` enum, equal to its value."""

    #: A fixed step whose error falls as step^order: Richardson's estimate from the same run at twice the step.
    STEP = "step"
    #: Exact flows with events at their instants: rounding only.
    EXACT = "exact"
    #: The error is the method's model of the circuit (a smoothing's O(eps), ngspice's devices): no step twin.
    MODEL = "model"

    def __str__(self) -> str:
        return self.value


class Method(ABC):
    """Base class of every method (subclasses are frozen dataclasses).

    Its ``problem`` arguments are typed Any: each method narrows them to the problems of its ``domains`` (an
    LCSProblem, a MechanicalProblem), which no one type of the base could admit for all of them."""

    key: ClassVar[str] = ""
    #: One line for ``pcsuite list``.
    description: ClassVar[str] = ""
    #: Name of the option that receives a run's step (``h``, or an output spacing), or "" for none.
    step_option: ClassVar[str] = ""
    #: The problems it takes: ``lcs`` (converters), ``mechanical`` (friction and impacts).
    domains: ClassVar[tuple[str, ...]] = ("lcs",)
    #: What a run's ``steps`` counts (the one-line summary's unit).
    counts: ClassVar[str] = "steps"
    #: How the accuracy checks (:mod:`converters.analysis.accuracy`) estimate the error: ``step`` a fixed step
    #: whose error falls as step^order (Richardson's estimate from the same run at twice the step,
    #: :meth:`coarsened`); ``exact`` exact flows with events at their instants (rounding only); ``model`` the
    #: error is the method's model of the circuit (a smoothing's O(eps)), which no step twin measures.
    error_kind: ClassVar[ErrorKind] = ErrorKind.STEP
    #: Traits from ``error_kind`` (set for each subclass): a fixed step that :meth:`coarsened` doubles; exact flows.
    fixed_step: ClassVar[bool] = True
    exact: ClassVar[bool] = False
    #: What a ``model`` method's error is (the summary's reason for not estimating it).
    model_error: ClassVar[str] = ""
    #: Steady states of many parameter points advance in one compiled call (:mod:`converters.sweeps.batch`).
    batches: ClassVar[bool] = False
    #: A method that runs a model's circuit itself (domain ``circuit``: ngspice) measures a sweep's points on its own
    #: run: its row's measures and their types here, the row from :meth:`sweep_row`, and :meth:`sweep_chunk_done`
    #: after each chunk (:class:`converters.sweeps.ModelSweep` asks). None: the sweep runs the method on the LCS.
    sweep_measures: ClassVar[dict[str, type] | None] = None

    def sweep_check(self, model: Any, p: dict[str, Any], steady: bool, periods: int) -> None:
        """Refuse, before a sweep runs, what its points cannot be run with (a circuit method's)."""
        raise NotImplementedError(f"the {self.key} method runs on the LCS: a sweep steps it itself")

    def sweep_row(self, model: Any, p: dict[str, Any], steady: bool, periods: int) -> dict[str, Any]:
        """The measures (:attr:`sweep_measures`) of one sweep point run by the method itself."""
        raise NotImplementedError(f"the {self.key} method runs on the LCS: a sweep steps it itself")

    def sweep_chunk_done(self) -> None:
        """After a chunk of :meth:`sweep_row` calls (a worker process it started ends with the chunk)."""

    def __init_subclass__(cls, key: str = "", **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        cls.error_kind = ErrorKind(cls.error_kind)
        cls.fixed_step = cls.error_kind is ErrorKind.STEP
        cls.exact = cls.error_kind is ErrorKind.EXACT
        if key:
            cls.key = key
            METHODS[key] = cls

    @property
    @abstractmethod
    def order(self) -> float:
        """Declared order of convergence of the method's error in its step (inf: exact)."""

    @abstractmethod
    def solve(self, problem: Any, x0: np.ndarray) -> Trajectory:
        """Solve ``problem`` over its t_span from ``x0`` (already validated) into a Trajectory."""

    def supports(self, problem: Any) -> None:
        """Raise ParameterError (naming the method and the remedy) if the problem is out of reach."""

    @property
    def label(self) -> str:
        """A short human-readable name with the main option (e.g. ``theta(0.5)``)."""
        return self.key

    def options(self) -> dict[str, object]:
        """The method's options as plain data (for JSON summaries and reports)."""
        return {f.name: getattr(self, f.name) for f in dataclasses.fields(cast("DataclassInstance", self))}

    @property
    def step(self) -> float | None:
        """The fixed step in s of a ``step`` method (its ``step_option``), else None."""
        return float(getattr(self, self.step_option)) if self.fixed_step else None

    def coarsened(self, factor: float = 2.0) -> "Method":
        """The same method at ``factor`` times its step: the twin of Richardson's estimate (``step`` methods)."""
        if not self.fixed_step:
            raise ValueError(f"the {self.key} method has no fixed step to coarsen (its error_kind is {self.error_kind})")
        step = self.step
        assert step is not None                  # a fixed-step method has its step
        return cast(Method, dataclasses.replace(cast("DataclassInstance", self), **{self.step_option: factor * step}))

    #: Measured peak bytes per stored sample and per value of it (states, pairs, time, labels), the run and its
    #: labelled waveform table (what ``--out`` writes) included: ``benchmarks/memory.py`` calibrates them.
    bytes_per_value: ClassVar[float] = 60.0

    def samples(self, problem: Any) -> float:
        """How many samples a run of ``problem`` stores (before it starts): the span over the step or output
        spacing, plus every switching instant of the law; inf where it cannot be bounded."""
        t0, t1 = problem.t_span
        step = getattr(self, self.step_option, None) if self.step_option else None
        law = getattr(problem, "switching", None)
        period = getattr(law, "period", getattr(problem, "period", np.inf))
        if step is None:            # segments only: a forced problem has a few per period, an autonomous one is
            # bounded by the method's own event cap
            return (t1 - t0) / period * SEGMENTS_PER_PERIOD if np.isfinite(period) and period > 0 else 0.0
        breaks = (t1 - t0) / period * len(getattr(law, "starts", (0,))) if np.isfinite(period) and period > 0 else 0.0
        count: float = (t1 - t0) / float(step) + breaks + 1.0
        return count

    def memory_estimate(self, problem: Any) -> float:
        """Bytes a run of ``problem`` will allocate at its peak (estimate from :meth:`samples`)."""
        values = getattr(problem, "n", 2) + 2 * getattr(problem, "k", 0) + 8
        return self.samples(problem) * values * self.bytes_per_value

    def check_memory(self, problem: Any, remedy: str = "a larger --h, or a shorter --t-end / fewer --periods") -> None:
        """Refuse, before the first step, a run above the memory limit (:mod:`converters.limits`)."""
        from ..limits import check_memory
        t0, t1 = problem.t_span
        step = getattr(self, self.step_option, None) if self.step_option else None
        check_memory(f"--method {self.key}: {t1 - t0:.3g} s" + (f" at {self.step_option} = {step:.3g} s "
                                                                f"({self.samples(problem):.3g} samples)" if step else ""),
                     self.memory_estimate(problem),
                     remedy=remedy)

    def period_map(self, problem: Any) -> "PeriodMap":
        """x(t0) -> x(t1) over ``problem.t_span`` by repeated solves, Jacobian by finite differences."""
        self.supports(problem)
        return FiniteDifferenceMap(lambda x0: self.solve(problem, x0).x[-1])

    @classmethod
    def option_names(cls) -> list[str]:
        return [f.name for f in dataclasses.fields(cast("type[DataclassInstance]", cls))]

    @classmethod
    def from_options(cls, step: float | None = None, **options: Any) -> "Method":
        """Build from command-line style options; ``step`` goes to the method's ``step_option``.

        Unknown options are refused with the list of valid ones; None values take the defaults."""
        names = cls.option_names()
        unknown = [k for k, v in options.items() if v is not None and k not in names]
        if unknown:
            raise ParameterError(f"unknown option {unknown[0]!r} for method {cls.key!r}; valid options: "
                                 f"{', '.join(names)}")
        values = {k: v for k, v in options.items() if v is not None}
        if step is not None and cls.step_option:
            values.setdefault(cls.step_option, step)
        return cls(**values)


#: The entry-point group of methods registered by other packages (pyproject's ``[project.entry-points]``).
ENTRY_POINTS = "pcsuite.methods"


_ENTRY_POINTS_READ: set[str] = set()


def load_methods(everywhere: bool = False) -> dict[str, type[Method]]:
    """Every method: the built-in ones and those registered under :data:`ENTRY_POINTS`, imported on first use
    (importing one registers it in :data:`METHODS`): pcsuite's own (ngspice, ``spice``) and, with ``everywhere``,
    every installed package's. Each is read once per process. pcsuite's own distribution's metadata is one file
    (0.3 ms); every installed package's is a scan of all their metadata (50 ms in a fresh process here, a tenth of
    a cold ``pcsuite simulate``), paid only when a method is asked for by a name nothing else registered
    (:func:`get_method`)."""
    from importlib import metadata
    scope = "everywhere" if everywhere else "pcsuite"
    if scope not in _ENTRY_POINTS_READ:
        points: Iterable[metadata.EntryPoint]
        try:
            points = [] if everywhere else [point for point in metadata.distribution("pcsuite").entry_points
                                            if point.group == ENTRY_POINTS]
        except metadata.PackageNotFoundError:      # run from a source tree that was never installed
            everywhere = True
        if everywhere:
            points = metadata.entry_points(group=ENTRY_POINTS)
        for point in points:
            if point.name not in METHODS:
                point.load()
        _ENTRY_POINTS_READ.add(scope)
    return METHODS


def get_method(key: str) -> type[Method]:
    if key not in METHODS:
        load_methods()
    if key not in METHODS:
        load_methods(everywhere=True)
    try:
        return METHODS[key]
    except KeyError:
        raise ParameterError(f"method must be one of {', '.join(METHODS)}; got {key!r}") from None


class PeriodMap:
    """x0 -> (x at the end of the span, d x_end / d x0), counting the spans it simulates.

    ``jacobian_kind`` says how the Jacobian is computed: ``exact`` (product of the one-step
    matrices, or state-transition and saltation matrices) or ``finite differences``."""

    jacobian_kind = "exact"

    def __init__(self) -> None:
        self.evaluations = 0

    def __call__(self, x0: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        raise NotImplementedError

    def end(self, x0: np.ndarray) -> np.ndarray:
        """The end state only (no Jacobian)."""
        return self(x0)[0]

    def events(self, x0: np.ndarray) -> Sequence[tuple[float, str, int, int]] | None:
        """The events of the span from x0 as (time, kind, pair, config) tuples in time order (``kind`` as in
        a Trajectory's events; ``pair`` -1 and ``config`` the configuration entered for a switching-law
        event), or None where the map does not record them (callers then simulate)."""
        return None


class RecordedSolution(Protocol):
    """A :class:`RecordingPeriodMap`'s run: the state at the end of its span, and its events as
    :meth:`PeriodMap.events` gives them."""

    @property
    def x_end(self) -> npt.NDArray[np.float64]: ...

    def event_list(self) -> Sequence[tuple[float, str, int, int]]: ...


class RecordingPeriodMap(PeriodMap):
    """A period map that keeps its last run: ``events(x0)`` reuses it when x0 is the state it started from.
    Subclasses give ``_solve(x0, jacobian) -> (solution, jacobian or None)``, the solution with ``x_end`` and
    ``event_list()``."""

    def __init__(self) -> None:
        super().__init__()
        self._last: tuple[np.ndarray | None, RecordedSolution | None] = (None, None)

    def _solve(self, x0: npt.NDArray[np.float64],
               jacobian: bool) -> tuple[RecordedSolution, npt.NDArray[np.float64] | None]:
        raise NotImplementedError

    def _run(self, x0: np.ndarray, jacobian: bool) -> tuple[RecordedSolution, npt.NDArray[np.float64] | None]:
        self.evaluations += 1
        x0 = np.array(x0, dtype=float)
        solution, jac = self._solve(x0, jacobian)
        self._last = (x0, solution)
        return solution, jac

    def end(self, x0: np.ndarray) -> np.ndarray:
        return self._run(x0, False)[0].x_end

    def __call__(self, x0: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        solution, jac = self._run(x0, True)
        assert jac is not None                   # asked for: every _solve gives it
        return solution.x_end, jac

    def events(self, x0: np.ndarray) -> Sequence[tuple[float, str, int, int]] | None:
        last_x0, solution = self._last
        if last_x0 is None or not np.array_equal(last_x0, np.asarray(x0, dtype=float)):
            solution = self._run(x0, False)[0]
        assert solution is not None              # kept with the x0 it started from
        return solution.event_list()


class _SteppedMethod(Protocol):
    """A theta stepper's options (:func:`check_step_and_theta`)."""

    @property
    def h(self) -> float: ...

    @property
    def theta(self) -> float: ...


def check_step_and_theta(method: _SteppedMethod) -> None:
    """Validate a stepper's ``h`` (positive) and ``theta`` (in [0.5, 1]) in place (frozen dataclasses)."""
    from ..validate import check_positive, parse_value
    object.__setattr__(method, "h", check_positive("h", method.h, "s"))
    theta = parse_value("theta", method.theta)
    if not 0.5 <= theta <= 1.0:
        raise ParameterError(f"theta must be in [0.5, 1]; got {theta!r}")
    object.__setattr__(method, "theta", theta)


class FiniteDifferenceMap(PeriodMap):
    """Forward differences with steps 1e-7 (1 + |x_j|): n + 1 spans per Jacobian."""

    jacobian_kind = "finite differences"

    def __init__(self, end: Callable[[npt.NDArray[np.float64]], npt.ArrayLike]) -> None:
        super().__init__()
        self._end = end

    def end(self, x0: np.ndarray) -> np.ndarray:
        self.evaluations += 1
        return np.asarray(self._end(np.asarray(x0, dtype=float)), dtype=float)

    def __call__(self, x0: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        x0 = np.asarray(x0, dtype=float)
        base = self.end(x0)
        jac = np.empty((x0.size, x0.size))
        for j in range(x0.size):
            dx = 1e-7 * (1.0 + abs(x0[j]))
            probe = x0.copy()
            probe[j] += dx
            jac[:, j] = (self.end(probe) - base) / dx
        return base, jac
