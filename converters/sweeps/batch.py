"""Batched steady states of the theta stepper: many parameter points of one scheduled LCS (one complementarity
pair, the PWM converters) advanced together in one compiled call.

Per point: the one-step matrices of its plan's sets (:func:`.theta_kernels.theta_matrices`) and their
affine maps (:func:`.theta_kernels.branch_maps`), ``warm_up`` periods from x0, then Newton on the one-period
map with its exact Jacobian, exactly as the serial engine (:func:`batch_steady`); finally one period on the
orbit, recorded for the row's measures. The plan (grid, step configurations, matrix sets) comes from the
serial stepper's own planner, each period is the serial stepper's own loop and Jacobian
(:func:`.theta_kernels.run_scalar`, :func:`.theta_kernels.step_jacobian`) and Newton the serial engine's own
compiled driver (:func:`converters.analysis.newton_kernel.newton_advance`: its iteration, halving and stopping
rule), answered here by the compiled period, so a batched point and a serial one solve the same discrete map the
same way. One difference: the spectral radius rho that bounds the
distance to the orbit comes from numba's LAPACK here and numpy's in the serial engine (the last bits may
differ, so a point right at the tolerance can take one Newton iteration more or less).
"""
from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numba import njit

from ..analysis.newton_kernel import newton_advance
from ..analysis.floquet import spectral_radius
from ..compiled import NEWTON_CONVERGED, NEWTON_EVALUATE, NEWTON_RADIUS, register_state
from ..methods.theta_kernels import branch_maps, run_scalar, step_jacobian, theta_matrices

if TYPE_CHECKING:
    import numpy.typing as npt

    FloatArray = npt.NDArray[np.float64]
    IntArray = npt.NDArray[np.int64]

_spectral_radius = njit(cache=True)(spectral_radius)

#: Status per point.
CONVERGED, NOT_CONVERGED, NO_SOLUTION, ROUNDING, SINGULAR, NONFINITE = 0, 1, 2, 3, 4, 5
#: A point's status from the driver's verdict (indexed by the NEWTON_* verdicts of converters.compiled).
STATUS = (NOT_CONVERGED, CONVERGED, ROUNDING, NOT_CONVERGED, SINGULAR, NO_SOLUTION, NONFINITE)


@njit(cache=True)
def _period(x0: FloatArray, which: IntArray, Phi_b: FloatArray, Gamma_b: FloatArray, CPhi: FloatArray,
            q0: FloatArray, M: FloatArray, H: FloatArray, xs: FloatArray, us: FloatArray, ys: FloatArray,
            jac: FloatArray, with_jacobian: bool, state: tuple[float, ...] | None) -> bool:
    """One period from x0 (one pair; ``which`` its steps): states into xs, pair into us, ys (rows 0..steps,
    shapes (rows, n), (rows, 1), (rows, 1)); the Jacobian into jac when asked. The serial stepper's own loop
    and Jacobian (:func:`.theta_kernels.run_scalar`, :func:`.theta_kernels.step_jacobian`), called once a
    period: a batched point equals a serial one step for step. Returns False when a step LCP has no
    solution (M <= 0 with q < 0)."""
    n = x0.shape[0]
    for i in range(n):
        xs[0, i] = x0[i]
    status, _ = run_scalar(which, Phi_b, Gamma_b, CPhi, q0, M, xs, us, ys, 0, state)
    if status != 0:
        return False
    if with_jacobian:
        for i in range(n):
            for l in range(n):
                jac[i, l] = 1.0 if i == l else 0.0
        step_jacobian(which, us, Phi_b, H, CPhi, M, jac)
    return True


def batch_steady(A: FloatArray, B: FloatArray, C: FloatArray, D: FloatArray, E: FloatArray, F: FloatArray,
                 set_configs: IntArray, set_dts: FloatArray, counts: IntArray, which: IntArray, steps: IntArray,
                 theta: float, x0: FloatArray, warm_up: int, tol: float, max_iter: int, xs: FloatArray,
                 us: FloatArray, ys: FloatArray, x_star: FloatArray, jac_out: FloatArray, status: IntArray,
                 iterations: IntArray, residuals: FloatArray, distances: FloatArray) -> None:
    """Steady states of P points (module docstring), in place.

    A..F: (P, configs, ...) matrices; set_configs, set_dts: (P, sets) the plan's matrix sets (``counts`` used
    per point); which: (P, S) each step's set; steps: (P,) steps per period; x0: (P, n) starts. Outputs: xs
    (P, S + 1, n), us, ys (P, S + 1) the final period on the orbit; x_star (P, n); jac_out (P, n, n); status,
    iterations (P,); residuals, distances (P,) relative.

    Newton is the serial engine's driver (:func:`converters.analysis.newton_kernel.newton_advance`, which
    :func:`converters.analysis.periodic.newton_orbit` runs too), so a batched point and a serial one take the same
    iterations to the same orbit."""
    _batch_steady(A, B, C, D, E, F, set_configs, set_dts, counts, which, steps, theta, x0, warm_up, tol, max_iter,
                  xs, us, ys, x_star, jac_out, status, iterations, residuals, distances, register_state(x0.shape[1]))


@njit(cache=True)
def _batch_steady(A: FloatArray, B: FloatArray, C: FloatArray, D: FloatArray, E: FloatArray, F: FloatArray,
                  set_configs: IntArray, set_dts: FloatArray, counts: IntArray, which: IntArray, steps: IntArray,
                  theta: float, x0: FloatArray, warm_up: int, tol: float, max_iter: int, xs: FloatArray,
                  us: FloatArray, ys: FloatArray, x_star: FloatArray, jac_out: FloatArray, status: IntArray,
                  iterations: IntArray, residuals: FloatArray, distances: FloatArray,
                  state: tuple[float, ...] | None) -> None:
    """:func:`batch_steady` compiled (``state``: :func:`converters.compiled.register_state`)."""
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
        Phi_b, Gamma_b = np.empty((sets, 2, n, n)), np.empty((sets, 2, n))
        CPhi, q0 = np.empty((sets, 1, n)), np.empty((sets, 1))
        if ok:
            branch_maps(Phi, Gamma, Hm, Cs, Fs, Mm, Phi_b, Gamma_b, CPhi, q0)
        x = x0[p].copy()
        jac = np.empty((n, n))
        S = steps[p]
        wp = which[p, :S]
        xp, up, yp = xs[p], us[p].reshape((us.shape[1], 1)), ys[p].reshape((ys.shape[1], 1))
        status[p] = NO_SOLUTION
        if not ok:
            continue
        for _ in range(warm_up):
            if not _period(x, wp, Phi_b, Gamma_b, CPhi, q0, Mm, Hm, xp, up, yp, jac, False, state):
                ok = False
                break
            for i in range(n):
                x[i] = xp[S, i]
        if not ok or not _period(x, wp, Phi_b, Gamma_b, CPhi, q0, Mm, Hm, xp, up, yp, jac, True, state):
            continue
        px = xp[S].copy()
        dx, a = np.empty(n), np.empty((n, n + 1))
        trial, p_trial, jac_trial = np.empty(n), np.empty(n), np.empty((n, n))
        istate, rstate = np.zeros(4, dtype=np.int64), np.full(4, np.inf)
        ok = True
        while True:                 # the driver asks, this answers (newton_kernel: reverse communication)
            verdict = newton_advance(x, px, jac, dx, a, trial, p_trial, jac_trial, ok, istate, rstate, tol, max_iter)
            if verdict == NEWTON_RADIUS:
                rstate[3] = _spectral_radius(jac)
            elif verdict == NEWTON_EVALUATE:
                ok = _period(trial, wp, Phi_b, Gamma_b, CPhi, q0, Mm, Hm, xp, up, yp, jac_trial, True, state)
                for i in range(n):
                    p_trial[i] = xp[S, i]
            else:
                break
        iterations[p], residuals[p], distances[p] = istate[1], rstate[1], rstate[2]
        status[p] = STATUS[verdict]
        if verdict == NEWTON_CONVERGED:
            for i in range(n):
                x_star[p, i] = x[i] + dx[i]                   # the last (tiny) step taken too
                for l in range(n):
                    jac_out[p, i, l] = jac[i, l]
        if status[p] == CONVERGED:                           # the recorded period: the one on the orbit
            _period(x_star[p], wp, Phi_b, Gamma_b, CPhi, q0, Mm, Hm, xp, up, yp, jac, False, state)


__all__ = ["batch_steady", "CONVERGED", "NOT_CONVERGED", "NO_SOLUTION", "ROUNDING", "SINGULAR", "NONFINITE"]
