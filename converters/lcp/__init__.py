"""Linear complementarity problem solvers: one algorithm per module, one entry point (:func:`solve_lcp`; many
small problems in one call: :func:`solve_lcp_many`).

The names below load on first use (PEP 562 ``__getattr__``): the solvers are compiled (numba), and a process
that imports this package without solving an LCP (``pcsuite simulate`` of a converter whose steps the compiled
loop solves inline) does not pay numba's import.
"""
import importlib
from typing import Any

from .state import METHOD_NAMES

#: Each public name and the module that defines it.
_WHERE = {"solve_lcp": "solve", "solve_lcp_many": "solve", "LCPBatch": "solve", "check_lcp": "solve", "SOLVERS": "engine", "LCPResult": "answer",
          "lcp_error": "result", "SOLVED": "answer", "NO_SOLUTION": "answer", "MAX_ITERATIONS": "answer",
          "FAILED": "answer", "STATUSES": "answer", "read_siconos_lcp": "siconos", "LCPFile": "siconos"}


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_WHERE))


def __getattr__(name: str) -> Any:
    if name not in _WHERE:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(f".{_WHERE[name]}", __name__), name)
    globals()[name] = value
    return value


__all__ = ["solve_lcp", "solve_lcp_many", "LCPBatch", "check_lcp", "LCPResult", "lcp_error", "read_siconos_lcp", "LCPFile", "SOLVERS",
           "SOLVED", "NO_SOLUTION", "MAX_ITERATIONS", "FAILED", "STATUSES", "METHOD_NAMES"]
