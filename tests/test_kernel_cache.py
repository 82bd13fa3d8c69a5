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
    assert "analysis/floquet.py" in compiled                      # spectral_radius, compiled by sweeps/batch.py
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


def _names_read(code) -> set:
    """The global and attribute names a function's code reads, its nested functions' too."""
    import types
    names = set(code.co_names)
    for const in code.co_consts:
        if isinstance(const, types.CodeType):
            names |= _names_read(const)
    return names


def _defined_in(module_name: str, name: str) -> str:
    """The module that defines ``name`` where ``module_name`` holds it: followed through ``from X import name``
    (a constant carries no trace of where it came from)."""
    import ast
    import importlib.util
    import sys
    module = sys.modules[module_name]
    for node in ast.walk(ast.parse(Path(module.__file__).read_text())):
        if isinstance(node, ast.ImportFrom):
            for alias in node.names:
                if (alias.asname or alias.name) == name:
                    base = (importlib.util.resolve_name("." * node.level + (node.module or ""), module.__package__)
                            if node.level else node.module)
                    if f"{base}.{alias.name}" in sys.modules:          # a submodule
                        return f"{base}.{alias.name}"
                    return _defined_in(base, alias.name) if base.split(".")[0] == "converters" else base
    return module_name


def _file_of(module_name: str) -> str:
    import sys
    return Path(sys.modules[module_name].__file__).resolve().relative_to(PACKAGE.resolve()).as_posix()


def test_every_name_a_compiled_function_reads_is_defined_in_a_listed_source():
    """numba compiles in what a kernel reads: the functions it calls and the values of the constants it names
    (an edit to any of them must clear the JIT's cache and make the ahead-of-time module stale, which records
    exactly kernel_cache.SOURCES). Walked from every compiled function of every listed module, through the
    functions they call and the modules they read attributes of."""
    import importlib
    import types

    from numba.core.dispatcher import Dispatcher
    todo = []
    for relative in kernel_cache.COMPILED:
        module = importlib.import_module("converters." + relative[:-3].replace("/", "."))
        todo += [value for value in vars(module).values() if isinstance(value, Dispatcher)]
    assert len(todo) > 50
    read, seen = set(), set()
    while todo:
        function = getattr(todo.pop(), "py_func", None)
        if function is None or function in seen or not function.__module__.startswith("converters"):
            continue
        seen.add(function)
        read.add(function.__module__)
        names = _names_read(function.__code__)
        for name in names & set(function.__globals__):
            value = function.__globals__[name]
            if isinstance(value, types.ModuleType):
                if value.__name__.startswith("converters"):
                    read.add(value.__name__)
                    todo += [getattr(value, attribute) for attribute in names if callable(getattr(value, attribute,
                                                                                                   None))]
            elif isinstance(value, Dispatcher) or isinstance(value, types.FunctionType):
                todo.append(value if isinstance(value, Dispatcher) else types.SimpleNamespace(py_func=value))
            elif not isinstance(value, type):
                read.add(_defined_in(function.__module__, name))
    files = {_file_of(name) for name in read if name.startswith("converters")}
    assert "lcp/state.py" in files and "compiled.py" in files and "methods/theta_kernels.py" in files
    assert files <= set(kernel_cache.SOURCES), sorted(files - set(kernel_cache.SOURCES))
