"""``pcsuite lcp solve FILE``: solve an LCP stored in the Siconos .dat format."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from converters.lcp import SOLVERS


def add(sub) -> None:
    lcp = sub.add_parser("lcp", help="linear complementarity problems").add_subparsers(title="lcp commands")
    solve = lcp.add_parser("solve", help="solve an LCP stored in the Siconos .dat format")
    solve.add_argument("file", type=Path)
    solve.add_argument("--method", default="lemke", choices=list(SOLVERS))
    solve.add_argument("--tol", type=float, default=1e-10)
    solve.add_argument("--max-iter", type=int, default=None)
    solve.add_argument("--json", action="store_true", help="print one JSON object")
    solve.set_defaults(run=run)


def run(args) -> int:
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
