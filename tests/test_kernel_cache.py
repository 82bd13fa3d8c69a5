"""converters.kernel_cache: numba's cache of every compiled module goes when any kernel source changes (a caller
keeps an old copy of a callee or a constant otherwise: numba issue 6845), and the list covers every module
with compiled code."""
import re
from pathlib import Path

from converters import kernel_cache

PACKAGE = Path(kernel_cache.__file__).parent


def test_the_list_holds_every_module_with_compiled_code():
    """Every module that defines a numba function, and every module whose plain function another compiles with
    njit(...)(name) (numba caches it beside its own module)."""
    compiled = set()
    for path in PACKAGE.rglob("*.py"):
        text = path.read_text()
        if re.search(r"^\s*@njit", text, re.M):
            compiled.add(path.relative_to(PACKAGE).as_posix())
        for name in re.findall(r"= njit\([^)]*\)\((\w+)\)", text):
            source = re.search(rf"^from (\.+)([\w.]*) import .*\b{name}\b", text, re.M)
            assert source, f"{path}: where does {name} come from?"
            base = path.parent
            for _ in range(len(source.group(1)) - 1):
                base = base.parent
            compiled.add((base / (source.group(2).replace(".", "/") + ".py")).relative_to(PACKAGE).as_posix())
    assert "analysis/periodic.py" in compiled                     # spectral_radius, compiled by sweeps/batch.py
    assert compiled == set(kernel_cache.COMPILED)


def test_a_changed_source_clears_the_compiled_caches_that_may_hold_an_old_copy_of_it(tmp_path):
    for name in kernel_cache.SOURCES:
        (tmp_path / name).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / name).write_text(f"# {name}\n")
    lcp, methods = tmp_path / "lcp" / "__pycache__", tmp_path / "methods" / "__pycache__"
    lcp.mkdir()
    methods.mkdir()
    files = [lcp / "lemke.run-40.py311.nbi", lcp / "lemke.run-40.py311.nbc", lcp / "engine.solve_once-9.py311.nbc",
             lcp / "kernels.solve_augmented-14.py311.nbi", methods / "theta_kernels.run_steps-108.py311.3.nbc",
             lcp / "other.py311.pyc", methods / "theta.cpython-311.pyc"]
    for path in files:
        path.write_text("x")
    assert kernel_cache.refresh(tmp_path)                                  # no stamp yet: cleared
    assert [p.exists() for p in files] == [False] * 5 + [True, True]      # numba's files only
    files[0].write_text("x")
    assert not kernel_cache.refresh(tmp_path) and files[0].exists()        # unchanged sources: kept
    (tmp_path / "lcp" / "kernels.py").write_text("# kernels, changed\n")   # a callee changed: its callers' copies go
    files[4].write_text("x")
    assert kernel_cache.refresh(tmp_path) and not files[0].exists() and not files[4].exists()
    files[4].write_text("x")
    (tmp_path / "compiled.py").write_text("MAX_INLINE_K = 9\n")            # a constant the kernels read
    assert kernel_cache.refresh(tmp_path) and not files[4].exists()


def test_the_caches_in_numba_cache_dir_go_too(tmp_path, monkeypatch):
    import hashlib
    root, user = tmp_path / "src", tmp_path / "numba-cache"
    for name in kernel_cache.SOURCES:
        (root / name).parent.mkdir(parents=True, exist_ok=True)
        (root / name).write_text(f"# {name}\n")
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(user))
    lcp = str((root / "lcp").resolve())
    where = user / f"lcp_{hashlib.sha1(lcp.encode()).hexdigest()}"     # numba.core.caching's naming
    where.mkdir(parents=True)
    (where / "lemke.run-40.py311.nbi").write_text("x")
    assert kernel_cache.refresh(root) and not (where / "lemke.run-40.py311.nbi").exists()
