"""Murty's least-index principal pivoting method (Bard-type), finite for P-matrices.

The basis is the set J of indices with z basic. Each iteration solves M_JJ z_J = -q_J, forms
w = q + M z and flips the least index whose basic variable is negative. On P-matrices this
terminates in at most 2^k pivots (Murty's exponential examples reach that bound), so a wall-clock
``deadline`` (checked at every pivot) bounds the run.
"""
from __future__ import annotations

import numpy as np

from .result import FAILED, MAX_ITERATIONS, SOLVED, finish


def murty(M: np.ndarray, q: np.ndarray, *, tol: float, max_iter: int, deadline=None):
    k = q.shape[0]
    in_basis = np.zeros(k, dtype=bool)
    z = np.zeros(k)
    scale = 1e-12 * (1.0 + np.abs(q).max())
    for iteration in range(max_iter + 1):
        if deadline is not None and deadline.expired():
            return finish(M, q, z, status=FAILED, iterations=iteration, method="murty", tol=tol,
                          message=deadline.message(f"murty (after {iteration} pivots)"))
        z = np.zeros(k)
        if in_basis.any():
            sub = M[np.ix_(in_basis, in_basis)]
            try:
                z[in_basis] = np.linalg.solve(sub, -q[in_basis])
            except np.linalg.LinAlgError:
                return finish(M, q, z, status=FAILED, iterations=iteration, method="murty", tol=tol,
                              message="murty: singular principal submatrix (M is not a P-matrix); "
                                      "try method='lemke'")
        w = q + M @ z
        basic_values = np.where(in_basis, z, w)
        negative = np.flatnonzero(basic_values < -scale)
        if negative.size == 0:
            return finish(M, q, np.maximum(z, 0.0), status=SOLVED, iterations=iteration,
                          method="murty", tol=tol)
        if iteration == max_iter:
            break
        in_basis[negative[0]] = ~in_basis[negative[0]]
    return finish(M, q, z, status=MAX_ITERATIONS, iterations=max_iter, method="murty", tol=tol,
                  message=f"murty reached max_iter ({max_iter}) pivots (it may cycle if M is not a "
                          "P-matrix); try method='lemke'")
