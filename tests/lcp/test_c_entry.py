"""solve_lcp's C entry point (converters/lcp/_fast.c): the same answers as the Python function it wraps, bit for
bit, on every problem and every argument it takes; everything else handed to Python unchanged."""
import dataclasses
import inspect
import pickle
import sys
import types

import numpy as np
import pytest

from converters import compiled
from converters.errors import LCPError
from converters.lcp import read_siconos_lcp, solve_lcp
from converters.lcp.problems import murty_exponential, problem_set, random_p_matrix

C_ENTRY = not isinstance(solve_lcp, types.FunctionType)
PYTHON = getattr(solve_lcp, "__wrapped__", solve_lcp)
METHODS = ["auto", "lemke", "murty", "pgs", "newton"]


def test_the_c_entry_is_solve_lcp_whenever_the_ahead_of_time_kernels_are_used():
    assert C_ENTRY == (compiled.source() == "ahead-of-time"), compiled.source()


needs_c_entry = pytest.mark.skipif(not C_ENTRY, reason=f"kernels from {compiled.source()}: solve_lcp is the Python "
                                                       "function (the test above checks that this is right)")


def same(a, b):
    """Two LCPResults equal in every field, arrays bit for bit."""
    assert type(a) is type(b)
    for name in ("status", "method", "message", "iterations"):
        assert getattr(a, name) == getattr(b, name), name
    assert a.err == b.err or (np.isnan(a.err) and np.isnan(b.err))
    assert np.array_equal(a.z, b.z, equal_nan=True) and np.array_equal(a.w, b.w, equal_nan=True)
    assert a.z.dtype == b.z.dtype == np.float64 and a.z.flags.c_contiguous and a.z.flags.writeable
    assert len(a.solutions) == len(b.solutions)


def outcome(call):
    try:
        return call()
    except Exception as exc:                   # noqa: BLE001 (compared below: the same type and words)
        return exc


def same_outcome(*args, **kwargs):
    ours, python = outcome(lambda: solve_lcp(*args, **kwargs)), outcome(lambda: PYTHON(*args, **kwargs))
    if isinstance(python, Exception):
        assert type(ours) is type(python) and str(ours) == str(python)
    else:
        same(ours, python)
    return ours


@needs_c_entry
@pytest.mark.parametrize("fast_paths", [True, False])
@pytest.mark.parametrize("method", METHODS)
def test_every_peer_problem_gives_the_python_answer(peer, method, fast_paths):
    """Closed forms, auto's plan (its messages when a method gave way), Lemke's ray proven or not, PGS failing
    on a nonsymmetric M, Newton: every branch of the thin path, through C and through Python."""
    statuses = set()
    for path in sorted(peer.glob("lcp_*.dat")):
        p = read_siconos_lcp(path)
        result = same_outcome(np.ascontiguousarray(p.M), np.ascontiguousarray(p.q), method=method,
                              fast_paths=fast_paths)
        statuses.add(result.status)
    assert "solved" in statuses


@needs_c_entry
@pytest.mark.parametrize("kind", ["spd", "pd", "triangular"])
def test_random_p_matrix_problems_give_the_python_answer(kind):
    rng = np.random.default_rng(7)
    for k in range(1, 13):
        M = random_p_matrix(rng, k, kind)
        for _ in range(3):
            q = rng.standard_normal(k)
            for method in METHODS:
                result = same_outcome(M, q, method=method)
                assert result.status == "solved" or (method == "pgs" and kind != "spd")   # PGS: symmetric M
            same_outcome(M, q, tol=1e-6)
            same_outcome(M, q, "lemke", 1e-8)                    # method and tol by position
    for case in problem_set():
        same_outcome(case.M, case.q)


@needs_c_entry
def test_a_solve_beyond_the_first_slice_of_work_goes_on_in_python_with_the_same_answer():
    """Murty's example at k = 16 takes 2^16 - 1 pivots, more than one slice: the C entry hands it to the sliced
    solve, which returns what the Python function returns."""
    M, q = murty_exponential(16)
    result = same_outcome(M, q, method="murty", fast_paths=False)
    assert result.status == "solved" and result.iterations == 2 ** 16 - 1


@needs_c_entry
@pytest.mark.parametrize("args,kwargs", [
    (([[2.0, 1.0], [1.0, 2.0]], [-1.0, -1.0]), {}),                              # lists
    ((np.eye(3, dtype=np.float32), -np.ones(3, dtype=np.float32)), {}),           # float32
    ((np.asfortranarray(np.array([[2.0, 1.0], [0.5, 3.0]])), np.array([-1.0, 2.0])), {}),   # Fortran order
    ((np.eye(3), -np.ones(6)[::2]), {}),                                         # a strided q
    ((np.eye(3).astype(">f8"), -np.ones(3)), {}),                                # big-endian doubles
    ((np.eye(2), -np.ones(2)), {"method": "enum"}),
    ((np.eye(2), -np.ones(2)), {"method": 3}),
    ((np.eye(2), -np.ones(2)), {"method": "simplex"}),
    ((np.eye(2), -np.ones(2)), {"method": "lemke", "pivot_tol": 1e-9}),
    ((np.eye(2), -np.ones(2)), {"method": "pgs", "omega": 1.2}),
    ((np.eye(2), -np.ones(2)), {"max_iter": 5}),
    ((np.eye(2), -np.ones(2)), {"max_iter": None, "time_limit": None}),
    ((np.eye(2), -np.ones(2)), {"time_limit": 1.0}),
    ((np.eye(2), -np.ones(2)), {"tol": 0}),
    ((np.eye(2), -np.ones(2)), {"tol": np.float64(1e-8)}),
    ((np.eye(2), -np.ones(2)), {"tol": 1.0}),
    ((np.eye(2), -np.ones(2)), {"fast_paths": "no"}),
    ((np.eye(2), -np.ones(2)), {"fast_paths": np.bool_(False)}),
    ((np.eye(2), -np.ones(2), "auto", 1e-10, None, True, None), {}),              # all seven by position
    ((np.eye(2), -np.ones(2)), {"M": np.eye(2)}),                                # given twice
    ((np.eye(2), -np.ones(2), "lemke"), {"method": "lemke"}),
    ((np.eye(2),), {}),
    ((np.array([[np.nan, 0.0], [0.0, 1.0]]), -np.ones(2)), {}),                   # NaN: Python's message
    ((np.eye(2), np.array([-np.inf, 1.0])), {}),
    ((np.eye(2), -np.ones(3)), {}),
    ((np.zeros((0, 0)), np.zeros(0)), {}),
    ((np.eye(129), -np.ones(129)), {}),                                          # above FAST_MAX_K
    ((np.eye(2), np.ones(2)), {"method": "newton"}),
])
def test_every_other_call_is_handed_to_python_unchanged(args, kwargs):
    same_outcome(*args, **kwargs)


@needs_c_entry
def test_a_time_or_memory_limit_in_the_environment_is_read_by_python(monkeypatch):
    M, q = murty_exponential(6)
    monkeypatch.setenv("PCSUITE_TIME_LIMIT", "2")
    same_outcome(M, q)
    monkeypatch.setenv("PCSUITE_TIME_LIMIT", "soon")
    assert "PCSUITE_TIME_LIMIT" in str(same_outcome(M, q))        # the limit's own error, as Python words it
    monkeypatch.delenv("PCSUITE_TIME_LIMIT")
    monkeypatch.setenv("PCSUITE_MAX_MEMORY", "100")                # bytes: less than one work array
    assert "PCSUITE_MAX_MEMORY" in str(same_outcome(M, q)) or "memory" in str(same_outcome(M, q))


@needs_c_entry
def test_it_reads_as_solve_lcp_pickles_by_name_and_its_results_are_frozen_dataclasses():
    assert solve_lcp.__doc__ == PYTHON.__doc__ and solve_lcp.__name__ == "solve_lcp"
    assert inspect.signature(solve_lcp) == inspect.signature(PYTHON)
    assert pickle.loads(pickle.dumps(solve_lcp)) is solve_lcp
    assert repr(solve_lcp) == repr(PYTHON)
    result = solve_lcp(np.eye(2), -np.ones(2))
    with pytest.raises(dataclasses.FrozenInstanceError):
        result.status = "failed"
    assert dataclasses.replace(result, message="x").message == "x"
    assert pickle.loads(pickle.dumps(result)).method == "auto:closed form"
    assert result.solutions == [] and result.solutions is not solve_lcp(np.eye(2), -np.ones(2)).solutions


@needs_c_entry
def test_a_hundred_thousand_calls_leak_no_reference():
    M, q = murty_exponential(5)
    M2 = np.array([[2.0, 1.0], [1.0, 2.0]])
    q2 = np.array([-1.0, 1.0])
    from converters.lcp import answer
    watched = [M, q, M2, q2, answer.SOLVED, answer.LCPResult, None]
    for _ in range(100):                                          # caches filled
        solve_lcp(M, q, fast_paths=False), solve_lcp(M2, q2), outcome(lambda: solve_lcp(M, q, max_iter=-1))
    before = [sys.getrefcount(x) for x in watched]
    for _ in range(30_000):
        solve_lcp(M, q, fast_paths=False)                          # auto:lemke
        solve_lcp(M2, q2)                                          # a closed form
        outcome(lambda: solve_lcp(M, q, max_iter=-1))             # an error, in Python
    assert [sys.getrefcount(x) for x in watched] == before


@needs_c_entry
@pytest.mark.parametrize("keep", ["the result", "z alone", "w alone", "a view of z", "a weak reference to z",
                                  "a read-only z", "a list of solutions grown"])
def test_a_result_or_array_still_held_is_never_recycled(keep):
    """The C entry recycles a result (its arrays and list) only once nothing else refers to it: whatever the caller
    keeps keeps its values, and every recycled result is the new answer in full (writeable arrays, an empty list)."""
    import weakref
    M, q = murty_exponential(3)                                        # z = (0, 0, 1), w = (1, 1, 0)
    other = (2.0 * np.eye(3), np.array([-2.0, -4.0, -6.0]))           # z = (1, 2, 3), w = 0: the same k
    expected = PYTHON(M, q)
    held = solve_lcp(M, q)
    kept = {"the result": lambda r: r, "z alone": lambda r: r.z, "w alone": lambda r: r.w,
            "a view of z": lambda r: r.z[:], "a weak reference to z": lambda r: weakref.ref(r.z),
            "a read-only z": lambda r: r.z.flags.__setattr__("writeable", False),
            "a list of solutions grown": lambda r: r.solutions.append("mine")}[keep](held)
    del held
    for _ in range(3):                                                 # more calls than the pool has entries
        for problem in (other, (np.eye(1), -np.ones(1)), other):
            again = solve_lcp(*problem)
            same(again, PYTHON(*problem))
            assert again.solutions == [] and again.z.flags.writeable and again.w.flags.writeable
            del again
            if keep == "the result":
                same(kept, expected)
            elif keep in ("z alone", "a view of z"):
                assert np.array_equal(kept, expected.z)
            elif keep == "w alone":
                assert np.array_equal(kept, expected.w)
            elif keep == "a weak reference to z":
                assert kept() is None or np.array_equal(kept(), expected.z)


@needs_c_entry
def test_auto_messages_kept_by_the_c_entry_are_pythons_own_words():
    """When other methods of auto's plan gave way, the C entry keeps the message by (method used, stages,
    eigenvalue, k) in 8 entries: ten bimatrix games (Lemke ends on a ray, enumeration solves) of k = 3 .. 12,
    solved three times round, overflow them; every answer must still be the Python function's, word for word."""
    rng = np.random.default_rng(0)
    games = []
    for m, n in [(1, 2), (2, 2), (2, 3), (3, 3), (3, 4), (4, 4), (4, 5), (5, 5), (5, 6), (6, 6)]:
        M = np.block([[np.zeros((m, m)), rng.uniform(1, 30, (m, n))], [rng.uniform(1, 30, (n, m)), np.zeros((n, n))]])
        games.append((M, -np.ones(m + n)))
    for _ in range(3):
        for M, q in games:
            result = solve_lcp(M, q)
            assert result.method == "auto:enum" and "lemke ended on a ray" in result.message
            same(result, PYTHON(M, q))


@needs_c_entry
def test_a_lemke_answer_that_fails_the_check_goes_on_through_auto_as_in_python():
    """In the one-call solve Lemke leaves the check of its answer to the check on the original problem; when that
    fails, the sliced solve runs the plan again, where Lemke's own check fails and auto goes on. An ill-conditioned
    M (condition ~1e11) at tol = 1e-16: the message must name Lemke's failed check, and the answer be Python's."""
    rng = np.random.default_rng(4)
    k = int(rng.integers(2, 9))
    U, _ = np.linalg.qr(rng.normal(size=(k, k)))
    M = U @ np.diag(np.logspace(0, -rng.uniform(6, 15), k)) @ U.T
    q = rng.normal(size=k)
    result = same_outcome(M, q, tol=1e-16, fast_paths=False)
    assert "lemke's answer failed the residual check" in result.message


@needs_c_entry
def test_the_solver_refuses_a_configuration_it_would_misread():
    """Its limits are read before the object exists (an int subclass's __index__ could otherwise reach a half-built
    Solver through the garbage collector); anything but exact ints and str is refused."""
    from converters.lcp import solve as solve_module
    arguments = list(solve_module._solver_arguments(PYTHON))
    arguments[15] = (1.5,) * len(arguments[15])                           # once_max_iter
    with pytest.raises(ValueError, match="names and labels must be str, limits int"):
        type(solve_lcp)(*arguments)
