"""One entry point for every LCP solver: :func:`solve_lcp`."""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from .. import limits
from ..errors import LCPError
from ..validate import as_matrix, as_vector
from . import fastpaths
from .enumeration import enumerate_bases
from .lemke import lemke
from .murty import murty
from .newton import newton_fb
from .pgs import pgs
from .result import SOLVED, LCPResult, finish

SOLVERS = {"lemke": lemke, "murty": murty, "enum": enumerate_bases, "pgs": pgs, "newton": newton_fb}
DEFAULT_MAX_ITER = {"lemke": 10_000, "murty": 100_000, "enum": None, "pgs": 10_000, "newton": 1000}
#: Accepted range of ``tol`` (below 1e-16 double precision cannot resolve it; above 1e-2 it is no solution).
TOL_RANGE = (1e-16, 1e-2)
#: Accepted range of ``max_iter``: every iteration costs at least a microsecond, so 10^9 is already beyond any
#: time limit; larger values are refused rather than silently meaningless.
MAX_ITER_RANGE = (1, 10**9)
#: Seconds one solve may take when neither ``time_limit`` nor --time-limit / PCSUITE_TIME_LIMIT is given.
DEFAULT_TIME_LIMIT = 20.0
#: Working memory of each method in k x k arrays of doubles, M and its normalised copy included:
#: Lemke's k x (2k + 2) tableau (2), the rank-one update's temporary (2) and the lexicographic keys (1);
#: Murty's M_JJ and its LU copy; Newton's identity, Jacobian, two temporaries and the LU copy.
WORK_ARRAYS = {"lemke": 7, "murty": 4, "enum": 3, "pgs": 3, "newton": 7}


def solve_lcp(M, q, method: str = "lemke", tol: float = 1e-10, max_iter: int | None = None,
              fast_paths: bool = True, time_limit: float | None = None, **options) -> LCPResult:
    """Solve LCP(q, M): find z >= 0 with w = q + M z >= 0 and z . w = 0.

    The solvers work on the normalised problem q' = q / s, M' = M / m (s ~ max|q|, m ~ max|M|, rounded to
    powers of two so that the scaling is exact); z solves LCP(q, M) iff z' = m z / s solves LCP(q', M'). The
    answer is scaled back and checked on the original problem, so q or M of any magnitude (1e-200, 1e200)
    is solved as well as at magnitude 1, and a z that under- or overflows when scaled back is reported.

    Parameters
    ----------
    M : array_like, shape (k, k)
    q : array_like, shape (k,)
    method : {'lemke', 'murty', 'enum', 'pgs', 'newton'}
        Lemke (complementary pivoting, lexicographic), Murty (least-index principal pivoting),
        enumeration of all complementary bases (k <= 12; returns every basic solution),
        projected Gauss-Seidel (symmetric PD M), semismooth Newton on Fischer-Burmeister.
    tol : float in [1e-16, 1e-2]
        Accepted residual err = ||z - max(0, z - w)|| / ||q||, and the relative tolerance of the checks
        z >= 0, w >= 0, min(z_i, w_i) = 0 (see :func:`converters.lcp.result.finish`).
    max_iter : int in [1, 10**9], optional
        Pivots, sweeps or Newton steps; a method-specific default when omitted.
    fast_paths : bool
        Use the closed forms for q >= 0, k = 1 and k = 2 (not for ``enum``, which lists all solutions).
    time_limit : float, optional
        Seconds the solve may take (0.1 .. 7 days); when omitted, --time-limit / PCSUITE_TIME_LIMIT, else
        20 s. A solve that reaches it returns ``failed`` with a message saying so.
    **options
        Method-specific: ``omega`` (pgs), ``pivot_tol`` (lemke).

    Returns
    -------
    LCPResult
        Never a silent wrong answer: ``solved`` only when z >= 0, w >= 0, z . w = 0 (relative to the
        problem's scale) and err <= tol hold on the original problem.
    """
    if method not in SOLVERS:
        raise LCPError(f"method must be one of {', '.join(SOLVERS)}; got {method!r}")
    M, q = check_lcp(M, q)
    if not (isinstance(tol, (int, float, np.integer, np.floating)) and not isinstance(tol, bool)
            and TOL_RANGE[0] <= tol <= TOL_RANGE[1]):
        raise LCPError(f"tol must be in [{TOL_RANGE[0]:g}, {TOL_RANGE[1]:g}]; got {tol!r}")
    tol = float(tol)
    if max_iter is not None and DEFAULT_MAX_ITER[method] is None:
        raise LCPError(f"max_iter does not apply to method {method!r} (it visits every complementary basis once; "
                       f"k <= 12); got max_iter = {max_iter!r}")
    if max_iter is None:
        max_iter = DEFAULT_MAX_ITER[method]
    elif not (isinstance(max_iter, (int, np.integer)) and not isinstance(max_iter, bool)
              and MAX_ITER_RANGE[0] <= max_iter <= MAX_ITER_RANGE[1]):
        raise LCPError(f"max_iter must be an integer in [{MAX_ITER_RANGE[0]}, {MAX_ITER_RANGE[1]}]; got {max_iter!r}")
    seconds = check_time_limit(time_limit)
    k = q.shape[0]
    limits.check_memory(f"solve_lcp (method {method}): k = {k} ({WORK_ARRAYS[method]} work arrays of k x k doubles)",
                        8.0 * WORK_ARRAYS[method] * k * k, remedy="a smaller problem")
    deadline = limits.Deadline(seconds)
    Ms, qs, shift = normalise(M, q)
    if fast_paths and method != "enum":
        for rule in (fastpaths.trivial, fastpaths.scalar, fastpaths.pair):
            z = rule(Ms, qs)
            if z is not None:    # checked once, on the original problem
                result = finish(M, q, np.ldexp(z, shift) if shift else z, status=SOLVED, iterations=0,
                                method=method, tol=tol, message=f"closed form ({rule.__name__})")
                if result.solved:
                    return result
    result = SOLVERS[method](Ms, qs, tol=tol, max_iter=max_iter, deadline=deadline, **options)
    return unscale(result, M, q, shift, tol)


def check_time_limit(time_limit) -> float:
    """Seconds for one solve: ``time_limit`` when given (checked), else --time-limit / PCSUITE_TIME_LIMIT, else 20 s."""
    if time_limit is None:
        return limits.time_limit(DEFAULT_TIME_LIMIT)
    low, high = limits.TIME_RANGE
    if not (isinstance(time_limit, (int, float, np.integer, np.floating)) and not isinstance(time_limit, bool)
            and low <= time_limit <= high):
        raise LCPError(f"time_limit must be a number of seconds in [{low:g}, {high:g}]; got {time_limit!r}")
    return float(time_limit)


def normalise(M: np.ndarray, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, int]:
    """(M / 2^em, q / 2^es, es - em) with 2^es ~ max|q|, 2^em ~ max|M| (exact: powers of two); a zero M or q is
    left as it is. z = z' 2^(es - em) maps solutions of the normalised problem back."""
    qbig = float(np.abs(q).max())
    mbig = float(np.abs(M).max())
    es = math.frexp(qbig)[1]    # 0 when qbig = 0
    em = math.frexp(mbig)[1]
    Ms = np.ldexp(M, -em) if em else M
    qs = np.ldexp(q, -es) if es else q
    return Ms, qs, es - em


def unscale(result: LCPResult, M, q, shift: int, tol: float) -> LCPResult:
    """The result of the normalised problem as a result of LCP(q, M), checked again on (q, M)."""
    with np.errstate(all="ignore"):
        z = np.ldexp(result.z, shift) if shift else result.z
        solutions = [np.ldexp(s, shift) for s in result.solutions] if shift else result.solutions
    final = finish(M, q, z, status=result.status, iterations=result.iterations, method=result.method, tol=tol,
                   message=result.message, solutions=solutions)
    if result.solved and not final.solved:   # solved when normalised, not once z is scaled back by 2^shift
        final = replace(final, message=f"{final.message} (z solves the normalised problem but not once scaled back "
                                       f"by 2^{shift}: the solution is not representable in double precision)")
    return final


def check_lcp(M, q) -> tuple[np.ndarray, np.ndarray]:
    """Validate shapes and finiteness; returns float arrays (M is k x k, q has length k)."""
    try:
        M = as_matrix("M", M, (None, None))
        if M.shape[0] != M.shape[1]:
            raise LCPError(f"M must be square (k x k); got shape {M.shape[0]}x{M.shape[1]}")
        q = as_vector("q", q, M.shape[0])
    except LCPError:
        raise
    except ValueError as exc:
        raise LCPError(str(exc)) from None
    if M.shape[0] == 0:
        raise LCPError("M must be at least 1x1; got an empty matrix")
    return M, q
