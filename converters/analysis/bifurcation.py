"""Brute-force bifurcation diagrams: the attractor's stroboscopic samples against a parameter.

For each parameter value the problem is simulated from a start state for ``transient`` + ``record``
switching periods (one run of the method: the compiled stepper's loop, or the event method) and the
states at the last ``record`` period starts x(t0 + m T) are kept; the method's output must hold the
period starts (the stepper's grid does: ramp resets are grid points; give the event method
``output_step = T``). Each attractor gets its period: the smallest p <= record / 2 with
|x_{m+p} - x_m| below ``period_rtol`` (relative) for every kept m, or 0 (no period found: chaotic,
quasi-periodic, or not settled yet, as next to a bifurcation where the multipliers approach the unit
circle). Optionally the largest Lyapunov exponent of the map, lambda = lim (1/N) sum log |J_m w_m| (w_m
the unit vector carried along by the Jacobians J_m of the method's period map), says what the samples
cannot: lambda < 0 on a periodic attractor, > 0 on a chaotic one (nepers per switching period).

Values are taken in contiguous chunks of ``chunk``; inside a chunk each value starts from the previous
value's final state (the attractor followed along the path, so short transients suffice), the first one
of a chunk from ``x0`` with twice the transient. Chunks run in parallel (:mod:`converters.parallel`); the
result does not depend on the number of workers.
"""
from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any, TypeVar

import numpy as np
import numpy.typing as npt

from ..errors import ParameterError
from ..validate import shortened, as_matrix, as_vector, check_integer, check_range
from ..parallel import parallel_map

if TYPE_CHECKING:
    from ..methods.base import Method, PeriodMap

#: What :func:`_chained` collects per value (an Attractor, a SectionRow).
_Row = TypeVar("_Row")


@dataclass(frozen=True)
class Attractor:
    """What iterating the period map showed at one parameter value.

    Attributes
    ----------
    value : float
    samples : ndarray, shape (record, n)
        x(t0 + m T) after the transient.
    period : int
        Smallest period (in switching periods) of the samples, 0 when none was found.
    lyapunov : float
        Largest Lyapunov exponent per switching period over the recorded periods (nan when not computed).
    error : str
        Why the run stopped (the samples are then empty), or empty.
    """

    value: float
    samples: np.ndarray
    period: int
    lyapunov: float
    error: str = ""


def detect_period(samples: np.ndarray, rtol: float = 1e-6) -> int:
    """The smallest p <= len(samples) / 2 with |x_{m+p} - x_m| <= rtol (1 + max |x|) for every m, else 0.

    ``samples``: one sample per period, as a vector (a scalar per period) or a (periods, n) matrix."""
    rtol = check_range("rtol", rtol, 0.0, 1.0, low_open=True)
    if getattr(samples, "ndim", None) == 2 or (isinstance(samples, (list, tuple)) and samples
                                                and isinstance(samples[0], (list, tuple, np.ndarray))):
        samples = as_matrix("samples", samples, (None, None))
    else:
        samples = as_vector("samples", samples, None)
    if samples.shape[0] < 2:
        return 0
    limit = rtol * (1.0 + np.abs(samples).max())
    for p in range(1, samples.shape[0] // 2 + 1):
        if np.abs(samples[p:] - samples[:-p]).max() <= limit:
            return p
    return 0


def iterate(period_map: PeriodMap, x0: npt.ArrayLike, transient: int, record: int,
            lyapunov: bool = True) -> tuple[np.ndarray, float]:
    """Samples x(t0 + m T), m = transient .. transient + record - 1, of the one-period map, and the largest
    Lyapunov exponent over the recorded periods (nan without ``lyapunov``)."""
    x = np.array(x0, dtype=float)
    for _ in range(transient):
        x = period_map.end(x)
    samples = np.empty((record, x.size))
    growth = np.empty(record)
    for m, (sample, growth[m]) in enumerate(_tangent_growth(period_map, x, record, lyapunov)):
        samples[m] = sample
    return samples, (float(growth.sum()) / record if lyapunov else float("nan"))


def lyapunov_interval(period_map: PeriodMap, x0: npt.ArrayLike, transient: int, blocks: int, block: int,
                      confidence: float = 0.95) -> tuple[float, float, np.ndarray]:
    """The largest Lyapunov exponent per period of the map, with its confidence interval by batch means: one
    tangent vector carried over ``blocks`` consecutive blocks of ``block`` periods (after ``transient``), each
    block's mean log growth a sample, the half-width Student's t quantile times their standard error. Returns
    (exponent, half-width, the blocks' exponents). For a flow sampled at fixed times a periodic attractor's
    exponent is 0 (the flow's direction); its blocks scatter as the speed along the orbit differs at their ends,
    which the half-width states."""
    from scipy import stats
    blocks = check_integer("blocks", blocks, 2)
    block = check_integer("block", block, 1)
    confidence = check_range("confidence", confidence, 0.0, 1.0, low_open=True, high_open=True)
    x = np.array(x0, dtype=float)
    for _ in range(transient):
        x = period_map.end(x)
    growth = np.array([g for _, g in _tangent_growth(period_map, x, blocks * block, True)])
    means = growth.reshape(blocks, block).mean(axis=1)
    half = float(stats.t.ppf(0.5 + 0.5 * confidence, blocks - 1) * means.std(ddof=1) / np.sqrt(blocks))
    return float(means.mean()), half, means


def _tangent_growth(period_map: PeriodMap, x: npt.NDArray[np.float64], steps: int,
                    lyapunov: bool) -> Iterator[tuple[npt.NDArray[np.float64], float]]:
    """(x before each step, log of the tangent vector's growth over it: 0 without ``lyapunov``) for ``steps``
    steps of the map from x, the tangent vector renormalised each step."""
    w = np.ones(x.size) / np.sqrt(x.size)
    for _ in range(steps):
        before, size = x, 1.0
        if lyapunov:
            x, jac = period_map(x)
            w = jac @ w
            size = float(np.linalg.norm(w))
            if size == 0.0 or not np.isfinite(size):        # a multiplier at zero (a held pair): restart
                w, size = np.ones(x.size) / np.sqrt(x.size), 1e-300
            w = w / size
        else:
            x = period_map.end(x)
        if not np.all(np.isfinite(x)):
            raise FloatingPointError("the state left the finite numbers")
        yield before, np.log(size)


def _chained(values: Iterable[float], x0: npt.NDArray[np.float64],
             one: Callable[[float, npt.NDArray[np.float64], bool], tuple[_Row, npt.NDArray[np.float64]]],
             failed: Callable[[float, str], _Row]) -> list[_Row]:
    """``one(value, x, first) -> (row, final state)`` along ``values``, each value from the previous one's final
    state (the first from x0); a value the model or method refuses becomes ``failed(value, message)`` and the
    chain starts again from x0."""
    out, x = [], np.array(x0, dtype=float)
    for i, value in enumerate(values):
        try:
            row, x_end = one(float(value), x, i == 0)
        except (ValueError, RuntimeError, ArithmeticError) as exc:
            out.append(failed(float(value), f"{type(exc).__name__}: {exc}"))
            x = np.array(x0, dtype=float)
            continue
        out.append(row)
        x = x_end
    return out


@dataclass(frozen=True)
class _Chunk:
    """One worker task: a run of consecutive values (picklable)."""

    problem_of: Callable[[float], Any]
    method: Method
    x0: np.ndarray
    transient: int
    record: int
    lyapunov: bool
    period_rtol: float

    def __call__(self, values: Iterable[float]) -> list[Attractor]:
        def one(value: float, x: npt.NDArray[np.float64], first: bool) -> tuple[Attractor, npt.NDArray[np.float64]]:
            samples, x_end, lyap = self.one(value, x, self.transient * (2 if first else 1))
            return Attractor(value, samples, detect_period(samples, self.period_rtol), lyap), x_end

        def failed(value: float, message: str) -> Attractor:
            return Attractor(value, np.empty((0, self.x0.size)), 0, float("nan"), message)
        return _chained(values, self.x0, one, failed)

    def one(self, value: float, x: npt.NDArray[np.float64], transient: int) -> tuple[np.ndarray, np.ndarray, float]:
        """(samples at the period starts, the state at the end, Lyapunov exponent or nan) of one value."""
        from ..simulate import simulate
        problem = self.problem_of(value)
        T = problem.period
        if not np.isfinite(T):
            raise ParameterError("a brute-force diagram needs a periodic switching law (a schedule or a ramp)")
        t0 = problem.t_span[0]
        periods = transient + self.record
        run = simulate(replace(problem, t_span=(t0, t0 + periods * T)), self.method, x0=x)
        targets = t0 + T * np.arange(transient, periods + 1)
        rows = np.minimum(np.searchsorted(run.t, targets - 1e-9 * T), run.t.size - 1)
        if np.abs(run.t[rows] - targets).max() > 1e-6 * T:
            raise ParameterError(f"the method's output must hold every period start t0 + m T (the stepper's grid "
                                 f"does; give the event method output_step = T = {T:g} s); got {self.method.label}")
        samples, x_end = run.x[rows[:-1]], run.x[rows[-1]]
        lyap = float("nan")
        if self.lyapunov:
            period_map = self.method.period_map(replace(problem, t_span=(t0, t0 + T)))
            lyap = iterate(period_map, samples[0], 0, self.record, True)[1]
        return samples, x_end, lyap


def _path_values(values: npt.ArrayLike) -> np.ndarray:
    """The diagram's parameter values: finite numbers, at least one ("abc": numpy's words had named no parameter)."""
    try:
        out = np.asarray(values, dtype=float).ravel()
    except (TypeError, ValueError):
        out = np.empty(0)
    if out.size == 0 or not np.all(np.isfinite(out)):
        raise ParameterError(f"values must be finite numbers, at least one; got {values!r}")
    return out


def brute_force(problem_of: Callable[[float], Any], method: Method, values: npt.ArrayLike, x0: npt.ArrayLike, *,
                transient: int = 200, record: int = 64, lyapunov: bool = False, period_rtol: float = 1e-6,
                chunk: int = 20, workers: int | None = None, progress: bool = False) -> list[Attractor]:
    """The brute-force diagram over ``values`` (module docstring).

    Parameters
    ----------
    problem_of : picklable callable
        Parameter value -> problem (its switching law must have a period T; only its start time is used).
    method : Method
        Any method whose output holds the period starts (module docstring).
    values : array_like
        Parameter values, in path order.
    x0 : array_like, shape (n,)
        Start state of each chunk.
    transient, record : int
        Periods dropped, then kept, at each value.
    lyapunov : bool
        Also estimate the largest Lyapunov exponent over the recorded periods from the Jacobians of the
        method's period map (exact for the event method; finite differences for the stepper under a
        state-driven law: n + 1 runs a period).
    chunk, workers, progress
        Values per task, processes (default: every core this process may use), a progress bar.

    Returns
    -------
    list of Attractor, one per value.
    """
    values = _path_values(values)
    for name, count, low in (("transient", transient, 0), ("record", record, 1), ("chunk", chunk, 1)):
        check_integer(name, count, low)                                     # chunk 0: a range() crash before
    if not (isinstance(period_rtol, (int, float, np.floating)) and 0.0 < period_rtol < 1.0):
        raise ParameterError(f"period_rtol must be in (0, 1); got {period_rtol!r}")   # -1 or NaN: accepted before
    if not isinstance(lyapunov, (bool, np.bool_)):
        raise ParameterError(f"lyapunov must be True or False; got {lyapunov!r}")
    task = _Chunk(problem_of, method, np.array(x0, dtype=float), int(transient), int(record), lyapunov, period_rtol)
    chunks = [values[i:i + chunk] for i in range(0, values.size, chunk)]
    results = parallel_map(task, chunks, workers=workers, chunk=1, progress=progress, label="brute-force diagram",
                           unit="chunk")
    return [attractor for part in results for attractor in part]


@dataclass(frozen=True)
class SectionRow:
    """The events of one kind (a Poincare section: block 1 starting to stick, an impact) seen at one value after
    the transient: their times, their phases in the time unit, and the states there."""

    value: float
    times: np.ndarray
    phases: np.ndarray
    states: np.ndarray
    error: str = ""


@dataclass(frozen=True)
class _SectionChunk:
    problem_of: Callable[[float], Any]
    method: Method
    x0: np.ndarray
    transient: float
    record: float
    unit: float
    kind: str
    pair: int

    def __call__(self, values: Iterable[float]) -> list[SectionRow]:
        from ..simulate import simulate

        def one(value: float, x: npt.NDArray[np.float64], first: bool) -> tuple[SectionRow, npt.NDArray[np.float64]]:
            transient = self.transient * (2 if first else 1)
            problem = self.problem_of(value)
            t0 = problem.t_span[0]
            unit = problem.period if np.isfinite(problem.period) else self.unit
            run = simulate(replace(problem, t_span=(t0, t0 + (transient + self.record) * unit)), self.method, x0=x)
            events = run.events
            chosen = events[(events["kind"] == self.kind) & (events["pair"] == self.pair)
                            & (events["time"] >= t0 + transient * unit)]
            times = chosen["time"].to_numpy(dtype=float)
            states = np.column_stack([np.interp(times, run.t, run.x[:, k]) for k in range(run.x.shape[1])]) \
                if times.size else np.empty((0, run.x.shape[1]))
            return SectionRow(value, times, np.mod(times - t0, unit) / unit, states), run.x[-1]

        def failed(value: float, message: str) -> SectionRow:
            return SectionRow(value, np.empty(0), np.empty(0), np.empty((0, self.x0.size)), message)
        return _chained(values, self.x0, one, failed)


def section_diagram(problem_of: Callable[[float], Any], method: Method, values: npt.ArrayLike, x0: npt.ArrayLike, *,
                    kind: str, pair: int, transient: float = 50.0, record: float = 50.0, unit: float | None = None,
                    chunk: int = 10, workers: int | None = None, progress: bool = False) -> list[SectionRow]:
    """A brute-force diagram on a Poincare section: at each value, the events of ``kind`` on ``pair`` after
    ``transient`` time units, over ``record`` more (the unit: the forcing period, or ``unit`` for an
    autonomous problem); chunks seeded along the path and run in parallel as in :func:`brute_force`."""
    values = _path_values(values)
    task = _SectionChunk(problem_of, method, np.array(x0, dtype=float), float(transient), float(record),
                         float(unit or 1.0), kind, int(pair))
    chunks = [values[i:i + chunk] for i in range(0, values.size, chunk)]
    results = parallel_map(task, chunks, workers=workers, chunk=1, progress=progress, label="section diagram",
                           unit="chunk")
    return [row for part in results for row in part]


def aperiodic_onset(attractors: list[Attractor], run: int = 3) -> float | None:
    """The first value (in path order) that starts ``run`` consecutive attractors without a period (and
    without errors), or None. Isolated aperiodic values next to a bifurcation (slow convergence where a
    multiplier nears the unit circle) do not count."""
    _check_attractors(attractors)
    run = check_integer("run", run, 1)
    streak = 0
    for i, a in enumerate(attractors):
        streak = streak + 1 if (not a.error and a.period == 0) else 0
        if streak == run:
            return attractors[i - run + 1].value
    return None


def _check_attractors(attractors: object) -> None:
    if not (isinstance(attractors, (list, tuple)) and all(isinstance(a, Attractor) for a in attractors)):
        raise ParameterError(f"attractors must be a list of Attractor (from brute_force); got {shortened(attractors)}")


def period_windows(attractors: list[Attractor]) -> list[dict]:
    """Consecutive values with the same detected period: [{period, first, last, count}] in path order."""
    _check_attractors(attractors)
    windows: list[dict] = []
    for a in attractors:
        period = -1 if a.error else a.period
        if windows and windows[-1]["period"] == period:
            windows[-1].update(last=a.value, count=windows[-1]["count"] + 1)
        else:
            windows.append({"period": period, "first": a.value, "last": a.value, "count": 1})
    return windows


__all__ = ["Attractor", "brute_force", "iterate", "lyapunov_interval", "detect_period", "aperiodic_onset",
           "period_windows", "SectionRow", "section_diagram"]
