"""The one-step matrices of the theta-method: the only place their formulas live.

For a configuration (A, B, C, D, E, F), a step dt and theta:
    W     = (I - dt theta A)^-1
    Phi   = W (I + dt (1 - theta) A)        x_free = Phi x_k + Gamma
    Gamma = dt W E
    H     = dt W B                          x_{k+1} = x_free + H u_{k+1}
    M     = D + C H                         q = C x_free + F,  y_{k+1} = q + M u_{k+1}
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..problems import Configuration


@dataclass(frozen=True)
class StepMatrices:
    """Stacked one-step matrices; entry s is one (configuration, dt) pair.

    Shapes: Phi (m, n, n), Gamma (m, n), H (m, n, k), C (m, k, n), F (m, k), M (m, k, k).
    """

    Phi: np.ndarray
    Gamma: np.ndarray
    H: np.ndarray
    C: np.ndarray
    F: np.ndarray
    M: np.ndarray


def step_matrices(configs: list[Configuration], dts: np.ndarray, theta: float) -> StepMatrices:
    """One-step matrices for configs[i] over dts[i], batched (one LAPACK call for all of them)."""
    dts = np.asarray(dts, dtype=float)
    A = np.stack([c.A for c in configs])
    B = np.stack([c.B for c in configs])
    E = np.stack([c.E for c in configs])
    C = np.stack([c.C for c in configs])
    n = A.shape[1]
    eye = np.eye(n)[None]
    lhs = eye - (dts * theta)[:, None, None] * A
    rhs_phi = eye + (dts * (1.0 - theta))[:, None, None] * A
    # Solve for [Phi | W E | W B] at once.
    rhs = np.concatenate([rhs_phi, (dts[:, None] * E)[:, :, None], dts[:, None, None] * B], axis=2)
    sol = np.linalg.solve(lhs, rhs)
    Phi, Gamma, H = sol[:, :, :n], sol[:, :, n], sol[:, :, n + 1:]
    M = np.stack([c.D for c in configs]) + C @ H
    F = np.stack([c.F for c in configs])
    return StepMatrices(*(np.ascontiguousarray(a) for a in (Phi, Gamma, H, C, F, M)))
