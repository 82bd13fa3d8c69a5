"""Thermal chains: a device's junction-to-case impedance as a Foster or a Cauer network.

A Foster chain is R_k, tau_k in series (each an R_k || C_k, tau_k = R_k C_k): its step response to a power P is
Z(t) P = P sum R_k (1 - exp(-t / tau_k)), which datasheets publish as Z_th,jc(t). A Cauer chain is a ladder of
capacitances to the thermal reference with resistances between them (junction first): its states are the
capacitances' temperatures, its response exp of a tridiagonal matrix, here by its eigen-decomposition (the
matrix is similar to a symmetric one, so the decomposition is real and well conditioned). In steady state both
carry P through the sum of their resistances.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from ..errors import ParameterError

KINDS = ("foster", "cauer")


@dataclass(frozen=True)
class ThermalChain:
    """``kind`` "foster" (``second`` the time constants tau_k, s) or "cauer" (``second`` the capacitances C_k,
    J/K, junction first); ``R`` the resistances (K/W)."""

    kind: str
    R: tuple[float, ...]
    second: tuple[float, ...]
    what: str = "thermal chain"

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise ParameterError(f"{self.what}: the kind must be foster or cauer; got {self.kind!r}")
        label = "tau (s)" if self.kind == "foster" else "C (J/K)"
        if not self.R or len(self.R) != len(self.second):
            raise ParameterError(f"{self.what}: one R (K/W) and one {label} per stage, at least one stage; got "
                                 f"{len(self.R)} and {len(self.second)}")
        for name, values in (("R (K/W)", self.R), (label, self.second)):
            if not all(np.isfinite(v) and v > 0 for v in values):
                raise ParameterError(f"{self.what}: every {name} must be a finite number > 0; got {list(values)}")

    @property
    def resistance(self) -> float:
        """Junction to case in steady state (K/W)."""
        return float(sum(self.R))

    def foster(self) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
        """(R_k, tau_k) of the Foster chain with the same step response (a Cauer chain's: its modes)."""
        if self.kind == "foster":
            return np.array(self.R), np.array(self.second)
        A, b = self._ladder()
        # A = -C^-1 G with G symmetric: S = C^1/2 (-A) C^-1/2 is symmetric, so eigh gives real modes
        c = np.sqrt(np.array(self.second))
        rates, V = np.linalg.eigh(-(c[:, None] * A) / c[None, :])
        # T_j(t) = e_0 . (I - exp(A t)) (-A)^-1 b P = P sum_k R_k (1 - exp(-rate_k t)), R_k = V_0k^2 / (C_0 rate_k)
        u = V / c[:, None]                            # right eigenvectors of -A (columns)
        w = V * c[:, None]                            # its left eigenvectors
        weights = u[0, :] * (w.T @ b) / rates
        return weights, 1.0 / rates

    def step(self, t: npt.ArrayLike, power: float) -> npt.NDArray[np.float64]:
        """The junction's rise over the case (K) at times t (s) after a power step (W) from equilibrium."""
        R, tau = self.foster()
        t = np.asarray(t, dtype=float)
        return power * np.sum(R * -np.expm1(-t[..., None] / tau), axis=-1)

    def _ladder(self) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
        """The Cauer ladder's dT/dt = A T + b P (T the capacitances' rises over the case, junction first; the last
        resistance to the case)."""
        R, C = np.array(self.R), np.array(self.second)
        n = R.size
        G = np.zeros((n, n))
        for k in range(n):                       # R_k between node k and node k + 1 (the case after the last)
            g = 1.0 / R[k]
            G[k, k] += g
            if k + 1 < n:
                G[k + 1, k + 1] += g
                G[k, k + 1] -= g
                G[k + 1, k] -= g
        b = np.zeros(n)
        b[0] = 1.0 / C[0]
        return -G / C[:, None], b
