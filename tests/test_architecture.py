"""The architecture holds: no import cycle (modules or packages, function-local imports included),
validation never branches on a model's name, and one periodic-orbit engine serves every caller."""
import ast
import re
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("converters", "netlists", "validation")
MODEL_NAMES = ("buck", "boost", "buck-boost", "cuk", "prc")


def _module_name(path: Path) -> str:
    parts = path.relative_to(ROOT).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _modules() -> dict[str, Path]:
    return {_module_name(p): p for pkg in PACKAGES for p in (ROOT / pkg).rglob("*.py")}


def _typing_only(tree: ast.AST) -> set[int]:
    """The ids of the import nodes under ``if TYPE_CHECKING:`` (never executed: what a type checker reads)."""
    guarded = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            guarded |= {id(n) for stmt in node.body for n in ast.walk(stmt)}
    return guarded


def _imports(name: str, path: Path, modules: dict, typing: bool = True) -> set[str]:
    """Every project module ``name`` imports, anywhere in the file (function-local imports too); ``typing``: also
    those under ``if TYPE_CHECKING:`` (what a module knows of, as the packages' layering counts it; the runtime's
    import cycles do not include them)."""
    is_package = path.name == "__init__.py"
    package = name if is_package else name.rpartition(".")[0]
    out = set()
    tree = ast.parse(path.read_text())
    skip = set() if typing else _typing_only(tree)
    for node in ast.walk(tree):
        if id(node) in skip:
            continue
        if isinstance(node, ast.Import):
            targets = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                parts = package.split(".")
                parts = parts[:len(parts) - (node.level - 1)]
                base = ".".join(parts + ([base] if base else []))
            # `from pkg import mod` imports the module pkg.mod when there is one, else names from pkg
            targets = [f"{base}.{a.name}" if f"{base}.{a.name}" in modules else base for a in node.names]
        else:
            continue
        for target in targets:
            while target and target not in modules:
                target = target.rpartition(".")[0]
            if target and target != name:
                out.add(target)
    return out


def _cycle(graph: dict) -> list | None:
    """A cycle of the directed graph, or None (iterative depth-first search)."""
    colour = {node: 0 for node in graph}
    for root in graph:
        if colour[root]:
            continue
        stack = [(root, iter(sorted(graph[root])))]
        path = [root]
        colour[root] = 1
        while stack:
            node, children = stack[-1]
            child = next(children, None)
            if child is None:
                colour[node] = 2
                stack.pop()
                path.pop()
            elif colour.get(child, 2) == 1:
                return path[path.index(child):] + [child]
            elif colour.get(child) == 0:
                colour[child] = 1
                stack.append((child, iter(sorted(graph[child]))))
                path.append(child)
    return None


def test_no_import_cycle_between_modules():
    """Runtime imports, a package's __init__ included: a module that imports its own package's __init__ (even inside
    a function) while the __init__ imports it is a cycle (the edge had been dropped, and hid one)."""
    modules = _modules()
    graph = {name: _imports(name, path, modules, typing=False) for name, path in modules.items()}
    assert _cycle(graph) is None, f"import cycle: {' -> '.join(_cycle(graph))}"


def _package(tmp_path: Path, files: dict[str, str]) -> dict[str, Path]:
    """A package ``converters`` of ``files`` (module name -> source; "" is its __init__) written under tmp_path."""
    package = tmp_path / "converters"
    package.mkdir()
    modules = {}
    for name, text in files.items():
        path = package / f"{name or '__init__'}.py"
        path.write_text(text)
        modules["converters" + (f".{name}" if name else "")] = path
    return modules


def test_an_import_of_the_packages_own_init_is_an_edge_and_a_typing_import_is_not_a_runtime_one(tmp_path):
    modules = _package(tmp_path, {
        "": "from .control import Control\nREGISTRY = {}\n",
        "control": "class Control:\n    def on(self):\n        from . import REGISTRY\n",
        "typed": "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from . import control\n"})
    graph = {name: _imports(name, path, modules, typing=False) for name, path in modules.items()}
    assert _cycle(graph) == ["converters", "converters.control", "converters"] and graph["converters.typed"] == set()
    assert _imports("converters.typed", modules["converters.typed"], modules) == {"converters.control"}


def test_the_cycle_finder_finds_a_function_local_cycle(tmp_path):
    """The old event -> periodic -> stepping -> event cycle, through a function-local import, is caught."""
    assert _cycle({"a": {"b"}, "b": {"c"}, "c": {"a"}}) == ["a", "b", "c", "a"]
    assert _cycle({"a": {"b"}, "b": set(), "c": {"a"}}) is None
    modules = _package(tmp_path, {"": "", "event": "from .periodic import shoot\n",
                                  "periodic": "def shoot():\n    from .event import run\n"})
    graph = {name: _imports(name, path, modules) for name, path in modules.items()}
    assert _cycle(graph) == ["converters.event", "converters.periodic", "converters.event"]


def test_no_import_cycle_between_packages():
    """converters.{lcp, problems, methods, analysis, models, ...}, netlists, validation: a strict layering."""
    modules = _modules()

    def package(name):
        parts = name.split(".")
        return ".".join(parts[:2]) if parts[0] == "converters" and len(parts) > 2 else (
            name if parts[0] == "converters" else parts[0])
    graph: dict[str, set] = {}
    for name, path in modules.items():
        source = package(name)
        graph.setdefault(source, set())
        for target in _imports(name, path, modules):
            if package(target) != source:
                graph[source].add(package(target))
                graph.setdefault(package(target), set())
    assert _cycle(graph) is None, f"package cycle: {' -> '.join(_cycle(graph))}"
    assert "converters.analysis" not in graph["converters.methods"]      # methods know nothing of orbits
    assert not any(p.startswith("converters.models") for p in graph["converters.methods"])
    below_validation = [p for p in graph if p.startswith("converters") or p == "netlists"]
    assert not [p for p in below_validation if "validation" in graph[p]]
    assert not [p for p in graph if p.startswith("converters") and "netlists" in graph[p]]


_NAMES = "|".join(re.escape(n) for n in MODEL_NAMES)
_BRANCH = re.compile(rf"""(==|!=)\s*["']({_NAMES})["']|["']({_NAMES})["']\s*(==|!=)|"""
                     rf"""\bin\s*[(\[{{]\s*["']({_NAMES})["']|\.name\s*(==|!=|in\b)""")


def _lines_matching(pattern, packages, skip=()) -> list[str]:
    """path:line: text of every code line (comments cut) of ``packages`` that ``pattern`` finds."""
    hits = []
    for pkg in packages:
        for path in (ROOT / pkg).rglob("*.py"):
            if path.relative_to(ROOT).as_posix() in skip:
                continue
            for number, line in enumerate(path.read_text().splitlines(), 1):
                if pattern.search(line.split("#")[0]):
                    hits.append(f"{path.relative_to(ROOT)}:{number}: {line.strip()}")
    return hits


def test_validation_never_branches_on_a_model_name():
    assert _lines_matching(_BRANCH, ["validation"]) == []


def test_the_branch_pattern_does_catch_a_branch():
    assert _BRANCH.search('if conv.name == "prc":') and _BRANCH.search("fraction = 0.5 if name == 'prc' else D")
    assert not _BRANCH.search('get_model("boost", "smc")')


def test_one_periodic_orbit_engine_serves_the_stepper_the_event_method_gdcm_and_the_report(monkeypatch):
    from converters.analysis import periodic
    calls = []
    original = periodic.newton_orbit

    def counting(period_map, *args, **kwargs):
        calls.append(type(period_map).__name__)
        return original(period_map, *args, **kwargs)
    monkeypatch.setattr(periodic, "newton_orbit", counting)
    from converters.run import run_converter
    from validation import gdcm, tradeoff
    run_converter("buck", {}, steady=True)                                   # the stepper (simulate --steady)
    run_converter("buck", {}, method="event", steady=True)                  # the event method
    gdcm._lcp_point({"converter": "cuk", "D": 0.4, "R": 10.0})            # GDCM maps and pcsuite gdcm
    tradeoff.reference(tradeoff.CASES[1], periods=2)                         # the report's exact references
    assert calls == ["StepPlanMap", "EventPeriodMap", "StepPlanMap", "StepPlanMap", "EventPeriodMap"]


#: The loops that evaluate a map and solve a linear system with its Jacobian (a Newton iteration, found by its
#: structure: :func:`_newton_loops`), each with why it is one. The engine is the first two; the continuation's are
#: Newton on an extended system in (x, p) with a bordering row (a pseudo-arclength or a test-function condition),
#: whose Jacobian is not J - I and whose stopping rule cannot be the engine's (its distance to the orbit estimated
#: from the multipliers): they call the period map through the family and keep their own loop.
NEWTON_LOOPS = {
    "converters/analysis/periodic.py:newton_orbit": "the engine: the compiled driver over any method's period map",
    "converters/sweeps/batch.py:_batch_steady": "the engine: the same compiled driver over the batched stepper",
    "converters/analysis/continuation/corrector.py:_correct": "pseudo-arclength: [F(x, p); t . (z - z_pred)] = 0",
    "converters/analysis/continuation/condition.py:locate_condition": "bordered: [P(x, p) - x; c(p, x)] = 0",
}
_SOLVES = {"solve", "lstsq", "lu_solve", "solve_triangular", "inv", "newton_step", "newton_advance"}


def _callee(call: ast.Call) -> str:
    f = call.func
    return f.attr if isinstance(f, ast.Attribute) else f.id if isinstance(f, ast.Name) else ""


def _newton_loops(tree: ast.AST) -> list[str]:
    """The functions of ``tree`` with a loop that both evaluates a map (a call of something named a map, a
    residual, a map's ``end`` or ``period_run``, or of a name bound to one) and solves a linear system (numpy's or
    scipy's solvers, or the compiled Newton driver, by name or through ``kernel("newton_...")``)."""
    found = []
    for fn in ast.walk(tree):
        if not isinstance(fn, (ast.FunctionDef, ast.AsyncFunctionDef)):
            continue
        solvers, maps = set(_SOLVES), {a.arg for a in fn.args.args + fn.args.kwonlyargs if "map" in a.arg}
        for node in ast.walk(fn):
            if isinstance(node, ast.Assign) and isinstance(node.value, ast.Call):
                callee = _callee(node.value)
                constants = [str(a.value) for a in node.value.args if isinstance(a, ast.Constant)]
                names = {t.id for t in node.targets if isinstance(t, ast.Name)}
                if callee == "kernel" and any(c.startswith("newton") for c in constants):
                    solvers |= names
                elif "map" in callee.lower() and callee != "map":
                    maps |= names
        for loop in (n for n in ast.walk(fn) if isinstance(n, (ast.For, ast.While))):
            callees = {_callee(c) for c in ast.walk(loop) if isinstance(c, ast.Call)}
            evaluates = {c for c in callees if c in maps or ("map" in c.lower() and c != "map")
                         or c in ("residual", "end", "period_run")}
            if callees & solvers and evaluates:
                found.append(fn.name)
                break
    return found


def test_no_module_runs_a_newton_iteration_of_its_own_beyond_the_engine_and_the_continuations_extended_ones():
    """By structure, not by a function's name (a `def newton...` pattern had missed the continuation's loops)."""
    found = {f"{path.relative_to(ROOT).as_posix()}:{name}" for path in ROOT.joinpath("converters").rglob("*.py")
             for name in _newton_loops(ast.parse(path.read_text()))}
    assert found == set(NEWTON_LOOPS)


def test_the_structural_check_finds_a_newton_loop_whatever_its_names():
    disguised = """
def settle(problem, method, x):
    stroboscope = method.period_map(problem)
    for _ in range(9):
        y, jac = stroboscope(x)
        x = x + np.linalg.solve(jac - np.eye(x.size), y - x)
    return x

def iterate(pm, x):
    while True:
        x = pm.end(x)

def driven(f, x):
    go = kernel("newton_advance")
    while go(x, f.residual(x)):
        pass
"""
    assert _newton_loops(ast.parse(disguised)) == ["settle", "driven"]


_KEYS = "lcp|event|smooth|moreau|spice"
_METHOD_BRANCH = re.compile(rf"""\b(method|key|kind)\b\s*(==|!=)\s*["']({_KEYS})["']|["']({_KEYS})["']\s*(==|!=)\s*\S*"""
                            rf"""\b(method|key|kind)\b|\b(method|key|kind)\b\s*(not\s+)?in\s*[(\[{{]\s*["']({_KEYS})["']""")


def test_nothing_branches_on_a_method_key_outside_the_registry():
    """What a method can do, and how its error is estimated, are declared by the method (error_kind, batches,
    domains, step_option, counts); nobody asks which one it is (the review found run.py, accuracy.py, the CLI and
    the sweeps asking)."""
    assert _lines_matching(_METHOD_BRANCH, PACKAGES, skip=("converters/methods/base.py",)) == []


_CONTROLS = "pwm|smc|smc-implicit|voltage-mode|peak-current|valley-current|current-loop|voltage-loop|circuit"
_CONTROL_BRANCH = re.compile(rf"""\bcontrol\b\s*(==|!=)\s*["']({_CONTROLS})["']|["']({_CONTROLS})["']\s*(==|!=)|"""
                             rf"""\bcontrol\b\s*(not\s+)?in\s*[(\[{{]\s*["']({_CONTROLS})["']""")


def test_nothing_branches_on_a_control_name():
    """What a control does lives in the tables keyed by it (the models' registry, the netlist writers, the
    comparisons, the scene kinds' runners and rules), looked up once; no module asks which control it has."""
    assert _lines_matching(_CONTROL_BRANCH, PACKAGES) == []


_PAIR_KEY = re.compile(r"""\(\s*["'](buck|boost|buck-boost|cuk|prc)["']\s*,\s*["']({_CONTROLS})["']\s*\)\s*:"""
                       .replace("{_CONTROLS}", _CONTROLS))


def test_controls_compose_with_converters_instead_of_a_model_per_pair():
    """A control closes its loop around any converter it names (converters.models.control); no module keys a model
    by a (converter, control) pair written out (the registry had ("boost", "smc"): BoostSMC(...), a model class per
    pair that re-derived its converter's circuit)."""
    assert _lines_matching(_PAIR_KEY, PACKAGES) == []
    assert _PAIR_KEY.search('("boost", "smc"): BoostSMC(implicit=False),')
    assert not _PAIR_KEY.search('get_model("boost", "smc")')


def test_the_control_branch_pattern_does_catch_a_branch():
    assert _CONTROL_BRANCH.search('if model.control == "smc":') and _CONTROL_BRANCH.search("elif args.control != 'pwm':")
    assert _CONTROL_BRANCH.search('if scene.control in ("smc", "circuit"):')
    assert not _CONTROL_BRANCH.search('get_model("boost", "smc")')


def test_the_method_branch_pattern_does_catch_a_branch():
    assert _METHOD_BRANCH.search('if method.key == "lcp":') and _METHOD_BRANCH.search("if args.method != 'spice':")
    assert _METHOD_BRANCH.search('if method in ("lcp", None):') and _METHOD_BRANCH.search('"event" == tr.method')
    assert not _METHOD_BRANCH.search('run_converter("buck", method="event")')


def test_one_newton_driver_serves_the_serial_engine_and_the_batched_steady_states():
    """Newton's iteration, its halving and its stopping rule are one compiled driver (newton_kernel.newton_advance,
    which alone calls newton_step); the serial engine and the batched sweeps only answer its requests."""
    def users(pattern):
        return sorted(p.relative_to(ROOT).as_posix() for p in ROOT.joinpath("converters").rglob("*.py")
                      if p.name not in ("compiled.py", "build_kernels.py") and re.search(pattern, p.read_text()))
    assert users(r"(?<!def )newton_step\(") == ["converters/analysis/newton_kernel.py"]
    assert users(r"newton_advance") == ["converters/analysis/newton_kernel.py", "converters/analysis/periodic.py",
                                        "converters/sweeps/batch.py"]


@pytest.mark.parametrize("name", MODEL_NAMES)
def test_every_model_declares_its_signals_and_modes(name):
    from converters.models import get_converter
    model = get_converter(name)
    assert set(model.signal_names) >= {"vout", "switch"}
    assert model.off_held_label in model.mode_labels or model.off_held_label == "GDCM-OFF"
    p = model.resolve({})
    assert np.asarray(model.pair_currents).shape == (len(model.configurations(p)), len(model.pair_names))


def test_the_mechanical_module_reuses_the_core():
    """No second integrator and no second shooting code: the models build problems, validation reads runs;
    only the methods integrate (solve_ivp in the smoothing and the mechanical event machine), and only the one
    orbit engine solves for fixed points."""
    mechanical = [*ROOT.joinpath("converters", "models", "mechanics").rglob("*.py"),
                  *ROOT.joinpath("converters", "analysis", "mechanics").rglob("*.py"), ROOT / "validation" / "mechanics.py", ROOT / "validation" / "mechanics_plots.py",
                  ROOT / "validation" / "cli" / "mech.py"]
    pattern = re.compile(r"solve_ivp|odeint|def \w*(newton|shoot|fixed_point|integrate|step)\w*\(|linalg\.solve\(")
    assert not [p.name for p in mechanical if pattern.search(p.read_text())]
    integrators = [p.relative_to(ROOT).as_posix() for p in ROOT.joinpath("converters").rglob("*.py")
                   if "solve_ivp(" in p.read_text()]
    assert sorted(integrators) == ["converters/methods/event/mechanical.py", "converters/methods/smoothing.py"]


def test_one_event_core_with_one_engine_per_problem_type():
    """The event method's engines (LCS: exact flows; mechanical: DOP853 between events) return the core's piecewise
    solution and serve the core's period map; no other module runs an event loop (a class with a ``run(self, x0``
    that records segments)."""
    from converters.methods import EventDriven
    from converters.methods.event import ENGINES
    from converters.methods.event.core import EnginePeriodMap, PiecewiseSolution
    from converters.models import get_converter
    from converters.models.mechanics import get_mechanical
    from converters.simulate import simulate
    buck = get_converter("buck")
    p = buck.resolve({})
    friction = get_mechanical("friction")
    q = friction.resolve({})
    for problem in (buck.problem(p, 2 * buck.period(p)), friction.problem(q, friction.period(q))):
        tr = simulate(problem, EventDriven())
        machine = EventDriven().period_map(problem).machine
        assert isinstance(EventDriven().period_map(problem), EnginePeriodMap)
        assert isinstance(machine.run(problem.x0)[0], PiecewiseSolution) and tr.events is not None
    assert [engine.__name__.rsplit(".", 1)[1] for _, engine in ENGINES] == ["mechanical", "machine"]
    loops = sorted(path.relative_to(ROOT).as_posix() for path in ROOT.joinpath("converters").rglob("*.py")
                   if re.search(r"def run\(self, x0", path.read_text()) and "segments" in path.read_text())
    assert loops == ["converters/methods/event/machine.py", "converters/methods/event/mechanical.py"]


def test_every_process_pool_is_the_parallel_backends():
    """One way to run work in other processes: converters.parallel (the D-K maps, diagrams, suites, stability
    map, ngspice runner and sweeps all go through it); nobody else builds a pool or forks."""
    pattern = re.compile(r"ProcessPoolExecutor|multiprocessing\.(Pool|Process|get_context)|os\.fork\(")
    users = sorted(path.relative_to(ROOT).as_posix() for path in _modules().values() if pattern.search(path.read_text()))
    assert users == ["converters/parallel/local.py"]
    assert pattern.search("pool = futures.ProcessPoolExecutor(max_workers=1)")


def _private_imports(modules: dict) -> list[str]:
    """``from X import _name`` where X is a module of another package than the importer's (a private name reached
    across packages: what it names may change without notice)."""
    found = []
    for name, path in modules.items():
        package = name if path.name == "__init__.py" else name.rpartition(".")[0]
        for node in ast.walk(ast.parse(path.read_text())):
            if not isinstance(node, ast.ImportFrom):
                continue
            base = node.module or ""
            if node.level:
                parts = package.split(".")
                parts = parts[:len(parts) - (node.level - 1)]
                base = ".".join(parts + ([base] if base else []))
            if base not in modules:
                continue
            owner = base if modules[base].name == "__init__.py" else base.rpartition(".")[0]
            for alias in node.names:
                if alias.name.startswith("_") and not alias.name.startswith("__") and owner != package:
                    found.append(f"{name} imports {base}.{alias.name}")
    return found


def test_no_private_name_is_imported_across_packages():
    assert _private_imports(_modules()) == []


def test_the_private_import_finder_finds_one(tmp_path):
    (tmp_path / "a").mkdir()
    (tmp_path / "a" / "__init__.py").write_text("")
    (tmp_path / "a" / "inner.py").write_text("def _helper(): pass\n")
    (tmp_path / "b").mkdir()
    (tmp_path / "b" / "__init__.py").write_text("")
    (tmp_path / "b" / "user.py").write_text("from ..a.inner import _helper\n")
    (tmp_path / "a" / "sibling.py").write_text("from .inner import _helper\n")     # the same package: allowed
    modules = {"a": tmp_path / "a" / "__init__.py", "a.inner": tmp_path / "a" / "inner.py",
               "a.sibling": tmp_path / "a" / "sibling.py", "b": tmp_path / "b" / "__init__.py",
               "b.user": tmp_path / "b" / "user.py"}
    assert _private_imports(modules) == ["b.user imports a.inner._helper"]
