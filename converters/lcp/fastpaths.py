"""Closed-form answers for the LCPs met most often in time-stepping: q >= 0, k = 1, k = 2.

Each returns ``None`` when it does not apply (the general solvers then take over), and the
caller's residual check still judges the answer.
"""
from __future__ import annotations

import numpy as np


def trivial(M: np.ndarray, q: np.ndarray):
    """q >= 0: z = 0 is a solution (the least-norm one)."""
    return np.zeros_like(q) if np.all(q >= 0.0) else None


def scalar(M: np.ndarray, q: np.ndarray):
    """k = 1 with M > 0: z = max(0, -q/M)."""
    if q.shape[0] != 1 or not M[0, 0] > 0.0:
        return None
    return np.array([max(0.0, -q[0] / M[0, 0])])


def pair(M: np.ndarray, q: np.ndarray):
    """k = 2: try the four complementary bases in order of size; least-norm feasible one wins."""
    if q.shape[0] != 2:
        return None
    best = None
    for z in _pair_candidates(M, q):
        w = q + M @ z
        scale = 1e-12 * (1.0 + np.abs(q).max())
        if np.all(z >= -scale) and np.all(w >= -scale):
            z = np.maximum(z, 0.0)
            if best is None or z @ z < best @ best:
                best = z
    return best


def _pair_candidates(M, q):
    yield np.zeros(2)
    if M[0, 0] > 0.0:
        yield np.array([-q[0] / M[0, 0], 0.0])
    if M[1, 1] > 0.0:
        yield np.array([0.0, -q[1] / M[1, 1]])
    det = M[0, 0] * M[1, 1] - M[0, 1] * M[1, 0]
    if abs(det) > 1e-14 * (np.abs(M).max() ** 2):
        yield np.array([(-q[0] * M[1, 1] + q[1] * M[0, 1]) / det, (-q[1] * M[0, 0] + q[0] * M[1, 0]) / det])
