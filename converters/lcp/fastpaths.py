"""Closed-form answers for the LCPs met most often in time-stepping, q >= 0, k = 1, k = 2, and for a triangular M
with a positive diagonal (compiled).

:func:`closed_form` tries one rule and returns True with z filled when it applies; the caller's residual
check on the original problem still judges the answer.
"""
from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numba import njit

from . import state as S

if TYPE_CHECKING:
    import numpy.typing as npt

    FloatArray = npt.NDArray[np.float64]

#: The rules in the order they are tried; :func:`closed_form` takes the index.
RULES = S.CLOSED_FORM_RULES


@njit(cache=True, _nrt=False, inline='always')
def closed_form(M: FloatArray, q: FloatArray, rule: int, z: FloatArray) -> bool:
    """Rule 0 (trivial): q >= 0, z = 0 (the least-norm solution); 1 (scalar): k = 1 with M > 0,
    z = max(0, -q/M); 2 (pair): k = 2, the four complementary bases in order of size, the least-norm
    feasible one; 3 (triangular): k > 2, M triangular with a positive diagonal, by substitution
    (:func:`_triangular`). Fills z and returns True when the rule applies."""
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
    if rule == 3 and k > 2:
        return _triangular(M, q, z)
    return False


@njit(cache=True, _nrt=False)
def _triangular(M: FloatArray, q: FloatArray, z: FloatArray) -> bool:
    """Rule 3: M upper or lower triangular (diagonal included) with a positive diagonal, hence a P-matrix and
    one solution, found by substitution: from the row with a single unknown on, w_i = r_i + M_ii z_i with
    r_i the row's known part, so z_i = max(0, -r_i / M_ii) (z_i = 0 when r_i >= 0, else w_i = 0). Exact in
    k^2 / 2 multiply-adds where pivoting may need 2^k - 1 pivots (Murty's examples, on which Lemke's and
    Murty's own rules are exponential). False, at the first entry that shows the rule does not apply, for
    any other M."""
    k = q.shape[0]
    for i in range(k):
        if not M[i, i] > 0.0:
            return False
    upper = True
    for i in range(1, k):
        for j in range(i):
            if M[i, j] != 0.0:
                upper = False
                break
        if not upper:
            break
    if not upper:
        for i in range(k - 1):
            for j in range(i + 1, k):
                if M[i, j] != 0.0:
                    return False
    for step in range(k):
        i = k - 1 - step if upper else step
        r = q[i]
        if upper:
            for j in range(i + 1, k):
                r += M[i, j] * z[j]
        else:
            for j in range(i):
                r += M[i, j] * z[j]
        v = -r / M[i, i]
        z[i] = v if v > 0.0 else 0.0
    return True


@njit(cache=True, _nrt=False)
def _pair(M: FloatArray, q: FloatArray, z: FloatArray) -> bool:
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


def trivial(M: np.ndarray, q: np.ndarray) -> FloatArray | None:
    """q >= 0: z = 0 (None when the rule does not apply)."""
    return _apply(M, q, 0)


def scalar(M: np.ndarray, q: np.ndarray) -> FloatArray | None:
    """k = 1 with M > 0: z = max(0, -q/M) (None when the rule does not apply)."""
    return _apply(M, q, 1)


def pair(M: np.ndarray, q: np.ndarray) -> FloatArray | None:
    """k = 2: the least-norm feasible complementary basis (None when none is feasible or k != 2)."""
    return _apply(M, q, 2)


def triangular(M: np.ndarray, q: np.ndarray) -> FloatArray | None:
    """k > 2, M upper or lower triangular with a positive diagonal: the one solution, by substitution (None when
    the rule does not apply)."""
    return _apply(M, q, 3)


def _apply(M: npt.ArrayLike, q: npt.ArrayLike, rule: int) -> FloatArray | None:
    M, q = np.ascontiguousarray(M, dtype=float), np.ascontiguousarray(q, dtype=float)
    z = np.zeros(q.shape[0])
    return z if closed_form(M, q, rule, z) else None
