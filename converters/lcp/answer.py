"""What :func:`converters.lcp.solve_lcp` returns (:class:`LCPResult`) and its statuses: plain Python, so the
compiled solve path can build its answer without importing the compiled modules."""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    import numpy.typing as npt

SOLVED = "solved"
NO_SOLUTION = "no_solution"
MAX_ITERATIONS = "max_iterations"
FAILED = "failed"
STATUSES = (SOLVED, NO_SOLUTION, MAX_ITERATIONS, FAILED)   # the compiled code's status numbers index this tuple


@dataclass(frozen=True, slots=True)
class LCPResult:
    """Outcome of :func:`solve_lcp`.

    Attributes
    ----------
    z, w : ndarray, shape (k,)
        The complementary pair, w = q + M z (the last iterate when not solved).
    status : str
        ``solved``, ``no_solution`` (proven: Lemke's ray with a row of w negative for every z >= 0 or with
        M positive semidefinite, hence copositive-plus; or no feasible complementary basis, enumeration),
        ``max_iterations`` or ``failed`` (a ray that proves nothing is ``failed``: a solution may exist).
    err : float
        ||z - max(0, z - w)|| / ||q|| of the returned z.
    iterations : int
        Pivots (pivoting methods), sweeps (PGS), Newton steps or visited bases (enumeration); for
        ``auto``, those of the method that produced the answer.
    method : str
        The method that produced the answer; ``auto:<method>`` when ``auto`` chose it.
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


_new = object.__new__
#: the fields' slot descriptors: a frozen dataclass sets its fields through them (object.__setattr__ is what
#: its __init__ calls, and costs more)
_SLOTS = tuple(LCPResult.__dict__[name].__set__ for name in ("z", "w", "status", "err", "iterations", "method",
                                                            "message", "solutions"))
_Z, _W, _STATUS, _ERR, _ITERATIONS, _METHOD, _MESSAGE, _SOLUTIONS = _SLOTS


def make_result(z: npt.NDArray[np.float64], w: npt.NDArray[np.float64], status: str, err: float, iterations: int,
                method: str, message: str = "",
                solutions: list[npt.NDArray[np.float64]] | None = None) -> LCPResult:
    """An LCPResult built without the frozen dataclass's per-field ``object.__setattr__`` (a quarter of the
    cost of a small solve); the same object as ``LCPResult(...)``."""
    result = _new(LCPResult)
    _Z(result, z)
    _W(result, w)
    _STATUS(result, status)
    _ERR(result, err)
    _ITERATIONS(result, iterations)
    _METHOD(result, method)
    _MESSAGE(result, message)
    _SOLUTIONS(result, [] if solutions is None else solutions)
    return result
