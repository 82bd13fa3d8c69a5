"""``method="auto"``: choose a method by size and structure, fall back on failure (compiled, resumable).

The plan (closed forms for q >= 0, k = 1, k = 2 and a triangular M with a positive diagonal are tried before it
by :func:`converters.lcp.solve_lcp`):

1. **pgs** first when M is symmetric with a positive diagonal (the structure of a symmetric positive
   definite M; definiteness itself is not tested: a Cholesky factorisation would cost a third of a Lemke
   run). It is a probe: at most max(8, k/2) sweeps (a sweep and its check cost about 3 k^2, a Lemke run
   about k pivots of k^2, so this is at most half of one), and it stops as soon as the residual stops
   shrinking or its rate of decrease projects more sweeps than that (one sweep, on a problem it would
   take hundreds of sweeps to solve to tol). A strongly diagonally dominant M is solved in a few sweeps;
   otherwise the plan goes on.
2. **lemke** (lexicographic): it terminates on every problem (degenerate ones included) and solves every
   P-matrix, positive semidefinite or copositive-plus problem that has a solution. When it ends on a ray:
   - a row i with q_i < 0 and M_ij <= 0 for every j makes w_i < 0 for every z >= 0: **no_solution**, proven;
   - M positive semidefinite (least eigenvalue of (M + M^T)/2 >= -``PSD_TOL`` k max|M|) is copositive-plus,
     and then the ray proves that no solution exists: **no_solution** (a negative 2 x 2 principal minor
     disproves it at once; the eigenvalue, k^3 work outside the time slices, is computed for k <=
     ``PSD_MAX_K`` = 1000 only, a fraction of a second);
   - otherwise the ray proves nothing (a bimatrix game, for instance, has solutions Lemke with the covering
     vector 1 may miss), and the plan goes on.
3. **enum** when k <= 12: the first feasible complementary basis whose solution passes the check.
4. **newton** (Fischer-Burmeister): a different kind of method, which also reaches non-basic solutions.

The first solution that passes the check ends the plan (``result.method`` = ``auto:<method>``). When
every method ends without one, the status is ``failed``, with each method's reason in the message: no
proof of non-existence was found, so none is claimed. Murty is not in the plan: it
terminates only for P-matrices, which Lemke already solves. ``max_iter`` applies to each method (each
has its default otherwise).
"""
from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numba import njit

from . import state as S
from .dispatch import DEFAULT_MAX_ITER, advance_method, method_sizes
from .enumeration import MAX_K as ENUM_MAX_K

if TYPE_CHECKING:
    import numpy.typing as npt

    FloatArray = npt.NDArray[np.float64]
    IntArray = npt.NDArray[np.int64]

#: PGS's sweeps in the plan: max(PGS_MIN_SWEEPS, k // 2).
PGS_MIN_SWEEPS = 8
#: Tolerance of the positive semidefiniteness test, per unit of k, relative to max|M|.
PSD_TOL = 1e-13
#: Largest k for which the least eigenvalue is computed (no proof is attempted above).
PSD_MAX_K = 1000


@njit(cache=True, _nrt=False)
def first_stage(M: FloatArray) -> int:
    """PGS when M is symmetric with a positive diagonal, else Lemke."""
    k = M.shape[0]
    for i in range(k):
        if not M[i, i] > 0.0:
            return S.LEMKE
        for j in range(i):
            if M[i, j] != M[j, i]:
                return S.LEMKE
    return S.PGS


@njit(cache=True, _nrt=False)
def stage_max_iter(stage: int, max_iter: int, k: int) -> int:
    """max_iter of a method of the plan: the caller's (> 0) or the method's default; PGS at most max(8, k/2)."""
    limit = max_iter if max_iter > 0 else DEFAULT_MAX_ITER[stage]
    if stage == S.PGS:
        limit = min(limit, max(PGS_MIN_SWEEPS, k // 2))
    return limit


@njit(cache=True, _nrt=False)
def next_stage(stage: int, k: int) -> int:
    if stage == S.PGS:
        return S.LEMKE
    if stage == S.LEMKE:
        return S.ENUM if k <= ENUM_MAX_K else S.NEWTON
    if stage == S.ENUM:
        return S.NEWTON
    return S.AUTO     # none left


@njit(cache=True, _nrt=False)
def sizes(k: int) -> tuple[int, int]:
    """The workspace of the largest method of the plan (they run one after another in it)."""
    nf, ni = method_sizes(S.LEMKE, k, True)
    for method in (S.NEWTON, S.PGS, S.ENUM):
        if method == S.ENUM and k > ENUM_MAX_K:
            continue
        f, i = method_sizes(method, k, True)
        nf, ni = max(nf, f), max(ni, i)
    return nf, ni


@njit(cache=True, _nrt=False)
def infeasible_row(M: FloatArray, q: FloatArray) -> int:
    """A row i with q_i < 0 and M_ij <= 0 for every j (w_i < 0 for every z >= 0), or -1."""
    k = q.shape[0]
    for i in range(k):
        if q[i] < 0.0:
            nonpositive = True
            for j in range(k):
                if M[i, j] > 0.0:
                    nonpositive = False
                    break
            if nonpositive:
                return i
    return -1


@njit(cache=True, _nrt=False)
def semidefinite_by_minors(M: FloatArray, st: IntArray, sf: FloatArray) -> int:
    """Whether (M + M^T)/2 is positive semidefinite to ``PSD_TOL`` k max|M|, as far as the cheap tests tell:
    -1 disproved (a 2 x 2 principal submatrix's least eigenvalue bounds the whole matrix's from above) or
    not tested (k above PSD_MAX_K); 1 proven (M = 0); 0 when only the least eigenvalue can tell (the caller
    computes it, :func:`least_symmetric_eigenvalue`, and :func:`run` concludes with it)."""
    k = M.shape[0]
    big = 0.0
    for i in range(k):
        for j in range(k):
            big = max(big, abs(M[i, j]))
    if big == 0.0:
        st[S.PSD] = S.PSD_EIGENVALUE
        sf[S.INFO_X] = 0.0
        return 1
    bound = -PSD_TOL * k * big
    st[S.PSD] = S.PSD_MINOR
    for i in range(k):
        a = M[i, i]
        if a < bound:
            return -1
        for j in range(i):
            c, b = M[j, j], 0.5 * (M[i, j] + M[j, i])
            if 0.5 * (a + c) - np.sqrt(0.25 * (a - c) ** 2 + b * b) < bound:
                return -1
    if k > PSD_MAX_K:
        st[S.PSD] = S.PSD_UNTESTED
        return -1
    st[S.PSD] = S.PSD_EIGENVALUE
    return 0


@njit(cache=True, _nrt=False)
def proves_psd(eig: float, k: int) -> bool:
    """Whether the least eigenvalue of (M + M^T)/2 over max|M| shows M positive semidefinite (to PSD_TOL k,
    relative to max|M|, as the minors' bound): the proof after Lemke's ray."""
    return eig >= -PSD_TOL * k


@njit(cache=True)
def least_symmetric_eigenvalue(M: FloatArray) -> float:
    """The least eigenvalue of (M + M^T)/2 divided by max|M| (0 for M = 0)."""
    k = M.shape[0]
    sym = np.empty((k, k))
    big = 0.0
    for i in range(k):
        for j in range(k):
            sym[i, j] = 0.5 * (M[i, j] + M[j, i])
            big = max(big, abs(M[i, j]))
    if big == 0.0:
        return 0.0
    return np.linalg.eigvalsh(sym)[0] / big


@njit(cache=True, _nrt=False)
def run(M: FloatArray, q: FloatArray, z: FloatArray, fw: FloatArray, iw: IntArray, st: IntArray, sf: FloatArray,
        tol: float, max_iter: int, budget: int, opts: FloatArray) -> bool:
    """Advance the plan by slices of at most ``budget`` multiply-adds per method; True when it ended, with
    st[STATUS], st[OUTCOME] (OK, PROOF_ROW, PROOF_PSD or EXHAUSTED), st[USED] (the method that produced the
    answer, or the last one run), st[ITER] (its iterations), st[STAGE_OUTCOME + m] and st[STAGE_ITER + m]
    (what each method m of the plan ended with; -1 when it did not run) and sf[INFO_X] (the eigenvalue,
    when Lemke's ray made the plan compute it).

    Allocation-free, like every method: when Lemke's ray needs the least eigenvalue of (M + M^T)/2 (LAPACK,
    which allocates), it returns False with st[PHASE] = EIGENVALUE; the caller puts the eigenvalue in
    sf[INFO_X] (:func:`least_symmetric_eigenvalue`) and calls again (:func:`converters.lcp.engine.advance`)."""
    k = q.shape[0]
    if st[S.PHASE] == S.EIGENVALUE:   # Lemke's ray: the caller has put the least eigenvalue in sf[INFO_X]
        if proves_psd(sf[S.INFO_X], k):
            return _no_solution_psd(st)
        if not _next(st, k):
            return True
    if st[S.STAGE] == S.AUTO:       # not started
        for m in range(S.N_METHODS):
            st[S.STAGE_OUTCOME + m] = -1
            st[S.STAGE_ITER + m] = 0
        sf[S.INFO_X] = np.nan
        st[S.STAGE] = first_stage(M)
        st[S.PHASE] = S.START
    while True:
        stage = st[S.STAGE]
        if not advance_method(stage, M, q, z, fw, iw, st, sf, tol, stage_max_iter(stage, max_iter, k), budget,
                              opts, True):
            return False
        outcome = st[S.OUTCOME]
        st[S.STAGE_OUTCOME + stage] = outcome
        st[S.STAGE_ITER + stage] = st[S.ITER]
        st[S.USED] = stage
        if st[S.STATUS] == S.SOLVED:
            st[S.OUTCOME] = S.OK
            return True
        if stage == S.LEMKE and outcome == S.RAY:
            row = infeasible_row(M, q)
            if row >= 0:
                st[S.STATUS] = S.NO_SOLUTION
                st[S.OUTCOME] = S.PROOF_ROW
                st[S.INFO] = row
                return True
            verdict = semidefinite_by_minors(M, st, sf)
            if verdict == 1:
                return _no_solution_psd(st)
            if verdict == 0:         # the caller computes the eigenvalue (LAPACK allocates), then calls again
                st[S.PHASE] = S.EIGENVALUE
                return False
        if not _next(st, k):
            return True


@njit(cache=True, _nrt=False)
def _no_solution_psd(st: IntArray) -> bool:
    st[S.PHASE] = S.DONE
    st[S.STATUS] = S.NO_SOLUTION
    st[S.OUTCOME] = S.PROOF_PSD
    return True


@njit(cache=True, _nrt=False)
def _next(st: IntArray, k: int) -> bool:
    """Move the plan to its next method; False (with status failed) when none is left."""
    following = next_stage(st[S.STAGE], k)
    if following == S.AUTO:
        st[S.STATUS] = S.FAILED
        st[S.OUTCOME] = S.EXHAUSTED
        return False
    st[S.STAGE] = following
    st[S.PHASE] = S.START
    return True
