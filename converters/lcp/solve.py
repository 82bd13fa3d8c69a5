"""One entry point for every LCP solver: :func:`solve_lcp`."""
from __future__ import annotations

import numpy as np

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


def solve_lcp(M, q, method: str = "lemke", tol: float = 1e-10, max_iter: int | None = None,
              fast_paths: bool = True, **options) -> LCPResult:
    """Solve LCP(q, M): find z >= 0 with w = q + M z >= 0 and z . w = 0.

    Parameters
    ----------
    M : array_like, shape (k, k)
    q : array_like, shape (k,)
    method : {'lemke', 'murty', 'enum', 'pgs', 'newton'}
        Lemke (complementary pivoting, lexicographic), Murty (least-index principal pivoting),
        enumeration of all complementary bases (k <= 12; returns every basic solution),
        projected Gauss-Seidel (symmetric PD M), semismooth Newton on Fischer-Burmeister.
    tol : float
        Accepted residual err = ||z - max(0, z - w)|| / ||q||.
    max_iter : int, optional
        Pivots, sweeps or Newton steps; a method-specific default when omitted.
    fast_paths : bool
        Use the closed forms for q >= 0, k = 1 and k = 2 (not for ``enum``, which lists all solutions).
    **options
        Method-specific: ``omega`` (pgs), ``pivot_tol`` (lemke).

    Returns
    -------
    LCPResult
        Never a silent wrong answer: ``solved`` only when err <= tol.
    """
    if method not in SOLVERS:
        raise LCPError(f"method must be one of {', '.join(SOLVERS)}; got {method!r}")
    M, q = check_lcp(M, q)
    if not (np.isfinite(tol) and tol > 0.0):
        raise LCPError(f"tol must be a positive finite number; got {tol!r}")
    if max_iter is None:
        max_iter = DEFAULT_MAX_ITER[method]
    elif not (isinstance(max_iter, (int, np.integer)) and max_iter >= 1):
        raise LCPError(f"max_iter must be an integer >= 1; got {max_iter!r}")
    if fast_paths and method != "enum":
        for rule in (fastpaths.trivial, fastpaths.scalar, fastpaths.pair):
            z = rule(M, q)
            if z is not None:
                result = finish(M, q, z, status=SOLVED, iterations=0, method=method, tol=tol,
                                message=f"closed form ({rule.__name__})")
                if result.solved:
                    return result
    return SOLVERS[method](M, q, tol=tol, max_iter=max_iter, **options)


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
