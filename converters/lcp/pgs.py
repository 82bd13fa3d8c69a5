"""Projected Gauss-Seidel (with optional over-relaxation omega in (0, 2)).

z_i <- max(0, z_i - omega * w_i / M_ii), sweeping i = 1..k. Converges for symmetric positive
definite M; needs M_ii > 0. A wall-clock ``deadline`` is checked at every sweep.
"""
from __future__ import annotations

import numpy as np

from .result import FAILED, MAX_ITERATIONS, SOLVED, accepts, finish


def pgs(M: np.ndarray, q: np.ndarray, *, tol: float, max_iter: int, omega: float = 1.0, deadline=None):
    k = q.shape[0]
    diag = np.diag(M).copy()
    if np.any(diag <= 0.0):
        i = int(np.flatnonzero(diag <= 0.0)[0])
        return finish(M, q, np.zeros(k), status=FAILED, iterations=0, method="pgs", tol=tol,
                      message=f"pgs needs a positive diagonal; M[{i},{i}] = {diag[i]:g}; try method='lemke'")
    with np.errstate(over="ignore", invalid="ignore"):  # divergence is detected and reported below
        return _sweeps(M, q, diag, tol, max_iter, omega, deadline)


def _sweeps(M, q, diag, tol, max_iter, omega, deadline):
    k = q.shape[0]
    z = np.zeros(k)
    rows = [M[i] for i in range(k)]
    for sweep in range(1, max_iter + 1):
        if deadline is not None and deadline.expired():
            return finish(M, q, z, status=FAILED, iterations=sweep - 1, method="pgs", tol=tol,
                          message=deadline.message(f"pgs (after {sweep - 1} sweeps)"))
        for i in range(k):
            wi = q[i] + rows[i] @ z
            z[i] = max(0.0, z[i] - omega * wi / diag[i])
        if not np.all(np.isfinite(z)):
            return finish(M, q, np.zeros(k), status=FAILED, iterations=sweep, method="pgs", tol=tol,
                          message=f"pgs diverged at sweep {sweep} (M is not symmetric positive definite); "
                                  "try method='lemke'")
        if accepts(M, q, z, tol):
            return finish(M, q, z, status=SOLVED, iterations=sweep, method="pgs", tol=tol)
    return finish(M, q, z, status=MAX_ITERATIONS, iterations=max_iter, method="pgs", tol=tol,
                  message=f"pgs reached max_iter ({max_iter}) sweeps (converges only for symmetric "
                          "positive definite M); try method='lemke'")
