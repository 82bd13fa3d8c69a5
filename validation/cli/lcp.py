"""``pcsuite lcp solve FILE``: solve an LCP stored in the Siconos .dat format."""
from __future__ import annotations

import sys

import numpy as np

from converters.lcp import METHOD_NAMES

from .common import given_path, integer, json_text, number


def add(sub) -> None:
    lcp = sub.add_parser("lcp", help="linear complementarity problems").add_subparsers(title="lcp commands")
    solve = lcp.add_parser("solve", help="solve an LCP stored in the Siconos .dat format")
    solve.add_argument("file", type=given_path)
    solve.add_argument("--method", default="auto", choices=list(METHOD_NAMES),
                       help="auto (default: chooses by size and structure, falls back on failure; the output "
                            "names the method that solved it), lemke, murty, enum, pgs or newton")
    solve.add_argument("--tol", type=number(_tol_range), default=1e-10, help="accepted residual, in [1e-16, 1e-2] (default 1e-10)")
    solve.add_argument("--max-iter", type=integer(1, _max_iter), default=None,
                       help="pivots, sweeps or Newton steps, in [1, 10^9] (default: per method; with auto, each "
                            "method of its plan); the solve also "
                            "stops at --time-limit (default 20 s)")
    solve.add_argument("--no-fast-paths", action="store_true",
                       help="always run the method itself: no closed form (q >= 0, k <= 2, triangular M with a "
                            "positive diagonal) answers first; to study a method's pivots, e.g. on Murty's example")
    solve.add_argument("--json", action="store_true", help="print one JSON object")
    solve.set_defaults(run=run, one_run=True)


def _tol_range() -> str:
    from converters.lcp.solve import TOL_RANGE
    return f"[{TOL_RANGE[0]:g}, {TOL_RANGE[1]:g}]"


def _max_iter() -> int:
    from converters.lcp.solve import MAX_ITER_RANGE
    return MAX_ITER_RANGE[1]


def run(args) -> int:
    from converters.lcp import read_siconos_lcp, solve_lcp
    from converters.validate import quoted
    problem = read_siconos_lcp(args.file, context="lcp solve")
    result = solve_lcp(problem.M, problem.q, method=args.method, tol=args.tol, max_iter=args.max_iter,
                       fast_paths=not args.no_fast_paths)
    if args.json:
        print(json_text({"file": str(args.file), "k": int(problem.q.shape[0]), **result.to_dict()}))
    else:
        print(f"{quoted(problem.name)}: k = {problem.q.shape[0]}, method = {result.method}, status = {result.status}, "
              f"err = {result.err:.3g}, iterations = {result.iterations}")
        print("z =", np.array2string(result.z, precision=6))
        if result.message and result.solved:
            print(result.message)
        if args.method == "enum":
            print(f"{len(result.solutions)} basic solution(s):")
            for s in result.solutions:
                print("  ", np.array2string(s, precision=6))
    if not result.solved:  # why, with the remedy: one line on stderr (also in the JSON object)
        print(f"pcsuite: lcp solve {quoted(args.file)}: {result.status}: {' '.join(result.message.split())}",
              file=sys.stderr)
    return 0 if result.solved else 1
