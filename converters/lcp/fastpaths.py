"""Closed-form answers for the LCPs met most often in time-stepping: q >= 0, k = 1, k = 2 (compiled).

:func:`closed_form` tries one rule and returns True with z filled when it applies; the caller's residual
check on the original problem still judges the answer.
"""
from __future__ import annotations

import numpy as np
from numba import njit

from . import state as S

#: The rules in the order they are tried; :func:`closed_form` takes the index.
RULES = S.CLOSED_FORM_RULES


@njit(cache=True, _nrt=False)
def closed_form(M, q, rule, z):
    """Rule 0 (trivial): q >= 0, z = 0 (the least-norm solution); 1 (scalar): k = 1 with M > 0,
    z = max(0, -q/M); 2 (pair): k = 2, the four complementary bases in order of size, the least-norm
    feasible one. Fills z and returns True when the rule applies."""
    k = q.shape[0]
    if rule == 0:
        for i in range(k):
            if not q[i] >= 0.0:
                return False
        z[:] = 0.0
        return True
    if rule == 1:
        if k != 1 or not M[0, 0] > 0.0:
            return False
        v = -q[0] / M[0, 0]
        z[0] = v if v > 0.0 else 0.0
        return True
    if rule == 2 and k == 2:
        return _pair(M, q, z)
    return False


@njit(cache=True, _nrt=False)
def _pair(M, q, z):
    scale = 1e-12 * (1.0 + max(abs(q[0]), abs(q[1])))
    m_big = max(max(abs(M[0, 0]), abs(M[0, 1])), max(abs(M[1, 0]), abs(M[1, 1])))
    det = M[0, 0] * M[1, 1] - M[0, 1] * M[1, 0]
    found = False
    best0 = best1 = 0.0
    for candidate in range(4):
        if candidate == 0:
            a, b = 0.0, 0.0
        elif candidate == 1:
            if not M[0, 0] > 0.0:
                continue
            a, b = -q[0] / M[0, 0], 0.0
        elif candidate == 2:
            if not M[1, 1] > 0.0:
                continue
            a, b = 0.0, -q[1] / M[1, 1]
        else:
            if not abs(det) > 1e-14 * (m_big * m_big):
                continue
            a = (-q[0] * M[1, 1] + q[1] * M[0, 1]) / det
            b = (-q[1] * M[0, 0] + q[0] * M[1, 0]) / det
        w0 = q[0] + (M[0, 0] * a + M[0, 1] * b)
        w1 = q[1] + (M[1, 0] * a + M[1, 1] * b)
        if a >= -scale and b >= -scale and w0 >= -scale and w1 >= -scale:
            a = a if a > 0.0 else 0.0
            b = b if b > 0.0 else 0.0
            if not found or a * a + b * b < best0 * best0 + best1 * best1:
                found, best0, best1 = True, a, b
    if found:
        z[0] = best0
        z[1] = best1
    return found


def trivial(M: np.ndarray, q: np.ndarray):
    """q >= 0: z = 0 (None when the rule does not apply)."""
    return _apply(M, q, 0)


def scalar(M: np.ndarray, q: np.ndarray):
    """k = 1 with M > 0: z = max(0, -q/M) (None when the rule does not apply)."""
    return _apply(M, q, 1)


def pair(M: np.ndarray, q: np.ndarray):
    """k = 2: the least-norm feasible complementary basis (None when none is feasible or k != 2)."""
    return _apply(M, q, 2)


def _apply(M, q, rule):
    M, q = np.ascontiguousarray(M, dtype=float), np.ascontiguousarray(q, dtype=float)
    z = np.zeros(q.shape[0])
    return z if closed_form(M, q, rule, z) else None
