"""Semismooth Newton method on the Fischer-Burmeister reformulation, with an Armijo line search.

Phi_i(z) = sqrt(z_i^2 + w_i^2) - z_i - w_i, w = q + M z; Phi(z) = 0 exactly at LCP solutions.
The merit psi = ||Phi||^2 / 2 is continuously differentiable; when the Newton direction is not a
good descent direction the method falls back to -grad psi (De Luca, Facchinei and Kanzow 1996).
Converges globally for P-matrices (every stationary point of psi is then a solution). A wall-clock
``deadline`` is checked at every step.
"""
from __future__ import annotations

import numpy as np

from .result import FAILED, MAX_ITERATIONS, SOLVED, accepts, finish


def newton_fb(M: np.ndarray, q: np.ndarray, *, tol: float, max_iter: int,
              rho: float = 1e-10, p: float = 2.1, beta: float = 0.5, sigma: float = 1e-4, deadline=None):
    k = q.shape[0]
    z = np.zeros(k)
    eye = np.eye(k)
    for iteration in range(1, max_iter + 1):
        if deadline is not None and deadline.expired():
            return finish(M, q, np.maximum(z, 0.0), status=FAILED, iterations=iteration - 1, method="newton",
                          tol=tol, message=deadline.message(f"newton (after {iteration - 1} steps)"))
        w = q + M @ z
        phi, jac = _fb_and_jacobian(z, w, M, eye)
        psi = 0.5 * phi @ phi
        grad = jac.T @ phi
        try:
            direction = np.linalg.solve(jac, -phi)
            if grad @ direction > -rho * np.linalg.norm(direction) ** p:
                direction = -grad
        except np.linalg.LinAlgError:
            direction = -grad
        step = 1.0
        while step > 1e-14:
            trial = z + step * direction
            phi_t = _fb(trial, q + M @ trial)
            if 0.5 * phi_t @ phi_t <= psi + sigma * step * (grad @ direction):
                break
            step *= beta
        else:
            return finish(M, q, z, status=FAILED, iterations=iteration, method="newton", tol=tol,
                          message="newton: line search failed (stationary point of the merit "
                                  "function; M is probably not a P-matrix); try method='lemke'")
        z = trial
        if accepts(M, q, np.maximum(z, 0.0), tol):
            return finish(M, q, np.maximum(z, 0.0), status=SOLVED, iterations=iteration,
                          method="newton", tol=tol)
    return finish(M, q, np.maximum(z, 0.0), status=MAX_ITERATIONS, iterations=max_iter, method="newton",
                  tol=tol, message=f"newton reached max_iter ({max_iter}) steps; try method='lemke'")


def _fb(z, w):
    return np.sqrt(z * z + w * w) - z - w


def _fb_and_jacobian(z, w, M, eye):
    norm = np.sqrt(z * z + w * w)
    phi = norm - z - w
    # A generalized Jacobian element; at (0, 0) take the limit along direction (1, 1).
    safe = norm > 1e-300
    da = np.where(safe, z / np.where(safe, norm, 1.0), 1.0 / np.sqrt(2.0)) - 1.0
    db = np.where(safe, w / np.where(safe, norm, 1.0), 1.0 / np.sqrt(2.0)) - 1.0
    return phi, da[:, None] * eye + db[:, None] * M


__all__ = ["newton_fb", "FAILED"]
