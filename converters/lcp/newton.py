"""Semismooth Newton method on the Fischer-Burmeister reformulation, with an Armijo line search (compiled).

Phi_i(z) = sqrt(z_i^2 + w_i^2) - z_i - w_i, w = q + M z; Phi(z) = 0 exactly at LCP solutions.
The merit psi = ||Phi||^2 / 2 is continuously differentiable; when the Newton direction is not a
good descent direction the method falls back to -grad psi (De Luca, Facchinei and Kanzow 1996).
Converges globally for P-matrices (every stationary point of psi is then a solution). A wall-clock
deadline is checked between slices of work. :func:`run` is resumable (see :mod:`converters.lcp.lemke`).
"""
from __future__ import annotations

import math
from typing import TYPE_CHECKING

from numba import njit

from . import state as S
from .kernels import solve_augmented
from .result import accepts_scaled, affine, copy_into, mark_done, max_abs, max_abs_matrix

if TYPE_CHECKING:
    import numpy as np
    import numpy.typing as npt

    FloatArray = npt.NDArray[np.float64]
    IntArray = npt.NDArray[np.int64]

#: Defaults of the options rho, p (descent test), beta (step reduction) and sigma (Armijo constant).
RHO, P, BETA, SIGMA = 1e-10, 2.1, 0.5, 1e-4


@njit(cache=True, _nrt=False)
def sizes(k: int) -> tuple[int, int]:
    """Doubles of workspace: the Jacobian, its augmented copy, and 7 vectors."""
    return k * k + k * (k + 1) + 7 * k, 0


@njit(cache=True, _nrt=False)
def run(M: FloatArray, q: FloatArray, z: FloatArray, fw: FloatArray, iw: IntArray, st: IntArray, tol: float,
        max_iter: int, budget: int, rho: float, p: float, beta: float, sigma: float) -> bool:
    """Advance Newton by at most ``budget`` multiply-adds; True when finished (see ``lemke.run``).
    The iterate x lives in the workspace; z holds max(x, 0)."""
    k = q.shape[0]
    o = 0
    jac = fw[o:o + k * k].reshape((k, k))
    o += k * k
    aug = fw[o:o + k * (k + 1)].reshape((k, k + 1))
    o += k * (k + 1)
    x, w, phi, grad, direction, trial, phi_t = (fw[o:o + k], fw[o + k:o + 2 * k], fw[o + 2 * k:o + 3 * k],
                                                fw[o + 3 * k:o + 4 * k], fw[o + 4 * k:o + 5 * k],
                                                fw[o + 5 * k:o + 6 * k], fw[o + 6 * k:o + 7 * k])
    if st[S.PHASE] == S.START:
        x[:] = 0.0
        st[S.ITER] = 0
        st[S.PHASE] = S.RUNNING
    q_big, m_big = max_abs(q), max_abs_matrix(M)
    iteration = st[S.ITER] + 1
    while iteration <= max_iter:
        _fb_and_jacobian(M, q, x, w, phi, jac)
        psi = 0.5 * _dot(phi, phi)
        for j in range(k):
            s = 0.0
            for i in range(k):
                s += jac[i, j] * phi[i]
            grad[j] = s
        for i in range(k):
            for j in range(k):
                aug[i, j] = jac[i, j]
            aug[i, k] = -phi[i]
        if solve_augmented(aug, k, 1):
            for i in range(k):
                direction[i] = aug[i, k]
            if _dot(grad, direction) > -rho * math.sqrt(_dot(direction, direction)) ** p:
                for i in range(k):
                    direction[i] = -grad[i]
        else:
            for i in range(k):
                direction[i] = -grad[i]
        slope = _dot(grad, direction)
        step = 1.0
        accepted = False
        while step > 1e-14:
            for i in range(k):
                trial[i] = x[i] + step * direction[i]
            _fb(M, q, trial, w, phi_t)
            if 0.5 * _dot(phi_t, phi_t) <= psi + sigma * step * slope:
                accepted = True
                break
            step *= beta
        if not accepted:
            copy_into(x, z)       # the last iterate as it is
            st[S.ITER] = iteration
            return mark_done(st, S.FAILED, S.LINESEARCH)
        copy_into(trial, x)
        _clip(x, z)
        if accepts_scaled(M, q, q_big, m_big, z, w, tol):
            st[S.ITER] = iteration
            return mark_done(st, S.SOLVED, S.OK)
        budget -= k * k * k // 3 + 6 * k * k
        if budget <= 0 and iteration < max_iter:    # the caller checks its deadline here, then calls again
            st[S.ITER] = iteration
            return False
        iteration += 1
    _clip(x, z)
    st[S.ITER] = max_iter
    return mark_done(st, S.MAX_ITERATIONS, S.MAXIT)


@njit(cache=True, _nrt=False)
def _dot(a: FloatArray, b: FloatArray) -> float:
    s = 0.0
    for i in range(a.shape[0]):
        s += a[i] * b[i]
    return s


@njit(cache=True, _nrt=False)
def _clip(x: FloatArray, z: FloatArray) -> None:
    for i in range(x.shape[0]):
        z[i] = x[i] if x[i] > 0.0 else 0.0


@njit(cache=True, _nrt=False)
def _fb(M: FloatArray, q: FloatArray, x: FloatArray, w: FloatArray, phi: FloatArray) -> None:
    affine(M, q, x, w)
    for i in range(q.shape[0]):
        phi[i] = math.sqrt(x[i] * x[i] + w[i] * w[i]) - x[i] - w[i]


@njit(cache=True, _nrt=False)
def _fb_and_jacobian(M: FloatArray, q: FloatArray, x: FloatArray, w: FloatArray, phi: FloatArray,
                     jac: FloatArray) -> None:
    """Phi and a generalized Jacobian element diag(da) + diag(db) M; at (0, 0) the limit along (1, 1)."""
    k = q.shape[0]
    _fb(M, q, x, w, phi)
    for i in range(k):
        norm = math.sqrt(x[i] * x[i] + w[i] * w[i])
        if norm > 1e-300:
            da, db = x[i] / norm - 1.0, w[i] / norm - 1.0
        else:
            da = db = 1.0 / math.sqrt(2.0) - 1.0
        for j in range(k):
            jac[i, j] = db * M[i, j]
        jac[i, i] += da


__all__ = ["run", "sizes"]
