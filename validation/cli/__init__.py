"""The ``pcsuite`` command line: one module per subcommand. Bad input exits 2 with one line naming the
parameter, its valid range and the value received."""
from __future__ import annotations

import argparse
import sys

from converters.errors import PcsuiteError

from . import bench, bifurcation, compare, gdcm, gdcm_map, lcp, listing, mech, netlist, report, simulate, sweep

EXIT_BAD_INPUT = 2
#: The subcommands, in the order ``pcsuite --help`` lists them.
SUBCOMMANDS = (listing, simulate, lcp, compare, gdcm, gdcm_map, sweep, bifurcation, mech, netlist, report, bench)


def main(argv=None) -> int:
    parser = build_parser()
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


class Parser(argparse.ArgumentParser):
    """argparse with the project's one-line errors (no usage dump)."""

    def error(self, message):
        self.exit(EXIT_BAD_INPUT, f"pcsuite: error: {message}\n")


def build_parser() -> argparse.ArgumentParser:
    parser = Parser(prog="pcsuite", description="Power-converter study suite: LCP time-stepping of DC-DC "
                                                "converters cross-checked against ngspice.")
    sub = parser.add_subparsers(title="commands", parser_class=Parser)
    for command in SUBCOMMANDS:
        command.add(sub)
    return parser
