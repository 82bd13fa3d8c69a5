"""`pcsuite lcp solve`: tiny and huge scales solved, out-of-range flags refused, and the time and memory limits."""
import contextlib
import json
import time
import tracemalloc

import numpy as np
import pytest

from converters.lcp.problems import murty_exponential
from validation.cli import main

ALL = ["auto", "lemke", "murty", "enum", "pgs", "newton"]


@pytest.fixture(autouse=True)
def limits(monkeypatch):
    # main() writes --time-limit / --max-memory into the environment: setting them here restores them afterwards
    monkeypatch.setenv("PCSUITE_TIME_LIMIT", "20")
    monkeypatch.setenv("PCSUITE_MAX_MEMORY", "1G")


@contextlib.contextmanager
def peak_memory():
    """Python's allocations while the block runs: yields a function returning their peak (bytes)."""
    tracemalloc.start()
    peak = []
    try:
        yield lambda: peak[0]
    finally:
        peak.append(tracemalloc.get_traced_memory()[1])
        tracemalloc.stop()


def write_dense(path, M, q):
    n = len(q)
    lines = [f"{n}", "0", f"{n} {n}", f"{n} {n}"]
    lines += [" ".join(f"{v:.17g}" for v in M[:, j]) for j in range(n)]
    lines.append(" ".join(f"{v:.17g}" for v in q))
    path.write_text("\n".join(lines) + "\n")
    return path


def run(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


@pytest.mark.parametrize("method", ALL)
@pytest.mark.parametrize("scale", [1e-200, 1e-100, 1e100])
def test_the_issue_file_is_solved_at_every_scale(capsys, tmp_path, method, scale):
    path = write_dense(tmp_path / "t.dat", np.eye(3), np.full(3, -scale))
    code, out, err = run(capsys, "lcp", "solve", str(path), "--method", method, "--json")
    data = json.loads(out)
    assert code == 0 and data["status"] == "solved" and err == ""
    np.testing.assert_allclose(data["z"], scale, rtol=1e-9)
    assert min(data["w"]) >= -1e-10 * scale


@pytest.mark.parametrize("argv,message", [
    (["--tol", "10"], "pcsuite: error: tol must be in [1e-16, 0.01]; got 10.0\n"),
    (["--tol", "1e-20"], "pcsuite: error: tol must be in [1e-16, 0.01]; got 1e-20\n"),
    (["--max-iter", "1000000000000"],
     "pcsuite: error: max_iter must be an integer in [1, 1000000000]; got 1000000000000\n"),
    (["--max-iter", "0"], "pcsuite: error: max_iter must be an integer in [1, 1000000000]; got 0\n"),
])
def test_out_of_range_flags_exit_2_with_one_line(capsys, tmp_path, argv, message):
    path = write_dense(tmp_path / "t.dat", np.eye(3), -np.ones(3))
    code, out, err = run(capsys, "lcp", "solve", str(path), *argv)
    assert (code, out, err) == (2, "", message)


def test_murty_with_a_huge_max_iter_stops_at_the_time_limit(capsys, tmp_path, ticking_clock):
    """The flag reaches the solve: it stops at its 100th look at the clock (10 ms each: tests/lcp/conftest.py) or
    just after, not at the 20 s of PCSUITE_TIME_LIMIT."""
    M, q = murty_exponential(300)
    path = write_dense(tmp_path / "lcp_murty300.dat", M, q)
    code, out, err = run(capsys, "lcp", "solve", str(path), "--method", "murty", "--max-iter", "1000000000",
                         "--time-limit", "1", "--no-fast-paths", "--json")
    assert 100 <= ticking_clock.reads <= 120, ticking_clock.reads
    assert code == 1 and json.loads(out)["status"] == "failed"
    assert err.count("\n") == 1 and err.startswith(f"pcsuite: lcp solve {path}: failed: murty (after ")
    assert "pivots) reached the time limit of 1 s; raise it with --time-limit S" in err


def test_a_50000_header_is_refused_naming_the_limit_and_the_flag(capsys, tmp_path):
    path = tmp_path / "big.dat"
    path.write_text("50000\n0\n50000 50000\n50000 50000\n1 2 3\n")
    with peak_memory() as peak:
        code, out, err = run(capsys, "lcp", "solve", str(path))
    assert peak() < 1 << 20                      # refused from the header: nothing near n^2 doubles allocated
    assert code == 2 and out == "" and err.count("\n") == 1
    assert err.startswith(f"pcsuite: error: lcp solve {path}: n = 50000 (dense M of n^2 doubles) needs about 18.6 GiB, "
                          "above the memory limit of 1 GiB; use a smaller LCP")
    assert "--max-memory 32G" in err


@pytest.mark.parametrize("method,flags", [("lemke", ["--method", "lemke"]), ("auto", [])])   # auto: the default
def test_the_max_memory_flag_applies_to_the_solver_working_memory(capsys, tmp_path, method, flags):
    path = write_dense(tmp_path / "eye600.dat", np.eye(600), -np.ones(600))   # M: 2.9 MB; Lemke's work: 20.2 MB
    code, out, err = run(capsys, "lcp", "solve", str(path), "--max-memory", "16M", *flags)
    assert code == 2 and out == ""
    assert err.startswith(f"pcsuite: error: solve_lcp (method {method}): k = 600 (7 work arrays of k x k doubles) "
                          "needs about 19.2 MiB, above the memory limit of 16 MiB")


def test_dev_zero_is_refused_at_once(capsys):
    with peak_memory() as peak:
        code, out, err = run(capsys, "lcp", "solve", "/dev/zero")
    assert peak() < 1 << 20                      # refused by its kind, before reading: nothing read into memory
    assert (code, out) == (2, "")
    assert err == "pcsuite: error: FILE must be a regular file; got '/dev/zero', a character device\n"


def test_no_fast_paths_runs_the_method_itself(capsys, tmp_path):
    path = write_dense(tmp_path / "lcp_murty6.dat", *murty_exponential(6))
    code, out, _ = run(capsys, "lcp", "solve", str(path), "--method", "murty", "--json")
    fast = json.loads(out)
    assert code == 0 and fast["iterations"] == 0 and fast["message"] == "closed form (triangular)"
    code, out, _ = run(capsys, "lcp", "solve", str(path), "--method", "murty", "--no-fast-paths", "--json")
    pivoted = json.loads(out)
    assert code == 0 and pivoted["iterations"] == 2**6 - 1 and pivoted["z"] == fast["z"] == [0, 0, 0, 0, 0, 1]


def _hold(seconds: float, compiling: bool):
    """engine.sizes after ``seconds`` of set-up: inside numba's compiler lock (as a kernel's first compile) or not."""
    from converters.lcp import engine
    sizes = engine.sizes

    def slow(method, k):
        if compiling:
            from numba.core.compiler_lock import global_compiler_lock
            with global_compiler_lock:
                time.sleep(seconds)
        else:
            time.sleep(seconds)
        return sizes(method, k)
    return slow


@pytest.mark.parametrize("compiling", [True, False], ids=["compiling", "working"])
def test_a_compile_inside_a_one_run_command_does_not_count_against_its_time_limit(capsys, tmp_path, monkeypatch,
                                                                                  compiling):
    """--time-limit 0.1 arms an alarm at 0.605 s: 1 s in numba's compiler (a first solve on a cold cache) puts it off
    by that second and the solve answers; 1 s of the run's own work still ends it there, in one line."""
    from converters.lcp import engine
    monkeypatch.setattr(engine, "sizes", _hold(1.0, compiling))
    path = write_dense(tmp_path / "pair.dat", np.array([[2.0, 1.0], [1.0, 2.0]]), np.array([-3.0, -3.0]))
    code, out, err = run(capsys, "lcp", "solve", str(path), "--method", "enum", "--no-fast-paths", "--time-limit",
                         "0.1", "--json")
    if compiling:
        assert code == 0 and err == "" and json.loads(out)["status"] == "solved", err
    else:
        assert code == 2 and err == ("pcsuite: error: the run did not finish within the time limit of 0.1 s "
                                     "(--time-limit); raise it, or ask for a shorter run (--t-end, --periods) or a "
                                     "coarser one\n"), err
