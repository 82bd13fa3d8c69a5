"""Batched steady states of the theta stepper: many parameter points of one scheduled LCS (one complementarity
pair, the PWM converters) advanced together in one compiled call.

Per point: the one-step matrices of its plan's sets (:func:`.theta_kernels.theta_matrices`), ``warm_up``
periods from x0, then Newton on the one-period map with its exact Jacobian (the product of the one-step
derivatives Phi - H (C Phi) / M on the steps where the pair is held), exactly as the serial engine
(:func:`batch_steady`); finally one period on the orbit, recorded for the row's measures. The plan (grid, step configurations, matrix sets) comes from the serial stepper's own planner, so
a batched point and a serial one solve the same discrete map.
"""
from __future__ import annotations

import numpy as np
from numba import njit

from .theta_kernels import theta_matrices

#: Status per point.
CONVERGED, NOT_CONVERGED, NO_SOLUTION, ROUNDING, SINGULAR, NONFINITE = 0, 1, 2, 3, 4, 5


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
        # the step is theta_kernels._run_scalar's, written out again on purpose: the same arithmetic in the
        # same order (a batched point equals a serial one to rounding); a shared @njit helper measured 35 %
        # slower here (10,000-point sweep 3.0 -> 4.2 s), the per-step call not being inlined.
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


@njit(cache=True, inline="always")
def _solve_shifted(jac, r, a, dx):
    """dx with (jac - I) dx = -r, by elimination with partial pivoting (n is small); False when singular."""
    n = r.shape[0]
    for i in range(n):
        for l in range(n):
            a[i, l] = jac[i, l] - (1.0 if i == l else 0.0)
        a[i, n] = -r[i]
    for col in range(n):
        piv = col
        for row in range(col + 1, n):
            if abs(a[row, col]) > abs(a[piv, col]):
                piv = row
        for cc in range(n + 1):
            tmp = a[col, cc]
            a[col, cc] = a[piv, cc]
            a[piv, cc] = tmp
        if a[col, col] == 0.0:
            return False
        for row in range(col + 1, n):
            f = a[row, col] / a[col, col]
            for cc in range(col, n + 1):
                a[row, cc] -= f * a[col, cc]
    for row in range(n - 1, -1, -1):
        acc = a[row, n]
        for l in range(row + 1, n):
            acc -= a[row, l] * dx[l]
        dx[row] = acc / a[row, row]
    return True


@njit(cache=True)
def batch_steady(A, B, C, D, E, F, set_configs, set_dts, counts, which, steps, theta, x0, warm_up, tol, max_iter,
                 xs, us, ys, x_star, jac_out, status, iterations, residuals, distances):
    """Steady states of P points (module docstring), in place.

    A..F: (P, configs, ...) matrices; set_configs, set_dts: (P, sets) the plan's matrix sets (``counts`` used
    per point); which: (P, S) each step's set; steps: (P,) steps per period; x0: (P, n) starts. Outputs: xs
    (P, S + 1, n), us, ys (P, S + 1) the final period on the orbit; x_star (P, n); jac_out (P, n, n); status,
    iterations (P,); residuals, distances (P,) relative.

    Newton is :func:`converters.analysis.periodic.newton_orbit` step for step (the same distance estimate
    max(|dx|, |r| / (1 - rho)), the same halving of a step that does not lower the residual, the same plain
    period when no fraction does, the same refusal at the rounding level), so a batched point and a serial one
    take the same iterations to the same orbit."""
    P, n = x0.shape[0], x0.shape[1]
    eps = 2.220446049250313e-16
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
        status[p] = NO_SOLUTION
        if not ok:
            continue
        for _ in range(warm_up):
            if not _period(x, which[p], S, Phi, Gamma, Hm, Cs, Fs, Mm, xp, up, yp, jac, False):
                ok = False
                break
            for i in range(n):
                x[i] = xp[S, i]
        if not ok or not _period(x, which[p], S, Phi, Gamma, Hm, Cs, Fs, Mm, xp, up, yp, jac, True):
            continue
        px = xp[S].copy()
        r = np.empty(n)
        dx = np.empty(n)
        trial = np.empty(n)
        jac_trial = np.empty((n, n))
        a = np.empty((n, n + 1))
        status[p] = NOT_CONVERGED
        for it in range(max_iter + 1):
            scale = 1.0
            worst = 0.0
            for i in range(n):
                scale = max(scale, 1.0 + abs(x[i]))
                r[i] = px[i] - x[i]
                worst = max(worst, abs(r[i]))
            residuals[p] = worst / scale
            iterations[p] = it
            rho = np.abs(np.linalg.eigvals(jac.astype(np.complex128))).max()   # complex: a real matrix may have complex roots
            if not _solve_shifted(jac, r, a, dx):
                status[p] = SINGULAR
                break
            step = 0.0
            for i in range(n):
                step = max(step, abs(dx[i]))
            distance = step / scale
            if rho < 1.0:
                distance = max(distance, worst / (1.0 - rho) / scale)
            distances[p] = distance
            if distance <= tol:
                status[p] = CONVERGED
                for i in range(n):
                    x_star[p, i] = x[i] + dx[i]                   # the last (tiny) step taken too
                    for l in range(n):
                        jac_out[p, i, l] = jac[i, l]
                break
            if worst / scale <= 64.0 * eps:
                status[p] = ROUNDING
                break
            if it == max_iter:
                break
            accepted = False
            for _ in range(8):
                for i in range(n):
                    trial[i] = x[i] + dx[i]
                if _period(trial, which[p], S, Phi, Gamma, Hm, Cs, Fs, Mm, xp, up, yp, jac_trial, True):
                    finite = True
                    gap = 0.0
                    for i in range(n):
                        finite = finite and np.isfinite(xp[S, i])
                        gap = max(gap, abs(xp[S, i] - trial[i]))
                    if finite and gap < worst:
                        accepted = True
                        break
                for i in range(n):
                    dx[i] *= 0.5
            if not accepted:
                for i in range(n):
                    trial[i] = px[i]
                if not _period(trial, which[p], S, Phi, Gamma, Hm, Cs, Fs, Mm, xp, up, yp, jac_trial, True):
                    status[p] = NO_SOLUTION
                    break
                finite = True
                for i in range(n):
                    finite = finite and np.isfinite(xp[S, i])
                if not finite:
                    status[p] = NONFINITE
                    break
            for i in range(n):
                x[i] = trial[i]
                px[i] = xp[S, i]
                for l in range(n):
                    jac[i, l] = jac_trial[i, l]
        if status[p] == CONVERGED:                           # the recorded period: the one on the orbit
            _period(x_star[p], which[p], S, Phi, Gamma, Hm, Cs, Fs, Mm, xp, up, yp, jac, False)


__all__ = ["batch_steady", "CONVERGED", "NOT_CONVERGED", "NO_SOLUTION", "ROUNDING", "SINGULAR", "NONFINITE"]
