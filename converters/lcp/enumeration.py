"""Enumeration of all 2^k complementary bases: every basic solution of the LCP (compiled).

For each index set J (by increasing size, each size in lexicographic order) solve M_JJ z_J = -q_J and
keep z if z >= 0 and w = q + M z >= 0. Ill-conditioned principal submatrices (2-norm condition number
above 1e12) are skipped (their solutions, if any, are not basic; auto's first-solution search skips only
singular ones and lets the check judge the rest). Refuses k > 12 (4096 bases); a
wall-clock deadline is checked between slices of work, at multiples of 64 bases. :func:`run` is
resumable (see :mod:`converters.lcp.lemke`); with ``first`` it stops at the first feasible basis whose
solution passes the check, keeping none (``auto`` uses that), otherwise it lists every basic solution and
answers with the least-norm one (the most accurate one when that fails the check).
"""
from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np
from numba import njit

from . import state as S
from .kernels import solve_augmented
from .result import accepts, accepts_scaled, copy_into, mark_done, max_abs, max_abs_matrix, residual

if TYPE_CHECKING:
    import numpy.typing as npt

    FloatArray = npt.NDArray[np.float64]
    IntArray = npt.NDArray[np.int64]

MAX_K = S.ENUM_MAX_K


@njit(cache=True, _nrt=False)
def sizes(k: int, listing: bool) -> tuple[int, int]:
    """Doubles and integers of workspace: the augmented M_JJ | -q_J, M_JJ, two vectors, max|q| and max|M| and,
    when ``listing`` (every basic solution is kept), up to 2^k solutions; the index set J."""
    return _solutions_offset(k) + ((1 << k) * k if listing else 0), k


@njit(cache=True, _nrt=False)
def _solutions_offset(k: int) -> int:
    return k * (k + 1) + k * k + 2 * k + 2


def solutions(fw: np.ndarray, st: np.ndarray, k: int) -> list:
    """The basic solutions found so far, as a list of arrays (copies)."""
    o = _solutions_offset(k)
    return [fw[o + s * k:o + (s + 1) * k].copy() for s in range(int(st[S.INFO]))]


@njit(cache=True, _nrt=False)
def run(M: FloatArray, q: FloatArray, z: FloatArray, fw: FloatArray, iw: IntArray, st: IntArray, tol: float,
        budget: int, first: bool) -> bool:
    """Advance the enumeration by at most ``budget`` multiply-adds; True when finished (see ``lemke.run``).
    st[ITER] counts the visited bases, st[INFO] the solutions found."""
    k = q.shape[0]
    o = 0
    aug = fw[o:o + k * (k + 1)].reshape((k, k + 1))    # M_JJ | -q_J in its top-left m x (m + 1) block
    o += k * (k + 1)
    sub_buf = fw[o:o + k * k]
    o += k * k
    zc, w = fw[o:o + k], fw[o + k:o + 2 * k]
    o += 2 * k
    big = fw[o:o + 2]          # max|q|, max|M| for the check, read once
    o += 2
    sols = fw[o:o + (0 if first else (1 << k) * k)].reshape((0 if first else 1 << k, k))
    J = iw[:k]
    if st[S.PHASE] == S.START:
        st[S.AUX] = 0          # the size of J
        st[S.ITER] = 0         # bases visited
        st[S.INFO] = 0         # solutions found
        st[S.PHASE] = S.RUNNING
        big[0] = max_abs(q)
        big[1] = max_abs_matrix(M)
    size = st[S.AUX]
    visited = st[S.ITER]
    nsol = st[S.INFO]
    qscale = 1.0
    for i in range(k):
        qscale = max(qscale, abs(q[i]))
    while size <= k:
        visited += 1
        if visited % 64 == 0 and budget <= 0:    # the caller checks its deadline here, then calls again
            st[S.AUX] = size
            st[S.ITER] = visited - 1
            st[S.INFO] = nsol
            if nsol > 0 and not first:
                copy_into(sols[0], z)
            else:
                z[:] = 0.0
            return False
        budget -= 10 * size * size * size + k * k + 1
        if _basic_solution(M, q, J, size, zc, w, aug, sub_buf, qscale, not first):
            if first:     # auto: the first one that passes the check ends it; none is kept
                nsol += 1
                if accepts_scaled(M, q, big[0], big[1], zc, w, tol):
                    copy_into(zc, z)
                    st[S.ITER] = visited
                    st[S.INFO] = nsol
                    return mark_done(st, S.SOLVED, S.OK)
                size = _next_subset(J, size, k)
                continue
            duplicate = False
            for s in range(nsol):
                same = True
                for i in range(k):
                    if not abs(zc[i] - sols[s, i]) <= 1e-12 * qscale + 1e-9 * abs(sols[s, i]):
                        same = False
                        break
                if same:
                    duplicate = True
                    break
            if not duplicate:
                copy_into(zc, sols[nsol])
                nsol += 1
        size = _next_subset(J, size, k)
    st[S.ITER] = visited
    st[S.INFO] = nsol
    if nsol == 0:
        z[:] = 0.0
        return mark_done(st, S.NO_SOLUTION, S.NOBASIS)
    if first:     # feasible bases, none of which passed the check
        z[:] = 0.0
        return mark_done(st, S.FAILED, S.CHECK)
    best, best_norm = 0, np.inf
    for s in range(nsol):
        norm = 0.0
        for i in range(k):
            norm += sols[s, i] * sols[s, i]
        if norm < best_norm:
            best, best_norm = s, norm
    copy_into(sols[best], z)
    if accepts(M, q, z, w, tol):
        return mark_done(st, S.SOLVED, S.OK)
    best, best_err = 0, np.inf     # the least-norm one may be ill-conditioned; take the most accurate
    for s in range(nsol):
        copy_into(sols[s], zc)
        err = residual(M, q, zc, w)
        if err < best_err:
            best, best_err = s, err
    copy_into(sols[best], z)
    if accepts(M, q, z, w, tol):
        return mark_done(st, S.SOLVED, S.OK)
    return mark_done(st, S.FAILED, S.CHECK)


@njit(cache=True, _nrt=False, inline='always')
def _basic_solution(M: FloatArray, q: FloatArray, J: IntArray, m: int, z: FloatArray, w: FloatArray, aug: FloatArray,
                    sub_buf: FloatArray, qscale: float, conditioned: bool) -> bool:
    """z with z_J = -M_JJ^-1 q_J (zero elsewhere); True when it is feasible (z, w >= -1e-9 scale), then
    clipped at 0. False too when M_JJ is singular, or, with ``conditioned``, ill-conditioned (2-norm
    condition number above 1e12: an SVD per basis, :func:`condition_number`; auto's first-solution search
    goes without it, as the check on the answer judges it anyway). ``aug`` (k x (k + 1)) holds M_JJ | -q_J in
    its top-left block (solve_augmented takes the block's size: no reshape per basis)."""
    k = q.shape[0]
    if m > 0:
        if conditioned:
            sub = sub_buf[:m * m].reshape((m, m))
            for r in range(m):
                for c in range(m):
                    sub[r, c] = M[J[r], J[c]]
            if condition_number(sub, m) > 1e12:
                return False
        for r in range(m):
            for c in range(m):
                aug[r, c] = M[J[r], J[c]]
            aug[r, m] = -q[J[r]]
        if not solve_augmented(aug, m, 1):
            return False
    r = 0                       # z in one pass (J ascending): no zeroing first, which a call to memset would do
    for i in range(k):
        if r < m and J[r] == i:
            z[i] = aug[r, m]
            r += 1
        else:
            z[i] = 0.0
    zbig = 0.0
    for i in range(k):
        zbig = max(zbig, abs(z[i]))
    feasible_tol = 1e-9 * max(qscale, zbig)
    for i in range(k):
        s = 0.0
        for j in range(k):
            s += M[i, j] * z[j]
        w[i] = q[i] + s
        if not (z[i] >= -feasible_tol and w[i] >= -feasible_tol):
            return False
    for i in range(k):
        z[i] = z[i] if z[i] > 0.0 else 0.0
    return True


@njit(cache=True, _nrt=False)
def condition_number(a: FloatArray, m: int) -> float:
    """The 2-norm condition number sigma_max / sigma_min of the m x m matrix ``a`` (overwritten; inf when
    singular), by one-sided Jacobi (Hestenes): rotate pairs of columns until they are orthogonal, then the
    singular values are the column norms, each to high relative accuracy (the smallest included, which
    the condition number needs). Written here rather than np.linalg.cond because it allocates nothing (the
    methods are compiled without numba's reference counting); m <= 12, a few sweeps of m^3 work."""
    for _ in range(60):
        rotated = False
        for p in range(m - 1):
            for r in range(p + 1, m):
                alpha = beta = gamma = 0.0
                for i in range(m):
                    alpha += a[i, p] * a[i, p]
                    beta += a[i, r] * a[i, r]
                    gamma += a[i, p] * a[i, r]
                if not abs(gamma) > 1e-15 * math.sqrt(alpha * beta):
                    continue
                rotated = True
                zeta = (beta - alpha) / (2.0 * gamma)
                t = math.copysign(1.0, zeta) / (abs(zeta) + math.sqrt(1.0 + zeta * zeta))
                c = 1.0 / math.sqrt(1.0 + t * t)
                s = c * t
                for i in range(m):
                    x, y = a[i, p], a[i, r]
                    a[i, p] = c * x - s * y
                    a[i, r] = s * x + c * y
        if not rotated:
            break
    largest, smallest = 0.0, np.inf
    for j in range(m):
        norm = 0.0
        for i in range(m):
            norm += a[i, j] * a[i, j]
        norm = math.sqrt(norm)
        largest = max(largest, norm)
        smallest = min(smallest, norm)
    return np.inf if smallest == 0.0 else largest / smallest


@njit(cache=True, _nrt=False, inline='always')
def _next_subset(J: IntArray, m: int, k: int) -> int:
    """Advance J (of size m) to the next index set: lexicographic within a size, then the next size.
    Returns the new size (k + 1 when every set was visited)."""
    i = m - 1
    while i >= 0 and J[i] == k - m + i:
        i -= 1
    if i >= 0:
        J[i] += 1
        for j in range(i + 1, m):
            J[j] = J[j - 1] + 1
        return m
    m += 1
    for j in range(min(m, k)):
        J[j] = j
    return m


__all__ = ["run", "sizes", "MAX_K"]
