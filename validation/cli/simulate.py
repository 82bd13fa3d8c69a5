"""``pcsuite simulate CONVERTER``: one run, its waveform file and its JSON summary."""
from __future__ import annotations

import sys
import time
from typing import Any

from converters.errors import ParameterError, ResourceError
from converters.trajectory import signal_unit

from .common import add_params, add_spice_options, check_out, given_path, integer, json_text, method_options, write_frame


def add(sub) -> None:
    from converters.methods.base import load_methods
    from converters.models import CONTROLS

    METHODS = load_methods()
    sim = sub.add_parser("simulate", help="simulate a converter and write its waveforms")
    sim.add_argument("converter")
    add_params(sim)
    circuits = {key: cls for key, cls in METHODS.items() if {"lcs", "circuit"} & set(cls.domains)}
    sim.add_argument("--method", default=None, choices=list(circuits),
                     help="; ".join(f"{key}: {cls.description}" for key, cls in circuits.items())
                     + " (default lcp; with --rtol pcsuite chooses)")
    sim.add_argument("--h", default=None, help="step in s (default T/1000); event and smooth: "
                                              "output sample spacing")
    sim.add_argument("--eps", default=None, help="smooth: smoothing width eps (default 1e-4, units of y)")
    sim.add_argument("--rtol", default=None,
                     help="accuracy on request: the periodic steady state with every reported value's error "
                          "estimate below RTOL (relative; mode fractions and event instants in units of T); "
                          "pcsuite chooses the method and step and reports them")
    sim.add_argument("--solver-rtol", default=None, help="smooth: scipy's relative tolerance (default 1e-6; the "
                                                         "result's error is the smoothing's, O(eps))")
    sim.add_argument("--theta", default=None, help="theta in [0.5, 1] (default 0.5 where the step resolves every "
                     "time constant of the circuit, else 1: backward Euler, which does not ring)")
    sim.add_argument("--grade", default=None,
                     help="lcp: the first step after each switching instant as a fraction of --h, in [0, 1) (default 0: "
                          "uniform steps); the steps then grow by --growth until they reach --h")
    sim.add_argument("--growth", default=None, help="lcp: the ratio of consecutive graded steps, in (1, 10] (default 1.2)")
    span = sim.add_mutually_exclusive_group()
    span.add_argument("--t-end", default=None, help="duration in s (with --steady: the span returned on the orbit)")
    span.add_argument("--periods", type=integer(1), default=None,
                      help="duration in switching periods (default 500; with --steady: the periods returned on the "
                           "orbit, default 20)")
    sim.add_argument("--control", default="pwm", choices=list(CONTROLS),
                     help="boost: sliding-mode current control (smc: hysteresis; smc-implicit: the implicit "
                          "relay) with -p Vref=.. -p band=.. [-p Kp=.. -p Ki=.. -p t_step=.. -p R_step=..]; buck: "
                          "voltage-mode: the ramp comparator, -p A=.. -p Vref=.. -p VL=.. -p VU=.. [-p latch=1]")
    sim.add_argument("--steady", action="store_true", help="run to the method's periodic orbit (Newton shooting)")
    sim.add_argument("--steady-tol", default=None,
                     help="with --steady: relative distance to the orbit at which the steady state counts as reached "
                          "(default 1e-6)")
    add_spice_options(sim)
    sim.add_argument("--output-step", default=None,
                     help="output spacing in s, as SPICE's: one sample per OUTPUT_STEP before what the summary and "
                          "the plot read (every step there); the run's memory is then bounded by its output (default: "
                          "every step, or the finest spacing that fits in half the memory limit)")
    sim.add_argument("--out", type=given_path, default=None, help="waveform file, .csv or .parquet")
    sim.add_argument("--plot", type=given_path, default=None,
                     help="FILE.png or FILE.svg: the last periods' waveforms and the mode timeline; FILE.html: an "
                          "interactive scope of the whole run (zoom, two cursors with the mean and RMS between them)")
    sim.add_argument("--thermal", type=given_path, default=None,
                     help="with --steady: a thermal setup (FILE.toml: devices, their PLECS .xml or .toml loss and "
                          "thermal descriptions, heatsinks, ambient) for the devices' losses and junction temperatures "
                          "(default: the one a netlist names on a '*pcsuite thermal FILE' line)")
    sim.add_argument("--json", action="store_true", help="print one JSON summary object")
    sim.set_defaults(run=run, one_run=True)


def run(args) -> int:
    from ..io import check_output_file; check_output_file("--plot", args.plot)  # noqa: E702 (before the run)
    from converters.params import parse_assignments
    from converters.run import STEADY_TOL, run_converter, run_summary
    check_out(args.out)
    if args.plot is not None and args.plot.suffix.lower() not in (".png", ".svg", ".html"):
        raise ParameterError(f"--plot must end in .png, .svg or .html; got {str(args.plot)!r}")
    params = parse_assignments(args.params)
    if args.thermal is not None and not args.steady and args.rtol is None:
        raise ParameterError("--thermal reads the losses of the periodic steady state: give --steady (or --rtol)")
    thermal = None if args.thermal is None else _thermal_setup(args.thermal)      # read before the run
    if args.steady_tol is not None and not args.steady and args.rtol is None:
        raise ParameterError(f"--steady-tol applies with --steady only; got --steady-tol {args.steady_tol} without it")
    if args.rtol is not None:
        given = [flag for flag, value in (("--method", args.method), ("--h", args.h), ("--theta", args.theta),
                                          ("--grade", args.grade), ("--growth", args.growth), ("--eps", args.eps), ("--solver-rtol", args.solver_rtol),
                                          ("--steady-tol", args.steady_tol), ("--spice-tmax", args.spice_tmax),
                                          ("--spice-reltol", args.spice_reltol), ("--spice-method", args.spice_method))
                 if value is not None]
        if given:
            raise ParameterError(f"--rtol chooses the method and its step; give either --rtol or {', '.join(given)}")
        if args.output_step is not None:
            raise ParameterError("--output-step applies to a run from rest (--rtol returns its periods on the orbit at "
                                 "every step)")
        tr = run_converter(args.converter, params, control=args.control, t_end=args.t_end, periods=args.periods,
                           rtol=args.rtol)
        summary = run_summary(tr)
    else:
        from converters.methods.base import DEFAULT_METHOD, get_method
        method = args.method or DEFAULT_METHOD
        cls = get_method(method)
        if "circuit" in cls.domains:          # it runs the circuit itself: no step of ours, no Newton, its own points
            given = [flag for flag, value in (("--h", args.h), ("--steady-tol", args.steady_tol),
                                              ("--output-step", args.output_step)) if value is not None]
            if given:
                raise ParameterError(f"{', '.join(given)} do{'es' if len(given) == 1 else ''} not apply to --method "
                                     f"{method} ({cls.description})")
        elif args.output_step is not None and args.steady:
            raise ParameterError("--output-step applies to a run from rest (--steady returns its periods on the orbit "
                                 "at every step)")
        options = method_options(method, {"theta": args.theta, "grade": args.grade, "growth": args.growth,
                                          "eps": args.eps, "solver_rtol": args.solver_rtol,
                                          "spice_tmax": args.spice_tmax, "spice_reltol": args.spice_reltol,
                                          "spice_method": args.spice_method})
        setup_s = _set_up(args.converter, params, args.control, method, args.steady, options) \
            if "lcs" in cls.domains else None
        # (the method as given: the default's may leave a step's unstable orbit to the exact method)
        tr = run_converter(args.converter, params, control=args.control, method=args.method, h=args.h,
                           t_end=args.t_end, periods=args.periods, steady=args.steady,
                           steady_tol=STEADY_TOL if args.steady_tol is None else args.steady_tol,
                           output_step=args.output_step, **options)
        summary = run_summary(tr)
        if args.steady and args.method is None and args.h is None and args.steady_tol is None \
                and all(v is None for v in options.values()):
            from converters.run import default_answer
            tr, summary = default_answer(args.converter, params, tr, summary, control=args.control,
                                         periods=args.periods)
        if "lcs" in cls.domains:
            summary["setup_s"] = setup_s
    if args.steady or args.rtol is not None:
        model = tr.labels.model
        if thermal is None and hasattr(model, "netlist"):
            from converters.thermal.network import declared_setup
            declared = declared_setup(model.netlist.text, model.source)
            thermal = None if declared is None else _thermal_setup(declared)
        if thermal is not None:
            from converters.thermal.summary import thermal_summary
            summary["thermal"] = thermal_summary(model, tr.metadata["params"], tr, thermal)
            if "warning" in summary["thermal"]:
                summary["warnings"] = [*summary.get("warnings", []), summary["thermal"]["warning"]]
    if args.out is not None:
        from ..scope import scope_meta
        frame = tr.waveforms()
        meta = {k: summary.get(k) for k in ("converter", "control", "method", "options", "output_step",
                                            "resolved_from_s") if k in summary}
        if tr.resolved_from <= tr.t[0]:         # every step stored: the scope of the file integrates as the run does
            meta["scope"] = scope_meta(tr, [c for c in frame.columns if c not in ("time", "mode")])
        write_frame(frame, args.out, meta=meta)
    if args.plot is not None and args.plot.suffix.lower() == ".html":
        from ..scope import of_trajectory, write_scope
        write_scope(of_trajectory(tr, title=_scope_title(args.converter, summary["method"],
                                                         tr.metadata.get("params") or {})), args.plot)
    elif args.plot is not None:
        import io

        from ..io import atomic_write_bytes
        fig = tr.plot()
        buffer = io.BytesIO()
        fig.savefig(buffer, format=args.plot.suffix.lower()[1:], dpi=110, bbox_inches="tight")
        import matplotlib.pyplot as plt
        plt.close(fig)
        atomic_write_bytes(args.plot, buffer.getvalue())
    if args.json:
        print(json_text(summary))
    else:
        _print(summary, tr, args)
    return 0


def _thermal_setup(path):
    from converters.thermal.network import read_setup
    return read_setup(path)


def _set_up(converter, params, control, method, steady, options) -> float:
    """The one-time set-up of a process (loading the compiled kernels: the ahead-of-time module, ~2 ms, or numba
    loading them from its disk cache on their first call, ~0.3 s; :mod:`converters.compiled`), paid here on one
    coarse period of the same model and method (a model without a fixed period, or with a step: 50 of its
    default steps) so that the run's ``wall_s`` measures the computation alone; returns its time (the JSON's
    ``setup_s``)."""
    from converters.models import get_model
    from converters.run import run_converter
    start = time.perf_counter()
    model = get_model(converter, control)
    p = model.resolve(params)
    try:
        if model.periodic(p) and not model.step_times(p):
            run_converter(model, p, method=method, h=model.period(p) / 20, periods=1, steady=steady, **options)
        else:
            run_converter(model, p, method=method, t_end=50 * model.default_h(p), **options)
    except ResourceError:                   # a limit reached (--time-limit's alarm) is the command's
        raise
    except (ValueError, RuntimeError):      # a set-up that fails says nothing: the run itself reports
        pass
    return time.perf_counter() - start


def _print(summary: dict, tr, args) -> None:
    unit = tr.algorithm.counts
    options = ", ".join(f"{k} = {v:.3g}" if isinstance(v, float) else f"{k} = {v}"
                        for k, v in summary["options"].items() if k != "params" and v is not None
                        and not isinstance(v, dict) and k != "max_events")
    title = summary["converter"] + (f" --control {summary['control']}" if "control" in summary else "")
    line = f"{title} ({tr.method}): {summary['steps']} {unit} ({options}) in {summary['wall_s']:.3f} s; "
    # a netlist's vout is the file's output (its first .meas vector, v(out) or its first node): named, in its unit
    model = getattr(tr.labels, "model", None)
    output = getattr(model, "output", None)
    unit = signal_unit(getattr(model, "signal_units", None) or {}, "vout")
    line += f"vout{f' ({output})' if output else ''} mean = {summary['vout_mean']:.9g} {unit}"
    if "vref" in summary:
        line += f" (Vref {summary['vref']:g} V)"
    print(line)
    if "switching_frequency_Hz" in summary:
        print(f"switching {summary['switching_frequency_Hz'] / 1e3:.6g} kHz (predicted "
              f"{summary['predicted_frequency_Hz'] / 1e3:.6g} kHz at the measured mean vout)")
    if "lambda_mean" in summary:
        print(f"lambda = 1 - s = {summary['lambda_mean']:.8f} (Vin/v = {summary['vin_over_v']:.8f})")
    if "spice_settle" in summary:
        print(f"ngspice from the LCP's orbit, {summary['steady_periods']} periods: its 10-period mean moves "
              f"{summary['spice_settle']:.2g} ({'settled' if summary['spice_settled'] else 'NOT settled'})")
    elif "steady_periods" in summary:
        orbit = summary["orbit"]
        print(f"periodic steady state after {summary['steady_periods']} periods (Newton: {orbit['iterations']} "
              f"iterations, distance to the orbit {orbit['distance']:.2g}, Floquet spectral radius "
              f"{_radius(orbit['spectral_radius'])})")
    for held in summary.get("invariants", ()):     # what the loops, cutsets and charge islands hold fixed
        print(f"held ({held['kind']}): {held['constraint']} = {held['value']:.6g} {held['unit']}")
    power = summary.get("power")
    if power:                 # every converter with a power balance: a warning about it names what is printed
        from converters.analysis.accuracy import MEASUREMENT_RTOL
        estimates = power.get("loss_error_estimates_W", {})

        def loss(name: str, value: float) -> str:
            # a loss known to less than 1 % of itself says how well (a diode's drop conducting for one step)
            error = estimates.get(name, 0.0)
            within = f" +- {error * 1e3:.2g}" if error > MEASUREMENT_RTOL * abs(value) else ""
            return f"{name} {value * 1e3:.4g}{within} mW"
        losses = ", ".join(loss(k, v) for k, v in power["losses_W"].items()) or "none: ideal parts"
        within = (f" +- {100 * power['efficiency_error_estimate']:.1g}" if "efficiency_error_estimate" in power
                  else "")
        print(f"power over the last {summary['window_periods']:g} periods: in {power['input_W']:.6g} W, out "
              f"{power['output_W']:.6g} W, efficiency {100 * power['efficiency']:.3f}{within} % (losses: {losses})")
    thermal = summary.get("thermal")
    if thermal:
        for name, d in thermal["devices"].items():
            off = "recovery" if d["kind"] == "Diode" else "turn-off"
            print(f"{name} ({d['name']}): {d['total_W']:.4g} W (conduction {d['conduction_W']:.4g}, turn-on "
                  f"{d['turn_on_W']:.4g}, {off} {d.get('recovery_W', d.get('turn_off_W')):.4g}), junction "
                  f"{d['tj_C']:.2f} degC, case {d['case_C']:.2f} degC")
        power = thermal["power"]
        print(f"with the devices' losses: in {power['input_W']:.6g} W, out {power['output_W']:.6g} W, efficiency "
              f"{100 * power['efficiency']:.3f} % (ambient {thermal['ambient_C']:g} degC)")
        accuracy = thermal.get("accuracy", {})
        if accuracy.get("checked"):
            print(f"device losses within ~{accuracy['losses_error_estimate']:.1g} of their total (estimated: the run's "
                  "distance to its orbit and the orbit's losses at a finer step)")
    step = summary.get("step")
    if step:
        final = ("steady state after the step" if step["final_from"] != "run end"
                 else "the last periods' mean: the final value is not known")
        over = ("" if "overshoot_V" not in step else
                f", overshoot {step['overshoot_V']:.3g} V ({step['overshoot_percent']:.3g} % of the final value)"
                if step["overshoot_V"] > 0 else ", no overshoot")
        settling = (f"settling {step['settling_time_s'] * 1e3:.4g} ms" if step["settled"] else
                    f"NOT settled by the end of the run ({step['vout_end']:.6g} V; outside the band until "
                    f"{step['settling_time_s'] * 1e3:.4g} ms after the step)")
        print(f"step at {step['t_step_s'] * 1e3:.6g} ms: vout {step['vout_before']:.6g} -> {step['vout_final']:.6g} V "
              f"({final}){over}, largest deviation {step['deviation_V']:.3g} V, {settling} (band +- "
              f"{step['band_V']:.3g} V)")
    if "output_step" in summary:
        print(f"kept every step from {summary['resolved_from_s'] * 1e3:.6g} ms (what the summary and the plot read); "
              f"before it one sample per {summary['output_step']:.3g} s (--output-step)")
    if "mode_fractions" in summary:
        print("modes (last period): " + ", ".join(f"{k} {v:.6f}" for k, v in summary["mode_fractions"].items()))
    accuracy = summary.get("accuracy", {})
    if "quantities" in accuracy:
        how = (f"{accuracy['method']}" + (f", h = T/{accuracy['steps_per_period']}, theta {accuracy['theta']:g}"
                                         if accuracy["steps_per_period"] else ", exact flows"))
        print(f"accuracy on request: rtol {accuracy['rtol']:g} {'met' if accuracy['met'] else 'NOT met'} ({how}; "
              f"{accuracy['wall_s']:.3f} s)")
        for name, q in accuracy["quantities"].items():
            print(f"  {name:18s} {q['value']:.10g}  +- {q['error_estimate']:.2g} ({q['relative_error_estimate']:.1g})")
        for event in accuracy["events"]:
            print(f"  {event['pair']} {event['kind']} at {event['time_T']:.9f} T  +- {event['error_estimate_T']:.2g} T")
    elif accuracy.get("estimates"):
        print("accuracy (relative; " + accuracy["how"] + "): " + ", ".join(
            f"{name} within ~{q['error_estimate']:.1g}" for name, q in accuracy["estimates"].items()))
    elif "estimates" in accuracy:      # a window check with nothing to estimate: exact flows over a short run
        print("accuracy: exact flows (no step error); whether the run has settled is not estimated (the run is "
              "shorter than two windows of its measures, or a step lies in them)")
    elif not accuracy.get("checked") and "transient" in accuracy:       # a method whose error is its model's
        print(f"vout mean moved {accuracy['transient']:.1g} (relative) from the 10 periods before ({accuracy['reason']})")
    elif accuracy.get("checked"):
        how = (f"the run's distance to its orbit; the {tr.method} method has no step error" if tr.algorithm.exact
               else f"the run's distance to its orbit and {accuracy['estimated_by']}" if "estimated_by" in accuracy
               else "the run's distance to its orbit and Richardson at h and 2h")
        trust = "" if accuracy.get("trusted", True) else "; not to be trusted here: see the warning"
        print(f"vout mean within ~{accuracy['vout_mean_error_estimate']:.1g} (relative) of the exact periodic value "
              f"(estimated: {how}{trust})")
    for warning in summary.get("warnings", []):
        print(f"warning: {warning}", file=sys.stderr)
    from converters.validate import quoted
    for path in (args.out, args.plot):
        if path is not None:
            print(f"wrote {quoted(path)}")


def _radius(rho: float) -> str:
    """A spectral radius as read: within 1e-5 of 1 as 1 less its distance (0.99999985 printed "1" looked marginal)."""
    return f"1 - {1.0 - rho:.2g}" if 0.0 < 1.0 - rho < 1e-5 else f"{rho:.6g}"


def _scope_title(converter: str, method: str, params: dict) -> str:
    """The scope's heading: the circuit, its method and its operating point."""
    from converters.plotting import eng
    point = ", ".join(f"{k} = {eng(v)}" for k, v in params.items()
                      if isinstance(v, (int, float)) and not isinstance(v, bool))
    return f"{converter} ({method}){': ' + point if point else ''}"
