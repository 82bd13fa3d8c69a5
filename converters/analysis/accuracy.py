"""Accuracy on request: a converter's periodic steady state with an error estimate on every number.

:func:`accurate_steady` returns the orbit's measures over one period - vout's mean and ripple, each
inductor current's RMS and peak, the mode fractions, the pairs' event instants (in units of T) and the power
summary (input and output power, each loss) - each with an ``error_estimate``, chosen so that every one meets a
relative tolerance ``rtol`` (mode fractions and event instants: absolute, in units of T; losses relative to the
input power; the efficiency, their ratio, is then within rtol: :func:`efficiency_estimate`):

* **Stepper** (theta = 0.5, declared order p = 2): the method's own orbit at N and 2N steps per period;
  the estimate of each value at N' = r N (first 200 from 100) is Richardson's |Q(N') - Q(N)| / (r^p - 1).
  While an estimate is above ``rtol`` / ``SAFETY`` (through a diode event the stepper's order falls below
  its declared 2), the next N' is the one the estimates and the order predict (x 1.2), compared with the
  last run when r <= ``MAX_RATIO``, else with a new one at N' / 2. On a circuit the event method cannot take (SIN
  or PWL sources) the order is the one observed between the last two differences (:func:`_order_between`), not
  the declared 2: nothing exact checks the stepper there. Where a diode with a series resistance conducts into
  the state, the order is 1 (:func:`stepped_order`). An estimate is never below what the
  previous one predicts at N' by the order (two runs that agree by chance are not convergence). Every
  orbit starts from the previous one (one warm-up). Event instants are read inside the step, by extrapolating the
  pair's vanishing quantity (y before it is held, u before it is released) from the two steps before it
  (or, after a switching edge, back from the two after it); the mode fractions come from those instants
  and the switching edges, not from the step grid. Where a time constant far below the step makes the
  refinement start with backward Euler and that step damps one of the circuit's resonances more than the
  circuit does (a snubber's ring), its runs at N and 2N erase the ring alike and their estimates agree with
  themselves: the refinement starts again with the trapezoid from the steps at which it does not ring on the
  fastest mode, as far as the memory limit allows.
* **Event-driven** (exact flows, events to rounding): taken when the stepper would need more than
  ``MAX_STEPS`` steps per period (the trade-off data: there the exact method is the cheaper; at 1e-8 and
  below). Its estimate is the orbit's Newton distance and the rounding of its period map, not Richardson; ripple
  and peaks, read on its samples, are estimated from every other sample and read again on the orbit's period at
  ``SAMPLE_GROWTH`` times the samples while that estimate misses the target.

Every estimate has a floor: the orbit's rounding, eps x (operations per period) / (1 - rho), which near
rho = 1 (light load) keeps a fine stepper from some targets; the event method then takes over.

The orbit itself is solved to ``rtol`` / 100 (the Newton distance enters every estimate as well). A target
the orbit cannot resolve in double precision (a Floquet multiplier within ~1e-5 of 1 at light load) is met
as far as it can be and the result says so (``met`` False, ``message``).
"""
from __future__ import annotations

import math
import time
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any, cast

import numpy as np
import numpy.typing as npt

from ..errors import ParameterError, ResourceError, SimulationError
from ..methods.base import ErrorKind
from ..trajectory import locate_pair_change, parabola_peak

if TYPE_CHECKING:
    from ..methods.base import Method
    from ..models.base import Model
    from ..trajectory import Trajectory
    from .periodic import PeriodicOrbit

#: Estimates must fall below rtol / SAFETY (the stepper's effective order through a diode event is ~1.3-1.5,
#: not its declared 2, so Richardson with p = 2 can underestimate by up to ~3x).
SAFETY = 2.0
#: Steps per period for the first (coarse) orbit, and the most the stepper is asked for before the event
#: method takes over.
FIRST_STEPS = 100
MAX_STEPS = 1 << 17
#: Largest growth of N between two refinements, and the largest ratio of the steps of the two runs an
#: estimate compares (from a jump of 10x the coarse value is not yet asymptotic: an extremum's estimate came
#: out 16x short).
MAX_GROWTH = 16
MAX_RATIO = 2
#: An estimate may fall at most 1/GUARD below what the previous one predicts by the order (:func:`_guarded`).
GUARD = 0.1
THETA = 0.5
#: The most order a default run's Richardson estimate assumes for a stepper of declared order above it when the orbit
#: has a diode event inside a step (measured at the 15 points of tests/analysis: theta 0.5's effective order
#: through the events is ~1.3-1.5; with p = 2 the estimate fell to 0.28x the true error, with 1.5 to 0.46x).
#: Below it the order observed on a third orbit at 4h is taken (:func:`_observed_order`), down to OBSERVED_FLOOR: a
#: ladder whose every diode stops inside a step (the 10-stage Cockcroft-Walton) read 0.40x its error at 1.5.
ORDER_THROUGH_EVENTS = 1.5
#: The order assumed where it cannot be observed (the orbit at 4h not found, or not a step the circuit takes; the
#: first run of ``--rtol`` on a circuit the event method cannot take): backward Euler's, the first order a diode event
#: inside a step leaves.
LEAST_ORDER = 1.0
#: The least order observed that a default run's estimate takes, and the one it takes where the differences h-2h and
#: 2h-4h do not shrink by 2^0.5: a Cockcroft-Walton ladder's are still before their asymptotic range at the default
#: step (observed 0.30 to 0.53: its error falls more slowly from 4h to h than it will), and order 1 there read its
#: error 1.35x (6 stages) to 3.3x (12 stages at T/1000) short; at 0.5 the estimates are 1.2x to 1.8x above it.
OBSERVED_FLOOR = 0.5
#: The event method's output samples per period (ripple and peaks are read on them; the estimate of that
#: reading is Richardson's on every other sample, the sampling error being O(spacing^2) at a smooth extremum).
EVENT_SAMPLES = 8192
#: Where an extremum read on them misses the target, the period is run again on the orbit with SAMPLE_GROWTH times
#: the samples, up to MAX_EVENT_SAMPLES a period (a 10 mF output's ripple, a snubber's ring on a winding's peak).
SAMPLE_GROWTH, MAX_EVENT_SAMPLES = 8, 1 << 19
#: The event method's rounding: its period map is a few exact segments.
EVENT_SEGMENTS = 16
#: Rounding per step of the stepper's period map, in units of eps (measured, see :func:`_rounding`).
ROUNDING_PER_OPERATION = 0.25 * np.finfo(float).eps
RTOL_RANGE = (1e-10, 0.1)


@dataclass(frozen=True)
class Estimate:
    """A reported value, its error estimate (absolute) and the scale its relative error is taken on."""

    value: float
    error_estimate: float
    scale: float

    @property
    def relative(self) -> float:
        return self.error_estimate / self.scale if self.scale > 0 else self.error_estimate

    def as_dict(self) -> dict:
        return {"value": self.value, "error_estimate": self.error_estimate, "relative_error_estimate": self.relative}


@dataclass(frozen=True)
class AccurateSteady:
    """The periodic steady state, its measures with error estimates, and how they were obtained."""

    quantities: dict
    events: list
    rtol: float
    method: Method
    steps_per_period: int | None
    trajectory: Trajectory
    orbit: PeriodicOrbit
    met: bool
    message: str = ""
    runs: list = field(default_factory=list)
    wall_s: float = 0.0

    @property
    def h(self) -> float | None:
        return getattr(self.method, "h", None)

    def worst(self) -> float:
        """The largest relative error estimate over every quantity."""
        items = list(self.quantities.values()) + [e for _, _, e in self.events]
        return max((e.relative for e in items), default=0.0)

    def summary(self) -> dict:
        return {"rtol": self.rtol, "met": self.met, "message": self.message, "method": self.method.key,
                "h": self.h, "theta": getattr(self.method, "theta", None), "steps_per_period": self.steps_per_period,
                "worst_relative_error_estimate": self.worst(),
                "quantities": {name: q.as_dict() for name, q in self.quantities.items()},
                "events": [{"pair": pair, "kind": kind, "time_T": e.value, "error_estimate_T": e.error_estimate}
                           for pair, kind, e in self.events],
                "runs": self.runs, "wall_s": self.wall_s}


# --- measures of one period ------------------------------------------------------------------------------

def _exact(tr: Trajectory) -> bool:
    """The run's events sit at their exact instants (its method declares exact flows)."""
    return tr.algorithm is not None and tr.algorithm.exact


def _model_error(method: Method) -> str:
    return f"the {method.key} method's error is {method.model_error}, not estimated here"


def _inductor_currents(model: Model) -> list[str]:
    return [name for name in model.state_names if name.startswith("i")]


#: The name :func:`substep_events` gives a state-driven law's switchings (a comparator's crossings).
SWITCHING = "comparator"


def substep_events(tr: Trajectory, T: float, t0: float = 0.0) -> list[tuple[str, str, float]]:
    """(pair, kind, (time - t0) / T) of each pair event in [t0, t0 + T): exact for the event method; for the
    stepper located inside its step from the quantity that vanishes there (module docstring). A state-driven law's
    switchings are (:data:`SWITCHING`, "crossing", instant), at the instant the run located."""
    columns = tr.event_table()
    columns = columns if columns is not None else {}
    times = np.asarray(columns.get("time", ()), dtype=float)
    out: list[tuple[str, str, float]] = []
    if times.size == 0:
        return out
    steps, pairs = np.asarray(columns["step"]), np.asarray(columns["pair"])
    kinds = np.asarray(columns["kind"]).astype(str)
    exact = _exact(tr)
    # an LCS run's (its pairs and configurations are recorded)
    u, y, config = cast("tuple[npt.NDArray[np.float64], npt.NDArray[np.float64], npt.NDArray[np.int_]]",
                        (tr.u, tr.y, tr.config))
    t = tr.t
    for k in np.flatnonzero((times >= t0 - 2 * T / max(t.size, 1)) & (times <= t0 + T)):
        pair, j = int(pairs[k]), int(steps[k])
        if pair < 0:
            # a state-driven law's switching: its instant is the run's own (the stepper locates a crossing inside
            # its step and redoes the step from it); read as a pair's, it was the last diode's, on the grid (a
            # type III boost's duty ratio 2.2e-4 off with --rtol 1e-4 "met")
            time_ = float(times[k])
            if 0.0 <= time_ - t0 < T * (1 - 1e-12):
                out.append((SWITCHING, "crossing", (time_ - t0) / T))
            continue
        kind = "held" if kinds[k].startswith("act") else "released"
        if exact:
            time_ = float(times[k])
        else:
            time_ = locate_pair_change(t, u[:, pair], y[:, pair], config, j, kind) if j + 1 < t.size else float(t[j])
        if 0.0 <= time_ - t0 < T * (1 - 1e-12):
            out.append((tr.pair_names[pair], kind, (time_ - t0) / T))
    return out


def mode_fractions(tr: Trajectory, T: float, events: Sequence[tuple[str, str, float]], edges: npt.ArrayLike,
                   t0: float = 0.0) -> dict:
    """Fraction of [t0, t0 + T] in each mode, its boundaries the switching edges (absolute times) and the
    event instants (in units of T from t0)."""
    bounds = np.unique(np.concatenate([[t0, t0 + T], np.asarray(edges, float), [t0 + e[2] * T for e in events]]))
    bounds = bounds[(bounds >= t0) & (bounds <= t0 + T)]
    first = max(int(np.searchsorted(tr.t, t0)) - 1, 0)
    last = min(int(np.searchsorted(tr.t, t0 + T, side="right")) + 1, tr.t.size)
    rows = np.arange(first, last)
    t = tr.t[rows]
    labels = np.asarray(tr.modes(rows)).astype(str)
    out: dict = {}
    for a, b in zip(bounds[:-1], bounds[1:]):
        if b - a <= 1e-12 * T:
            continue
        j = int(np.searchsorted(t, a + 1e-9 * T, side="right"))         # the first step ending inside (a, b]
        if _exact(tr):                                                  # its samples sit on the events
            j = int(np.searchsorted(t, 0.5 * (a + b)))
        j = min(max(j, 1), t.size - 1)
        out[labels[j]] = out.get(labels[j], 0.0) + (b - a) / T
    return out


def extremum(t: npt.NDArray[np.float64], v: npt.ArrayLike, config: npt.NDArray[np.int_] | None, sign: float,
             at_events: Iterable[float] = (), edges: Iterable[float] = ()) -> float:
    """sign x the largest of sign * v between samples: at a smooth extremum inside one configuration the
    vertex of the parabola through the three samples around the largest (the sampled value is O(h^2) short of
    it); at a switching edge (a kink) the sample itself; at a pair event inside a step (a kink between
    samples) the value there, ``at_events`` (:func:`event_values`). A sample on a switching edge (``edges``)
    holds the value before it: where the signal jumps there (a capacitor's ESR carrying the diode's current from
    the edge) the value after it is the parabola through the next three samples at the edge."""
    w = sign * np.asarray(v, dtype=float)
    j = int(np.argmax(w))
    # the vertex of a parabola through three samples of one configuration (one through the value before a jump had
    # read a DCM boost's ripple with ESR 12 % high: 0.328 V for 0.292), around the largest sample and around every
    # other local maximum whose vertex could pass it (gaining at most a quarter of its larger drop to a neighbour):
    # a ring's peaks alike to 1e-3, sampled at another phase each, had read the vertex of one whose sample was the
    # highest and not of the higher one between two samples (a 300 MHz loop's peak 1.2e-3 low)
    peaks = [j]
    if w.size > 2:
        inner = w[1:-1]
        drop = np.maximum(inner - w[:-2], inner - w[2:])
        could = (inner > w[:-2]) & (inner >= w[2:]) & (inner + 0.25 * drop > w[j])
        peaks += [int(k) + 1 for k in np.flatnonzero(could) if int(k) + 1 != j]
    best = max([*(parabola_peak(t, w, config, k) for k in peaks), *(sign * e for e in at_events),
                *_right_limits(t, w, config, edges)])
    return float(sign * best)


def _right_limits(t: npt.NDArray[np.float64], w: npt.NDArray[np.float64], config: npt.NDArray[np.int_] | None,
                  edges: Iterable[float]) -> list[float]:
    """w just after each switching edge that falls on a sample where the configuration changes and w jumps there:
    the parabola through the three samples after it (one configuration), at the edge. A jump moves w by more than
    a step's change after it; a continuous w's value there is the sample's, exactly (the parabola's O(h^3) would
    only add the noise a Richardson estimate reads as error: a DCM boost's inductor peak, 5.6e-6 estimated on an
    error of 2e-10)."""
    out: list[float] = []
    if config is None:
        return out
    for edge in edges:
        k = int(np.searchsorted(t, edge))
        if not (k + 3 < t.size and abs(t[k] - edge) <= 1e-12 * max(abs(edge), t[-1] - t[0])
                and config[k] != config[k + 1] and config[k + 1] == config[k + 2] == config[k + 3]):
            continue
        (t1, t2, t3), (a, b, c) = t[k + 1:k + 4], w[k + 1:k + 4]
        if not t[k] < t1 < t2 < t3:
            continue
        d12, d23 = (b - a) / (t2 - t1), (c - b) / (t3 - t2)
        s = t[k]
        after = float(a + d12 * (s - t1) + (d23 - d12) / (t3 - t1) * (s - t1) * (s - t2))
        if abs(after - w[k]) > abs(b - a):
            out.append(after)
    return out


def event_values(tr: Trajectory, v: npt.NDArray[np.float64], instants: Iterable[float]) -> list[float]:
    """v at each event instant inside a step, extrapolated from the two samples before it (same configuration:
    O(h^2)); an instant on a sample takes the sample."""
    out = []
    t = tr.t
    for instant in instants:
        j = int(np.searchsorted(t, instant, side="right")) - 1
        if 0 <= j < t.size and t[j] == instant:
            out.append(float(v[j]))
        elif j >= 1 and tr.config is not None and tr.config[j] == tr.config[j - 1] and t[j] > t[j - 1]:
            out.append(float(v[j] + (v[j] - v[j - 1]) / (t[j] - t[j - 1]) * (instant - t[j])))
    return out


def measures(model: Model, p: dict, tr: Trajectory, T: float) -> tuple[dict, list]:
    """({name: (value, scale)}, events) of one period of ``tr`` starting at 0."""
    values = {}
    edges = np.asarray(model.problem(p, T).switching.breakpoints(0.0, T), dtype=float)
    # a pair that changes at a switching edge changes with the configuration: an edge, not a state event
    events = [e for e in substep_events(tr, T)
              if not np.any(np.abs(np.concatenate([edges, [0.0, T]]) - e[2] * T) <= 1e-9 * T)]
    instants = [] if _exact(tr) else [e[2] * T for e in events]
    # a measure's relative error is taken on its own size, or on the circuit's floor where it is smaller: an output
    # the diodes block both ways (4e-16 V in a 12 V circuit) had been estimated against its own rounding, "6.2e-28"
    least, amps = circuit_floor(tr, "vout"), circuit_floor(tr, "A")
    mean = tr.mean("vout", t0=0.0, t1=T)
    values["vout_mean"] = (mean, max(abs(mean), least))
    rows = np.arange(tr.t.size)
    vout = np.asarray(tr.signal("vout", rows), dtype=float)
    at = event_values(tr, vout, instants)
    ripple = extremum(tr.t, vout, tr.config, 1.0, at, edges) - extremum(tr.t, vout, tr.config, -1.0, at, edges)
    values["vout_ripple"] = (ripple, max(abs(ripple), SMALLEST * abs(mean), least))
    for name in _inductor_currents(model):
        rms = tr.rms(name, t0=0.0, t1=T)
        values[f"{name}_rms"] = (rms, max(abs(rms), amps))
        current = tr.state(name)
        sign = 1.0 if current.max() >= -current.min() else -1.0
        peak = extremum(tr.t, current, tr.config, sign, event_values(tr, current, instants), edges)
        values[f"{name}_peak"] = (peak, max(abs(peak), amps))
    for label, fraction in mode_fractions(tr, T, events, edges).items():
        values[f"fraction_{label}"] = (fraction, 1.0)
    values.update(power_measures(model, p, tr, T))
    return values, events


def power_measures(model: Model, p: dict, tr: Trajectory, T: float) -> dict:
    """The power summary over one period as measures ({name: (value, scale)}): ``input_W`` and ``output_W`` (each
    relative to itself) and ``loss_<element>`` (relative to the input power, as the summary's
    ``losses_W_error_estimate``: a loss of 1 mW beside 60 W need not be known to rtol of itself); {} for a model
    without a power balance, or a run that cannot measure it. The efficiency is their ratio: its relative error
    is at most the sum of theirs (:func:`efficiency_estimate`)."""
    if not hasattr(model, "power"):
        return {}
    power = model.power(tr, p, 0.0, T)
    if not np.isfinite(power["input_W"]):
        return {}
    scale = max(abs(power["input_W"]), 1e-300)
    out = {"input_W": (power["input_W"], scale), "output_W": (power["output_W"], max(abs(power["output_W"]), 1e-300))}
    out.update({f"loss_{name}": (value, scale) for name, value in power["losses_W"].items()})
    return out


def efficiency_estimate(quantities: dict) -> float | None:
    """The efficiency's error estimate (absolute) from the input and output power's (``quantities``: name ->
    {value, relative_error_estimate}, as :meth:`AccurateSteady.summary` gives them): eta = P_out / P_in, so
    |d eta| <= eta (|d P_in| / P_in + |d P_out| / P_out). A bound, not a Richardson estimate of eta itself: at
    an orbit resolved only to the rounding near rho = 1, eta's own error is noise at that level, larger or smaller
    than the floor by a factor 50 from one point to the next (ideal Cuk converters at 1e-7); None without them."""
    if "input_W" not in quantities or "output_W" not in quantities:
        return None
    eta = quantities["output_W"]["value"] / quantities["input_W"]["value"]
    return abs(eta) * (quantities["input_W"]["relative_error_estimate"]
                       + quantities["output_W"]["relative_error_estimate"])


# --- the search ---------------------------------------------------------------------------------------------

def _orbit(model: Model, p: dict, method: Method, x_guess: npt.NDArray[np.float64] | None, warm_up: int,
           tol: float) -> tuple[PeriodicOrbit, Trajectory]:
    """The method's orbit (Newton on its period map, after ``warm_up`` periods) and one period on it, the
    stepper's from the same step plan (built once)."""
    from .periodic import ROUNDING_LIMITED, require, require_stable, shoot
    T = model.period(p)
    problem = model.problem(p, T, x_guess)
    period_map = method.period_map(problem)
    # shooting's own checks: settling rounds where Newton fails, a remote orbit checked against the transient
    orbit = shoot(problem, method, problem.x0, warm_up=warm_up, tol=tol, polish=True, period_map=period_map)
    # an orbit the circuit does not settle on is no steady state to be accurate about (a peak-current buck past its
    # period doubling had read "rtol 0.001 met", vout 7.0452 +- 0.0063 V, where it settles at 6.000005 V on its
    # period-2 orbit; at 1e-5 "1 - rho = -0.7 amplifies" the rounding)
    if orbit.converged or orbit.message.startswith(ROUNDING_LIMITED):
        require_stable(model, p, orbit, "accuracy on request needs a steady state: run --periods N without --rtol")
    orbit = require(orbit, f"the periodic orbit of {model.key}")
    plan = getattr(period_map, "plan", None)
    if plan is not None and hasattr(plan, "trajectory"):
        tr = plan.trajectory(orbit.x0)
    else:
        from ..simulate import simulate
        tr = simulate(model.problem(p, T, orbit.x0), method)
    return orbit, replace(tr, labels=model.labels(p))


def _extremum_run(model: Model, tr: Trajectory, T: float) -> float:
    """The fewest steps of a configuration's run that holds an extremum the measures read (vout's maximum and
    minimum, each inductor current's peak): inf where none is short. An extremum in a run of a few steps lies at
    its ends, where no parabola of one configuration reaches and the runs at N and N/2 share their samples (a buck
    at D = 0.01, its on-time two steps at T/200: its vout minimum 2e-4 V below the sample, the ripple "met" at
    0.1753036 +- 1.3e-6 where it is 0.1755037). The period's runs are taken cyclically (the one through t = 0 is
    one run). An extremum on a sample between two runs lies in the run its one-sided slopes point into (second-order
    differences on each side); where they disagree in sign it is a corner at the switching, which the sample holds
    exactly (an RC's peak at its switch's edge). A signal flat to the circuit's floor (a path the diodes block) has
    no extremum to resolve."""
    config = tr.config
    if config is None:
        return math.inf
    rows = np.flatnonzero(tr.t <= tr.t[0] + T * (1 + 1e-12))
    t, steps = tr.t[rows], np.asarray(config)[rows][1:]         # steps[k]: the configuration of (t[k], t[k + 1]]
    N = steps.size
    if N < 3:
        return math.inf
    change = np.flatnonzero(steps[1:] != steps[:-1]) + 1
    starts, ends = np.concatenate([[0], change]), np.concatenate([change, [N]])
    length = np.empty(N)
    for a, b in zip(starts, ends):
        length[a:b] = b - a
    if len(starts) > 1 and steps[0] == steps[-1]:                # the run through t = 0, joined
        length[:ends[0]] = length[starts[-1]:] = ends[0] + (N - starts[-1])
    h = float(np.median(np.diff(t)))
    floor = circuit_floor(tr)
    fewest = math.inf
    signals = [(np.asarray(tr.signal("vout", rows), dtype=float), (1.0, -1.0))]
    for name in _inductor_currents(model):            # the peak on the side measures() reads
        current = np.asarray(tr.state(name), dtype=float)[rows]
        signals.append((current, (1.0 if current.max() >= -current.min() else -1.0,)))
    for values, signs in signals:
        if np.ptp(values) <= floor:
            continue
        for sign in signs:
            w = sign * values[:N]                        # one period, cyclic (the orbit's last sample is its first)
            j = int(np.argmax(w))
            left, right = (j - 1) % N, j % N              # the steps ending and starting at sample j
            if steps[left] == steps[right]:
                fewest = min(fewest, length[right])
                continue
            slope_left = ((3 * w[j] - 4 * w[(j - 1) % N] + w[(j - 2) % N]) / (2 * h)
                          if steps[(left - 1) % N] == steps[left] else None)
            slope_right = ((-3 * w[j] + 4 * w[(j + 1) % N] - w[(j + 2) % N]) / (2 * h)
                           if steps[(right + 1) % N] == steps[right] else None)
            if slope_left is None or slope_right is None:
                fewest = min(fewest, length[left], length[right])
            elif slope_left * slope_right > 0.0:       # still rising (or falling) through the switching
                fewest = min(fewest, length[right] if slope_right > 0.0 else length[left])
    return fewest


def _sampled(model: Model, tr: Trajectory, T: float) -> dict:
    """Ripple and peaks read on every other output sample (event instants kept, and the samples either side of each
    boundary: the exact run holds both, so a jump's value after it is read as a sample): {name: value}."""
    keep = np.zeros(tr.t.size, dtype=bool)
    keep[::2] = True
    keep[-1] = True
    if len(tr.events):
        keep[np.clip(tr.events["step"].to_numpy(dtype=int), 0, tr.t.size - 1)] = True
    configs = cast("npt.NDArray[np.int_]", tr.config)     # an LCS run's (its configurations are recorded)
    changed = np.diff(configs) != 0
    held = getattr(tr, "held", None)
    if held is not None and held.shape[0] == configs.size and held.size:
        # a held set's change is a boundary the exact run holds both sides of too (a diode's current as it turns on)
        changed |= (np.diff(held.astype(np.int8), axis=0) != 0).any(axis=1)
    edges = np.flatnonzero(changed)                      # the samples either side of a switching edge
    keep[edges] = keep[edges + 1] = True
    rows = np.flatnonzero(keep & (tr.t <= T))
    t, config = tr.t[rows], configs[rows]
    vout = np.asarray(tr.signal("vout", rows), dtype=float)
    out = {"vout_ripple": extremum(t, vout, config, 1.0) - extremum(t, vout, config, -1.0)}
    for name in _inductor_currents(model):
        current = tr.state(name)
        # signed and on the side :func:`measures` takes (a winding's negative peak was compared in its absolute
        # value with its signed one: 2 x 2.71 A apart, "estimated only to 0.67" on an exact run)
        sign = 1.0 if current.max() >= -current.min() else -1.0
        out[f"{name}_peak"] = extremum(t, current[rows], config, sign)
    return out


def _rounding(orbit: PeriodicOrbit, operations: int) -> float:
    """The orbit's relative error floor: its Newton distance, and the rounding of a period map of
    ``operations`` steps amplified by 1 / (1 - rho): the step matrices' own rounding repeats at every step,
    so it adds up over a period and the fixed point moves by it / (1 - rho). Calibrated on the DCM
    buck-boost at 5 kOhm (rho = 1 - 1.6e-5): 1.1e-7 measured after 34,928 steps = 0.23 eps per step."""
    rho = float(np.abs(orbit.multipliers).max()) if len(orbit.multipliers) else 0.0
    amplification = 1.0 / max(1.0 - rho, 1e-12)
    return max(orbit.distance, ROUNDING_PER_OPERATION * operations * amplification)


def paired_events(a: Sequence[tuple], b: Sequence[tuple]) -> list[tuple[int, int]] | None:
    """Which event of ``b`` each event of ``a`` is (index pairs in ``a``'s order), or None where the two runs'
    period events are not the same: every pair with the same sequence of kinds in both (the k-th event of a pair is
    its k-th in the other run; only then is one run's event an estimate of the other's). Events of different pairs
    may interleave differently: a 12-stage ladder's diodes at nearly one instant swap places from one step to the
    next, and a strict order left every event without an estimate (inf) up to the largest step count."""
    def by_pair(events: Sequence[tuple]) -> dict[Any, list[tuple[str, int]]]:
        out: dict[Any, list[tuple[str, int]]] = {}
        for index, event in enumerate(events):
            out.setdefault(event[0], []).append((event[1], index))
        return out
    ours, theirs = by_pair(a), by_pair(b)
    if len(a) != len(b) or ours.keys() != theirs.keys():
        return None
    matches = []
    for pair, sequence in ours.items():
        if [kind for kind, _ in sequence] != [kind for kind, _ in theirs[pair]]:
            return None
        matches += [(i, j) for (_, i), (_, j) in zip(sequence, theirs[pair])]
    return sorted(matches)


def _estimates(fine: dict, coarse: dict, fine_events: list[tuple[str, str, float]],
               coarse_events: list[tuple[str, str, float]], order: float, floor: float,
               ratio: float = 2.0) -> tuple[dict[str, Estimate], list[tuple[str, str, Estimate]]]:
    """Richardson's estimates of the fine values from a coarse run with ``ratio`` times the step."""
    factor = ratio ** order - 1.0
    out = {}
    for name, (value, scale) in fine.items():
        other = coarse.get(name, (0.0 if name.startswith("fraction_") else math.nan, scale))[0]
        error = abs(value - other) / factor if math.isfinite(other) else math.inf
        # a period without pair events has its mode fractions on the switching edges: exact
        state_floor = floor * scale if (fine_events or not name.startswith("fraction_")) else 0.0
        out[name] = Estimate(float(value), max(error, state_floor), float(scale))
    for name in coarse:
        if name.startswith("fraction_") and name not in out:             # a mode the finer orbit lost
            out[name] = Estimate(0.0, coarse[name][0] / factor, 1.0)
    matches = paired_events(fine_events, coarse_events)
    if matches is not None:
        events = [(pair, kind, Estimate(tf, max(abs(tf - coarse_events[j][2]) / factor, floor), 1.0))
                  for (pair, kind, tf), (_, j) in zip(fine_events, matches)]
    else:                                                                # the event sequence is not settled
        events = [(pair, kind, Estimate(tf, math.inf, 1.0)) for pair, kind, tf in fine_events]
    return out, events


def _guarded(quantities: dict[str, Estimate], events: list[tuple[str, str, Estimate]],
             history: tuple[int, dict[str, Estimate], list[tuple[str, str, Estimate]]] | None, n: int,
             order: float) -> tuple[dict[str, Estimate], list[tuple[str, str, Estimate]]]:
    """Each estimate at least ``GUARD`` x what the previous one predicts at n steps (its value x (n_prev /
    n)^order): two runs whose values meet by chance (the stepper's error through diode events is irregular
    in h) must not pass for converged (buck DCM at 1e-7: 3.4e-10 estimated against 1.9e-8 true without this
    guard), while a previous estimate from before the asymptotic range (too large) must not inflate the next
    one past 10x the truth (the guard at 1: ripple at 1e-4, 3.5e-5 estimated against 9e-7 true)."""
    if history is None:
        return quantities, events
    n_prev, previous, previous_events = history
    shrink = GUARD * (n_prev / n) ** order
    out = {}
    for name, q in quantities.items():
        before = previous.get(name)
        predicted = before.error_estimate * shrink if before is not None else 0.0
        out[name] = Estimate(q.value, max(q.error_estimate, predicted), q.scale)
    matches = paired_events(events, previous_events)
    if matches is not None:
        events = [(pair, kind, Estimate(e.value, max(e.error_estimate, previous_events[j][2].error_estimate * shrink),
                                        1.0)) for (pair, kind, e), (_, j) in zip(events, matches)]
    return out, events


def accurate_steady(model: Model, p: dict, rtol: float, *, x0: npt.NDArray[np.float64] | None = None,
                    progress: Any = None) -> AccurateSteady:
    """The periodic steady state of ``model`` at ``p`` with every measure's error estimate below ``rtol``
    (module docstring). Raises ParameterError for an rtol outside [1e-10, 0.1] or a model without a fixed
    period, SimulationError when no orbit is found."""
    from ..methods import EventDriven, Theta
    from .periodic import passive, stability_undecided
    rtol = float(rtol)
    if not RTOL_RANGE[0] <= rtol <= RTOL_RANGE[1]:
        raise ParameterError(f"rtol must be in [{RTOL_RANGE[0]:g}, {RTOL_RANGE[1]:g}]; got {rtol!r}")
    if not model.periodic(p):
        raise ParameterError(f"rtol: accuracy on request works on a periodic steady state; {model.key} has no fixed "
                             "switching period")
    clock = time.perf_counter()
    T = model.period(p)
    tol = max(rtol / 100.0, 1e-12)
    target = rtol / SAFETY
    runs = []

    def run(method: Method, guess: npt.NDArray[np.float64] | None, warm_up: int) -> tuple[PeriodicOrbit, Trajectory]:
        start = time.perf_counter()
        orbit, tr = _orbit(model, p, method, guess, warm_up, tol)
        runs.append({"method": method.key, "steps_per_period": int(round(T / method.step)) if method.step else None,
                     "periods": int(warm_up + orbit.evaluations + 1), "wall_s": time.perf_counter() - start,
                     "orbit_distance": orbit.distance})
        return orbit, tr

    # where the exact method cannot take the circuit (a SIN or PWL source) nothing checks the stepper's estimates
    # after it: they take the order observed from one estimate to the next (:func:`_order_between`), not the
    # declared 2 (a SIN rectifier's error converges at order 1: its estimates read 3.0x short)
    try:
        EventDriven().supports(model.problem(p, T))
        observe = False
    except ResourceError:
        raise
    except ParameterError:
        observe = True
    exact_takes_it = not observe
    stepper_failed: SimulationError | None = None     # a finer stepper run's refusal, left to the exact method
    differences: list[tuple[int, float, float]] = []         # (fine N, N / coarse N, |vout_mean difference|)
    theta, coarse_n = _refinement_start(model, p)
    try:
        orbit, tr = run(Theta(h=T / coarse_n, theta=theta), x0, 20)
        previous = (measures(model, p, tr, T), orbit)
    except SimulationError:
        previous = None
    fine_n = 2 * coarse_n
    history, best = None, None
    events: list            # (pair, kind, Estimate) of the stepper's runs; (pair, kind, time) of the event method's
    stopped = ""            # why the stepper's refinement stopped short of MAX_STEPS
    damped = ""             # why backward Euler's estimates cannot be trusted (:func:`_overdamped`)
    unresolved = ""         # why the finest stepper run's estimates miss an error (a short run, an onset in a step)
    most_n = MAX_STEPS
    while previous is not None and fine_n <= most_n:
        fine_method = Theta(h=T / fine_n, theta=theta)
        try:
            orbit, tr = run(fine_method, previous[1].x0, 0)
        except ResourceError as why:     # a SIN source's plan holds a matrix set a step: memory ends the refinement
            if best is None:
                raise
            stopped = f"the next run at {fine_n:,} steps a period cannot be made ({why})"
            break
        except SimulationError as why:
            # the stepper's orbit at this step unstable or not found, where the exact method takes the circuit: its
            # orbit decides (a DCM boost's switch capacitance ringing with L: the trapezoid's multiplier -1.00211 at
            # one step, the circuit's orbit stable at 0.99893, had been refused as "the circuit does not settle")
            if not exact_takes_it:
                raise
            stepper_failed = why
            break
        fine, fine_events = measures(model, p, tr, T)
        (coarse, coarse_events), _ = previous
        floor = _rounding(orbit, fine_n)
        order = stepped_order(fine_method, tr)
        if observe:
            differences.append((fine_n, fine_n / coarse_n, abs(fine["vout_mean"][0] - coarse["vout_mean"][0])))
            order = _order_between(differences, order)
        quantities, events = _estimates(fine, coarse, fine_events, coarse_events, order, floor,
                                        ratio=fine_n / coarse_n)
        quantities, events = _guarded(quantities, events, history, fine_n, order)
        history = (fine_n, quantities, events)
        result = AccurateSteady(quantities, events, rtol, fine_method, fine_n, tr, orbit, True, runs=runs)
        worst = result.worst()
        # backward Euler erasing a resonance the circuit keeps (a snubber's ring) does so at N and 2N alike: its
        # estimates agree with themselves (a buck's 1 ohm, 10 pF snubbers: 9e-6 estimated, 6.6e-4 true)
        damped = _overdamped(model, p, fine_method, remedy=False) if theta > THETA else ""
        # an interval of a few steps holds its extrema at its ends, where no parabola of one configuration reaches
        # and the runs at N and N/2 share their samples (a buck at D = 0.01, its on-time two steps at T/200: the
        # ripple 0.1753036 +- 1.3e-6 met, where it is 0.1755037): met only from FEW_STEPS steps an interval
        few = _extremum_run(model, tr, T)
        # a conduction that begins inside the first step after a switching lies inside it at N and N/2 alike, and
        # Richardson does not see its first-order error at any step (a buck with 1 mohm in its inductor into 1 Mohm:
        # its peak 4.7873e-5 +- 1.7e-9 A "met", where it is 4.79452e-5, 43 times the estimate): the exact method
        onset = _unresolved_onset(model, p, tr) if worst <= target and not damped else ""
        unresolved = onset or (f"an extremum lies in a run of {few:.0f} step{'s' if few != 1 else ''} (its estimate "
                               f"needs {FEW_STEPS})" if few < FEW_STEPS else "")
        if onset:
            best, stopped = result, onset
            break
        if worst <= target and not damped and few >= FEW_STEPS:
            # a spectral radius the step's own error may carry across 1 is no stable orbit yet: the exact method's
            # decides (a voltage-mode buck past its period doubling, exact -1.0139, read stable and "met")
            undecided = (stability_undecided(orbit.multipliers, previous[1].multipliers)
                         if exact_takes_it and not passive(model, p) else "")
            if not undecided:
                return replace(result, wall_s=time.perf_counter() - clock)
            best, stopped, stepper_failed = result, undecided, SimulationError(undecided)
            break
        best = result
        if damped and theta > THETA:
            # the trapezoid from the steps at which it does not ring on the fastest mode damps nothing: the
            # refinement starts again there (the same buck: 1.7e5 steps a period, 0.04 s each), as far as memory
            # allows; the event method after it where it does not meet rtol
            theta, coarse_n = THETA, _resolved_steps(model, p)
            try:
                orbit, tr = run(Theta(h=T / coarse_n, theta=theta), orbit.x0, 0)
            except (ResourceError, SimulationError) as why:
                stopped = f"the trapezoid at {coarse_n:,} steps a period cannot be run ({why})"
                break
            previous, history, fine_n = (measures(model, p, tr, T), orbit), None, 2 * coarse_n
            most_n = max(MAX_STEPS, 4 * coarse_n)
            differences.clear()
            # from steps that do not resolve the fastest mode (h rate up to 6) the trapezoid is not in its
            # asymptotic regime: its estimates take the order observed, as a SIN source's do (the 100 pF snubbed
            # buck converges at order ~1 there: 2.5e-5, 1.5e-5, 9.9e-6, 4.6e-6 V off at 16,667..133,336 steps; the
            # declared 2 read its error 4.4x short)
            observe = True
            continue
        if floor > target:                       # rounding over the period's steps, amplified near rho = 1
            break
        # the next fine N from the estimates and the order (x 1.2, to land in one step); its coarse
        # run is this one when the ratio stays within MAX_RATIO, else a new one at half the step count
        growth = 1.2 * (worst / target) ** (1.0 / order) if math.isfinite(worst) else 2.0
        if few < FEW_STEPS:      # at least the next doubling (the extremum may move into a long run there)
            growth = max(growth, 2.0)
        next_n = int(math.ceil(fine_n * min(max(growth, 2.0), MAX_GROWTH)))
        if next_n > most_n:
            break
        if next_n <= MAX_RATIO * fine_n:
            coarse_n, previous = fine_n, ((fine, fine_events), orbit)
        else:
            coarse_n = next_n // 2
            try:
                orbit_c, tr_c = run(Theta(h=T / coarse_n, theta=theta), orbit.x0, 0)
            except ResourceError as why:
                stopped = f"the next runs at {coarse_n:,} and {next_n:,} steps a period cannot be made ({why})"
                break
            previous = (measures(model, p, tr_c, T), orbit_c)
        fine_n = next_n
    # the stepper would need more than MAX_STEPS steps per period: the exact method, where it takes the circuit
    method = EventDriven(output_step=T / EVENT_SAMPLES)
    try:
        method.supports(model.problem(p, T))
        orbit, tr = run(method, x0 if previous is None else previous[1].x0, 20 if previous is None else 0)
    except (ParameterError, SimulationError, ResourceError) as why:
        if best is None or stepper_failed is not None:
            # no coarser run stands for an answer once a finer one was refused: the exact method's refusal decides
            raise
        # a SIN source, a time constant the exact flows would cross in billions of substeps (a 1 mohm ESR beside
        # 10 pF: 3.3e-15 s), a limit reached, or no orbit found: the stepper's finest run is the answer, its
        # Richardson estimates stated and rtol said unmet
        # the rules the stepper's estimates answer to hold for its finest run too (a SIN source's circuit)
        met = best.worst() <= rtol and not damped and not unresolved
        message = "" if met else (f"the stepper's estimate at {best.steps_per_period:,} steps a period is "
                                  f"{best.worst():.2g}" + (f", not to be trusted: {damped}" if damped else "")
                                  + (f", not to be trusted: {unresolved}" if unresolved and unresolved != stopped
                                     else "")
                                  + "; " + (f"{stopped}; " if stopped else "")
                                  + f"and the exact event method does not take this circuit ({why})")
        return replace(best, met=met, message=message, wall_s=time.perf_counter() - clock)
    floor = _rounding(orbit, EVENT_SEGMENTS)
    samples = EVENT_SAMPLES
    while True:
        values, events = measures(model, p, tr, T)
        quantities = {name: Estimate(float(v), floor * s if (events or not name.startswith("fraction_")) else 0.0,
                                     float(s)) for name, (v, s) in values.items()}
        read = _sampled(model, tr, T)
        for name, coarse in read.items():                           # extrema read on the samples: their error
            q = quantities[name]
            quantities[name] = Estimate(q.value, max(abs(q.value - coarse) / 3.0, q.error_estimate), q.scale)
        if max((quantities[name].relative for name in read), default=0.0) <= target \
                or samples * SAMPLE_GROWTH > MAX_EVENT_SAMPLES:
            break
        # an extremum between samples short of the target (a snubber's ring on a peak, a 10 mF output's ripple):
        # the same orbit's period again at a finer spacing, its flows as exact as before
        start = time.perf_counter()
        # (the result's method keeps the first spacing: a run shown on the orbit need not carry the finest)
        samples *= SAMPLE_GROWTH
        from ..simulate import simulate
        tr = replace(simulate(model.problem(p, T, orbit.x0), EventDriven(output_step=T / samples)),
                     labels=model.labels(p))
        runs.append({"method": method.key, "steps_per_period": None, "periods": 1, "samples_per_period": samples,
                     "wall_s": time.perf_counter() - start, "orbit_distance": orbit.distance})
    exact_events = [(pair, kind, Estimate(time_T, floor, 1.0)) for pair, kind, time_T in events]
    result = AccurateSteady(quantities, exact_events, rtol, method, None, tr, orbit, True, runs=runs)
    met = result.worst() <= rtol
    name, worst = max(((name, q.relative) for name, q in quantities.items()), key=lambda item: item[1],
                      default=("", 0.0))
    if met:
        message = ""
    elif worst > 10.0 * floor:      # not the orbit's rounding: an extremum read on the samples (a ripple)
        message = (f"{name} is estimated only to {worst:.2g} (relative), read on the exact run's {samples:,} "
                   f"samples a period (an extremum between two of them); rtol {rtol:g} is beyond it")
    else:
        message = (f"the orbit is resolved to {orbit.distance:.2g} in double precision (a Floquet multiplier at "
                   f"{np.abs(orbit.multipliers).max():.8f}); rtol {rtol:g} is beyond it")
    return replace(result, met=met, message=message, wall_s=time.perf_counter() - clock)


def _resolved_steps(model: Model, p: dict) -> int:
    """The fewest steps per period at which the trapezoid does not ring on the circuit's fastest mode (its
    amplification at z = -h rate above -RINGS: :func:`~converters.methods.theta.check_ringing`)."""
    from ..methods.theta import RINGS
    limit = 2.0 * (1.0 + RINGS) / (1.0 - RINGS)          # (1 - z/2) / (1 + z/2) = -RINGS at z = h rate = limit
    return max(FIRST_STEPS, math.ceil(model.period(p) * model.fastest_rate(p) / limit))


def _refinement_start(model: Model, p: dict) -> tuple[float, int]:
    """The stepper's theta for the whole refinement and its first steps per period: THETA (second order) from the
    first step count at which it does not ring on the circuit's fastest mode (the amplification -RINGS of
    :func:`~converters.methods.theta.check_ringing`: h rate <= 6; FIRST_STEPS at least) where that leaves the
    refinement room, else backward Euler from FIRST_STEPS (L-stable, first order): theta 0.5 over a 3.3e-15 s node
    (1 mohm beside 10 pF, 3e7 time constants a step at T/100) had no step LCP solution, and --rtol fell to the event
    method, which refuses that time constant."""
    needed = _resolved_steps(model, p)
    if needed <= FIRST_STEPS:
        return THETA, FIRST_STEPS
    return (THETA, needed) if needed <= MAX_STEPS // FIRST_STEPS else (1.0, FIRST_STEPS)


def stepped_order(method: Method, tr: Trajectory) -> float:
    """The order of the stepper's run ``tr``: the method's declared one, or LEAST_ORDER where a pair that conducts
    in the run has a resistance of its own (D_ii > 0: a diode's RS) and moves the state (B's column): the stepper
    moves the state by the pair at each step's end (h B u_{k+1}), backward Euler on the RS C modes. A Greinacher
    doubler's error halves with h (1.20e-3, 6.0e-4, 3.0e-4 V at T/400, T/800, T/1600), and --rtol 1e-4 had read
    it 3.1 times short at the declared 2, "met" 1.2e-4 off."""
    order = float(method.order)
    problem = tr.problem
    if order <= LEAST_ORDER or tr.u is None or tr.config is None or problem is None or not tr.u.shape[1]:
        return order
    held = tr.active
    for c in np.unique(tr.config):
        if int(c) >= len(problem.configurations):   # a run in phases holds its first phase's problem
            continue
        cfg = problem.configurations[int(c)]
        conducting = held[tr.config == c].any(axis=0)
        own = np.diag(np.asarray(cfg.D, dtype=float)) > 0.0
        moves = np.abs(np.asarray(cfg.B, dtype=float)).max(axis=0) > 0.0
        if (conducting & own & moves).any():
            return LEAST_ORDER
    return order


def _order_between(differences: Sequence[tuple[int, float, float]], declared: float) -> float:
    """The order of an error C N^-p that makes the last two Richardson differences (N, r = N / coarse N, |Q(N) -
    Q(N / r)| = C N^-p (r^p - 1)) what they are, within [LEAST_ORDER, declared]; LEAST_ORDER before there are two
    (or where they do not shrink)."""
    if len(differences) < 2:
        return LEAST_ORDER
    (n1, r1, d1), (n2, r2, d2) = differences[-2:]
    if not (d1 > 0.0 and d2 > 0.0):
        return declared if d2 == 0.0 else LEAST_ORDER

    # zero at the order that makes d1 / d2 what it is; decreasing in q where r2 <= n2 / n1 (the loop's growth >= 2)
    def mismatch(q: float) -> float:
        return math.log(d1 / d2) - q * math.log(n2 / n1) - math.log((r1 ** q - 1.0) / (r2 ** q - 1.0))
    low, high = LEAST_ORDER, declared
    if mismatch(high) >= 0.0:
        return high
    if mismatch(low) <= 0.0:
        return low
    for _ in range(60):
        mid = 0.5 * (low + high)
        low, high = (mid, high) if mismatch(mid) > 0.0 else (low, mid)
    return 0.5 * (low + high)


# --- what a run with the defaults can claim --------------------------------------------------------------

#: The smallest scale of a measure's relative error, relative to the circuit's (a ripple's: to its mean).
SMALLEST = 1e-6
#: The accuracy the defaults promise on every reported mean, or warn about.
DEFAULT_RTOL = 1e-3


def circuit_floor(tr: Trajectory, unit: str | None = None) -> float:
    """The smallest size a relative error is taken on: SMALLEST of the circuit's scale (its largest state, input or
    pair variable over the run). An output that is rounding (a path the diodes block both ways: 4e-16 V in a 12 V
    circuit) had read "within ~0.2" and "has not settled (2.5e-01 from the periodic orbit)" on an orbit 5.5e-14
    from Newton's, and "3.7e-16 +- 6.2e-28" under --rtol. One floor for the defaults' check and --rtol's measures:
    a fixed 1 nV had served the first, which is 1e-6 of a 1 mV circuit and 1e-12 of a 1 kV one.

    With a ``unit`` ("V", "A", or "vout" for the output's) of a model that says its scales (a netlist's
    :meth:`~converters.models.Circuit.unit_scales`), the scale is that unit's, and the other unit's through the
    circuit's largest conductance where that is smaller than the mixed scale: a volt is no size for an ampere (a peak
    detector fed through 1 Gohm, its diode's 3.9 nA peak read half as large at h, had been judged against 1e-6 of
    its 10 V source: 3.3e-5 "off", no warning), and currents that are all rounding (a path the diodes block) are
    still judged against the current the circuit's voltages drive through it."""
    scale = max(float(np.abs(np.asarray(a, dtype=float)).max(initial=0.0))
                for a in (tr.x, tr.u if tr.u is not None else 0.0, tr.y if tr.y is not None else 0.0))
    mixed = max(SMALLEST * scale, float(np.finfo(float).tiny))
    if unit == "vout":                                  # the output's own unit
        units = getattr(getattr(tr.labels, "model", None), "signal_units", None) or {}
        unit = units.get("vout", "V")
    scales = _unit_scales(tr) if unit in ("V", "A") else None
    if scales is None:
        return mixed
    conductance = scales["S"]
    if conductance > 0.0:
        other = scales["V"] * conductance if unit == "A" else scales["A"] / conductance
        across = min(mixed, SMALLEST * other)
    else:
        across = mixed
    return max(SMALLEST * scales[cast(str, unit)], across, float(np.finfo(float).tiny))


def _unit_scales(tr: Trajectory) -> dict[str, float] | None:
    """The run's largest voltage, current and its circuit's conductance (:meth:`~converters.models.Circuit.
    unit_scales`), once per run; None where the model does not say them."""
    if "_unit_scales" not in tr.__dict__:
        labels = tr.labels
        say = getattr(getattr(labels, "model", None), "unit_scales", None)
        tr.__dict__["_unit_scales"] = (None if say is None or labels is None
                                       else say(tr.samples(np.arange(tr.t.size)), getattr(labels, "params", {})))
    return cast("dict[str, float] | None", tr.__dict__["_unit_scales"])


#: A conduction interval spanning fewer steps than this is named in the warning.
FEW_STEPS = 20


def last_period(model: Model, p: dict, tr: Trajectory) -> dict:
    """The last period's mode fractions and event instants read inside the step (not on the output grid)."""
    T = model.period(p)
    t0 = float(tr.t[-1]) - T
    edges = model.problem(p, float(tr.t[-1])).switching.breakpoints(t0, t0 + T)
    boundaries = np.concatenate([np.asarray(edges, float), [t0, t0 + T]])
    events = [e for e in substep_events(tr, T, t0)
              if not np.any(np.abs(boundaries - (t0 + e[2] * T)) <= 1e-9 * T)]
    fractions = mode_fractions(tr, T, events, edges, t0)
    bounds = np.unique(np.concatenate([boundaries, [t0 + e[2] * T for e in events]]))
    # each mode between two pair events with no switching edge between them, shortest first: (its length in T, the
    # event that starts it, the one that ends it)
    timed = sorted(events, key=lambda e: e[2])
    between = sorted(((b[2] - a[2], a, b) for a, b in zip(timed, timed[1:]) if b[2] - a[2] > 1e-12
                      and not np.any((boundaries > t0 + a[2] * T) & (boundaries < t0 + b[2] * T))),
                     key=lambda mode: mode[0])
    return {"mode_fractions": fractions, "events": events, "t0": t0,
            "shortest_interval_T": float(np.diff(bounds)[np.diff(bounds) > 1e-12 * T].min() / T),
            "modes_between_events": between}


@dataclass(frozen=True)
class OrbitRuns:
    """One period on the method's periodic orbit (``fine``), for a stepper also on its orbit at 2h (``coarse``; None
    for the exact event method), and the order Richardson's estimate from the two takes (:func:`_observed_order`)."""
    fine: Trajectory
    coarse: Trajectory | None
    order: float
    #: The orbits' Floquet multipliers at h and 2h (a stepper's), or None.
    multipliers: tuple[npt.NDArray[np.complex128], npt.NDArray[np.complex128]] | None = None

    @property
    def factor(self) -> float:
        """2^p - 1: the difference at h and 2h over the error at h, for an error C h^p."""
        return 2.0 ** self.order - 1.0


def orbit_runs(model: Model, p: dict, method: Method, tr: Trajectory, observe: bool = True) -> OrbitRuns | str:
    """:func:`_orbit_runs` from the run's last state, found once per run and method: the accuracy check and the
    devices' losses' estimate (:mod:`converters.thermal.summary`) read the same orbits. ``observe``: the order
    observed on a third orbit at 4h (else the declared one: a caller that does not read it)."""
    cache: dict[int, Any] = tr.__dict__.setdefault("_orbit_runs", {})
    if id(method) not in cache:
        cache[id(method)] = (_orbit_runs(model, p, method, tr.x[-1], observe), method)   # the method kept: its id
    return cast("OrbitRuns | str", cache[id(method)][0])


def _orbit_runs(model: Model, p: dict, method: Method, x_guess: npt.NDArray[np.float64],
                observe: bool = True) -> OrbitRuns | str:
    """One period on the method's periodic orbit, and for the stepper also on its orbit at 2h (None for the
    event method, exact), with the order of the stepper's error; or a string saying which orbit was not found."""
    from ..simulate import simulate
    from .periodic import ROUNDING_RESOLVED, resolved, shoot    # an orbit rounding stops short of 1e-8 serves
    T = model.period(p)
    orbit = shoot(model.problem(p, T, x_guess), method, x_guess, tol=1e-8, polish=True)
    if not resolved(orbit):
        # its tolerance is the check's, not the run's: a run at --steady-tol 1e-4 read "> tol 1e-08" as its own
        return (f"the check's own orbit (Newton from the run's end to 1e-8, or to {ROUNDING_RESOLVED:g} where rounding "
                f"stops it) was not found ({orbit.message})")

    def run(m: Method, x0: npt.NDArray[np.float64]) -> Trajectory:
        return replace(simulate(model.problem(p, T, x0), m), labels=model.labels(p))
    if not method.fixed_step:
        return OrbitRuns(run(method, orbit.x0), None, math.inf)
    coarse = method.coarsened()
    try:
        orbit_2h = shoot(model.problem(p, T, orbit.x0), coarse, orbit.x0, tol=1e-8, polish=True)
    except ResourceError:
        raise
    except ParameterError as why:        # a step the run takes whose double it does not (a SIN source: T / 2h whole)
        return f"the orbit at 2h cannot be run ({why})"
    if not resolved(orbit_2h):
        return f"the orbit at 2h was not found ({orbit_2h.message})"
    fine = run(method, orbit.x0)
    coarse_run = run(coarse, orbit_2h.x0)
    order = float(method.order)
    if observe and order > LEAST_ORDER:
        # through a diode event inside a step the trapezoid's order falls to 1.5 or below; where a pair changes with a
        # switching edge it can fall to 1 as well (a step from the edge takes the pair's value before it: a Dickson
        # pump's diodes, each switching at the clock's edges, converge at order 1 and order 2 read 3.0x short)
        ceiling = min(order, ORDER_THROUGH_EVENTS) if substep_events(fine, T) else order
        order = _observed_order(model, p, method, orbit_2h.x0, fine, coarse_run,
                                min(ceiling, stepped_order(method, fine)))
    return OrbitRuns(fine, coarse_run, order, (orbit.multipliers, orbit_2h.multipliers))


def _observed_order(model: Model, p: dict, method: Method, x_2h: npt.NDArray[np.float64], fine: Trajectory,
                    coarse: Trajectory, ceiling: float) -> float:
    """The order of the stepper's error in vout's mean, which falls below the declared one by as much as the diode
    events weigh: from a third orbit at 4h, log2 of the ratio of the differences 2h-4h and h-2h, at most ``ceiling``
    (the declared order, or :data:`ORDER_THROUGH_EVENTS` through an event inside a step), at least
    :data:`OBSERVED_FLOOR` (also where the differences do not shrink); :data:`LEAST_ORDER` where the orbit at 4h
    cannot be found or run. Backward Euler, of declared order LEAST_ORDER, is not asked: its order is that
    already."""
    from ..simulate import simulate
    from .periodic import resolved, shoot
    T = model.period(p)
    coarser = method.coarsened(4.0)
    try:
        orbit_4h = shoot(model.problem(p, T, x_2h), coarser, x_2h, tol=1e-8, polish=True)
        if not resolved(orbit_4h):
            return LEAST_ORDER
        at_4h = simulate(model.problem(p, T, orbit_4h.x0), coarser)
    except ResourceError:
        raise
    except (ParameterError, SimulationError):   # 4h not a step the circuit takes (a SIN source: T / 4h not whole),
        return LEAST_ORDER                       # or a step LCP without a solution there
    m_h, m_2h = fine.mean("vout", t0=0.0, t1=T), coarse.mean("vout", t0=0.0, t1=T)
    m_4h = replace(at_4h, labels=model.labels(p)).mean("vout", t0=0.0, t1=T)
    near, far = m_h - m_2h, m_2h - m_4h
    if near == 0.0:
        return ceiling
    ratio = far / near
    if not ratio > 2.0 ** OBSERVED_FLOOR:      # not shrinking as a power of h (or changing sign): not asymptotic
        return OBSERVED_FLOOR
    return min(ceiling, math.log2(ratio))


def _power_check(model: Model, p: dict, runs: OrbitRuns, reported: dict | None,
                 reference: Trajectory | None = None) -> dict:
    """How far the reported efficiency (absolute), input power and each loss (relative to the input power) may
    be from the exact periodic ones: the reported values' distance to the orbit's plus Richardson's estimate
    from the orbits at h and 2h, by the method's order (the switched currents' jumps at the switching edges are
    integrated within each step's own configuration: ``Trajectory`` reads a step that starts at an edge in its own
    configuration). Backward Euler's end-point rule is first order: at h = T/1000 a 48 V buck's efficiency (with
    DCR, Ron, a diode drop and ESR) reads 5.7e-4 short. With a ``reference`` (the exact method's orbit, one period
    from 0), its values stand for the exact ones."""
    if reported is None or not hasattr(model, "power") or not np.isfinite(reported.get("input_W", np.nan)):
        return {}
    T = model.period(p)
    fine, coarse = runs.fine, runs.coarse
    at_h = model.power(fine, p, 0.0, T)
    exact = {"efficiency": at_h["efficiency"], "input_W": at_h["input_W"], **at_h["losses_W"]}
    if reference is not None:
        at_exact = model.power(reference, p, 0.0, T)
        exact = {"efficiency": at_exact["efficiency"], "input_W": at_exact["input_W"], **at_exact["losses_W"]}
    elif coarse is not None:
        at_2h = model.power(coarse, p, 0.0, T)
        coarse_values = {"efficiency": at_2h["efficiency"], "input_W": at_2h["input_W"], **at_2h["losses_W"]}
        exact = {k: v + (v - coarse_values[k]) / runs.factor for k, v in exact.items()}
    scale = max(abs(exact["input_W"]), 1e-300)
    losses = [abs(v - exact[k]) / scale for k, v in reported["losses_W"].items() if k in exact]
    return {"efficiency_error_estimate": abs(reported["efficiency"] - exact["efficiency"]),
            "input_W_error_estimate": abs(reported["input_W"] - exact["input_W"]) / scale,
            "losses_W_error_estimate": max(losses, default=0.0),
            # each loss's own, in W: a diode's drop conducting one step of the period is known to 10 % of itself
            # where the largest is known to 1e-5 of the input
            "loss_error_estimates_W": {k: abs(v - exact[k]) for k, v in reported["losses_W"].items() if k in exact},
            # its parts, for the remedy: the run's distance to the orbit, and the step's error on the orbit
            "efficiency_transient": abs(reported["efficiency"] - at_h["efficiency"]),
            "efficiency_discretization": abs(at_h["efficiency"] - exact["efficiency"])}


def _power_warning(check: dict, method: Method) -> str:
    error = check.get("efficiency_error_estimate", 0.0)
    if not error > DEFAULT_RTOL:
        return ""
    if check["efficiency_transient"] > check["efficiency_discretization"]:
        remedy = "the run has not settled (its power balance still carries the transient): use --steady"
    else:
        remedy = ("the step is too coarse: use --method event (exact at the switchings), a smaller --h, or --rtol"
                  if method.fixed_step else "use --steady")
    return (f"efficiency may be {error:.1e} off (more than {DEFAULT_RTOL:g}; input power "
            f"{check['input_W_error_estimate']:.1e}): {remedy}")


def default_check(model: Model, p: dict, method: Method, tr: Trajectory, reported: float,
                  power: dict | None = None) -> dict:
    """How far the reported mean (vout over the run's last 10 periods) may be from the exact periodic one, relative
    to vout's RMS over the period (its mean for a DC output; the size of an AC one, whose mean is ~0; at least
    :func:`circuit_floor`):
    the run's distance to the method's own orbit (a transient not settled) plus the method's discretization
    error, Richardson's from the orbit at h and 2h (a stepper of declared order above 1: the order observed at h,
    2h and 4h, at least :data:`OBSERVED_FLOOR`, at most the declared one and :data:`ORDER_THROUGH_EVENTS` through a
    diode event inside a step; backward Euler: its order 1; the event method: none).
    Returns the estimate, its parts, the order Richardson took, the shortest interval between switchings in
    steps, and a warning when the estimate exceeds ``DEFAULT_RTOL``; with the run's ``power`` summary, also the
    efficiency's and the input power's estimates (:func:`_power_check`), and a warning when the efficiency's
    exceeds it."""
    T = model.period(p)
    out: dict[str, Any] = {"target": DEFAULT_RTOL}
    if method.error_kind is ErrorKind.MODEL:
        reason = _model_error(method)
        end = float(tr.t[-1])
        if end - float(tr.t[0]) < 20 * T * (1 - 1e-4):      # (ngspice starts its samples at ~5e-5 T)
            return {**out, "checked": False, "reason": reason}
        # what can be said: how far the mean moved from the 10 periods before (a transient it still carries)
        before = tr.mean("vout", t0=end - 20 * T, t1=end - 10 * T)
        transient = abs(reported - before) / max(abs(reported), circuit_floor(tr, "vout"))
        out.update(checked=False, reason=reason, transient=transient)
        if transient > DEFAULT_RTOL:
            out["warning"] = (f"vout mean may be {transient:.1e} off (more than {DEFAULT_RTOL:g}): the run has not "
                              f"settled (its 10-period mean moved {transient:.1e} from the 10 periods before): run "
                              "more --periods")
        return out
    runs = orbit_runs(model, p, method, tr)
    if isinstance(runs, str):
        return {**out, "checked": False, "reason": runs,
                "warning": f"vout mean's error could not be estimated: {runs}"}
    fine, coarse = runs.fine, runs.coarse
    period = last_period(model, p, tr)
    step = getattr(method, "h", None)
    floor = circuit_floor(tr, "vout")
    doubts, reference = second_resolution(model, p, method, tr, runs)
    exact_reference = reference if not isinstance(reference, str) else None
    if exact_reference is not None:
        m_h = fine.mean("vout", t0=0.0, t1=T)
        exact = exact_reference.mean("vout", t0=0.0, t1=T)
        scale = max(abs(exact), fine.rms("vout", t0=0.0, t1=T), floor)
        out["estimated_by"] = ("each value's distance from the exact (event) method's orbit, as Richardson at h and 2h "
                               "cannot be trusted here (" + "; ".join(cause for cause, _ in doubts) + ")")
    else:
        m_h, exact, scale = richardson_mean(fine, coarse, runs.factor, T, floor)
    transient = abs(reported - m_h) / scale
    discretization = abs(m_h - exact) / scale
    error = abs(reported - exact) / scale
    out.update(checked=True, vout_mean_error_estimate=error, transient=transient, discretization=discretization,
               **({"richardson_order": runs.order} if coarse is not None and exact_reference is None else {}),
               shortest_interval_steps=period["shortest_interval_T"] * T / step if step else None,
               **_power_check(model, p, runs, power, exact_reference))
    power_warning = _power_warning(out, method)
    if error > DEFAULT_RTOL:
        reasons = []
        if transient > 0.5 * error:
            reasons.append(f"the run has not settled ({transient:.1e} from the periodic orbit): use --steady")
        if discretization > 0.5 * error:
            few = out["shortest_interval_steps"]
            reasons.append("the step is too coarse" + (f" (the shortest interval spans {few:.0f} steps)"
                                                       if few is not None and few < FEW_STEPS else "")
                           + (": use --method event (exact flows), or a smaller --h" if exact_reference is not None
                              else ": use --rtol 1e-4 (or a smaller --h)"))
        out["warning"] = (f"vout mean may be {error:.1e} off (more than {DEFAULT_RTOL:g}): " + "; ".join(reasons))
    if power_warning:
        out["warning"] = f"{out['warning']}; {power_warning}" if "warning" in out else power_warning
    from .periodic import passive, stability_undecided, undecided_remedy
    undecided = (stability_undecided(*runs.multipliers) if runs.multipliers is not None and not passive(model, p)
                 else "")
    if undecided:
        # (a voltage-mode buck near its period doubling: the stepper's radius at T/200 is 0.06 off the exact one)
        out["trusted"] = False
        said = f"the orbit's {undecided[4:]}: {undecided_remedy(model, p)}"
        out["warning"] = f"{out['warning']}; {said}" if "warning" in out else said
    if exact_reference is None:
        for _, said in doubts:
            out["trusted"] = False
            if isinstance(reference, str):
                said = f"{said} (the exact method could not check it: {reference})"
            out["warning"] = f"{out['warning']}; {said}" if "warning" in out else said
    imbalance = _energy_check(model, p, method, fine, coarse, out)
    if imbalance:
        out["trusted"] = False
        out["warning"] = f"{out['warning']}; {imbalance}" if "warning" in out else imbalance
    if coarse is not None:
        other = exact_reference if exact_reference is not None else coarse
        against = "on the exact orbit" if exact_reference is not None else "2h"
        for check in (_measurement_check(fine, other, T, circuit_floor(tr), out, against=against),
                      _jump_loss_check(fine, other, T, out, against=against),
                      _mode_check(model, p, fine, other, out, against=against)):
            if check:
                out["warning"] = f"{out['warning']}; {check}" if "warning" in out else check
    edges = edge_terms(model, p, fine, T)
    if edges:           # the power PULSEs' edges run as steps: a part no second resolution sees (both run them so)
        estimates = out.setdefault("measurement_error_estimates", {})
        for name, term in edges.items():
            estimates[name] = max(float(estimates.get(name, 0.0)), term)
        out["edge_terms"] = edges
    share = edge_share(model, p, T)
    if share:           # a diode's turn-on or -off inside an edge moves by up to its width (a mode only the ramp has
        # is not among the labels: a ladder's all-off instant, 2e-3 T under its edges, which the steps skip)
        fractions = out.setdefault("mode_fraction_error_estimates", {})
        for label in last_period(model, p, fine)["mode_fractions"]:
            fractions[str(label)] = max(float(fractions.get(str(label), 0.0)), share)
    return out


def _power_edges(model: Model, p: dict) -> tuple[tuple[str, float, tuple[tuple[float, float], ...]], ...]:
    """The compiled circuit's power PULSEs' edges stepped at their middle ((source, period, ((middle, width), ...)),
    ...); () for a model without."""
    compiled = getattr(model, "compiled", None)
    return tuple(compiled(p).power_edges) if compiled is not None else ()


def edge_share(model: Model, p: dict, T: float) -> float:
    """The power PULSEs' edges' total width over a period ``T``, in units of it (0 for a circuit without them): how
    far the step at their middle can move a mode fraction."""
    return sum(width * max(round(T / per), 1) for _, per, pairs in _power_edges(model, p) for _, width in pairs) / T


def edge_terms(model: Model, p: dict, run: Trajectory, T: float) -> dict[str, float]:
    """{signal: the relative error in its rms (on ``run``'s period from 0) of running the power PULSEs' edges as steps
    at their middle}, for each signal that jumps there; {} for a circuit without them. A signal that jumps by J over
    an edge of width w (a source's own node, a current its feedthrough sets) has its mean square (J/2)^2 2w/3 lower
    under the ramp than under the step, J^2 w / 6 per edge (its mean's first-order change cancels): a stiff node's
    source read rms 5 V where its 1 us edges give 4.99667 V, stated 1e-14. The jump is read across the edge's rows
    (a stepper's next row a step later: its drift over the step counted too)."""
    edges = _power_edges(model, p)
    if not edges:
        return {}
    middles = [(middle + k * per, width) for _, per, pairs in edges for middle, width in pairs
               for k in range(max(int(round(T / per)), 1)) if middle + k * per < T]
    rows = run.rows_between(0.0, T)
    t = run.t[rows]
    at = []
    for middle, width in middles:
        j = int(np.searchsorted(t, middle - 1e-9 * T))
        if j + 1 < t.size and abs(t[j] - middle) <= 1e-9 * T:
            at.append((j, width))
    if not at:
        return {}
    measured = run.measurement_rows(t0=0.0, t1=T)
    out = {}
    for name, row in measured.items():
        if name == "switch":
            continue
        v = np.asarray(run.signal(name, rows), dtype=float)
        drop = sum((v[j + 1] - v[j]) ** 2 * width for j, width in at) / (6.0 * T)
        size = max(abs(float(row["max"])), abs(float(row["min"])), float(row["rms"]))
        square = max(float(row["rms"]), 1e-3 * size) ** 2
        if drop > 0.0 and square > 0.0:
            out[name] = drop / (2.0 * square)
    return out


def second_resolution(model: Model, p: dict, method: Method, tr: Trajectory,
                      runs: OrbitRuns) -> tuple[list[tuple[str, str]], Trajectory | str | None]:
    """Why Richardson at h and 2h cannot be trusted on a stepper's ``runs`` (:func:`orbit_runs` of ``tr``), each as
    (the cause, the warning with its remedy): a resonance the step damps or shifts, a conduction beginning inside the
    first step after a switching, a mode shorter than a step; and there the second resolution: one period of the
    exact method's orbit (:func:`_exact_reference`), or why there is none (None where nothing is in doubt). Found
    once per run and method: the accuracy check and the devices' losses' estimate read the same. (A buck's RC
    snubber rings at 1.6 MHz, Q 1,000, across a 10 ns step: Richardson stated 1.4e-13 for vout 7.0e-5 off.)"""
    cache: dict[int, Any] = tr.__dict__.setdefault("_second_resolution", {})
    if id(method) in cache:
        return cast("tuple[list[tuple[str, str]], Trajectory | str | None]", cache[id(method)][0])
    fine, coarse = runs.fine, runs.coarse
    doubts = [(_overdamped(model, p, method, remedy=False), _overdamped(model, p, method))]
    if coarse is not None:
        T, step = model.period(p), getattr(method, "h", None)
        onset = _unresolved_onset(model, p, fine, remedy=False)
        brief = _unresolved_mode(last_period(model, p, tr), tr, T, step, False)
        ramp = _unresolved_ramp(model, p, step)
        doubts += [(onset, onset + ONSET_REMEDY), (brief, brief + BRIEF_REMEDY), (ramp, ramp + RAMP_REMEDY)]
    doubts = [doubt for doubt in doubts if doubt[0]]
    reference = _exact_reference(model, p, fine) if doubts and coarse is not None else None
    cache[id(method)] = ((doubts, reference), method)            # the method kept: its id
    return doubts, reference


def exact_reference_of(tr: Trajectory) -> Trajectory | None:
    """The exact orbit a run's check took as its second resolution (:func:`second_resolution`), if it took one."""
    for (_, reference), _method in tr.__dict__.get("_second_resolution", {}).values():
        if reference is not None and not isinstance(reference, str):
            return cast("Trajectory", reference)
    return None


def _exact_reference(model: Model, p: dict, fine: Trajectory) -> Trajectory | str:
    """One period of the exact (event) method's orbit from 0, Newton from the stepper's orbit (``fine``) to 1e-8: the
    second resolution of a stepper's run whose own estimate cannot be trusted; or why there is none (the method
    does not take the circuit, a SIN source; or its orbit was not found within the limits)."""
    from ..methods import EventDriven
    from .periodic import exact_refusal
    refused = exact_refusal(model, p)
    if refused:
        return refused.split(": use ")[0]
    try:
        runs = _orbit_runs(model, p, EventDriven(), fine.x[0], observe=False)
    except (ParameterError, SimulationError, ResourceError) as failed:
        return str(failed).split("; ")[0]
    return runs if isinstance(runs, str) else runs.fine


def _mode_check(model: Model, p: dict, fine: Trajectory, coarse: Trajectory, out: dict, against: str = "2h") -> str:
    """The mode fractions of the orbit at h against 2h (read inside the step, :func:`last_period`): their
    differences, in units of the period, into ``out["mode_fraction_error_estimates"]``, and a warning where one is
    more than MEASUREMENT_RTOL of its fraction (at least of 1e-3 of the period). A stepper's fractions had carried no
    estimate: a DCM boost whose switch capacitance rings read D1 0.18398 where it is 0.17803 (+3.3 %), with no
    word. ``against``: what ``coarse`` is (``2h``, or ``the exact orbit``: its fractions then the exact ones)."""
    at_h, at_2h = (last_period(model, p, run)["mode_fractions"] for run in (fine, coarse))
    estimates = {str(label): abs(float(at_h.get(label, 0.0)) - float(at_2h.get(label, 0.0)))
                 for label in dict.fromkeys([*at_h, *at_2h])}
    out["mode_fraction_error_estimates"] = estimates
    off = {label: e for label, e in estimates.items()
           if e > MEASUREMENT_RTOL * max(float(at_h.get(label, 0.0)), 1e-3)}
    if not off:
        return ""
    named = sorted(off, key=lambda label: -off[label] / max(float(at_h.get(label, 0.0)), 1e-3))
    listed = ", ".join(f"{label} {float(at_h.get(label, 0.0)):.4g} +- {off[label]:.1e}" for label in named[:3])
    more = f" and {len(named) - 3} more" if len(named) > 3 else ""
    return (f"mode fractions may be off by more than {MEASUREMENT_RTOL:g} of themselves ({listed}{more}: in units of "
            f"the period, their difference at h and {against}): use --method event, a smaller --h, or --rtol")


def _jump_loss_check(fine: Trajectory, coarse: Trajectory, T: float, out: dict, against: str = "2h") -> str:
    """The jumps' loss (charge or flux redistributed) over the period on the orbit at h against 2h (its difference the
    estimate, relative to itself, into ``out["redistribution_error_estimate"]``); a warning past
    MEASUREMENT_RTOL. A flyback's leakage ringing undamped with its switch's 1 nF was caught by the switch at a
    voltage the step did not resolve: 0.04569 W where the exact orbit loses 0.13570 W."""
    count, loss = fine.jump_losses(t0=0.0, t1=T)
    if not count:
        return ""
    _, other = coarse.jump_losses(t0=0.0, t1=T)
    error = abs(loss - other) / max(abs(loss), abs(other), 1e-300)
    out["redistribution_error_estimate"] = error
    if error <= MEASUREMENT_RTOL:
        return ""
    return (f"the jumps' loss (charge or flux redistributed) may be {100 * error:.2g} % off (at h and {against}: "
            f"{loss / T:.4g} and {other / T:.4g} W): use --method event (exact at the jumps)")


def richardson_mean(fine: Trajectory, coarse: Trajectory | None, factor: float, T: float,
                    floor: float) -> tuple[float, float, float]:
    """vout's mean on the orbit at h, Richardson's extrapolation of it from the orbit at 2h (``factor`` =
    2^order - 1; the mean at h itself without one), and the scale its errors are relative to: vout's rms over the
    period, its mean for a DC output (to its ripple's square) and its size for an AC one, whose mean is ~0 (an
    inverter's load current: 6e-13 A, "2.2e-01 off" against it); at least ``floor``."""
    m_h = fine.mean("vout", t0=0.0, t1=T)
    exact = m_h if coarse is None else m_h + (m_h - coarse.mean("vout", t0=0.0, t1=T)) / factor
    return m_h, exact, max(abs(exact), fine.rms("vout", t0=0.0, t1=T), floor)


def mean_discretization(fine: Trajectory, coarse: Trajectory, factor: float, T: float, floor: float) -> float:
    """Richardson's estimate of vout's mean on the orbit at h (:func:`richardson_mean`), relative to its scale."""
    m_h, exact, scale = richardson_mean(fine, coarse, factor, T, floor)
    return abs(m_h - exact) / scale


def step_checks(model: Model, p: dict, fine: Trajectory, coarse: Trajectory, factor: float,
                signals: Iterable[str] | None = None, method: Method | None = None) -> list[str]:
    """What a stepper's orbit at h (``fine``, one period from 0) says against its orbit at 2h (``coarse``) that its
    numbers may miss, as reasons: vout's mean past DEFAULT_RTOL (:func:`mean_discretization`), a measurement of
    ``signals`` (default: every one) past MEASUREMENT_RTOL (:func:`_measurement_check`), a conduction beginning
    inside the first step after a switching (:func:`_unresolved_onset`); with the run's ``method``, also a resonance
    the step damps or shifts (:func:`_overdamped`) and a mode shorter than a step (:func:`_unresolved_mode`), which
    the difference at h and 2h cannot see (a sweep of a series resonant converter had stored its rows as ok, 9.9e-5
    off where h and 2h differ by 1e-6). The checks of a sweep's steady row; :func:`default_check` makes them with
    its own order and more (and takes the exact orbit where Richardson cannot be trusted)."""
    T = model.period(p)
    floor = circuit_floor(fine, "vout")
    reasons = []
    mean = mean_discretization(fine, coarse, factor, T, floor)
    if mean > DEFAULT_RTOL:
        reasons.append(f"vout mean may be {mean:.1e} off (more than {DEFAULT_RTOL:g})")
    spread = _measurement_check(fine, coarse, T, floor, {}, signals, remedy=False)
    if spread:
        reasons.append(spread)
    onset = _unresolved_onset(model, p, fine)
    if onset:
        reasons.append(onset)
    if method is not None:
        unseen = [_overdamped(model, p, method, remedy=False),
                  _unresolved_mode(last_period(model, p, fine), fine, T, getattr(method, "h", None), remedy=False)]
        reasons += [f"{cause}: the runs at h and 2h may both miss it by more than they differ" for cause in unseen
                    if cause]
    return reasons


#: The measures of each signal a run's summary prints (``measurements``), estimated by :func:`_measurement_check`.
MEASURES = ("mean", "rms", "min", "max", "ripple")
#: A mean or rms is judged against itself, down to this fraction of its signal's size: a diode's mean current in
#: a Cockcroft-Walton ladder, 3e-3 of its peak, had read 4.5 % high (the step after each source edge starting
#: from the new configuration's current) where its difference from 2h was 1.3e-4 of the peak; a capacitor's mean,
#: 0 on the orbit, is judged against this fraction of its size, not its rounding.
OWN_SCALE_FLOOR = 1e-3


def _measure_scale(measure: str, row: Mapping[str, Any], other: Mapping[str, Any], size: float,
                   own: bool = True) -> float:
    """What a measure's difference between h and 2h is relative to: a mean or rms its own magnitude (at least
    :data:`OWN_SCALE_FLOOR` of the signal's size; a mean with ``own`` False the size), an extremum or ripple the
    signal's size."""
    if measure == "rms" or (own and measure == "mean"):
        return max(abs(float(row[measure])), abs(float(other[measure])), OWN_SCALE_FLOOR * size)
    return size


#: The signals' estimates a warning names (the worst first).
NAMED = 3
#: The accuracy the defaults promise on every printed measurement of a signal (its peaks and ripple relative to the
#: signal's size, its mean and rms to themselves: :func:`_measure_scale`), or warn about: a sampled peak is a
#: step's slope off where a current jumps at a switching edge (the buck's diode current: 3.5e-3 at T/1000), which
#: the waveform shows as it is.
MEASUREMENT_RTOL = 1e-2


def _measurement_check(fine: Trajectory, coarse: Trajectory, T: float, floor: float, out: dict,
                       signals: Iterable[str] | None = None, remedy: bool = True,
                       window: tuple[float, float] | None = None, own: bool = True, against: str = "2h") -> str:
    """Each printed signal's mean, rms, min, max and ripple on the orbit at h against the orbit at 2h, relative to
    the signal's size (its largest magnitude or rms, at least ``floor``; a mean or rms to itself:
    :func:`_measure_scale`), into ``out["measurement_error_estimates"]``
    ({signal: its worst}); the difference itself is the estimate, as for a first-order error (a sampled peak's: a
    step that misses a current spike converges no faster). A warning names the worst beyond MEASUREMENT_RTOL: a
    rectifier charging its capacitor through 1 mohm had printed its diode's peak 4.4 % low and its rms 0.9 % low
    with no word, the mean's estimate (2.9e-6) speaking for everything. ``remedy``: the warning ends with what
    to do (a sweep's row states the reason only). ``window``: (t0, t1) of both runs (default: their period from 0,
    an orbit's); ``own``: a mean is judged against itself (:func:`_measure_scale`; not over two runs' windows that
    are no orbits, whose capacitors' mean currents, 0 on an orbit, are each run's drift); ``against``: what
    ``coarse`` is (``2h``, or ``the exact orbit``)."""
    t0, t1 = window if window is not None else (0.0, T)
    at_h, at_2h = (run.measurement_rows(t0=t0, t1=t1, names=signals) for run in (fine, coarse))
    worst: dict[str, tuple[float, str]] = {}
    for name, row in at_h.items():
        other = at_2h.get(name)
        if other is None or name == "switch":
            continue
        size = max(abs(float(row["max"])), abs(float(row["min"])), float(row["rms"]),
                   circuit_floor(fine, str(row["unit"])) if row["unit"] in ("V", "A") else floor)
        worst[name] = max((abs(float(row[m]) - float(other[m])) / _measure_scale(m, row, other, size, own), m)
                          for m in MEASURES)
    out["measurement_error_estimates"] = {name: value for name, (value, _) in worst.items()}
    beyond = sorted(((value, name, measure) for name, (value, measure) in worst.items() if value > MEASUREMENT_RTOL),
                    reverse=True)
    if not beyond:
        return ""
    named = ", ".join(f"{name} {measure} {value:.1e}" for value, name, measure in beyond[:NAMED])
    more = f" and {len(beyond) - NAMED} more" if len(beyond) > NAMED else ""
    relative = "a peak's or ripple's signal, to a mean or rms itself" if own else \
        "a peak's, mean's or ripple's signal, to an rms itself"
    what = (f"measurements may be off by more than {MEASUREMENT_RTOL:g} ({named}{more}: their values at h and "
            f"{against} differ by that, relative to {relative})")
    return what + (": use --method event, a smaller --h, or --rtol" if remedy else "")


#: The exact method's energy balance closes to rounding (1e-11 on the shipped netlists): past this it is a fault.
ENERGY_EXACT_RTOL = 1e-8
def _energy_check(model: Model, p: dict, method: Method, fine: Trajectory, coarse: Trajectory | None,
                  out: dict) -> str:
    """The orbit's energy balance over its period (:func:`energy_balance`) into ``out`` (``energy_residual``, and
    ``energy_residual_2h`` for a stepper), and why the values cannot be trusted where the exact flows do not close
    it beyond rounding. A stepper's residual is reported, not judged: it is the power's quadrature on the samples as
    much as the scheme's error, large where its states are right (a diode event inside a step: 2.8e-2 on the
    Cockcroft-Walton ladder at T/4000, 5.3e-2 at 2h, its vout within 3e-6; a time constant shorter than the step,
    whose pulse of current no sample sees: 0.83 on an RC of 100 ns stepped at 1 us by backward Euler, its 10 V
    exact). '' where it closes or the model has no stored energy to weigh."""
    T = model.period(p)
    balance = energy_balance(model, p, fine, 0.0, T)
    if balance is None:
        return ""
    residual = balance["residual"]
    out["energy_residual"] = residual
    if method.exact:
        # what rounding alone can leave, on the same scale: at no load it is most of the little the sources deliver
        out["energy_residual_floor"] = balance["rounding_J"] / max(abs(balance["absorbed_J"]),
                                                                   balance["delivered_J"], 1e-300)
    if coarse is not None:
        out["energy_residual_2h"] = energy_balance(model, p, coarse, 0.0, T)["residual"]
    if method.exact and residual > ENERGY_EXACT_RTOL and balance["residual_J"] > 2.0 * balance["rounding_J"]:
        return (f"the run's energy balance does not close ({residual:.1e} of the energy its sources deliver): "
                "the exact method's values are not to be trusted here")
    return ""


def energy_balance(model: Any,  # a Model, read by duck typing: a Circuit's stored_energy, storage_power, source_power
                   p: dict, tr: Trajectory, t0: float, t1: float) -> dict | None:
    """The run's energy balance over [t0, t1]: what its capacitors and inductors absorbed, sum of v i integrated by
    the run's own rule (:meth:`~converters.trajectory.Trajectory.integral`), less what its jumps lost, against the
    change of their stored energy 1/2 C v^2 + 1/2 i^T L i between the window's ends; relative to the energy the
    independent sources exchange (the integral of sum |v i|). The sources' energy equals the resistors' plus this
    absorbed energy at every instant (Tellegen), so a residual is energy the run creates or loses: zero to rounding
    on the exact flows. None where the model has no stored energy to weigh (a built-in converter, a batch's point).
    Returns {"residual": relative, "absorbed_J", "stored_J", "jumps_J" (lost at the state's jumps and impulses),
    "delivered_J", "residual_J" (absolute), "rounding_J" (what rounding the stored energies' differences leaves)}."""
    energy = getattr(model, "stored_energy", None)
    if energy is None:
        return None
    rows = tr.rows_between(t0, t1)
    first, last = int(rows[0]), int(rows[-1])
    e0, e1 = energy(tr.x[first], p), energy(tr.x[last], p)
    if e0 is None:
        return None
    absorbed = tr.integral(lambda samples: model.storage_power(samples, p), t0, t1)
    delivered = tr.integral(lambda samples: model.source_power(samples, p), t0, t1)
    segments = getattr(tr.exact, "_segments_in", None) if tr.rule == "exact" else None
    if segments is not None:
        # the exact flows: each segment's absorbed energy is its stored energy's change, and what the state's jumps
        # and Moreau's impulses between segments lose (a forward's primary handing its flux to the reset winding at
        # turn-off: the leakage's share, and the diode's impulse) is the rest
        smooth, previous, lost, size = 0.0, None, 0.0, 0.0
        for seg, a, b in segments(t0, t1):
            start = seg.xt0 if a == seg.t0 else seg.flow.advance(seg.xt0, a - seg.t0)
            end = seg.xt1 if b == seg.t1 else seg.flow.advance(seg.xt0, b - seg.t0)
            e_start, e_end = energy(start[:-1], p), energy(end[:-1], p)
            smooth += e_end - e_start
            size += (abs(e_start) + abs(e_end)) * (1.0 + (b - a) / seg.flow.delta)
            if previous is not None:
                lost += previous - e_start
            previous = e_end
        residual = absorbed - smooth
        # each segment's change is a difference of stored energies at states advanced by m steps of expm(delta Z),
        # each step's rounding a part in 1e16 of the state: up to 2 m eps of the stored energy, which at no load can
        # exceed what the sources deliver (a 6-stage ladder at 1e13 ohm: 1.5e-14 J a period delivered beside
        # 2.2e-3 J stored; a 4.9 us segment of 1,635 steps leaves 2.8e-16 J, bounded by 1.6e-15)
        return {"residual": abs(residual) / max(abs(absorbed), delivered, 1e-300), "absorbed_J": absorbed,
                "stored_J": e1 - e0, "jumps_J": lost, "delivered_J": delivered, "residual_J": abs(residual),
                "rounding_J": float(np.finfo(float).eps * size)}
    # a jump at a window's end counts where the run holds the state on both its sides there (the stepper's two
    # samples at the instant); the event method's run starts after the jump it enters with
    span = t1 - t0
    at = lambda t: int(np.sum(np.abs(tr.t[rows] - t) <= 1e-12 * span))          # noqa: E731
    jumps = sum(lost for t, lost in tr.jumps if t0 + 1e-12 * span < t < t1 - 1e-12 * span
                or (abs(t - t0) <= 1e-12 * span and at(t0) > 1) or (abs(t - t1) <= 1e-12 * span and at(t1) > 1))
    residual = absorbed - jumps - (e1 - e0)
    return {"residual": abs(residual) / max(abs(absorbed), delivered, 1e-300), "absorbed_J": absorbed,
            "stored_J": e1 - e0, "jumps_J": jumps, "delivered_J": delivered, "residual_J": abs(residual),
            "rounding_J": float(np.finfo(float).eps) * (abs(e0) + abs(e1))}


#: A pair counts as conducting where its u exceeds this fraction of the largest u at that sample, and as blocking
#: at a switching where its y exceeds this fraction of its scale (|C_i| |x| + |F_i|).
ONSET_RTOL = 1e-6


def _unresolved_mode(period: dict, tr: Trajectory, T: float, step: float | None, remedy: bool = True) -> str:
    """Why the stepper's estimate cannot be trusted where its orbit (``tr``'s last period, read by
    :func:`last_period`: ``modes_between_events``) holds a mode shorter than one step between two pair events: the step
    cannot resolve it, and the runs at h and 2h may both make it where the circuit has none (a series resonant
    converter's bridge commutating as its current reverses: "off" for 0.038 of a step at T/1000, T/2000 and T/4000
    alike; the estimate 6.5e-5, the exact orbit, which commutes directly, 6.0e-4 away; a parallel resonant one's
    D1+D2+D4). '' where every such mode spans a step, or both events fall inside one step (a bridge's pair of diodes
    starting together, their instants read 0.006 of a step apart: one event of the step's). ``remedy``: with what
    follows and what to do (else the cause alone)."""
    if not step:
        return ""

    def crosses_a_step(mode) -> bool:
        start, end = period["t0"] + mode[1][2] * T, period["t0"] + mode[2][2] * T
        return bool(np.any((tr.t > start) & (tr.t <= end + 1e-9 * step)))
    # (a mode of exactly one step, its events on the grid, is the step's own and scales with it: Richardson sees it)
    found = next((mode for mode in period.get("modes_between_events", ())
                  if mode[0] * T < (1.0 - 1e-6) * step and crosses_a_step(mode)), None)
    if found is None:
        return ""
    length, (pair_a, kind_a, _), (pair_b, kind_b, _) = found
    name = lambda pair, kind: "the comparator's switching" if pair == SWITCHING else f"{pair} {kind}"  # noqa: E731
    cause = (f"between {name(pair_a, kind_a)} and {name(pair_b, kind_b)} the orbit holds a mode for "
             f"{length * T / step:.2g} of a step ({length:.2g} T)")
    return cause + (BRIEF_REMEDY if remedy else "")


def _unresolved_ramp(model: Model, p: dict, step: float | None) -> str:
    """Why the stepper's estimate cannot be trusted where a power PULSE's edge, a ramp of the LCS, is shorter than a
    step while the circuit's fastest mode follows it (its time constant below ten times the edge): the runs at h and
    2h both cross the edge in one step, and what the mode carries along it is not resolved by either (100 ns edges
    into 10 ohm and 1 nF at a 1 us step: the resistor's peak 0.0909 A where the ramp drives 0.1 A, the estimate
    2.8e-4). Backward Euler's one step takes a mode of rate a through a ramp of width w quasi-statically, its current
    C s a w / (1 + a w) beside the flow's C s (1 - e^(-a w)): off by 1 / (1 + a w), below 1e-3 past RAMP_QUASI_STATIC
    (a 1 fs node behind 1 ns edges reads its 10 mA exactly). '' otherwise."""
    compiled = getattr(model, "compiled", None)
    ramps = compiled(p).ramped_edges if compiled is not None and step else ()
    short = [(title, max(tr, tf)) for title, tr, tf in ramps if min(tr, tf) < step]
    if not short:
        return ""
    rate = model.fastest_rate(p)
    title, edge = min(short, key=lambda item: item[1])
    if not RAMP_FOLLOWED < rate * edge <= RAMP_QUASI_STATIC:
        return ""
    return (f"{title}'s edges ({edge:.3g} s) are ramps shorter than the step ({step:.3g} s), which the circuit's "
            f"fastest mode ({1.0 / rate:.3g} s) follows")


#: A ramp shorter than a step is in doubt (:func:`_unresolved_ramp`) where the fastest mode's rate times the edge
#: exceeds this: the mode then follows the ramp within it, where a slower one takes it as a step.
RAMP_FOLLOWED = 0.1
#: ... and at most this: a faster mode is quasi-static along the ramp, which the step then reads to 1 / (1 + a w).
RAMP_QUASI_STATIC = 1e3
#: What follows from :func:`_unresolved_ramp`'s cause, and what to do.
RAMP_REMEDY = (": the runs at h and 2h both cross each edge in one step, so the estimate may be far too small; use "
               "--method event (exact on the ramps), or a --h below the edges")
#: What follows from :func:`_unresolved_mode`'s cause, and what to do.
BRIEF_REMEDY = (": the step cannot resolve it, and the runs at h and 2h may both make a mode the circuit does not "
                "have, so the estimate may be far too small; use --method event (exact at every event), or a --h that "
                "resolves it")
#: What follows from :func:`_unresolved_onset`'s cause, and what to do.
ONSET_REMEDY = (": the step at h and 2h both hide the instant, so the estimate may be far too small; use --method "
                "event (exact at the instant), or a --h that resolves it")


def _unresolved_onset(model: Model, p: dict, fine: Trajectory, remedy: bool = True) -> str:
    """Why the stepper's estimate cannot be trusted where a pair starts conducting inside the first step after a
    switching while it blocks at the switching itself in the configuration entered (a switch's Coss charging in
    6 ns at a turn-off inside a 10 ns step): the instant then lies inside the step at h and at 2h alike, its error
    is first order and Richardson at h and 2h does not see it (boost-coss.cir at theta 1: estimate 3.3e-6 where
    the event method's orbit is 2.9e-4 away). '' when every conduction begins at a switching or is located
    between samples the step resolves. ``remedy``: with what follows and what to do (else the cause alone)."""
    from ..lcp import solve_lcp                 # imported here: the solvers load numba, which most checks never need
    T = model.period(p)
    problem = model.problem(p, T)
    t, x = fine.t, fine.x
    # an LCS run's (its pairs and configurations are recorded)
    u, config = cast("tuple[npt.NDArray[np.float64], npt.NDArray[np.int_]]", (fine.u, fine.config))
    for edge in problem.switching.breakpoints(-1e-9 * T, T):
        j = int(np.searchsorted(t, edge + 1e-9 * T, side="right")) - 1      # the last sample at the edge (after a jump)
        if j < 0 or j + 1 >= t.size or abs(t[j] - edge) > 1e-9 * T:
            continue
        c = problem.configurations[int(config[j + 1])]
        before = u[j] > ONSET_RTOL * max(float(np.abs(u[j]).max()), 1e-300)
        after = u[j + 1] > ONSET_RTOL * max(float(np.abs(u[j + 1]).max()), 1e-300)
        starting = np.flatnonzero(after & ~before)
        if not starting.size:
            continue
        # the configuration's LCP at the instant (its u is a current or a voltage, pair by pair, as compiled)
        q = c.C @ x[j] + c.F
        at_edge = solve_lcp(c.D, q)
        if not at_edge.solved:
            continue
        w = c.D @ at_edge.z + q
        scale = np.abs(c.C) @ np.abs(x[j]) + np.abs(c.F) + np.abs(c.D) @ np.abs(at_edge.z)
        for i in starting:
            if at_edge.z[i] <= 0.0 and w[i] > ONSET_RTOL * scale[i]:
                cause = (f"{fine.pair_names[i]} starts conducting inside the first step after the switching at "
                         f"{edge / T:.4g} T (blocking there: y = {w[i]:.3g})")
                return cause + (ONSET_REMEDY if remedy else "")
    return ""


def _overdamped(model: Model, p: dict, method: Any, remedy: bool = True) -> str:  # (a Method; a theta's has h)
    """Why the estimate cannot be trusted where the step damps one of the circuit's resonances more than the
    circuit does (:func:`~converters.methods.theta.overdamped_resonance`): Richardson at h and 2h then compares two
    runs that both erase the ring, and agrees with itself ('' when no resonance is); with ``remedy``, what to do
    (a run that chose its own step, accuracy on request, takes the reason alone)."""
    theta = getattr(method, "theta", None)
    if theta is None or not hasattr(model, "problem"):
        return ""
    from ..methods.theta import overdamped_resonance, undamped_resonance
    configurations = model.problem(p, model.period(p)).configurations
    stated = "the values and their estimates may be off by more than stated"
    if theta <= 0.5:
        # the trapezoid adds no damping, but a resonance no resistance damps rings on, its frequency off by
        # (omega h)^2 / 12 at h and 2h alike (a series resonant converter's Lr with the 100 pF across its switches:
        # the estimate 1.1e-6, the exact method 9.9e-5 away)
        undamped = undamped_resonance(configurations)
        if undamped is None:
            return ""
        frequency, q = undamped
        shift = (2.0 * np.pi * frequency * method.h) ** 2 / 12.0
        # what the ring's phase has drifted by over a period, in radians: what the next switching meets (a DCM
        # boost's 10 uH with 2 nF across its switch, 1.1 MHz at 10 ns: a shift of 4.2e-4 but 0.03 rad a period, its
        # diode's fraction 1.6 % off with an estimate 5x short)
        phase = shift * 2.0 * np.pi * frequency * model.period(p)
        if max(shift, phase) <= DEFAULT_RTOL:           # (a Cuk's 5 kHz input loop at T/1000: 8e-9)
            return ""
        reason = (f"the circuit's {frequency:.3g} Hz resonance is undamped (no resistance in its loop), and the "
                  f"trapezoid (h = {method.h:.3g} s) shifts its ring's frequency by {shift:.1e} ((omega h)^2 / 12; "
                  f"{phase:.2g} rad a period) at h and 2h alike")
        return reason + (f": {stated} (a smaller --h shrinks that error, no estimate sees it); use --method event "
                         "(exact flows)" if remedy else "")
    found = overdamped_resonance(configurations, method.h, theta)
    if found is None:
        # a resonance no resistance damps (no decay of its own to compare with): the step's damping of it over a
        # period, -ln|r(i omega h)| T / h (a buck's 50 nH loop with 1 nF across its switch, 22.5 MHz at h = 1 ns and
        # theta 1: e^-10 a period; it rang 14 diode cycles a period, and the value was 2.6 % off without a warning)
        undamped = undamped_resonance(configurations)
        if undamped is None:
            return ""
        frequency = undamped[0]
        z = 2j * np.pi * frequency * method.h
        decay = -np.log(abs((1.0 + (1.0 - theta) * z) / (1.0 - theta * z))) * model.period(p) / method.h
        if not decay > DEFAULT_RTOL:
            return ""
        reason = (f"the circuit's {frequency:.3g} Hz resonance is undamped (no resistance in its loop), and the step "
                  f"damps it by e^-{decay:.3g} a period (theta {theta:g}, h = {method.h:.3g} s)")
        return reason + (f": {stated}; use --method event (exact flows)" if remedy else "")
    frequency, q, ratio = found
    reason = (f"the step damps the circuit's {frequency:.3g} Hz resonance (Q {q:.3g}) {ratio:.3g}x faster than the "
              f"circuit does (theta {theta:g}, h = {method.h:.3g} s)")
    return reason + (f": {stated}; use a smaller --h, or --theta 0.5 where every time constant is resolved"
                     if remedy else "")


#: The measures of a run's summary that :func:`window_check` estimates (those the summary has).
WINDOW_MEASURES = ("vout_mean", "switching_frequency_Hz", "lambda_mean")


def window_check(model: Model, p: dict, method: Method, tr: Trajectory, summary: dict, window: Sequence[float],
                 coarse: Trajectory | None = None) -> dict:
    """How far the measures of a run with no periodic orbit to compare with (a model without a fixed period, the
    sliding-mode boost; or a run with a load or input step) may be off, over the ``window`` (t0, t1) its summary
    read:

    - discretization: the same run at 2h, Richardson with order 1, |Q(h) - Q(2h)| (the state-switched stepper
      locates each switching by linear interpolation inside its step, first order in h, whatever the theta
      method's own order); the event method: none (exact flows);
    - transient: how far vout's mean over the window moved from the window of the same length before it (not
      estimated when the run is shorter than two windows or a step time lies in them);

    ``coarse``: that run at 2h (the caller's, from the same x0 over the same span; None for the event method).
    Each relative estimate is the sum of its parts; a warning names the larger part when one exceeds
    ``DEFAULT_RTOL``."""
    out: dict[str, Any] = {"target": DEFAULT_RTOL}
    if method.error_kind is ErrorKind.MODEL:
        return {**out, "checked": False, "reason": _model_error(method)}
    names = [name for name in WINDOW_MEASURES if isinstance(summary.get(name), float)]
    t0, t1 = (float(t) for t in window)
    if method.fixed_step and coarse is None:
        raise ValueError("window_check: the stepper's run needs its coarse twin at 2h")
    coarse_summary = model.summary(coarse, p) if coarse is not None else None
    a = 2.0 * t0 - t1
    steps = [t for t in model.step_times(p) if a < t < t1]
    transient = None
    if a >= tr.t[0] - 1e-12 * (t1 - t0) and not steps:
        transient = (abs(tr.mean("vout", t0=a, t1=t0) - summary["vout_mean"])
                     / max(abs(summary["vout_mean"]), circuit_floor(tr, "vout")))
    estimates = {}
    for name in names:
        value = summary[name]
        part = {"discretization": abs(value - coarse_summary[name]) / max(abs(value), circuit_floor(tr, "vout"))
                if coarse_summary else None}
        if name == "vout_mean":
            part["transient"] = transient
        known = [x for x in part.values() if x is not None]
        if known:       # the event method's switching frequency: exact flows, no transient measured: nothing to say
            estimates[name] = {**part, "error_estimate": sum(known)}
    out.update(checked=True, window_s=[t0, t1], estimates=estimates,
               how=("the same run at 2h" if coarse_summary else "exact flows") + "; vout's mean over the window before"
               + ("" if transient is not None else " (not estimated: the run is shorter than two windows or a step "
                  "lies in them)"))
    worst = max(estimates, key=lambda name: estimates[name]["error_estimate"]) if estimates else None
    if worst is not None and estimates[worst]["error_estimate"] > DEFAULT_RTOL:
        part = estimates[worst]
        why = ("the run has not settled: use a longer --t-end" if (part.get("transient") or 0.0) >
               (part["discretization"] or 0.0) else
               "the step is too coarse: use a smaller --h")
        modes = summary.get("mode_fractions") or {}
        if why.startswith("the run has not settled") and len(modes) == 1:
            from .periodic import ONE_MODE
            why += f" (its last period stays in one mode, {next(iter(modes))}: {ONE_MODE}; it may stay there)"
        out["warning"] = (f"{worst} may be {part['error_estimate']:.1e} off (relative; more than {DEFAULT_RTOL:g}): "
                          f"{why}")
    if coarse is not None:
        # every printed signal, as the orbit's check reads them (a current-mode loop's 1 ns snubbers under backward
        # Euler: their rms 29 % low with vout's mean right, and no word)
        spread = _measurement_check(tr, coarse, t1 - t0, circuit_floor(tr), out, window=(t0, t1), own=False)
        if spread:
            out["warning"] = f"{out['warning']}; {spread}" if "warning" in out else spread
        smeared = _smeared_pulses(model, p, method, t1)
        if smeared:
            out["trusted"] = False
            out["warning"] = f"{out['warning']}; {smeared}" if "warning" in out else smeared
    return out


def _smeared_pulses(model: Model, p: dict, method: Method, span: float) -> str:
    """'' or why a stepper's run under a state-driven law cannot say how far its pulses are off: a time constant
    shorter than the step carries each switching's charge in a pulse the step smears over itself, and the run at 2h
    smears it over steps whose crossings fall elsewhere, so their difference follows no power of h (a hysteretic
    buck's 1 ns snubber at 5 ns: its rms 2.5e-4 apart at h and 2h over one window, 30 % from the exact)."""
    from ..problems import Schedule
    step = getattr(method, "h", None)
    rate = getattr(model, "fastest_rate", None)
    if not step or rate is None or isinstance(model.problem(p, span).switching, Schedule):
        return ""
    fastest = float(rate(p))
    if not fastest * step > 1.0:
        return ""
    return (f"a time constant of {1.0 / fastest:.2g} s is shorter than the step ({step:.2g} s): the currents it "
            "carries at each switching are pulses the steps smear, which the run at 2h does not bound under a "
            "state-driven law (its crossings fall elsewhere in their steps): their rms and peaks are not resolved; "
            f"use --method event, or --h below {1.0 / fastest:.2g} s")


__all__ = ["accurate_steady", "AccurateSteady", "Estimate", "measures", "substep_events", "mode_fractions",
           "default_check", "last_period", "window_check", "DEFAULT_RTOL"]
