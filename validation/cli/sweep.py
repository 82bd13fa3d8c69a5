"""``pcsuite sweep MODEL --grid NAME=START:STOP:COUNT ...``: a model's steady state over a grid or a Latin
hypercube of parameter points, one row per point, streamed to a Parquet dataset that an interrupted run
resumes."""
from __future__ import annotations

import signal
import sys
from pathlib import Path

from converters.errors import ParameterError

from .common import EXIT_INTERRUPTED, MAX_WORKERS, add_params, check_workers, given_path, integer, json_text, number

#: A stored row as the summary loads it back (25 columns), generously.
BYTES_PER_ROW = 400


def add(sub) -> None:
    from converters.models import CONTROLS
    sw = sub.add_parser("sweep", help="a model over a grid of parameter points: one row per point (Parquet), "
                                      "resumable, on this machine's cores or a Dask cluster")
    sw.add_argument("model", help="the converter (buck, boost, buck-boost, cuk, prc)")
    sw.add_argument("--grid", action="append", default=[], metavar="NAME=START:STOP:COUNT[:log]",
                    help="a swept parameter (repeatable: the full grid of all of them; SPICE suffixes allowed)")
    sw.add_argument("--lhs", type=integer(1, _max_points), default=None, metavar="N",
                    help="N Latin-hypercube points over the --grid ranges (NAME=START:STOP[:log], no COUNT) "
                         "instead of the full grid")
    sw.add_argument("--seed", type=integer(0), default=None,
                    help="the Latin hypercube's or the tolerance study's seed (default 0)")
    sw.add_argument("--tolerance", action="append", default=[], metavar="NAME=TOL[%][:DIST]",
                    help="a tolerance study (repeatable, instead of --grid): NAME spread about its value (-p or its "
                         "default) by TOL, normal (TOL = 3 sigma, truncated there; default), uniform or lognormal "
                         "(e.g. C=5%%, L=10%%:uniform)")
    sw.add_argument("--samples", type=integer(1, _max_points), default=None, metavar="N",
                    help="the tolerance study's samples (default 1000)")
    sw.add_argument("--sampler", default=None, choices=["lhs", "sobol"],
                    help="the tolerance study's unit hypercube: a Latin hypercube (default) or a scrambled Sobol "
                         "sequence")
    sw.add_argument("--spec", action="append", default=[], metavar="METRIC<VALUE",
                    help="a specification (repeatable; <, <=, >, >=; e.g. vout_ripple<50m, efficiency>0.95): the "
                         "summary gives the fraction meeting each and the yield meeting all, with its 95 %% "
                         "confidence interval, and the worst sample")
    sw.add_argument("--corners", action="store_true",
                    help="with --tolerance: also run the 2^k worst-case corners (each parameter at its extremes) and "
                         "give each spec's worst corner")
    sw.add_argument("--indices", action="store_true",
                    help="with --tolerance: each metric's first-order (variance-based) sensitivity indices from the "
                         "study's own sample (RBD-FAST, SALib), with their 95 %% confidence; at least 100 samples")
    add_params(sw)
    sw.add_argument("--control", default="pwm", choices=list(CONTROLS), help="the control law (default pwm)")
    from converters.methods.base import DEFAULT_METHOD, load_methods
    from converters.sweeps.ensemble import sweep_methods

    METHODS = load_methods()
    circuits = [key for key, cls in METHODS.items() if "circuit" in cls.domains]
    sw.add_argument("--method", default=DEFAULT_METHOD, choices=list(dict.fromkeys([*sweep_methods(), *circuits])),
                    help="lcp: the stepper, h = T/200 (default; batched); event: exact switching; spice: ngspice")
    sw.add_argument("--steady", action="store_true",
                    help="measure on the periodic orbit (lcp, event: Newton shooting; spice: started on the LCP's "
                         "orbit); without it: --periods periods from rest, measured over the last one")
    sw.add_argument("--periods", type=integer(1), default=None,
                    help="periods simulated (default 50 from rest; spice: 10, from the orbit with --steady)")
    sw.add_argument("--h-fraction", type=number("(0, 1)"), default=None, help="lcp: step h / T (default 1/200)")
    sw.add_argument("--rtol", type=number(_rtol_range), default=None,
                    help="accuracy on request (with --steady): each point's measures with error estimates below "
                         "RTOL, the method and step chosen per point (columns error_estimate, "
                         "vout_mean_error_estimate, accuracy_method, steps_per_period, rtol_met)")
    sw.add_argument("--scheduler", default="local",
                    help="local (this machine's processes, default), serial, batched (one process), or a Dask "
                         "scheduler tcp://HOST:PORT")
    sw.add_argument("--workers", type=integer(1, MAX_WORKERS), default=None, help="local: processes (default: every core)")
    sw.add_argument("--chunk", type=integer(1), default=None, help="points per task (default: 500 batched, 2 ngspice)")
    sw.add_argument("--out", type=given_path, default=None,
                    help="the sweep directory (default sweep-MODEL); an interrupted sweep resumes from it")
    sw.add_argument("--metric", action="append", default=None,
                    help="a column on demand and the summary plot's metric (repeatable, the first plotted, a tolerance study's "
                         "every one and its specs'; default "
                         "the first --spec's, or vout_mean): a standard measure, SIGNAL.STAT (STAT mean, rms, min, max, ripple: vout.max, "
                         "v(out).ripple), efficiency, input_W, output_W, total_loss_W or losses.NAME")
    sw.add_argument("--no-progress", action="store_true", help="no progress bar")
    sw.add_argument("--json", action="store_true", help="print one JSON summary object")
    sw.set_defaults(run=run)


def _max_points() -> int:
    from converters.sweeps.points import MAX_POINTS
    return MAX_POINTS


def _rtol_range() -> str:
    from converters.analysis.accuracy import RTOL_RANGE
    return f"[{RTOL_RANGE[0]:g}, {RTOL_RANGE[1]:g}]"


def build(args):
    """The ensemble and the points the arguments ask for (every value checked before anything runs)."""
    from converters.params import parse_assignments
    from converters.sweeps import Axis, Grid, LatinHypercube, ModelSweep
    from converters.validate import parse_value

    base = {k: parse_value(k, v) for k, v in parse_assignments(args.params).items()}
    from converters.limits import check_memory
    from converters.sweeps.specs import Spec
    named = [Spec.metric_of(text) for text in args.spec]
    # the plotted metric: the first --metric, else the first spec's, else vout_mean
    metrics = list(dict.fromkeys([*(args.metric or (named[:1] or ["vout_mean"])), *named]))
    if args.tolerance:
        if args.grid or args.lhs is not None:
            raise ParameterError("--tolerance is a study of its own (samples about the nominal values); give either "
                                 "--tolerance or --grid/--lhs")
        from converters.models import get_model
        from converters.sweeps.points import Tolerance, Tolerances
        model = get_model(args.model, args.control)
        nominals = model.resolve(base)
        nominals = {**{q.name: nominals.get(q.name) for q in model.parameters}, **nominals}
        n = 1000 if args.samples is None else args.samples
        check_memory(f"sweep: --samples {n}", float(n) * (BYTES_PER_ROW + 8 * len(args.tolerance)),
                     remedy="fewer --samples")
        # a name as -p and --grid take it (a netlist's are case-insensitive, as SPICE's)
        named = [f"{model.parameter_name(t.partition('=')[0].strip())}={t.partition('=')[2]}" if "=" in t else t
                 for t in args.tolerance]
        points = Tolerances([Tolerance.parse(t, nominals) for t in named], n,
                            0 if args.seed is None else args.seed, args.sampler or "lhs")
        from converters.sweeps.indices import MIN_SAMPLES
        if args.indices and n < MIN_SAMPLES:
            raise ParameterError(f"--indices: first-order indices need at least {MIN_SAMPLES} samples; got --samples {n}")
    elif args.lhs is not None:
        check_memory(f"sweep: --lhs {args.lhs} points", float(args.lhs) * (BYTES_PER_ROW + 8 * len(args.grid)),
                     remedy="fewer --lhs points")
        points = LatinHypercube([Axis.parse(g, count_required=False) for g in args.grid], args.lhs,
                                0 if args.seed is None else args.seed)
    else:
        points = Grid([Axis.parse(g) for g in args.grid])
    check_memory(f"sweep: {points.size:,} points", float(points.size) * BYTES_PER_ROW, remedy="fewer points")
    # -p, --grid and --tolerance name a parameter as the model keys it (a netlist's case-insensitively): -p L=10u
    # beside --tolerance L=10% had reached the netlist as both L and l, "-p l is given twice"
    from converters.models import get_model as model_of
    keyed = model_of(args.model, args.control).parameter_name
    names = [keyed(str(k)) for k in base]
    twice = next((k for k, name in zip(base, names) if names.count(name) > 1), None)
    if twice is not None:
        both = " and ".join(k for k in base if keyed(str(k)) == keyed(str(twice)))
        raise ParameterError(f"-p {twice} is given twice (as {both}; a netlist's names are case-insensitive)")
    base = dict(zip(names, base.values()))
    clash = sorted(set(base) & {keyed(str(name)) for name in points.names})
    if clash and points.kind != "tolerance":             # a tolerance's nominal may be given with -p
        raise ParameterError(f"{clash[0]} is both swept (--grid) and fixed (-p); give it once")
    if args.periods is not None and args.periods < 1:
        raise ParameterError(f"--periods must be an integer >= 1; got {args.periods}")
    _refuse_ignored(args)
    if _runs_circuits(args.method):
        from converters.methods.base import get_method
        measures = get_method(args.method).sweep_measures or {}
        extra = [m for m in metrics if m not in measures]
        if extra:
            raise ParameterError(f"--metric {extra[0]}: an ngspice sweep's measures are "
                                 f"{', '.join(k for k, t in measures.items() if t is not str)}")
        ensemble = ModelSweep(args.model, args.control, base, method=args.method, steady=args.steady,
                              periods=args.periods or 10)
    elif args.rtol is not None:
        from converters.methods.base import DEFAULT_METHOD
        if args.h_fraction is not None or args.method != DEFAULT_METHOD:
            raise ParameterError("--rtol chooses the method and its step; give either --rtol or "
                                 + ("--h-fraction" if args.h_fraction is not None else f"--method {args.method}"))
        ensemble = ModelSweep(args.model, args.control, base, steady=args.steady, rtol=float(args.rtol),
                              metrics=_extra(metrics))
    else:
        ensemble = ModelSweep(args.model, args.control, base, method=args.method,
                              h_fraction=1.0 / 200.0 if args.h_fraction is None else args.h_fraction, steady=args.steady,
                              periods=args.periods or 50, metrics=_extra(metrics))
    for metric in metrics:
        if ensemble.measures.get(metric) is str:
            numeric = [k for k, t in ensemble.measures.items() if t is not str]
            raise ParameterError(f"--metric must be numeric: one of {', '.join(numeric)} or one on demand; got "
                                 f"{metric!r}")
    # each spec's value in its metric's unit (vout_mean<3V had been refused: "the parameter takes no unit")
    specs = [Spec.parse(text, getattr(ensemble, "units", {})) for text in args.spec]
    return ensemble, points, metrics, specs


def _extra(metrics: list) -> tuple:
    """The metrics that are not a standard measure (columns on demand)."""
    from converters.sweeps.ensemble import on_demand
    return tuple(on_demand(metrics))


def _runs_circuits(key: str) -> bool:
    """The method runs the circuit itself (ngspice: its sweep rows are its own, through the same ModelSweep)."""
    from converters.methods.base import get_method
    return "circuit" in get_method(key).domains


def _refuse_ignored(args) -> None:
    """Every flag acts or is refused: the combinations in which one would be ignored."""
    if args.lhs is None and not args.tolerance and args.seed is not None:   # --seed 0 too: given, and would be ignored
        raise ParameterError(f"--seed sets the Latin hypercube; it does not apply without --lhs (got --seed {args.seed})")
    if not args.tolerance:
        given = [f for f, v in (("--samples", args.samples), ("--sampler", args.sampler)) if v is not None]
        given += ["--corners"] if args.corners else []
        given += ["--indices"] if args.indices else []
        if given:
            raise ParameterError(f"{given[0]} sets the tolerance study; it does not apply without --tolerance")
    from converters.methods.base import get_method
    if _runs_circuits(args.method):
        given = [f for f, v in (("--h-fraction", args.h_fraction), ("--rtol", args.rtol)) if v is not None]
        if given:
            raise ParameterError(f"{', '.join(given)} do{'es' if len(given) == 1 else ''} not apply to --method "
                                 f"{args.method} (ngspice's own transient)")
    elif not get_method(args.method).fixed_step and args.h_fraction is not None:
        raise ParameterError(f"--h-fraction sets the lcp stepper's step; it does not apply to --method {args.method} "
                             f"(exact switching; got --h-fraction {args.h_fraction})")
    if args.rtol is not None and args.periods is not None:
        raise ParameterError("--periods does not apply with --rtol (the periodic orbit is measured, whatever the "
                             f"periods; got --periods {args.periods})")
    if args.steady and not _runs_circuits(args.method) and args.periods is not None:
        raise ParameterError("--periods does not apply with --steady for lcp and event (each point is measured on its "
                             f"periodic orbit found by Newton shooting; got --periods {args.periods})")
    if args.workers is not None and args.scheduler != "local":
        raise ParameterError(f"--workers sets the local processes; it does not apply to --scheduler {args.scheduler} "
                             f"(got --workers {args.workers})")


def run(args) -> int:
    from ..io import check_output_parent; check_output_parent("--out", args.out)  # noqa: E702 (before the run)
    from converters.parallel import backend_for

    from converters.validate import quoted

    from ..sweep import run_sweep, write_summary
    ensemble, points, metrics, specs = build(args)
    check_workers(args.workers)
    if args.chunk is not None and args.chunk < 1:
        raise ParameterError(f"--chunk must be an integer >= 1; got {args.chunk}")
    backend = backend_for(args.scheduler, workers=args.workers)
    # a netlist's default folder is named by its file's stem, in the current directory (its path would nest folders)
    out = args.out or Path(f"sweep-{Path(args.model).stem if args.model.lower().endswith('.cir') else args.model}")
    if hasattr(backend, "client"):
        backend.client()                              # a scheduler that does not answer: refused before --out is made
    previous = signal.signal(signal.SIGTERM, _interrupt)          # a terminated sweep stops like an interrupted one
    try:
        result = run_sweep(ensemble, points, out, backend=backend, chunk=args.chunk, progress=not args.no_progress)
    except KeyboardInterrupt:
        from ..sweep import load_sweep
        stored = len(load_sweep(out)) if (out / "sweep.json").exists() else 0
        print(f"pcsuite: interrupted: {stored:,} of {points.size:,} points are stored in {quoted(out)}; run the same "
              "command to compute the rest", file=sys.stderr)
        return EXIT_INTERRUPTED
    finally:
        signal.signal(signal.SIGTERM, previous)
        if hasattr(backend, "close"):
            backend.close()
    plotted = metrics if points.kind == "tolerance" else metrics[0]
    title = f"{ensemble.model} ({args.method}{', steady' if args.steady else ''})"
    title += "" if points.kind == "tolerance" else f": {metrics[0]}"
    units = getattr(ensemble, "units", {})
    frame = write_summary(out, points, plotted, title, specs=specs, units=units, scope_metrics=metrics)
    failed = frame[frame["status"] != "ok"]
    # rows from rest whose last period is not yet the steady state's (their values are the transient's)
    from converters.sweeps.ensemble import NOT_SETTLED, TOO_COARSE
    unsettled = frame[(frame["status"] == "ok") & frame["message"].astype(str).str.startswith(NOT_SETTLED)]
    # rows whose orbit at 2h says the step is too coarse for their measures (as simulate warns of its own)
    coarse = frame[(frame["status"] == "ok") & frame["message"].astype(str).str.startswith(TOO_COARSE)]
    summary = {"out": str(out), "points": points.size, "stored_before": result.on_disk_before,
               "computed": result.computed, "ok": int(len(frame) - len(failed)), "failed": int(len(failed)),
               "unsettled": int(len(unsettled)), "too_coarse": int(len(coarse)),
               "wall_s": result.wall_s, "points_per_s": result.rate,
               "failures": failed["message"].value_counts().head(5).to_dict(),
               "dataset": str(out / "parts"), "summary_plot": str(out / "summary.png")}
    if (out / "summary.html").is_file() and len(points.names) == 1 and points.kind != "tolerance":
        summary["summary_scope"] = str(out / "summary.html")
    if specs or points.kind == "tolerance":
        from converters.sweeps.specs import study_summary
        summary["study"] = study_summary(frame, specs, points)
        if points.kind == "tolerance" and hasattr(ensemble, "nominal_error"):
            summary["study"]["accuracy"] = study_accuracy(ensemble, frame, [s.metric for s in specs] or metrics)
        if args.corners:
            summary["study"]["corners"] = _corners(ensemble, points, specs)
        if args.indices:
            from converters.sweeps.indices import METHOD, first_order
            summary["study"]["indices"] = {"method": METHOD, "metrics": first_order(frame, list(points.names), metrics,
                                                                                   seed=points.seed)}
    if len(unsettled):
        summary["warnings"] = [f"{len(unsettled):,} of the {summary['ok']:,} points stored as ok have not settled "
                               "(their measures are the transient's, not the steady state's; the first: "
                               f"{unsettled['message'].iloc[0]})"]
    if len(coarse):
        summary["warnings"] = [*summary.get("warnings", []),
                               f"{len(coarse):,} of the {summary['ok']:,} points stored as ok may be off by more than "
                               "the defaults promise (the first: " + str(coarse["message"].iloc[0]) + ")"]
    # no point succeeded: say so in the exit code too (1, as a failed check), not only in the counts
    code = 1 if points.size and not summary["ok"] else 0
    if args.json:
        print(json_text(summary))
        return code
    print(f"  {points.size:,} points: {summary['ok']:,} ok, {summary['failed']:,} failed "
          f"({result.on_disk_before:,} already stored, {result.computed:,} computed in {result.wall_s:.2f} s, "
          f"{result.rate:,.0f} points/s)")
    for message, count in summary["failures"].items():
        print(f"  failed x{count}: {message}")
    for warning in summary.get("warnings", []):
        print(f"pcsuite: warning: {warning}", file=sys.stderr)
    if "study" in summary:
        _print_study(summary["study"], units)
    print(f"  dataset: {quoted(summary['dataset'])}  (pandas.read_parquet)\n  plot:    {quoted(summary['summary_plot'])}")
    if "summary_scope" in summary:
        print(f"  scope:   {quoted(summary['summary_scope'])}  (pcsuite view {quoted(out)})")
    if code:
        print(f"pcsuite: no point of the sweep succeeded ({points.size:,} failed); the reasons are above",
              file=sys.stderr)
    return code


#: A tolerance study's metric is accurate enough where its error is below this fraction of its spread.
WELL_BELOW = 0.1
#: A spread (and an error) below this fraction of a metric's size is rounding: the samples do not move it.
ROUNDING_SPREAD = 1e-12


def study_accuracy(ensemble, frame, metrics) -> dict:
    """How accurate a tolerance study's metrics are against their spread: per metric, the error estimate at the
    nominal point (:meth:`~converters.sweeps.ensemble.ModelSweep.nominal_error`), the samples' standard deviation and
    their ratio; a warning where the ratio is above WELL_BELOW (every sample then moves by a good part of what
    decides the yield: the DCM boost's at h = T/200 by backward Euler read 0.6 % low with a spread of ~1 %, and the
    yield's interval excluded the exact method's)."""
    import numpy as np
    ok = frame[frame["status"] == "ok"]
    out = {"metrics": {}, "warnings": []}
    for metric, (error, how) in ensemble.nominal_error(list(dict.fromkeys(metrics))).items():
        values = ok[metric].to_numpy(dtype=float) if metric in ok else np.array([])
        spread = float(np.std(values)) if values.size > 1 else float("nan")
        size = float(np.abs(values).max(initial=0.0))
        ratio = error / spread if spread > 0 else (0.0 if error == 0 else float("inf"))
        out["metrics"][metric] = {"error": error, "spread": spread, "ratio": ratio, "how": how}
        if values.size < 2:
            # one sample has no spread to weigh the error against (--samples 1 had read "inf of its spread (nan)")
            out["metrics"][metric].update(ratio=float("nan"), samples=int(values.size))
            continue
        if spread <= ROUNDING_SPREAD * size and error <= ROUNDING_SPREAD * size:
            # a metric the toleranced parameters do not move (an ideal CCM buck's mean: D Vin, whatever L, C and R):
            # its spread is rounding, and an error at rounding is no part of it ("2.7e-15 is 0.2 of 1.3e-14")
            out["metrics"][metric]["ratio"] = float("nan")
            out["metrics"][metric]["constant"] = True
            continue
        if not ratio <= WELL_BELOW:
            out["warnings"].append(f"{metric}'s error ({error:.3g}) is {ratio:.2g} of its spread over the samples "
                                   f"({spread:.3g}): the yield may be off; use a smaller --h-fraction, --rtol or "
                                   "--method event")
    return out


#: The most corners --corners runs (2^10: ten toleranced parameters).
MAX_CORNERS = 1024


def _corners(ensemble, points, specs) -> dict:
    """The 2^k corners' rows (this process) and, per spec, the worst corner and its value."""
    import pandas as pd

    from converters.sweeps.specs import study_summary
    corners = points.corners()
    if len(corners) > MAX_CORNERS:
        raise ParameterError(f"--corners runs 2^k corners: at most {MAX_CORNERS:,} (10 tolerances); got "
                             f"{len(corners):,}")
    frame = pd.DataFrame(ensemble.rows(list(enumerate(corners))))
    found = study_summary(frame, specs, points)
    return {"count": len(corners), "passed": found["passed"], "specs": found["specs"]}


def _print_study(study: dict, units: dict) -> None:
    print(f"  yield {100 * study['yield']:.2f} % ({study['passed']:,} of {study['samples']:,} meet every spec; "
          f"{100 * study['confidence']:g} % interval {100 * study['yield_low']:.2f} to {100 * study['yield_high']:.2f} %"
          f"; {study['failed_points']:,} points failed to simulate)")
    for row in study["specs"]:
        unit = units.get(row["spec"].split("<")[0].split(">")[0], "")
        worst = ", ".join(f"{k} = {v:.6g}" for k, v in row["worst_point"].items())
        print(f"  {row['spec']}: {100 * row['fraction']:.2f} % meet it; worst {row['worst_value']:.6g}"
              f"{' ' + unit if unit not in ('', '1') else ''} at {worst}")
    for metric, a in study.get("accuracy", {}).get("metrics", {}).items():
        unit = units.get(metric, "")
        unit = f" {unit}" if unit not in ("", "1") else ""
        if a.get("constant"):
            against = f"; the samples do not move it (standard deviation {a['spread']:.2g}{unit}, rounding)"
        elif a["spread"] != a["spread"]:                                   # NaN: one sample, or none
            against = f"; {'one sample' if a.get('samples') == 1 else 'no sample'}, no spread to weigh it against"
        else:
            against = f", {a['ratio']:.2g} of its spread (standard deviation {a['spread']:.3g}{unit})"
        print(f"  accuracy: {metric} within ~{a['error']:.2g}{unit} ({a['how']}){against}")
    for warning in study.get("accuracy", {}).get("warnings", []):
        print(f"warning: {warning}", file=sys.stderr)
    if "indices" in study:
        print(f"  first-order indices ({study['indices']['method']}; 95 % half-widths):")
        for metric, found in study["indices"]["metrics"].items():
            ranked = sorted(found["S1"], key=lambda k: -found["S1"][k])
            shares = ", ".join(f"{k} {found['S1'][k]:.3f} +- {found['S1_conf'][k]:.3f}" for k in ranked)
            print(f"    {metric}: {shares} (sum {found['sum']:.3f})")
    if "corners" in study:
        c = study["corners"]
        print(f"  worst-case corners: {c['passed']} of {c['count']} meet every spec")
        for row in c["specs"]:
            worst = ", ".join(f"{k} = {v:.6g}" for k, v in row["worst_point"].items())
            print(f"    {row['spec']}: worst corner {row['worst_value']:.6g} at {worst}")


def _interrupt(signum, frame):
    raise KeyboardInterrupt
