"""The compiled step loop of Moreau-Jean time-stepping (numba, cached on disk; the scheme:
:mod:`converters.methods.moreau`)."""
from __future__ import annotations

import numpy as np
import numpy.typing as npt
from numba import njit

from ..lcp.kernels import masks_by_size, solve_small_lcp

Array = npt.NDArray[np.float64]


@njit(cache=True)
def _popp(p: npt.NDArray[np.float64], a: float) -> float:
    """Popp's magnitude N (alpha / (1 + gamma a) + beta + eta a^2) at a = |s|; p = (N, alpha, gamma, beta, eta)."""
    magnitude: float = p[0] * (p[1] / (1.0 + p[2] * a) + p[3] + p[4] * a * a)
    return magnitude


@njit(cache=True)
def run_moreau(q: Array, v: Array, impulse: Array, status: npt.NDArray[np.int64], h: float, theta: float, M: Array,
               W: Array, K: Array, C: Array, f: Array, WT: Array, V: Array, popp: Array, WN: Array, c0: Array,
               c1: Array, e: Array, start: int) -> int:
    """Steps start .. N-1 of the Moreau-Jean scheme (module docstring), in place. Per step: ``impulse`` (m + c)
    and ``status`` (m + c: 0 stick / 1 slip+ / 2 slip- for friction, 3 closed / 4 open for contacts).
    Returns the step that failed (an LCP with no solution) or -1."""
    N, n = q.shape[0] - 1, q.shape[1]
    m, c = WT.shape[0], WN.shape[0]
    k = c + 2 * m
    H = np.zeros((m + c, n))
    for i in range(m):
        H[i] = WT[i]
    for j in range(c):
        H[m + j] = WN[j]
    WH = W @ H.T                                  # n x (m + c)
    D = H @ WH                                    # Delassus matrix
    order = masks_by_size(k) if k > 0 else np.zeros(1, dtype=np.int64)
    A = np.zeros((k, k))
    b = np.zeros(k)
    z = np.zeros(k)
    work = np.empty((k, k + 1))
    lb, ub = np.zeros(m), np.zeros(m)
    active = np.zeros(c, dtype=np.bool_)
    mask = -1
    rhs = np.empty(n)
    for s in range(start, N):
        for r in range(n):
            acc = 0.0
            for l in range(n):
                acc += M[r, l] * v[s, l] - h * K[r, l] * q[s, l] - h * h * theta * (1.0 - theta) * K[r, l] * v[s, l] \
                    - h * (1.0 - theta) * C[r, l] * v[s, l]
            rhs[r] = acc + h * (theta * f[s + 1, r] + (1.0 - theta) * f[s, r])
        vfree = W @ rhs
        if k == 0:
            for r in range(n):
                v[s + 1, r] = vfree[r]
                q[s + 1, r] = q[s, r] + h * (theta * v[s + 1, r] + (1.0 - theta) * v[s, r])
            continue
        for i in range(m):
            slip_now = 0.0
            for l in range(n):
                slip_now += WT[i, l] * v[s, l]
            bound = h * _popp(popp[i], abs(slip_now - V[i]))
            lb[i], ub[i] = -bound, bound
        for j in range(c):
            gap, rate, free = c0[s, j], c1[s, j], c1[s + 1, j]
            for l in range(n):
                gap += WN[j, l] * q[s, l]
                rate += WN[j, l] * v[s, l]
                free += WN[j, l] * vfree[l]
            # the gap half a step ahead along the free motion, to second order: g + (h/2) U + (h/2)^2/2 a with the
            # relative acceleration a = (U_free - U) / h. Siconos' rule (g + h U / 2 <= 0) leaves out a: a follower
            # resting on a cam that starts to lift (U = 0, g = +1e-12 from the step's O(h^3) error) would fly
            # free for a step, be caught up and bounce (e > 0) while it should ride the cam
            active[j] = gap + 0.375 * h * rate + 0.125 * h * free <= 0.0
        # The LCP: rows 0..c-1 normal impulses, then the relays' two blocks (zeta = P - lb, mu).
        A[:, :] = 0.0
        for j in range(c):
            rate = c1[s, j]
            for l in range(n):
                rate += WN[j, l] * v[s, l]
            if not active[j]:
                A[j, j] = 1.0
                b[j] = 1.0
                continue
            free = c1[s + 1, j]
            for l in range(n):
                free += WN[j, l] * vfree[l]
            b[j] = free + e[j] * rate
            for jj in range(c):
                if active[jj]:
                    A[j, jj] = D[m + j, m + jj]
            for i in range(m):
                A[j, c + i] = D[m + j, i]
                b[j] += D[m + j, i] * lb[i]
        for i in range(m):
            free = -V[i]
            for l in range(n):
                free += WT[i, l] * vfree[l]
            b[c + i] = free
            for jj in range(c):
                if active[jj]:
                    A[c + i, jj] = D[i, m + jj]
            for ii in range(m):
                A[c + i, c + ii] = D[i, ii]
                b[c + i] += D[i, ii] * lb[ii]
            A[c + i, c + m + i] = 1.0
            A[c + m + i, c + i] = -1.0
            b[c + m + i] = ub[i] - lb[i]
        if c == 0 and m == 1:                          # one relay: the clipped stick impulse
            stick = -(b[0] - D[0, 0] * lb[0]) / D[0, 0]
            z[0] = min(max(stick, lb[0]), ub[0]) - lb[0]
            mask = 0
        else:
            mask = solve_small_lcp(A, b, k, z, mask, order, work)
            if mask < 0:
                return s
        for j in range(c):
            impulse[s + 1, m + j] = z[j] if active[j] else 0.0
        for i in range(m):
            impulse[s + 1, i] = lb[i] + z[c + i]
        for r in range(n):
            acc = vfree[r]
            for a in range(m + c):
                acc += WH[r, a] * impulse[s + 1, a]
            v[s + 1, r] = acc
            q[s + 1, r] = q[s, r] + h * (theta * v[s + 1, r] + (1.0 - theta) * v[s, r])
        for i in range(m):
            p = impulse[s + 1, i]
            if p > lb[i] * (1.0 - 1e-9) and p < ub[i] * (1.0 - 1e-9):
                status[s + 1, i] = 0
            else:
                status[s + 1, i] = 2 if p > 0.0 else 1        # friction at its bound opposes the slip
        for j in range(c):
            status[s + 1, m + j] = 3 if impulse[s + 1, m + j] > 0.0 else 4
    return -1
