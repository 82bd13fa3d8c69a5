"""``pcsuite netlist CONVERTER``: print the generated ngspice netlist."""
from __future__ import annotations

from .common import add_params


def add(sub) -> None:
    net = sub.add_parser("netlist", help="print the ngspice netlist of a converter")
    net.add_argument("converter")
    add_params(net)
    net.add_argument("--control", default="pwm", choices=["pwm", "smc", "voltage-mode"],
                     help="boost: smc (sliding-mode control); buck: voltage-mode (the ramp comparator)")
    net.add_argument("--t-end", default=None, help="duration in s (default 500 periods)")
    net.set_defaults(run=run)


def run(args) -> int:
    from converters.models import get_model
    from converters.params import parse_assignments
    from converters.run import duration
    from netlists import model_netlist
    model = get_model(args.converter, args.control)
    p = model.resolve(parse_assignments(args.params))
    print(model_netlist(model, p, duration(model, p, args.t_end)).text, end="")
    return 0
