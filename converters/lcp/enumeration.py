"""Enumeration of all 2^k complementary bases: every basic solution of the LCP.

For each index set J (by increasing size) solve M_JJ z_J = -q_J and keep z if z >= 0 and
w = q + M z >= 0. Singular principal submatrices are skipped (their solutions, if any, are not
basic). Refuses k > 12 (4096 bases); a wall-clock ``deadline`` is checked every 64 bases.
"""
from __future__ import annotations

from itertools import combinations

import numpy as np

from ..errors import LCPError
from .result import FAILED, NO_SOLUTION, SOLVED, finish, lcp_error

MAX_K = 12


def enumerate_bases(M: np.ndarray, q: np.ndarray, *, tol: float, max_iter: int | None = None, deadline=None):
    k = q.shape[0]
    if k > MAX_K:
        raise LCPError(f"enumeration visits 2^k bases: k must be <= {MAX_K}; got k = {k}; "
                       "use method='lemke' or 'murty'")
    qscale = max(1.0, float(np.abs(q).max()))
    solutions: list[np.ndarray] = []
    visited = 0
    for size in range(k + 1):
        for subset in combinations(range(k), size):
            visited += 1
            if deadline is not None and visited % 64 == 0 and deadline.expired():
                return finish(M, q, solutions[0] if solutions else np.zeros(k), status=FAILED, iterations=visited,
                              method="enum", tol=tol, solutions=solutions,
                              message=deadline.message(f"enum (after {visited} of {2 ** k} bases)"))
            z = np.zeros(k)
            if size:
                J = list(subset)
                sub = M[np.ix_(J, J)]
                if np.linalg.cond(sub) > 1e12:
                    continue
                z[J] = np.linalg.solve(sub, -q[J])
            w = q + M @ z
            feasible_tol = 1e-9 * max(qscale, float(np.abs(z).max(initial=0.0)))
            if np.all(z >= -feasible_tol) and np.all(w >= -feasible_tol):
                z = np.maximum(z, 0.0)
                if not any(np.allclose(z, s, rtol=1e-9, atol=1e-12 * qscale) for s in solutions):
                    solutions.append(z)
    if not solutions:
        return finish(M, q, np.zeros(k), status=NO_SOLUTION, iterations=visited, method="enum", tol=tol,
                      message="enum: no complementary basis is feasible (no basic solution exists)")
    best = min(solutions, key=lambda s: float(s @ s))
    result = finish(M, q, best, status=SOLVED, iterations=visited, method="enum", tol=tol, solutions=solutions)
    if result.status == FAILED:  # the least-norm one may be ill-conditioned; take the most accurate
        best = min(solutions, key=lambda s: lcp_error(M, q, s))
        result = finish(M, q, best, status=SOLVED, iterations=visited, method="enum", tol=tol,
                        solutions=solutions)
    return result
