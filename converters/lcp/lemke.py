"""Lemke's complementary pivoting algorithm with lexicographic degeneracy resolution.

Tableau form of  w - M z - d z0 = q  with covering vector d = 1. The columns of the initial
identity (the w-columns) hold B^-1 at every pivot, so the lexicographic ratio test compares the
rows (rhs, B^-1 row) / pivot-column entry; this makes every pivot sequence finite even on
degenerate problems (a wall-clock ``deadline``, checked at every pivot, bounds the run). Ray
termination (no positive entry in the entering column) means no solution was found; for
copositive-plus M it proves that none exists.
"""
from __future__ import annotations

import numpy as np

from .result import FAILED, MAX_ITERATIONS, NO_SOLUTION, SOLVED, finish


def lemke(M: np.ndarray, q: np.ndarray, *, tol: float, max_iter: int, pivot_tol: float = 1e-13, deadline=None):
    k = q.shape[0]
    if np.all(q >= 0.0):
        return finish(M, q, np.zeros(k), status=SOLVED, iterations=0, method="lemke", tol=tol)
    z0_col, rhs_col = 2 * k, 2 * k + 1
    tableau = np.zeros((k, 2 * k + 2))
    tableau[:, :k] = np.eye(k)
    tableau[:, k:2 * k] = -M
    tableau[:, z0_col] = -1.0
    tableau[:, rhs_col] = q
    basis = np.arange(k)  # variable index basic in each row: w_i = i, z_i = k + i, z0 = 2k

    # First pivot: z0 enters, the lexicographically most negative row (rhs/1, e_i) leaves.
    row = _lexmin_rows(tableau, np.arange(k), z0_col, k, sign=-1.0)
    entering = z0_col
    iterations = 0
    while True:
        leaving = basis[row]
        _pivot(tableau, row, entering)
        basis[row] = entering
        iterations += 1
        if leaving == z0_col:
            return _result(M, q, tableau, basis, iterations, tol, SOLVED)
        entering = leaving + k if leaving < k else leaving - k  # the complement of what left
        if iterations >= max_iter:
            return _result(M, q, tableau, basis, iterations, tol, MAX_ITERATIONS,
                           f"lemke reached max_iter ({max_iter}) pivots; raise max_iter")
        if deadline is not None and deadline.expired():
            return _result(M, q, tableau, basis, iterations, tol, FAILED,
                           deadline.message(f"lemke (after {iterations} pivots)"))
        column = tableau[:, entering]
        scale = max(1.0, np.abs(column).max())
        candidates = np.flatnonzero(column > pivot_tol * scale)
        if candidates.size == 0:
            return _result(M, q, tableau, basis, iterations, tol, NO_SOLUTION,
                           "lemke: ray termination (no solution found; for copositive-plus M none exists)")
        # z0 leaves as soon as it ties for the minimum ratio: that ends the algorithm.
        ratios = tableau[candidates, rhs_col] / column[candidates]
        best = ratios.min()
        z0_rows = candidates[(basis[candidates] == z0_col)
                             & (ratios <= best + 1e-12 * max(1.0, abs(best)))]
        row = z0_rows[0] if z0_rows.size else _lexmin_rows(tableau, candidates, entering, k)


def _lexmin_rows(tableau, rows, col, k, sign=1.0):
    """Row of ``rows`` whose vector (rhs, B^-1 row) / (sign * entry) is lexicographically smallest."""
    rhs_col = 2 * k + 1
    keys = np.column_stack([tableau[rows, rhs_col], tableau[rows, :k]]) / (sign * tableau[rows, col])[:, None]
    remaining = np.arange(rows.size)
    for j in range(keys.shape[1]):
        values = keys[remaining, j]
        low = values.min()
        remaining = remaining[values <= low + 1e-11 * max(1.0, abs(low))]
        if remaining.size == 1:
            break
    return rows[remaining[0]]


def _pivot(tableau, row, col):
    tableau[row] /= tableau[row, col]
    factors = tableau[:, col].copy()
    factors[row] = 0.0
    tableau -= np.outer(factors, tableau[row])


def _result(M, q, tableau, basis, iterations, tol, status, message=""):
    k = q.shape[0]
    z = np.zeros(k)
    values = tableau[:, 2 * k + 1]
    for row, var in enumerate(basis):
        if k <= var < 2 * k:
            z[var - k] = values[row]
    z = np.maximum(z, 0.0) if status == SOLVED else z
    return finish(M, q, z, status=status, iterations=iterations, method="lemke", tol=tol, message=message)


__all__ = ["lemke", "FAILED"]
