"""The theta method: the LCP time-stepper.

Data flow, time schedules: the schedule's switching instants are merged into the uniform grid so
that every step lies inside one configuration; the one-step matrices are computed once per
(configuration, step size) pair (the uniform step plus the split steps at switching instants); the
compiled loop (:func:`.theta_kernels.run_steps`) advances the state, solving each step's small LCP
inline; any step it cannot solve inline is solved here by Lemke and the loop resumes.

State-driven laws: a hysteresis or latched :class:`StateSwitching`, or several at once (:class:`Comparators`),
runs in :func:`.theta_kernels.run_state_switched` (each crossing located inside the step, the step redone from
it); the implicit :class:`Relay` in :func:`.theta_kernels.run_relay` (one LCP of size
k + 2 per step).

The period map of a scheduled run has an exact Jacobian: the product of the one-step derivatives
Phi - H_J M_JJ^-1 C_J Phi over the run (:func:`.theta_kernels.step_jacobian`; with one pair, each step's
own affine map).
"""
from __future__ import annotations

import functools
import time
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any, NamedTuple, cast

import numpy as np
import numpy.typing as npt

from ..errors import ParameterError, SimulationError
from ..compiled import EVENTS_FULL, FORBIDDEN, MAX_INLINE_K, NO_SOLUTION, OK, kernel, register_state
from ..problems import Comparators, LCSProblem, Relay, Schedule, StateSwitching
from ..problems.switching import initial_bits, law_channels
from ..trajectory import Trajectory
from .base import Method, PeriodMap, check_step_and_theta
from .discretize import StepMatrices, step_matrices

if TYPE_CHECKING:
    from ..problems.lcs import Configuration

FloatArray = npt.NDArray[np.float64]
#: Configurations and matrix sets by index (int32 for the compiled loops' ``which``, int64 elsewhere).
IndexArray = npt.NDArray[np.integer[Any]]
#: A matrix set's key: a configuration index, or (index, step start, dt) under sinusoidal inputs.
SetKey = int | tuple[int, float, float]
#: A run's grid and sets (:func:`_plan`): (t, config at each grid point, each step's set, set_configs, set_dts).
Plan = tuple[FloatArray, IndexArray, npt.NDArray[np.int32], list[SetKey], FloatArray]
#: A run's event columns (time, step, pair, kind, config), or what locates them when first read.
EventTable = dict[str, npt.NDArray[Any]]
Events = EventTable | Callable[[], EventTable]
#: A state-driven law as the compiled loop's per-channel arrays (:func:`law_arrays`).
LawArrays = tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray, FloatArray, FloatArray,
                  npt.NDArray[np.int64], npt.NDArray[np.int64], FloatArray, npt.NDArray[np.int64]]


@dataclass(frozen=True)
class Theta(Method, key="lcp"):
    """The theta-method (Moreau): x_{k+1} = x_k + h [theta f(x_{k+1}) + (1 - theta) f(x_k)] + h B u_{k+1}.

    The complementarity multiplier u is taken fully implicitly (an impulse over the step), so
    each step is one LCP(q, M) with M = D + h C W B, W = (I - h theta A)^-1.

    Parameters
    ----------
    h : float
        Step size in s (> 0). Steps are split at the schedule's switching instants.
    theta : float
        In [0.5, 1]: 1 is backward Euler (order 1, L-stable), 0.5 the trapezoidal rule (order 2
        on smooth stretches; about 1 through the diode switchings, with a smaller constant).
    grade : float
        The first step after each switching instant of a time schedule as a fraction of h, in [0, 1): 0 (the
        default) steps uniformly; otherwise the steps start at grade h and grow by ``growth`` a step until they
        reach h, as SPICE cuts its step at a breakpoint and lets it grow back: fine where the transients a
        switching starts (a diode's RS C charge transfer) are fast, h elsewhere.
    growth : float
        The ratio of consecutive graded steps, in (1, 10].
    """

    h: float
    theta: float = 0.5
    grade: float = 0.0
    growth: float = 1.2
    step_option = "h"
    batches = True
    bytes_per_value = 50.0
    description = ("LCP time-stepper: theta method (--theta in [0.5, 1], 1 = backward Euler; default 0.5 where the "
                   "step resolves every time constant of the circuit, else 1), one LCP per step")

    def __post_init__(self) -> None:
        check_step_and_theta(self)
        from ..validate import parse_value
        grade, growth = parse_value("grade", self.grade), parse_value("growth", self.growth)
        if not 0.0 <= grade < 1.0:
            raise ParameterError(f"grade (the first step after a switching instant, as a fraction of h) must be in "
                                 f"[0, 1); got {grade!r}")
        if not 1.0 < growth <= 10.0:
            raise ParameterError(f"growth (the ratio of consecutive graded steps) must be in (1, 10]; got {growth!r}")
        object.__setattr__(self, "grade", grade)
        object.__setattr__(self, "growth", growth)

    @property
    def graded(self) -> tuple[float, ...]:
        """The grid's offsets after each switching instant (:attr:`grade`): grade h, then each step ``growth``
        times the last, while it is shorter than h; () for uniform steps."""
        if not self.grade:
            return ()
        offsets, step, at = [], self.grade * self.h, 0.0
        while step < self.h:
            at += step
            offsets.append(at)
            step *= self.growth
        return tuple(offsets)

    def samples(self, problem: LCSProblem) -> float:
        """The uniform run's samples and the graded steps after each switching instant."""
        base = super().samples(problem)
        law, (t0, t1) = problem.switching, problem.t_span
        if not self.grade or not isinstance(law, Schedule) or not np.isfinite(law.period):
            return base
        return base + len(self.graded) * ((t1 - t0) / law.period + 1.0) * len(law.starts)

    def memory_estimate(self, problem: LCSProblem) -> float:
        """The run's samples (:meth:`Method.memory_estimate`) and, with sinusoidal inputs, its plan's matrix sets:
        one a step of the period (each step's inputs differ), each with its n x n, n x k and k x k matrices and
        the stacks they are built from (:func:`.discretize.step_matrices`): 6 n^2 + 9 n k + 4 k^2 values a set,
        measured 0.92 of it at peak (a 12-stage ladder, n = k = 24, at 6,400 steps a period: 564 MB). Without
        inputs a period's sets are its configurations: a few."""
        base = super().memory_estimate(problem)
        law = problem.switching
        if getattr(problem, "inputs", None) is None or not isinstance(law, Schedule) or not np.isfinite(law.period):
            return base
        n, k = problem.n, problem.k
        sets = law.period / self.h + len(law.starts) * (1 + len(self.graded))
        return base + sets * 8.0 * (6 * n * n + 9 * n * k + 4 * k * k)

    @property
    def order(self) -> float:
        """1 for backward Euler, 2 for theta = 0.5 (on smooth stretches); 1 otherwise."""
        return 2.0 if self.theta == 0.5 else 1.0

    @property
    def label(self) -> str:
        return "backward-euler" if self.theta == 1.0 else f"theta({self.theta:g})"

    def supports(self, problem: LCSProblem) -> None:
        if self.grade and not isinstance(problem.switching, Schedule):
            raise ParameterError("grade: graded steps follow a time schedule's switching instants; this problem "
                                 "switches on its state (its instants are not known before the run)")
        if getattr(problem, "inputs", None) is not None and not isinstance(problem.switching, Schedule):
            raise ParameterError("sinusoidal inputs (SIN sources) need a time schedule in the stepper; a state-driven "
                                 "law with them is not supported")
        if problem.jumps and not isinstance(problem.switching, Schedule):
            raise ParameterError("a switch that closes across a capacitance (the charges jump) under a state-driven "
                                 "law is not stepped yet (its crossings are located inside a step): use --method event")
        if not isinstance(problem.switching, Schedule) and problem.k > MAX_INLINE_K:
            raise ParameterError(f"the state-driven laws need k <= {MAX_INLINE_K} complementarity pairs in the "
                                 f"stepper; this problem has k = {problem.k}")

    def solve(self, problem: LCSProblem, x0: np.ndarray) -> Trajectory:
        start = time.perf_counter()
        law = problem.switching
        if isinstance(law, Schedule):
            plan = StepPlan.build(problem, self)
            return plan.trajectory(x0, wall_s=time.perf_counter() - start)
        if isinstance(law, (StateSwitching, Comparators)):
            return _solve_state_switched(problem, self, x0, start)
        return _solve_relay(problem, self, x0, start)

    def period_map(self, problem: LCSProblem) -> PeriodMap:
        """Scheduled problems: the exact Jacobian of the discrete map; otherwise finite differences."""
        self.supports(problem)
        if isinstance(problem.switching, Schedule):
            return StepPlanMap(StepPlan.build(problem, self))
        return super().period_map(problem)


#: The largest h |lambda| the trapezoidal rule is given: its amplification (1 + z/2) / (1 - z/2) of a decaying
#: mode z = h lambda is 0.33 at z = -1 (exact: 0.37), 0 at z = -2 and tends to -1 as z -> -inf, so a mode the step
#: does not resolve flips sign every step and hardly decays: it rings.
RESOLVED = 1.0
#: A pair whose u and y after a step are both within this fraction of the step's largest pair quantity is at its
#: corner (:meth:`StepPlan.corners_blocking`).
CORNER = 1e-12


def _flows(configurations: Iterable[Configuration], held: bool = True) -> Iterator[FloatArray]:
    """Each configuration's A and, with ``held``, A - B_j D_jj^-1 C_j for each pair j with D_jj > 0 (a diode's series
    resistance in conduction: a time constant the free flow does not show)."""
    for config in configurations:
        yield config.A
        if held:
            for j in range(config.D.shape[0]):
                if config.D[j, j] > 0.0:
                    yield config.A - np.outer(config.B[:, j], config.C[j]) / config.D[j, j]


def fastest_rate(configurations: Iterable[Configuration], *, held: bool = True, below: float = 0.0) -> float:
    """The largest |lambda| (1/s) of the configurations' flows (:func:`_flows`). With ``below`` > 0 a flow whose
    row-sum norm (a bound on its |lambda|) is at most ``below`` is not decomposed: the answer is then exact where it
    is above ``below``, and at most ``below`` otherwise (enough to compare with it, at a fraction of the cost on a
    sweep's points)."""
    fastest = 0.0
    for A in _flows(configurations, held):
        if not (A.size and np.isfinite(A).all()):
            continue
        if below > 0.0 and np.abs(A).sum(axis=1).max() <= below:
            continue                    # |lambda| <= its norm <= below: no change to a comparison with below
        fastest = max(fastest, float(np.abs(np.linalg.eigvals(A)).max()))
    return fastest


def stable_theta(rate: float, h: float) -> float:
    """The default theta for steps of ``h`` s on a circuit whose fastest mode decays at ``rate`` (1/s,
    :func:`fastest_rate`): 0.5 (the trapezoidal rule, second order) where the step resolves it (h rate <=
    :data:`RESOLVED`), else 1 (backward Euler, L-stable: a mode faster than the step is damped in one step instead
    of ringing)."""
    return 0.5 if h * rate <= RESOLVED else 1.0


def overdamped_resonance(configurations: Iterable[Configuration], h: float,
                         theta: float) -> tuple[float, float, float] | None:
    """The resonance the theta method damps most beyond the circuit's own damping, as (frequency in Hz, Q, the
    ratio of the scheme's extra decay rate to the mode's own), where that ratio exceeds 1; None where no
    oscillatory mode is damped more by the step than by the circuit. The scheme's decay rate of a mode lambda is
    -ln|r(h lambda)| / h, r(z) = (1 + (1 - theta) z) / (1 - theta z): backward Euler adds ~h omega^2 / 2 (a
    100 pF snubber's 5 MHz ring with a 10 uH inductor, Q 316, decays 96x faster at h = 10 ns than it does)."""
    if theta <= 0.5:        # the trapezoid adds no damping: a ratio above 1 there is the rounding of an undamped mode
        return None
    worst = None
    for config in configurations:
        for lam in np.linalg.eigvals(config.A) if config.A.size and np.isfinite(config.A).all() else ():
            sigma, omega = -lam.real, abs(lam.imag)
            if omega <= 0.0 or sigma <= UNDAMPED * abs(lam):
                continue
            z = h * lam
            extra = -np.log(abs((1.0 + (1.0 - theta) * z) / (1.0 - theta * z))) / h - sigma
            ratio = extra / sigma
            if ratio > 1.0 and (worst is None or ratio > worst[2]):
                worst = (omega / (2.0 * np.pi), abs(lam) / (2.0 * sigma), float(ratio))
    return worst


#: A mode whose decay rate is below this fraction of its |lambda| is undamped: its decay is the eigenvalues' rounding
#: (a flyback's 0.2 uH leakage with 1 nF, coupled at k = 0.999: 7e-12 of |lambda|, its matrix ill-conditioned; a
#: resistance of a micro-ohm in that loop would damp it by 4e-8).
UNDAMPED = 1e-9


def undamped_resonance(configurations: Iterable[Configuration]) -> tuple[float, float] | None:
    """(frequency in Hz, Q) of the highest-frequency oscillatory mode no resistance damps (decay below
    :data:`UNDAMPED` of |lambda|: an LC loop with no resistance in it), or None."""
    found = None
    for config in configurations:
        for lam in np.linalg.eigvals(config.A) if config.A.size and np.isfinite(config.A).all() else ():
            sigma, omega = -lam.real, abs(lam.imag)
            if omega > 0.0 and abs(sigma) <= UNDAMPED * abs(lam) and (found is None or omega > found[0]):
                found = (omega, abs(lam) / (2.0 * max(abs(sigma), 1e-300)))
    return None if found is None else (found[0] / (2.0 * np.pi), found[1])


def default_theta(configurations: Iterable[Configuration], h: float) -> float:
    """:func:`stable_theta` for ``configurations`` stepped at ``h``, their flows decomposed only where a norm bound
    leaves it open (the default of every run and every sweep point)."""
    return stable_theta(fastest_rate(configurations, below=RESOLVED / h), h)


#: The most a mode may flip and keep of its amplitude in one step before a theta is refused for ringing.
RINGS = 0.5


def check_ringing(theta: float, rate: float, h: float) -> None:
    """Refuse a theta that rings on the fastest mode: its amplification (1 + (1 - theta) z) / (1 - theta z) at
    z = -h rate below -:data:`RINGS` (theta 0.5: from h rate > 6; 73,995 V from a 10 V source on a 1 fs node)."""
    z = -h * rate
    if (1.0 + (1.0 - theta) * z) / (1.0 - theta * z) < -RINGS:
        raise ParameterError(f"theta {theta:g} rings on this circuit's fastest mode (time constant {1 / rate:.3g} s, "
                             f"{h * rate:.3g} of them in a step of {h:.3g} s: each step flips it and keeps more than "
                             f"half of it): use theta 1 (backward Euler; the default here) or h below "
                             f"{RESOLVED / rate:.3g} s")


def BackwardEuler(h: float) -> Theta:
    """Backward Euler, the seed's Algorithm 1: ``Theta(h, theta=1)``."""
    return Theta(h=h, theta=1.0)


MAX_STEPS = 200_000_000


def time_grid(problem: LCSProblem, h: float, graded: tuple[float, ...] = ()) -> np.ndarray:
    """Uniform grid of step h over t_span, with every switching instant inserted; ``graded``: offsets after each
    switching instant (t0 among them where the schedule switches there) that replace the uniform points they span
    (:attr:`Theta.graded`).

    Grid points closer than h/1000 to a switching instant are dropped (the instant replaces them), but for a period's
    start (a multiple of the switching period).
    """
    t0, t1 = problem.t_span
    Theta(h=h, theta=1.0).check_memory(problem)           # before anything of the run's size is allocated
    n_steps = int(np.ceil((t1 - t0) / h * (1.0 - 1e-12)))
    uniform = t0 + h * np.arange(n_steps + 1)
    uniform[-1] = t1
    breaks = problem.switching.breakpoints(t0, t1)
    if graded:
        # graded steps follow a schedule's instants (Theta.supports)
        uniform, breaks = _graded(cast(Schedule, problem.switching), uniform, breaks, t0, t1, h, np.asarray(graded))
    if breaks.size == 0:
        return uniform
    nearest = np.searchsorted(breaks, uniform)         # breaks[nearest - 1] < uniform <= breaks[nearest]
    bounded = np.concatenate(([-np.inf], breaks, [np.inf]))
    gap = np.minimum(bounded[nearest + 1] - uniform, uniform - bounded[nearest])     # to the nearer switching
    keep = (gap > 1e-3 * h)
    keep[0] = keep[-1] = True
    T = problem.switching.period
    if np.isfinite(T):
        # a period's start stays a sample however near a switching falls (a ramp reset at the middle of its fall,
        # 5e-9 T before it): what reads the run period by period (a bifurcation diagram's strobe, a window of whole
        # periods) needs a row there
        phase = uniform / T
        keep |= np.abs(phase - np.round(phase)) <= 1e-9 * max(1.0, float(np.abs(phase).max(initial=1.0)))
    grid = np.concatenate((uniform[keep], breaks))
    grid.sort()
    return np.unique(grid) if (grid[1:] == grid[:-1]).any() else grid      # np.union1d, without its overhead


def _graded(schedule: Schedule, uniform: np.ndarray, breaks: np.ndarray, t0: float, t1: float, h: float,
            offsets: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(uniform, breaks) with the graded points after each switching instant: each instant's offsets (those before
    the next instant and t1) join the breaks, and the uniform points they span (up to h/1000 past the last) go."""
    phase = t0 % schedule.period
    starts = np.asarray(schedule.starts)
    at_start = bool(np.any(np.minimum(np.abs(starts - phase), schedule.period - np.abs(starts - phase))
                           <= 1e-12 * schedule.period))
    instants = np.concatenate(([t0] if at_start else [], breaks))
    ends = np.concatenate((instants[1:], [t1]))
    points, keep = [], np.ones(uniform.size, dtype=bool)
    for start, end in zip(instants, ends):
        inside = start + offsets
        inside = inside[inside < end - 1e-3 * h]
        if inside.size:
            points.append(inside)
            keep &= ~((uniform > start) & (uniform <= inside[-1] + 1e-3 * h))
    keep[0] = keep[-1] = True
    if not points:
        return uniform, breaks
    return uniform[keep], np.sort(np.concatenate([breaks, *points]))


def _step_sets(dt: np.ndarray, step_config: np.ndarray, h: float,
               n_configs: int) -> tuple[npt.NDArray[np.int32], list[SetKey], FloatArray]:
    """Matrix set of each step: sets 0..m-1 are the uniform step h in each configuration, then one per
    distinct (configuration, shorter step) at the switching instants. Returns (which, set_configs, set_dts)."""
    which = step_config.astype(np.int32)
    split = np.flatnonzero(np.abs(dt - h) > 1e-9 * h)
    fractions = np.round(dt[split] / h, 10)
    # key = configuration * 2 + fraction of h (in (0, 1.001]): one float per split step, unique by value
    first, inverse = _distinct(step_config[split] * 2.0 + fractions)
    which[split] = n_configs + inverse
    set_configs = list(range(n_configs)) + [int(c) for c in step_config[split][first]]
    # each fraction's dt from its first step in any configuration: sets of configurations alike but for E, F then
    # have equal steps and share their elimination (discretize.step_matrices)
    first_of_fraction, which_fraction = _distinct(fractions)
    set_dts = np.concatenate([np.full(n_configs, h), dt[split][first_of_fraction[which_fraction]][first]])
    return which, cast("list[SetKey]", set_configs), set_dts          # its ints (a list's type is invariant)


def _distinct(keys: np.ndarray) -> tuple[IndexArray, IndexArray]:
    """(first, inverse) of np.unique over ``keys``: the index of each distinct value's first occurrence (in sorted
    order of the values) and each key's distinct value; a period's few split steps without np.unique's overhead."""
    if keys.size > 64:
        _, first, inverse = np.unique(keys, return_index=True, return_inverse=True)
        return first, inverse
    listed = keys.tolist()
    distinct = sorted(set(listed))
    return (np.array([listed.index(key) for key in distinct], dtype=np.int64),
            np.array([distinct.index(key) for key in listed], dtype=np.int32))


def _period_grid(problem: LCSProblem, h: float, graded: tuple[float, ...] = ()) -> Plan | None:
    """One period of a run that repeats it, from a whole period m T: (local grid [0, T] with the switching
    instants, each step's configuration, each step's matrix set, set_configs, set_dts); None when the run does
    not repeat a period (no period, a start other than m T: a run kept in chunks of whole periods starts each on
    the same grid as the run whole; sinusoidal inputs where T is not a whole number of steps). A period that is not
    a whole number of steps ends on a short step, in every period alike: the grid Newton's period map ran on. (A run
    gridded whole from 0 had steps that straddle the period starts, and its periods were not the orbit's: at h =
    T/303.03 a buck's capacitor current read a mean of 5.1e-6 A, its estimate 50 times smaller.)"""
    schedule = cast(Schedule, problem.switching)          # a plan's problem switches on a schedule
    T, n_configs = schedule.period, len(problem.configurations)
    per_period = T / h if np.isfinite(T) else 0.0
    steps = int(round(per_period))
    t0 = problem.t_span[0]
    if (not np.isfinite(T) or per_period < 1.0 or t0 != round(t0 / T) * T
            or (problem.inputs is not None and abs(per_period - steps) > 1e-9 * per_period)):
        return None
    one = problem if problem.t_span == (0.0, T) else replace(problem, t_span=(0.0, T))
    local = time_grid(one, h, graded)                                    # [0, T] with the breakpoints
    local_config = schedule.config_at(0.5 * (local[:-1] + local[1:]))
    if problem.inputs is not None:
        # sinusoidal inputs: every step of the period has its own E and F (the same in every period): one set per
        # step, named (configuration, start, dt) for :func:`_set_configuration`
        dts = np.diff(local)
        set_configs: list[SetKey] = [(int(c), float(t), float(dt)) for c, t, dt in zip(local_config, local[:-1], dts)]
        return local, local_config, np.arange(dts.size, dtype=np.int32), set_configs, dts
    local_which, set_configs, set_dts = _step_sets(np.diff(local), local_config, h, n_configs)
    return local, local_config, local_which, set_configs, set_dts


def _set_configuration(problem: LCSProblem, key: SetKey, theta: float) -> Configuration:
    """The Configuration of a matrix set: a configuration index, or (index, step start, dt) under sinusoidal
    inputs (E at the step's theta point, F at its end, where the step's LCP holds)."""
    if isinstance(key, tuple):
        index, start, dt = key
        return problem.configuration_at(index, start + theta * dt, start + dt)
    return problem.configurations[key]


def _repeat_period(period: Plan, T: float, t1: float, h: float, t0: float = 0.0) -> Plan:
    """(t, config, which, set_configs, set_dts) of the run over [t0, t1] (t0 a whole number of periods) made of
    the period repeated (config: the configuration at each grid point, :attr:`StepPlan.config`); a run that
    ends inside a step gets that step's own matrix set (the last one). Each array is written once, in place
    (no temporaries of the run's size: a steady-state point allocates little more than the run it returns)."""
    local, local_config, local_which, set_configs, set_dts = period
    first = int(round(t0 / T))
    periods, steps = int(np.ceil((t1 - t0) / T * (1.0 - 1e-12))), local.size - 1
    grid = np.empty(periods * steps + 1)
    np.add((first + np.arange(periods))[:, None] * T, local[None, :-1],
           out=grid[:-1].reshape(periods, steps))                                                        # increasing
    # the grid points before t1: all of them over whole periods (the period's own last instant may lie within
    # h/1000 of its end: an interleaved buck's carrier retrace 1.2 ps before T, whose on-time the run had lost in
    # every period map, a phase's current 2.4 % low); else those up to h/1000 before t1 (no sliver of a last step)
    whole = abs((t1 - t0) / T - periods) <= 1e-9
    count = periods * steps if whole else int(np.searchsorted(grid[:-1], t1 - 1e-3 * h))
    t = grid[:count + 1]
    t[count] = t1
    configs = np.empty(periods * steps + 1, dtype=local_config.dtype)
    configs[1:].reshape(periods, steps)[:] = local_config
    configs[0] = local_config[0]
    config = configs[:count + 1]
    step_config = config[1:]
    which = np.empty(periods * steps, dtype=local_which.dtype)
    which.reshape(periods, steps)[:] = local_which
    which = which[:count]
    last_dt, nominal = t[-1] - t[-2], set_dts[which[-1]]
    if abs(last_dt - nominal) > 1e-9 * h:    # the run ends inside a step: its own matrix set
        which[-1] = len(set_configs)
        last = int(step_config[-1])
        set_configs = set_configs + [(last, float(t[-2]), float(last_dt)) if isinstance(set_configs[0], tuple)
                                     else last]
        set_dts = np.append(set_dts, last_dt)
    return t, config, which, set_configs, set_dts


def _too_long(problem: LCSProblem, h: float, graded: tuple[float, ...] = ()) -> bool:
    """More than MAX_STEPS steps in the repeated grid (the general grid then refuses the run)."""
    T, (t0, t1) = problem.switching.period, problem.t_span
    periods = int(np.ceil((t1 - t0) / T * (1.0 - 1e-12)))
    starts = cast(Schedule, problem.switching).starts                  # asked of a schedule's runs only
    return periods * (int(round(T / h)) + len(starts) * (1 + len(graded))) > MAX_STEPS


class GridPlan(NamedTuple):
    """A run's grid and matrix sets as arrays (:func:`plan_arrays`), for callers that step it themselves (the
    batched steady states of :mod:`converters.sweeps.batch`)."""

    t: np.ndarray
    #: Each step's configuration.
    step_config: np.ndarray
    #: Each step's matrix set.
    which: np.ndarray
    #: Each matrix set's configuration (:data:`SetKey`) and step.
    set_configs: list[SetKey]
    set_dts: np.ndarray


def plan_arrays(problem: LCSProblem, h: float, graded: tuple[float, ...] = ()) -> GridPlan:
    """The grid and matrix sets of a run of ``problem`` at step ``h`` (:func:`_plan`)."""
    t, config, which, set_configs, set_dts = _plan(problem, h, graded=graded)
    return GridPlan(t, config[1:], which, set_configs, set_dts)


def _plan(problem: LCSProblem, h: float, period: Plan | None = None, graded: tuple[float, ...] = ()) -> Plan:
    """(t, config, which, set_configs, set_dts) of a run: config the configuration at each grid point (each
    step's, the first step's at t0), which each step's matrix set.

    When the period is a whole number of steps and the run starts at 0, one period is built
    (:func:`_period_grid`, or ``period`` when given) and repeated (the split steps at the switching instants
    are then the same in every period: one matrix set each); otherwise the whole grid is built and sorted by
    :func:`time_grid`."""
    period = _period_grid(problem, h, graded) if period is None else period
    if problem.inputs is not None and (period is None or _too_long(problem, h, graded)):
        raise ParameterError(f"sinusoidal inputs need a run on whole steps of whole periods from a period start: the "
                             f"period T = {problem.switching.period:g} s a whole number of steps h = {h:g} s, t_start a "
                             f"multiple of T (got t_start = {problem.t_span[0]:g} s)")
    if period is None or _too_long(problem, h, graded):
        t = time_grid(problem, h, graded)
        config = np.empty(t.size, dtype=np.int64)
        config[1:] = cast(Schedule, problem.switching).config_at(0.5 * (t[:-1] + t[1:]))
        config[0] = config[1]
        return (t, config, *_step_sets(np.diff(t), config[1:], h, len(problem.configurations)))
    return _repeat_period(period, problem.switching.period, problem.t_span[1], h, problem.t_span[0])


@dataclass(frozen=True)
class StepPlan:
    """Everything about a run that does not depend on the initial state: the time grid, the
    configuration of each step and the one-step matrix set each step uses. Reused by shooting
    (one period map, many initial states) without rebuilding anything, and over a longer span
    (:meth:`spanning`: the same period's grid and matrix sets repeated)."""

    problem: LCSProblem
    method: Theta
    t: np.ndarray
    #: The configuration at each grid point: each step's (step j at config[j + 1]), the first step's at t0.
    config: np.ndarray
    which: np.ndarray
    mats: StepMatrices
    #: The period the grid repeats (:func:`_period_grid`), or None.
    period: Plan | None = None

    @classmethod
    def build(cls, problem: LCSProblem, method: Theta) -> "StepPlan":
        if problem.inputs is not None:          # a set a step (:meth:`Theta.memory_estimate`): shooting's too
            method.check_memory(problem)
        period = _period_grid(problem, method.h, method.graded)
        t, config, which, set_configs, set_dts = _plan(problem, method.h, period, method.graded)
        mats = step_matrices([_set_configuration(problem, c, method.theta) for c in set_configs], set_dts,
                             method.theta)
        return cls(problem, method, t, config, which, mats, period)

    @property
    def step_config(self) -> np.ndarray:
        """Each step's configuration."""
        return self.config[1:]

    def spanning(self, t_end: float, x0: np.ndarray | None = None) -> "StepPlan":
        """The plan of the same problem over [t0, t_end] (from x0, default the problem's): the period's grid
        and matrix sets repeated when the plan has a period (one more set when the run ends inside a
        step), otherwise built anew. The run's memory is checked first, as
        :func:`~converters.simulate.simulate` does."""
        problem = replace(self.problem, t_span=(self.problem.t_span[0], t_end),
                          x0=self.problem.x0 if x0 is None else x0)
        self.method.check_memory(problem)
        if self.period is None or _too_long(problem, self.method.h, self.method.graded):
            return StepPlan.build(problem, self.method)
        t, config, which, set_configs, set_dts = _repeat_period(self.period, problem.switching.period, t_end,
                                                                self.method.h, problem.t_span[0])
        mats = self.mats
        if len(set_configs) > len(mats):          # the run ends inside a step
            extra = step_matrices([_set_configuration(problem, c, self.method.theta) for c in set_configs[len(mats):]],
                                  set_dts[len(mats):], self.method.theta)
            mats = mats.concatenate(extra)
        return StepPlan(problem, self.method, t, config, which, mats, self.period)

    def advance(self, x0: npt.ArrayLike) -> tuple[FloatArray, FloatArray, FloatArray, int]:
        """Run every step from x0: (x, u, y, general_solves), arrays of shape (N, n), (N, k), (N, k)."""
        problem = self.problem
        x_init = _checked_start(problem, x0)
        N, n, k = self.t.shape[0], problem.n, problem.k
        x = np.empty((N, n))
        u = np.zeros((N, k))
        y = np.empty((N, k))
        x[0] = x_init
        u[0], y[0] = _initial_pair(problem, int(self.config[0]), x_init, problem.t_span[0])
        return x, u, y, self.steps(x, u, y)

    def steps(self, x: FloatArray, u: FloatArray, y: FloatArray) -> int:
        """Every step from x[0], in place of rows 1.. of x, u, y (u[0], y[0] are not read); returns the
        number of steps solved by the general LCP solver."""
        mats, which, t = self.mats, self.which, self.t
        k = self.problem.k
        inline = k <= MAX_INLINE_K
        state = register_state(self.problem.n)
        run_steps = kernel("run_steps")
        period = self.period[0].size - 1 if self.period is not None else 0       # steps in a period: the guesses
        general_solves = 0
        j = 0
        while True:
            if j >= which.shape[0]:     # the run's last step was solved here
                return general_solves
            status, j = run_steps(which, mats.Phi, mats.Gamma, mats.H, mats.C, mats.F, mats.M, mats.Phi_b,
                                  mats.Gamma_b, mats.CPhi, mats.q0, x, u, y, j, inline, period, state)
            if status == OK:
                return general_solves
            s = which[j]
            x_free = mats.Phi[s] @ x[j] + mats.Gamma[s]
            q = mats.C[s] @ x_free + mats.F[s]
            if status == NO_SOLUTION:
                raise SimulationError(_no_solution_message(t[j], mats.M[s], q))
            from ..lcp import solve_lcp                 # imported here: a run that never needs it starts faster
            result = solve_lcp(mats.M[s], q, method="lemke")
            if not result.solved:
                result = solve_lcp(mats.M[s], q, method="enum") if k <= 12 else result
            if not result.solved:
                raise SimulationError(f"the step LCP at t = {t[j]:.6g} s could not be solved ({result.status}: "
                                      f"{result.message}); try a smaller h")
            u[j + 1] = result.z
            y[j + 1] = result.w
            x[j + 1] = x_free + mats.H[s] @ result.z
            general_solves += 1
            j += 1

    def jacobian(self, u: np.ndarray, y: np.ndarray | None = None) -> np.ndarray:
        """d x_end / d x0 of the run that produced the multipliers ``u`` (exact; see the module docstring); with its
        ``y``, a pair at its corner (u = y = 0) taken as blocking (:meth:`corners_blocking`)."""
        jac = np.eye(self.problem.n)
        held = u if y is None else self.corners_blocking(u, y)
        kernel("step_jacobian")(self.which, held, self.mats.Phi_b, self.mats.H, self.mats.CPhi, self.mats.M, jac)
        return jac

    def corners_blocking(self, u: np.ndarray, y: np.ndarray) -> np.ndarray:
        """``u`` with each pair at its corner after a step (u = y = 0, to CORNER of the step's largest) whose u is
        the device's voltage (its port a voltage source: :attr:`LCSProblem.pair_currents`) marked held, as a pair
        whose u is its current is at u = 0: blocking; a port a configuration holds twice (two diodes in series
        through a winding) once. The Jacobian's active set is u > 0, so such a pair had been linearised as
        conducting (v = 0 held), which it is not either way: a two-switch forward's rectifier diode, at zero current
        and voltage while the core's reset leaves its winding idle, made the winding's current a multiplier at
        k^2 = 0.9801 of the Jacobian, where the run itself, perturbed, returns it to 1e-6 (the event method, which
        reads idle pairs as not conducting: 0.94147)."""
        currents = getattr(self.problem, "pair_currents", None)
        if currents is None or not u.size:
            return u
        config = self.config[1:]
        voltage = ~np.asarray(currents, dtype=bool)[config]                   # (steps, k): u is the voltage
        after_u, after_y = u[1:], y[1:]
        scale = np.maximum(np.abs(after_u).max(axis=1, initial=0.0), np.abs(after_y).max(axis=1, initial=0.0))
        corner = voltage & (after_u <= CORNER * scale[:, None]) & (np.abs(after_y) <= CORNER * scale[:, None])
        if not corner.any():
            return u
        marked = u.copy()
        twins = {c: self.problem.configurations[c].twin_ports() for c in np.unique(config[corner.any(axis=1)])}
        for r in np.flatnonzero(corner.any(axis=1)):
            held = marked[r + 1] > 0.0
            for i in np.flatnonzero(corner[r]):
                if not any(held[j] for j in twins[int(config[r])].get(int(i), ())):
                    marked[r + 1, i] = np.finfo(float).tiny       # held: u > 0 in the active set, 0 in the state
                    held[i] = True
        return marked

    def trajectory(self, x0: npt.ArrayLike, wall_s: float = 0.0) -> Trajectory:
        start_clock = time.perf_counter()
        x, u, y, general_solves = self.advance(x0)
        t, config, M, which = self.t, self.config, self.mats.M, self.which
        # located when first read, on this run's own arrays: the names are rebound below to the arrays with a row
        # after each jump, which the step indices (and ``which``) do not count (an index past the end, or another
        # step's matrix set: a flyback's switch capacitance crashed, a dead time's edge read 6x too short)
        events: Events = functools.partial(_events, t, u, y, config, M, which)
        jumps: tuple[tuple[float, float], ...] = ()
        if self.problem.jumps:
            t, x, u, y, config, events, jumps = _with_jumps(self.problem, t, x, u, y, config, events)
        return _trajectory(self.problem, self.method, t, x, u, y, config, events,
                           wall_s + time.perf_counter() - start_clock, general_solves=general_solves, jumps=jumps)


def _with_jumps(problem: LCSProblem, t: FloatArray, x: FloatArray, u: FloatArray, y: FloatArray, config: IndexArray,
                events: Events) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, IndexArray, Events,
                                         tuple[tuple[float, float], ...]]:
    """The run with a sample after each jump (:class:`~converters.problems.Jump`), at the same time: the state
    the step took from (P x + q) beside the one before it. The steps fold the jump into the step they take from a
    switching instant; without this row the samples would join the state before the jump to the one a step after
    it, and a mean by the scheme's rule would count the jump as a ramp over that step (an error of
    1/2 dv h / T: 5e-4 of a capacitor's mean, shorted each period, at the default step). The new row takes
    the pair of the step it starts and that step's configuration; event rows move with the samples. Returns the
    arrays and the jumps ((time, energy lost), ...: :attr:`~converters.trajectory.Trajectory.jumps`)."""
    jumped = []
    for j in np.concatenate(([0], 1 + np.flatnonzero(config[2:] != config[1:-1]))):      # where steps change
        jump = problem.configurations[config[j + 1]].jump
        if jump is not None:
            after = jump(x[j])
            if np.abs(after - x[j]).max() > 1e-13 * max(np.abs(x[j]).max(), np.abs(after).max()):
                jumped.append((j, after))
    if not jumped:
        return t, x, u, y, config, events, ()
    jumps = tuple((float(t[j]), float(problem.configurations[config[j + 1]].jump.loss(x[j]))) for j, _ in jumped)
    rows = np.array([j for j, _ in jumped])
    at = rows + 1                                        # inserted before the sample after each jump
    t, u, y = (np.insert(a, at, a[at], axis=0) for a in (t, u, y))
    config = np.insert(config, at, config[at], axis=0)
    t[at + np.arange(at.size)] = t[rows + np.arange(at.size)]
    x = np.insert(x, at, np.array([after for _, after in jumped]), axis=0)

    def moved() -> EventTable:
        table = events() if callable(events) else events
        return dict(table, step=table["step"] + np.searchsorted(rows, table["step"], side="right"))
    return t, x, u, y, config, moved, jumps


def _checked_start(problem: LCSProblem, x0: npt.ArrayLike) -> np.ndarray:
    x_init = np.asarray(x0, dtype=float)
    if x_init.shape != (problem.n,) or not np.isfinite(x_init).all():
        raise ParameterError(f"x0 must be {problem.n} finite numbers; got {x0!r}")
    return x_init


class StepPlanMap(PeriodMap):
    """The stepper's map over a scheduled problem's span, with the exact Jacobian of the discrete map.
    One plan and one set of run buffers serve every evaluation."""

    def __init__(self, plan: StepPlan) -> None:
        super().__init__()
        self.plan = plan
        N, n, k = plan.t.shape[0], plan.problem.n, plan.problem.k
        self._x, self._u, self._y = np.empty((N, n)), np.zeros((N, k)), np.empty((N, k))

    def _run(self, x0: npt.ArrayLike) -> np.ndarray:
        self._x[0] = _checked_start(self.plan.problem, x0)
        self.plan.steps(self._x, self._u, self._y)
        end: np.ndarray = self._x[-1].copy()
        return end

    def end(self, x0: np.ndarray) -> np.ndarray:
        self.evaluations += 1
        return self._run(x0)

    def __call__(self, x0: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        self.evaluations += 1
        end = self._run(x0)
        return end, self.plan.jacobian(self._u, self._y)


def _trajectory(problem: LCSProblem, method: Theta, t: FloatArray, x: FloatArray, u: FloatArray, y: FloatArray,
                config: IndexArray, events: Events, wall_s: float, relay: FloatArray | None = None,
                general_solves: int = 0, jumps: tuple[tuple[float, float], ...] = ()) -> Trajectory:
    """The stepper's Trajectory: backward Euler's samples are integrated by its own end-point rule,
    theta < 1 by the trapezoidal rule (the scheme's own quadrature)."""
    return Trajectory(t=t, x=x, u=u, y=y, config=config, state_names=problem.state_names,
                      pair_names=problem.pair_names,
                      config_names=tuple(c.name or f"config{i}" for i, c in enumerate(problem.configurations)),
                      relay=relay, event_columns=events, method=method.key, steps=t.shape[0] - 1, wall_s=wall_s,
                      rule="end" if method.theta == 1.0 else "linear", pair_rule="end", period=problem.switching.period,
                      general_solves=general_solves, problem=problem, algorithm=method, jumps=jumps,
                      metadata=dict(problem.metadata, h=method.h, theta=method.theta, label=method.label))


def _config_stacks(problem: LCSProblem) -> tuple[FloatArray, ...]:
    return tuple(np.ascontiguousarray(np.stack([getattr(c, key) for c in problem.configurations]))
                 for key in "ABCDEF")


def law_arrays(law: StateSwitching | Comparators) -> LawArrays:
    """A state-driven law (:class:`StateSwitching` or :class:`Comparators`) as the compiled loop's per-channel
    arrays: (c, d, low, slope, ramp_period, delay, band, latch, clocked, limit, table)."""
    channels, table = law_channels(law)
    ramps = [ch.function.ramp for ch in channels]
    column: Callable[..., npt.NDArray[Any]] = lambda values, dtype=float: np.array(values, dtype=dtype)  # noqa: E731
    return (np.ascontiguousarray(np.stack([ch.function.c for ch in channels])),
            column([ch.function.d for ch in channels]),
            column([r.low if r is not None else 0.0 for r in ramps]),
            column([r.slope if r is not None else 0.0 for r in ramps]),
            column([r.period if r is not None else np.inf for r in ramps]),
            column([r.delay if r is not None else 0.0 for r in ramps]),
            column([ch.band for ch in channels]),
            column([ch.latch for ch in channels], np.int64), column([ch.clocked for ch in channels], np.int64),
            column([-1.0 if ch.limit is None else ch.limit for ch in channels]), column(table, np.int64))


def _solve_state_switched(problem: LCSProblem, method: Theta, x0: np.ndarray, start: float) -> Trajectory:
    from . import theta_kernels                 # numba's JIT (the ahead-of-time module holds the scheduled loop)
    law = cast("StateSwitching | Comparators", problem.switching)         # Theta.solve's state-driven laws
    A, B, C, D, E, F = _config_stacks(problem)
    n_configs = len(problem.configurations)
    mats = step_matrices(list(problem.configurations), np.full(n_configs, method.h), method.theta)
    t = time_grid(problem, method.h)   # step h, with the ramp resets inserted
    N, n, k = t.size, problem.n, problem.k
    x, u, y = np.empty((N, n)), np.zeros((N, k)), np.empty((N, k))
    config = np.empty(N, dtype=np.int64)
    bits = initial_bits(law, x0, problem.t_span[0])
    arrays = law_arrays(law)
    current = int(arrays[-1][bits])
    x[0] = x0
    u[0], y[0] = _initial_pair(problem, current, x0)
    config[0] = current
    state = np.array([bits, 0, 0], dtype=np.int64)
    capacity = 1024
    ev_time, ev_config, ev_step = np.empty(capacity), np.empty(capacity, dtype=np.int64), np.empty(capacity, dtype=np.int64)
    j = 0
    while True:
        status, j = theta_kernels.run_state_switched(A, B, C, D, E, F, mats.Phi, mats.Gamma, mats.H, mats.M, t, method.h,
                                                     method.theta, *arrays, x, u, y, config, j, state, ev_time,
                                                     ev_config, ev_step)
        if status == OK:
            break
        if status == EVENTS_FULL:
            capacity *= 4
            ev_time, ev_config, ev_step = (np.resize(ev_time, capacity), np.resize(ev_config, capacity),
                                           np.resize(ev_step, capacity))
            continue
        if status == FORBIDDEN:
            # raises, naming the channels' states (only a Comparators' table holds -1)
            cast(Comparators, law).config(int(state[0]), float(ev_time[state[2]]))
        raise SimulationError(f"the step LCP at t = {t[j]:.6g} s could not be solved inline (k = {k}); the "
                              "state-driven laws need LCPs the inline solver takes: try a smaller h")
    count = int(state[2])
    pair_events = _events(t, u, y, config, mats.M, config[1:])
    events = _merge_events(pair_events, ev_time[:count], ev_step[:count], ev_config[:count])
    planned = t.size - 1
    rows = _with_crossings(problem, t, x, u, y, config, events)
    return replace(_trajectory(problem, method, *rows, time.perf_counter() - start), steps=planned)


def _with_crossings(problem: LCSProblem, t: FloatArray, x: FloatArray, u: FloatArray, y: FloatArray,
                    config: IndexArray, events: EventTable) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray,
                                                                     IndexArray, EventTable]:
    """The run with a sample at each switching of a state-driven law inside a step, in the configuration it ends.
    The loop places the crossing inside the step and redoes the step from it, but keeps its samples on the grid;
    without a sample there a mean by the linear rule reads the whole step in the new configuration, a comparator's
    duty ratio in whole steps (a voltage loop's switch node at D = 0.025: 4 % low, its input power 5.9 %, h and 2h
    quantizing alike). The new row's state is the one before it (the step's start, or the crossing before it in the
    same step) moved along the field of the configuration in force between them: O(h^2) from the loop's own state
    there, which it does not keep, where the step's chord is O(h) off at the corner the switching makes. Its pairs
    are the step's first; the events' rows move with the samples."""
    switches = events["kind"] == "switch"
    steps, times, entered = events["step"][switches], events["time"][switches], events["config"][switches]
    span = t[steps + 1] - t[steps]
    at_grid = times <= t[steps] + 1e-12 * span                 # a ramp's reset: a grid point already
    inside = ~at_grid & (times < t[steps + 1] - 1e-12 * span)
    if not inside.any():
        return t, x, u, y, config, events
    # the configuration in force as each step starts: the row's own, or the one the last reset at its grid point
    # entered (the table is in time order)
    start = config.copy()
    for j, c in zip(steps[at_grid].tolist(), entered[at_grid].tolist()):
        start[j] = c
    steps, times, entered = steps[inside], times[inside], entered[inside]
    first = np.r_[True, steps[1:] != steps[:-1]]               # the first crossing in its step
    ends = np.where(first, start[steps], np.r_[0, entered[:-1]])
    # each crossing's state: the one before it (the step's start, or the crossing before it in the same step) moved
    # along the field of the configuration in force between them
    x_new = np.empty((steps.size, x.shape[1]))
    for k in range(steps.size):
        before_t, before_x = (t[steps[k]], x[steps[k]]) if first[k] else (times[k - 1], x_new[k - 1])
        cfg = problem.configurations[int(ends[k])]
        x_new[k] = before_x + (times[k] - before_t) * (cfg.A @ before_x + cfg.B @ u[steps[k]] + cfg.E)
    at = steps + 1
    t, config = np.insert(t, at, times), np.insert(config, at, ends)
    x = np.insert(x, at, x_new, axis=0)
    u, y = (np.insert(a, at, a[steps], axis=0) for a in (u, y))
    # an event's row: its step's, moved past the rows inserted before it in time (at most its own)
    moved = events["step"] + np.searchsorted(times, events["time"], side="right")
    return t, x, u, y, config, dict(events, step=moved)


def _solve_relay(problem: LCSProblem, method: Theta, x0: np.ndarray, start: float) -> Trajectory:
    from . import theta_kernels                 # numba's JIT (the ahead-of-time module holds the scheduled loop)
    law = cast(Relay, problem.switching)                 # Theta.solve's remaining law
    A, B, C, D, E, F = _config_stacks(problem)
    t = time_grid(problem, method.h)   # step h, with the ramp resets inserted
    N, n, k = t.size, problem.n, problem.k
    x, u, y = np.empty((N, n)), np.zeros((N, k)), np.empty((N, k))
    blend = np.zeros(N)
    x[0] = x0
    u[0], y[0] = _initial_pair(problem, law.low, x0)
    status, j = theta_kernels.run_relay(A, B, C, D, E, F, law.low, law.high, t, method.h, method.theta, law.function.c,
                          law.function.d, x, u, y, blend, 0)
    if status != OK:
        raise SimulationError(f"the relay step LCP at t = {t[j]:.6g} s (size k + 2 = {k + 2}) has no solution "
                              "the inline solver finds; try a smaller h")
    blend[0] = blend[1] if N > 1 else 0.0
    config = np.full(N, law.low, dtype=np.int64)
    mats = step_matrices([problem.configurations[law.low]], np.array([method.h]), method.theta)
    events = _events(t, u, y, config, mats.M, np.zeros(N - 1, dtype=np.int64))
    return _trajectory(problem, method, t, x, u, y, config, events, time.perf_counter() - start, relay=blend)


def _merge_events(pair_events: EventTable, times: FloatArray, steps: npt.NDArray[np.int64],
                  configs: npt.NDArray[np.int64]) -> EventTable:
    """Pair events and switching-law events in one table, sorted by time."""
    n_pairs = len(pair_events["time"])
    out = {"time": np.concatenate([pair_events["time"], times]),
           "step": np.concatenate([pair_events["step"], steps]),
           "pair": np.concatenate([pair_events["pair"], np.full(len(times), -1)]),
           "kind": np.concatenate([pair_events["kind"].astype(object), np.full(len(times), "switch", dtype=object)]),
           "config": np.concatenate([np.full(n_pairs, -1), configs])}
    order = np.argsort(out["time"], kind="stable")
    return {key: value[order] for key, value in out.items()}


def _initial_pair(problem: LCSProblem, config: int, x0: np.ndarray,
                  t0: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """The consistent pair at t0: LCP(C x0 + F, D); when D is singular and no solution exists, u = 0."""
    c = problem.configuration_at(config, t0)
    q = c.C @ x0 + c.F
    if np.any(c.D):
        from ..lcp import solve_lcp             # imported here: a run that never needs it starts faster
        result = solve_lcp(c.D, q, method="lemke")
        if result.solved:
            return result.z, result.w
    return np.zeros(problem.k), q


def _no_solution_message(t: float, M: FloatArray, q: FloatArray) -> str:
    return (f"the step LCP at t = {t:.6g} s has no solution (M = {M[0, 0]:.4g} <= 0 with q = {q[0]:.4g} < 0): "
            "the circuit forces a current into a blocking diode or an inductor into an open switch; "
            "check the model or add the missing parasitic path")


def _events(t: FloatArray, u: FloatArray, y: FloatArray, config: IndexArray, M_stack: FloatArray,
            which: IndexArray) -> EventTable:
    """Sub-step estimate of each complementarity switch from the step's own LCP data.

    Activation (y falls through 0): with u_i held at 0 the step would end at y_i = -M_ii u_{j+1,i};
    linear interpolation of y_i from y_{j,i} to that value gives the crossing.
    Release (u falls through 0): the unconstrained multiplier at the step end is -y_{j+1} / M_ii.
    Steps across a configuration change are left out (the change itself is the event there).
    Step j used the matrix set ``which[j]`` of ``M_stack``.
    """
    active = u > y
    steps, pairs = np.divmod(np.flatnonzero(active[1:] != active[:-1]), u.shape[1])   # np.nonzero's order, faster
    keep = (config[steps] == config[steps + 1]) | (steps == 0)
    steps, pairs = steps[keep], pairs[keep]
    m_ii = M_stack[which[steps], pairs, pairs]
    activating = active[steps + 1, pairs]
    with np.errstate(divide="ignore", invalid="ignore"):
        a = np.where(activating, y[steps, pairs], u[steps, pairs])
        b = np.where(activating, m_ii * u[steps + 1, pairs],
                     np.where(m_ii > 0, y[steps + 1, pairs] / m_ii, np.nan))
        frac = np.where(np.isfinite(b) & (a + b > 0), a / (a + b), 0.5)
    dt = t[steps + 1] - t[steps]
    return {"time": t[steps] + np.clip(frac, 0.0, 1.0) * dt, "step": steps, "pair": pairs,
            "kind": np.where(activating, "activate", "release")}
