"""Batched steady states of the theta stepper: many parameter points of one scheduled LCS (one complementarity
pair, the PWM converters) advanced together in one compiled call.

Per point: the one-step matrices of its plan's sets (:func:`.theta_kernels.theta_matrices`), ``warm_up``
periods from x0, then Newton on the one-period map with its exact Jacobian (the product of the one-step
derivatives Phi - H (C Phi) / M on the steps where the pair is held), until the step is below ``tol``
(relative) or the residual reaches rounding; finally one period on the orbit, recorded for the row's
measures. The plan (grid, step configurations, matrix sets) comes from the serial stepper's own planner, so
a batched point and a serial one solve the same discrete map.
"""
from __future__ import annotations

import numpy as np
from numba import njit

from .theta_kernels import theta_matrices

#: Status per point.
CONVERGED, NOT_CONVERGED, NO_SOLUTION = 0, 1, 2


@njit(cache=True, inline="always")
def _period(x0, which, steps, Phi, Gamma, H, C, F, M, xs, us, ys, jac, with_jacobian):
    """One period from x0 (one pair): states into xs[0..steps], pair into us, ys; the Jacobian into jac when
    asked. Returns False when a step LCP has no solution (M <= 0 with q < 0)."""
    n = x0.shape[0]
    for i in range(n):
        xs[0, i] = x0[i]
    if with_jacobian:
        for i in range(n):
            for l in range(n):
                jac[i, l] = 1.0 if i == l else 0.0
    xf = np.empty(n)
    step = np.empty((n, n))
    tmp = np.empty((n, n))
    for j in range(steps):
        s = which[j]
        q = F[s, 0]
        for i in range(n):
            acc = Gamma[s, i]
            for l in range(n):
                acc += Phi[s, i, l] * xs[j, l]
            xf[i] = acc
            q += C[s, 0, i] * acc
        m = M[s, 0, 0]
        z = 0.0
        if q < 0.0:
            if m <= 0.0:
                return False
            z = -q / m
        for i in range(n):
            xs[j + 1, i] = xf[i] + H[s, i, 0] * z
        us[j + 1] = z
        ys[j + 1] = q + m * z
        if with_jacobian:
            for i in range(n):
                for l in range(n):
                    step[i, l] = Phi[s, i, l]
            if z > 0.0:                                      # held: d z / d x = -(C Phi) / M
                for l in range(n):
                    cphi = 0.0
                    for r in range(n):
                        cphi += C[s, 0, r] * Phi[s, r, l]
                    for i in range(n):
                        step[i, l] -= H[s, i, 0] * cphi / m
            for i in range(n):
                for l in range(n):
                    acc = 0.0
                    for r in range(n):
                        acc += step[i, r] * jac[r, l]
                    tmp[i, l] = acc
            for i in range(n):
                for l in range(n):
                    jac[i, l] = tmp[i, l]
    return True


@njit(cache=True)
def batch_steady(A, B, C, D, E, F, set_configs, set_dts, counts, which, steps, theta, x0, warm_up, tol, max_iter,
                 xs, us, ys, x_star, jac_out, status, iterations, residuals):
    """Steady states of P points (module docstring), in place.

    A..F: (P, configs, ...) matrices; set_configs, set_dts: (P, sets) the plan's matrix sets (``counts`` used
    per point); which: (P, S) each step's set; steps: (P,) steps per period; x0: (P, n) starts. Outputs: xs
    (P, S + 1, n), us, ys (P, S + 1) the final period on the orbit; x_star (P, n); jac_out (P, n, n); status,
    iterations (P,); residuals (P,) relative."""
    P, n = x0.shape[0], x0.shape[1]
    for p in range(P):
        sets = counts[p]
        Phi = np.empty((sets, n, n))
        Gamma = np.empty((sets, n))
        Hm = np.empty((sets, n, 1))
        Mm = np.empty((sets, 1, 1))
        W = np.empty((n, n))
        ok = True
        for s in range(sets):
            c = set_configs[p, s]
            ok = ok and theta_matrices(A[p, c], B[p, c], C[p, c], D[p, c], E[p, c], F[p, c], set_dts[p, s], theta,
                                       Phi[s], Gamma[s], Hm[s], Mm[s], W)
        Cs = np.empty((sets, 1, n))
        Fs = np.empty((sets, 1))
        for s in range(sets):
            c = set_configs[p, s]
            for i in range(n):
                Cs[s, 0, i] = C[p, c, 0, i]
            Fs[s, 0] = F[p, c, 0]
        x = x0[p].copy()
        jac = np.empty((n, n))
        S = steps[p]
        xp, up, yp = xs[p], us[p], ys[p]
        if not ok:
            status[p] = NO_SOLUTION
            continue
        for _ in range(warm_up):
            if not _period(x, which[p], S, Phi, Gamma, Hm, Cs, Fs, Mm, xp, up, yp, jac, False):
                ok = False
                break
            for i in range(n):
                x[i] = xp[S, i]
        if not ok:
            status[p] = NO_SOLUTION
            continue
        status[p] = NOT_CONVERGED
        a = np.empty((n, n + 1))
        for it in range(max_iter + 1):
            if not _period(x, which[p], S, Phi, Gamma, Hm, Cs, Fs, Mm, xp, up, yp, jac, True):
                status[p] = NO_SOLUTION
                break
            scale = 1.0
            for i in range(n):
                scale = max(scale, 1.0 + abs(x[i]))
            worst = 0.0
            for i in range(n):
                r = xp[S, i] - x[i]
                worst = max(worst, abs(r))
                for l in range(n):
                    a[i, l] = jac[i, l] - (1.0 if i == l else 0.0)
                a[i, n] = -r
            residuals[p] = worst / scale
            iterations[p] = it
            from_rounding = worst <= 64.0 * 2.220446049250313e-16 * scale
            # (J - I) dx = -r by elimination (n small)
            for col in range(n):
                piv = col
                for r in range(col + 1, n):
                    if abs(a[r, col]) > abs(a[piv, col]):
                        piv = r
                for cc in range(n + 1):
                    tmp = a[col, cc]
                    a[col, cc] = a[piv, cc]
                    a[piv, cc] = tmp
                if a[col, col] == 0.0:
                    break
                for r in range(col + 1, n):
                    f = a[r, col] / a[col, col]
                    for cc in range(col, n + 1):
                        a[r, cc] -= f * a[col, cc]
            dx = np.zeros(n)
            for r in range(n - 1, -1, -1):
                acc = a[r, n]
                for l in range(r + 1, n):
                    acc -= a[r, l] * dx[l]
                dx[r] = acc / a[r, r] if a[r, r] != 0.0 else 0.0
            step = 0.0
            for i in range(n):
                step = max(step, abs(dx[i]))
            if step / scale <= tol or from_rounding:
                status[p] = CONVERGED
                for i in range(n):
                    x_star[p, i] = x[i] + dx[i]                   # the last (tiny) step taken too
                    for l in range(n):
                        jac_out[p, i, l] = jac[i, l]
                break
            if it == max_iter:
                break
            for i in range(n):
                x[i] += dx[i]
        if status[p] == CONVERGED:                           # the recorded period: the one on the orbit
            _period(x_star[p], which[p], S, Phi, Gamma, Hm, Cs, Fs, Mm, xp, up, yp, jac, False)


__all__ = ["batch_steady", "CONVERGED", "NOT_CONVERGED", "NO_SOLUTION"]
