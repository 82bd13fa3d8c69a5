"""The compiled kernels' two sources (converters.compiled): the ahead-of-time module built by ``make setup`` is
current and used, gives the very numbers numba's JIT gives, is refused once a kernel source changes, and a
plain ``pcsuite simulate`` then starts without numba, scipy or pandas."""
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from converters import compiled

ROOT = Path(__file__).resolve().parents[2]


def _run(code: str, **env) -> str:
    environment = {key: value for key, value in os.environ.items() if key != "PCSUITE_KERNELS"}
    environment.update(env)
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, env=environment,
                          timeout=300)
    assert done.returncode == 0, done.stderr
    return done.stdout


def test_the_ahead_of_time_module_is_current_and_used():
    """make setup builds it (python -m converters.build_kernels); a fresh process loads it."""
    assert compiled.stale() == "", f"{compiled.stale()}: run make setup"
    assert _run("from converters import compiled; print(compiled.source())").strip() == "ahead-of-time"
    assert _run("from converters import compiled; print(compiled.source())",
                PCSUITE_KERNELS="jit").strip() == "jit: PCSUITE_KERNELS=jit"
    warned = subprocess.run([sys.executable, "-c", "from converters import compiled; print(compiled.source())"],
                            capture_output=True, text=True, cwd=ROOT, env={**os.environ, "PCSUITE_KERNELS": "fast"})
    assert warned.stdout.strip() == "ahead-of-time"
    assert "PCSUITE_KERNELS must be one of auto, jit; got 'fast'; using auto" in warned.stderr


SUMMARY = """
import json, sys
from converters.run import run_converter, run_summary
out = {}
for name, params, steady in %s:
    tr = run_converter(name, params, method="lcp", periods=30, steady=steady)
    s = run_summary(tr)
    s.pop("wall_s")
    out[f"{name} {params} {steady}"] = [s, tr.x.tolist(), tr.u.tolist()]
print(json.dumps(out, default=float))
"""
#: one pair with n = 2 and 4 (the register loops; with Ron or Rd, D != 0 and the consistent start is an LCP),
#: the PRC's bridge (n = 4, k = 4: the general inline loop), and steady states (the exact Jacobian and the
#: Newton step)
CASES = [("buck", {}, False), ("buck", {"D": 0.7, "R": 2.0}, True), ("boost", {"Ron": 0.05}, False),
         ("cuk", {}, False), ("prc", {}, True), ("buck-boost", {"Vf": 0.7, "Rd": 0.05}, True)]


@pytest.mark.slow
def test_ahead_of_time_and_jit_kernels_give_identical_numbers():
    code = SUMMARY % repr(CASES)
    aot = json.loads(_run(code))
    jit = json.loads(_run(code, PCSUITE_KERNELS="jit"))
    assert aot.keys() == jit.keys()
    for key in aot:
        assert aot[key] == jit[key], key                    # bit for bit: the same LLVM code from one source


def test_a_module_built_from_other_sources_is_refused(tmp_path, monkeypatch):
    record = json.loads(compiled.RECORD.read_text())
    source = next(iter(record["sources"]))
    record["stats"][source] = [0, 0]                          # touched since the build (size and time differ) ...
    (tmp_path / "record.json").write_text(json.dumps(record))
    monkeypatch.setattr(compiled, "RECORD", tmp_path / "record.json")
    assert compiled.stale() == ""                              # ... with the same content: still current
    record["sources"][source] = "0" * 64                      # as if that kernel were edited since the build
    (tmp_path / "record.json").write_text(json.dumps(record))
    monkeypatch.setattr(compiled, "RECORD", tmp_path / "record.json")
    monkeypatch.setattr(compiled, "_loaded", {})
    monkeypatch.setattr(compiled, "_decided", [])          # as a new process decides
    assert compiled.stale() == f"{source} changed since the ahead-of-time build"
    from converters.methods import theta_kernels
    assert compiled.kernel("run_steps") is theta_kernels.run_steps            # numba's dispatcher instead
    assert compiled.source().startswith("jit: ")
    record["python"] = "cpython-299"
    (tmp_path / "record.json").write_text(json.dumps(record))
    assert "built for cpython-299" in compiled.stale()
    record["python"], record["numpy"] = sys.implementation.cache_tag, "1.0.0"
    (tmp_path / "record.json").write_text(json.dumps(record))
    assert compiled.stale() == f"the ahead-of-time module was built against numpy 1.0.0, not {np.__version__}"
    (tmp_path / "record.json").unlink()
    assert "not built" in compiled.stale()


def test_a_plain_simulate_imports_neither_numba_scipy_pandas_nor_matplotlib():
    code = ("import sys, io, contextlib\nfrom validation.cli import main\nbuf = io.StringIO()\n"
            "with contextlib.redirect_stdout(buf):\n"
            "    code = main(['simulate', 'buck', '--h', '5e-8', '--t-end', '5e-3', '--json'])\n"
            "summary = __import__('json').loads(buf.getvalue())\n"
            "print(code, summary['steps'], sorted(m for m in ('numba', 'scipy', 'pandas', 'matplotlib', 'llvmlite') "
            "if m in sys.modules))")
    assert _run(code).strip().split(maxsplit=2) == ["0", "100000", "[]"]


def test_run_steps_serves_every_register_size_and_the_rows():
    """The ahead-of-time run_steps picks its export by the state's size (1..6 in registers, None: in x)."""
    from converters.methods.theta_kernels import run_steps as jit_run_steps
    run_steps = compiled.kernel("run_steps")
    rng = np.random.default_rng(3)
    for n in (1, 2, 3, 5, 6, 7, 9):
        sets, N = 2, 400
        Phi = 0.45 * rng.standard_normal((sets, n, n)) / np.sqrt(n)
        Gamma, H = rng.standard_normal((sets, n)), rng.standard_normal((sets, n, 1))
        C, F = rng.standard_normal((sets, 1, n)), np.array([[5.0], [-5.0]])     # set 0 frees, set 1 holds
        M = np.full((sets, 1, 1), 2.0)
        from converters.methods.discretize import StepMatrices
        from converters.methods.theta_kernels import branch_maps
        Phi_b, Gamma_b, CPhi, q0 = np.empty((sets, 2, n, n)), np.empty((sets, 2, n)), np.empty((sets, 1, n)), \
            np.empty((sets, 1))
        branch_maps(Phi, Gamma, H, C, F, M, Phi_b, Gamma_b, CPhi, q0)
        m = StepMatrices(Phi, Gamma, H, C, F, M, Phi_b, Gamma_b, CPhi, q0)
        which = (np.arange(N - 1) % 2).astype(np.int32)
        results = []
        for function in (run_steps, jit_run_steps):
            x, u, y = np.zeros((N, n)), np.zeros((N, 1)), np.zeros((N, 1))
            x[0] = rng.standard_normal(n) if not results else results[0][0][0]
            status = function(which, m.Phi, m.Gamma, m.H, m.C, m.F, m.M, m.Phi_b, m.Gamma_b, m.CPhi, m.q0, x, u, y,
                              0, True, 0, compiled.register_state(n))
            results.append((x, u, y, tuple(status)))
        assert results[0][3] == results[1][3] == (compiled.OK, N - 1)
        assert 0 < (results[0][1] > 0).sum() < N - 1, n      # both branches taken
        for a, b in zip(results[0][:3], results[1][:3]):
            assert np.array_equal(a, b), n


def test_arguments_of_another_kind_go_to_the_jit_never_read_wrongly():
    """numba.pycc's wrappers check only that an array is an ndarray: a strided, Fortran-order or int64 argument
    would be read wrongly (or crash); compiled.kernel checks every argument and hands those to numba's JIT."""
    from converters.analysis.newton_kernel import newton_step as jit
    aot = compiled.kernel("newton_step")
    x, px = np.array([1.0, 2.0]), np.array([1.1, 2.1])
    jac = np.array([[0.5, 0.1], [0.0, 0.3]])
    kinds = [(np.array([1.0, 0.0, 2.0, 0.0])[::2], px, jac),          # strided
             (x, px, np.asfortranarray(jac)),                         # Fortran order
             (np.array([1, 2]), px, jac)]                             # int64
    for a, b, c in kinds:
        expected_step, step = np.empty(2), np.empty(2)
        expected = jit(np.ascontiguousarray(a, dtype=float), b, np.ascontiguousarray(c), 0.5, expected_step,
                       np.empty((2, 3)), 1e-10, 0, 50)
        assert aot(a, b, c, 0.5, step, np.empty((2, 3)), 1e-10, 0, 50) == expected
        assert np.array_equal(step, expected_step)
    assert not compiled.conforms(["f8:1", "i8"], (np.zeros(2), True))      # a bool is not an int here
    assert not compiled.conforms(["f8:1"], (np.zeros(2, dtype=np.float32),))
    assert compiled.conforms(["f8:2", "f8", "b1"], (np.zeros((2, 2)), 1.0, False))


def test_a_problem_built_from_fortran_order_matrices_gives_the_same_numbers():
    from dataclasses import replace

    from converters.methods import BackwardEuler
    from converters.models import get_model
    from converters.problems import Configuration
    from converters.simulate import simulate
    model = get_model("buck")
    p = model.resolve({})
    T = model.period(p)
    problem = model.problem(p, 20 * T)
    transposed = tuple(Configuration(A=np.asfortranarray(c.A), B=np.asfortranarray(c.B), C=np.asfortranarray(c.C),
                                     D=np.asfortranarray(c.D), E=c.E, F=c.F, name=c.name)
                       for c in problem.configurations)
    fortran = replace(problem, configurations=transposed)
    assert np.array_equal(simulate(problem, BackwardEuler(T / 200)).x, simulate(fortran, BackwardEuler(T / 200)).x)


def test_an_edit_outside_the_kernel_sources_leaves_the_module_in_use_and_one_inside_makes_it_stale(tmp_path):
    """The module records the kernels' own sources only: a copy of the package with one line added to errors.py
    (which every command imports) still loads it in a fresh process; one line added to lcp/lemke.py makes the copy
    fall back to the JIT, naming the file."""
    import shutil
    assert compiled.stale() == "", f"{compiled.stale()}: run make setup"
    package = tmp_path / "converters"
    shutil.copytree(ROOT / "converters", package, ignore=shutil.ignore_patterns("__pycache__"))
    source = f"import sys; sys.path.insert(0, {str(tmp_path)!r}); from converters import compiled; print(compiled.source())"
    with open(package / "errors.py", "a") as errors:
        errors.write("# an unrelated edit\n")
    assert _run(source).strip() == "ahead-of-time"
    with open(package / "lcp" / "lemke.py", "a") as lemke:
        lemke.write("# an edit to a kernel\n")
    assert _run(source).strip() == "jit: lcp/lemke.py changed since the ahead-of-time build"
