"""The result of an LCP solve, and the accuracy measure every solver is judged by."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

SOLVED = "solved"
NO_SOLUTION = "no_solution"
MAX_ITERATIONS = "max_iterations"
FAILED = "failed"
STATUSES = (SOLVED, NO_SOLUTION, MAX_ITERATIONS, FAILED)


def lcp_error(M: np.ndarray, q: np.ndarray, z: np.ndarray) -> float:
    """Siconos' accuracy measure err = ||z - max(0, z - w)||_2 / ||q||_2, w = q + M z.

    The norm of q is replaced by 1 when q = 0 (then z = 0 is the answer and err is absolute).
    """
    w = q + M @ z
    qnorm = float(np.linalg.norm(q))
    return float(np.linalg.norm(z - np.maximum(0.0, z - w))) / (qnorm if qnorm > 0.0 else 1.0)


@dataclass(frozen=True)
class LCPResult:
    """Outcome of :func:`solve_lcp`.

    Attributes
    ----------
    z, w : ndarray, shape (k,)
        The complementary pair, w = q + M z (the last iterate when not solved).
    status : str
        ``solved``, ``no_solution`` (ray termination: for copositive-plus M this proves that no
        solution exists), ``max_iterations`` or ``failed``.
    err : float
        ||z - max(0, z - w)|| / ||q|| of the returned z.
    iterations : int
        Pivots (pivoting methods), sweeps (PGS) or Newton steps.
    method : str
    message : str
        Why the solve did not succeed, with the remedy, or empty.
    solutions : list of ndarray
        Every basic solution (enumeration only).
    """

    z: np.ndarray
    w: np.ndarray
    status: str
    err: float
    iterations: int
    method: str
    message: str = ""
    solutions: list = field(default_factory=list)

    @property
    def solved(self) -> bool:
        return self.status == SOLVED

    def to_dict(self) -> dict:
        out = {"status": self.status, "method": self.method, "z": self.z.tolist(), "w": self.w.tolist(),
               "err": self.err, "iterations": self.iterations}
        if self.message:
            out["message"] = self.message
        if self.method == "enum":
            out["solutions"] = [s.tolist() for s in self.solutions]
        return out


def finish(M, q, z, *, status, iterations, method, tol, message="", solutions=()):
    """Build the result, checking the residual: a claimed solution above ``tol`` becomes ``failed``."""
    z = np.asarray(z, dtype=float)
    w = q + M @ z
    err = lcp_error(M, q, z)
    if status == SOLVED and not err <= tol:
        status = FAILED
        message = (f"{method}: final residual err = {err:.3g} exceeds tol = {tol:.3g} "
                   f"(ill-conditioned principal submatrix?); try method='lemke' or 'enum'")
    return LCPResult(z=z, w=w, status=status, err=err, iterations=iterations, method=method,
                     message=message, solutions=list(solutions))
