"""Ranges of tol, max_iter and time_limit; every iterative solver stops at its time limit; memory is checked first."""
import time
import tracemalloc

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


def stopped_at_the_limit(clock, seconds: float) -> bool:
    """The solve looked at the clock (10 ms a look: tests/lcp/conftest.py) until just past ``seconds``, and stopped
    there: it neither gave up early nor went on (a look before the first slice and one after each; numba's loads of
    cached kernels at a first call read the clock twice each, their time not counted: a few more)."""
    looks = round(seconds / clock.step)
    return looks <= clock.reads <= looks + 20


def test_murty_on_a_300x300_exponential_problem_stops_at_the_time_limit(ticking_clock):
    M, q = murty_exponential(300)     # 2^300 - 1 pivots
    # 10^6 pivots (~20 s of work): without looks at the clock it ends at max_iter, not at the limit
    result = solve_lcp(M, q, method="murty", max_iter=10**6, fast_paths=False, time_limit=1.0)
    assert stopped_at_the_limit(ticking_clock, 1.0), ticking_clock.reads
    assert result.status == "failed" and TIME_MESSAGE.format(1.0) in result.message
    assert result.message.startswith(f"murty (after {result.iterations} pivots) reached")
    # pivots between the looks: a slice of 2^22 multiply-adds is ~46 pivots of this 300 x 300 tableau
    assert 40 * 100 < result.iterations < 10**6 and np.all(np.isfinite(result.z))


def test_the_time_limit_comes_from_the_environment_when_not_given(monkeypatch, ticking_clock):
    monkeypatch.setenv("PCSUITE_TIME_LIMIT", "0.5")
    M, q = murty_exponential(300)
    result = solve_lcp(M, q, method="murty", max_iter=10**6, fast_paths=False)
    assert stopped_at_the_limit(ticking_clock, 0.5), ticking_clock.reads
    assert TIME_MESSAGE.format(0.5) in result.message


def test_pgs_stalling_on_an_ill_conditioned_problem_stops_at_the_time_limit(ticking_clock):
    rng = np.random.default_rng(3)
    Q, _ = np.linalg.qr(rng.standard_normal((200, 200)))
    M = Q @ np.diag(np.logspace(0, -9, 200)) @ Q.T     # SPD, condition number 1e9: PGS needs ~1e9 sweeps
    M = 0.5 * (M + M.T)
    result = solve_lcp(M, -np.ones(200), method="pgs", tol=1e-16, max_iter=10**6, time_limit=0.5)
    assert stopped_at_the_limit(ticking_clock, 0.5), ticking_clock.reads
    assert result.status == "failed" and TIME_MESSAGE.format(0.5) in result.message
    assert result.message.startswith(f"pgs (after {result.iterations} sweeps)") and result.iterations > 10 * 50


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
    tracemalloc.start()
    try:
        with pytest.raises(ResourceError, match=r"^solve_lcp \(method lemke\): k = 600 \(7 work arrays of k x k "
                                                r"doubles\) needs about 19\.2 MiB, above the memory limit of 16 MiB; "
                                                r".*--max-memory"):
            solve_lcp(M, q, method="lemke")
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 3 * 600 * 600 * 8                # refused before Lemke's tableau: at most a copy of M and its scaling
    result = solve_lcp(M, -q, method="murty", fast_paths=False)   # q >= 0: z = 0 at the first pivot
    assert result.solved and result.iterations == 0
    np.testing.assert_array_equal(result.z, 0.0)


# ------------------------------------------------------------------ the clock measures the solve, not its set-up
# numba compiles a kernel (or loads it from its on-disk cache) at its first call, inside the first solve that needs
# it; with an empty cache that takes longer than the default limit of 20 s, and a limit that counted it would end
# the first solve before its first step ("enum (after 0 of 4 bases) reached the time limit").

PAIR = (np.array([[2.0, 1.0], [1.0, 2.0]]), np.array([-3.0, -3.0]))      # z = (1, 1), one basic solution of four
RAY = (-np.eye(3), -np.ones(3))          # Lemke ends on a ray: the one-call solve hands it to the sliced one


def _hold_the_compiler_lock(seconds: float) -> None:
    """What a kernel's first call costs its caller: ``seconds`` inside numba's compiler lock, as a compile."""
    from numba.core.compiler_lock import global_compiler_lock
    with global_compiler_lock:
        time.sleep(seconds)


def test_a_compile_inside_the_solve_does_not_count_against_its_time_limit(monkeypatch):
    from converters.lcp import engine
    sizes = engine.sizes

    def compiled_now(method, k):
        _hold_the_compiler_lock(0.3)
        return sizes(method, k)
    monkeypatch.setattr(engine, "sizes", compiled_now)
    result = solve_lcp(*PAIR, method="enum", time_limit=0.1, fast_paths=False)
    assert result.solved and result.iterations == 4 and result.message == ""
    np.testing.assert_allclose(result.z, [1.0, 1.0], rtol=1e-15)

    def slow_work(method, k):       # the same 0.3 s as the solve's own work: it still reaches the limit
        time.sleep(0.3)
        return sizes(method, k)
    monkeypatch.setattr(engine, "sizes", slow_work)
    result = solve_lcp(*PAIR, method="enum", time_limit=0.1, fast_paths=False)
    assert result.status == "failed" and result.iterations == 0
    assert result.message.startswith("enum (after 0 of 4 bases) " + TIME_MESSAGE.format(0.1))


def test_loading_the_one_call_solve_does_not_count_against_the_time_limit(monkeypatch):
    """The thin path's first call loads its kernel (an import, a compile): a solve it hands to the sliced solve
    has its whole limit left."""
    from converters.lcp import solve
    monkeypatch.setenv("PCSUITE_TIME_LIMIT", "0.1")
    solve._load_once()
    load = solve._load_once

    def slow_load():
        time.sleep(0.3)
        return load()
    monkeypatch.setattr(solve, "_once", None)
    monkeypatch.setattr(solve, "_load_once", slow_load)
    result = solve.solve_lcp(*RAY, method="lemke", fast_paths=False)
    assert result.status == "no_solution" and result.iterations == 1
    assert result.message.startswith("lemke: ray termination, and no solution exists: w[0] = q[0]")


FRESH = """
import json, time
import numpy as np
from converters import compiled
from converters.lcp import solve_lcp
out = {"kernels": compiled.source()}
for name, M, q, method, limit in (("full", [[2.0, 1.0], [1.0, 2.0]], [-3.0, -3.0], "enum", 1.0),
                                  ("thin", -np.eye(3), -np.ones(3), "lemke", None)):
    start = time.monotonic()
    r = solve_lcp(np.array(M, dtype=float), np.array(q, dtype=float), method=method, fast_paths=False,
                  time_limit=limit)
    out[name] = {"status": r.status, "iterations": r.iterations, "message": r.message,
                 "seconds": time.monotonic() - start}
print(json.dumps(out))
"""


@pytest.mark.slow
def test_a_fresh_machine_compiles_the_solvers_outside_the_time_limit(tmp_path):
    """numba's JIT with an empty cache (as on a fresh machine, or after a kernel source changed): the first solves
    compile the methods, which takes longer than their limit of 1 s, and still solve."""
    import json
    import os
    import subprocess
    import sys
    from pathlib import Path
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path), "PCSUITE_KERNELS": "jit", "PCSUITE_TIME_LIMIT": "1"}
    done = subprocess.run([sys.executable, "-c", FRESH], capture_output=True, text=True, env=env, timeout=900,
                          cwd=Path(__file__).resolve().parents[2])
    assert done.returncode == 0, done.stderr
    out = json.loads(done.stdout)
    assert out["kernels"] == "jit: PCSUITE_KERNELS=jit"
    assert out["full"]["seconds"] > 1.0 and out["thin"]["seconds"] > 1.0, out      # the compiles were inside the calls
    assert (out["full"]["status"], out["full"]["iterations"], out["full"]["message"]) == ("solved", 4, ""), out
    assert (out["thin"]["status"], out["thin"]["iterations"]) == ("no_solution", 1), out
    assert out["thin"]["message"].startswith("lemke: ray termination, and no solution exists"), out
