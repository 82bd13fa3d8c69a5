"""The result of an LCP solve, the accuracy measure every solver is judged by, and the check that no
wrong answer is ever called solved."""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

SOLVED = "solved"
NO_SOLUTION = "no_solution"
MAX_ITERATIONS = "max_iterations"
FAILED = "failed"
STATUSES = (SOLVED, NO_SOLUTION, MAX_ITERATIONS, FAILED)


def scaled_norm(v: np.ndarray) -> float:
    """||v||_2 computed on v / max|v| (never underflows nor overflows in the sum of squares)."""
    v = np.asarray(v, dtype=float)
    big = float(np.abs(v).max(initial=0.0))
    if big == 0.0 or not math.isfinite(big):
        return big
    u = v / big
    return big * math.sqrt(float(u @ u))


def lcp_error(M: np.ndarray, q: np.ndarray, z: np.ndarray) -> float:
    """Siconos' accuracy measure err = ||z - max(0, z - w)||_2 / ||q||_2, w = q + M z.

    z - max(0, z - w) is evaluated as min(z, w) (the same number, without the cancellation of z - (z - w)),
    and both norms on vectors divided by their largest magnitude first, so that q = 1e-200 or 1e200
    neither underflows nor overflows. When q = 0 (then z = 0 is the answer) err is the absolute
    ||min(z, w)||.
    """
    z = np.asarray(z, dtype=float)
    with np.errstate(all="ignore"):
        return _error(q, z, q + M @ z)


def _error(q, z, w) -> float:
    """err of (z, w) (inside an errstate that ignores floating-point warnings)."""
    r = np.minimum(z, w)
    rbig = float(np.abs(r).max())
    if not rbig > 0.0:
        return 0.0 if rbig == 0.0 else float("nan")
    if rbig == math.inf:
        return math.inf
    qbig = float(np.abs(q).max())
    r = r / rbig
    rnorm = math.sqrt(float(r @ r))
    if qbig == 0.0:
        return rbig * rnorm
    u = q / qbig
    return (rbig / qbig) * (rnorm / math.sqrt(float(u @ u)))


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
    """Build the result, checking a claimed solution: it becomes ``failed`` (the message says which condition
    failed) unless z >= 0, w = q + M z >= 0 and min(z_i, w_i) = 0 hold to ``tol`` relative to the problem's
    own magnitudes (z against max(max|z|, max|q| / max|M|), w against max(max|q|, max|M| max|z|)) and
    err <= tol."""
    z = np.asarray(z, dtype=float)
    with np.errstate(all="ignore"):
        w = q + M @ z
        err = _error(q, z, w)
        if status == SOLVED:
            problem = check_solution(M, q, z, w, err, tol)
            if problem:
                status, message = FAILED, f"{method}: {problem}"
    return LCPResult(z=z, w=w, status=status, err=err, iterations=iterations, method=method,
                     message=message, solutions=list(solutions))


def accepts(M, q, z, tol) -> bool:
    """True when :func:`finish` would accept z as a solution (the stopping test of the iterative methods)."""
    with np.errstate(all="ignore"):
        w = q + M @ z
        return not check_solution(M, q, z, w, _error(q, z, w), tol)


def check_solution(M, q, z, w, err, tol) -> str:
    """'' when (z, w) solves LCP(q, M) to ``tol`` (scale-relative, see :func:`finish`), else which condition fails.

    Call it inside ``np.errstate(all="ignore")``: a huge M times a huge z may overflow the scale to inf, and then
    w is negligible against it, which is what the division says."""
    z_scale = float(np.abs(z).max())
    w_scale = float(np.abs(w).max())
    if not (math.isfinite(z_scale) and math.isfinite(w_scale)):
        return "the claimed solution is not finite (z or w = q + M z overflows); the problem is too badly scaled"
    q_big, m_big = float(np.abs(q).max()), float(np.abs(M).max())
    w_scale = max(q_big, m_big * z_scale)
    if m_big > 0.0:   # z's own unit is max|q| / max|M|: rounding noise in an all-but-zero z is not "the scale"
        z_scale = max(z_scale, q_big / m_big)
    zn = z / z_scale if z_scale > 0.0 else z    # z_scale = 0: z = 0 exactly
    wn = w / w_scale if w_scale > 0.0 else w    # w_scale = 0: w = q + M z = 0 exactly
    i = int(wn.argmin())
    if not wn[i] >= -tol:
        return (f"the claimed solution is infeasible: w[{i}] = {w[i]:.3g} < 0 ({wn[i]:.3g} relative to the "
                f"problem's scale max(|q|, |M| |z|) = {w_scale:.3g}; allowed -tol = {-tol:.3g})")
    i = int(zn.argmin())
    if not zn[i] >= -tol:
        return (f"the claimed solution is infeasible: z[{i}] = {z[i]:.3g} < 0 ({zn[i]:.3g} relative to "
                f"max(|z|, |q| / |M|) = {z_scale:.3g}; allowed -tol = {-tol:.3g})")
    gap = np.minimum(zn, wn)
    i = int(gap.argmax())
    if not gap[i] <= tol:
        return (f"the claimed solution is not complementary: z[{i}] = {z[i]:.3g} and w[{i}] = {w[i]:.3g} are "
                f"both positive (relative {zn[i]:.3g} and {wn[i]:.3g}; allowed tol = {tol:.3g})")
    if not err <= tol:
        return (f"final residual err = {err:.3g} exceeds tol = {tol:.3g} "
                f"(ill-conditioned principal submatrix?); try method='lemke' or 'enum'")
    return ""
