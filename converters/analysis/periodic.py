"""Periodic steady states of a periodically switched LCS by shooting.

The time-stepper over one period is a map P: x(0) -> x(T). It is piecewise affine (affine while the
sequence of complementarity modes stays the same), so Newton's method on P(x) - x = 0 with a
finite-difference Jacobian usually lands on the fixed point in two or three iterations, where
brute-force simulation of a lightly damped ideal converter can need 10^4 periods or more. The fixed
point is the periodic orbit of the discrete scheme itself, so it is checked by simulating on.
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ..problems import LCSProblem
from ..methods import Theta
from ..methods.theta import StepPlan


@dataclass(frozen=True)
class ShootingResult:
    x: np.ndarray            # state at the start of the periodic orbit
    residual: float          # max |P(x) - x| / (1 + max |x|)
    iterations: int
    periods_simulated: int   # one-period map evaluations, Jacobian columns included
    converged: bool


def shoot(problem: LCSProblem, method: Theta, x_guess, tol: float = 1e-9, max_iter: int = 30,
          plan: StepPlan | None = None) -> ShootingResult:
    """Newton's method on P(x) - x = 0, P being one period of ``problem`` (its t_span is one period).

    ``plan``: a prebuilt :class:`StepPlan` of that problem and method (saves rebuilding it)."""
    plan = plan or StepPlan.build(problem, method)  # grid and matrices once; each evaluation is one compiled loop
    return newton_fixed_point(lambda x0: plan.advance(x0)[0][-1], x_guess, tol=tol, max_iter=max_iter)


def newton_fixed_point(period_map, x_guess, tol: float = 1e-9, max_iter: int = 30) -> ShootingResult:
    """Newton's method with a finite-difference Jacobian on P(x) - x = 0 for any one-period map P.

    The residual is max |P(x) - x| / (1 + max |x|). Steps are halved (up to 12 times) when the
    affine model overshoots because the sequence of modes changed."""
    x = np.array(x_guess, dtype=float)
    n = x.size
    evaluations = 0

    def evaluate(x0):
        nonlocal evaluations
        evaluations += 1
        return period_map(x0)

    px = evaluate(x)
    residual = np.inf
    for iteration in range(1, max_iter + 1):
        r = px - x
        scale = 1.0 + np.abs(x).max()
        residual = float(np.abs(r).max() / scale)
        if residual < tol:
            return ShootingResult(x, residual, iteration - 1, evaluations, True)
        jac = np.empty((n, n))
        for j in range(n):
            dx = 1e-7 * (1.0 + abs(x[j]))
            probe = x.copy()
            probe[j] += dx
            jac[:, j] = (evaluate(probe) - px) / dx
        try:
            step = np.linalg.solve(jac - np.eye(n), -r)
        except np.linalg.LinAlgError:
            break
        for _ in range(12):
            trial = x + step
            p_trial = evaluate(trial)
            if np.all(np.isfinite(p_trial)) and np.abs(p_trial - trial).max() < np.abs(r).max():
                break
            step *= 0.5
        x, px = trial, p_trial
    return ShootingResult(x, residual, max_iter, evaluations, False)


def one_period(problem: LCSProblem, period: float) -> LCSProblem:
    t0 = problem.t_span[0]
    return replace(problem, t_span=(t0, t0 + period))
