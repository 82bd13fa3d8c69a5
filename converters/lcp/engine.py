"""How a method runs: the one-call compiled solve, the sliced run under a time limit, and the messages.

Every method's compiled ``run`` advances by at most a budget of multiply-adds and can be called again to
continue (its state lives in the workspace arrays). Two drivers use them:

- :func:`solve_once` (compiled, one call from Python): allocates the workspace, then :func:`solve_in` checks
  finiteness, normalises (q, M by powers of two), tries the closed forms, runs the method with a budget of
  ``CHUNK`` multiply-adds (a few milliseconds at most; the shortest time limit one can set is 0.1 s), scales
  back and checks the answer on the original problem. It answers only when the method solved the problem
  within that budget; every other outcome (auto asking for an eigenvalue included) is left to
- :class:`Run` (Python): the same compiled ``run`` in slices of ``CHUNK``, the deadline looked at between
  slices (and the least eigenvalue computed when auto asks for it), then :meth:`Run.outcome` turns the state
  into status and message (run again from the start: the one-call solve keeps no state, and its budget is a
  few milliseconds).

So the time limit is honoured to within one slice, and each algorithm exists once, compiled. The
public functions at the end (:func:`lemke`, :func:`murty`, ...) run one method on a problem as given.
"""
from __future__ import annotations

import functools
import math
from typing import TYPE_CHECKING

import numpy as np
from numba import njit

from ..errors import LCPError
from . import auto
from . import lemke as lemke_module
from . import newton as newton_module
from . import state as S
from .dispatch import (DEFAULT_MAX_ITER, DEFAULT_OPTIONS, OPT_BETA, OPT_OMEGA, OPT_P, OPT_PIVOT_TOL, OPT_RHO,
                       OPT_SIGMA, advance_method, method_sizes)
from .enumeration import MAX_K as ENUM_MAX_K
from .enumeration import solutions as enum_solutions
from .fastpaths import closed_form
from .result import STATUSES, check, check_message, check_scaled, max_abs_finite, max_abs_matrix_finite, residual

if TYPE_CHECKING:
    import numpy.typing as npt

    from ..limits import Deadline
    from .answer import LCPResult

    FloatArray = npt.NDArray[np.float64]
    IntArray = npt.NDArray[np.int64]
    #: solve_once's answer: (answer, iterations, err, used, rule, stages, info_x)
    Once = tuple[int, int, float, int, int, int, float]

#: Method names, indexed by the compiled code's method numbers (``state.AUTO`` .. ``state.NEWTON``).
METHODS = S.METHOD_NAMES
CODES = {name: code for code, name in enumerate(METHODS)}
#: What one iteration of each method is called in messages.
UNITS = ("steps", "pivots", "pivots", "bases", "sweeps", "steps")
CHUNK = S.CHUNK
#: Options each method takes, with their index in the options array.
OPTIONS = {"lemke": {"pivot_tol": OPT_PIVOT_TOL}, "pgs": {"omega": OPT_OMEGA},
           "newton": {"rho": OPT_RHO, "p": OPT_P, "beta": OPT_BETA, "sigma": OPT_SIGMA}}
ONCE_SOLVED, ONCE_CLOSED_FORM, ONCE_OTHER, ONCE_NOT_FINITE = (S.ONCE_SOLVED, S.ONCE_CLOSED_FORM, S.ONCE_OTHER,
                                                              S.ONCE_NOT_FINITE)
N_RULES = len(S.CLOSED_FORM_RULES)
#: Largest pivot tolerance Lemke accepts: a larger one counts true pivots as zero.
MAX_PIVOT_TOL = 1e-6


# ----------------------------------------------------------------------------------------------- compiled

@njit(cache=True, _nrt=False)
def exponents(M: FloatArray, q: FloatArray) -> tuple[int, int, bool]:
    """(es, em, finite): 2^es ~ max|q|, 2^em ~ max|M| (frexp exponents; 0 for a zero vector or matrix)."""
    es, em, finite, _, _ = magnitudes(M, q)
    return es, em, finite


@njit(cache=True, _nrt=False, inline='always')
def magnitudes(M: FloatArray, q: FloatArray) -> tuple[int, int, bool, float, float]:
    """(es, em, finite, max|q|, max|M|) (see :func:`exponents`)."""
    qbig, q_finite = max_abs_finite(q)
    mbig, m_finite = max_abs_matrix_finite(M)
    if not (q_finite and m_finite):
        return 0, 0, False, 0.0, 0.0
    return math.frexp(qbig)[1], math.frexp(mbig)[1], True, qbig, mbig


#: 2^e for every normal exponent, POW2[e + 1022] (a table: libm's ldexp costs a twentieth of a small solve).
POW2 = np.ldexp(1.0, np.arange(-1022, 1024))


@njit(cache=True, _nrt=False, inline='always')
def scale_pow2(x: FloatArray, e: int, out: FloatArray) -> None:
    """out = x * 2^e, exactly as ldexp (a multiplication by the power of two when it is a normal number:
    the same correctly rounded result)."""
    if -1022 <= e <= 1023:
        f = POW2[e + 1022]
        for i in range(x.shape[0]):
            out[i] = x[i] * f
    else:
        for i in range(x.shape[0]):
            out[i] = math.ldexp(x[i], e)


@njit(cache=True)
def normalised(M: FloatArray, q: FloatArray) -> tuple[FloatArray, FloatArray, int, bool]:
    """(M / 2^em, q / 2^es, es - em, finite) with 2^es ~ max|q|, 2^em ~ max|M| (exact: powers of two); a zero M
    or q is left as it is. z = z' 2^(es - em) maps solutions of the normalised problem back."""
    es, em, finite = exponents(M, q)
    Ms = M
    if em != 0:
        Ms = np.empty_like(M)
        scale_pow2(M.reshape(-1), -em, Ms.reshape(-1))
    qs = q
    if es != 0:
        qs = np.empty_like(q)
        scale_pow2(q, -es, qs)
    return Ms, qs, es - em, finite


@njit(cache=True, _nrt=False)
def sizes(method: int, k: int) -> tuple[int, int]:
    if method == S.AUTO:
        return auto.sizes(k)
    return method_sizes(method, k, False)


@njit(cache=True, _nrt=False, inline='always')
def advance(method: int, M: FloatArray, q: FloatArray, z: FloatArray, fw: FloatArray, iw: IntArray, st: IntArray,
            sf: FloatArray, tol: float, max_iter: int, budget: int, opts: FloatArray) -> bool:
    """Advance ``method`` (auto included) by a slice of at most ``budget`` multiply-adds; True when it ended.
    False also when auto waits for the least eigenvalue (st[PHASE] == EIGENVALUE): the caller puts
    :func:`converters.lcp.auto.least_symmetric_eigenvalue` in sf[INFO_X] and calls again (:class:`Run`)."""
    if method == S.AUTO:
        return auto.run(M, q, z, fw, iw, st, sf, tol, max_iter, budget, opts)
    return advance_method(method, M, q, z, fw, iw, st, sf, tol, max_iter, budget, opts, False)


@njit(cache=True, _nrt=False, inline='always')
def scale_pow2_matrix(A: FloatArray, e: int, out: FloatArray) -> None:
    """:func:`scale_pow2` of a matrix, row by row (a row is a view; a reshape would call numba's helper library)."""
    for i in range(A.shape[0]):
        scale_pow2(A[i], e, out[i])


@njit(cache=True)
def solve_once(M: FloatArray, q: FloatArray, z: FloatArray, w: FloatArray, method: int, tol: float, max_iter: int,
               fast_paths: bool, opts: FloatArray, budget: int) -> Once:
    """The whole solve in one compiled call, when it succeeds within ``budget``.

    Returns (answer, iterations, err, used, rule, stages, info_x). ``answer`` ONCE_SOLVED: z, w = q + M z
    and err are filled and checked on (q, M); ``used`` is the method that solved it (auto's choice);
    ``stages`` packs what each method of auto's plan ended with (4 bits per method, outcome + 1; 0: not
    run; then st[PSD]) and info_x the eigenvalue auto computed (NaN: none). ONCE_CLOSED_FORM: solved by closed form
    ``rule``. ONCE_OTHER: anything else (not solved, not within the budget, or auto needing an eigenvalue):
    the caller runs the sliced solve, which reports it. ONCE_NOT_FINITE: M or q holds NaN or inf (the
    caller raises).

    This function only allocates the workspace; :func:`solve_in` does the rest without numba's reference
    counting (with it, the atomic increments and decrements of every array argument of every call were
    three quarters of a small solve's time).
    """
    k = q.shape[0]
    nf, ni = sizes(method, k)
    buf = np.empty(k * k + 2 * k + S.SF_SIZE + nf)     # one allocation: M', q', z', sf and the workspace
    ibuf = np.empty(S.ST_SIZE + ni, dtype=np.int64)    # and one for st and the integer workspace
    return solve_in(M, q, z, w, method, tol, max_iter, fast_paths, opts, budget, buf[:k * k].reshape((k, k)),
                    buf[k * k:], ibuf)


@njit(cache=True, _nrt=False)
def solve_in(M: FloatArray, q: FloatArray, z: FloatArray, w: FloatArray, method: int, tol: float, max_iter: int,
             fast_paths: bool, opts: FloatArray, budget: int, mbuf: FloatArray, buf: FloatArray,
             ibuf: IntArray) -> Once:
    """:func:`solve_once` in the caller's workspace: ``mbuf`` (k x k, for M'), ``buf`` (2k + SF_SIZE + the
    method's doubles) and ``ibuf`` (ST_SIZE + its integers: st is zeroed here, the methods set up their own). (M'
    has its own 2-D buffer: a reshape costs a call into numba's helper library, a fifth of a small solve.)"""
    k = q.shape[0]
    es, em, finite, q_big, m_big = magnitudes(M, q)
    if not finite:
        return ONCE_NOT_FINITE, 0, 0.0, method, -1, 0, 0.0
    shift = es - em
    Ms = M
    if em != 0:
        Ms = mbuf
        scale_pow2_matrix(M, -em, mbuf)
    qs = q
    if es != 0:
        qs = buf[:k]
        scale_pow2(q, -es, qs)
    zs = buf[k:2 * k]
    sf = buf[2 * k:2 * k + S.SF_SIZE]
    sf[:] = 0.0
    fw = buf[2 * k + S.SF_SIZE:]
    st = ibuf[:S.ST_SIZE]
    st[:] = 0
    st[S.CALLER_CHECKS] = 1     # the check below is the one that counts (Lemke's own would repeat it)
    iw = ibuf[S.ST_SIZE:]
    if fast_paths and method != S.ENUM:
        for rule in range(N_RULES):
            if closed_form(Ms, qs, rule, zs):     # checked once, on the original problem
                scale_pow2(zs, shift, z)
                err = residual(M, q, z, w)
                if check_scaled(q_big, m_big, z, w, err, tol)[0] == 0:
                    return ONCE_CLOSED_FORM, 0, err, method, rule, 0, 0.0
    if not advance(method, Ms, qs, zs, fw, iw, st, sf, tol, max_iter, budget, opts):
        return ONCE_OTHER, 0, 0.0, method, -1, 0, 0.0
    if st[S.STATUS] != S.SOLVED:
        return ONCE_OTHER, 0, 0.0, method, -1, 0, 0.0
    scale_pow2(zs, shift, z)
    err = residual(M, q, z, w)
    if check_scaled(q_big, m_big, z, w, err, tol)[0] != 0:      # not solved once scaled back (or Lemke unchecked)
        return ONCE_OTHER, 0, 0.0, method, -1, 0, 0.0
    used, stages = method, 0
    if method == S.AUTO:
        used = st[S.USED]
        for m in range(S.N_METHODS):
            stages |= (st[S.STAGE_OUTCOME + m] + 1) << (4 * m)
        stages |= st[S.PSD] << (4 * S.N_METHODS)
    return ONCE_SOLVED, st[S.ITER], err, used, -1, stages, sf[S.INFO_X]


@njit(cache=True)
def solve_many(Ms: FloatArray, qs: FloatArray, Z: FloatArray, W: FloatArray, method: int, tol: float, max_iter: int,
               fast_paths: bool, opts: FloatArray, budget: int, answers: IntArray, iterations: IntArray,
               errs: FloatArray, used: IntArray, rules: IntArray, stages: IntArray, infos: FloatArray) -> None:
    """:func:`solve_once` on each of P problems of one size (Ms (P, k, k), qs (P, k); answers into Z, W (P, k) and
    the per-problem arrays), the workspace allocated once for all of them: the compiled half of
    :func:`converters.lcp.solve_lcp_many`."""
    k = qs.shape[1]
    nf, ni = sizes(method, k)
    buf = np.empty(k * k + 2 * k + S.SF_SIZE + nf)
    ibuf = np.empty(S.ST_SIZE + ni, dtype=np.int64)
    _solve_many_in(Ms, qs, Z, W, method, tol, max_iter, fast_paths, opts, budget, answers, iterations, errs, used,
                   rules, stages, infos, buf[:k * k].reshape((k, k)), buf[k * k:], ibuf)


@njit(cache=True, _nrt=False)
def _solve_many_in(Ms: FloatArray, qs: FloatArray, Z: FloatArray, W: FloatArray, method: int, tol: float,
                   max_iter: int, fast_paths: bool, opts: FloatArray, budget: int, answers: IntArray,
                   iterations: IntArray, errs: FloatArray, used: IntArray, rules: IntArray, stages: IntArray,
                   infos: FloatArray, mbuf: FloatArray, buf: FloatArray, ibuf: IntArray) -> None:
    """:func:`solve_many`'s loop in its workspace, without reference counting (each problem's rows are views: with
    it, every view's atomic increment and decrement cost more than a small solve)."""
    for p in range(qs.shape[0]):
        answers[p], iterations[p], errs[p], used[p], rules[p], stages[p], infos[p] = solve_in(
            Ms[p], qs[p], Z[p], W[p], method, tol, max_iter, fast_paths, opts, budget, mbuf, buf, ibuf)


# ------------------------------------------------------------------------------------------------- Python

def options_array(method: str, options: dict) -> np.ndarray:
    """The options array for ``method``; unknown options and out-of-range values are refused."""
    opts = DEFAULT_OPTIONS.copy()
    allowed = OPTIONS.get(method, {})
    for name, value in options.items():
        if name not in allowed:
            takes = ", ".join(f"{o} ({m})" for m, names in OPTIONS.items() for o in names)
            raise LCPError(f"option {name!r} does not apply to method {method!r}; the options are {takes}")
        if not (isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, bool)
                and math.isfinite(value) and value > 0.0):
            raise LCPError(f"{name} must be a positive finite number; got {value!r}")
        if name == "omega" and not value < 2.0:
            raise LCPError(f"omega must be in (0, 2); got {value!r}")
        if name == "beta" and not value < 1.0:
            raise LCPError(f"beta must be in (0, 1); got {value!r}")
        # a pivot below pivot_tol (relative) counts as zero: 0.5 made Lemke end on a ray for a positive definite M
        if name == "pivot_tol" and not value <= MAX_PIVOT_TOL:
            raise LCPError(f"pivot_tol must be in (0, {MAX_PIVOT_TOL:g}]; got {value!r}")
        if name == "sigma" and not value < 0.5:         # Armijo's constant: a sufficient decrease needs < 1/2
            raise LCPError(f"sigma must be in (0, 0.5); got {value!r}")
        if name == "p" and not value > 2.0:             # the descent test's exponent (De Luca, Facchinei, Kanzow)
            raise LCPError(f"p must be > 2; got {value!r}")
        opts[allowed[name]] = float(value)
    return opts


class Run:
    """A method's run on LCP(q, M) advanced slice by slice until it ends or ``deadline`` expires."""

    def __init__(self, code: int, M: np.ndarray, q: np.ndarray, *, tol: float, max_iter: int,
                 deadline: Deadline | None, opts: FloatArray):
        self.code, self.M, self.q, self.tol, self.max_iter, self.deadline = code, M, q, tol, max_iter, deadline
        k = q.shape[0]
        nf, ni = sizes(code, k)
        self.z = np.zeros(k)
        self.fw = np.empty(nf)
        self.iw = np.empty(ni, dtype=np.int64)
        self.st = np.zeros(S.ST_SIZE, dtype=np.int64)
        self.sf = np.zeros(S.SF_SIZE)
        self.timed_out = deadline is not None and deadline.expired()
        while not self.timed_out and not advance(code, M, q, self.z, self.fw, self.iw, self.st, self.sf, tol,
                                                 max_iter, CHUNK, opts):
            if self.st[S.PHASE] == S.EIGENVALUE:     # auto's plan asks for it (Lemke's ray)
                self.sf[S.INFO_X] = auto.least_symmetric_eigenvalue(M)
            self.timed_out = deadline is not None and deadline.expired()

    def stage(self) -> int:
        """The method running or last run (auto's current stage)."""
        return int(self.st[S.STAGE]) if self.code == S.AUTO and self.st[S.STAGE] != S.AUTO else self.code

    def outcome(self) -> tuple[str, str, str, int]:
        """(status, message, method label, iterations) of the run, on the problem it was given."""
        st, k, name = self.st, self.q.shape[0], METHODS[self.code]
        stage = self.stage()
        if self.timed_out:
            what = _progress(stage, int(st[S.ITER]), k)
            if self.code == S.AUTO:
                label = "auto" if stage == S.AUTO else f"auto:{METHODS[stage]}"
                what = "auto (before its first method)" if stage == S.AUTO else f"auto: {what}"
            else:
                label = name
            return "failed", self.deadline.message(what), label, int(st[S.ITER])  # type: ignore[union-attr]
        status = STATUSES[int(st[S.STATUS])]
        if self.code == S.AUTO:
            outcomes = tuple(int(st[S.STAGE_OUTCOME + m]) for m in range(S.N_METHODS))
            used = int(st[S.USED])
            message = auto_message(int(st[S.OUTCOME]), used, outcomes + (int(st[S.PSD]),), int(st[S.INFO]),
                                   known(self.sf[S.INFO_X]), self.max_iter, k)
            return status, message, f"auto:{METHODS[used]}", int(st[S.ITER])
        if self.code == S.LEMKE and int(st[S.OUTCOME]) == S.RAY:
            status, message = self._ray()
            return status, message, name, int(st[S.ITER])
        return status, self._message(int(st[S.OUTCOME])), name, int(st[S.ITER])

    def _ray(self) -> tuple[str, str]:
        """Lemke's ray, judged as auto judges it: ``no_solution`` only with a proof (a row of w negative for every
        z >= 0, or M positive semidefinite, hence copositive-plus), else ``failed`` (a solution may exist)."""
        M, q, k = self.M, self.q, self.q.shape[0]
        row = auto.infeasible_row(M, q)
        if row >= 0:
            return "no_solution", (f"lemke: ray termination, and no solution exists: w[{row}] = q[{row}] + sum_j "
                                   f"M[{row},j] z_j <= q[{row}] < 0 for every z >= 0")
        st, sf = np.zeros(S.ST_SIZE, dtype=np.int64), np.zeros(S.SF_SIZE)
        verdict = auto.semidefinite_by_minors(M, st, sf)
        eig = sf[S.INFO_X] if verdict == 1 else None
        if verdict == 0:
            eig = auto.least_symmetric_eigenvalue(M)
            verdict = 1 if auto.proves_psd(eig, k) else -1
        if verdict == 1:
            return "no_solution", (f"lemke: ray termination, and M is positive semidefinite (least eigenvalue of "
                                   f"(M + M^T)/2: {eig:.3g} max|M|), hence copositive-plus: no solution exists")
        return "failed", (f"lemke: ray termination, which proves nothing here ({_not_psd(int(st[S.PSD]), eig)}): a "
                          "solution may exist; try method='auto' (it goes on to enumeration and Newton)")

    def _message(self, outcome: int) -> str:
        name, st, max_iter = METHODS[self.code], self.st, self.max_iter
        if outcome == S.OK:
            return ""
        if outcome == S.CHECK:
            w = np.empty_like(self.q)
            err = residual(self.M, self.q, self.z, w)
            return f"{name}: " + check_message(*check(self.M, self.q, self.z, w, err, self.tol), self.tol)
        if outcome == S.SINGULAR:
            return "murty: singular principal submatrix (M is not a P-matrix); try method='lemke'"
        if outcome == S.DIAG:
            i = int(st[S.INFO])
            return f"pgs needs a positive diagonal; M[{i},{i}] = {self.sf[S.INFO_X]:g}; try method='lemke'"
        if outcome == S.DIVERGED:
            return (f"pgs diverged at sweep {int(st[S.INFO])} (M is not symmetric positive definite); "
                    "try method='lemke'")
        if outcome == S.LINESEARCH:
            return ("newton: line search failed (stationary point of the merit function; M is probably not a "
                    "P-matrix); try method='lemke'")
        if outcome == S.NOBASIS:
            return "enum: no complementary basis is feasible (no basic solution exists)"
        # S.MAXIT
        return {"lemke": f"lemke reached max_iter ({max_iter}) pivots; raise max_iter",
                "murty": f"murty reached max_iter ({max_iter}) pivots (it may cycle if M is not a P-matrix); "
                         "try method='lemke'",
                "pgs": f"pgs reached max_iter ({max_iter}) sweeps (converges only for symmetric positive "
                       "definite M); try method='lemke'",
                "newton": f"newton reached max_iter ({max_iter}) steps; try method='lemke'"}[name]

    def solutions(self) -> list:
        return enum_solutions(self.fw, self.st, self.q.shape[0]) if self.code == S.ENUM else []


def _progress(method: int, iterations: int, k: int) -> str:
    """'lemke (after 12 pivots)', 'enum (after 64 of 4096 bases)'."""
    if method == S.ENUM:
        return f"enum (after {iterations} of {2 ** k} bases)"
    return f"{METHODS[method]} (after {iterations} {UNITS[method]})"


@functools.lru_cache(maxsize=1024)
def auto_message(outcome: int, used: int, outcomes: tuple, row: int, eig: float | None, max_iter: int,
                 k: int) -> str:
    """What auto did, when there is more to say than ``auto:<method>``: the methods that did not solve the
    problem and why, the proof of non-existence, or why none is claimed. (Kept for repeated solves of
    problems of one kind, as in time-stepping: the same words are not formatted again.)"""
    if outcome == S.PROOF_ROW:
        return (f"auto: no solution exists: w[{row}] = q[{row}] + sum_j M[{row},j] z_j <= q[{row}] < 0 for every "
                f"z >= 0 (q[{row}] < 0 and no M[{row},j] is positive); lemke ended on a ray")
    if outcome == S.PROOF_PSD:
        return (f"auto: lemke ended on a ray and M is positive semidefinite (least eigenvalue of (M + M^T)/2: "
                f"{eig:.3g} max|M|), hence copositive-plus: no solution exists")
    quiet = (S.OK, S.SLOW) if outcome == S.OK else (S.OK,)    # PGS giving way is the plan, not a failure
    reports = [_stage_report(m, outcomes[m], outcomes[S.N_METHODS], eig, max_iter, k)
               for m in (S.PGS, S.LEMKE, S.ENUM, S.NEWTON) if outcomes[m] >= 0 and outcomes[m] not in quiet]
    if outcome == S.OK:
        return f"auto: {'; '.join(reports)}; solved by {METHODS[used]}" if reports else ""
    return ("auto: no method of the plan found a solution (" + "; ".join(reports) + "), and no proof that none "
            "exists (a row of w negative for every z >= 0, or Lemke's ray with M positive semidefinite)")


def _not_psd(psd: int, eig: float | None) -> str:
    """Why a Lemke ray proves nothing: M not positive semidefinite (how that was found), or not tested."""
    return {S.PSD_EIGENVALUE: f"M is not positive semidefinite: least eigenvalue of (M + M^T)/2 = {eig:.3g} "
                              "max|M|" if eig is not None else "",
            S.PSD_MINOR: "M is not positive semidefinite: a diagonal entry or a 2 x 2 principal minor of "
                         "(M + M^T)/2 is negative",
            S.PSD_UNTESTED: f"M was not tested for positive semidefiniteness, k > {auto.PSD_MAX_K}"}.get(psd, "")


def _stage_report(method: int, outcome: int, psd: int, eig: float | None, max_iter: int, k: int) -> str:
    name = METHODS[method]
    limit = auto.stage_max_iter(method, max_iter, k)
    if outcome == S.RAY:
        return f"lemke ended on a ray (which proves nothing here: {_not_psd(psd, eig)})"
    if outcome == S.MAXIT:
        return f"{name} reached max_iter ({limit}) {UNITS[method]}"
    if outcome == S.CHECK:
        return f"{name}'s answer failed the residual check"
    if outcome == S.NOBASIS:
        return f"enum found no feasible complementary basis among the 2^{k} = {2 ** k}"
    if outcome == S.LINESEARCH:
        return "newton's line search failed (a stationary point of the merit function)"
    if outcome == S.DIVERGED:
        return "pgs diverged"
    if outcome == S.SLOW:
        return f"pgs converged too slowly to finish within {limit} sweeps"
    return f"{name} ended with outcome {outcome}"


def known(x: float) -> float | None:
    """A float, None for NaN (not computed)."""
    x = float(x)
    return None if x != x else x


def unpack_stages(stages: int) -> tuple:
    """solve_once's packed stages: each method's outcome (-1: not run), then st[PSD]."""
    return tuple(((stages >> (4 * m)) & 15) - 1 for m in range(S.N_METHODS)) + ((stages >> (4 * S.N_METHODS)) & 15,)


def run_method(name: str, M: npt.ArrayLike, q: npt.ArrayLike, *, tol: float, max_iter: int | None,
               deadline: Deadline | None = None, **options: float) -> LCPResult:
    """``name`` on LCP(q, M) exactly as given (no normalisation, no closed forms), sliced under ``deadline``;
    the answer is checked on (q, M). This is what ``lemke()``, ``murty()``, ... are."""
    from .result import finish
    code = CODES[name]
    M, q = np.ascontiguousarray(M, dtype=float), np.ascontiguousarray(q, dtype=float)
    if max_iter is None:
        max_iter = DEFAULT_MAX_ITER[code] if code != S.AUTO else -1
    run = Run(code, M, q, tol=float(tol), max_iter=int(max_iter), deadline=deadline, opts=options_array(name, options))
    status, message, label, iterations = run.outcome()
    return finish(M, q, run.z, status=status, iterations=iterations, method=label, tol=tol, message=message,
                  solutions=run.solutions())


# ------------------------------------------------------------------------------- each method on a problem as given

def lemke(M: np.ndarray, q: np.ndarray, *, tol: float, max_iter: int, pivot_tol: float = lemke_module.PIVOT_TOL,
          deadline: Deadline | None = None) -> LCPResult:
    """Lemke (:mod:`converters.lcp.lemke`) on LCP(q, M) as given: no normalisation, no closed forms; the
    compiled loop in slices with ``deadline`` checked between them; the answer checked on (q, M)."""
    return run_method("lemke", M, q, tol=tol, max_iter=max_iter, deadline=deadline, pivot_tol=pivot_tol)


def murty(M: np.ndarray, q: np.ndarray, *, tol: float, max_iter: int, deadline: Deadline | None = None) -> LCPResult:
    """Murty (:mod:`converters.lcp.murty`) on LCP(q, M) as given (see :func:`lemke`)."""
    return run_method("murty", M, q, tol=tol, max_iter=max_iter, deadline=deadline)


def pgs(M: np.ndarray, q: np.ndarray, *, tol: float, max_iter: int, omega: float = 1.0,
        deadline: Deadline | None = None) -> LCPResult:
    """Projected Gauss-Seidel (:mod:`converters.lcp.pgs`) on LCP(q, M) as given (see :func:`lemke`)."""
    return run_method("pgs", M, q, tol=tol, max_iter=max_iter, deadline=deadline, omega=omega)


def newton_fb(M: np.ndarray, q: np.ndarray, *, tol: float, max_iter: int, rho: float = newton_module.RHO,
              p: float = newton_module.P, beta: float = newton_module.BETA, sigma: float = newton_module.SIGMA,
              deadline: Deadline | None = None) -> LCPResult:
    """Newton-FB (:mod:`converters.lcp.newton`) on LCP(q, M) as given (see :func:`lemke`)."""
    return run_method("newton", M, q, tol=tol, max_iter=max_iter, deadline=deadline, rho=rho, p=p, beta=beta,
                      sigma=sigma)


def enumerate_bases(M: np.ndarray, q: np.ndarray, *, tol: float, max_iter: int | None = None,
                    deadline: Deadline | None = None) -> LCPResult:
    """Every basic solution of LCP(q, M) as given (``solutions``), the least-norm one as z
    (:mod:`converters.lcp.enumeration`); k <= 12."""
    k = np.shape(q)[0]
    if k > ENUM_MAX_K:
        raise LCPError(f"enumeration visits 2^k bases: k must be <= {ENUM_MAX_K}; got k = {k}; "
                       "use method='lemke' or 'murty'")
    return run_method("enum", M, q, tol=tol, max_iter=None, deadline=deadline)


def auto_plan(M: np.ndarray, q: np.ndarray, *, tol: float, max_iter: int | None = None,
              deadline: Deadline | None = None) -> LCPResult:
    """The ``auto`` plan (:mod:`converters.lcp.auto`) on LCP(q, M) as given (see :func:`lemke`)."""
    return run_method("auto", M, q, tol=tol, max_iter=max_iter, deadline=deadline)


#: Each method on a problem as given (no normalisation, no closed forms): what solve_lcp runs, after those.
SOLVERS = {"auto": auto_plan, "lemke": lemke, "murty": murty, "enum": enumerate_bases, "pgs": pgs,
           "newton": newton_fb}
