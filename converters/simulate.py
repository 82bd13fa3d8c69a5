"""``simulate(problem, method)``: the one entry point from a problem to a Trajectory."""
from __future__ import annotations

import time

import numpy as np

from .methods import EventDriven, Smoothing, Theta
from .methods.theta import StepPlan
from .problems import LCSProblem
from .trajectory import Trajectory


def simulate(problem: LCSProblem, method: Theta, *, x0=None) -> Trajectory:
    """Simulate an LCS with the theta time-stepper.

    Parameters
    ----------
    problem : LCSProblem
    method : Theta, EventDriven or Smoothing
        ``Theta(h, theta)`` or ``BackwardEuler(h)``: the LCP time-stepper (here);
        ``EventDriven(...)``: the exact event-driven method (:mod:`converters.methods.event`);
        ``Smoothing(eps, rtol)``: the smoothed diode and a stiff solver (:mod:`converters.methods.smoothing`).
    x0 : array_like, shape (n,), optional
        Overrides ``problem.x0`` (cheap restarts for shooting and steady-state searches).

    Returns
    -------
    Trajectory
    """
    if isinstance(method, EventDriven):
        from .methods.event import simulate_event
        solution = simulate_event(problem, method, x0=x0)
        period = problem.schedule.period
        scale = period if np.isfinite(period) else problem.t_span[1] - problem.t_span[0]
        return solution.trajectory(method.output_step or scale / 1000.0)
    if isinstance(method, Smoothing):
        from .methods.smoothing import simulate_smooth
        return simulate_smooth(problem, method, x0=x0)
    start_clock = time.perf_counter()
    plan = StepPlan.build(problem, method)
    return plan.trajectory(problem.x0 if x0 is None else x0, wall_s=time.perf_counter() - start_clock)
