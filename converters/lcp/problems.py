"""The project's own LCP problem set, generated in code (seeded, so every run sees the same problems).

Families: random P-matrices (positive definite and non-PD triangular ones), symmetric positive
definite, positive semidefinite with many solutions, degenerate (ties in the ratio test),
Murty's exponential family, and problems with no solution.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class LCPCase:
    name: str
    family: str
    M: np.ndarray
    q: np.ndarray
    solvable: bool          # a solution exists
    note: str = ""


def random_p_matrix(rng: np.random.Generator, k: int, kind: str = "pd") -> np.ndarray:
    """A random P-matrix of size k.

    kind ``pd``: positive definite, non-symmetric (G G^T / k + skew + I/2);
    ``spd``: symmetric positive definite; ``triangular``: upper triangular with positive
    diagonal and large off-diagonal entries (a P-matrix that is not positive definite).
    """
    if kind == "spd":
        G = rng.standard_normal((k, k))
        return G @ G.T / k + 0.5 * np.eye(k)
    if kind == "pd":
        G = rng.standard_normal((k, k))
        S = rng.standard_normal((k, k))
        return G @ G.T / k + (S - S.T) + 0.5 * np.eye(k)
    if kind == "triangular":
        U = np.triu(rng.uniform(-2.0, 2.0, (k, k)), 1)
        return U + np.diag(rng.uniform(0.5, 2.0, k))
    raise ValueError(f"kind must be one of pd, spd, triangular; got {kind!r}")


def murty_exponential(k: int) -> tuple[np.ndarray, np.ndarray]:
    """Murty's example: M = I + 2 * strict upper triangle, q = -1; least-index pivoting takes 2^k - 1 pivots."""
    return np.eye(k) + 2.0 * np.triu(np.ones((k, k)), 1), -np.ones(k)


def problem_set(seed: int = 20261122) -> list[LCPCase]:
    rng = np.random.default_rng(seed)
    cases: list[LCPCase] = []
    for k in (3, 8, 20):
        for kind in ("spd", "pd", "triangular"):
            M = random_p_matrix(rng, k, kind)
            cases.append(LCPCase(f"p_{kind}_{k}", f"P-matrix ({kind})", M, rng.standard_normal(k), True))
    M = np.array([[1.0, 1.0], [1.0, 1.0]])
    cases.append(LCPCase("psd_seed", "PSD, many solutions", M, np.array([-1.0, -1.0]), True,
                         "seed example: every z >= 0 with z1 + z2 = 1"))
    G = rng.standard_normal((6, 3))
    M = G @ G.T  # rank 3
    z_star = np.array([0.7, 0.0, 1.2, 0.0, 0.3, 0.0])
    w_star = np.array([0.0, 0.4, 0.0, 1.1, 0.0, 0.2])
    cases.append(LCPCase("psd_rank3_6", "PSD (rank-deficient)", M, w_star - M @ z_star, True,
                         "q = w* - M z* with a known complementary pair"))
    # Degenerate: several rows tie in the first ratio test and the solution sits on w = z = 0.
    M = random_p_matrix(rng, 6, "spd")
    z_star = np.array([1.0, 0.0, 2.0, 0.0, 0.0, 0.5])
    q = -M @ z_star
    q[[1, 3, 4]] = -(M @ z_star)[[1, 3, 4]]  # w = 0 where z = 0: doubly degenerate pairs
    cases.append(LCPCase("degenerate_6", "degenerate (w = z = 0)", M, q, True, "z* = (1,0,2,0,0,0.5)"))
    cases.append(LCPCase("degenerate_ties_4", "degenerate (ratio ties)", np.eye(4) + 0.5 * np.ones((4, 4)),
                         -np.ones(4), True, "all rows tie in the first pivot"))
    for k in (6, 10):
        M, q = murty_exponential(k)
        cases.append(LCPCase(f"murty_exp_{k}", "Murty exponential", M, q, True, f"Murty pivots 2^{k} - 1"))
    cases.append(LCPCase("no_solution_negI", "no solution", -np.eye(3), -np.ones(3), False, "M = -I, q = -1"))
    cases.append(LCPCase("no_solution_zero_row", "no solution", np.array([[0.0, 0.0], [1.0, 1.0]]),
                         np.array([-1.0, 1.0]), False, "w1 = -1 whatever z"))
    return cases
