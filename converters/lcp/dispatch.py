"""One compiled switch over the five methods: advance the chosen one by a slice of work, size its workspace.

``opts`` holds the methods' options in a float64 array: OPT_PIVOT_TOL (lemke), OPT_OMEGA (pgs), OPT_RHO,
OPT_P, OPT_BETA, OPT_SIGMA (newton).
"""
from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numba import njit

from . import enumeration, lemke, murty, newton, pgs
from . import state as S

if TYPE_CHECKING:
    import numpy.typing as npt

    FloatArray = npt.NDArray[np.float64]
    IntArray = npt.NDArray[np.int64]

OPT_PIVOT_TOL, OPT_OMEGA, OPT_RHO, OPT_P, OPT_BETA, OPT_SIGMA = range(6)
N_OPTIONS = OPT_SIGMA + 1
DEFAULT_OPTIONS = np.array([lemke.PIVOT_TOL, 1.0, newton.RHO, newton.P, newton.BETA, newton.SIGMA])
#: max_iter of each method when the caller gives none (indexed by method code; enumeration has none).
DEFAULT_MAX_ITER = (0, 10_000, 100_000, 0, 10_000, 1000)


@njit(cache=True)
def default_options() -> FloatArray:
    """A fresh copy of :data:`DEFAULT_OPTIONS` (compiled: the ahead-of-time module holds it too)."""
    return DEFAULT_OPTIONS.copy()


@njit(cache=True, _nrt=False, inline='always')
def advance_method(method: int, M: FloatArray, q: FloatArray, z: FloatArray, fw: FloatArray, iw: IntArray,
                   st: IntArray, sf: FloatArray, tol: float, max_iter: int, budget: int, opts: FloatArray,
                   first: bool) -> bool:
    """Advance ``method`` (not auto) on LCP(q, M) by at most ``budget`` multiply-adds; True when it ended.
    ``first``: auto's use (enumeration stops at the first solution, PGS stops when converging too slowly)."""
    if method == S.LEMKE:
        return lemke.run(M, q, z, fw, iw, st, tol, max_iter, budget, opts[OPT_PIVOT_TOL])
    if method == S.MURTY:
        return murty.run(M, q, z, fw, iw, st, tol, max_iter, budget)
    if method == S.ENUM:
        return enumeration.run(M, q, z, fw, iw, st, tol, budget, first)
    if method == S.PGS:
        return pgs.run(M, q, z, fw, iw, st, sf, tol, max_iter, budget, opts[OPT_OMEGA], first)
    return newton.run(M, q, z, fw, iw, st, tol, max_iter, budget, opts[OPT_RHO], opts[OPT_P], opts[OPT_BETA],
                      opts[OPT_SIGMA])


@njit(cache=True, _nrt=False)
def method_sizes(method: int, k: int, first: bool) -> tuple[int, int]:
    """(doubles, integers) of workspace ``method`` (not auto) needs for size k (``first``: as auto runs it)."""
    if method == S.LEMKE:
        return lemke.sizes(k)
    if method == S.MURTY:
        return murty.sizes(k)
    if method == S.ENUM:
        return enumeration.sizes(k, not first)
    if method == S.PGS:
        return pgs.sizes(k)
    return newton.sizes(k)
