"""Linear complementarity problem solvers: one algorithm per module, one entry point."""
from .result import FAILED, MAX_ITERATIONS, NO_SOLUTION, SOLVED, STATUSES, LCPResult, lcp_error
from .siconos import LCPFile, read_siconos_lcp
from .solve import SOLVERS, check_lcp, solve_lcp

__all__ = ["solve_lcp", "check_lcp", "LCPResult", "lcp_error", "read_siconos_lcp", "LCPFile", "SOLVERS",
           "SOLVED", "NO_SOLUTION", "MAX_ITERATIONS", "FAILED", "STATUSES"]
