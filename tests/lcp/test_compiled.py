"""The compiled methods against the former pure-Python ones (tests/lcp/reference.py, the oracle), and the thin
path of solve_lcp against its full path: same answers, same checks, same limits."""
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import example, given, settings, strategies as st

from converters.errors import LCPError, ResourceError
from converters.lcp import engine, read_siconos_lcp, solve_lcp
from converters.lcp.engine import enumerate_bases, lemke, murty, newton_fb, pgs
from converters.lcp.problems import murty_exponential, problem_set, random_p_matrix
from converters.lcp.solve import normalise

from . import reference

ROOT = Path(__file__).resolve().parents[2]

COMPILED = {"lemke": lemke, "murty": murty, "pgs": pgs, "newton": newton_fb, "enum": enumerate_bases}
MAX_ITER = {"lemke": 10_000, "murty": 100_000, "pgs": 10_000, "newton": 1000}


def same_path(method, M, q):
    """The compiled method takes the oracle's path: same status and iterations, and the same z (to rounding)
    wherever the run ends at an answer (a run stopped at max_iter may drift in the last bits for 10^4 sweeps)."""
    M, q, _ = normalise(M, q)
    kwargs = {} if method == "enum" else {"max_iter": MAX_ITER[method]}
    old = reference.REFERENCE[method](M, q, tol=1e-10, **kwargs)
    new = COMPILED[method](M, q, tol=1e-10, **kwargs)
    if method == "lemke" and old.status == "no_solution":   # the oracle's ray; ours is no_solution with a proof,
        assert new.status in ("no_solution", "failed") and "lemke: ray termination" in new.message   # else failed
    else:
        assert new.status == old.status, (method, new.message)
    same = True
    if method in ("newton", "pgs"):
        # an iteration stopping on a residual threshold: the compiled sums (another order than NumPy's BLAS) may
        # cross it one iteration apart (seen: Newton 119 vs 118 on an integer problem); pivots are exact
        if abs(new.iterations - old.iterations) > 1:
            # more only where the path is decided by rounding: the oracle itself strays as far when one
            # entry of q or M moves by one ulp (seen: Newton on a degenerate integer problem, k = 7, whose
            # iterates oscillate and amplify a 1e-16 difference 3x per step: 49 vs 40 iterations, and the
            # oracle takes 39-62 on q nudged by one ulp; k = 4, seed 113: 146 vs 155, the oracle 147-161 on q
            # nudged and 145-169 on M nudged: the compiled sums round differently inside M z, not only in q)
            strays = max(abs(reference.REFERENCE[method](M_n, q_n, tol=1e-10, **kwargs).iterations
                             - old.iterations) for M_n, q_n in _nudged(M, q))
            assert strays >= abs(new.iterations - old.iterations), (method, new.iterations, old.iterations, strays)
            same = False
    else:
        assert new.iterations == old.iterations, (method, new.message)
    if new.status != "max_iterations" and same:
        tolerance = 1e-9 * np.abs(old.z) + 1e-12 * (1.0 + np.abs(old.z).max())
        if method in ("newton", "pgs") and np.any(np.abs(new.z - old.z) > tolerance):
            # the same iterations, yet z apart by more than rounding: only where the oracle itself moves as far
            # on a one-ulp nudge (seen: Newton, integer k = 7, seed 23866: 27 iterations each, z 3.3e-9 apart,
            # the oracle's own z 3.9e-8 apart on a nudged entry, its M has eigenvalues on both half-planes)
            strays = max(np.abs(reference.REFERENCE[method](M_n, q_n, tol=1e-10, **kwargs).z - old.z).max()
                         for M_n, q_n in _nudged(M, q))
            assert np.abs(new.z - old.z).max() <= strays, (method, np.abs(new.z - old.z).max(), strays)
        else:
            np.testing.assert_allclose(new.z, old.z, rtol=1e-9, atol=1e-12 * (1.0 + np.abs(old.z).max()))
    if method == "enum":
        assert len(new.solutions) == len(old.solutions)
        for a, b in zip(new.solutions, old.solutions):
            np.testing.assert_allclose(a, b, rtol=1e-9, atol=1e-12)


def _nudged(M, q):
    """(M, q) with one entry of q or of M moved by one ulp, up or down: every such copy."""
    for i in range(q.shape[0]):
        for direction in (np.inf, -np.inf):
            nudged = q.copy()
            nudged[i] = np.nextafter(nudged[i], direction)
            yield M, nudged
            for j in range(q.shape[0]):
                nudged_M = M.copy()
                nudged_M[i, j] = np.nextafter(nudged_M[i, j], direction)
                yield nudged_M, q


@pytest.mark.parametrize("method", list(COMPILED))
def test_compiled_methods_take_the_reference_path_on_the_project_problem_set(method):
    for case in problem_set():
        if method == "enum" and case.M.shape[0] > 12:
            continue
        same_path(method, case.M, case.q)


@pytest.mark.parametrize("method", list(COMPILED))
def test_compiled_methods_take_the_reference_path_on_the_peer_collection(peer, method):
    for path in sorted(peer.glob("lcp_*.dat")):
        p = read_siconos_lcp(path)
        if method == "enum" and p.M.shape[0] > 12:
            continue
        same_path(method, p.M, p.q)


@settings(max_examples=40, deadline=None)
@example(k=7, seed=1, kind="integer")     # Newton's path decided by rounding (see same_path)
@example(k=4, seed=113, kind="integer")   # the same, the oracle straying further on M nudged than on q
@example(k=7, seed=23866, kind="integer")  # Newton's z decided by rounding at equal iterations
@given(k=st.integers(1, 12), seed=st.integers(0, 2**32 - 1),
       kind=st.sampled_from(["pd", "spd", "triangular", "integer"]))
@pytest.mark.slow
def test_compiled_methods_take_the_reference_path_on_random_problems(k, seed, kind):
    rng = np.random.default_rng(seed)
    if kind == "integer":        # any matrix: rays, singular submatrices, degenerate ties, no solution
        M, q = rng.integers(-3, 4, (k, k)).astype(float), rng.integers(-3, 4, k).astype(float)
    else:
        M, q = random_p_matrix(rng, k, kind), rng.standard_normal(k)
    for method in COMPILED:
        same_path(method, M, q)


def peer_problems(peer):
    return [read_siconos_lcp(path) for path in sorted(peer.glob("lcp_*.dat"))]


@pytest.mark.parametrize("method", ["auto", "lemke", "murty", "pgs", "newton"])
def test_the_thin_path_answers_as_the_full_path(peer, method):
    """float64 C arrays take the thin path; lists take the full one (validation in Python, sliced run)."""
    for p in peer_problems(peer):
        thin = solve_lcp(p.M, p.q, method=method)
        full = solve_lcp(p.M.tolist(), p.q.tolist(), method=method)
        assert (thin.status, thin.method, thin.iterations, thin.message) == \
            (full.status, full.method, full.iterations, full.message), p.name
        np.testing.assert_array_equal(thin.z, full.z)
        np.testing.assert_array_equal(thin.w, full.w)
        assert thin.err == full.err


def test_a_small_solve_takes_the_thin_path(monkeypatch, peer):
    p = read_siconos_lcp(peer / "lcp_CPS_2.dat")
    solve_lcp(p.M, p.q)

    def refuse(*args, **kwargs):
        raise AssertionError("the sliced run was used")
    monkeypatch.setattr(engine, "Run", refuse)
    assert solve_lcp(p.M, p.q).solved and solve_lcp(np.asfortranarray(p.M), p.q).solved   # F order: one copy
    with pytest.raises(AssertionError, match="sliced run"):
        solve_lcp(p.M.tolist(), p.q)


def test_a_solve_longer_than_one_slice_continues_where_it_stopped():
    M, q = murty_exponential(16)           # 65535 pivots: many slices of CHUNK multiply-adds
    result = solve_lcp(M, q, method="murty", fast_paths=False)    # the pivots, not the triangular closed form
    assert result.solved and result.iterations == 2**16 - 1
    np.testing.assert_allclose(result.z, np.eye(16)[-1])
    enum = solve_lcp(*murty_exponential(12), method="enum")   # 4096 bases, also in slices
    assert enum.solved and enum.iterations == 4096 and len(enum.solutions) == 1


@pytest.mark.parametrize("M,q,match", [
    (np.array([[np.nan]]), np.array([1.0]), r"M must contain only finite numbers; got nan"),
    (np.eye(2), np.array([1.0, np.inf]), r"q must contain only finite numbers; got inf"),
    (np.eye(2, dtype=np.float32), np.array([1.0, np.nan], dtype=np.float32), r"q must contain only finite"),
    (np.eye(3), np.ones(2), r"q must be a vector of length 3; got shape 2"),
    (np.ones((2, 3)), np.ones(2), r"M must be square \(k x k\); got shape 2x3"),
    (np.zeros((0, 0)), np.zeros(0), r"M must be at least 1x1; got an empty matrix"),
])
def test_the_thin_path_refuses_what_the_full_path_refuses(M, q, match):
    with pytest.raises(LCPError, match=match):
        solve_lcp(M, q)


def test_other_dtypes_and_layouts_give_the_same_answer(peer):
    p = read_siconos_lcp(peer / "lcp_mmc.dat")
    base = solve_lcp(p.M, p.q)
    for M, q in ((np.asfortranarray(p.M), p.q), (p.M.astype(np.longdouble), p.q), (p.M.tolist(), p.q[::-1][::-1]),
                 (p.M.copy(), np.asfortranarray(p.q))):
        again = solve_lcp(M, q)
        assert again.method == base.method and again.iterations == base.iterations
        np.testing.assert_array_equal(again.z, base.z)


def test_the_limits_in_the_environment_are_read_at_every_call(monkeypatch):
    M, q = np.eye(2) + 1.0, -np.ones(2)
    monkeypatch.setenv("PCSUITE_TIME_LIMIT", "soon")
    with pytest.raises(ResourceError, match=r"PCSUITE_TIME_LIMIT must be a number of seconds"):
        solve_lcp(M, q)
    monkeypatch.setenv("PCSUITE_TIME_LIMIT", "5")
    assert solve_lcp(M, q).solved
    monkeypatch.setenv("PCSUITE_MAX_MEMORY", "lots")
    with pytest.raises(ResourceError, match=r"PCSUITE_MAX_MEMORY must be a size in bytes"):
        solve_lcp(M, q)
    monkeypatch.setenv("PCSUITE_MAX_MEMORY", "16M")
    with pytest.raises(ResourceError, match=r"solve_lcp \(method auto\): k = 600 .* above the memory limit of 16 MiB"):
        solve_lcp(np.eye(600), -np.ones(600))
    monkeypatch.delenv("PCSUITE_MAX_MEMORY")
    assert solve_lcp(np.eye(600), -np.ones(600)).solved


@pytest.mark.parametrize("options,match", [
    (dict(method="lemke", omega=1.2), r"option 'omega' does not apply to method 'lemke'"),
    (dict(method="pgs", omega=2.0), r"omega must be in \(0, 2\); got 2.0"),
    (dict(method="pgs", omega=-1.0), r"omega must be a positive finite number; got -1.0"),
    (dict(method="newton", beta=1.5), r"beta must be in \(0, 1\); got 1.5"),
    (dict(method="lemke", pivot_tol=float("nan")), r"pivot_tol must be a positive finite number; got nan"),
    (dict(method="lemke", pivot_tol=0.5), r"pivot_tol must be in \(0, 1e-06\]; got 0.5"),   # made Lemke end on a ray
    (dict(method="newton", sigma=1.0), r"sigma must be in \(0, 0.5\); got 1.0"),
    (dict(method="newton", p=2.0), r"p must be > 2; got 2.0"),
])
def test_options_are_checked(options, match):
    with pytest.raises(LCPError, match=match):
        solve_lcp(np.eye(2), -np.ones(2), **options)


def test_options_act():
    M = random_p_matrix(np.random.default_rng(8), 10, "spd")
    q = -np.ones(10)
    plain, over = (solve_lcp(M, q, method="pgs", omega=omega, fast_paths=False) for omega in (1.0, 1.5))
    assert plain.solved and over.solved and plain.iterations != over.iterations
    np.testing.assert_allclose(over.z, plain.z, atol=1e-8)


# ------------------------------------------------------------------- compiled without reference counting

@pytest.mark.slow
def test_the_solve_path_below_the_allocation_does_no_reference_counting(tmp_path):
    # solve_once allocates the workspace; everything below it (solve_in and the methods it calls) is compiled
    # with _nrt=False: the atomic increments and decrements of array arguments were 3/4 of a small solve.
    # Read in the LLVM IR of a fresh compile (numba does not keep the IR of cached code): a new cache dir.
    script = """
import numpy as np
from converters.lcp import engine, state as S
from converters.lcp.dispatch import DEFAULT_OPTIONS
M, q = np.array([[2.0, 1.0, 0.0], [1.0, 2.0, 1.0], [0.0, 1.0, 2.0]]), -np.ones(3)
answer = engine.solve_once(M, q, np.empty(3), np.empty(3), S.AUTO, 1e-10, -1, True, DEFAULT_OPTIONS, S.CHUNK)
assert answer[0] == S.ONCE_SOLVED
(ir,) = engine.solve_once.inspect_llvm().values()
print(ir)
"""
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path), "PYTHONPATH": str(ROOT)}
    run = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, env=env, cwd=tmp_path)
    assert run.returncode == 0, run.stderr[-2000:]
    bodies = {}                                     # the package's compiled functions, linked into the module
    for chunk in run.stdout.split("\ndefine ")[1:]:
        name = re.search(r'@"?([^"\s(]+)', chunk.split("\n", 1)[0]).group(1)
        if "converters" in name:
            bodies[name] = chunk.split("\n}\n", 1)[0]
    once = [name for name in bodies if "solve_once" in name]
    rest = {name: body for name, body in bodies.items() if "solve_once" not in name}
    # the whole call tree is in the module (its small helpers inlined into their callers: inline='always')
    assert any("solve_in" in name for name in rest) and any("lemke" in name for name in rest) and len(rest) > 15
    counted = [name for name, body in rest.items() if "@NRT_incref" in body or "@NRT_decref" in body
               or "@NRT_MemInfo_alloc" in body]
    assert counted == []
    assert any("@NRT_MemInfo_alloc" in bodies[name] for name in once)     # the one function that allocates


def test_auto_hands_the_eigenvalue_to_its_caller_and_concludes_with_it():
    # Lemke's ray on a positive semidefinite M: the least eigenvalue of (M + M^T)/2 (LAPACK allocates) is
    # asked of the caller; given it, the plan proves that no solution exists
    from converters.lcp import auto
    from converters.lcp import state as S
    from converters.lcp.dispatch import DEFAULT_OPTIONS
    M, q = np.array([[1.0, -1.0, 0.0], [-1.0, 1.0, 0.0], [0.0, 0.0, 1.0]]), -np.ones(3)
    nf, ni = engine.sizes(S.AUTO, 3)
    z, fw, iw = np.zeros(3), np.empty(nf), np.empty(ni, dtype=np.int64)
    st, sf = np.zeros(S.ST_SIZE, dtype=np.int64), np.zeros(S.SF_SIZE)
    args = (S.AUTO, M, q, z, fw, iw, st, sf, 1e-10, -1, S.CHUNK, DEFAULT_OPTIONS)
    assert not engine.advance(*args) and st[S.PHASE] == S.EIGENVALUE and st[S.STATUS] == S.NO_SOLUTION
    assert np.isnan(sf[S.INFO_X])
    sf[S.INFO_X] = auto.least_symmetric_eigenvalue(M)
    assert sf[S.INFO_X] == pytest.approx(0.0, abs=1e-15)      # eigenvalues 0, 1, 2
    assert engine.advance(*args) and st[S.STATUS] == S.NO_SOLUTION and st[S.OUTCOME] == S.PROOF_PSD
    # told a negative eigenvalue instead, the plan goes on to enumeration (and finds no basis either)
    st[:] = 0
    assert not engine.advance(*args) and st[S.PHASE] == S.EIGENVALUE
    sf[S.INFO_X] = -0.5
    while not engine.advance(*args):
        pass
    assert st[S.STAGE_OUTCOME + S.LEMKE] == S.RAY and st[S.STAGE_OUTCOME + S.ENUM] == S.NOBASIS
    # through solve_lcp: the one-call path leaves it to the sliced one, which answers with the proof
    result = solve_lcp(M, q)
    assert result.status == "no_solution" and "M is positive semidefinite" in result.message


@pytest.mark.parametrize("m", [1, 2, 3, 5, 8, 12])
@pytest.mark.parametrize("log_cond", [0.0, 3.0, 7.0, 11.0])
def test_the_condition_number_agrees_with_numpy(m, log_cond):
    # enumeration's conditioning test, written allocation-free (one-sided Jacobi), against LAPACK's SVD
    from converters.lcp.enumeration import condition_number
    rng = np.random.default_rng(m * 100 + int(log_cond))
    U, _ = np.linalg.qr(rng.standard_normal((m, m)))
    V, _ = np.linalg.qr(rng.standard_normal((m, m)))
    exact = 10.0 ** log_cond if m > 1 else 1.0
    A = U @ np.diag(np.logspace(0.0, -log_cond, m)) @ V.T
    # rounding A perturbs sigma_min by ~eps sigma_max: the condition number is known to ~eps cond (relative)
    rel = 1e-10 + 10.0 * m * np.finfo(float).eps * exact
    assert np.linalg.cond(A) == pytest.approx(exact, rel=rel)           # the bound holds for LAPACK
    assert condition_number(A.copy(), m) == pytest.approx(exact, rel=rel)


def test_the_condition_number_of_a_singular_matrix_is_above_any_threshold():
    from converters.lcp.enumeration import condition_number
    assert condition_number(np.zeros((3, 3)), 3) == np.inf
    assert condition_number(np.array([[1.0, 2.0], [2.0, 4.0]]), 2) > 1e15
    assert condition_number(np.array([[1.0, 2.0, 3.0], [4.0, 5.0, 6.0], [7.0, 8.0, 9.0]]), 3) > 1e15
