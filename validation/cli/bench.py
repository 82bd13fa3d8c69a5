"""``pcsuite bench``: the speed-accuracy trade-off of every method and the stability map."""
from __future__ import annotations

from .common import given_path, integer, json_text


def _max_periods() -> int:
    from ..bench import PERIODS_RANGE
    return PERIODS_RANGE[1]


def add(sub) -> None:
    bench = sub.add_parser("bench", help="the speed-accuracy trade-off of every method and the stability map")
    bench.add_argument("--quick", action="store_true",
                       help="trade-off: the DCM cases, a short sweep (the form make report measures itself)")
    bench.add_argument("--no-spice", action="store_true", help="leave ngspice out")
    bench.add_argument("--only", choices=["tradeoff", "stability"], default=None)
    bench.add_argument("--periods", type=integer(2, _max_periods), default=None,
                       help="trade-off: periods per run (default 200)")
    bench.add_argument("--out", type=given_path, default=None, help="output directory (default reports/bench)")
    bench.add_argument("--json", action="store_true", help="print the summary as JSON")
    bench.set_defaults(run=run)


def run(args) -> int:
    from ..bench import check_out; check_out(args.out)  # noqa: E702 (refused before the run)
    from ..bench import DEFAULT_OUT, run_bench
    from converters.errors import ParameterError
    if args.only == "stability":
        given = [flag for flag, value in (("--periods", args.periods), ("--quick", args.quick or None)) if value is not None]
        if given:
            raise ParameterError(f"{' and '.join(given)} set{'s' if len(given) == 1 else ''} the trade-off; it does not "
                                 "apply with --only stability (the stability map runs its fixed cases)")
    out = args.out or DEFAULT_OUT
    summary = run_bench(out, quick=args.quick, spice=not args.no_spice, only=args.only, periods=args.periods,
                        progress=not args.json)
    if args.json:
        print(json_text(summary))
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
    from converters.validate import quoted
    print(f"wrote {quoted(out)}/")
    return 0
