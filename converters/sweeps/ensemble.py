"""An ensemble of runs of one model over parameter points (DifferentialEquations.jl's EnsembleProblem): a
point -> the model's problem, a method, and the row of measures each run gives.

:class:`ModelSweep` is the whole description, plain and picklable: it travels to any backend (this process,
local processes, a Dask cluster) and gives the same rows everywhere. A row holds the point's index and
parameters, its status (``ok`` or ``failed``) and message, and the steady state's measures: the mean and
ripple of vout and the RMS of the first state over one period on the orbit, the conduction mode class
(CCM, DCM, GDCM-ON, ... from :mod:`converters.analysis.modes`; a netlist's sequence of conduction states,
'S1 > D1 > off') and the fraction of the period a pair is held (a netlist's: nothing conducts), the Floquet
spectral radius and the Newton iterations. A point that fails is a row with its message, never an exception.

``rows`` runs the points of a PWM converter on the LCP stepper (one complementarity pair) through
one compiled call (:mod:`converters.sweeps.batch`); any other model or method, and a point the batch
cannot take, goes through the per-point path :meth:`ModelSweep.row`. Both read their measures with
:func:`orbit_row` from the same one-period trajectory, so their rows agree to rounding.
"""
from __future__ import annotations

import math
import time
from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, cast

import numpy as np

from ..errors import ParameterError, SimulationError
from ..problems import Schedule

if TYPE_CHECKING:
    from ..methods.base import Method
    from ..methods.theta import Theta
    from ..models import Model
    from ..problems import LCSProblem
    from ..trajectory import Trajectory

#: Newton's tolerance on the orbit (relative, the engine's default). The last Newton step is taken too
#: (polished): on a fixed mode sequence the period map is affine and that step lands on the fixed point to
#: rounding, so every backend gives the same orbit to ~1e-14 whatever the tolerance.
STEADY_TOL = 1e-10
#: A point whose orbit Newton can resolve only to the rounding level of its map (1 - rho ~ 1e-5 amplifies it: a
#: lightly damped circuit, the SEPIC at 19 ohm stepped with theta 0.5 to 2.5e-10) is kept within this distance; its
#: orbit_distance says how close.
ROUNDED_TOL = 1e-8
MAX_ITER = 50
#: The measures of a row and their types (a failed row leaves them empty).
MEASURES = {"vout_mean": float, "vout_ripple": float, "rms_state0": float, "mode": str, "held_fraction": float,
            "spectral_radius": float, "iterations": int, "orbit_distance": float}
#: With an rtol: the largest relative error estimate of the point's measures, the mean's, the method and steps
#: per period chosen (0: the event method), and whether rtol was met.
ACCURACY_MEASURES = {"error_estimate": float, "vout_mean_error_estimate": float, "accuracy_method": str,
                     "steps_per_period": int, "rtol_met": bool}


def on_demand(metrics: Iterable[str]) -> list:
    """The metrics that are not a standard measure (nor an accuracy one): columns computed on demand."""
    return [m for m in metrics if m not in MEASURES and m not in ACCURACY_MEASURES]


#: A run from rest diverges when the largest magnitude of its state grows by more than this a period over its
#: last five periods without slowing (an exponential's constant ratio; a start-up's ratio falls period by period:
#: a time constant of 50 T still grows 1.2 % a period at 50 periods, but 6 % slower each time).
DIVERGING = 0.01


def unstable(spectral_radius: float) -> str:
    """Why a point whose orbit has this spectral radius has no steady state ('' when it is stable): the same
    judgement as ``simulate --steady``'s."""
    if spectral_radius < 1.0:
        return ""
    from ..analysis.periodic import ELSEWHERE
    return (f"unstable orbit (Floquet spectral radius {spectral_radius:.6g}): the circuit does not settle on it "
            f"({ELSEWHERE})")


def diverging(run: Trajectory, T: float) -> str:
    """Why a run from rest has no measures worth keeping ('' when none): a state that is not finite, or whose
    largest magnitude grows by more than :data:`DIVERGING` a period over the last five without slowing."""
    x = np.abs(np.asarray(run.x))
    if not np.isfinite(x).all():
        return "diverged: the state is no longer finite"
    end = run.t[-1]
    peaks = np.array([x[(run.t >= end - (k + 1) * T * (1 + 1e-9)) & (run.t <= end - k * T * (1 - 1e-9))].max(initial=0.0)
                      for k in range(5, -1, -1)])
    if (peaks[:-1] <= 0.0).any():
        return ""
    growth = peaks[1:] / peaks[:-1] - 1.0
    if growth.min() > DIVERGING and growth[-1] >= 0.99 * growth[0]:
        return (f"diverging: the state's largest magnitude grows {100 * growth[-1]:.3g} % a period (to "
                f"{peaks[-1]:.3g} at the end): no steady state")
    return ""


#: A row from rest whose mean may be further than this (relative) from the periodic steady state says so.
UNSETTLED = 1e-3
#: What a row from rest that has not settled says first (the command line counts them).
NOT_SETTLED = "not settled"


def unsettled(run: Trajectory, T: float) -> str:
    """Why a run from rest's last period is not the steady state's ('' where it is, to UNSETTLED): its mean of vout
    still moves, and the moves' decay over the last five periods, taken as geometric (ratio r a period), puts the
    steady state about move r / (1 - r) away (a DCM boost at 50 periods: 40.6 V stored as ok, 54.37 V its orbit's;
    this reads 0.26). A ring-down's means alternate: the moves are summed over two periods."""
    end = float(run.t[-1])
    periods = int(round((end - float(run.t[0])) / T))
    if periods < 6:
        # too few to read a decay from (a boost at 5 periods: 9.94 V stored as ok, its orbit 54.37 V)
        return (f"{NOT_SETTLED} as far as can be told: {periods} period{'s' if periods > 1 else ''} from rest are "
                "too few to measure how far the last is from the periodic steady state (6 at least): use --steady, "
                "or more --periods")
    means = np.array([run.mean("vout", t0=end - (k + 1) * T, t1=end - k * T) for k in range(5, -1, -1)])
    steps = np.diff(means)
    moves = np.abs(steps)
    scale = max(abs(means[-1]), run.rms("vout", t0=end - T, t1=end), 1e-300)
    first, last = moves[:2].sum(), moves[-2:].sum()
    if last <= 1e-12 * scale:
        return ""
    ratio = (last / first) ** (1.0 / 3.0) if first > 0.0 else math.inf
    if ratio >= 0.999:
        # moves that do not shrink are no transient to extrapolate (a period-doubled orbit's means alternate by a
        # constant step: "about 1.8e+01 from the periodic steady state (its moves decaying geometrically)" had
        # read, and --steady then refused the point's unstable period-1 orbit); moves of one sign are a transient
        # slower than five periods show (a buck into 10 mF still charging)
        if np.all(steps[:-1] * steps[1:] < 0.0):
            return (f"{NOT_SETTLED} after {periods} periods from rest: its mean of vout moved {moves[-1] / scale:.1e} "
                    "(relative) over the last period, alternating, and its moves do not decay (a period-doubled "
                    "orbit, or chaos?): see pcsuite bifurcation, or more --periods")
        return (f"{NOT_SETTLED} after {periods} periods from rest: its mean of vout still moves "
                f"{moves[-1] / scale:.1e} (relative) a period, one way, with no decay seen over the last five: use "
                "--steady, or more --periods")
    away = 0.5 * last * ratio / (1.0 - ratio) / scale
    if away <= UNSETTLED:
        return ""
    return (f"{NOT_SETTLED} after {periods} periods from rest: its mean of vout moved {moves[-1] / scale:.1e} "
            f"(relative) over the last period and is about {away:.1e} from the periodic steady state (its moves "
            "decaying geometrically): use --steady, or more --periods")


#: A circuit's size (state units, :func:`~converters.analysis.periodic.problem_size`) below which the batched engine's
#: absolute Newton tolerance (1e-10 of 1 + |x|) is coarser than 1e-7 of it: such points run alone.
SMALL_CIRCUIT = 1e-3
#: What a steady row whose step is too coarse for its mean says first (the command line counts them).
TOO_COARSE = "the step is too coarse"
#: The least difference of a row's spectral radius at h and 2h its message states (a strongly damped orbit's radius,
#: 1e-17 to 1e-9, at rounding: its relative difference says nothing of the step).
SPECTRAL_FLOOR = 1e-4


def step_error(model: Model, p: dict, method: Method, run: Trajectory, at_2h: Trajectory,
               multipliers: tuple[np.ndarray, np.ndarray] | None = None) -> str:
    """'' or the message of a stepper's steady row whose step is too coarse: its one-period run on the orbit at h
    against the one at 2h, by the checks a simulate run's warnings make
    (:func:`~converters.analysis.accuracy.step_checks`: vout's mean by Richardson against DEFAULT_RTOL, every
    measurement by its difference against MEASUREMENT_RTOL, a conduction beginning inside the first step after a
    switching). A buck at f_sw = 316 Hz (deep DCM, its inductor's current reset within a few steps) had been stored
    as ok at 8.214 V for 9.031 V, and at 100 Hz its ripple 41 % and its inductor's rms 80 % low. The spectral
    radius stored beside (of ``multipliers`` at h and 2h) is judged by their difference against MEASUREMENT_RTOL
    too: the voltage-mode buck's at T/200 had read 0.8829 where it is 0.8241, with no word."""
    from dataclasses import replace

    from ..analysis.accuracy import ORDER_THROUGH_EVENTS, step_checks
    fine, coarse = (replace(r, labels=model.labels(p)) for r in (run, at_2h))
    # the declared order, at most that through a diode event inside a step (no third orbit at 4h here)
    # the signals the row stores: vout (its mean and ripple) and the first state (its rms)
    reasons = step_checks(model, p, fine, coarse, 2.0 ** min(float(method.order), ORDER_THROUGH_EVENTS) - 1.0,
                          signals=("vout", model.state_names[0]), method=method)
    if multipliers is not None:
        from ..analysis.accuracy import MEASUREMENT_RTOL
        rho_h, rho_2h = (float(np.abs(m).max(initial=0.0)) for m in multipliers)
        # (a radius at rounding, 3e-17 at h and 1.7e-17 at 2h, decides nothing: a floor on the difference)
        if abs(rho_h - rho_2h) > max(MEASUREMENT_RTOL * rho_h, SPECTRAL_FLOOR):
            reasons.append(f"the spectral radius may be {abs(rho_h - rho_2h):.1e} off ({rho_h:.6g} at h, "
                           f"{rho_2h:.6g} at 2h)")
    return f"{TOO_COARSE}: " + "; ".join(reasons) + ": use --rtol, or a smaller --h" if reasons else ""


def _orbit_at_2h(model: Model, p: dict, method: Method, x_orbit: np.ndarray) -> tuple[Trajectory, np.ndarray] | str:
    """One period of the stepper's orbit at 2h, Newton from the orbit at h, and its Floquet multipliers; or why it
    was not found."""
    from ..analysis.periodic import resolved, shoot
    from ..simulate import simulate
    T = model.period(p)
    coarse = method.coarsened()
    orbit = shoot(model.problem(p, T, x_orbit), coarse, x_orbit, tol=STEADY_TOL, polish=True)
    if not resolved(orbit):
        return f"{TOO_COARSE} to tell: its orbit at 2h was not found ({orbit.message})"
    return simulate(model.problem(p, T, orbit.x0), coarse), orbit.multipliers


def failed_row(index: int, point: dict, message: str, wall_s: float = 0.0) -> dict:
    """The row of a point that gave no result: its parameters, status ``failed`` and the reason."""
    return {"index": int(index), **{k: _number(v) for k, v in point.items()}, "status": "failed",
            "message": message, "wall_s": wall_s}



def _refuse_steps(model: Model, params: dict) -> None:
    """A sweep's row is a periodic steady state or the last period of a run from rest: a load or input step
    would be ignored (each point's problem is the circuit before it), so it is refused."""
    given = [name for name in getattr(model, "STEP_PARAMETERS", ()) if name in params]
    if given:
        raise ParameterError(f"{', '.join(given)}: a sweep measures each point's steady state (or the last period "
                             "from rest), not a step response; simulate the step with pcsuite simulate -p t_step=.. "
                             "-p R_step=.. (or Vin_step)")
    steps = model.step_times(model.resolve(params))
    if steps:                           # a netlist's switch on a gate that does not repeat, or its ramp's corner
        raise ParameterError(f"{model.key} has a step at {steps[0]:.6g} s (a switch on a gate that does not repeat, "
                             "or a PWL source in the power circuit): a sweep measures each point's steady state (or the last period from rest), not a step "
                             "response; simulate the step with pcsuite simulate")

@dataclass(frozen=True)
class ModelSweep:
    """Rows of ``model`` (under ``control``) at parameter points: ``base`` parameters overlaid with each point's.

    ``method``: ``lcp`` (the stepper, h = T * ``h_fraction``, ``theta``) or ``event``; ``steady``: the method's
    periodic orbit (``warm_up`` periods from rest, then Newton) or, without it, ``periods`` periods from rest
    (the measures over the last one). A method that runs the circuit itself (``spice``) measures each point on its
    own run (:attr:`converters.methods.base.Method.sweep_measures`): ``periods`` periods from the LCP stepper's
    orbit (``steady``) or from rest."""

    model: str
    control: str = "pwm"
    base: dict = field(default_factory=dict)
    method: str = "lcp"
    h_fraction: float = 1.0 / 200.0
    #: None: each point's own default (0.5 where the step resolves every time constant, else 1), as simulate's.
    theta: float | None = None
    steady: bool = True
    warm_up: int = 20
    periods: int = 50
    rtol: float | None = None
    #: Measures on demand beside the standard ones (:mod:`.metrics`: SIGNAL.STAT, efficiency, losses.NAME, ...).
    metrics: tuple = ()
    #: Their units, found when the sweep is built (checking a power metric runs a period).
    metric_units: dict = field(default_factory=dict, init=False, repr=False, compare=False)

    @property
    def measures(self) -> dict:
        """The row's measures and their types; with ``rtol`` also each point's error estimates and the step
        chosen (accuracy on request); then the metrics asked for."""
        own = self._runs_circuit()
        if own is not None:
            return dict(own)
        standard = {**MEASURES, **ACCURACY_MEASURES} if self.rtol is not None else MEASURES
        return {**standard, **{name: float for name in self.metrics if name not in standard}}

    @property
    def units(self) -> dict:
        """Each measure's unit ('' where it has none: a mode, a count)."""
        model = self._model()
        state = model.state_names[0] if getattr(model, "state_names", None) else ""
        from ..trajectory import signal_unit
        out = {**{q.name: q.unit for q in model.parameters}, "vout_mean": "V", "vout_ripple": "V", "rms_state0": signal_unit({}, state), "held_fraction": "1",
               "spectral_radius": "1", "orbit_distance": "1", "error_estimate": "1", "vout_mean_error_estimate": "1",
               "settle": "1"}
        return {**out, **self.metric_units}

    def __post_init__(self) -> None:
        from ..models import get_model
        model = get_model(self.model, self.control)
        _refuse_steps(model, self.base)
        p = model.resolve(self.base)
        if self.steady and not np.isfinite(model.problem(p, 1.0).period):
            raise ParameterError(f"steady: {model.key} switches on its state, with no forcing period to shoot over; "
                                 "sweep it without --steady (periods from rest, measured over the last one)")
        if self.method not in sweep_methods():
            raise ParameterError(f"method must be {' or '.join(sweep_methods())} for a sweep; got {self.method!r}")
        if self._runs_circuit() is not None:
            if self.rtol is not None or self.metrics:
                raise ParameterError(f"method {self.method} runs the circuit itself: its sweep measures "
                                     f"{', '.join(self.measures)}; rtol and metrics on demand are the LCS methods'")
            self._circuit_method().sweep_check(model, p, self.steady, self.periods)
            return
        from ..analysis.periodic import MAX_WARM_UP
        from ..validate import check_flag, check_integer, check_range
        check_flag("steady", self.steady)
        check_integer("warm_up", self.warm_up, 0, MAX_WARM_UP)
        check_integer("periods", self.periods, 1, MAX_WARM_UP)
        if self.theta is not None:
            check_range("theta", self.theta, 0.5, 1.0)
        if not (isinstance(self.h_fraction, (float, int)) and not isinstance(self.h_fraction, bool)
                and 0.0 < self.h_fraction < 1.0):
            raise ParameterError(f"h_fraction (h / T) must be in (0, 1); got {self.h_fraction!r}")
        if self.rtol is not None:
            from ..analysis.accuracy import RTOL_RANGE
            if not self.steady:
                raise ParameterError("rtol: accuracy on request gives the periodic steady state; add steady (--steady)")
            if not (isinstance(self.rtol, float) and RTOL_RANGE[0] <= self.rtol <= RTOL_RANGE[1]):
                raise ParameterError(f"rtol must be in [{RTOL_RANGE[0]:g}, {RTOL_RANGE[1]:g}]; got {self.rtol!r}")
        if not isinstance(self.metrics, tuple):
            raise ParameterError(f"metrics must be a tuple of names; got {self.metrics!r}")
        from .metrics import check_metrics
        object.__setattr__(self, "metric_units", check_metrics(model, p, on_demand(self.metrics)))

    # --- one point ----------------------------------------------------------------------------------------

    def validate(self, point: dict) -> None:
        """Refuse a point outside the model's parameter ranges (ParameterError naming the parameter)."""
        model = self._model()
        _refuse_steps(model, point)
        model.resolve({**self.base, **point})

    def _model(self) -> Model:
        from ..models import get_model
        return get_model(self.model, self.control)

    def _runs_circuit(self) -> dict[str, type] | None:
        """The measures of a method that runs the circuit itself, or None for a method on the LCS."""
        from ..methods.base import get_method
        return get_method(self.method).sweep_measures

    def _circuit_method(self) -> Method:
        from ..methods.base import get_method
        return get_method(self.method)()

    def _method(self, model: Model, p: dict, problem: LCSProblem) -> Method:
        """A ``step`` method at h = T h_fraction (with ``theta`` where it takes one: the sweep's, else the point's
        default from ``problem``'s configurations), an exact one sampled at T/1000."""
        from ..methods.base import get_method
        from ..methods.theta import default_theta
        cls = get_method(self.method)
        T = model.period(p)
        step = T * self.h_fraction if cls.fixed_step else T / 1000
        options = {}
        if "theta" in cls.option_names():
            options["theta"] = self.theta if self.theta is not None else default_theta(problem.configurations, step)
        return cls.from_options(step=step, **options)

    def row(self, index: int, point: dict) -> dict:
        """The row of one point, by the per-point path (failures as rows)."""
        from ..analysis.periodic import ROUNDING_LIMITED, passive, shoot, stability_undecided
        from ..simulate import simulate
        clock = time.perf_counter()
        out = {"index": int(index), **{k: _number(v) for k, v in point.items()}}
        try:
            model = self._model()
            p = model.resolve({**self.base, **point})
            if self._runs_circuit() is not None:
                try:
                    measured = self._circuit_method().sweep_row(model, p, self.steady, self.periods)
                except (ValueError, RuntimeError, ArithmeticError) as exc:    # the first line of ngspice's story
                    first = str(exc).splitlines()[0] if str(exc) else ""
                    return failed_row(index, point, f"{type(exc).__name__}: {first[:300]}", time.perf_counter() - clock)
                return {**out, "status": "ok", "message": "", **measured, "wall_s": time.perf_counter() - clock}
            if self.rtol is not None:
                row = self._accurate_row(model, p)
                if unstable(row["spectral_radius"]):
                    return failed_row(index, point, unstable(row["spectral_radius"]), time.perf_counter() - clock)
                return {**out, "status": "ok", "message": "", **row, "wall_s": time.perf_counter() - clock}
            T = model.period(p)
            problem = model.problem(p, T)
            method = self._method(model, p, problem)
            if self.steady:
                orbit = shoot(problem, method, problem.x0, warm_up=self.warm_up, tol=STEADY_TOL, max_iter=MAX_ITER,
                              polish=True)
                if not orbit.converged and not (orbit.message.startswith(ROUNDING_LIMITED) and
                                                orbit.distance <= ROUNDED_TOL):
                    return failed_row(index, point, f"no steady state: {orbit.message}", time.perf_counter() - clock)
                at_2h = _orbit_at_2h(model, p, method, orbit.x0) if method.fixed_step else None
                if isinstance(at_2h, tuple) and not passive(model, p) and stability_undecided(orbit.multipliers,
                                                                                               at_2h[1]):
                    return self._exact_row(index, point, stability_undecided(orbit.multipliers, at_2h[1]))
                if unstable(orbit.spectral_radius):
                    return failed_row(index, point, unstable(orbit.spectral_radius), time.perf_counter() - clock)
                if orbit.warning:          # an orbit the transient was not seen to reach (simulate warns of it)
                    return failed_row(index, point, f"no trusted steady state: {orbit.warning}",
                                      time.perf_counter() - clock)
                run = simulate(model.problem(p, T, orbit.x0), method)
                extra = {"spectral_radius": orbit.spectral_radius, "iterations": orbit.iterations,
                         "orbit_distance": orbit.distance}
                if at_2h is not None:
                    extra["message"] = at_2h if isinstance(at_2h, str) else step_error(
                        model, p, method, run, at_2h[0], (orbit.multipliers, at_2h[1]))
            else:
                long = simulate(model.problem(p, self.periods * T), method)
                if diverging(long, T):
                    return failed_row(index, point, diverging(long, T), time.perf_counter() - clock)
                run = simulate(model.problem(p, T, long.x[-1]), method)
                from dataclasses import replace
                extra = {"message": unsettled(replace(long, labels=model.labels(p)), T)}
            return {**out, "status": "ok", "message": "", **orbit_row(model, p, run, self.metrics), **extra,
                    "wall_s": time.perf_counter() - clock}
        except (ValueError, RuntimeError, ArithmeticError) as exc:
            return failed_row(index, point, f"{type(exc).__name__}: {exc}", time.perf_counter() - clock)

    def _exact_row(self, index: int, point: dict, why: str) -> dict:
        """The row of a point whose stability the stepper leaves undecided (``why``), by the exact method where it
        takes the circuit (its message says so), else failed with the reason."""
        from dataclasses import replace

        from ..analysis.periodic import exact_refusal
        model = self._model()
        refused = exact_refusal(model, model.resolve({**self.base, **point}))
        if refused:
            return failed_row(index, point, f"{why}; the exact method does not take the circuit ({refused}): use a "
                                            "smaller --h")
        row = replace(self, method="event", theta=None).row(index, point)
        said = f"{why}: decided by the exact method"
        row["message"] = f"{row['message']}; {said}" if row.get("message") else said
        return row

    def nominal_error(self, metrics: Iterable[str]) -> dict:
        """How accurate each of ``metrics`` is, read at the nominal point (the base parameters): {metric: (absolute
        error estimate, how)}. The stepper: |Q(h) - Q(h/2)| (a first-order bound on the error at h, whatever its
        order); accuracy on request: rtol of the value; the event method: 0 (exact flows). Empty where the nominal
        point does not give a row."""
        from ..methods.base import get_method
        at_h = self.row(0, {})
        if at_h["status"] != "ok":
            return {}
        numeric = [m for m in metrics if isinstance(at_h.get(m), float)]
        if self.rtol is not None:
            return {m: (abs(at_h[m]) * self.rtol, f"accuracy on request (rtol {self.rtol:g})") for m in numeric}
        if self._runs_circuit() is not None:         # its error is its devices': no estimate to state
            return {}
        if not get_method(self.method).fixed_step:
            return {m: (0.0, f"{self.method}: exact flows") for m in numeric}
        from dataclasses import replace
        at_half = replace(self, h_fraction=self.h_fraction / 2).row(0, {})
        if at_half["status"] != "ok":
            return {}
        return {m: (abs(at_h[m] - at_half[m]), f"the nominal point at h = T/{1 / self.h_fraction:.4g} against "
                    f"h/2") for m in numeric if isinstance(at_half.get(m), float)}

    def _accurate_row(self, model: Model, p: dict) -> dict:
        """The measures of :func:`converters.analysis.accuracy.accurate_steady` (values its, mode and held
        fraction from its one-period orbit) with the worst and the mean's relative error estimates."""
        from ..analysis.accuracy import accurate_steady
        result = accurate_steady(model, p, self.rtol)
        q = result.quantities
        row = orbit_row(model, p, result.trajectory, self.metrics)
        # the first state's RMS is an estimated measure where that state is an inductor's current; a capacitor's
        # (a netlist's first state may be one) is the orbit's, read by the run's own rule
        rms = q.get(f"{model.state_names[0]}_rms")
        row.update(vout_mean=q["vout_mean"].value, vout_ripple=q["vout_ripple"].value,
                   rms_state0=row["rms_state0"] if rms is None else rms.value,
                   spectral_radius=float(np.abs(result.orbit.multipliers).max()), iterations=int(result.orbit.iterations),
                   orbit_distance=float(result.orbit.distance),
                   error_estimate=result.worst(), vout_mean_error_estimate=q["vout_mean"].relative,
                   accuracy_method=result.method.key, steps_per_period=int(result.steps_per_period or 0),
                   rtol_met=bool(result.met))
        return row

    # --- many points at once ----------------------------------------------------------------------------------

    @property
    def chunk_hint(self) -> int:
        """Points per chunk: enough that a chunk of cheap points outweighs its round trip to a worker."""
        from ..methods.base import get_method
        if self._runs_circuit() is not None:
            return 2                  # a run is seconds: small chunks spread them over the workers
        stepped = get_method(self.method).fixed_step
        return 500 if self.batchable() else (100 if stepped and self.rtol is None else 10)

    def failed(self, index: int, point: dict, message: str) -> dict:
        return failed_row(index, point, message)

    def batchable(self) -> bool:
        from ..models import Converter
        model = self._model()
        from ..methods.base import get_method
        return (get_method(self.method).batches and self.steady and self.rtol is None and isinstance(model, Converter)
                and len(model.pair_names) == 1)

    def rows(self, items: list[tuple[int, dict]]) -> list[dict]:
        """Rows of (index, point) items: one compiled call for every point the batch can take (module docstring),
        the per-point path for the rest. Rows in the order of ``items``."""
        if self._runs_circuit() is not None:
            try:
                return [self.row(i, point) for i, point in items]
            finally:
                self._circuit_method().sweep_chunk_done()
        if not self.batchable():
            return [self.row(i, point) for i, point in items]
        from ..analysis.periodic import problem_size
        from ..methods.theta import plan_arrays
        model = self._model()
        prepared, rows, plans, resolved = [], {}, {}, {}
        clock = time.perf_counter()
        for index, point in items:
            try:
                resolved[index] = model.resolve({**self.base, **point})
            except (ValueError, RuntimeError, ArithmeticError) as exc:
                rows[index] = failed_row(index, point, f"{type(exc).__name__}: {exc}")
        model.prepare(list(resolved.values()))        # a netlist's points compiled together
        shared = (time.perf_counter() - clock) / max(len(items), 1)
        for index, point in items:
            if index in rows:
                continue
            clock = time.perf_counter() - shared
            try:
                p = resolved[index]
                problem = model.problem(p, model.period(p))
                # the batched steps take no jump, and their plan is a schedule's (a comparator's switching is the
                # state's, its law no key of a shared plan: a voltage-mode sweep had failed every point with
                # "unhashable type"): the point's own run does
                # and its Newton measures distances against 1 + |x|: a circuit far below 1 (a buck from 1.2e-11 V,
                # stored 8 % off in 0 iterations) is resolved by the point's own shoot(), relative to its size
                alone = not isinstance(problem.switching, Schedule) or problem_size(problem) < SMALL_CIRCUIT
                if problem.jumps or alone:
                    rows[index] = self.row(index, point)
                    continue
                method = cast("Theta", self._method(model, p, problem))        # batchable: the stepper
                # the grid and matrix sets follow from the schedule and the step alone: points that vary only
                # the circuit's values (a tolerance study) share them
                key = (problem.switching, problem.t_span, method, len(problem.configurations))
                plan = plans.get(key) or plans.setdefault(key, plan_arrays(problem, method.h, method.graded))
                prepared.append((index, point, p, method, problem, plan, time.perf_counter() - clock))
            except (ValueError, RuntimeError, ArithmeticError) as exc:
                rows[index] = failed_row(index, point, f"{type(exc).__name__}: {exc}", time.perf_counter() - clock)
        for theta in sorted({item[3].theta for item in prepared}):       # one compiled call per theta
            self._batched(model, [item for item in prepared if item[3].theta == theta], rows)
        return [rows[index] for index, _ in items]

    def _batched(self, model: Model, prepared: list, rows: dict) -> None:
        """The rows of prepared points of one theta through one compiled call (:func:`.batch.batch_steady`), and
        each converged row checked against its orbit at 2h through a second one (:func:`step_error`)."""
        from ..analysis.periodic import REMOTE_PERIODS, passive, periods_apart, stability_undecided
        from ..methods.theta import plan_arrays
        from .batch import CONVERGED, ROUNDING
        clock = time.perf_counter()
        found = _batch_orbits(prepared, self.warm_up)
        share = (time.perf_counter() - clock) / len(prepared)          # the compiled call's time, per point
        near: list[tuple] = []          # the converged points (their rows, or None where unstable) for the 2h pass
        for item, (status, x_star, run, rho, iterations, residual, distance, multipliers) in zip(prepared, found):
            index, point, p, method, problem, plan, prep = item
            clock = time.perf_counter() - prep - share
            if status == ROUNDING and distance <= ROUNDED_TOL:     # kept: the per-point path's orbit
                rows[index] = self.row(index, point)
                continue
            if status != CONVERGED:
                rows[index] = failed_row(index, point, _batch_failure(status, residual, distance),
                                         time.perf_counter() - clock)
                continue
            if unstable(rho):
                rows[index] = failed_row(index, point, unstable(rho), time.perf_counter() - clock)
                near.append((index, point, p, method, problem, x_star, None, multipliers))  # unless 2h leaves it open
                continue
            if periods_apart(x_star, rho, problem.x0, STEADY_TOL) > REMOTE_PERIODS:
                # an orbit its slowest mode would take so long to reach from the start: the point's own shoot()
                # checks it against the settled transient (from problem.x0, before the warm-up: a few more points
                # than shoot's own test, none fewer)
                rows[index] = self.row(index, point)
                continue
            try:
                measured = orbit_row(model, p, run, self.metrics)
            except SimulationError as exc:
                rows[index] = failed_row(index, point, f"{type(exc).__name__}: {exc}", time.perf_counter() - clock)
                continue
            rows[index] = {"index": int(index), **{key: _number(v) for key, v in point.items()}, "status": "ok",
                           "message": "", **measured, "spectral_radius": rho, "iterations": int(iterations),
                           "orbit_distance": float(distance), "wall_s": time.perf_counter() - clock}
            near.append((index, point, p, method, problem, x_star, run, multipliers))
        # the same points at 2h, from their orbits at h (a second compiled call: the check costs what the rows did)
        coarse, plans = [], {}
        for index, point, p, method, problem, x_star, run, rho in near:
            twice = method.coarsened()
            moved = model.problem(p, model.period(p), x_star)
            key = (moved.switching, moved.t_span, twice, len(moved.configurations))
            plan = plans.get(key) or plans.setdefault(key, plan_arrays(moved, twice.h, twice.graded))
            coarse.append((index, None, p, twice, moved, plan, 0.0))
        lossy = passive(model, prepared[0][2])        # (the points differ in values only: one structure, one law)
        for (index, point, p, method, problem, x_star, run, mu), (status, _, at_2h, _, *rest) in zip(
                near, _batch_orbits(coarse, 0) if coarse else []):
            clock = time.perf_counter()
            # a spectral radius whose distance from 1 the step's own error may cross: the exact method decides (a
            # voltage-mode buck just past its period doubling, exact -1.0139, read 0.97 to 0.99 at T/200: stored as
            # stable; just before it, as unstable)
            undecided = stability_undecided(mu, rest[-1]) if status == CONVERGED and not lossy else ""
            if undecided:
                rows[index] = self._exact_row(index, point, undecided)
                continue
            if run is None:                                # unstable at h and 2h alike: its failed row stands
                continue
            try:
                rows[index]["message"] = (step_error(model, p, method, run, at_2h, (mu, rest[-1]))
                                          if status == CONVERGED else
                                          f"{TOO_COARSE} to tell: its orbit at 2h was not found")
            except (ValueError, RuntimeError, ArithmeticError) as exc:
                rows[index]["message"] = f"{TOO_COARSE} to tell: {type(exc).__name__}: {exc}"
            rows[index]["wall_s"] += time.perf_counter() - clock


def _batch_orbits(prepared: list, warm_up: int) -> list[tuple]:
    """One compiled call (:func:`.batch.batch_steady`) for prepared points of one theta: per point (status, x*,
    its one-period run, spectral radius, iterations, residual, distance, Floquet multipliers)."""
    from .batch import batch_steady
    P = len(prepared)
    n = prepared[0][4].n
    configs = len(prepared[0][4].configurations)
    S = max(len(item[5].which) for item in prepared)
    sets = max(len(item[5].set_configs) for item in prepared)
    A, B = np.zeros((P, configs, n, n)), np.zeros((P, configs, n, 1))
    C, D = np.zeros((P, configs, 1, n)), np.zeros((P, configs, 1, 1))
    E, F = np.zeros((P, configs, n)), np.zeros((P, configs, 1))
    set_configs, set_dts = np.zeros((P, sets), dtype=np.int64), np.ones((P, sets))
    counts, which, steps = np.zeros(P, dtype=np.int64), np.zeros((P, S), dtype=np.int64), np.zeros(P, dtype=np.int64)
    x0 = np.zeros((P, n))
    for k, (_, _, _, _, problem, plan, _) in enumerate(prepared):
        for c, cfg in enumerate(problem.configurations):
            A[k, c], B[k, c], C[k, c], D[k, c], E[k, c], F[k, c] = cfg.A, cfg.B, cfg.C, cfg.D, cfg.E, cfg.F
        counts[k] = len(plan.set_configs)
        set_configs[k, :counts[k]], set_dts[k, :counts[k]] = plan.set_configs, plan.set_dts
        steps[k] = len(plan.which)
        which[k, :steps[k]] = plan.which
        x0[k] = problem.x0
    xs, us, ys = np.zeros((P, S + 1, n)), np.zeros((P, S + 1)), np.zeros((P, S + 1))
    x_star, jac = np.zeros((P, n)), np.zeros((P, n, n))
    status, iterations = np.zeros(P, dtype=np.int64), np.zeros(P, dtype=np.int64)
    residuals, distances = np.full(P, np.inf), np.full(P, np.inf)
    batch_steady(A, B, C, D, E, F, set_configs, set_dts, counts, which, steps, prepared[0][3].theta, x0, warm_up,
                 STEADY_TOL, MAX_ITER, xs, us, ys, x_star, jac, status, iterations, residuals, distances)
    out = []
    for k, (_, _, _, method, problem, plan, _) in enumerate(prepared):
        count = steps[k] + 1
        config = np.concatenate([plan.step_config[:1], plan.step_config])
        run = _stepper_trajectory(problem, method, plan.t, xs[k, :count], us[k, :count, None], ys[k, :count, None],
                                  config)
        multipliers = np.linalg.eigvals(jac[k]) if np.all(np.isfinite(jac[k])) else np.full(n, np.inf + 0j)
        rho = float(np.abs(multipliers).max())
        out.append((int(status[k]), x_star[k].copy(), run, rho, int(iterations[k]), float(residuals[k]),
                    float(distances[k]), multipliers))
    return out


def sweep_methods() -> list[str]:
    """The methods a sweep takes: a converter's, with an error a step twin or exact flows can state."""
    from ..methods.base import METHODS, load_methods
    load_methods()
    return [key for key, cls in METHODS.items()
            if ("lcs" in cls.domains and (cls.fixed_step or cls.exact)) or cls.sweep_measures is not None]


def _batch_failure(code: int, residual: float, distance: float) -> str:
    from . import batch as tb
    why = {tb.NO_SOLUTION: "a step LCP has no solution (a held pair with M <= 0)",
           tb.SINGULAR: "the period map's Jacobian has a multiplier at 1 (the orbit is not isolated)",
           tb.NONFINITE: "the period map left the finite numbers",
           tb.ROUNDING: "the residual is at the rounding level of the map and 1 - rho amplifies it",
           tb.NOT_CONVERGED: f"no convergence in {MAX_ITER} Newton iterations"}[int(code)]
    return (f"no steady state: {why}; residual {residual:.3g}, estimated distance {distance:.3g} > tol "
            f"{STEADY_TOL:.3g}")


def _stepper_trajectory(problem: LCSProblem, method: Theta, t: np.ndarray, x: np.ndarray, u: np.ndarray,
                        y: np.ndarray, config: np.ndarray) -> Trajectory:
    from ..trajectory import Trajectory
    return Trajectory(t=t, x=x, u=u, y=y, config=config, state_names=problem.state_names, pair_names=problem.pair_names,
                      method=method.key, algorithm=method, steps=t.size - 1, rule="end" if method.theta == 1.0 else "linear",
                      period=problem.period)


def orbit_row(model: Model, p: dict, run: Trajectory, metrics: tuple = ()) -> dict:
    """The measures of a one-period run on the orbit (the module docstring), through the model's labels, and the
    metrics asked for (:mod:`.metrics`)."""
    from dataclasses import replace

    from ..analysis.modes import orbit_intervals, period_modes
    from .metrics import metric_value
    run = replace(run, labels=model.labels(p))
    t0, t1 = run.t[0], run.t[-1]
    # a netlist's output the circuit leaves floating has no value to store (simulate warns of it, compare refuses it)
    circuit = cast(Any, model)                # a Circuit's: built-in converters' outputs are states
    shares = (circuit.floating_shares(run, p, ["vout"], float(t0), float(t1)) if hasattr(model, "floating_shares")
              else {})
    if shares:
        raise SimulationError(f"no value to measure: {circuit.floating_text(p, shares)}")
    mode, held = period_modes(model, orbit_intervals(run))
    row = {"vout_mean": float(run.mean("vout", t0=t0, t1=t1)), "vout_ripple": float(run.ripple("vout", t0=t0, t1=t1)),
           "rms_state0": float(run.rms(run.state_names[0], t0=t0, t1=t1)), "mode": mode, "held_fraction": held}
    return {**row, **{name: metric_value(model, p, run, name) for name in metrics if name not in row}}


def _number(value: Any) -> Any:
    try:
        return float(value)
    except (TypeError, ValueError):
        return value


__all__ = ["ModelSweep", "orbit_row", "failed_row", "on_demand", "MEASURES", "STEADY_TOL"]
