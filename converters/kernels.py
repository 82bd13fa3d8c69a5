"""Compiled hot loops (numba, cached on disk): the per-step LCS update and small inline LCPs.

Everything here works on plain arrays; the problem/method objects stay in Python.
"""
from __future__ import annotations

import numpy as np
from numba import njit

#: Status codes returned by :func:`run_steps`.
OK, NEEDS_GENERAL_SOLVER, NO_SOLUTION = 0, 1, 2
#: Largest k solved inline (by warm-started enumeration of complementary bases).
MAX_INLINE_K = 8


@njit(cache=True)
def _solve_subset(M, q, mask, k, z, work):
    """Solve M_JJ z_J = -q_J for J = bits of mask by Gaussian elimination with partial pivoting.

    Writes z (zeros outside J); returns False when M_JJ is (numerically) singular.
    """
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
    for col in range(m):
        piv = col
        best = abs(work[col, col])
        for r in range(col + 1, m):
            if abs(work[r, col]) > best:
                best = abs(work[r, col])
                piv = r
        if best <= 1e-300:
            return False
        if piv != col:
            for c in range(col, m + 1):
                tmp = work[col, c]
                work[col, c] = work[piv, c]
                work[piv, c] = tmp
        for r in range(col + 1, m):
            f = work[r, col] / work[col, col]
            for c in range(col, m + 1):
                work[r, c] -= f * work[col, c]
    for r in range(m - 1, -1, -1):
        s = work[r, m]
        for c in range(r + 1, m):
            s -= work[r, c] * z[idx[c]]
        z[idx[r]] = s / work[r, r]
    return True


@njit(cache=True)
def _feasible(M, q, z, k, eps):
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
def solve_small_lcp(M, q, k, z, mask_prev, order, work):
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
def run_steps(which, Phi, Gamma, H, C, F, M, x, u, y, start, inline):
    """Advance x, u, y from row ``start`` to the end; step j uses the matrix set ``which[j]``.

    Returns (status, j): OK when every step is done, NEEDS_GENERAL_SOLVER at the first step j
    whose LCP is too large or degenerate for the inline solver (the caller solves it and resumes
    at j + 1), NO_SOLUTION when a scalar LCP provably has none.
    """
    n = x.shape[1]
    k = u.shape[1]
    if not inline:
        return NEEDS_GENERAL_SOLVER, start
    if k == 1:
        return _run_scalar(which, Phi, Gamma, H, C, F, M, x, u, y, start)
    xf = np.empty(n)
    q = np.empty(k)
    z = np.empty(k)
    work = np.empty((k, k + 1))
    order = _masks_by_size(k)
    mask = 0
    for j in range(start, which.shape[0]):
        s = which[j]
        for i in range(n):
            acc = Gamma[s, i]
            for l in range(n):
                acc += Phi[s, i, l] * x[j, l]
            xf[i] = acc
        for i in range(k):
            acc = F[s, i]
            for l in range(n):
                acc += C[s, i, l] * xf[l]
            q[i] = acc
        mask = solve_small_lcp(M[s], q, k, z, mask, order, work)
        if mask < 0:
            return NEEDS_GENERAL_SOLVER, j
        for i in range(n):
            acc = xf[i]
            for l in range(k):
                acc += H[s, i, l] * z[l]
            x[j + 1, i] = acc
        for i in range(k):
            acc = q[i]
            for l in range(k):
                acc += M[s, i, l] * z[l]
            y[j + 1, i] = acc
            u[j + 1, i] = z[i]
    return OK, which.shape[0]


@njit(cache=True)
def _run_scalar(which, Phi, Gamma, H, C, F, M, x, u, y, start):
    """k = 1: the step LCP is z = max(0, -q/M) inline (the common case of one diode)."""
    n = x.shape[1]
    xf = np.empty(n)
    for j in range(start, which.shape[0]):
        s = which[j]
        q = F[s, 0]
        for i in range(n):
            acc = Gamma[s, i]
            for l in range(n):
                acc += Phi[s, i, l] * x[j, l]
            xf[i] = acc
            q += C[s, 0, i] * acc
        m = M[s, 0, 0]
        if q >= 0.0:
            z = 0.0
        elif m > 0.0:
            z = -q / m
        else:
            return NO_SOLUTION, j
        for i in range(n):
            x[j + 1, i] = xf[i] + H[s, i, 0] * z
        u[j + 1, 0] = z
        y[j + 1, 0] = q + m * z
    return OK, which.shape[0]


@njit(cache=True)
def _masks_by_size(k):
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
