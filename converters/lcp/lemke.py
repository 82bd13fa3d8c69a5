"""Lemke's complementary pivoting algorithm with lexicographic degeneracy resolution (compiled).

Tableau form of  w - M z - d z0 = q  with covering vector d = 1. The columns of the initial
identity (the w-columns) hold B^-1 at every pivot, so the lexicographic ratio test compares the
rows (rhs, B^-1 row) / pivot-column entry (the tableau is stored condensed: see :func:`run`); this
makes every pivot sequence finite even on degenerate problems (a wall-clock deadline, checked
between slices of work, bounds the run). Ray
termination (no positive entry in the entering column) means no solution was found; for
copositive-plus M it proves that none exists.

:func:`run` is resumable: it works in the caller's workspace and returns when its work budget is spent
(see :mod:`converters.lcp.engine`), so one compiled loop serves both the one-call solve and a solve that
checks a time limit between slices.
"""
from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numba import njit

from . import state as S
from .result import accepts_scaled, mark_done, max_abs, max_abs_finite, max_abs_matrix

if TYPE_CHECKING:
    import numpy.typing as npt

    FloatArray = npt.NDArray[np.float64]
    IntArray = npt.NDArray[np.int64]

PIVOT_TOL = 1e-13


@njit(cache=True, _nrt=False)
def sizes(k: int) -> tuple[int, int]:
    """Doubles and integers of workspace: the k x (k + 2) condensed tableau, w, the pivot row and max|q|, max|M|
    (for the check at the end); the basis, the nonbasic variables, every variable's place, candidate rows and
    lexicographic scratch."""
    return k * (k + 2) + k + (k + 2) + 2, 6 * k + 2


@njit(cache=True, _nrt=False)
def run(M: FloatArray, q: FloatArray, z: FloatArray, fw: FloatArray, iw: IntArray, st: IntArray, tol: float,
        max_iter: int, budget: int, pivot_tol: float) -> bool:
    """Advance Lemke on LCP(q, M) by at most ``budget`` multiply-adds; returns True when finished (status,
    outcome and iterations in ``st``), False when the budget is spent (z then holds the current iterate).

    The tableau is kept condensed: the k + 1 nonbasic columns and the rhs (half the work of the full
    k x (2k + 2) tableau per pivot, with the same numbers: a basic variable's column is a unit vector,
    which the lexicographic test reads without storing it). Variables: w_i = i, z_i = k + i, z0 = 2k."""
    k = q.shape[0]
    n = k + 2
    z0, rhs = 2 * k, k + 1
    C = fw[:k * n].reshape((k, n))
    w = fw[k * n:k * n + k]
    prow = fw[k * n + k:k * n + k + n]
    big = fw[k * n + k + n:k * n + k + n + 2]       # max|q|, max|M|: read once, while setting up
    basis, nonbasic, place = iw[:k], iw[k:2 * k + 1], iw[2 * k + 1:4 * k + 2]
    cand, rem = iw[4 * k + 2:5 * k + 2], iw[5 * k + 2:6 * k + 2]
    have_row = False
    row = 0
    if st[S.PHASE] == S.START:
        st[S.ITER] = 0
        nonneg = True
        for i in range(k):
            if not q[i] >= 0.0:
                nonneg = False
        for i in range(k):
            for j in range(k):
                C[i, j] = -M[i, j]
        if st[S.CALLER_CHECKS] == 0:       # only _done's own check reads them
            big[0] = max_abs(q)
            big[1] = max_abs_matrix(M)
        if nonneg:
            z[:] = 0.0
            return _done(M, q, z, w, big, st, tol, S.SOLVED, S.OK)
        for i in range(k):
            C[i, k] = -1.0
            C[i, rhs] = q[i]
            basis[i] = i            # w_i basic in row i
            place[i] = -1 - i       # basic: -1 - row; nonbasic: its column
            nonbasic[i] = k + i     # z_i nonbasic in column i
            place[k + i] = i
            cand[i] = i
        nonbasic[k] = z0
        place[z0] = k
        # First pivot: z0 enters (its column is -1 in every row), and the lexicographically least row of
        # (q_i, e_i) leaves: the least q_i, and of the rows tied with it (to the tolerance of _lexmin_rows) the
        # last, since e_i of a later row is lexicographically smaller. _lexmin_rows' very comparisons, without
        # its divisions by -(-1) and its walk through the k unit vectors.
        low = np.inf
        for i in range(k):
            if q[i] < low:
                low = q[i]
        bound = low + 1e-11 * max(1.0, abs(low))
        for i in range(k):
            if q[i] <= bound:
                row = i
        st[S.AUX] = z0
        st[S.PHASE] = S.RUNNING
        have_row = True
    entering = st[S.AUX]
    iterations = st[S.ITER]
    while True:
        col = place[entering]
        if not have_row:
            scale = max(1.0, max_abs_finite(C[:, col])[0])    # four running maxima (result.largest): one had
            #                                                    been a maxsd chain, 1/8 of Lemke's time at k = 9
            nc = 0
            for i in range(k):
                if C[i, col] > pivot_tol * scale:
                    cand[nc] = i
                    nc += 1
            if nc == 0:
                _z_from_basis(C, place, k, z, False)
                st[S.ITER] = iterations
                return _done(M, q, z, w, big, st, tol, S.NO_SOLUTION, S.RAY)
            best = np.inf
            ratios = w              # free until the end (the check fills it): each candidate's ratio, once
            for t in range(nc):
                ratio = C[cand[t], rhs] / C[cand[t], col]
                ratios[t] = ratio
                if ratio < best:
                    best = ratio
            # z0 leaves as soon as it ties for the minimum ratio: that ends the algorithm. Else the rows tied
            # with the minimum to _lexmin_rows' tolerance (wider) are its first level, found in the same pass (the
            # ratios not divided again); more than one go on to its next levels.
            bound = best + 1e-12 * max(1.0, abs(best))
            tie = best + 1e-11 * max(1.0, abs(best))
            row = -1
            m = 0
            for t in range(nc):
                if ratios[t] <= tie:
                    c = cand[t]
                    if basis[c] == z0 and ratios[t] <= bound:
                        row = c
                        break
                    rem[m] = c
                    m += 1
            if row < 0:
                if m == 1:
                    row = rem[0]
                else:
                    for t in range(m):
                        cand[t] = rem[t]
                    row = _lexmin_rows(C, place, cand, m, col, k, 1.0, rem)
        have_row = False
        leaving = basis[row]
        _pivot(C, row, col, prow)
        basis[row] = entering
        place[entering] = -1 - row
        nonbasic[col] = leaving
        place[leaving] = col
        iterations += 1
        if leaving == z0:
            _z_from_basis(C, place, k, z, True)
            st[S.ITER] = iterations
            return _done(M, q, z, w, big, st, tol, S.SOLVED, S.OK)
        entering = leaving + k if leaving < k else leaving - k  # the complement of what left
        if iterations >= max_iter:
            _z_from_basis(C, place, k, z, False)
            st[S.ITER] = iterations
            return _done(M, q, z, w, big, st, tol, S.MAX_ITERATIONS, S.MAXIT)
        budget -= k * n
        if budget <= 0:    # the caller checks its deadline here, then calls again
            st[S.AUX] = entering
            st[S.ITER] = iterations
            _z_from_basis(C, place, k, z, False)
            return False


@njit(cache=True, _nrt=False, inline='always')
def _done(M: FloatArray, q: FloatArray, z: FloatArray, w: FloatArray, big: FloatArray, st: IntArray, tol: float,
          status: int, outcome: int) -> bool:
    """Record the end; a claimed solution must pass the check on this (normalised) problem (max|q| and max|M| in
    ``big``, read while setting up), unless the caller checks it on the original one (st[CALLER_CHECKS]: the
    one-call solve, which hands a failure to the sliced solve, where Lemke checks and auto goes on)."""
    if status == S.SOLVED and st[S.CALLER_CHECKS] == 0 and not accepts_scaled(M, q, big[0], big[1], z, w, tol):
        status, outcome = S.FAILED, S.CHECK
    return mark_done(st, status, outcome)


@njit(cache=True, _nrt=False, inline='always')
def _inverse_entry(C: FloatArray, place: IntArray, r: int, j: int) -> float:
    """Entry (r, j) of B^-1: the column of w_j, a unit vector while w_j is basic."""
    p = place[j]
    if p >= 0:
        return C[r, p]
    return 1.0 if -1 - p == r else 0.0


@njit(cache=True, _nrt=False)
def _lexmin_rows(C: FloatArray, place: IntArray, rows: IntArray, nrows: int, col: int, k: int, sign: float,
                 rem: IntArray) -> int:
    """Row of rows[:nrows] whose vector (rhs, B^-1 row) / (sign * entry) is lexicographically smallest."""
    rhs = k + 1
    for t in range(nrows):
        rem[t] = rows[t]
    n = nrows
    for j in range(k + 1):
        low = np.inf
        for t in range(n):
            r = rem[t]
            v = (C[r, rhs] if j == 0 else _inverse_entry(C, place, r, j - 1)) / (sign * C[r, col])
            if v < low:
                low = v
        bound = low + 1e-11 * max(1.0, abs(low))
        m = 0
        for t in range(n):
            r = rem[t]
            v = (C[r, rhs] if j == 0 else _inverse_entry(C, place, r, j - 1)) / (sign * C[r, col])
            if v <= bound:
                rem[m] = r
                m += 1
        n = m
        if n == 1:
            break
    return rem[0]


@njit(cache=True, _nrt=False)
def _pivot(C: FloatArray, row: int, col: int, prow: FloatArray) -> None:
    """Exchange the basic variable of ``row`` with the nonbasic one of ``col``: the leaving variable takes
    the column, which becomes B^-1's new column (the full tableau's numbers, operation for operation).

    The pivot row is written whole to ``prow`` before the other rows read it, and column ``col`` apart: a
    vector load of entries just stored one by one waits for each store (store forwarding fails), which costs
    a third of Lemke's time on small tableaux (the numbers are the same: prow[col] = p / p = 1 gives C[i, col] - f
    = 0, which 0 - f / p then replaces)."""
    n = C.shape[1]
    p = C[row, col]
    inv = 1.0 / p
    for j in range(n):
        prow[j] = C[row, j] / p
    for j in range(n):
        C[row, j] = prow[j]
    C[row, col] = inv
    for i in range(C.shape[0]):
        f = C[i, col]
        if i != row and f != 0.0:
            for j in range(n):
                C[i, j] -= f * prow[j]
            C[i, col] = 0.0 - f * inv


@njit(cache=True, _nrt=False, inline='always')
def _z_from_basis(C: FloatArray, place: IntArray, k: int, z: FloatArray, clip: bool) -> None:
    """z from the tableau: z_i is the rhs of its row when basic (place[k + i] = -1 - row), else 0. Each entry
    written once, by value (zeroing z first compiles to a call to memset, whose masked stores the loads of z
    just after, in the check, cannot be forwarded from: they wait for the stores to reach the cache)."""
    for i in range(k):
        p = place[k + i]
        if p < 0:
            v = C[-1 - p, k + 1]
            z[i] = (v if v > 0.0 else 0.0) if clip else v
        else:
            z[i] = 0.0


__all__ = ["run", "sizes"]
