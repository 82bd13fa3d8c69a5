"""One entry point for every LCP solver: :func:`solve_lcp`, and :func:`solve_lcp_many` for many small problems.

This module imports no numba: the thin path calls one compiled function, :func:`.engine.solve_once`, through
:func:`converters.compiled.kernel` (from the ahead-of-time module when it is current, so a process that solves
small LCPs never imports numba); the full path imports the engine when it first runs. A loop of many small
problems is one compiled call (:func:`solve_lcp_many`: the workspace allocated once, no Python per problem).
"""
from __future__ import annotations

import functools
import os
from dataclasses import dataclass
import sys
import threading
import time
from typing import TYPE_CHECKING, Any

import numpy as np

from .. import compiled, limits
from ..errors import LCPError
from ..validate import as_matrix, as_vector
from . import state as S
from .answer import SOLVED, LCPResult, make_result

if TYPE_CHECKING:
    from collections.abc import Callable, Iterator
    from types import ModuleType

    import numpy.typing as npt

ENUM_MAX_K = S.ENUM_MAX_K
DEFAULT_MAX_ITER = {"auto": None, "lemke": 10_000, "murty": 100_000, "enum": None, "pgs": 10_000, "newton": 1000}
#: ``tol`` when not given.
DEFAULT_TOL = 1e-10
#: Accepted range of ``tol`` (below 1e-16 double precision cannot resolve it; above 1e-2 it is no solution).
TOL_RANGE = (1e-16, 1e-2)
#: Accepted range of ``max_iter``: every iteration costs at least a microsecond, so 10^9 is already beyond any
#: time limit; larger values are refused rather than silently meaningless.
MAX_ITER_RANGE = (1, 10**9)
#: Seconds one solve may take when neither ``time_limit`` nor --time-limit / PCSUITE_TIME_LIMIT is given.
DEFAULT_TIME_LIMIT = 20.0
#: Working memory of each method in k x k arrays of doubles, M and its normalised copy included (upper
#: bounds): Lemke's k x (2k + 2) tableau (2) and its scratch; Murty's augmented M_JJ; Newton's Jacobian and
#: its augmented copy; auto runs its methods one after another in the largest of their workspaces.
WORK_ARRAYS = {"auto": 7, "lemke": 7, "murty": 4, "enum": 3, "pgs": 3, "newton": 7}

_F64 = np.dtype(np.float64)
_CODES = {name: code for code, name in enumerate(S.METHOD_NAMES)}
_CHUNK = S.CHUNK
_ONCE_SOLVED, _ONCE_CLOSED_FORM, _ONCE_OTHER = S.ONCE_SOLVED, S.ONCE_CLOSED_FORM, S.ONCE_OTHER
_ndarray = np.ndarray
_empty = np.empty
_monotonic = time.monotonic
_TOL_LOW, _TOL_HIGH = TOL_RANGE
_AUTO_LABELS = tuple(f"auto:{name}" for name in S.METHOD_NAMES)
_CLOSED_FORM_MESSAGES = tuple(f"closed form ({rule})" for rule in S.CLOSED_FORM_RULES)
#: auto's stages (packed as solve_once packs them) when PGS gave way and method m solved: nothing to report
_PGS_GAVE_WAY = tuple((1 << (4 * m)) | ((S.SLOW + 1) << (4 * S.PGS)) for m in range(S.N_METHODS))


def solve_lcp(M: npt.ArrayLike, q: npt.ArrayLike, method: str = "auto", tol: float = DEFAULT_TOL,
              max_iter: int | None = None, fast_paths: bool = True, time_limit: float | None = None,
              **options: float) -> LCPResult:
    """Solve LCP(q, M): find z >= 0 with w = q + M z >= 0 and z . w = 0.

    The solvers work on the normalised problem q' = q / s, M' = M / m (s ~ max|q|, m ~ max|M|, rounded to
    powers of two so that the scaling is exact); z solves LCP(q, M) iff z' = m z / s solves LCP(q', M'). The
    answer is scaled back and checked on the original problem, so q or M of any magnitude (1e-200, 1e200)
    is solved as well as at magnitude 1, and a z that under- or overflows when scaled back is reported.

    Every method is compiled (numba). A float64, C-ordered M and q with the defaults for max_iter,
    time_limit and the options take a thin path: the type and shape checks in Python, the finiteness
    check, the normalisation, the solve, the scaling back and the check on the original problem in one
    compiled call (a few microseconds for small k). Anything else (lists, other dtypes, a problem not
    solved within a millisecond of work, every answer that is not ``solved``) takes the full path, with
    the same checks and the time limit looked at between slices of a millisecond of work.

    Parameters
    ----------
    M : array_like, shape (k, k)
    q : array_like, shape (k,)
    method : {'auto', 'lemke', 'murty', 'enum', 'pgs', 'newton'}
        ``auto`` (default) chooses by size and structure and falls back on failure; ``result.method`` says
        which method produced the answer (``auto:lemke``, ``auto:enum``, ...). Its plan: the closed forms
        below; PGS first, as a probe of at most max(8, k/2) sweeps, when M is symmetric with a positive diagonal;
        Lemke; when Lemke ends on a ray, ``no_solution`` if that is proven (a row of w = q + M z negative for
        every z >= 0, or M positive semidefinite, hence copositive-plus), else enumeration (k <= 12) and
        then Newton-FB; ``failed`` when none solves it (no non-existence is claimed without a proof). See
        :mod:`converters.lcp.auto`.
        The others: Lemke (complementary pivoting, lexicographic), Murty (least-index principal pivoting),
        enumeration of all complementary bases (k <= 12; returns every basic solution),
        projected Gauss-Seidel (symmetric PD M), semismooth Newton on Fischer-Burmeister.
    tol : float in [1e-16, 1e-2]
        Accepted residual err = ||z - max(0, z - w)|| / ||q||, and the relative tolerance of the checks
        z >= 0, w >= 0, min(z_i, w_i) = 0 (see :func:`converters.lcp.result.finish`).
    max_iter : int in [1, 10**9], optional
        Pivots, sweeps or Newton steps; a method-specific default when omitted (for ``auto``: applies to
        each method of its plan).
    fast_paths : bool
        Use the closed forms for q >= 0, k = 1, k = 2 and a triangular M with a positive diagonal (exact
        by substitution, where pivoting may take 2^k steps), also for a named method; not for ``enum``, which
        lists all solutions.
    time_limit : float, optional
        Seconds the solve may take (0.1 .. 7 days); when omitted, --time-limit / PCSUITE_TIME_LIMIT, else
        20 s. A solve that reaches it returns ``failed`` with a message saying so. The limit measures the
        solve: neither the first import of the solvers nor numba's compile (or cache load) of a kernel at its
        first call counts.
    **options : float
        Method-specific: ``pivot_tol`` (lemke), ``omega`` in (0, 2) (pgs), ``rho``, ``p``, ``beta``,
        ``sigma`` (newton).

    Returns
    -------
    LCPResult
        Never a silent wrong answer: ``solved`` only when z >= 0, w >= 0, z . w = 0 (relative to the
        problem's scale) and err <= tol hold on the original problem.
    """
    code = _CODES.get(method) if isinstance(method, str) else None
    if code is None:
        raise LCPError(f"method must be one of {', '.join(S.METHOD_NAMES)}; got {method!r}")
    # The thin path: everything it needs checked here, the rest (finiteness included) in the compiled call.
    if (M.__class__ is _ndarray and q.__class__ is _ndarray and M.dtype is _F64 and q.dtype is _F64
            and tol.__class__ is float and _TOL_LOW <= tol <= _TOL_HIGH and max_iter is None
            and time_limit is None and not options and fast_paths.__class__ is bool and code != S.ENUM
            and M.ndim == 2 and q.ndim == 1):
        k = q.shape[0]
        if M.shape[0] == k and M.shape[1] == k and k > 0:
            if not M.flags.c_contiguous:
                M = np.ascontiguousarray(M)
            if not q.flags.c_contiguous:
                q = np.ascontiguousarray(q)
            if _ENVIRON is not None and k <= _K_UNDER_DEFAULT_MEMORY and not _ENVIRON.get(_TIME_KEY) \
                    and not _ENVIRON.get(_MEMORY_KEY):   # no limit set, and the default memory limit is far
                seconds = DEFAULT_TIME_LIMIT
            else:
                seconds = _environment_time_limit()
                _check_memory(method, k)
            z = _empty(k)
            w = _empty(k)
            once = _once or _load_once()       # loaded (imported, compiled) before the clock starts
            started = _monotonic()
            answer, iterations, err, used, rule, stages, eig = once(
                M, q, z, w, code, tol, _ONCE_MAX_ITER[code], fast_paths, _OPTIONS, _CHUNK)
            if answer == _ONCE_SOLVED:
                if code != S.AUTO:
                    return make_result(z, w, SOLVED, err, iterations, method)
                if stages == 1 << (4 * used) or stages == _PGS_GAVE_WAY[used]:
                    message = ""
                else:
                    message = _solved_message(used, stages, eig if eig == eig else None, k)
                return make_result(z, w, SOLVED, err, iterations, _AUTO_LABELS[used], message)
            if answer == _ONCE_CLOSED_FORM:
                return make_result(z, w, SOLVED, err, 0, "auto:closed form" if code == S.AUTO else method,
                                   _CLOSED_FORM_MESSAGES[rule])
            if answer == _ONCE_OTHER:
                return _solve_sliced(M, q, code, tol, DEFAULT_MAX_ITER[method], fast_paths,
                                     _deadline(seconds, started), _OPTIONS)  # type: ignore[arg-type]
            # NaN or inf: the full path raises the validation error
    # The full path.
    started = _monotonic()
    setup = _setup_seconds()
    M, q = check_lcp(M, q)
    if not (isinstance(tol, (int, float, np.integer, np.floating)) and not isinstance(tol, bool)
            and TOL_RANGE[0] <= tol <= TOL_RANGE[1]):
        raise LCPError(f"tol must be in [{TOL_RANGE[0]:g}, {TOL_RANGE[1]:g}]; got {tol!r}")
    tol = float(tol)
    if not isinstance(fast_paths, (bool, np.bool_)):      # "False" would be true
        raise LCPError(f"fast_paths must be True or False; got {fast_paths!r}")
    if max_iter is not None and method == "enum":
        raise LCPError(f"max_iter does not apply to method {method!r} (it visits every complementary basis once; "
                       f"k <= 12); got max_iter = {max_iter!r}")
    if max_iter is None:
        max_iter = DEFAULT_MAX_ITER[method]
    elif not (isinstance(max_iter, (int, np.integer)) and not isinstance(max_iter, bool)
              and MAX_ITER_RANGE[0] <= max_iter <= MAX_ITER_RANGE[1]):
        raise LCPError(f"max_iter must be an integer in [{MAX_ITER_RANGE[0]}, {MAX_ITER_RANGE[1]}]; got {max_iter!r}")
    engine = _engine()                  # its first import is set-up, not the solve's time
    opts = engine.options_array(method, options)
    seconds = check_time_limit(time_limit)
    k = q.shape[0]
    if method == "enum" and k > ENUM_MAX_K:
        raise LCPError(f"enumeration visits 2^k bases: k must be <= {ENUM_MAX_K}; got k = {k}; "
                       "use method='lemke' or 'murty'")
    _check_memory(method, k)
    return _solve_sliced(M, q, code, tol, max_iter, fast_paths, _deadline(seconds, started, setup), opts)


@functools.lru_cache(maxsize=1024)
def _solved_message(used: int, stages: int, eig: float | None, k: int) -> str:
    """auto's message when it solved the problem after other methods of its plan did not (``stages`` as
    solve_once packs them; ``eig`` None when not computed). Cached whole: unpacking and formatting it took
    three times as long as the compiled solve of a k = 4 problem."""
    from . import engine
    return engine.auto_message(S.OK, used, engine.unpack_stages(stages), -1, eig, -1, k)


def _solve_sliced(M: npt.NDArray[np.float64], q: npt.NDArray[np.float64], code: int, tol: float, max_iter: int | None,
                  fast_paths: bool, deadline: limits.Deadline, opts: npt.NDArray[np.float64]) -> LCPResult:
    """The full path on a validated problem: normalise, closed forms, the method in slices with the deadline
    looked at between them, then scale back and check on the original problem."""
    engine = _engine()
    from .fastpaths import RULES, closed_form
    from .result import finish
    method = S.METHOD_NAMES[code]
    Ms, qs, shift = normalise(M, q)
    if fast_paths and code != S.ENUM:
        label = "auto:closed form" if code == S.AUTO else method
        for rule, name in enumerate(RULES):
            z = np.zeros(q.shape[0])
            if closed_form(Ms, qs, rule, z):    # checked once, on the original problem
                result = finish(M, q, _scaled(z, shift), status=SOLVED, iterations=0, method=label, tol=tol,
                                message=f"closed form ({name})")
                if result.solved:
                    return result
    run = engine.Run(code, Ms, qs, tol=tol, max_iter=-1 if max_iter is None else int(max_iter), deadline=deadline,
                     opts=opts)
    status, message, label, iterations = run.outcome()
    final = finish(M, q, _scaled(run.z, shift), status=status, iterations=iterations, method=label, tol=tol,
                   message=message, solutions=[_scaled(s, shift) for s in run.solutions()])
    if status == SOLVED and not final.solved:   # solved when normalised, not once z is scaled back by 2^shift
        final = make_result(final.z, final.w, final.status, final.err, final.iterations, final.method,
                            f"{final.message} (z solves the normalised problem but not once scaled back by "
                            f"2^{shift}: the solution is not representable in double precision)", final.solutions)
    return final


def _scaled(z: np.ndarray, shift: int) -> np.ndarray:
    if not shift:
        return z.copy()
    from .engine import scale_pow2
    out = np.empty_like(z)
    scale_pow2(z, shift, out)
    return out


def normalise(M: np.ndarray, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, int]:
    """(M / 2^em, q / 2^es, es - em) with 2^es ~ max|q|, 2^em ~ max|M| (exact: powers of two); a zero M or q is
    left as it is. z = z' 2^(es - em) maps solutions of the normalised problem back."""
    from .engine import normalised
    Ms, qs, shift, _ = normalised(np.ascontiguousarray(M, dtype=float), np.ascontiguousarray(q, dtype=float))
    return Ms, qs, int(shift)


def check_time_limit(time_limit: float | None) -> float:
    """Seconds for one solve: ``time_limit`` when given (checked), else --time-limit / PCSUITE_TIME_LIMIT, else 20 s."""
    if time_limit is None:
        return _environment_time_limit()
    low, high = limits.TIME_RANGE
    if not (isinstance(time_limit, (int, float, np.integer, np.floating)) and not isinstance(time_limit, bool)
            and low <= time_limit <= high):
        raise LCPError(f"time_limit must be a number of seconds in [{low:g}, {high:g}]; got {time_limit!r}")
    return float(time_limit)


def _deadline(seconds: float, started: float, setup: float | None = None) -> limits.Deadline:
    """The deadline of a solve that started at ``started`` (monotonic clock), when this thread's set-up time
    (:func:`_setup_seconds`) was ``setup`` (None: it is now)."""
    return _SolveDeadline(seconds, started, _setup_seconds() if setup is None else setup)


# ------------------------------------------------------------------------- the clock of the time limit
# A time limit measures the solve, never the compile or the import of the code that runs it: with an empty cache
# the methods take tens of seconds to compile, longer than the default limit of 20 s, and a first solve would end
# at its limit before its first step. So a solve's clock does not run while its thread is in numba's compiler
# (converters.limits' compile clock) or imports the engine (numba with it), and the thin path reads the clock once
# its kernel is loaded.

_imports: dict = {}       # thread id -> seconds that thread spent importing the engine
_get_ident = threading.get_ident


def _setup_seconds() -> float:
    """Seconds this thread has spent so far in numba's compiler and importing the engine (counted from the
    install of the compile clock, which comes before a solve can compile anything)."""
    return limits.compile_seconds(_get_ident()) + _imports.get(_get_ident(), 0.0)


class _SolveDeadline(limits.Deadline):
    """:class:`converters.limits.Deadline` on the solve's own time: what its thread spent compiling kernels or
    importing the engine since the solve started is not counted."""

    def __init__(self, seconds: float, started: float, setup: float):
        self.seconds = float(seconds)
        self.end = started - setup + self.seconds

    def expired(self) -> bool:
        return _monotonic() - _setup_seconds() > self.end


def _engine() -> ModuleType:
    """converters.lcp.engine, imported at its first use (numba with it) with the time that takes counted as
    set-up, and numba's compile clock installed."""
    engine = sys.modules.get(f"{__package__}.engine")
    if engine is None:
        begun = _monotonic()
        from . import engine
        ident = _get_ident()
        _imports[ident] = _imports.get(ident, 0.0) + _monotonic() - begun
    limits.install_compile_clock()
    return engine  # type: ignore[return-value]


def check_lcp(M: npt.ArrayLike, q: npt.ArrayLike) -> tuple[np.ndarray, np.ndarray]:
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
    return np.ascontiguousarray(M), np.ascontiguousarray(q)


# ------------------------------------------------------------------------- limits, read at the cost of a dict lookup
# os.environ.get costs half a microsecond when the variable is unset (it raises and catches KeyError inside),
# as much as a whole small solve; os.environ keeps its values in the dict ``_data`` (CPython), read here
# directly, and the parsed value is kept for as long as the raw value does not change. Same values, same
# validation and messages as converters.limits.

_ENVIRON = getattr(os.environ, "_data", None)


def _environ_key(name: str) -> str | bytes | None:
    try:
        return os.environ.encodekey(name)
    except AttributeError:   # not CPython's os.environ: read it the ordinary way
        return None


_TIME_KEY = _environ_key(limits.TIME_ENV)
_MEMORY_KEY = _environ_key(limits.MEMORY_ENV)
if _TIME_KEY is None or _MEMORY_KEY is None:
    _ENVIRON = None
_parsed: dict = {}
#: Below this k every method's working memory is under the default limit.
_K_UNDER_DEFAULT_MEMORY = int((limits.DEFAULT_MAX_MEMORY / (8.0 * max(WORK_ARRAYS.values()))) ** 0.5)


def _environment_time_limit() -> float:
    if _ENVIRON is None:
        return limits.time_limit(DEFAULT_TIME_LIMIT)
    raw = _ENVIRON.get(_TIME_KEY)
    if not raw:
        return DEFAULT_TIME_LIMIT
    key = (_TIME_KEY, raw)
    value = _parsed.get(key)
    if value is None:
        value = _parsed[key] = limits.time_limit(DEFAULT_TIME_LIMIT)    # parses and checks (raises when bad)
    return value


def _check_memory(method: str, k: int) -> None:
    nbytes = 8.0 * WORK_ARRAYS[method] * k * k
    if _ENVIRON is not None:
        raw = _ENVIRON.get(_MEMORY_KEY)
        if not raw:
            limit = limits.DEFAULT_MAX_MEMORY
        else:
            limit = _parsed.get((_MEMORY_KEY, raw))
            if limit is None:
                limit = _parsed[(_MEMORY_KEY, raw)] = limits.max_memory()   # parses and checks (raises when bad)
        if nbytes <= limit:
            return
    limits.check_memory(f"solve_lcp (method {method}): k = {k} ({WORK_ARRAYS[method]} work arrays of k x k doubles)",
                        nbytes, remedy="a smaller problem")


# ------------------------------------------------------------------------- the compiled call, without dispatch
# The thin path has already checked the exact types (float64 C arrays, Python float / int / bool). From the
# ahead-of-time module, solve_once takes exactly those; from numba's JIT, calling the dispatcher would cost
# ~0.35 us of type dispatch, so the compiled entry point for those types is called directly (~0.2 us). Loaded
# at the first solve, not at import.

_ONCE_MAX_ITER = tuple(-1 if name in ("auto", "enum") else DEFAULT_MAX_ITER[name] for name in S.METHOD_NAMES)
_OPTIONS = None
_once = None


def _load_once() -> Callable[..., Any]:
    global _once, _OPTIONS
    _OPTIONS = compiled.kernel("lcp_default_options")()
    once = compiled.kernel("solve_once")
    if hasattr(once, "overloads"):                 # numba's dispatcher
        args = (np.eye(1), np.ones(1), np.empty(1), np.empty(1), 0, 1e-10, -1, True, _OPTIONS, _CHUNK)
        once(*args)
        from numba import typeof
        overload = once.overloads.get(tuple(typeof(a) for a in args))
        once = overload.entry_point if overload is not None else once
    _once = once
    return _once


# ------------------------------------------------------------------------- many problems in one call

@dataclass(frozen=True)
class LCPBatch:
    """What :func:`solve_lcp_many` returns: the answers of P problems as arrays; ``batch[i]`` is problem i's
    :class:`LCPResult` (as :func:`solve_lcp` would have returned it), ``list(batch)`` all of them.

    Attributes
    ----------
    z, w : ndarray, shape (P, k)
    status : tuple of str
    err : ndarray, shape (P,)
    iterations : ndarray of int, shape (P,)
    method, message : tuple of str
    """

    z: np.ndarray
    w: np.ndarray
    status: tuple
    err: np.ndarray
    iterations: np.ndarray
    method: tuple
    message: tuple

    @property
    def solved(self) -> np.ndarray:
        return np.array([s == SOLVED for s in self.status], dtype=bool)

    def __len__(self) -> int:
        return len(self.status)

    def __getitem__(self, i: int) -> LCPResult:
        return make_result(self.z[i], self.w[i], self.status[i], float(self.err[i]), int(self.iterations[i]),
                           self.method[i], self.message[i])

    def __iter__(self) -> Iterator[LCPResult]:
        return (self[i] for i in range(len(self)))


def solve_lcp_many(Ms: npt.ArrayLike, qs: npt.ArrayLike, method: str = "auto", tol: float = DEFAULT_TOL,
                   fast_paths: bool = True) -> LCPBatch:
    """Solve P problems LCP(qs[i], Ms[i]) of one size k, as :func:`solve_lcp` with its defaults would, in one
    compiled call: for loops of small problems (a parameter study, a Monte Carlo of a switched network), where
    calling :func:`solve_lcp` once per problem costs more in the call than in the solve. A problem the compiled
    call does not finish (not solved within its first slice of work, or one auto must report on) is solved by
    :func:`solve_lcp` itself, so every answer is the one it gives.

    Ms: array_like (P, k, k); qs: (P, k); ``method``, ``tol`` and ``fast_paths`` as :func:`solve_lcp`'s. Raises
    LCPError naming the first problem with NaN or inf."""
    code = _CODES.get(method) if isinstance(method, str) else None
    if code is None:
        raise LCPError(f"method must be one of {', '.join(S.METHOD_NAMES)}; got {method!r}")
    Ms, qs = np.ascontiguousarray(Ms, dtype=float), np.ascontiguousarray(qs, dtype=float)
    if Ms.ndim != 3 or qs.ndim != 2 or Ms.shape != (qs.shape[0], qs.shape[1], qs.shape[1]) or qs.shape[1] == 0:
        raise LCPError(f"Ms must be (P, k, k) and qs (P, k) with k >= 1; got Ms {Ms.shape}, qs {qs.shape}")
    if not (isinstance(tol, (int, float)) and not isinstance(tol, bool) and TOL_RANGE[0] <= tol <= TOL_RANGE[1]):
        raise LCPError(f"tol must be in [{TOL_RANGE[0]:g}, {TOL_RANGE[1]:g}]; got {tol!r}")
    if not isinstance(fast_paths, bool):
        raise LCPError(f"fast_paths must be True or False; got {fast_paths!r}")
    P, k = qs.shape
    _check_memory(method, k)
    if _once is None:
        _load_once()
    Z, W = np.empty((P, k)), np.empty((P, k))
    answers, iterations, used, rules, stages = (np.empty(P, dtype=np.int64) for _ in range(5))
    errs, infos = np.empty(P), np.empty(P)
    if code != S.ENUM:        # enumeration lists every solution: solve_lcp's own path
        compiled.kernel("solve_many")(Ms, qs, Z, W, code, float(tol), _ONCE_MAX_ITER[code], fast_paths, _OPTIONS, _CHUNK,
                                      answers, iterations, errs, used, rules, stages, infos)
    else:
        answers[:] = _ONCE_OTHER
    bad = np.flatnonzero(answers == S.ONCE_NOT_FINITE)
    if bad.size:
        raise LCPError(f"Ms[{bad[0]}] and qs[{bad[0]}] must be finite (no NaN or inf)")
    # the answers of the compiled call as solve_lcp labels them, by array (no Python per solved problem)
    solved, closed = answers == _ONCE_SOLVED, answers == _ONCE_CLOSED_FORM
    status = np.full(P, SOLVED, dtype=object)
    labels = np.full(P, method, dtype=object)
    messages = np.full(P, "", dtype=object)
    if code == S.AUTO:
        labels[solved] = np.array(_AUTO_LABELS, dtype=object)[used[solved]]
        labels[closed] = "auto:closed form"
        done, by = np.flatnonzero(solved), used[solved]
        plain = (stages[done] == np.left_shift(1, 4 * by)) | (stages[done] == np.array(_PGS_GAVE_WAY)[by])
        for i in done[~plain]:                            # a method of auto's plan gave way: its message
            u = int(used[i])
            messages[i] = _solved_message(u, int(stages[i]), infos[i] if infos[i] == infos[i] else None, k)
    messages[closed] = np.array(_CLOSED_FORM_MESSAGES, dtype=object)[rules[closed]]
    iterations[closed] = 0
    for i in np.flatnonzero(~(solved | closed)):          # not finished in one call: solve_lcp's own answer
        result = solve_lcp(Ms[i], qs[i], method=method, tol=float(tol), fast_paths=fast_paths)
        Z[i], W[i], errs[i], iterations[i] = result.z, result.w, result.err, result.iterations
        status[i], labels[i], messages[i] = result.status, result.method, result.message
    return LCPBatch(Z, W, tuple(status.tolist()), errs, iterations, tuple(labels.tolist()), tuple(messages.tolist()))
