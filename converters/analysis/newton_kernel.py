"""Newton shooting's driver, compiled (numba; also built ahead of time: :mod:`converters.compiled`): one Newton
iteration with its stopping rule (:func:`newton_step`) and the iteration around it (:func:`newton_advance`: the
step halved while the residual does not fall, a plain period where no fraction helps), written once for the serial
engine (:func:`converters.analysis.periodic.newton_orbit`, over any method's period map) and the batched steady
states (:mod:`converters.sweeps.batch`, over the stepper's compiled period).

The driver does not call the period map: it asks its caller for it (reverse communication, as ARPACK asks for
its matrix-vector products), so the same compiled code serves a map written in Python (the event method's) and
one compiled into the batch, and numba compiles and caches it without functions passed as values."""
from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numba import njit

from ..compiled import (NEWTON_CONTINUE, NEWTON_CONVERGED, NEWTON_EVALUATE, NEWTON_EXHAUSTED, NEWTON_NO_SOLUTION,
                        NEWTON_NONFINITE, NEWTON_RADIUS, NEWTON_ROUNDING, NEWTON_SINGULAR, ROUNDING)

if TYPE_CHECKING:
    import numpy.typing as npt

    FloatArray = npt.NDArray[np.float64]
    IntArray = npt.NDArray[np.int64]

EPS = 2.220446049250313e-16


@njit(cache=True)
def _solve_shifted(jac: FloatArray, x: FloatArray, px: FloatArray, work: FloatArray) -> float:
    """(jac - I) s = -(P(x) - x) by Gaussian elimination with partial pivoting on ``work`` (n x (n + 1)), s left in
    its last column; returns max |s|, inf where jac - I is singular (a pivot exactly 0: a multiplier at 1)."""
    n = x.shape[0]
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
            return np.inf
        for row in range(col + 1, n):
            f = work[row, col] / work[col, col]
            for cc in range(col, n + 1):
                work[row, cc] -= f * work[col, cc]
    largest = 0.0
    for row in range(n - 1, -1, -1):
        acc = work[row, n]
        for l in range(row + 1, n):
            acc -= work[row, l] * work[l, n]
        work[row, n] = acc / work[row, row]
        largest = max(largest, abs(work[row, n]))
    return largest


@njit(cache=True)
def newton_step(x: FloatArray, px: FloatArray, jac: FloatArray, rho: float, step: FloatArray, work: FloatArray,
                tol: float, iteration: int, max_iter: int) -> tuple[float, float, float, int]:
    """One Newton iteration on P(x) - x = 0 and the verdict on it: the arithmetic and the stopping rule of the
    serial engine (:func:`converters.analysis.periodic.newton_orbit`) and the batched steady states
    (:mod:`converters.sweeps.batch`), written once. Fills ``step`` with the Newton step dx,
    (jac - I) dx = -(P(x) - x) (Gaussian elimination with partial pivoting on ``work``, n x (n + 1)).

    ``rho``: the spectral radius of jac (:func:`converters.analysis.floquet.spectral_radius`, computed by the
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
    largest = _solve_shifted(jac, x, px, work)
    if largest == np.inf:
        return worst / scale, worst, np.inf, NEWTON_SINGULAR
    for i in range(n):
        step[i] = work[i, n]
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


#: Halvings of a Newton step that does not lower the residual before a plain period of the map is taken instead.
HALVINGS = 8
#: The driver's phases (``istate[0]``): at a new iterate, its radius known, a trial step evaluated, a plain
#: period evaluated.
_NEW, _STEP, _TRIAL, _PLAIN = 0, 1, 2, 3


@njit(cache=True)
def _accept(x: FloatArray, px: FloatArray, jac: FloatArray, trial: FloatArray, p_trial: FloatArray,
            jac_trial: FloatArray, istate: IntArray) -> int:
    n = x.shape[0]
    for i in range(n):
        x[i] = trial[i]
        px[i] = p_trial[i]
        for l in range(n):
            jac[i, l] = jac_trial[i, l]
    istate[1] += 1
    istate[0] = _STEP
    return NEWTON_RADIUS


@njit(cache=True)
def newton_advance(x: FloatArray, px: FloatArray, jac: FloatArray, dx: FloatArray, work: FloatArray,
                   trial: FloatArray, p_trial: FloatArray, jac_trial: FloatArray, ok: bool, istate: IntArray,
                   rstate: FloatArray, tol: float, max_iter: int) -> int:
    """Advance Newton's method on P(x) - x = 0 to its next request or its verdict (module docstring).

    In place: x, px = P(x), jac = P'(x) the iterate (the caller fills px and jac for the start), dx its Newton
    step, work (n x (n + 1)); trial, p_trial, jac_trial the state the caller evaluates and its P and P'.
    ``istate`` (int64: phase, iteration, halvings, relaxations; zeros to start), ``rstate`` (float64: worst
    residual, relative residual, estimated distance, rho). Returns NEWTON_RADIUS (the caller puts the spectral
    radius of jac in rstate[3] and calls again), NEWTON_EVALUATE (the caller puts P(trial) into p_trial, P'(trial)
    into jac_trial and ``ok``: False where the map cannot be taken, a step LCP without a solution, and calls
    again), or a verdict of :mod:`converters.compiled`: NEWTON_CONVERGED (x + dx is within about its square of the
    orbit), NEWTON_ROUNDING, NEWTON_EXHAUSTED, NEWTON_SINGULAR (:func:`newton_step`), NEWTON_NO_SOLUTION or
    NEWTON_NONFINITE (a plain period the map could not take, or that left the finite numbers).

    Each iteration: the Newton step; halved while neither the residual falls nor the simplified Newton correction
    passes Deuflhard's restricted monotonicity test, up to ``HALVINGS`` times (the map is piecewise affine: the
    Jacobian of one piece can point past a change of mode sequence); where no fraction helps (a start-up
    transient), one plain period of the map."""
    n = x.shape[0]
    phase = istate[0]
    if phase == _NEW:
        istate[0] = _STEP
        return NEWTON_RADIUS
    if phase == _STEP:
        residual, worst, distance, verdict = newton_step(x, px, jac, rstate[3], dx, work, tol, istate[1], max_iter)
        rstate[1] = residual
        if verdict == NEWTON_SINGULAR:
            return verdict
        rstate[0] = worst
        rstate[2] = distance
        if verdict != NEWTON_CONTINUE:
            return verdict
        istate[2] = 0
        for i in range(n):
            trial[i] = x[i] + dx[i]
        istate[0] = _TRIAL
        return NEWTON_EVALUATE
    finite = True
    gap = 0.0
    for i in range(n):
        finite = finite and np.isfinite(p_trial[i])
        gap = max(gap, abs(p_trial[i] - trial[i]))
    if phase == _TRIAL:
        if ok and finite and gap < rstate[0]:
            return _accept(x, px, jac, trial, p_trial, jac_trial, istate)
        if ok and finite:
            # Deuflhard's restricted monotonicity test: the step of fraction lam brings the simplified correction
            # below (1 - lam/2) of the full Newton step. It accepts what the residual's max-norm refuses when the
            # residual is in one unit and the distance in another (a DCM buck into a 1 F output: its inductor's
            # residual rises while vout's distance falls 2-4x a step).
            lam = 0.5 ** istate[2]
            full = 0.0
            for i in range(n):
                full = max(full, abs(dx[i]))
            full /= lam
            # the simplified Newton correction at the trial, with the iterate's Jacobian
            if _solve_shifted(jac, trial, p_trial, work) < (1.0 - 0.5 * lam) * full:
                return _accept(x, px, jac, trial, p_trial, jac_trial, istate)
        istate[2] += 1
        if istate[2] < HALVINGS:
            for i in range(n):
                dx[i] *= 0.5
                trial[i] = x[i] + dx[i]
            return NEWTON_EVALUATE
        istate[3] += 1
        for i in range(n):
            trial[i] = px[i]
        istate[0] = _PLAIN
        return NEWTON_EVALUATE
    if not ok:
        return NEWTON_NO_SOLUTION
    if not finite:
        return NEWTON_NONFINITE
    return _accept(x, px, jac, trial, p_trial, jac_trial, istate)
