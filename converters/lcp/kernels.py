"""Compiled small-LCP kernels (numba, cached on disk), called from the compiled step loops.

k = 1 in closed form; otherwise the previous step's active set first (it almost always still holds),
then every complementary basis by increasing size (warm-started enumeration; k <= MAX_INLINE_K). Above
MAX_INLINE_K (a Cockcroft-Walton ladder's 2N diodes) the step loops pivot from the previous step's active set
(:func:`converters.lcp.murty.solve_warm`).
"""
from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numba import njit

from ..compiled import MAX_INLINE_K  # noqa: F401 (largest k solved inline; the callers read it there)

if TYPE_CHECKING:
    import numpy.typing as npt

    FloatArray = npt.NDArray[np.float64]
    IntArray = npt.NDArray[np.int64]


@njit(cache=True, _nrt=False, inline='always')
def solve_augmented(a: FloatArray, m: int, cols: int) -> bool:
    """Gaussian elimination with partial pivoting on the m x (m + cols) augmented matrix ``a`` in place;
    the solution is left in a[:m, m:m + cols]. Returns False when the left block is (numerically) singular."""
    for col in range(m):
        piv = col
        best = abs(a[col, col])
        for r in range(col + 1, m):
            if abs(a[r, col]) > best:
                best = abs(a[r, col])
                piv = r
        if best <= 1e-300:
            return False
        if piv != col:
            for c in range(col, m + cols):
                tmp = a[col, c]
                a[col, c] = a[piv, c]
                a[piv, c] = tmp
        for r in range(col + 1, m):
            f = a[r, col] / a[col, col]
            if f != 0.0:
                for c in range(col, m + cols):
                    a[r, c] -= f * a[col, c]
    # back substitution row by row (the inner loop along a row: contiguous, vectorised), each entry's terms
    # subtracted in the same order as a column-by-column loop would
    for r in range(m - 1, -1, -1):
        for l in range(r + 1, m):
            f = a[r, l]
            for c in range(m, m + cols):
                a[r, c] -= f * a[l, c]
        d = a[r, r]
        for c in range(m, m + cols):
            a[r, c] /= d
    return True


@njit(cache=True)
def _solve_subset(M: FloatArray, q: FloatArray, mask: int, k: int, z: FloatArray, work: FloatArray) -> bool:
    """Solve M_JJ z_J = -q_J for J = bits of mask; writes z (zeros outside J); False when M_JJ is singular."""
    idx = np.empty(k, dtype=np.int64)
    m = 0
    for i in range(k):
        z[i] = 0.0
        if (mask >> i) & 1:
            idx[m] = i
            m += 1
    for r in range(m):
        for c in range(m):
            work[r, c] = M[idx[r], idx[c]]
        work[r, m] = -q[idx[r]]
    if not solve_augmented(work, m, 1):
        return False
    for r in range(m):
        z[idx[r]] = work[r, m]
    return True


@njit(cache=True)
def _feasible(M: FloatArray, q: FloatArray, z: FloatArray, k: int, eps: float) -> bool:
    for i in range(k):
        if z[i] < -eps:
            return False
        w = q[i]
        for l in range(k):
            w += M[i, l] * z[l]
        if w < -eps:
            return False
    return True


@njit(cache=True)
def solve_small_lcp(M: FloatArray, q: FloatArray, k: int, z: FloatArray, mask_prev: int, order: IntArray,
                    work: FloatArray) -> int:
    """Solve LCP(q, M) for small k in place of z; returns the active-set mask or -1 (no basis found).

    k = 1 in closed form; otherwise the previous step's active set is tried first (it almost
    always still holds), then every complementary basis by increasing size.
    """
    if k == 1:
        m = M[0, 0]
        if q[0] >= 0.0:
            z[0] = 0.0
            return 0
        if m > 0.0:
            z[0] = -q[0] / m
            return 1
        return -1
    qmax = 0.0
    for i in range(k):
        qmax = max(qmax, abs(q[i]))
    eps = 1e-12 * (1.0 + qmax)
    if mask_prev >= 0 and _solve_subset(M, q, mask_prev, k, z, work) and _feasible(M, q, z, k, eps):
        for i in range(k):
            z[i] = max(z[i], 0.0)
        return mask_prev
    for j in range(order.shape[0]):
        mask = order[j]
        if mask == mask_prev:
            continue
        if _solve_subset(M, q, mask, k, z, work) and _feasible(M, q, z, k, eps):
            for i in range(k):
                z[i] = max(z[i], 0.0)
            return mask
    return -1


@njit(cache=True)
def masks_by_size(k: int) -> IntArray:
    total = 1 << k
    order = np.empty(total, dtype=np.int64)
    m = 0
    for size in range(k + 1):
        for mask in range(total):
            bits = 0
            for i in range(k):
                bits += (mask >> i) & 1
            if bits == size:
                order[m] = mask
                m += 1
    return order
