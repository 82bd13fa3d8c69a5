"""One Newton iteration of the periodic-orbit engine and its stopping rule, compiled (numba; also built ahead of
time: :mod:`converters.compiled`): the serial engine (:func:`converters.analysis.periodic.newton_orbit`) and the
batched steady states (:mod:`converters.sweeps.batch`) share it, so the rule lives once."""
from __future__ import annotations

import numpy as np
from numba import njit

from ..compiled import (NEWTON_CONTINUE, NEWTON_CONVERGED, NEWTON_EXHAUSTED, NEWTON_ROUNDING, NEWTON_SINGULAR,
                        ROUNDING)

EPS = 2.220446049250313e-16


@njit(cache=True)
def newton_step(x, px, jac, rho, step, work, tol, iteration, max_iter):
    """One Newton iteration on P(x) - x = 0 and the verdict on it: the arithmetic and the stopping rule of the
    serial engine (:func:`converters.analysis.periodic.newton_orbit`) and the batched steady states
    (:mod:`converters.sweeps.batch`), written once. Fills ``step`` with the Newton step dx,
    (jac - I) dx = -(P(x) - x) (Gaussian elimination with partial pivoting on ``work``, n x (n + 1)).

    ``rho``: the spectral radius of jac (:func:`converters.analysis.periodic.spectral_radius`, computed by the
    caller: numpy's LAPACK in Python, numba's in compiled callers, so this kernel needs neither). Returns
    (residual, worst, distance, verdict): worst = max |P(x) - x|, residual = worst / scale with
    scale = 1 + max |x|; distance = max(max |dx|, worst / (1 - rho) when rho < 1) / scale, the estimated
    distance to the orbit; the verdict (``converters.compiled``): NEWTON_CONVERGED when distance <= tol, else
    NEWTON_ROUNDING when the residual is at most ROUNDING machine epsilons, else NEWTON_EXHAUSTED at
    iteration >= max_iter, else NEWTON_CONTINUE; NEWTON_SINGULAR when jac - I is singular (a pivot exactly 0: a
    multiplier at 1), step and distance then undefined."""
    n = x.shape[0]
    scale = 1.0
    worst = 0.0
    for i in range(n):
        scale = max(scale, 1.0 + abs(x[i]))
        worst = max(worst, abs(px[i] - x[i]))
    for i in range(n):
        for l in range(n):
            work[i, l] = jac[i, l] - (1.0 if i == l else 0.0)
        work[i, n] = x[i] - px[i]
    for col in range(n):
        pivot = col
        for row in range(col + 1, n):
            if abs(work[row, col]) > abs(work[pivot, col]):
                pivot = row
        for cc in range(n + 1):
            tmp = work[col, cc]
            work[col, cc] = work[pivot, cc]
            work[pivot, cc] = tmp
        if work[col, col] == 0.0:
            return worst / scale, worst, np.inf, NEWTON_SINGULAR
        for row in range(col + 1, n):
            f = work[row, col] / work[col, col]
            for cc in range(col, n + 1):
                work[row, cc] -= f * work[col, cc]
    largest = 0.0
    for row in range(n - 1, -1, -1):
        acc = work[row, n]
        for l in range(row + 1, n):
            acc -= work[row, l] * step[l]
        step[row] = acc / work[row, row]
        largest = max(largest, abs(step[row]))
    distance = largest / scale
    if rho < 1.0:
        distance = max(distance, worst / (1.0 - rho) / scale)
    residual = worst / scale
    if distance <= tol:
        return residual, worst, distance, NEWTON_CONVERGED
    if residual <= ROUNDING * EPS:
        return residual, worst, distance, NEWTON_ROUNDING
    if iteration >= max_iter:
        return residual, worst, distance, NEWTON_EXHAUSTED
    return residual, worst, distance, NEWTON_CONTINUE
