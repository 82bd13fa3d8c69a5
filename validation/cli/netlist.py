"""``pcsuite netlist CONVERTER``: the generated ngspice netlist, as a file ngspice runs on its own
(``ngspice -b FILE.cir`` prints the ``.meas`` mean and ripple of vout over the last 10 periods)."""
from __future__ import annotations

from converters.errors import ParameterError

from .common import add_params, given_path


def add(sub) -> None:
    net = sub.add_parser("netlist", help="the ngspice netlist of a converter (runs alone: ngspice -b FILE.cir)")
    net.add_argument("converter")
    add_params(net)
    from netlists.build import CONTROL_NETLISTS
    net.add_argument("--control", default="pwm", choices=list(CONTROL_NETLISTS),
                     help="the loop written with the circuit: boost smc (sliding mode), buck voltage-mode (the ramp "
                          "comparator), peak-current, valley-current, current-loop or voltage-loop (a clocked latch)")
    net.add_argument("--t-end", default=None, help="duration in s (default 500 periods)")
    net.add_argument("--steady", action="store_true",
                     help="start on the periodic orbit (the LCP stepper's, by Newton shooting) instead of at rest")
    net.add_argument("--out", type=given_path, default=None, help="write FILE.cir (atomically) instead of printing")
    net.set_defaults(run=run, no_time_limit=True)             # it writes a netlist; ngspice runs it elsewhere


def run(args) -> int:
    from ..io import check_output_file; check_output_file("--out", args.out)  # noqa: E702 (before the run)
    from converters.models import get_model
    from converters.params import parse_assignments
    from converters.run import STEADY_TOL, check_steady, duration, make_method, steady_state
    from netlists import model_netlist, standalone

    from ..io import atomic_write_text
    from ..spice import check_spice_memory
    if args.out is not None and args.out.suffix.lower() not in (".cir", ".sp", ".net"):
        raise ParameterError(f"--out must end in .cir, .sp or .net; got {str(args.out)!r}")
    from converters.models import DEFAULT_CONTROL, is_netlist
    if is_netlist(args.converter) and args.control != DEFAULT_CONTROL:
        raise ParameterError(f"--control applies to the built-in converters; a netlist states its own drives (got "
                             f"--control {args.control} with {str(args.converter)!r})")
    model = get_model(args.converter, args.control)
    p = model.resolve(parse_assignments(args.params))
    x0 = None
    if args.steady:
        check_steady(model, p)
        # the orbit to simulate's own tolerance: ngspice runs from it at a RELTOL of 1e-3 (a SEPIC at rho = 1 -
        # 3.6e-6 resolves it to 2.6e-10 in double precision, and 1e-10 had refused it)
        x0 = steady_state(model, p, make_method(model, p, "lcp"), tol=STEADY_TOL,
                          remedy="write it from rest without --steady").x0
    t_end = duration(model, p, args.t_end)
    if model.periodic(p) and t_end < model.period(p):
        raise ParameterError(f"t_end must be at least one switching period ({model.period(p):.3g} s): the netlist's "
                             f".meas lines measure the last periods; got {t_end:.3g} s")
    netlist = model_netlist(model, p, t_end, x0=x0)
    output = model.output if is_netlist(args.converter) else "vout"          # a file's output, as SPICE names it
    check_spice_memory(netlist, remedy="a shorter --t-end")      # refused here, not when ngspice runs out of memory
    if model.periodic(p):
        text = standalone(netlist, model.period(p), model.state_names, output=output)
    else:                # a switching law of its own (the sliding-mode boost): over its summary's window
        text = standalone(netlist, float("nan"), model.state_names, window=(model.window_start(p, 0.0, t_end), t_end),
                          output=output)
    if args.out is None:
        print(text, end="")
    else:
        atomic_write_text(args.out, text)
        from converters.validate import quoted
        print(f"wrote {quoted(args.out)} (run it: ngspice -b {quoted(args.out)})")
    return 0
