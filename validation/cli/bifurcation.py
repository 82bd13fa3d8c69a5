"""``pcsuite bifurcation CONVERTER --control voltage-mode --param NAME=START:STOP``: periodic orbits followed
along a parameter, their bifurcations, and the brute-force diagram."""
from __future__ import annotations

import sys

from converters.errors import ParameterError

from .common import MAX_WORKERS, add_params, check_workers, given_path, integer, json_text, unit_of


def add(sub) -> None:
    from converters.models import CONTROLS
    bif = sub.add_parser("bifurcation", help="periodic orbits along a parameter: continuation, bifurcations, "
                                             "brute-force diagram")
    bif.add_argument("converter")
    add_params(bif)
    bif.add_argument("--control", default=None, choices=list(CONTROLS),
                     help="the control law (default voltage-mode: the ramp comparator, -p A=.. -p Vref=.. -p VL=.. "
                          "-p VU=.. [-p latch=1]; a netlist FILE.cir states its own drives)")
    bif.add_argument("--param", required=True, metavar="NAME=START:STOP",
                     help="the parameter path, e.g. Vin=20:36 (SPICE suffixes allowed)")
    bif.add_argument("--max-period", type=integer(1), default=8,
                     help="follow period doublings up to orbits of this many switching periods (default 8)")
    bif.add_argument("--points", type=integer(0), default=800,
                     help="values of the brute-force diagram (default 800; 0: continuation only)")
    bif.add_argument("--transient", type=integer(0), default=None, help="periods dropped at each diagram value (default 200)")
    bif.add_argument("--record", type=integer(2), default=None, help="periods kept at each diagram value (default 64)")
    bif.add_argument("--diagram-method", default=None, choices=["lcp", "event"],
                     help="lcp: the compiled stepper, theta 0.5, h = T/500 (default, fast); event: exact, ~5x slower")
    bif.add_argument("--state", default=None, help="the state drawn (default: the model's output, e.g. vC)")
    bif.add_argument("--workers", type=integer(1, MAX_WORKERS), default=None, help="processes for the diagram (default: every core)")
    bif.add_argument("--diagram", type=given_path, default=None, help="write the diagram to FILE.png or FILE.svg")
    bif.add_argument("--json", action="store_true", help="print one JSON object (bifurcations, branches, diagram)")
    bif.set_defaults(run=run, no_time_limit=True)


def run(args) -> int:
    from ..io import check_output_file; check_output_file("--diagram", args.diagram)  # noqa: E702 (before the run)
    from converters.params import parse_assignments

    from ..bifurcation import diagram_figure, parse_path, run_study
    from ..io import atomic_write_bytes
    if args.diagram is not None and args.diagram.suffix.lower() not in (".png", ".svg"):
        raise ParameterError(f"--diagram must end in .png or .svg; got {str(args.diagram)!r}")
    if args.diagram is not None and args.points == 0:
        raise ParameterError("--diagram needs the brute-force diagram: --points must be >= 1; got 0")
    diagram_flags = [flag for flag, value in (("--transient", args.transient), ("--record", args.record),
                                              ("--diagram-method", args.diagram_method), ("--state", args.state),
                                              ("--workers", args.workers))
                     if value is not None]
    if args.points == 0 and diagram_flags:
        raise ParameterError(f"{', '.join(diagram_flags)} set{'s' if len(diagram_flags) == 1 else ''} the brute-force "
                             "diagram; --points 0 asks for continuation only")
    check_workers(args.workers)
    name, start, stop = parse_path(args.param)
    params = parse_assignments(args.params)
    if name in params:              # which value was meant? (the path would silently win)
        raise ParameterError(f"{name} is both swept (--param) and fixed (-p); give it once")
    from converters.models import is_netlist
    control = args.control or ("pwm" if is_netlist(args.converter) else "voltage-mode")
    study = run_study(args.converter, control, params, name, start, stop,
                      max_period=args.max_period, points=args.points,
                      transient=200 if args.transient is None else args.transient,
                      record=64 if args.record is None else args.record,
                      diagram=args.diagram_method or "lcp", state=args.state, workers=args.workers,
                      progress=not args.json)
    if args.diagram is not None:
        atomic_write_bytes(args.diagram, diagram_figure(study, args.diagram.suffix.lower().lstrip(".")))
    summary = study.to_dict()
    if args.diagram is not None:
        summary["diagram"]["file"] = str(args.diagram)
    if args.json:
        print(json_text(summary))
    else:
        _print(study, summary, args)
    return 0


def _print(study, summary: dict, args) -> None:
    unit = unit_of(study.model, study.name)
    print(f"{study.model.key} along {study.name} = {study.start:g} .. {study.stop:g}{unit}: continuation (event "
          f"method, exact Jacobians) in {study.continuation_s:.2f} s")
    for branch in summary["branches"]:
        stable = ", ".join(f"{a:.6g}..{b:.6g}" for a, b in branch["stable"]) or "nowhere"
        born = f", born at {branch['born_at']:.7g}" if branch["born_at"] is not None else ""
        print(f"  period-{branch['period']} orbit: {branch['orbits']} orbits{born}; stable on {stable}"
              + (f" ({branch['message']})" if branch["message"] else ""))
    print("bifurcations:" + ("" if study.bifurcations else " none along the path"))
    for b in study.bifurcations:
        mults = ", ".join(f"{m.real:.4f}{m.imag:+.4f}j" if abs(m.imag) > 1e-9 else f"{m.real:.4f}" for m in b.multipliers)
        change = (f"{'stable' if b.stable_before else 'unstable'} -> {'stable' if b.stable_after else 'unstable'}")
        # a bracket the search could not shrink (no orbit found inside it) is said, not only its width
        unrefined = b.located_by[b.located_by.index("bracket left"):].rstrip(")") if "bracket left" in b.located_by \
            else ""
        print(f"  {b.kind:<17} {study.name} = {b.value:.7g}{unit} (+- {b.width:.1g})  period {b.period}  multipliers "
              f"[{mults}]  {change}" + (f"  {b.detail}" if b.detail else "")
              + (f"  (not refined: {unrefined})" if unrefined else ""))
    feigenbaum = summary["feigenbaum"]
    if feigenbaum.get("ratios"):
        print(f"  doubling intervals shrink by {', '.join(f'{r:.3f}' for r in feigenbaum['ratios'])}; the cascade "
              f"accumulates near {feigenbaum['accumulation']:.5g} (Feigenbaum extrapolation)")
    diagram = summary.get("diagram")
    if diagram:
        onset = diagram["aperiodic_onset"]
        # isolated values without a period (fewer than aperiodic_onset's run) are no onset, but not periodic either
        isolated = sum(w["count"] for w in diagram["windows"] if w["period"] == 0)
        where = (f"aperiodic from {onset:.5g}" if onset is not None else
                 f"no aperiodic range ({isolated} isolated value{'s' if isolated != 1 else ''} without a period)"
                 if isolated else "periodic everywhere")
        unconfirmed = diagram["unconfirmed"]
        if unconfirmed:
            first = unconfirmed[0]
            values = f"{len(unconfirmed)} value{'s' if len(unconfirmed) > 1 else ''}"
            print(f"pcsuite: warning: the diagram's period at {values} is not the stable orbit's the continuation "
                  f"holds there (the first: {first['period']} at {first['value']:.6g}, where period "
                  f"{first['stable_period']} is stable): the diagram's step may "
                  "not resolve the attractor; use --diagram-method event", file=sys.stderr)
        print(f"brute-force diagram: {diagram['points']} values ({diagram['method']}) in {diagram['wall_s']:.1f} s; "
              + where
              + (f"; {diagram['errors']} values failed" if diagram["errors"] else ""))
        if args.diagram is not None:
            from converters.validate import quoted
            print(f"wrote {quoted(args.diagram)}")
