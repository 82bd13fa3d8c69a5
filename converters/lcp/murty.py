"""Murty's least-index principal pivoting method (Bard-type), finite for P-matrices (compiled).

The basis is the set J of indices with z basic. Each iteration solves M_JJ z_J = -q_J, forms
w = q + M z and flips the least index whose basic variable is negative. On P-matrices this
terminates in at most 2^k pivots (Murty's exponential examples reach that bound), so a wall-clock
deadline (checked between slices of work) bounds the run. :func:`run` is resumable (see
:mod:`converters.lcp.lemke`). :func:`solve_warm` starts it from a given basis: the step loops' solver above
MAX_INLINE_K pairs, from the previous step's active set (one solve of the active block when the set still holds,
a few flips when it changes; finite for a P-matrix from any start: K. G. Murty, "Note on a Bard-type scheme for
solving the complementarity problem", Opsearch 11, 1974).
"""
from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numba import njit

from . import state as S
from .kernels import solve_augmented
from .result import CHECK_OK, check_scaled, error, mark_done, max_abs, max_abs_matrix

if TYPE_CHECKING:
    import numpy.typing as npt

    FloatArray = npt.NDArray[np.float64]
    IntArray = npt.NDArray[np.int64]
    BoolArray = npt.NDArray[np.bool_]


@njit(cache=True, _nrt=False)
def sizes(k: int) -> tuple[int, int]:
    """Doubles and integers of workspace: the augmented M_JJ | -q_J and w; the basis flags and J."""
    return k * (k + 1) + k, 2 * k


@njit(cache=True, _nrt=False, inline="always")
def _basis_affine(M: FloatArray, q: FloatArray, z: FloatArray, idx: IntArray, m: int, w: FloatArray) -> None:
    """w = q + M z with z zero outside the basis idx[:m]: :func:`.result.affine`'s sums (index order, q added
    last) without the k - m zero terms (few pairs conduct at once in a rectifier or a multiplier)."""
    for i in range(q.shape[0]):
        s = 0.0
        for r in range(m):
            s += M[i, idx[r]] * z[idx[r]]
        w[i] = q[i] + s


@njit(cache=True, _nrt=False)
def run(M: FloatArray, q: FloatArray, z: FloatArray, fw: FloatArray, iw: IntArray, st: IntArray, tol: float,
        max_iter: int, budget: int) -> bool:
    """Advance Murty by at most ``budget`` multiply-adds; True when finished (see ``lemke.run``)."""
    return _run(M, q, z, fw, iw, st, tol, max_iter, budget, -1.0)


@njit(cache=True, _nrt=False)
def _run(M: FloatArray, q: FloatArray, z: FloatArray, fw: FloatArray, iw: IntArray, st: IntArray, tol: float,
         max_iter: int, budget: int, m_big: float) -> bool:
    """:func:`run` with max|M| given (``m_big`` >= 0: a step loop's M is one of a few, its scale known) or found
    when the answer is checked (< 0)."""
    k = q.shape[0]
    aug = fw[:k * (k + 1)].reshape((k, k + 1))
    w = fw[k * (k + 1):k * (k + 1) + k]
    in_basis, idx = iw[:k], iw[k:2 * k]
    if st[S.PHASE] == S.START:
        in_basis[:] = 0
        z[:] = 0.0
        st[S.ITER] = 0
        st[S.PHASE] = S.RUNNING
    qbig = 0.0
    for i in range(k):
        qbig = max(qbig, abs(q[i]))
    scale = 1e-12 * (1.0 + qbig)
    iteration = st[S.ITER]
    while iteration <= max_iter:
        z[:] = 0.0
        m = 0
        for i in range(k):
            if in_basis[i]:
                idx[m] = i
                m += 1
        if m > 0:
            for r in range(m):
                for c in range(m):
                    aug[r, c] = M[idx[r], idx[c]]
                aug[r, m] = -q[idx[r]]
            if not solve_augmented(aug, m, 1):
                z[:] = 0.0
                st[S.ITER] = iteration
                return mark_done(st, S.FAILED, S.SINGULAR)
            for r in range(m):
                z[idx[r]] = aug[r, m]
        negative = -1
        _basis_affine(M, q, z, idx, m, w)
        for i in range(k):
            basic = z[i] if in_basis[i] else w[i]
            if negative < 0 and basic < -scale:
                negative = i
        if negative < 0:
            clipped = False
            for i in range(k):
                if not z[i] > 0.0:
                    clipped = clipped or z[i] != 0.0          # negative (or NaN): w changes
                    z[i] = 0.0
            st[S.ITER] = iteration
            if clipped:
                _basis_affine(M, q, z, idx, m, w)          # w of the clipped z
            if m_big < 0.0:
                m_big = max_abs_matrix(M)
            if check_scaled(max_abs(q), m_big, z, w, error(q, z, w), tol)[0] != CHECK_OK:
                return mark_done(st, S.FAILED, S.CHECK)
            return mark_done(st, S.SOLVED, S.OK)
        if iteration == max_iter:
            break
        in_basis[negative] = 1 - in_basis[negative]
        iteration += 1
        budget -= m * m * m // 3 + k * k + k
        if budget <= 0:    # the caller checks its deadline here, then calls again
            st[S.ITER] = iteration
            return False
    st[S.ITER] = max_iter
    return mark_done(st, S.MAX_ITERATIONS, S.MAXIT)


#: The check a warm solve's answer passes (solve_lcp's default tolerance).
WARM_TOL = 1e-10


@njit(cache=True)
def solve_warm(M: FloatArray, q: FloatArray, z: FloatArray, active: BoolArray, fw: FloatArray, iw: IntArray,
               st: IntArray, max_pivots: int, m_big: float) -> int:
    """LCP(q, M) by :func:`run` started from the basis ``active`` (True where z_i > 0 is guessed), which is left
    holding the solution's basis; z in place; ``fw``, ``iw``, ``st`` its workspace (:func:`sizes`, ST_SIZE).
    Returns the number of flips, or -1 when a principal block is singular, the answer fails the check or
    ``max_pivots`` flips did not end (the caller's general solver takes that LCP). ``m_big``: max|M| (the step
    loop's matrices are a few, each scanned once, not at every step's check)."""
    k = q.shape[0]
    for i in range(st.shape[0]):
        st[i] = 0
    st[S.PHASE] = S.RUNNING
    for i in range(k):
        iw[i] = 1 if active[i] else 0
    _run(M, q, z, fw, iw, st, WARM_TOL, max_pivots, np.int64(1) << 62, m_big)
    if st[S.STATUS] != S.SOLVED:
        return -1
    for i in range(k):
        active[i] = iw[i] != 0
    return st[S.ITER]


__all__ = ["run", "sizes", "solve_warm"]
