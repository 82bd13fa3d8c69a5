"""Compiled hot loop of the theta stepper (numba, cached on disk): the per-step LCS update.

Everything here works on plain arrays; the problem/method objects stay in Python.
"""
from __future__ import annotations

import numpy as np
from numba import njit

from ..lcp.kernels import MAX_INLINE_K, _masks_by_size, solve_small_lcp

#: Status codes returned by :func:`run_steps`.
OK, NEEDS_GENERAL_SOLVER, NO_SOLUTION = 0, 1, 2


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


