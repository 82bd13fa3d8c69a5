"""An orbit of a family that meets one more condition: the codimension-one point where a test function of the orbit
vanishes (an impact reaching a corner of the constraint, say), solved with its parameter value.

Why a loop of its own and not the one Newton driver (:mod:`converters.analysis.newton_kernel`): the driver solves
P(x) - x = 0 over the state alone, its matrix J - I and its stopping rule the distance to the orbit estimated from
the map's multipliers (max |dx|, |P(x) - x| / (1 - rho)); here the unknowns are (x, p) with a bordering row, the
matrix is not J - I and has no multipliers to estimate a distance from, so the step is the extended system's and the
rule is its own (tests/test_architecture.py lists the Newton loops by structure, this one with its reason)."""
from __future__ import annotations

from collections.abc import Callable

import numpy as np
import numpy.typing as npt

from .family import OrbitFamily


def locate_condition(family: OrbitFamily, condition: Callable[[float, npt.NDArray[np.float64]], float], value: float,
                     x0: npt.ArrayLike, *, tol: float = 1e-11, iterations: int = 20,
                     step: float = 1e-7) -> tuple[float, np.ndarray, float, float]:
    """(value, x0, residual, condition) of the orbit of ``family`` on which ``condition(value, x)`` vanishes, from
    an orbit (value, x0) near it: Newton on P^k(x; p) - x = 0 and condition(p, x) = 0 in (x, p) together, the
    bordered Jacobian [[J - I, dP/dp], [dc/dx, dc/dp]] with the map's own J and the rest by central differences
    (relative ``step``). The condition need only be C1 across the point (a corner of the map, where J jumps, is
    passed: each side's J serves its side). Stops when the orbit's residual is at most tol (1 + |x|) and
    |condition| at most tol, or after ``iterations``; returns the last iterate with both residuals. (The engine's
    driver, :mod:`converters.analysis.newton_kernel`, solves for x at a fixed p and stops on the multipliers'
    distance estimate; this system has p among its unknowns and a second equation, so it has a loop of its own.)"""
    x = np.array(x0, dtype=float)
    n = x.size
    for _ in range(iterations):
        end, jac = family.period_map(value)(x)
        residual = end - x
        off = float(condition(value, x))
        if np.abs(residual).max() <= tol * (1.0 + np.abs(x).max()) and abs(off) <= tol:
            break
        dp = step * max(abs(value), 1.0)
        bordered = np.zeros((n + 1, n + 1))
        bordered[:n, :n] = jac - np.eye(n)
        bordered[:n, n] = (family.period_map(value + dp).end(x) - family.period_map(value - dp).end(x)) / (2.0 * dp)
        for j in range(n):
            dx = step * (1.0 + abs(x[j]))
            e = np.zeros(n)
            e[j] = dx
            bordered[n, j] = (condition(value, x + e) - condition(value, x - e)) / (2.0 * dx)
        bordered[n, n] = (condition(value + dp, x) - condition(value - dp, x)) / (2.0 * dp)
        delta = np.linalg.solve(bordered, -np.append(residual, off))
        x, value = x + delta[:n], value + float(delta[n])
    end = family.period_map(value).end(x)
    return float(value), x, float(np.abs(end - x).max()), float(condition(value, x))
