"""The pseudo-arclength corrector in scaled variables: Newton on [F(x, p); t . (z - z_pred)] = 0, and the tangent
(the null vector of [J - I, F_p]).

Why a loop of its own and not the one Newton driver (:mod:`converters.analysis.newton_kernel`): the driver solves
P(x) - x = 0 over the state alone, its matrix J - I and its stopping rule the distance to the orbit estimated from
the map's multipliers (max |dx|, |P(x) - x| / (1 - rho)); here the unknowns are (x, p) with a bordering row, the
matrix is not J - I and has no multipliers to estimate a distance from, so the step is the extended system's and the
rule is its own (tests/test_architecture.py lists the Newton loops by structure, this one with its reason)."""
from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt

if TYPE_CHECKING:
    from .family import OrbitFamily


# --- the corrector ------------------------------------------------------------------------------------

@dataclass
class _Scaling:
    x_scale: float
    p_scale: float
    #: Relative step of the forward difference for F_p: 1e-7 suits exact maps; a map accurate to eps wants
    #: about sqrt(eps).
    fd_step: float = 1e-7

    def z(self, x: npt.ArrayLike, p: float) -> np.ndarray:
        return np.append(np.asarray(x, dtype=float) / self.x_scale, p / self.p_scale)

    def split(self, z: npt.NDArray[np.float64]) -> tuple[np.ndarray, float]:
        return z[:-1] * self.x_scale, float(z[-1] * self.p_scale)


@dataclass
class _Solved:
    z: np.ndarray
    x: np.ndarray
    value: float
    jacobian: np.ndarray
    tangent: np.ndarray
    iterations: int


def _extended_rows(family: OrbitFamily, scaling: _Scaling, x: npt.NDArray[np.float64], value: float,
                   fx: npt.NDArray[np.float64], jacobian: npt.NDArray[np.float64],
                   fp: npt.NDArray[np.float64] | None = None) -> tuple[np.ndarray, np.ndarray]:
    """[J - I, F_p p_scale / x_scale]: the Jacobian of F / x_scale in the scaled variables (F_p by a forward
    difference unless given)."""
    n = x.size
    if fp is None:
        step = scaling.fd_step * max(abs(value), scaling.p_scale)
        fp = (family.period_map(value + step).end(x) - x - fx) / step
    rows = np.empty((n, n + 1))
    rows[:, :n] = jacobian - np.eye(n)
    rows[:, n] = fp * scaling.p_scale / scaling.x_scale
    return rows, fp


def _null_vector(rows: np.ndarray) -> np.ndarray:
    """The unit null vector of an n x (n + 1) matrix (its last right singular vector)."""
    return np.linalg.svd(rows)[2][-1]


def _correct(family: OrbitFamily, scaling: _Scaling, z_start: npt.ArrayLike, normal: npt.NDArray[np.float64],
             anchor: npt.NDArray[np.float64], tol: float, max_iter: int = 10) -> _Solved | None:
    """Newton on [F(x, p) / x_scale; normal . (z - anchor)] = 0 from z_start (scaled variables). The column
    F_p is taken once at the start (a chord Newton in p: it moves little over one correction) and again at
    the solution for its tangent.

    Not the engine's driver (:mod:`converters.analysis.newton_kernel`): that one solves P(x) - x = 0 in x alone
    with J - I, stops on the distance to the orbit |r| / (1 - rho) from the multipliers and falls back on a plain
    period where Newton stalls; here p is an unknown, the matrix is bordered by F_p and the tangent's row, and
    neither that stopping rule nor a plain period (it would leave the hyperplane) applies."""
    z = np.array(z_start, dtype=float)
    n = z.size - 1
    A = np.empty((n + 1, n + 1))
    fp = None
    for iteration in range(1, max_iter + 1):
        x, value = scaling.split(z)
        try:
            fx, jac = family.residual(value, x)
            if not np.all(np.isfinite(fx)):
                return None
            A[:n], fp = _extended_rows(family, scaling, x, value, fx, jac, fp)
        except (ValueError, RuntimeError) as exc:        # a parameter or state the model or method refuses
            family.refusal = str(exc)
            return None
        A[n] = normal
        rhs = -np.append(fx / scaling.x_scale, normal @ (z - anchor))
        try:
            dz = np.linalg.solve(A, rhs)
        except np.linalg.LinAlgError:
            return None
        if not np.all(np.isfinite(dz)):
            return None
        z = z + dz
        if np.abs(dz).max() <= tol:
            x, value = scaling.split(z)
            fx, jac = family.residual(value, x)
            rows, _ = _extended_rows(family, scaling, x, value, fx, jac)
            tangent = _null_vector(rows)
            return _Solved(z, x, value, jac, tangent if tangent @ normal >= 0 else -tangent, iteration)
    return None


# --- following a branch -----------------------------------------------------------------------------
