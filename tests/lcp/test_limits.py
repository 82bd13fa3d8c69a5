"""Ranges of tol, max_iter and time_limit; every iterative solver stops at its time limit; memory is checked first."""
import time

import numpy as np
import pytest

from converters.errors import LCPError, ResourceError
from converters.lcp import solve_lcp
from converters.lcp.engine import enumerate_bases, lemke, murty, newton_fb, pgs
from converters.lcp.problems import murty_exponential, random_p_matrix
from converters.limits import Deadline

ALL = ["auto", "lemke", "murty", "enum", "pgs", "newton"]
TIME_MESSAGE = "reached the time limit of {:g} s; raise it with --time-limit S"


@pytest.fixture(autouse=True)
def default_limits(monkeypatch):
    monkeypatch.delenv("PCSUITE_TIME_LIMIT", raising=False)
    monkeypatch.setenv("PCSUITE_MAX_MEMORY", "1G")


@pytest.mark.parametrize("tol", [10.0, 0.1, 1e-17, 0.0, -1e-10, float("nan"), float("inf"), "1e-10", True])
def test_tol_outside_its_range_is_refused(tol):
    with pytest.raises(LCPError, match=r"^tol must be in \[1e-16, 0\.01\]; got " + repr(tol).replace(".", r"\.")
                       .replace("(", r"\(").replace(")", r"\)")):
        solve_lcp(np.eye(2), [-1.0, -1.0], tol=tol)


@pytest.mark.parametrize("tol", [1e-16, 1e-2])
def test_tol_at_the_ends_of_its_range_is_accepted(tol):
    result = solve_lcp([[2.0, 1.0], [1.0, 2.0]], [-3.0, -3.0], method="lemke", tol=tol, fast_paths=False)
    assert result.solved and result.err <= tol
    np.testing.assert_allclose(result.z, [1.0, 1.0], rtol=1e-15)


@pytest.mark.parametrize("max_iter", [0, -5, 10**9 + 1, 10**12, 1e3, 2.5, True])
def test_max_iter_outside_its_range_is_refused(max_iter):
    with pytest.raises(LCPError, match=r"^max_iter must be an integer in \[1, 1000000000\]; got "):
        solve_lcp(np.eye(2), [-1.0, -1.0], max_iter=max_iter)


def test_max_iter_at_the_top_of_its_range_acts_with_the_time_limit():
    M, q = murty_exponential(12)     # 4095 pivots
    result = solve_lcp(M, q, method="murty", max_iter=10**9, fast_paths=False)
    assert result.solved and result.iterations == 2**12 - 1
    short = solve_lcp(M, q, method="murty", max_iter=100, fast_paths=False)
    assert short.status == "max_iterations" and short.iterations == 100


@pytest.mark.parametrize("limit", [0.01, 0.0, -1.0, float("nan"), 1e9, "1"])
def test_time_limit_outside_its_range_is_refused(limit):
    with pytest.raises(LCPError, match=r"^time_limit must be a number of seconds in \[0\.1, 604800\]; got "):
        solve_lcp(np.eye(2), [-1.0, -1.0], time_limit=limit)


def test_murty_on_a_300x300_exponential_problem_stops_at_the_time_limit():
    M, q = murty_exponential(300)     # 2^300 - 1 pivots
    start = time.perf_counter()
    result = solve_lcp(M, q, method="murty", max_iter=10**9, fast_paths=False, time_limit=1.0)
    elapsed = time.perf_counter() - start
    assert 1.0 <= elapsed < 2.0
    assert result.status == "failed" and TIME_MESSAGE.format(1.0) in result.message
    assert result.message.startswith(f"murty (after {result.iterations} pivots) reached")
    assert 100 < result.iterations < 10**9 and np.all(np.isfinite(result.z))


def test_the_time_limit_comes_from_the_environment_when_not_given(monkeypatch):
    monkeypatch.setenv("PCSUITE_TIME_LIMIT", "0.5")
    M, q = murty_exponential(300)
    start = time.perf_counter()
    result = solve_lcp(M, q, method="murty", max_iter=10**9, fast_paths=False)
    assert 0.5 <= time.perf_counter() - start < 1.5
    assert TIME_MESSAGE.format(0.5) in result.message


def test_pgs_stalling_on_an_ill_conditioned_problem_stops_at_the_time_limit():
    rng = np.random.default_rng(3)
    Q, _ = np.linalg.qr(rng.standard_normal((200, 200)))
    M = Q @ np.diag(np.logspace(0, -9, 200)) @ Q.T     # SPD, condition number 1e9: PGS needs ~1e9 sweeps
    M = 0.5 * (M + M.T)
    start = time.perf_counter()
    result = solve_lcp(M, -np.ones(200), method="pgs", tol=1e-16, max_iter=10**9, time_limit=0.5)
    assert 0.5 <= time.perf_counter() - start < 1.5
    assert result.status == "failed" and TIME_MESSAGE.format(0.5) in result.message
    assert result.message.startswith(f"pgs (after {result.iterations} sweeps)") and result.iterations > 10


@pytest.mark.parametrize("solver,name,unit", [(lemke, "lemke", "pivots"), (murty, "murty", "pivots"),
                                               (pgs, "pgs", "sweeps"), (newton_fb, "newton", "steps"),
                                               (enumerate_bases, "enum", "of 4096 bases")])
def test_every_iterative_solver_checks_its_deadline(solver, name, unit):
    M = random_p_matrix(np.random.default_rng(5), 12, "spd")
    q = -np.ones(12)
    deadline = Deadline(0.0)
    time.sleep(0.001)
    result = solver(M, q, tol=1e-10, max_iter=1000, deadline=deadline)
    assert result.status == "failed" and result.method == name
    assert f"{name} (after " in result.message and unit in result.message
    assert TIME_MESSAGE.format(0.0) in result.message
    assert solver(M, q, tol=1e-10, max_iter=1000, deadline=Deadline(60.0)).solved  # the same problem, in time


def test_solver_working_memory_is_checked_before_solving(monkeypatch):
    monkeypatch.setenv("PCSUITE_MAX_MEMORY", "16M")
    M, q = np.eye(600), -np.ones(600)   # Lemke: 7 x 600^2 doubles = 20.2 MB > 16 MiB; Murty: 4 x = 11.5 MB fits
    start = time.perf_counter()
    with pytest.raises(ResourceError, match=r"^solve_lcp \(method lemke\): k = 600 \(7 work arrays of k x k doubles\) "
                                            r"needs about 19\.2 MiB, above the memory limit of 16 MiB; .*--max-memory"):
        solve_lcp(M, q, method="lemke")
    assert time.perf_counter() - start < 0.5
    result = solve_lcp(M, -q, method="murty", fast_paths=False)   # q >= 0: z = 0 at the first pivot
    assert result.solved and result.iterations == 0
    np.testing.assert_array_equal(result.z, 0.0)
