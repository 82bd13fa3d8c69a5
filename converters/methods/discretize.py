"""The one-step matrices of the theta-method.

For a configuration (A, B, C, D, E, F), a step dt and theta:
    W     = (I - dt theta A)^-1
    Phi   = W (I + dt (1 - theta) A)        x_free = Phi x_k + Gamma
    Gamma = dt W E
    H     = dt W B                          x_{k+1} = x_free + H u_{k+1}
    M     = D + C H                         q = C x_free + F,  y_{k+1} = q + M u_{k+1}

and the same step as affine maps of x_k (:func:`.theta_kernels.branch_maps`): q = CPhi x_k + q0 with
CPhi = C Phi, q0 = C Gamma + F; for one pair, x_{k+1} = Phi_b[0] x_k + Gamma_b[0] when it is free (q >= 0)
and Phi_b[1] x_k + Gamma_b[1] = (Phi - H CPhi / M) x_k + Gamma - H q0 / M when it is held (q < 0).

The arithmetic is :func:`.theta_kernels.theta_matrices` (compiled, one elimination per distinct A, B, C, D and
step: sets that differ only in E, F share it), the one the
state-driven loops and the batched steady states use too: a plan's matrices are the same to the last bit
whichever path builds them.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from ..problems import Configuration, Jump
from ..compiled import kernel


@dataclass(frozen=True)
class StepMatrices:
    """Stacked one-step matrices; entry s is one (configuration, dt) pair.

    Shapes: Phi (m, n, n), Gamma (m, n), H (m, n, k), C (m, k, n), F (m, k), M (m, k, k); the affine maps
    (module docstring) Phi_b (m, 2, n, n), Gamma_b (m, 2, n) (branch 0: every pair free; 1: the one pair
    held), CPhi (m, k, n), q0 (m, k).
    """

    Phi: np.ndarray
    Gamma: np.ndarray
    H: np.ndarray
    C: np.ndarray
    F: np.ndarray
    M: np.ndarray
    Phi_b: np.ndarray
    Gamma_b: np.ndarray
    CPhi: np.ndarray
    q0: np.ndarray

    def __len__(self) -> int:
        sets: int = self.Phi.shape[0]
        return sets

    def concatenate(self, other: "StepMatrices") -> "StepMatrices":
        """These sets followed by ``other``'s."""
        return StepMatrices(*(np.ascontiguousarray(np.concatenate([getattr(self, f), getattr(other, f)]))
                              for f in self.__dataclass_fields__))


def step_matrices(configs: list[Configuration], dts: np.ndarray, theta: float) -> StepMatrices:
    """One-step matrices for configs[i] over dts[i], and their affine maps (one compiled call for all of them:
    :func:`.theta_kernels.theta_matrices`, the formulas above, as the batched steady states use them)."""
    dts = np.ascontiguousarray(dts, dtype=float)
    A, B, C, D, E, F = (np.ascontiguousarray(np.stack([getattr(c, key) for c in configs], dtype=float))
                        for key in "ABCDEF")
    sets, n, k = A.shape[0], A.shape[1], B.shape[2]
    Phi, Gamma, H, M = np.empty((sets, n, n)), np.empty((sets, n)), np.empty((sets, n, k)), np.empty((sets, k, k))
    Phi_b, Gamma_b = np.empty((sets, 2, n, n)), np.empty((sets, 2, n))
    CPhi, q0 = np.empty((sets, k, n)), np.empty((sets, k))
    if not kernel("set_matrices")(A, B, C, D, E, F, dts, float(theta), _leaders(configs, dts), Phi, Gamma, H, M,
                                  Phi_b, Gamma_b, CPhi, q0):
        raise np.linalg.LinAlgError("Singular matrix")
    for s, c in enumerate(configs):
        if c.jump is not None:
            _fold_jump(s, c.jump, Phi, Gamma, H, C, F, M, Phi_b, Gamma_b, CPhi, q0)
    return StepMatrices(Phi, Gamma, H, C, F, M, Phi_b, Gamma_b, CPhi, q0)


def _fold_jump(s: int, jump: Jump, Phi: npt.NDArray[np.float64], Gamma: npt.NDArray[np.float64],
               H: npt.NDArray[np.float64], C: npt.NDArray[np.float64], F: npt.NDArray[np.float64],
               M: npt.NDArray[np.float64], Phi_b: npt.NDArray[np.float64], Gamma_b: npt.NDArray[np.float64],
               CPhi: npt.NDArray[np.float64], q0: npt.NDArray[np.float64]) -> None:
    """Set s's step taken from the jumped state P x + q (:class:`~converters.problems.Jump`): Phi P and
    Gamma + Phi q, and its affine maps again (:func:`.theta_kernels.branch_maps`'s formulas). The jump is a
    projection, so every step of the configuration may take it: on a state already on its loops it is the
    identity, and the step keeps the loops (their constraint is linear and the scheme is), so the state moves only
    where the configuration is entered; the exact Jacobian of the period map then holds it too."""
    Gamma[s] = Gamma[s] + Phi[s] @ jump.q
    Phi[s] = Phi[s] @ jump.P
    CPhi[s] = C[s] @ Phi[s]
    q0[s] = C[s] @ Gamma[s] + F[s]
    Phi_b[s] = Phi[s]
    Gamma_b[s] = Gamma[s]
    if M.shape[1] == 1 and M[s, 0, 0] > 0.0:              # one pair: its held branch, u = -q / M
        Phi_b[s, 1] = Phi[s] - np.outer(H[s, :, 0], CPhi[s, 0]) / M[s, 0, 0]
        Gamma_b[s, 1] = Gamma[s] - H[s, :, 0] * q0[s, 0] / M[s, 0, 0]


def _leaders(configs: list[Configuration], dts: np.ndarray) -> np.ndarray:
    """For each set, the first set with the same A, B, C, D (by value) and step: its eliminations are shared
    (:func:`.theta_kernels.set_matrices`). A schedule's configurations often differ in E, F only (a PULSE
    source's levels and edges), and a sinusoidal input gives every step a set of its own with the same A..D."""
    values: dict[tuple[int, int, int, int], bytes] = {}
    firsts: dict[tuple[bytes, float], int] = {}
    leader = np.empty(len(configs), dtype=np.int32)
    for s, (c, dt) in enumerate(zip(configs, dts.tolist())):
        ident = (id(c.A), id(c.B), id(c.C), id(c.D))            # the configs are alive: ids are not reused
        value = values.get(ident)
        if value is None:
            value = values[ident] = b"".join(np.ascontiguousarray(getattr(c, key), dtype=float).tobytes()
                                             for key in "ABCD")
        leader[s] = firsts.setdefault((value, dt), s)
    return leader
