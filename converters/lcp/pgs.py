"""Projected Gauss-Seidel (with optional over-relaxation omega in (0, 2)) (compiled).

z_i <- max(0, z_i - omega * w_i / M_ii), sweeping i = 1..k. Converges for symmetric positive
definite M; needs M_ii > 0. A wall-clock deadline is checked between slices of work;
divergence (a non-finite z) is detected and reported. :func:`run` is resumable (see
:mod:`converters.lcp.lemke`).
"""
from __future__ import annotations

import math
from typing import TYPE_CHECKING

from numba import njit

from . import state as S
from .result import check_scaled, error, mark_done, max_abs, max_abs_matrix, residual

if TYPE_CHECKING:
    import numpy as np
    import numpy.typing as npt

    FloatArray = npt.NDArray[np.float64]
    IntArray = npt.NDArray[np.int64]


@njit(cache=True, _nrt=False)
def sizes(k: int) -> tuple[int, int]:
    """Doubles and integers of workspace: w."""
    return k, 0


@njit(cache=True, _nrt=False)
def run(M: FloatArray, q: FloatArray, z: FloatArray, fw: FloatArray, iw: IntArray, st: IntArray, sf: FloatArray,
        tol: float, max_iter: int, budget: int, omega: float, probe: bool) -> bool:
    """Advance PGS by at most ``budget`` multiply-adds; True when finished (see ``lemke.run``).

    With ``probe`` (auto's use) it also stops, with outcome SLOW, as soon as the residual does not shrink or
    its rate of decrease projects more than max_iter sweeps to reach tol."""
    k = q.shape[0]
    w = fw[:k]
    if st[S.PHASE] == S.START:
        z[:] = 0.0
        st[S.ITER] = 0
        for i in range(k):
            if M[i, i] <= 0.0:
                st[S.INFO] = i
                sf[S.INFO_X] = M[i, i]
                return mark_done(st, S.FAILED, S.DIAG)
        sf[S.PREVIOUS_ERR] = error(q, z, q)     # err of z = 0 (w = q)
        st[S.PHASE] = S.RUNNING
    q_big, m_big = max_abs(q), max_abs_matrix(M)
    sweep = st[S.ITER] + 1
    while sweep <= max_iter:
        finite = True
        for i in range(k):
            s = 0.0
            for j in range(k):
                s += M[i, j] * z[j]
            v = z[i] - omega * (q[i] + s) / M[i, i]
            z[i] = v if v > 0.0 else 0.0      # NaN -> 0, as Python's max(0.0, nan); inf stays
            if math.isinf(z[i]):
                finite = False
        if not finite:
            z[:] = 0.0
            st[S.ITER] = sweep
            st[S.INFO] = sweep
            return mark_done(st, S.FAILED, S.DIVERGED)
        err = residual(M, q, z, w)
        if check_scaled(q_big, m_big, z, w, err, tol)[0] == 0:
            st[S.ITER] = sweep
            return mark_done(st, S.SOLVED, S.OK)
        if probe:
            previous = sf[S.PREVIOUS_ERR]
            sf[S.PREVIOUS_ERR] = err
            if err > tol:
                rate = err / previous
                if not rate < 1.0 or sweep + math.log(tol / err) / math.log(rate) > max_iter:
                    st[S.ITER] = sweep
                    return mark_done(st, S.MAX_ITERATIONS, S.SLOW)
        budget -= 2 * k * k + k
        if budget <= 0 and sweep < max_iter:    # the caller checks its deadline here, then calls again
            st[S.ITER] = sweep
            return False
        sweep += 1
    st[S.ITER] = max_iter
    return mark_done(st, S.MAX_ITERATIONS, S.MAXIT)


__all__ = ["run", "sizes"]
