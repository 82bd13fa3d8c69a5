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
    except (PcsuiteError, ValueError) as exc:
        print(f"pcsuite: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="pcsuite", description="Power-converter study suite: LCP "
                                     "time-stepping of DC-DC converters cross-checked against ngspice.")
    sub = parser.add_subparsers(title="commands")

    lcp = sub.add_parser("lcp", help="linear complementarity problems").add_subparsers(title="lcp commands")
    solve = lcp.add_parser("solve", help="solve an LCP stored in the Siconos .dat format")
    solve.add_argument("file", type=Path)
    solve.add_argument("--method", default="lemke", choices=["lemke", "murty", "enum", "pgs", "newton"])
    solve.add_argument("--tol", type=float, default=1e-10)
    solve.add_argument("--max-iter", type=int, default=None)
    solve.add_argument("--json", action="store_true", help="print one JSON object")
    solve.set_defaults(run=_lcp_solve)

    report = sub.add_parser("report", help="run a suite of scenes and write the validation report")
    report.add_argument("suite", nargs="?", default="default")
    report.add_argument("--out", type=Path, default=None, help="output directory (default reports/SUITE)")
    report.set_defaults(run=_report)
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


def _report(args) -> int:
    from .report import run_section, write_report
    from .sections import SUITES
    if args.suite not in SUITES:
        raise ParameterError(
            f"SUITE must be one of {', '.join(sorted(SUITES))}; got {args.suite!r}")
    out = args.out or Path("reports") / args.suite
    from tqdm import tqdm
    sections = []
    for title, builder in tqdm(SUITES[args.suite], desc=f"report {args.suite}", unit="section", file=sys.stderr):
        sections.append(run_section(builder, title))
    index = write_report(sections, out, args.suite, options={"suite": args.suite})
    failed = [s.title for s in sections if not s.ok]
    print(f"wrote {index} ({len(sections) - len(failed)}/{len(sections)} sections pass)")
    for title in failed:
        print(f"  failed: {title}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
