"""Linear complementarity problem solvers: one algorithm per module, one entry point."""
from . import cache

cache.refresh()   # before any compiled function loads its cache (see converters.lcp.cache)

from .result import FAILED, MAX_ITERATIONS, NO_SOLUTION, SOLVED, STATUSES, LCPResult, lcp_error  # noqa: E402
from .siconos import LCPFile, read_siconos_lcp  # noqa: E402
from .solve import SOLVERS, check_lcp, solve_lcp  # noqa: E402

__all__ = ["solve_lcp", "check_lcp", "LCPResult", "lcp_error", "read_siconos_lcp", "LCPFile", "SOLVERS",
           "SOLVED", "NO_SOLUTION", "MAX_ITERATIONS", "FAILED", "STATUSES"]
