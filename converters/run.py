"""Run a model: parameters in, a labelled Trajectory out (what ``pcsuite simulate`` and scenes call).

A run passes through its stages once, top down in :func:`run_converter`:

1. resolve: the model and its parameters (:func:`_resolved`); accuracy on request (``rtol``) leaves here for
   :func:`converters.analysis.accuracy.accurate_steady`, which chooses the method and its step;
2. the method, from command-line style options (:func:`make_method`); a method that runs the circuit itself
   (ngspice) takes the run from here;
3. the span (:func:`_span`): the duration from rest, or the periods returned on the orbit;
4. the steady state (:func:`_on_steady_state`: the method's own orbit by Newton shooting, the span simulated
   from it on the same step plan), or the run from rest (:func:`_from_rest`: split at the model's load steps,
   kept as its :class:`~converters.saveat.SaveAt` says: output spacing, thinning, chunks);
5. labels and metadata (model, control, params, method options, periods, the orbit's statistics).

The summary and its accuracy estimate are the stages after it (:func:`run_summary`, :func:`check_accuracy`: by
what the method declares, ``Method.error_kind``).
"""
from __future__ import annotations

import time
from dataclasses import replace
from typing import Any, cast

import numpy as np
import numpy.typing as npt

from .analysis.periodic import (ONE_MODE, SIMULATE_REMEDY, PeriodicOrbit, instability, require, require_stable,
                                resolved, shoot)
from .errors import ParameterError, ResourceError, SimulationError
from .limits import max_memory
from .methods.base import DEFAULT_METHOD, Method, PeriodMap, get_method
from .methods.theta import StepPlanMap
from .models import Model, check_h, get_model
from .models.path import ParameterPath, check_no_step  # noqa: F401 (the API documents converters.run.ParameterPath)
from .saveat import SaveAt
from .simulate import simulate
from .trajectory import ReturnCode, Trajectory, concatenate, signal_unit
from .validate import check_flag, check_integer, parse_value

#: Periods simulated from x0 before Newton shooting starts: none. With the exact Jacobian Newton starts from x0
#: itself; where no fraction of its step lowers the residual (far from the orbit, off its mode sequence) it takes
#: a plain period instead, so the warm-up is only as long as the map needs (the buck's D and R sweeps of
#: benchmarks/steady_rate.py: 3.8-4.9 periods per point in all, against 20 fixed ones plus Newton's 5 before; the
#: same orbits, and the same modes at all 3,600 points of the four GDCM maps). Periods returned on the orbit by
#: default: STEADY_PERIODS.
WARM_UP_PERIODS = 0
STEADY_PERIODS = 20
#: The relative distance to the orbit at which a run's steady state counts as reached (``--steady-tol``).
STEADY_TOL = 1e-6
#: The steady tolerances taken: Newton aims at a tenth of one, and its own stops at 1e-15 (TOL_RANGE).
STEADY_TOL_RANGE = (1e-14, 1.0)
#: The most steps an accuracy-on-request run writes by default (its periods at the step rtol chose).
WRITTEN_STEPS = 1 << 20
DEFAULT_PERIODS = 500
#: Duration of a run of a model without a fixed period (s), when none is given.
DEFAULT_AUTONOMOUS_T_END = 30e-3


def resolve_model(name_or_model: str | Model, control: str = "pwm") -> Model:
    if isinstance(name_or_model, str):
        return get_model(name_or_model, control)
    if not isinstance(name_or_model, Model):
        from .models import CONVERTERS
        from .models import is_netlist
        if is_netlist(name_or_model):
            return get_model(name_or_model, control)
        raise ParameterError(f"the converter must be one of {', '.join(CONVERTERS)}, a netlist FILE.cir or a Model; "
                             f"got {name_or_model!r}")
    return name_or_model


def make_method(model: Model, p: dict, method: str | Method | None = None, h: float | str | None = None,
                **options: Any) -> Method:
    """The method for a run of ``model``: h defaults to the model's (T/1000), the stepper's theta
    to 0.5 where h resolves every time constant of the circuit, else 1 (:meth:`Model.default_theta`). ``h`` is
    the stepper's step or the output spacing of the other methods."""
    if isinstance(method, Method):
        if h is not None or any(v is not None for v in options.values()):
            raise ParameterError("give either a Method object or h and method options, not both")
        return method
    cls = get_method(method or DEFAULT_METHOD)
    if h is not None and not cls.step_option:
        raise ParameterError(f"h does not apply to the {cls.key} method (it takes no step of ours); got h = {h}")
    h = model.default_h(p) if h is None else parse_value("h", h)
    if model.periodic(p):
        check_h(h, model.period(p))
    elif not 0.0 < h <= model.max_h(p):
        raise ParameterError(f"h must be in (0, {model.max_h(p):.3g}] s for {model.key} (at most 1/20 of the "
                             f"shorter switching interval); got {h:g}")
    if options.get("theta") is None and "theta" in cls.option_names():     # 0.5 unless a mode is faster than h
        options["theta"] = model.default_theta(p, h)
    elif options.get("theta") is not None and "theta" in cls.option_names():
        from .methods.theta import check_ringing
        check_ringing(parse_value("theta", options["theta"]), model.fastest_rate(p), h)
    return cls.from_options(step=h, **options)


def duration(model: Model, p: dict, t_end: float | str | None = None, periods: int | None = None) -> float:
    """The run's length in s from t_end or a number of switching periods (default 500 periods, or 30 ms
    for a model without a fixed period)."""
    if t_end is not None and periods is not None:
        raise ParameterError("give either t_end or periods, not both")
    if t_end is not None:
        t_end = parse_value("t_end", t_end)
        if t_end <= 0:
            raise ParameterError(f"t_end must be positive (> 0 s); got {t_end!r}")
        return t_end
    if periods is not None:
        if not (isinstance(periods, (int, np.integer)) and periods >= 1):
            raise ParameterError(f"periods must be an integer >= 1; got {periods!r}")
        if not model.periodic(p):
            raise ParameterError(f"--periods does not apply to {model.key} (no fixed period); use --t-end")
        return periods * model.period(p)
    if hasattr(model, "default_duration"):          # a netlist: the .tran it states
        return model.default_duration(p)
    return DEFAULT_PERIODS * model.period(p) if model.periodic(p) else DEFAULT_AUTONOMOUS_T_END


def run_converter(name_or_model: str | Model, params: dict | None = None, *, control: str = "pwm",
                  method: str | Method | None = None, h: float | str | None = None, t_end: float | str | None = None,
                  periods: int | None = None, steady: bool = False, steady_tol: float = STEADY_TOL,
                  x0: npt.NDArray[np.float64] | None = None, rtol: float | str | None = None,
                  output_step: float | str | None = None, **options: Any) -> Trajectory:
    """Simulate a model (a converter under ``control``) with any method; returns a labelled Trajectory.

    Parameters
    ----------
    name_or_model : str or Model
        ``buck``, ``boost``, ``buck-boost``, ``cuk``, ``prc`` (with ``control``), or a Model.
    params : dict
        Parameter values (numbers or SPICE-style strings); unknown names are refused.
    method : str or Method, optional
        ``lcp`` (the default), ``event``, ``smooth`` (built from ``h`` and ``options``: ``theta``, ``eps``, ``solver_rtol``,
        ``event_tol``, ...), or a Method object; a method of the ``circuit`` domain (``spice``, registered by
        :mod:`validation.ngspice`) runs the model's circuit itself (its ``run_model``).
    h : float, optional
        The stepper's step, or the output spacing of the other methods (default: the model's, T/1000).
    t_end, periods : optional
        Duration in s or in switching periods (default 500 periods; with ``steady``, the span returned on the
        orbit, default 20 periods).
    steady : bool
        Run to the method's own periodic orbit: Newton shooting from x0 (``WARM_UP_PERIODS`` plain periods
        first: none) on the method's period map with its exact Jacobian until the estimated distance to the
        orbit is below ``steady_tol`` / 10 (relative); the span asked for (default ``STEADY_PERIODS`` periods)
        is then simulated from the orbit and returned (its time starts at 0; ``metadata['steady_periods']``
        counts every period simulated: Newton's, its plain periods and the span returned). The stepper builds
        its step plan once per operating point: Newton's map and the span returned share it.
        A run that cannot reach the orbit, or whose orbit is unstable (the circuit would not settle on it), raises
        SimulationError with the reason.
    x0 : array_like, optional
        Initial state (default: the model's, at rest).
    rtol : float, optional
        Accuracy on request (:func:`converters.analysis.accuracy.accurate_steady`): the periodic steady state
        with every measure's error estimate below rtol; pcsuite picks the method and h (so neither ``method``
        nor ``h`` nor method options may be given). ``metadata['accuracy']`` holds each value, its
        ``error_estimate``, the method and h; the span returned (default ``STEADY_PERIODS``) starts on the orbit.
    output_step : float, optional
        Output spacing (s) of a run from rest, as SPICE's: before what the summary and the plot read (the model's
        :meth:`~converters.models.base.Model.summary_from`: the last 20 periods, the sliding-mode window and the
        one before it, every period after a step), the run keeps one sample per ``output_step``; from there on
        every step. The run is simulated in chunks, so its memory is bounded by what it keeps, not by its steps.
        Default: every step, or, for a run whose steps would not fit in the memory limit, the finest spacing whose
        samples fit in half of it (``metadata['output_step']`` says which).
    """
    start = time.perf_counter()
    model, p = _resolved(name_or_model, control, params, steady, periods)
    if rtol is not None:                        # accuracy on request: the method and its step are chosen for it
        return _accurate(model, p, rtol, start, method=method, h=h, t_end=t_end, periods=periods, steady=steady,
                         x0=x0, options=options)
    given = method
    defaults = given is None and h is None and not any(v is not None for v in options.values())
    method = make_method(model, p, method, h, **options)
    if "circuit" in method.domains:             # a method that runs the model's circuit itself (ngspice)
        if output_step is not None:
            raise ParameterError(f"output_step applies to the LCS methods; the {method.key} method keeps its own points")
        return method.run_model(model, p, t_end=t_end, periods=periods, steady=steady, x0=x0)
    instead = _exact_instead(model, p, method) if defaults else None
    if instead is not None:
        method, why = instead
    span = _span(model, p, method, steady, t_end, periods)
    steady_tol = parse_value("steady_tol", steady_tol)
    if not STEADY_TOL_RANGE[0] <= steady_tol < STEADY_TOL_RANGE[1]:
        raise ParameterError(f"steady_tol must be in [{STEADY_TOL_RANGE[0]:g}, {STEADY_TOL_RANGE[1]:g}) (relative; "
                             f"Newton aims at a tenth of it); got {steady_tol!r}")
    if steady:
        if output_step is not None:
            raise ParameterError("output_step applies to a run from rest; --steady returns its periods on the orbit "
                                 "at every step")
        try:
            tr, meta = _on_steady_state(model, p, method, span, x0, steady_tol)
        except DiscretizationUnstable as why:
            if given is not None or h is not None or any(v is not None for v in options.values()):
                raise                               # the stepper asked for: its refusal names the step's instability
            # the default's step: the exact method's orbit is the answer, said so
            method = make_method(model, p, "event")
            tr, meta = _on_steady_state(model, p, method, span, why.exact.x0, steady_tol)
            meta["warnings"] = [*meta.get("warnings", []), f"{why.args[0].split('; use --method')[0]}: the exact "
                                "(event) method's orbit is given"]
    else:
        tr, meta = _from_rest(model, p, method, span, x0, SaveAt.plan(model, p, method, span, x0, output_step))
    if instead is not None:
        meta["warnings"] = [*meta.get("warnings", []), why]
    meta = {"model": model.name, "control": model.control, "params": p, "method_options": method.options(), **meta}
    return replace(tr, labels=model.labels(p), wall_s=time.perf_counter() - start, metadata={**tr.metadata, **meta})


def _resolved(name_or_model: str | Model, control: str, params: dict | None, steady: bool,
              periods: int | None) -> tuple[Model, dict]:
    """The run's first stage: the model and its parameters, resolved and checked."""
    model = resolve_model(name_or_model, control)
    if params is not None and not isinstance(params, dict):
        raise ParameterError(f"params must be a dict of NAME: VALUE; got {params!r}")
    p = model.resolve(params)
    check_flag("steady", steady)
    if periods is not None:
        check_integer("periods", periods, 1)
    return model, p


def _span(model: Model, p: dict, method: Method, steady: bool, t_end: float | str | None,
          periods: int | None) -> float:
    """The span the run returns (s): from rest, its duration; on the steady state, the periods returned on the
    orbit (default ``STEADY_PERIODS``). A step must fall inside it, and it must be at least one step."""
    if steady:
        check_steady(model, p)
        if t_end is None and periods is None:
            periods = STEADY_PERIODS
    span = duration(model, p, t_end, periods)
    for instant in model.step_times(p):
        if not 0.0 < instant < span:
            raise ParameterError(f"t_step must lie inside the run, in (0, {span:.6g}) s (the run's length); got "
                                 f"{instant:.6g} s: the step would not happen (a longer --t-end or more --periods)")
    step = getattr(method, method.step_option, None) if method.step_option else None
    if step is not None and span < step:
        raise ParameterError(f"t_end must be at least one step ({method.step_option} = {step:.3g} s); got {span:.3g} s")
    return span


def _on_steady_state(model: Model, p: dict, method: Method, span: float, x0: npt.NDArray[np.float64] | None,
                     steady_tol: float) -> tuple[Trajectory, dict]:
    """The steady-state stage: the method's own orbit by Newton shooting (refused when unstable: the circuit would
    not settle on it), then ``span`` simulated from it on the same step plan."""
    # Newton aims at a tenth of the tolerance asked; an orbit rounding stops short of that is still the answer
    # asked for where it is resolved to the tolerance itself (a DCM boost at --steady-tol 1e-11: 4.6e-12)
    orbit, period_map = _orbit_and_map(model, p, method, x0=x0, tol=0.1 * steady_tol, rounding_bound=steady_tol,
                                       explain=f" (Newton aims at a tenth of the tolerance asked, {steady_tol:.3g}, "
                                               "and takes an orbit rounding resolves to that tolerance itself)")
    unstable = instability(orbit.multipliers, model.period(p))
    if unstable and not method.exact:
        exact, unchecked = _exact_orbit(model, p, orbit.x0, steady_tol)
        if exact is None and unchecked:
            # the step's instability or the circuit's: the exact method, which would tell them apart, could not run
            step = getattr(method, "h", None)
            raise SimulationError(f"the stepper's periodic orbit of {model.key}" + (f" at h = {step:.3g} s" if step
                                  else "") + f" is {unstable.split(': the circuit')[0]}; the exact method, which "
                                  f"would tell the circuit's from the step's, could not check it ({unchecked}): run "
                                  "--periods N without --steady, or a smaller --h")
        if exact is not None and not instability(exact.multipliers, model.period(p)):
            # the stepper's orbit is unstable where the circuit's is not: its step's instability, not the circuit's
            # (a comparator chattering ~200 times a period inside 5 ns steps: 489.5 at h, 0.356 exact)
            step = getattr(method, "h", None)
            raise DiscretizationUnstable(
                f"the stepper's periodic orbit of {model.key}"
                + (f" at h = {step:.3g} s" if step else "") + f" is {unstable.split(': the circuit')[0]}, where the "
                f"circuit's exact orbit is stable (spectral radius {np.abs(exact.multipliers).max():.6g}): an "
                "instability of the step, not of the circuit; use --method event, or a smaller --h", exact)
        if exact is not None:                   # the circuit's own: its exact multipliers say how unstable
            require_stable(model, p, exact, "run --periods N without --steady")
    require_stable(model, p, orbit, "run --periods N without --steady")
    tr = _on_orbit(model, p, method, period_map, orbit.x0, span)
    T = model.period(p)
    simulated = orbit.evaluations + span / T        # the warm-up and Newton's spans, then the output
    # periods: what the returned run spans; steady_periods: every period simulated to get there and it
    return tr, {"periods": int(round(span / T)), "steady_periods": int(round(simulated)), "orbit": orbit.summary(),
                **({"warnings": [orbit.warning]} if orbit.warning else {})}


def _exact_instead(model: Model, p: dict, method: Method) -> tuple[Method, str] | None:
    """(the exact method, why) where the default stepper does not take the circuit and the exact method does (two
    comparator phases with a capacitance across each switch: the stepper does not locate a jump inside a step), so
    that the defaults answer; None where the stepper takes it, or neither does."""
    span = model.period(p) if model.periodic(p) else getattr(model, "default_duration", lambda p: None)(p)
    if method.exact or span is None:
        return None
    try:
        method.supports(model.problem(p, span))
        return None
    except ParameterError as refused:
        from .analysis.periodic import exact_refusal
        if exact_refusal(model, p, span):
            return None
        reason = str(refused).split(": use --method event")[0]
        return make_method(model, p, "event"), (f"the stepper does not take this circuit ({reason}): the exact "
                                                "(event) method's run is given")


class DiscretizationUnstable(SimulationError):
    """A stepper's orbit that is unstable where the exact method's is stable (``exact``: that orbit)."""

    def __init__(self, message: str, exact: PeriodicOrbit) -> None:
        super().__init__(message)
        self.exact = exact


def _exact_orbit(model: Model, p: dict, x0: npt.NDArray[np.float64],
                 steady_tol: float) -> tuple[PeriodicOrbit | None, str]:
    """(the exact method's orbit from ``x0`` (a stepper's), '') : what decides whether a stepper's unstable orbit is
    the circuit's; (None, '') where the method does not take the circuit (a SIN source), (None, why) where it
    takes it but found no orbit or reached a limit."""
    from .analysis.periodic import exact_refusal
    from .methods import EventDriven
    if exact_refusal(model, p):
        return None, ""
    try:
        return _orbit_and_map(model, p, EventDriven(), x0=x0, warm_up=0, tol=0.1 * steady_tol,
                              rounding_bound=steady_tol)[0], ""
    except (ParameterError, SimulationError, ResourceError) as why:
        return None, str(why).split("; ")[0]


def _from_rest(model: Model, p: dict, method: Method, span: float, x0: npt.NDArray[np.float64] | None,
               save: SaveAt) -> tuple[Trajectory, dict]:
    """The run from rest (or x0) over [0, span], split at the model's steps and kept as ``save`` says; where an
    open-loop step leads, for its response to be read against (:func:`_step_target`)."""
    tr = _simulate_phases(model, p, method, span, x0, save)
    meta: dict[str, Any] = {"periods": int(round(span / model.period(p))) if model.periodic(p) else None,
                            **save.metadata(tr)}
    target = _step_target(model, p, method)
    if target is not None:
        meta["step_target"] = target
    return tr, meta


def check_steady(model: Model, p: dict) -> None:
    """The one refusal of --steady (every method, ngspice and netlists): a steady state needs a fixed period."""
    check_no_step(model, p)
    if not model.periodic(p):
        raise ParameterError(f"--steady needs a fixed switching period; {model.key} has none (run --t-end, or find "
                             "its cycle with converters.analysis.periodic.autonomous_orbit and the event method)")


def _accurate(model: Model, p: dict, rtol: float | str, start: float, *, method: str | Method | None,
              h: float | str | None, t_end: float | str | None, periods: int | None, steady: bool,
              x0: npt.NDArray[np.float64] | None, options: dict[str, Any]) -> Trajectory:
    from .analysis.accuracy import accurate_steady
    rtol = parse_value("rtol", rtol)
    given = [name for name, value in (("method", method), ("h", h),
                                      *options.items()) if value is not None]
    if given:
        raise ParameterError(f"rtol chooses the method and its step; give either rtol or {', '.join(given)}, not "
                             "both")
    if not model.periodic(p):
        raise ParameterError(f"rtol: accuracy on request needs a periodic steady state; {model.key} has no fixed "
                             "switching period (run --t-end)")
    result = accurate_steady(model, p, rtol, x0=x0)
    T = model.period(p)
    span = duration(model, p, t_end, periods if (periods is not None or t_end is not None) else STEADY_PERIODS)
    if periods is None and t_end is None:
        # the default periods at the step rtol chose, as many as the memory limit and WRITTEN_STEPS hold: the
        # orbit's one period was run at that step, and a user who asked for none should not lose the answer to
        # the periods after it, nor wait minutes for a file of them (a stiff snubber's trapezoid at 3.3e5 steps a
        # period: 20 periods' CSV took 114 s)
        per_period = T / result.method.step if result.method.step else 0.0
        fits = [n for n in range(STEADY_PERIODS, 0, -1) if n * per_period <= WRITTEN_STEPS
                and result.method.memory_estimate(model.problem(p, n * T, result.orbit.x0)) <= max_memory()]
        span = T * (fits[0] if fits else 1)
    tr = simulate(model.problem(p, span, result.orbit.x0), result.method)
    simulated = sum(run["periods"] for run in result.runs) + span / T     # every orbit's periods, then the span
    meta = {"model": model.name, "control": model.control, "params": p, "method_options": result.method.options(),
            "orbit": result.orbit.summary(), "accuracy": result.summary(),
            "steady_periods": int(round(simulated)), "periods": int(round(span / T)),
            **({"warnings": [result.orbit.warning]} if result.orbit.warning else {})}
    return replace(tr, labels=model.labels(p), wall_s=time.perf_counter() - start, metadata={**tr.metadata, **meta},
                   retcode=ReturnCode.SUCCESS if result.met else ReturnCode.NOT_CONVERGED)


def _step_target(model: Model, p: dict, method: Method) -> float | None:
    """Where an open-loop step leads: the mean of vout over the periodic orbit of the circuit after the step (V),
    found by the same method; the step response is read against it, so a run that ends before settling says so
    rather than taking its last periods for the final value. None when the model has no such step (the
    sliding-mode boost's load step is judged on its own window) or the orbit cannot be found."""
    if not model.step_times(p) or not hasattr(model, "stepped") or not model.periodic(p):
        return None
    after = {k: v for k, v in model.stepped(p).items() if k not in model.STEP_PARAMETERS}
    try:
        orbit, period_map = _orbit_and_map(model, after, method)
    except ResourceError:                    # a limit reached is the run's, not a missing target
        raise
    except (SimulationError, ParameterError):
        return None
    tr = replace(_on_orbit(model, after, method, period_map, orbit.x0, model.period(after)),
                 labels=model.labels(after))
    return tr.mean("vout")


def _simulate_phases(model: Model, p: dict, method: Method, t_end: float, x0: npt.NDArray[np.float64] | None,
                     save: SaveAt) -> Trajectory:
    """One simulation per phase between the model's step times (a load step), the state and the switching
    law's memory carried across, each phase in the chunks ``save`` asks for, each chunk kept as it says."""
    bounds = [0.0] + [t for t in model.step_times(p) if 0.0 < t < t_end] + [t_end]
    parts, state, initial = [], x0, None
    for a, b in zip(bounds[:-1], bounds[1:]):
        options = model.phase_options(p, a)
        for c0, c1 in save.chunks(a, b, method, model.period(p) if model.periodic(p) else np.inf):
            part = simulate(model.problem(p, c1, state, t_start=c0, initial=initial, **options), method)
            state, initial = part.x[-1], int(part.config[-1])
            parts.append(save.kept(part, c0))
    return concatenate(parts)


def steady_state(model: Model, p: dict, method: Method, *, x0: npt.NDArray[np.float64] | None = None,
                 warm_up: int = WARM_UP_PERIODS, tol: float = 1e-10, periods: int = 1,
                 rounding_bound: float = 0.0, remedy: str = SIMULATE_REMEDY) -> PeriodicOrbit:
    """The method's own periodic orbit of ``model`` at ``p`` (raises SimulationError when Newton fails, offering
    ``remedy``; with ``rounding_bound``, an orbit rounding resolves to it serves:
    :func:`.analysis.periodic.require`)."""
    return _orbit_and_map(model, p, method, x0=x0, warm_up=warm_up, tol=tol, periods=periods,
                          rounding_bound=rounding_bound, remedy=remedy)[0]


def _orbit_and_map(model: Model, p: dict, method: Method, *, x0: npt.NDArray[np.float64] | None = None,
                   warm_up: int = WARM_UP_PERIODS, tol: float = 1e-10, periods: int = 1,
                   rounding_bound: float = 0.0, explain: str = "",
                   remedy: str = SIMULATE_REMEDY) -> tuple[PeriodicOrbit, PeriodMap]:
    """(orbit, period map): :func:`steady_state` and the map it shot on (its step plan, for the stepper,
    serves the run on the orbit too: :func:`_on_orbit`). Every orbit goes through here, so a step (no steady
    state: its problem over one period would be the circuit before the step) is refused here for all of them."""
    check_steady(model, p)
    problem = model.problem(p, periods * model.period(p), x0)
    period_map = method.period_map(problem)
    orbit = shoot(problem, method, problem.x0, periods=periods, warm_up=warm_up, tol=tol, period_map=period_map)
    if not resolved(orbit, rounding_bound) and orbit.settled is not None:
        latched = one_mode(model, p, method, orbit.settled)
        if latched and remedy == SIMULATE_REMEDY:         # no tolerance finds an orbit that is not there
            remedy = "run --periods N without --steady to see where it goes"
        explain += latched
    return require(orbit, f"the periodic orbit of {model.key}", rounding_bound, explain, remedy), period_map


def one_mode(model: Model, p: dict, method: Method, x: npt.NDArray[np.float64]) -> str:
    """Where a period from ``x`` (a transient's end) stays in one mode, what that means: no switch changes state,
    so there is no switching orbit to find (a loop latched at duty 1 or 0: its control never crosses its ramp),
    and the state that drifts most; else ''."""
    try:
        tr = run_converter(model, p, method=method, t_end=model.period(p), x0=x)
    except (SimulationError, ParameterError):
        return ""
    fractions = tr.mode_fractions(1)
    if len(fractions) != 1:
        return ""
    start, end = np.asarray(tr.x[0], dtype=float), np.asarray(tr.x[-1], dtype=float)
    i = int(np.argmax(np.abs(end - start)))
    unit = signal_unit(getattr(model, "signal_units", None) or {}, tr.state_names[i])
    return (f"; where the transient ends, a whole period stays in one mode ({next(iter(fractions))}): {ONE_MODE}, "
            f"and {tr.state_names[i]} drifts from {start[i]:.4g} to {end[i]:.4g} {unit} over the period")


def _on_orbit(model: Model, p: dict, method: Method, period_map: PeriodMap, x0: npt.NDArray[np.float64],
              span: float) -> Trajectory:
    """The run over [0, span] from x0 (on the orbit): the stepper repeats the step plan of its period map (grid
    and matrices built once per operating point); any other method simulates the model's problem."""
    if isinstance(period_map, StepPlanMap):
        return period_map.plan.spanning(span, x0).trajectory(x0)
    return simulate(model.problem(p, span, x0), method)


def steady_orbit(name_or_model: str | Model, params: dict | None = None, *, method: str | Method | None = None,
                 h: float | str | None = None, tol: float = 1e-8, warm_up: int = WARM_UP_PERIODS,
                 **options: Any) -> Trajectory:
    """One period of the method's periodic orbit, labelled (conduction modes, maps, GDCM): Newton shooting
    from rest (after ``warm_up`` plain periods), one step plan for Newton and the period returned.
    ``metadata['orbit']`` holds the orbit's statistics (residual, distance, multipliers)."""
    model = resolve_model(name_or_model)
    p = model.resolve(params)
    method = make_method(model, p, method, h, **options)
    orbit, period_map = _orbit_and_map(model, p, method, warm_up=warm_up, tol=tol)
    tr = _on_orbit(model, p, method, period_map, orbit.x0, model.period(p))
    return replace(tr, labels=model.labels(p),
                   metadata={**tr.metadata, "model": model.name, "params": p, "orbit": orbit.summary()})


#: The power summary's error estimates (:func:`converters.analysis.accuracy.default_check`).
POWER_ESTIMATES = ("efficiency_error_estimate", "input_W_error_estimate", "losses_W_error_estimate",
                   "loss_error_estimates_W")


def run_summary(tr: Trajectory, *, check: bool = True) -> dict:
    """The JSON summary of a run: converter, method, its options, steps, wall_s, and the model's measures
    (PWM converters: vout_mean over the last 10 periods, mode fractions of the last period); with ``check``, how
    accurate they are (:func:`check_accuracy`: re-runs at twice the step or on the method's orbit)."""
    meta = tr.metadata
    out = {"converter": meta["model"], "method": tr.method, "options": {**meta["method_options"], "params": meta["params"]},
           "steps": int(tr.steps), "wall_s": tr.wall_s, "retcode": tr.retcode.value}
    model, p = tr.labels.model, meta["params"]
    if model.control != Model.control:
        out["control"] = model.control
    out.update(model.summary(tr, p))
    for key in ("periods", "steady_periods", "output_step", "resolved_from_s"):
        if meta.get(key) is not None:
            out[key] = meta[key]
    out.update(meta.get("notes", {}))               # what the method says of its run (ngspice: has it settled)
    if "orbit" in meta:
        out["orbit"] = meta["orbit"]
    if "accuracy" in meta:                      # accuracy on request: the orbit's values and their estimates
        accuracy = meta["accuracy"]
        out["vout_mean"] = accuracy["quantities"]["vout_mean"]["value"]
        out["mode_fractions"] = {k[len("fraction_"):]: q["value"] for k, q in accuracy["quantities"].items()
                                 if k.startswith("fraction_")}
        out["accuracy"] = accuracy
        if not accuracy["met"]:
            out["warnings"] = [*out.get("warnings", []), f"rtol {accuracy['rtol']:g} not met: {accuracy['message']}"]
        quantities = accuracy["quantities"]
        if "power" in out and "input_W" in quantities:      # the rtol covers the power summary too
            from .analysis.accuracy import efficiency_estimate
            losses = [quantities[f"loss_{k}"]["relative_error_estimate"] for k in out["power"]["losses_W"]
                      if f"loss_{k}" in quantities]
            out["power"].update(efficiency_error_estimate=efficiency_estimate(quantities),
                                input_W_error_estimate=quantities["input_W"]["relative_error_estimate"],
                                losses_W_error_estimate=max(losses, default=0.0),
                                loss_error_estimates_W={k: quantities[f"loss_{k}"]["error_estimate"]
                                                        for k in out["power"]["losses_W"] if f"loss_{k}" in quantities})
    elif check:
        check_accuracy(tr, out)
    if meta.get("warnings"):
        out["warnings"] = [*meta["warnings"], *out.get("warnings", [])]
    return out


def check_accuracy(tr: Trajectory, summary: dict) -> dict:
    """How accurate a run's ``summary`` (:func:`run_summary`'s, without ``check``) is, by what its method declares
    (``Method.error_kind``): ``summary["accuracy"]`` and, where an estimate exceeds the default target,
    ``summary["warnings"]``; updated in place and returned.

    - A periodic circuit run with a time schedule (no step): the run against its method's periodic orbit, and a
      ``step`` method's orbit against the one at twice the step (Richardson's estimate by the order it observes);
      the mode fractions and events of the last period are then read inside the step
      (:func:`converters.analysis.accuracy.default_check`).
    - A run with no periodic orbit to compare with (a state-driven law, a load step): the same run at twice the
      step, and the window against the one before it (:func:`converters.analysis.accuracy.window_check`).
    - An ``exact`` method has no discretization to estimate; a ``model`` method's error is not a step's."""
    model, p, out = tr.labels.model, tr.metadata["params"], summary
    if tr.algorithm is None:
        return out
    method = cast(Method, tr.algorithm)           # a run's Algorithm is the Method that made it
    if model.periodic(p) and not model.step_times(p) and _schedule_driven(model, p):
        from .analysis.accuracy import default_check, last_period
        period = last_period(model, p, tr)
        out["mode_fractions"] = period["mode_fractions"]        # read inside the step, not on the grid
        out["events"] = [{"pair": pair, "kind": kind, "time_T": t} for pair, kind, t in period["events"]]
        check = default_check(model, p, method, tr, out["vout_mean"], out.get("power"))
        for key in POWER_ESTIMATES:          # the power summary's estimates stand beside its values
            if key in check:
                out["power"][key] = check.pop(key)
    elif isinstance(out.get("vout_mean"), float) and ("window_s" in out or "window_periods" in out):
        from .analysis.accuracy import window_check
        window = out.get("window_s") or (float(tr.t[-1]) - out["window_periods"] * model.period(p), float(tr.t[-1]))
        coarse = (run_converter(model, p, method=method.coarsened(), t_end=float(tr.t[-1] - tr.t[0]), x0=tr.x[0])
                  if method.fixed_step else None)      # the same run at twice the step
        check = window_check(model, p, method, tr, out, window, coarse)
        undecided = _stability_at_2h(model, p, method, tr)
        if undecided:
            check["trusted"] = False
            check["warning"] = f"{check['warning']}; {undecided}" if "warning" in check else undecided
        if model.periodic(p) and "mode_fractions" in out:
            # a comparator's switchings at the instants the run located inside its steps, not on its grid (a type III
            # boost's duty ratio printed 0.512000 at T/1000, exact 0.512937)
            from .analysis.accuracy import last_period
            out["mode_fractions"] = {str(k): float(v) for k, v in last_period(model, p, tr)["mode_fractions"].items()}
    else:
        return out
    out["accuracy"] = check
    if "warning" in check:
        out["warnings"] = [*out.get("warnings", []), check["warning"]]
    return out


def default_answer(name_or_model: str | Model, params: dict | None, tr: Trajectory, summary: dict, *,
                   control: str = "pwm", periods: int | None = None) -> tuple[Trajectory, dict]:
    """The default's answer on a periodic steady state: the default stepper's run ``tr`` (its ``summary``, checked:
    :func:`run_summary`), or the exact method's orbit where the run's own check found a value off by more than the
    defaults promise (against the exact orbit, its second resolution where the step's estimate could not be
    trusted, or at h and 2h) and the exact method takes the circuit: that orbit is the answer then, said so in the
    first of its summary's warnings. A DCM buck with 1 ohm and 220 pF across its switch: the stepper's 21.82 V
    stated 1.8e-2 off the exact 22.21 V; a flyback's clamp diode and a ladder's diodes stated 1.6 to 3.9 % off
    (their estimates honest, the values beyond what the defaults promise), each with exit 0. Where the exact
    method does not take the circuit (a SIN source) the step is refined instead (:func:`_refined`); where it finds
    no orbit, the stepper's answer and its warning stand. ``periods``: the span returned on the orbit, as
    :func:`run_converter`'s. Every command that answers with the default (``simulate --steady``, ``compare``) gives
    this one."""
    from .analysis.accuracy import exact_reference_of
    from .analysis.periodic import exact_refusal
    accuracy = summary.get("accuracy", {})
    if "warning" not in accuracy:
        return tr, summary
    reference = exact_reference_of(tr)
    if reference is None and exact_refusal(tr.labels.model, tr.metadata["params"]):
        return _refined(name_or_model, params, tr, summary, control, periods)
    try:
        exact = run_converter(name_or_model, params, control=control, method="event", periods=periods, steady=True,
                              x0=(tr if reference is None else reference).x[0], steady_tol=STEADY_TOL)
    except (ParameterError, SimulationError, ResourceError):
        return tr, summary
    check = "its check at h and 2h" if reference is None else "its check against the exact orbit"
    said = (f"the default step's values are off by more than the defaults promise ({check}: "
            f"{_cause(accuracy['warning'])}): the exact (event) method's orbit is given")
    out = run_summary(exact)
    out["warnings"] = [said, *out.get("warnings", [])]
    return exact, out


#: The finer steps the default tries, as fractions of its own, where its check finds a value beyond its promise and
#: the exact method does not take the circuit: each 4x the work, a first-order error 4x smaller.
REFINEMENTS = (4, 16)


def _refined(name_or_model: str | Model, params: dict | None, tr: Trajectory, summary: dict, control: str,
             periods: int | None) -> tuple[Trajectory, dict]:
    """The default stepper's steady run where its check at h and 2h found a value off by more than the defaults
    promise and the exact method does not take the circuit (a SIN source): the run again at h/4, then h/16, until
    its check finds every value within the promise; said in one warning, the finest run's own warnings after it
    where it still does not (a Delon doubler on a 50 Hz line: its diodes' peak 1.3 % low at T/1000, stated; 0.33 %
    at T/4000, within its estimate). A step the limits refuse keeps the last run's answer."""
    h, T = float(summary["options"]["h"]), float(tr.labels.model.period(tr.metadata["params"]))
    first = _cause(summary["accuracy"]["warning"])
    best, out = tr, summary
    for factor in REFINEMENTS:
        try:
            finer = run_converter(name_or_model, params, control=control, periods=periods, steady=True, h=h / factor,
                                  steady_tol=STEADY_TOL)
        except (ParameterError, SimulationError, ResourceError):
            break
        best, out = finer, run_summary(finer)
        if "warning" not in out.get("accuracy", {}):
            break
    if best is tr:
        return tr, summary
    step = float(out["options"]["h"])
    still = "warning" in out.get("accuracy", {})
    said = (f"the default step's values are off by more than the defaults promise (its check at h and 2h: {first}): "
            f"the step is refined to h = {step:.3g} s ({T / step:.0f} a period)"
            + (", where they still are" if still else ", where its check finds them within it"))
    out["warnings"] = [said, *out.get("warnings", [])]
    return best, out


def _cause(warning: str) -> str:
    """An accuracy warning without its remedy (the default's answer is the remedy)."""
    return warning.split("; use ")[0].split(": use ")[0]


def _stability_at_2h(model: Model, p: dict, method: Method, tr: Trajectory) -> str:
    """'' or why a stepper's steady orbit under a state-driven law may be on the other side of 1 than its spectral
    radius says: its orbit at 2h, from the run's start (on the orbit), against it
    (:func:`.analysis.periodic.stability_undecided`). The orbit's check does this from its own runs at h and 2h."""
    orbit = tr.metadata.get("orbit")
    if not (method.fixed_step and model.periodic(p) and orbit):
        return ""
    from .analysis.periodic import passive, stability_undecided, undecided_remedy
    if passive(model, p):
        return ""
    T = model.period(p)
    try:
        at_2h = shoot(model.problem(p, T, tr.x[0]), method.coarsened(), tr.x[0], tol=1e-8, polish=True)
    except (ParameterError, SimulationError):
        return ""
    if not resolved(at_2h):
        return ""
    at_h = [complex(re, im) for re, im in orbit.get("multipliers", [])]
    undecided = stability_undecided(at_h, at_2h.multipliers)
    return f"the orbit's {undecided[4:]}: {undecided_remedy(model, p)}" if undecided else ""


def _schedule_driven(model: Model, p: dict) -> bool:
    """The model switches on a time schedule (open loop: its orbit is the run's reference), not on its state."""
    from .problems import Schedule
    return isinstance(model.problem(p, model.period(p)).switching, Schedule)
