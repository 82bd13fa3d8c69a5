"""``pcsuite compare CONVERTER``: the LCP time-stepper against ngspice on the same circuit."""
from __future__ import annotations

from converters.errors import ParameterError

from .common import add_params, add_spice_options, given_path, json_text, spice_options


def add(sub) -> None:
    cmp = sub.add_parser("compare", help="the LCP time-stepper against ngspice on the same circuit")
    cmp.add_argument("converter")
    add_params(cmp)
    cmp.add_argument("--h", default=None, help="LCP step in s (default T/1000)")
    cmp.add_argument("--start", choices=["steady", "rest"], default=None,
                     help="steady (default): pcsuite on its periodic orbit, ngspice to its own steady state; rest: "
                          "both from rest (default for prc)")
    cmp.add_argument("--spice-start", choices=["own", "orbit"], default="own",
                     help="with --start steady: ngspice from its own start, run until it settles (default: "
                          "independent of pcsuite), or from pcsuite's orbit (faster; a wrong orbit of pcsuite's that "
                          "ngspice does not damp stays wrong in both)")
    cmp.add_argument("--control", default="pwm", choices=list(COMPARISONS),
                     help="the control around the converter (default pwm: open loop; see simulate)")
    cmp.add_argument("--t-end", default=None, help="duration in s (sliding mode; default 30 ms)")
    add_spice_options(cmp)
    cmp.add_argument("--plot", type=given_path, default=None,
                     help="FILE.png: the overlay and residual plot; FILE.html: an interactive scope, ngspice beside "
                          "pcsuite (zoom, two cursors with the mean and RMS between them)")
    cmp.add_argument("--json", action="store_true")
    cmp.set_defaults(run=run)


def run(args) -> int:
    from ..io import check_output_file; check_output_file("--plot", args.plot)  # noqa: E702 (before the run)
    from converters.params import parse_assignments

    if args.plot is not None and args.plot.suffix.lower() not in (".png", ".html"):
        raise ParameterError(f"--plot must end in .png or .html; got {str(args.plot)!r}")
    params = parse_assignments(args.params)
    from converters.models import DEFAULT_CONTROL, is_netlist
    if is_netlist(args.converter):
        if args.control != DEFAULT_CONTROL or args.t_end is not None:
            raise ParameterError("--control and --t-end apply to the built-in converters; a netlist states its drives "
                                 "and its .tran")
        rows, metrics, header, plot, extra = _circuit(args, params)
    else:
        rows, metrics, header, plot, extra = COMPARISONS[args.control](args, params)
    passed = all(ok for _, _, _, ok in rows)
    if args.plot is not None:
        plot(args.plot)
    if args.json:
        print(json_text({**extra, "metrics": metrics, "checks": {name: ok for name, _, _, ok in rows},
                         "thresholds": {name: threshold for name, _, threshold, _ in rows}, "passed": passed}))
    else:
        print(header)
        for key, value in metrics.items():
            text = f"{value:.9g}" if isinstance(value, float) else str(value)
            print(f"  {key:<36} {text}")
        for name, value, threshold, ok in rows:
            print(f"  check {name:<30} {'pass' if ok else 'FAIL'} (threshold {threshold:g})")
        for note in extra.get("notes", []):
            print(f"  note: {note}")
        print("PASS" if passed else "FAIL")
    return 0 if passed else 1


def _circuit(args, params):
    from converters.models import get_model
    from ..circuit_compare import compare_circuit
    from ..plots import comparison_plot
    circuit = get_model(args.converter)
    p = circuit.resolve(params)
    period = circuit.period(p) if circuit.periodic(p) else circuit.default_duration(p)
    result = compare_circuit(circuit, params, h=args.h, start=args.start, spice_options=spice_options(args, period),
                             spice_start=args.spice_start)
    header = f"{result.circuit}: LCP against {result.spice.metadata['ngspice']} on the same netlist"
    return result.rows, result.metrics, header, _plot(lambda: comparison_plot(result), result, header), result.to_dict()


def _plot(png, result, title):
    """Where ``--plot`` goes: the PNG ``png()`` draws, or the scope of both runs (FILE.html)."""
    def write(path) -> None:
        if path.suffix.lower() == ".html":
            from ..scope import of_comparison, write_scope
            write_scope(of_comparison(result.lcp, result.spice, title), path)
        else:
            from ..io import atomic_write_bytes
            atomic_write_bytes(path, png())
    return write


def _clocked(args, params):
    """A converter's LCP run against ngspice, open loop or under a clocked loop (validation.compare)."""
    from converters.models import get_model

    from ..compare import compare
    from ..plots import comparison_plot
    if args.t_end is not None:
        raise ParameterError("--t-end applies to --control smc; a clocked comparison runs the model's periods")
    model = get_model(args.converter, args.control)
    options = spice_options(args, model.period(model.resolve(params)))
    result = compare(args.converter, params, h=args.h, start=args.start, spice_options=options, control=args.control,
                     spice_start=args.spice_start)
    header = f"{result.converter}: LCP against {result.spice.metadata['ngspice']}"
    return result.rows, result.metrics, header, _plot(lambda: comparison_plot(result), result, header), result.to_dict()


def _smc(args, params):
    """The sliding-mode boost against its ngspice netlist (validation.smc), from rest."""
    if args.start is not None:
        raise ParameterError(f"--start applies to PWM comparisons; the sliding-mode comparison starts from rest "
                             f"(got --start {args.start})")
    from converters.models import get_model
    from converters.validate import parse_value

    from ..defaults import THRESHOLDS
    from ..smc import compare_smc, smc_checks, smc_plot
    model = get_model(args.converter, "smc")
    t_end = parse_value("t_end", args.t_end) if args.t_end is not None else 30e-3
    c = compare_smc(params, t_end=t_end, h=args.h,
                    spice_options=spice_options(args, model.period(model.resolve(params))))
    rows = smc_checks(c.metrics, THRESHOLDS["smc"], c.params, t_end)
    header = f"boost (sliding mode): LCP against {c.spice.metadata['ngspice']}"
    return (rows, c.metrics, header, _plot(lambda: smc_plot(c), c, header),
            {"converter": "boost", "control": "smc", "params": c.params})


#: The comparison of each control --control takes: the sliding-mode boost from rest, the clocked loops whose period
#: starts on (the diode's turn-off inside it) on their orbit. The voltage-mode buck's and valley current mode's
#: periods start off: the turn-off instant the comparison reads then falls on the period's edge, where it is not
#: defined; their ngspice runs are checked in their tests (bifurcation, closed-loop spice).
COMPARISONS = {"pwm": _clocked, "smc": _smc, "peak-current": _clocked, "current-loop": _clocked,
               "voltage-loop": _clocked}
