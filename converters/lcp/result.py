"""The result of an LCP solve, the accuracy measure every solver is judged by, and the check that no
wrong answer is ever called solved.

The measure (:func:`error`) and the check (:func:`check`) are compiled (numba, cached on disk): every method,
the compiled solve path of :func:`converters.lcp.solve_lcp` and :func:`finish` call these same two
functions; :func:`check_message` turns the check's code into the sentence a user reads.
"""
from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np
from numba import njit

from . import state as S
from .answer import FAILED, MAX_ITERATIONS, NO_SOLUTION, SOLVED, STATUSES, LCPResult, make_result  # noqa: F401

if TYPE_CHECKING:
    from collections.abc import Iterable

    import numpy.typing as npt

    FloatArray = npt.NDArray[np.float64]
    IntArray = npt.NDArray[np.int64]

#: The largest finite double: |x| <= _MAX_FLOAT is false for inf and NaN.
_MAX_FLOAT = 1.7976931348623157e308

#: Codes returned by :func:`check` (0: the pair solves the LCP).
CHECK_OK, CHECK_NOT_FINITE, CHECK_W_NEGATIVE, CHECK_Z_NEGATIVE, CHECK_NOT_COMPLEMENTARY, CHECK_RESIDUAL = range(6)


@njit(cache=True, _nrt=False, inline='always')
def mark_done(st: IntArray, status: int, outcome: int) -> bool:
    """End a compiled method's run in its state array (``state`` layout): done, with its status and why."""
    st[S.PHASE] = S.DONE
    st[S.STATUS] = status
    st[S.OUTCOME] = outcome
    return True


@njit(cache=True, _nrt=False, inline='always')
def affine(M: FloatArray, q: FloatArray, z: FloatArray, w: FloatArray) -> None:
    """w = q + M z (each sum_j M_ij z_j accumulated in index order, then q_i added)."""
    k = q.shape[0]
    for i in range(k):
        s = 0.0
        for j in range(k):
            s += M[i, j] * z[j]
        w[i] = q[i] + s


@njit(cache=True, _nrt=False)
def copy_into(src: FloatArray, out: FloatArray) -> None:
    """out[:] = src, element by element (an array-to-array slice assignment may allocate a temporary, which
    the allocation-free kernels cannot)."""
    for i in range(out.shape[0]):
        out[i] = src[i]


@njit(cache=True, _nrt=False, inline='always')
def residual(M: FloatArray, q: FloatArray, z: FloatArray, w: FloatArray) -> float:
    """w = q + M z (:func:`affine`); returns err of (z, w)."""
    affine(M, q, z, w)
    return error(q, z, w)


@njit(cache=True, _nrt=False, inline='always')
def error(q: FloatArray, z: FloatArray, w: FloatArray) -> float:
    """Siconos' accuracy measure err = ||z - max(0, z - w)||_2 / ||q||_2 of the pair (z, w).

    z - max(0, z - w) is evaluated as min(z, w) (the same number, without the cancellation of z - (z - w)),
    and both norms on vectors divided by their largest magnitude first, so that q = 1e-200 or 1e200
    neither underflows nor overflows. When q = 0 (then z = 0 is the answer) err is the absolute ||min(z, w)||.
    A NaN in z or w gives NaN.
    """
    k = q.shape[0]
    rbig = 0.0
    for i in range(k):
        a, b = z[i], w[i]
        if a != a or b != b:
            return np.nan
        r = abs(a if a < b else b)
        if r > rbig:
            rbig = r
    if rbig == 0.0:
        return 0.0
    if rbig == np.inf:
        return np.inf
    rsum = 0.0
    for i in range(k):
        a, b = z[i], w[i]
        r = (a if a < b else b) / rbig
        rsum += r * r
    qbig = 0.0
    for i in range(k):
        if abs(q[i]) > qbig:
            qbig = abs(q[i])
    if qbig == 0.0:
        return rbig * math.sqrt(rsum)
    usum = 0.0
    for i in range(k):
        u = q[i] / qbig
        usum += u * u
    return (rbig / qbig) * (math.sqrt(rsum) / math.sqrt(usum))


@njit(cache=True, _nrt=False, inline='always')
def check(M: FloatArray, q: FloatArray, z: FloatArray, w: FloatArray, err: float,
          tol: float) -> tuple[int, int, float, float, float, float]:
    """(code, i, a, b, c, d): code 0 when (z, w) solves LCP(q, M) to ``tol``, else which condition fails
    (``CHECK_*``) with the index and the numbers :func:`check_message` prints.

    Scale-relative: z is judged against max(max|z|, max|q| / max|M|) (z's own unit: rounding noise in an
    all-but-zero z is not "the scale"), w against max(max|q|, max|M| max|z|); a huge M times a huge z may
    overflow that scale to inf, and then w is negligible against it, which is what the division says."""
    return check_scaled(max_abs(q), max_abs_matrix(M), z, w, err, tol)


@njit(cache=True, _nrt=False, inline='always')
def largest(x: FloatArray, n: int,
            acc: tuple[float, float, float, float]) -> tuple[tuple[float, float, float, float], bool]:
    """Fold |x[0:n]| into the four running maxima ``acc`` (a 4-tuple; NaN passed over, as ``a > m`` is false);
    also whether every entry is finite. Four maxima, not one: a single running maximum is a chain of dependent
    vmaxsd, 4 cycles an entry (110 ns over a 9 x 9 M, a tenth of its solve); the largest of the four is the same
    number."""
    m0, m1, m2, m3 = acc
    finite = True
    j = 0
    while j + 4 <= n:
        a0, a1, a2, a3 = abs(x[j]), abs(x[j + 1]), abs(x[j + 2]), abs(x[j + 3])
        finite &= a0 <= _MAX_FLOAT and a1 <= _MAX_FLOAT and a2 <= _MAX_FLOAT and a3 <= _MAX_FLOAT
        m0 = a0 if a0 > m0 else m0
        m1 = a1 if a1 > m1 else m1
        m2 = a2 if a2 > m2 else m2
        m3 = a3 if a3 > m3 else m3
        j += 4
    while j < n:
        a0 = abs(x[j])
        finite &= a0 <= _MAX_FLOAT
        m0 = a0 if a0 > m0 else m0
        j += 1
    return (m0, m1, m2, m3), finite


@njit(cache=True, _nrt=False, inline='always')
def max_abs_finite(v: FloatArray) -> tuple[float, bool]:
    """(max|v|, whether every entry is finite)."""
    acc, finite = largest(v, v.shape[0], (0.0, 0.0, 0.0, 0.0))
    return max(max(acc[0], acc[1]), max(acc[2], acc[3])), finite


@njit(cache=True, _nrt=False, inline='always')
def max_abs_matrix_finite(M: FloatArray) -> tuple[float, bool]:
    """(max|M|, whether every entry is finite), row by row."""
    acc = (0.0, 0.0, 0.0, 0.0)
    finite = True
    for i in range(M.shape[0]):
        acc, row_finite = largest(M[i], M.shape[1], acc)
        finite &= row_finite
    return max(max(acc[0], acc[1]), max(acc[2], acc[3])), finite


@njit(cache=True, _nrt=False)
def max_abs(v: FloatArray) -> float:
    """max|v| (NaN passed over)."""
    return max_abs_finite(v)[0]


@njit(cache=True, _nrt=False)
def max_abs_matrix(M: FloatArray) -> float:
    """max|M| (NaN passed over)."""
    return max_abs_matrix_finite(M)[0]


@njit(cache=True, _nrt=False)
def check_scaled(q_big: float, m_big: float, z: FloatArray, w: FloatArray, err: float,
                 tol: float) -> tuple[int, int, float, float, float, float]:
    """:func:`check` with q_big = max|q| and m_big = max|M| known (the iterative methods check every sweep)."""
    k = z.shape[0]
    z_scale = 0.0
    w_scale = 0.0
    for i in range(k):
        a, b = abs(z[i]), abs(w[i])
        if not (a <= _MAX_FLOAT and b <= _MAX_FLOAT):
            return CHECK_NOT_FINITE, 0, 0.0, 0.0, 0.0, 0.0
        if a > z_scale:
            z_scale = a
        if b > w_scale:
            w_scale = b
    w_scale = m_big * z_scale
    if q_big >= w_scale:
        w_scale = q_big
    if m_big > 0.0 and q_big / m_big > z_scale:
        z_scale = q_big / m_big
    zdiv = z_scale if z_scale > 0.0 else 1.0    # z_scale = 0: z = 0 exactly
    wdiv = w_scale if w_scale > 0.0 else 1.0    # w_scale = 0: w = q + M z = 0 exactly
    # the least w[i] / wdiv is the least w[i] divided by wdiv (> 0: the quotient is monotone), so the index is
    # found on w itself (a division per entry was a tenth of a small solve); likewise z
    i = 0
    for j in range(1, k):
        if w[j] < w[i]:
            i = j
    if not w[i] / wdiv >= -tol:
        return CHECK_W_NEGATIVE, i, w[i], w[i] / wdiv, w_scale, 0.0
    i = 0
    for j in range(1, k):
        if z[j] < z[i]:
            i = j
    if not z[i] / zdiv >= -tol:
        return CHECK_Z_NEGATIVE, i, z[i], z[i] / zdiv, z_scale, 0.0
    # The largest gap, first with the reciprocals (two divisions, not 2k): each product is within 3.3e-16 (relative)
    # of the quotient, so a largest product below tol / (1 + 1e-15) (less the absolute error of a subnormal one)
    # proves every quotient <= tol. Otherwise (and when a scale is subnormal: its reciprocal overflows) the
    # quotients themselves decide, as they always did.
    zinv, winv = 1.0 / zdiv, 1.0 / wdiv
    gap_big = np.inf
    if zinv <= _MAX_FLOAT and winv <= _MAX_FLOAT:
        gap_big = -np.inf
        for j in range(k):
            gap_big = max(gap_big, min(z[j] * zinv, w[j] * winv))
    if not gap_big * (1.0 + 1e-15) + 1e-300 <= tol:
        i = 0
        gap_i = min(z[0] / zdiv, w[0] / wdiv)
        for j in range(1, k):
            gap = min(z[j] / zdiv, w[j] / wdiv)
            if gap > gap_i:
                i, gap_i = j, gap
        if not gap_i <= tol:
            return CHECK_NOT_COMPLEMENTARY, i, z[i], w[i], z[i] / zdiv, w[i] / wdiv
    if not err <= tol:
        return CHECK_RESIDUAL, 0, err, 0.0, 0.0, 0.0
    return CHECK_OK, 0, 0.0, 0.0, 0.0, 0.0


@njit(cache=True, _nrt=False, inline='always')
def accepts(M: FloatArray, q: FloatArray, z: FloatArray, w: FloatArray, tol: float) -> bool:
    """True when (z, q + M z) passes :func:`check` (the stopping test of the iterative methods); fills w."""
    err = residual(M, q, z, w)
    return check(M, q, z, w, err, tol)[0] == CHECK_OK


@njit(cache=True, _nrt=False, inline='always')
def accepts_scaled(M: FloatArray, q: FloatArray, q_big: float, m_big: float, z: FloatArray, w: FloatArray,
                   tol: float) -> bool:
    """:func:`accepts` with max|q| and max|M| known."""
    err = residual(M, q, z, w)
    return check_scaled(q_big, m_big, z, w, err, tol)[0] == CHECK_OK


def check_message(code: int, i: int, a: float, b: float, c: float, d: float, tol: float) -> str:
    """The sentence for a :func:`check` code ('' for CHECK_OK)."""
    if code == CHECK_OK:
        return ""
    if code == CHECK_NOT_FINITE:
        return "the claimed solution is not finite (z or w = q + M z overflows); the problem is too badly scaled"
    if code == CHECK_W_NEGATIVE:
        return (f"the claimed solution is infeasible: w[{i}] = {a:.3g} < 0 ({b:.3g} relative to the "
                f"problem's scale max(|q|, |M| |z|) = {c:.3g}; allowed -tol = {-tol:.3g})")
    if code == CHECK_Z_NEGATIVE:
        return (f"the claimed solution is infeasible: z[{i}] = {a:.3g} < 0 ({b:.3g} relative to "
                f"max(|z|, |q| / |M|) = {c:.3g}; allowed -tol = {-tol:.3g})")
    if code == CHECK_NOT_COMPLEMENTARY:
        return (f"the claimed solution is not complementary: z[{i}] = {a:.3g} and w[{i}] = {b:.3g} are "
                f"both positive (relative {c:.3g} and {d:.3g}; allowed tol = {tol:.3g})")
    return (f"final residual err = {a:.3g} exceeds tol = {tol:.3g} "
            f"(ill-conditioned principal submatrix?); try method='lemke' or 'enum'")


def _floats(M: npt.ArrayLike, q: npt.ArrayLike, z: npt.ArrayLike) -> tuple[FloatArray, FloatArray, FloatArray]:
    return (np.ascontiguousarray(M, dtype=float), np.ascontiguousarray(q, dtype=float),
            np.ascontiguousarray(z, dtype=float))


def lcp_error(M: np.ndarray, q: np.ndarray, z: np.ndarray) -> float:
    """Siconos' accuracy measure err = ||z - max(0, z - w)||_2 / ||q||_2, w = q + M z (see :func:`error`)."""
    M, q, z = _floats(M, q, z)
    return float(residual(M, q, z, np.empty_like(q)))


def check_solution(M: npt.ArrayLike, q: npt.ArrayLike, z: npt.ArrayLike, w: npt.ArrayLike, err: float,
                   tol: float) -> str:
    """'' when (z, w) solves LCP(q, M) to ``tol`` (scale-relative, see :func:`check`), else which condition fails."""
    M, q, z = _floats(M, q, z)
    return check_message(*check(M, q, z, np.ascontiguousarray(w, dtype=float), float(err), float(tol)), tol)


def finish(M: npt.ArrayLike, q: npt.ArrayLike, z: npt.ArrayLike, *, status: str, iterations: int, method: str,
           tol: float, message: str = "", solutions: Iterable[FloatArray] = ()) -> LCPResult:
    """Build the result, checking a claimed solution: it becomes ``failed`` (the message says which condition
    failed) unless z >= 0, w = q + M z >= 0 and min(z_i, w_i) = 0 hold to ``tol`` relative to the problem's
    own magnitudes (z against max(max|z|, max|q| / max|M|), w against max(max|q|, max|M| max|z|)) and
    err <= tol."""
    M, q, z = _floats(M, q, z)
    w = np.empty_like(q)
    err = float(residual(M, q, z, w))
    if status == SOLVED:
        problem = check_message(*check(M, q, z, w, err, float(tol)), tol)  # type: ignore[call-arg]
        if problem:
            status, message = FAILED, f"{method}: {problem}"
    return make_result(z, w, status, err, int(iterations), method, message, list(solutions))
