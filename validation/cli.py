"""The ``pcsuite`` command line. Bad input exits non-zero with one line naming the parameter."""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from converters.errors import ParameterError, PcsuiteError

EXIT_BAD_INPUT = 2


def main(argv=None) -> int:
    parser = _parser()
    args = parser.parse_args(argv)
    if not hasattr(args, "run"):
        parser.print_help()
        return EXIT_BAD_INPUT
    try:
        return args.run(args) or 0
    except BrokenPipeError:  # e.g. `pcsuite list | head`
        sys.stderr.close()
        return 0
    except (PcsuiteError, ValueError) as exc:
        print(f"pcsuite: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT


class _Parser(argparse.ArgumentParser):
    """argparse with the project's one-line errors (no usage dump)."""

    def error(self, message):
        self.exit(EXIT_BAD_INPUT, f"pcsuite: error: {message}\n")


def _parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="pcsuite", description="Power-converter study suite: LCP "
                                     "time-stepping of DC-DC converters cross-checked against ngspice.")
    sub = parser.add_subparsers(title="commands", parser_class=_Parser)

    listing = sub.add_parser("list", help="converters with their parameters, methods, scenes")
    listing.add_argument("--json", action="store_true")
    listing.set_defaults(run=_list)

    sim = sub.add_parser("simulate", help="simulate a converter and write its waveforms")
    sim.add_argument("converter")
    sim.add_argument("-p", dest="params", action="append", default=[], metavar="NAME=VALUE",
                     help="parameter value, SPICE suffixes allowed (repeatable)")
    sim.add_argument("--method", default="lcp", choices=["lcp", "event", "smooth", "spice"],
                     help="lcp: the LCP time-stepper; event: exact event-driven (one diode); smooth: "
                          "softplus-smoothed diode with a stiff solver; spice: the same circuit in ngspice")
    sim.add_argument("--h", default=None, help="step in s (default T/1000; PRC 50 ns); event and smooth: "
                                              "output sample spacing")
    sim.add_argument("--eps", default=None, help="smooth: smoothing width eps (default 1e-4, units of y)")
    sim.add_argument("--rtol", default=None, help="smooth: solver relative tolerance (default 1e-6)")
    sim.add_argument("--theta", default=None, help="theta in [0.5, 1] (default 1, PRC 0.5)")
    span = sim.add_mutually_exclusive_group()
    span.add_argument("--t-end", default=None, help="duration in s")
    span.add_argument("--periods", type=int, default=None, help="duration in switching periods (default 500)")
    sim.add_argument("--control", default="pwm", choices=["pwm", "smc", "smc-implicit"],
                     help="boost only: sliding-mode current control (hysteresis, or the implicit relay) "
                          "with -p Vref=.. -p band=.. [-p Kp=.. -p Ki=.. -p t_step=.. -p R_step=..]")
    sim.add_argument("--steady", action="store_true", help="run until the periodic steady state")
    sim.add_argument("--steady-tol", type=float, default=1e-6)
    sim.add_argument("--out", type=Path, default=None, help="waveform file, .csv or .parquet")
    sim.add_argument("--json", action="store_true", help="print one JSON summary object")
    sim.set_defaults(run=_simulate)

    lcp = sub.add_parser("lcp", help="linear complementarity problems").add_subparsers(title="lcp commands")
    solve = lcp.add_parser("solve", help="solve an LCP stored in the Siconos .dat format")
    solve.add_argument("file", type=Path)
    solve.add_argument("--method", default="lemke", choices=["lemke", "murty", "enum", "pgs", "newton"])
    solve.add_argument("--tol", type=float, default=1e-10)
    solve.add_argument("--max-iter", type=int, default=None)
    solve.add_argument("--json", action="store_true", help="print one JSON object")
    solve.set_defaults(run=_lcp_solve)

    cmp = sub.add_parser("compare", help="the LCP time-stepper against ngspice on the same circuit")
    cmp.add_argument("converter")
    cmp.add_argument("-p", dest="params", action="append", default=[], metavar="NAME=VALUE")
    cmp.add_argument("--h", default=None, help="LCP step in s (default T/1000)")
    cmp.add_argument("--start", choices=["steady", "rest"], default=None,
                     help="start both on the periodic orbit (default) or from rest (default for prc)")
    cmp.add_argument("--control", default="pwm", choices=["pwm", "smc"],
                     help="boost only: sliding-mode current control (see simulate)")
    cmp.add_argument("--t-end", default=None, help="duration in s (sliding mode; default 30 ms)")
    cmp.add_argument("--plot", type=Path, default=None, help="write the overlay/residual plot (.png)")
    cmp.add_argument("--json", action="store_true")
    cmp.set_defaults(run=_compare)

    gd = sub.add_parser("gdcm", help="predicted CCM/DCM/GDCM against the modes detected in LCP and ngspice")
    gd.add_argument("converter")
    gd.add_argument("-p", dest="params", action="append", default=[], metavar="NAME=VALUE")
    gd.add_argument("--h", default=None, help="LCP step in s (default T/1000)")
    gd.add_argument("--json", action="store_true", help="print one JSON object (predicted, lcp, spice, agree, ...)")
    gd.set_defaults(run=_gdcm)

    gmap = sub.add_parser("gdcm-map", help="D-K map of the conduction mode: prediction, LCP and ngspice")
    gmap.add_argument("converter", choices=["buck", "boost", "buck-boost", "cuk"])
    gmap.add_argument("--size", type=int, nargs=2, default=[30, 30], metavar=("N_D", "N_K"))
    gmap.add_argument("--no-spice", action="store_true", help="LCP and prediction only")
    gmap.add_argument("--workers", type=int, default=2, help="parallel ngspice processes (default 2)")
    gmap.add_argument("--out", type=Path, default=None, help="directory for map.csv and map.png")
    gmap.add_argument("--json", action="store_true", help="print the summary as JSON")
    gmap.set_defaults(run=_gdcm_map)

    net = sub.add_parser("netlist", help="print the ngspice netlist of a converter")
    net.add_argument("converter")
    net.add_argument("-p", dest="params", action="append", default=[], metavar="NAME=VALUE")
    net.add_argument("--t-end", default=None, help="duration in s (default 500 periods)")
    net.set_defaults(run=_netlist)

    report = sub.add_parser("report", help="run a suite of scenes and write the validation report")
    report.add_argument("suite", nargs="?", default="default")
    report.add_argument("--out", type=Path, default=None, help="output directory (default reports/SUITE)")
    report.add_argument("--workers", type=int, default=2, help="parallel processes (default 2)")
    report.set_defaults(run=_report)

    bench = sub.add_parser("bench", help="the speed-accuracy trade-off of every method and the stability map")
    bench.add_argument("--quick", action="store_true", help="trade-off: the DCM cases, a short sweep")
    bench.add_argument("--no-spice", action="store_true", help="leave ngspice out")
    bench.add_argument("--only", choices=["tradeoff", "stability"], default=None)
    bench.add_argument("--periods", type=int, default=None, help="trade-off: periods per run (default 200)")
    bench.add_argument("--out", type=Path, default=None, help="output directory (default reports/bench)")
    bench.add_argument("--json", action="store_true", help="print the summary as JSON")
    bench.set_defaults(run=_bench)
    return parser


def _lcp_solve(args) -> int:
    from converters.lcp import read_siconos_lcp, solve_lcp
    problem = read_siconos_lcp(args.file)
    result = solve_lcp(problem.M, problem.q, method=args.method, tol=args.tol, max_iter=args.max_iter)
    if args.json:
        print(json.dumps({"file": str(args.file), "k": int(problem.q.shape[0]), **result.to_dict()}))
    else:
        print(f"{problem.name}: k = {problem.q.shape[0]}, method = {result.method}, status = {result.status}, "
              f"err = {result.err:.3g}, iterations = {result.iterations}")
        print("z =", np.array2string(result.z, precision=6))
        if result.message:
            print(result.message)
        if args.method == "enum":
            print(f"{len(result.solutions)} basic solution(s):")
            for s in result.solutions:
                print("  ", np.array2string(s, precision=6))
    return 0 if result.solved else 1


def _list(args) -> int:
    from converters.models import CONVERTERS

    from converters.models.sliding import PARAMETERS as SMC_PARAMETERS

    from .scenes import SCENE_DIR, load_scene, suite_names
    from .sections import EXTRA_SECTIONS
    info = {"converters": {name: {"title": c.title, "states": list(c.state_names), "parameters": [
        {"name": p.name, "default": p.default, "unit": p.unit, "doc": p.doc, "range": p.range_text(),
         "optional": p.default is None} for p in c.parameters]} for name, c in CONVERTERS.items()},
        "methods": {"lcp": "LCP time-stepper: theta method (--theta, default 1 = backward Euler), one LCP per step",
                    "event": "exact event-driven: matrix exponentials per mode, events by root finding (one diode)",
                    "smooth": "diode smoothed by u = log(1 + exp(-y/eps)) (--eps), scipy Radau (--rtol)",
                    "spice": "the same circuit in ngspice (PySpice)"},
        "controls": {"smc": {"converter": "boost", "parameters": [
            {"name": p.name, "default": p.default, "unit": p.unit, "doc": p.doc, "range": p.range_text(),
             "optional": p.default is None} for p in SMC_PARAMETERS]}, "smc-implicit": {"converter": "boost"}},
        "scenes": {p.stem: load_scene(p).converter for p in sorted(SCENE_DIR.glob("*.toml"))},
        "suites": sorted(set(suite_names()) | set(EXTRA_SECTIONS))}
    if args.json:
        print(json.dumps(info, indent=2))
        return 0
    for name, conv in info["converters"].items():
        print(f"{name}: {conv['title']}  (states: {', '.join(conv['states'])})")
        for p in conv["parameters"]:
            default = "only when given" if p["optional"] else f"{p['default']:g}"
            print(f"    {p['name']:<6} {default:>16} {p['unit']:<4} {p['doc']}  range {p['range']}")
    print("methods:")
    for name, doc in info["methods"].items():
        print(f"    {name}: {doc}")
    print("boost --control smc | smc-implicit (sliding mode) parameters:")
    for p in info["controls"]["smc"]["parameters"]:
        default = "only when given" if p["optional"] else f"{p['default']:g}"
        print(f"    {p['name']:<6} {default:>16} {p['unit']:<7} {p['doc']}  range {p['range']}")
    print("scenes: " + ", ".join(f"{k} ({v})" for k, v in info["scenes"].items()))
    print("report suites: " + ", ".join(info["suites"]))
    return 0


def _simulate(args) -> int:
    from converters.params import parse_assignments
    from converters.run import run_converter
    if args.out is not None and args.out.suffix.lower() not in (".csv", ".parquet"):
        raise ParameterError(f"--out must end in .csv or .parquet; got {str(args.out)!r}")
    if args.control != "pwm":
        return _simulate_smc(args)
    if args.method == "spice":
        return _simulate_spice(args)
    run = run_converter(args.converter, parse_assignments(args.params), h=args.h, theta=args.theta,
                        t_end=args.t_end, periods=args.periods, steady=args.steady, steady_tol=args.steady_tol,
                        method=args.method, eps=args.eps, rtol=args.rtol)
    if args.out is not None:
        _write_frame(run.waveforms(), args.out)
    summary = run.summary()
    if args.json:
        print(json.dumps(summary, default=float))
    else:
        options = ", ".join(f"{k} = {v:.3g}" if isinstance(v, float) else f"{k} = {v}"
                            for k, v in run.method_options().items() if v is not None and k != "max_events")
        unit = {"lcp": "steps", "event": "segments", "smooth": "LU factorisations"}[run.method_name]
        print(f"{summary['converter']} ({run.method_name}): {summary['steps']} {unit} ({options}) in "
              f"{summary['wall_s']:.3f} s; vout mean (last 10 periods) = {summary['vout_mean']:.9g} V")
        if run.steady_periods is not None:
            print(f"periodic steady state after {run.steady_periods} periods")
        print("modes (last period): " + ", ".join(f"{k} {v:.3f}" for k, v in summary["mode_fractions"].items()))
        if args.out is not None:
            print(f"wrote {args.out}")
    return 0


def _check_smc_args(args):
    if args.converter != "boost":
        raise ParameterError(f"--control {args.control} is available for the boost only; got {args.converter!r}")
    if getattr(args, "steady", False) or getattr(args, "periods", None) is not None:
        raise ParameterError("--steady and --periods do not apply to sliding-mode control (no fixed period); "
                             "use --t-end")


def _simulate_smc(args) -> int:
    import time as _time

    from converters.params import parse_assignments
    from converters.models.sliding import predicted_frequency, resolve_smc, simulate_smc
    from converters.validate import parse_value
    _check_smc_args(args)
    p = resolve_smc(parse_assignments(args.params))
    t_end = parse_value("t_end", args.t_end) if args.t_end is not None else 30e-3
    if args.method == "spice":
        if args.control != "smc":
            raise ParameterError("--method spice simulates --control smc (the hysteresis comparator); "
                                 "the implicit relay exists in the LCP stepper only")
        from netlists import build_smc_netlist

        from .smc import WINDOW_S, _closings, _frequency, _mean
        from .spice import run_spice
        start = _time.perf_counter()
        netlist = build_smc_netlist(p, t_end)
        result = run_spice(netlist)
        t = result.time
        v, iL = result.signal(netlist.probes["vout"]), result.signal(netlist.probes["iL"])
        on = result.signal(netlist.probes["sw"]) < 0.5 * v
        t0 = t_end - min(WINDOW_S, 0.25 * t_end)
        summary = {"converter": "boost", "control": "smc", "method": "spice",
                   "options": {**result.options, "params": p, "ngspice": result.ngspice_version},
                   "steps": result.accepted_steps, "wall_s": _time.perf_counter() - start,
                   "vout_mean": _mean(t, v, t0), "vref": p["Vref"], "switching_frequency_Hz": _frequency(_closings(t, on), t0)}
        summary["predicted_frequency_Hz"] = predicted_frequency(p, summary["vout_mean"])
        import pandas as pd
        frame = pd.DataFrame({"time": t, "iL": iL, "vC": v, "vout": v, "switch": on.astype(int),
                              "mode": np.where(on, "CCM-ON", "CCM-OFF")})
    else:
        run = simulate_smc(p, scheme="hysteresis" if args.control == "smc" else "implicit", h=args.h, t_end=t_end)
        summary, frame = run.summary(), run.waveforms()
    if args.out is not None:
        _write_frame(frame, args.out)
    if args.json:
        print(json.dumps(summary, default=float))
    else:
        line = (f"boost ({args.control}, {summary['method']}): {summary['steps']} steps in {summary['wall_s']:.3f} s; "
                f"vout mean = {summary['vout_mean']:.6g} V (Vref {p['Vref']:g} V)")
        if "switching_frequency_Hz" in summary:
            line += (f"; switching {summary['switching_frequency_Hz'] / 1e3:.4g} kHz (predicted "
                     f"{summary['predicted_frequency_Hz'] / 1e3:.4g} kHz)")
        if "lambda_mean" in summary:
            line += f"; lambda = 1 - s = {summary['lambda_mean']:.8f} (Vin/v = {summary['vin_over_v']:.8f})"
        print(line)
    return 0


def _compare_smc(args) -> int:
    from converters.params import parse_assignments
    from converters.validate import parse_value

    from .io import atomic_write_bytes
    from .smc import compare_smc, smc_plot
    _check_smc_args(args)
    t_end = parse_value("t_end", args.t_end) if args.t_end is not None else 30e-3
    c = compare_smc(parse_assignments(args.params), t_end=t_end, h=args.h)
    if args.plot is not None:
        atomic_write_bytes(args.plot, smc_plot(c))
    m = c.metrics
    checks = {"vout_ref_rel_lcp": m["vout_ref_rel_lcp"] <= 5e-3, "vout_ref_rel_spice": m["vout_ref_rel_spice"] <= 5e-3,
              "frequency_rel_lcp": m["frequency_rel_lcp"] <= 0.05, "frequency_rel_spice": m["frequency_rel_spice"] <= 0.05,
              "frequency_lcp_vs_spice": m["frequency_lcp_vs_spice"] <= 0.05}
    if "recovery_lcp_vs_spice" in m:
        checks["recovery_lcp_vs_spice"] = m["recovery_lcp_vs_spice"] <= 0.1
    passed = all(checks.values())
    if args.json:
        print(json.dumps({"converter": "boost", "control": "smc", "params": c.params, "metrics": m,
                          "checks": checks, "passed": passed}, default=float))
    else:
        print(f"boost (sliding mode): LCP against {c.spice.ngspice_version}")
        for key, value in m.items():
            print(f"  {key:<32} {value:.6g}" if isinstance(value, float) else f"  {key:<32} {value}")
        for key, ok in checks.items():
            print(f"  check {key:<26} {'pass' if ok else 'FAIL'}")
        print("PASS" if passed else "FAIL")
    return 0 if passed else 1


def _write_frame(frame, path: Path):
    from .io import atomic_write_bytes
    frame = frame.copy()
    frame["mode"] = frame["mode"].astype(str)
    if path.suffix.lower() == ".csv":
        data = frame.to_csv(index=False).encode()
    else:
        import io as _io
        buffer = _io.BytesIO()
        frame.to_parquet(buffer, index=False)
        data = buffer.getvalue()
    atomic_write_bytes(path, data)


def _simulate_spice(args) -> int:
    import time as _time

    from converters.models import get_converter
    from converters.params import parse_assignments
    from netlists import build_netlist

    from .spice import run_spice, spice_waveforms
    if args.steady:
        raise ParameterError("--steady is available with --method lcp only; got --method spice")
    start = _time.perf_counter()
    conv = get_converter(args.converter)
    p = conv.resolve(parse_assignments(args.params))
    T = conv.period(p)
    t_end = args.t_end if args.t_end is not None else (args.periods or 500) * T
    netlist = build_netlist(conv.name, p, t_end)
    result = run_spice(netlist)
    window_start = result.time[-1] - 10 * T
    frame = spice_waveforms(conv, netlist, result, window_start)
    wall = _time.perf_counter() - start
    if args.out is not None:
        _write_frame(frame, args.out)
    t, v = frame["time"].to_numpy(), frame["vout"].to_numpy()
    w = t >= window_start
    last = t >= result.time[-1] - T
    dt = np.diff(t[last])
    labels = frame["mode"].to_numpy()[last][1:]
    summary = {"converter": conv.name, "method": "spice",
               "options": {**result.options, "params": p, "ngspice": result.ngspice_version},
               "steps": result.accepted_steps, "wall_s": wall,
               "vout_mean": float(np.trapezoid(v[w], t[w]) / (t[w][-1] - t[w][0])),
               "mode_fractions": {str(k): float(dt[labels == k].sum() / dt.sum()) for k in sorted(set(labels))}}
    if args.json:
        print(json.dumps(summary, default=float))
    else:
        print(f"{conv.name} (ngspice {result.ngspice_version}): {result.accepted_steps} steps in {wall:.3f} s; "
              f"vout mean (last 10 periods) = {summary['vout_mean']:.6g} V")
    return 0


def _compare(args) -> int:
    from converters.params import parse_assignments

    from .compare import THRESHOLDS, compare
    from .io import atomic_write_bytes
    from .plots import comparison_plot
    if args.plot is not None and args.plot.suffix.lower() != ".png":
        raise ParameterError(f"--plot must end in .png; got {str(args.plot)!r}")
    if args.control == "smc":
        return _compare_smc(args)
    result = compare(args.converter, parse_assignments(args.params), h=args.h, start=args.start)
    if args.plot is not None:
        atomic_write_bytes(args.plot, comparison_plot(result))
    if args.json:
        print(json.dumps(result.to_dict(), default=float))
    else:
        print(f"{result.converter}: LCP against {result.spice.ngspice_version}")
        for key, value in result.metrics.items():
            text = f"{value:.4g}" if isinstance(value, float) else str(value)
            print(f"  {key:<36} {text}")
        for key, ok in result.checks.items():
            print(f"  check {key:<30} {'pass' if ok else 'FAIL'} (threshold {THRESHOLDS[key]:g})")
        print("PASS" if result.passed else "FAIL")
    return 0 if result.passed else 1


def _gdcm(args) -> int:
    from converters.params import parse_assignments

    from .gdcm import gdcm_check
    result = gdcm_check(args.converter, parse_assignments(args.params), h=args.h)
    if args.json:
        print(json.dumps(result, default=float))
        return 0 if result["agree"] else 1
    print(f"{result['converter']}: predicted {result['predicted']}")
    pred = result.get("prediction")
    if pred:
        print(f"  closed form: K = {pred['K']:.4g}, Kcrit(D) = {pred['Kcrit']:.4g} -> {pred['closed_form']}; "
              f"exact (CCM orbit from the matrices): {pred['exact_matrix']}")
        for row in pred["conditions"]:
            print(f"  GDCM condition, {row['configuration']}: {'possible' if row['possible'] else 'impossible'} "
                  f"({row['condition']})")
        T = result["period_s"]
        for side in ("lcp", "spice"):
            print(f"  {side}: {result[side]}, held {result['held_fraction'][side]:.4f} of T")
            for iv in result["intervals"][side]:
                print(f"      {iv['mode']:<9} {iv['start'] / T:7.4f} T .. {iv['end'] / T:7.4f} T  ({iv['fraction']:.4f} T)")
    else:
        for side in ("lcp", "spice"):
            print(f"  {side}: " + ", ".join(f"{k} {v:.4f}" for k, v in result[side].items()))
    print("agree" if result["agree"] else "DISAGREE")
    return 0 if result["agree"] else 1


def _gdcm_map(args) -> int:
    from .gdcm import dk_map, map_plot, map_summary
    from .io import atomic_write_bytes
    n_d, n_k = args.size
    frame = dk_map(args.converter, n_d, n_k, spice=not args.no_spice, spice_workers=args.workers)
    summary = map_summary(frame)
    if args.out is not None:
        atomic_write_bytes(args.out / "map.csv", frame.drop(columns=["x0"], errors="ignore").to_csv(index=False).encode())
        atomic_write_bytes(args.out / "map.png", map_plot(frame))
    if args.json:
        print(json.dumps(summary, default=float))
    else:
        for key, value in summary.items():
            print(f"  {key:<28} {value:.4g}" if isinstance(value, float) else f"  {key:<28} {value}")
    return 0


def _netlist(args) -> int:
    from converters.models import get_converter
    from converters.params import parse_assignments
    from netlists import build_netlist
    conv = get_converter(args.converter)
    p = conv.resolve(parse_assignments(args.params))
    t_end = args.t_end if args.t_end is not None else 500 * conv.period(p)
    print(build_netlist(conv.name, p, t_end).text, end="")
    return 0


def _report(args) -> int:
    from .report import write_report
    from .scenes import suite_names
    from .sections import EXTRA_SECTIONS
    from .suite import run_suite, scene_section, scenes_summary
    suites = sorted(set(suite_names()) | set(EXTRA_SECTIONS))
    if args.suite not in suites:
        raise ParameterError(f"SUITE must be one of {', '.join(suites)}; got {args.suite!r}")
    out = args.out or Path("reports") / args.suite
    scenes, extras = run_suite(args.suite, EXTRA_SECTIONS.get(args.suite, ()), workers=args.workers)
    sections = ([scenes_summary(scenes)] if scenes else []) + [scene_section(r) for r in scenes] + list(extras)
    index = write_report(sections, out, args.suite, options={"suite": args.suite, "workers": args.workers})
    failed = [s.title for s in sections if not s.ok]
    print(f"wrote {index} ({len(sections) - len(failed)}/{len(sections)} sections pass)")
    for title in failed:
        print(f"  failed: {title}")
    return 0


def _bench(args) -> int:
    from .bench import DEFAULT_OUT, run_bench
    out = args.out or DEFAULT_OUT
    summary = run_bench(out, quick=args.quick, spice=not args.no_spice, only=args.only, periods=args.periods,
                        progress=not args.json)
    if args.json:
        print(json.dumps(summary, default=float))
        return 0
    import pandas as pd
    with pd.option_context("display.width", 200, "display.max_columns", 20, "display.float_format", "{:.3g}".format):
        if "tradeoff" in summary:
            part = summary["tradeoff"]
            print(f"trade-off: {part['runs']} runs ({part['failed_runs']} failed) over {part['periods']} periods "
                  f"in {part['wall_s']:.0f} s")
            accept = pd.DataFrame(part["acceptance"])
            keep = [c for c in ("case", "spice_default_error", "spice_default_wall_s", "lcp_setting", "lcp_speedup",
                                "event_setting", "event_error", "event_vs_spice", "result") if c in accept]
            print(accept[keep].to_string(index=False))
        if "stability" in summary:
            part = summary["stability"]
            print(f"stability: {part['runs']} runs in {part['wall_s']:.0f} s; ill-posed requests refused "
                  f"{part['ill_posed_refused']} of {part['ill_posed']}")
            print(pd.DataFrame(part["summary"]).to_string(index=False))
    print(f"wrote {out}/")
    return 0


if __name__ == "__main__":
    sys.exit(main())
