"""``pcsuite mech list|simulate|bifurcations MODEL``: the mechanical models (friction, impacts)."""
from __future__ import annotations

from converters.errors import ParameterError

from .common import (MAX_WORKERS, add_params, check_out, check_workers, given_path, integer, json_text, unit_of,
                     write_frame)


def add(sub) -> None:
    mech = sub.add_parser("mech", help="mechanical models: dry friction (sliding bifurcations), two blocks on a belt, "
                                       "the cam-follower with impacts, the bouncing ball")
    mech_sub = mech.add_subparsers(title="mech commands", parser_class=type(mech))

    listing = mech_sub.add_parser("list", help="the mechanical models and their parameters")
    listing.add_argument("--json", action="store_true")
    listing.set_defaults(run=run_list, no_time_limit=True)

    sim = mech_sub.add_parser("simulate", help="simulate a mechanical model and write its trajectory")
    sim.add_argument("model")
    add_params(sim)
    from converters.methods.base import load_methods
    METHODS = load_methods()
    mechanical = {key: cls for key, cls in METHODS.items() if "mechanical" in cls.domains}
    sim.add_argument("--method", default="event", choices=list(mechanical),
                     help="; ".join(f"{key}: {cls.description}" for key, cls in mechanical.items()))
    sim.add_argument("--h", default=None, help="moreau: step in s (default 1/2000 of the period); event: output spacing")
    span = sim.add_mutually_exclusive_group()
    span.add_argument("--t-end", default=None, help="duration in s")
    span.add_argument("--periods", type=integer(1), default=None,
                      help="duration in forcing periods (autonomous models: in their time unit; default 20)")
    sim.add_argument("--out", type=given_path, default=None, help="trajectory file, .csv or .parquet")
    sim.add_argument("--json", action="store_true", help="print one JSON summary object")
    sim.set_defaults(run=run_simulate, one_run=True)

    bif = mech_sub.add_parser("bifurcations", help="sliding bifurcations (friction), or the diagram of a model along "
                                                   "a parameter (stick-slip: the section, cam-follower: impact phases)")
    bif.add_argument("model")
    add_params(bif)
    bif.add_argument("--param", required=True, metavar="NAME=START:STOP", help="the parameter path, e.g. omega=2.85:2.95")
    bif.add_argument("--points", type=integer(0, lambda: MAX_POINTS), default=None,
                     help="values of the brute-force diagram (default: 0 for friction, 60 otherwise)")
    bif.add_argument("--workers", type=integer(1, MAX_WORKERS), default=None, help="processes for the diagram (default: every core)")
    bif.add_argument("--diagram", type=given_path, default=None, help="write the diagram to FILE.png or FILE.svg")
    bif.add_argument("--json", action="store_true", help="print one JSON object")
    bif.set_defaults(run=run_bifurcations, no_time_limit=True)


def run_list(args) -> int:
    from converters.models.mechanics import MECHANICAL_MODELS
    data = {name: {"title": m.title, "states": list(m.state_names),
                   "parameters": {p.name: {"default": p.default, "unit": p.unit, "doc": p.doc, "range": p.range_text()}
                                  for p in m.parameters}} for name, m in MECHANICAL_MODELS.items()}
    if args.json:
        print(json_text(data))
        return 0
    for name, m in MECHANICAL_MODELS.items():
        print(f"{name}: {m.title}  (states: {', '.join(m.state_names)})")
        for p in m.parameters:
            print(f"    {p.name:<8} {p.default:>10g} {p.unit:<8} {p.doc}  range {p.range_text()}")
    print("methods: event (exact, event-driven), moreau (Moreau-Jean time-stepping)")
    return 0


def _duration(model, p, t_end, periods) -> float:
    from converters.validate import parse_value
    if t_end is not None:
        value = parse_value("t_end", t_end)
        if not value > 0.0:
            raise ParameterError(f"t_end must be positive (> 0 s); got {value!r}")
        return value
    if periods is not None and not periods >= 1:
        raise ParameterError(f"periods must be an integer >= 1; got {periods!r}")
    return (periods or 20) * model.time_scale(p)


def run_simulate(args) -> int:
    import time
    from dataclasses import replace

    from converters.methods.base import get_method
    from converters.models.mechanics import get_mechanical
    from converters.params import parse_assignments
    from converters.simulate import simulate
    from converters.validate import parse_value
    check_out(args.out)
    clock = time.perf_counter()
    model = get_mechanical(args.model)
    p = model.resolve(parse_assignments(args.params))
    t_end = _duration(model, p, args.t_end, args.periods)
    scale = model.time_scale(p)
    h = None if args.h is None else parse_value("h", args.h)
    if h is not None and not 0.0 < h <= 0.05 * scale:
        raise ParameterError(f"h must be in (0, {0.05 * scale:.3g}] s (at most 1/20 of the model's time scale); got {h:g}")
    cls = get_method(args.method)
    method = cls.from_options(step=h or (model.default_h(p) if cls.fixed_step else None))
    run = simulate(model.problem(p, t_end), method)
    run = replace(run, labels=model.labels(p))
    summary = {"model": model.name, "method": args.method, "options": {**method.options(), "params": p},
               "steps": int(run.steps), "wall_s": time.perf_counter() - clock, **model.summary(run, p)}
    if args.out is not None:
        write_frame(run.to_pandas(["time", *model.state_names, *model.signal_names, "mode"]), args.out,
                    meta={"model": model.name, "method": run.method, "params": p,
                          "units": {"time": "s", "note": "SI units of each state and signal (m, m/s, N, rad)"}})
    if args.json:
        print(json_text(summary))
    else:
        print(f"{model.name} ({args.method}): {summary['steps']} {method.counts} in "
              f"{summary['wall_s']:.3f} s; events: " + ", ".join(f"{k} {v}" for k, v in summary["events"].items()))
        print("modes (last time unit): " + ", ".join(f"{k} {v:.3f}" for k, v in summary["mode_fractions"].items()))
        if args.out is not None:
            from converters.validate import quoted
            print(f"wrote {quoted(args.out)}")
    return 0


#: The diagram's values, at most, and what one value's row keeps (its samples or impacts), generously.
MAX_POINTS = 100_000
BYTES_PER_VALUE = 50_000


def run_bifurcations(args) -> int:
    from ..io import check_output_file; check_output_file("--diagram", args.diagram)  # noqa: E702 (before the run)
    import numpy as np

    from converters.models.mechanics import get_mechanical
    from converters.params import parse_assignments

    from ..bifurcation import parse_path
    from ..io import atomic_write_bytes
    from converters.analysis.mechanics import impact_phase_diagram, sliding_study, two_block_diagram
    from ..mechanics_plots import diagram_figure
    name, start, stop = parse_path(args.param)
    model = get_mechanical(args.model)
    params = parse_assignments(args.params)
    if name in params:              # which value was meant? (the path would silently win)
        raise ParameterError(f"{name} is both swept (--param) and fixed (-p); give it once")
    if args.diagram is not None and args.diagram.suffix.lower() not in (".png", ".svg"):
        raise ParameterError(f"--diagram must end in .png or .svg; got {str(args.diagram)!r}")
    points = args.points if args.points is not None else (0 if model.sliding and args.diagram is None else 60)
    # without a sliding study (friction's continuation), the diagram is the whole answer: it needs points
    low = 2 if args.diagram is not None or not model.sliding else 0
    if not (isinstance(points, int) and low <= points <= MAX_POINTS):
        raise ParameterError(f"--points must be an integer in [{low}, {MAX_POINTS}]"
                             + ("" if low == 0 or args.diagram is not None else
                                f" for the {args.model} (its study is the brute-force diagram)") + f"; got {points!r}")
    check_workers(args.workers)
    if args.workers is not None and (points == 0 or args.workers < 1):
        raise ParameterError(f"--workers must be >= 1 and needs the diagram (--points >= 2); got --workers {args.workers}"
                             f" with {points} points")
    from converters.limits import check_memory
    check_memory(f"the diagram: {points} values", points * BYTES_PER_VALUE, remedy="fewer --points")
    if not model.diagram:
        from converters.models.mechanics import MECHANICAL_MODELS
        raise ParameterError(f"the {model.title} has no bifurcations to follow; MODEL must be one of "
                             f"{', '.join(n for n, m in MECHANICAL_MODELS.items() if m.diagram)}")
    from converters.analysis.continuation import check_path
    spec = {p.name: p for p in model.parameters}
    if name not in spec:
        raise ParameterError(f"--param must name a parameter of {model.key} ({', '.join(spec)}); got {name!r}")
    check_path(name, start, stop, spec[name].low, spec[name].high, spec[name].low_open, spec[name].high_open)
    if model.diagram == "impacts" and name != model.sweep:
        raise ParameterError(f"the {model.name}'s diagram is against {model.sweep}; got --param {name}")
    for value in (start, stop):
        model.resolve({**params, name: value})
    out, study, rows = {}, None, None
    if model.sliding:
        study = sliding_study(model.name, params, name, start, stop, progress=not args.json)
        out = study.to_dict()
    values = np.linspace(start, stop, points) if points else np.empty(0)
    if points:
        if model.diagram == "stroboscopic":
            from converters.analysis.mechanics import friction_diagram
            rows = friction_diagram(params, name, values, workers=args.workers, progress=not args.json)
        elif model.diagram == "section":
            rows = two_block_diagram(params, name, values, workers=args.workers, progress=not args.json)
        else:
            rows = impact_phase_diagram(params, values, h_fraction=2.5e-4, workers=args.workers,
                                        progress=not args.json)
        out.setdefault("model", model.name)
        out.setdefault("param", name)
        out["diagram"] = _diagram_summary(model, rows)
    if args.diagram is not None:
        atomic_write_bytes(args.diagram, diagram_figure(model, name, rows, study, args.diagram.suffix.lower().lstrip(".")))
        out["diagram"]["file"] = str(args.diagram)
    if args.json:
        print(json_text(out))
        return 0
    if study is not None:
        unit = unit_of(model, name)
        print(f"{model.name} along {name} = {start:g} .. {stop:g}{unit} (continuation on the event method's exact map, "
              f"{study.wall_s:.1f} s); " + "; ".join(study.notes))
        for b in study.bifurcations:
            print(f"  {b.kind:<18} {name} = {b.value:.7g}{unit} (+- {b.width:.1g}, orbit of period {b.period})  "
                  f"{b.detail}")
        for branch in out["branches"]:
            if branch["message"]:
                print(f"  period-{branch['period']} branch: {branch['message']}")
    if rows is not None:
        print(f"diagram: {len(rows)} values; " + out["diagram"]["text"])
    if args.diagram is not None:
        from converters.validate import quoted
        print(f"wrote {quoted(args.diagram)}")
    return 0


def _diagram_summary(model, rows) -> dict:
    import numpy as np
    if rows and hasattr(rows[0], "samples"):                      # stroboscopic attractors
        from converters.analysis.bifurcation import aperiodic_onset, period_windows
        windows = period_windows(rows)
        return {"kind": "stroboscopic", "windows": windows, "aperiodic_onset": aperiodic_onset(rows),
                "errors": sum(bool(r.error) for r in rows),
                "text": ", ".join(f"period {w['period']} on {w['first']:.4g}..{w['last']:.4g}" for w in windows
                                  if w["count"] >= 3)}
    counts = [int(r.times.size) for r in rows]
    distinct = [int(np.unique(np.round(r.states[:, 1 if r.states.shape[1] > 2 else 0], 5)).size) if r.times.size else 0
                for r in rows]
    chattering = [bool(np.any(np.diff(np.sort(r.times)) < 1e-3 * (r.times.max() - r.times.min() + 1e-300)))
                  if r.times.size > 2 else False for r in rows]
    return {"kind": "section", "values": [r.value for r in rows], "events": counts, "distinct_points": distinct,
            "clustered": chattering, "errors": sum(bool(r.error) for r in rows),
            "text": f"{sum(counts)} section points; periodic (<= 8 distinct points) at "
                    f"{sum(1 for d in distinct if 0 < d <= 8)} of {len(rows)} values"}
