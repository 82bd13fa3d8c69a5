"""The code says its types: annotations cover at least 90 % of the parameters and the returns in converters/, and
the typed core (the solution, the methods, the circuit compiler) passes mypy --strict."""
import ast
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
#: What mypy --strict checks (the solution every method returns, the methods, the compiler).
STRICT = ("converters/trajectory.py", "converters/methods", "converters/circuits")


def _coverage(tree: ast.AST) -> tuple[int, int, int, int]:
    """(annotated parameters, parameters, annotated returns, functions) of a module; self and cls are not counted,
    and an ``__init__`` returns None by definition."""
    pa = pt = ra = rt = 0
    for node in ast.walk(tree):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            args = node.args.posonlyargs + node.args.args + node.args.kwonlyargs
            args += [a for a in (node.args.vararg, node.args.kwarg) if a is not None]
            for i, arg in enumerate(args):
                if i == 0 and arg.arg in ("self", "cls"):
                    continue
                pt += 1
                pa += arg.annotation is not None
            rt += 1
            ra += node.returns is not None or node.name == "__init__"
    return pa, pt, ra, rt


def test_annotations_cover_ninety_percent_of_parameters_and_returns():
    totals = [0, 0, 0, 0]
    for path in ROOT.joinpath("converters").rglob("*.py"):
        for i, v in enumerate(_coverage(ast.parse(path.read_text()))):
            totals[i] += v
    pa, pt, ra, rt = totals
    assert pa / pt >= 0.9 and ra / rt >= 0.9, f"parameters {pa}/{pt}, returns {ra}/{rt}"


def test_the_coverage_counts_what_it_says():
    tree = ast.parse("class A:\n    def __init__(self, a: int, b):\n        pass\n"
                     "    def f(self, *args: int, **kw) -> None: ...\n@staticmethod\ndef g(cls, x) -> int: ...\n")
    # a, b, *args, **kw and x (a first argument named cls is not counted); returns: __init__, f, g
    assert _coverage(tree) == (2, 5, 3, 3)


@pytest.mark.slow
def test_the_typed_core_passes_mypy_strict():
    if shutil.which("mypy", path=str(Path(sys.executable).parent)) is None:
        pytest.fail("mypy is not installed: it is in the test extras (pip install -e '.[test]')")
    out = subprocess.run([sys.executable, "-m", "mypy", "--strict", "--ignore-missing-imports",
                          "--follow-imports=silent", *STRICT], cwd=ROOT, capture_output=True, text=True)
    assert out.returncode == 0, out.stdout[-3000:]
