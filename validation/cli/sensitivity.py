"""``pcsuite sensitivity CONVERTER|FILE.cir [-p ...] [--metric SIGNAL] [--param NAME ...] [--check]``: the exact
sensitivities of a steady-state mean to every parameter, ranked (:mod:`converters.analysis.sensitivity`), with a
finite-difference check beside them on request and a tornado chart."""
from __future__ import annotations

import math

from .common import add_params, add_unstable_option, circuit_notes, given_path, on_exact_orbit, orbit_stability


def add(sub) -> None:
    from converters.models import CONTROLS
    cmd = sub.add_parser("sensitivity", help="exact sensitivities of a steady-state mean to every parameter (implicit "
                                             "function theorem on the period map), ranked")
    cmd.add_argument("converter")
    add_params(cmd)
    cmd.add_argument("--control", default="pwm", choices=list(CONTROLS),
                     help="the control law around the converter (default pwm: open loop)")
    cmd.add_argument("--metric", default="vout",
                     help="the signal whose mean over the period is differentiated: vout (default), a state (iL, vC) "
                          "or a signal (v(NODE), i(ELEMENT) of a netlist), optionally with .mean")
    cmd.add_argument("--param", action="append", default=None, metavar="NAME",
                     help="a parameter to differentiate by (repeatable; default: every parameter with a value that "
                          "keeps the switching period)")
    cmd.add_argument("--check", action="store_true",
                     help="also take each derivative by a five-point central difference of the steady state (four "
                          "orbits per parameter, Newton to 1e-11) and print it and the difference beside")
    add_unstable_option(cmd)
    cmd.add_argument("--plot", type=given_path, default=None,
                     help="write a tornado chart of the normalised sensitivities to FILE.png or FILE.svg")
    cmd.add_argument("--json", action="store_true",
                     help="print one JSON object (the metric, its value and unit, each parameter's derivative and "
                          "normalised sensitivity, the parameters not taken and why)")
    cmd.set_defaults(run=on_exact_orbit("sensitivity", run), one_run=True)


def run(args) -> int:
    from converters.analysis.sensitivity import finite_difference, sensitivities
    from converters.errors import ParameterError
    from converters.params import parse_assignments
    from converters.run import resolve_model
    from converters.validate import quoted

    from ..io import atomic_write_bytes, check_output_file
    check_output_file("--plot", args.plot)
    if args.plot is not None and args.plot.suffix.lower() not in (".png", ".svg"):
        raise ParameterError(f"--plot must end in .png or .svg; got {str(args.plot)!r}")
    model = resolve_model(args.converter, args.control)
    params = parse_assignments(args.params)
    found = sensitivities(model, params, metric=args.metric, parameters=args.param)
    summary = {"converter": model.key, **found.as_dict(),
               **orbit_stability("sensitivities", model.key, found.multipliers, model.period(model.resolve(params)),
                                  args.unstable, found.orbit_warning, found.border),
               **circuit_notes(model, params)}
    checks = {}
    if args.check:
        for row in found.rows:
            fd = finite_difference(model, params, args.metric, row.parameter, tol=1e-11)
            checks[row.parameter] = (fd, abs(fd - row.derivative) * abs(row.value) / max(abs(found.metric_value), 1e-300))
        for entry in summary["sensitivities"]:
            fd, difference = checks[entry["parameter"]]
            entry["finite_difference"], entry["normalised_difference"] = fd, difference
    if args.plot is not None:
        from ..plots import tornado_figure
        atomic_write_bytes(args.plot, tornado_figure(found, model.key, args.plot.suffix.lower().lstrip(".")))
        summary["plot"] = str(args.plot)
    if args.json:
        from .common import json_text
        print(json_text(summary))
        return 0
    unit = found.metric_unit
    print(f"{model.key}: exact sensitivities of mean({found.signal}) = {found.metric_value:.9g} {unit} on the periodic "
          f"{'steady state' if summary['stable'] else 'orbit (unstable)'} (event method; Floquet spectral radius "
          f"{summary['spectral_radius']:.6g}), ranked by "
          "|(p/m) dm/dp|")
    header = f"  {'parameter':<12} {'value':>12} {'unit':<5} {'dm/dp':>14} {'(p/m) dm/dp':>12}"
    if checks:
        header += f" {'finite diff.':>14} {'difference':>10}"
    print(header)
    for row in found.rows:
        normalised = row.normalised(found.metric_value)
        line = (f"  {row.parameter:<12} {row.value:>12.6g} {row.unit:<5} {row.derivative:>14.7g} "
                f"{normalised if math.isfinite(normalised) else float('nan'):>12.6g}")
        if checks:
            fd, difference = checks[row.parameter]
            line += f" {fd:>14.7g} {difference:>10.1e}"
        print(line)
    if checks:
        print("  difference: |exact - finite difference| x p/m (the normalised sensitivity's)")
    for name, why in found.skipped.items():
        print(f"  not taken: {name}: {why}")
    if args.plot is not None:
        print(f"wrote {quoted(args.plot)}")
    return 0
