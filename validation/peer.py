"""The Siconos peer collection: what Siconos expects of its own solvers, and our solvers run on it.

``EXPECTED_FAILURES`` transcribes the expected-failure list of Siconos' test suite (peer README),
restricted to the solvers we also have (Siconos Lemke, enumeration, Murty, PGS and Newton-FB map
to ours; CPG, RPGS, Latin, Newton-min and Bard have no counterpart here). ``DIFFERENCES`` explains
every place where our outcome differs from Siconos' expectation (measured with tol = 1e-6).
"""
from __future__ import annotations

import os
import time
from pathlib import Path

import numpy as np

from converters.lcp import read_siconos_lcp, solve_lcp
from converters.lcp.enumeration import MAX_K

METHODS = ("lemke", "murty", "enum", "pgs", "newton")
PEER_TOL = 1e-6

EXPECTED_FAILURES: dict[str, tuple[str, ...]] = {
    "enum_fails": ("pgs",),
    "CPS_1": (),                       # Newton-min and Newton-FB in Siconos; see DIFFERENCES
    "CPS_2": ("pgs", "murty"),
    "CPS_3": ("lemke", "murty", "enum", "pgs"),  # every solver except CPG and the Newton variants
    "CPS_4": ("pgs", "murty"),
    "CPS_4bis": ("pgs", "murty"),
    "Pang_isolated_sol_perturbed": ("enum", "lemke"),
}
# Siconos' Newton-FB is expected to fail on CPS_1; kept apart so the table can show it.
SICONOS_NEWTON_FB_FAILS = {"CPS_1"}

_ZERO_DIAGONAL = ("PGS needs M_ii > 0 and this M has zero diagonal entries; ours refuses with "
                  "'failed' where Siconos' PGS is not listed as failing (it is not expected to "
                  "reach err <= 1e-6 either: the update z_i - w_i / M_ii is undefined)")
_SINGULAR_PRINCIPAL = ("M is not a P-matrix (a zero principal minor): our Murty is textbook "
                       "principal pivoting on M_JJ and stops at the first singular M_JJ; Siconos' "
                       "Murty is a least-index rule on a Lemke-type tableau with an artificial variable")
DIFFERENCES: dict[tuple[str, str], str] = {
    ("CPS_1", "newton"): ("ours succeeds where Siconos' Newton-FB fails: at z_i = w_i = 0 we take the "
                          "generalized Jacobian along (1, 1) and fall back to the gradient when the "
                          "Newton step is not a descent direction; residual checked (err ~1e-12)"),
    ("CPS_3", "enum"): ("ours succeeds where Siconos' enumeration fails: we scan all 16 bases with a "
                        "scale-relative feasibility tolerance and find 3 basic solutions; residual 0"),
    ("Pang_isolated_sol", "murty"): _SINGULAR_PRINCIPAL,
    ("Pang_isolated_sol", "pgs"): _ZERO_DIAGONAL,
    ("inf_sol_perturbed", "murty"): _SINGULAR_PRINCIPAL,
    ("inf_sol_perturbed", "pgs"): _ZERO_DIAGONAL,
    ("Pang_isolated_sol_perturbed", "murty"): ("no solution exists: w1 = -1e-4 - z2 - z3 < 0 for every "
                                               "z >= 0, so the least reachable err is 7.07e-5 > 1e-6"),
    ("Pang_isolated_sol_perturbed", "pgs"): ("no solution exists (see murty); besides, M has zero "
                                             "diagonal entries"),
    ("Pang_isolated_sol_perturbed", "newton"): ("no solution exists: w1 = -1e-4 - z2 - z3 < 0 for every "
                                                "z >= 0; Newton-FB stalls at err = 7.07e-5, the least "
                                                "reachable, and reports max_iterations"),
    ("tobenna", "murty"): _SINGULAR_PRINCIPAL,
    ("tobenna", "pgs"): _ZERO_DIAGONAL,
    ("tobenna", "newton"): ("M + M^T is indefinite (least eigenvalue -4.1e3), so M is not a P-matrix "
                            "and the Fischer-Burmeister merit has non-solution stationary points; "
                            "ours stalls at one (Siconos' Newton-FB, with another Jacobian choice "
                            "and line search, does not). Lemke solves it (err 5e-12)"),
    ("mmc", "enum"): f"k = 26 > {MAX_K}: our enumeration refuses k > {MAX_K} by specification",
    ("tobenna", "enum"): f"k = 40 > {MAX_K}: our enumeration refuses k > {MAX_K} by specification",
    ("mmc", "lemke"): ("Siconos lists only its LU-update Lemke variant as failing here; our tableau "
                       "Lemke solves it (err ~1e-14)"),
}


def siconos_expects_failure(name: str, method: str) -> bool:
    if method == "newton" and name in SICONOS_NEWTON_FB_FAILS:
        return True
    return method in EXPECTED_FAILURES.get(name, ())


def ours_differs(name: str, method: str) -> str:
    """Explanation of a difference from Siconos' expectation, or '' when there is none on record."""
    return DIFFERENCES.get((name, method), "")


#: The collection as shipped with pcsuite (Apache-2.0 data, see its README and LICENSE).
PEER_DIR = Path(__file__).with_name("data") / "siconos-lcp"


def peer_directory() -> Path:
    """$PCSUITE_PEER_DIR when set (another copy of the collection), else the copy shipped in
    ``validation/data/siconos-lcp``."""
    env = os.environ.get("PCSUITE_PEER_DIR")
    path = Path(env) if env else PEER_DIR
    if not (path.is_dir() and any(path.glob("lcp_*.dat"))):
        from converters.errors import ParameterError
        raise ParameterError(f"PCSUITE_PEER_DIR must name a directory holding lcp_*.dat files; got {str(path)!r}")
    return path


#: Solved by every method before the timed runs: numba compiles (or loads from its cache) each solver at its
#: first call, and a table's time measures the solve. A pair the one-call solve answers, and a problem on which
#: Lemke ends on a ray (the sliced solve and its proof of non-existence).
WARM_UP = ((np.array([[2.0, 1.0], [1.0, 2.0]]), np.array([-3.0, -3.0])), (-np.eye(3), -np.ones(3)))


def warm_up(methods=METHODS, tol=PEER_TOL) -> None:
    """Load every solver the table runs, as the table calls them, before anything is timed."""
    for M, q in WARM_UP:
        for method in methods:
            solve_lcp(M, q, method=method, tol=tol, fast_paths=False)


def solver_table(problems, methods=METHODS, tol=PEER_TOL):
    """Run every solver on every (name, M, q); one row per pair with status, err, iterations, time (the solvers
    loaded first: :func:`warm_up`)."""
    warm_up(methods, tol)
    rows = []
    for name, M, q in problems:
        for method in methods:
            start = time.perf_counter()
            if method == "enum" and M.shape[0] > MAX_K:
                status, err, iterations, message = "refused", float("nan"), 0, f"k = {M.shape[0]} > {MAX_K}"
            else:
                result = solve_lcp(M, q, method=method, tol=tol, fast_paths=False)
                status, err, iterations, message = result.status, result.err, result.iterations, result.message
            rows.append({"problem": name, "k": M.shape[0], "method": method, "status": status, "err": err,
                         "iterations": iterations, "time_s": time.perf_counter() - start, "message": message})
    return rows


def peer_table(directory: Path):
    """The solver table on the peer collection, with Siconos' expectation and our explanation."""
    problems = [read_siconos_lcp(f) for f in sorted(directory.glob("lcp_*.dat"))]
    rows = solver_table([(p.name, p.M, p.q) for p in problems])
    for row in rows:
        expected_fail = siconos_expects_failure(row["problem"], row["method"])
        row["siconos"] = "fails" if expected_fail else "solves"
        ours_ok = row["status"] == "solved"
        row["differs"] = ours_ok == expected_fail
        row["explanation"] = ours_differs(row["problem"], row["method"]) if row["differs"] else ""
    return rows
