"""``simulate(problem, method)``: the one entry point from a problem to a Trajectory."""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import numpy.typing as npt

from .errors import ParameterError, SimulationError
from .methods.base import Method, load_methods
from .problems import LCSProblem
from .trajectory import Trajectory


def simulate(problem: LCSProblem, method: Method, *, x0: npt.ArrayLike | None = None) -> Trajectory:
    """Solve ``problem`` over its t_span with ``method``.

    Parameters
    ----------
    problem : LCSProblem
    method : Method
        ``Theta(h, theta)`` / ``BackwardEuler(h)`` (the LCP time-stepper), ``EventDriven(...)``
        (exact, event-driven) or ``Smoothing(eps, rtol)`` (smoothed pairs, a stiff solver); any
        :class:`~converters.methods.base.Method`.
    x0 : array_like, shape (n,), optional
        Overrides ``problem.x0`` (cheap restarts for shooting and steady-state searches).

    Returns
    -------
    Trajectory
    """
    if not isinstance(method, Method):
        raise ParameterError(f"method must be a pcsuite method ({', '.join(f'{k}: {c.__name__}' for k, c in load_methods().items())}"
                             f"); got {method!r}")
    if not isinstance(problem, LCSProblem) and not hasattr(problem, "t_span"):
        raise ParameterError(f"problem must be an LCSProblem (or a mechanical problem); got {problem!r}")
    method.supports(problem)
    method.check_memory(problem)
    start = check_x0(problem, x0)
    trajectory = method.solve(problem, start)
    # inf and NaN are absorbing: a state that left the finite numbers is not finite at the end (one look, O(1))
    if not np.all(np.isfinite(trajectory.x[-1])):
        bad = np.flatnonzero(~np.all(np.isfinite(trajectory.x), axis=1))
        raise SimulationError(f"the state left the finite numbers at t = {trajectory.t[bad[0]]:.6g} s (x0 = "
                              f"{np.array2string(start, precision=3)}): a start or a parameter "
                              "beyond what double precision can carry")
    return replace(trajectory, problem=problem, algorithm=method)


def check_x0(problem: LCSProblem, x0: npt.ArrayLike | None = None) -> np.ndarray:
    """``problem.x0`` when x0 is None, else x0 checked to be n finite numbers."""
    if x0 is None:
        return np.array(problem.x0, dtype=float)
    try:
        x = np.asarray(x0, dtype=float)
    except (TypeError, ValueError):
        raise ParameterError(f"x0 must be {problem.n} finite numbers; got {x0!r}") from None
    if x.shape != (problem.n,) or not np.all(np.isfinite(x)):
        raise ParameterError(f"x0 must be {problem.n} finite numbers; got {x0!r}")
    return x
