"""The layout of the small state arrays the compiled LCP methods keep between slices of work.

Every method's ``run`` works in an int64 state array ``st`` (``ST_SIZE`` entries) and a float64 one ``sf``
(``SF_SIZE``); these names index them and code what they hold. Plain module constants: numba reads them
as compile-time constants.
"""
# st: where the method is, and how it ended
PHASE, ITER, AUX, STATUS, OUTCOME, INFO, USED = range(7)
# st: auto's own entries (its current stage, and what each stage ended with)
STAGE = 7
STAGE_OUTCOME = 9      # 9 .. 9 + N_METHODS - 1: outcome of each method auto ran (-1: not run)
STAGE_ITER = 15        # 15 .. 15 + N_METHODS - 1: its iterations
PSD = 21               # how auto looked at M's semidefiniteness after Lemke's ray (PSD_* below)
# 1: the caller checks a claimed solution itself, on the original problem (engine.solve_in); Lemke then leaves its
# own check of the same answer on the normalised problem to it (0, a zeroed st: Lemke checks)
CALLER_CHECKS = 22
ST_SIZE = 24
# sf
INFO_X = 0
PREVIOUS_ERR = 1     # pgs probing for auto: the residual of the previous sweep
SF_SIZE = 4

# phases (EIGENVALUE: auto waits for the caller to compute the least eigenvalue of (M + M^T)/2 after Lemke's ray)
START, RUNNING, DONE, EIGENVALUE = 0, 1, 2, 3

# statuses: indices into converters.lcp.result.STATUSES
SOLVED, NO_SOLUTION, MAX_ITERATIONS, FAILED = 0, 1, 2, 3

#: Multiply-adds between two looks at the clock (a few milliseconds of work at most).
CHUNK = 1 << 22
#: The closed forms, in the order they are tried (:mod:`converters.lcp.fastpaths`).
CLOSED_FORM_RULES = ("trivial", "scalar", "pair", "triangular")
#: Largest k enumeration takes (2^k bases).
ENUM_MAX_K = 12
# solve_once's answers (:func:`converters.lcp.engine.solve_once`)
ONCE_SOLVED, ONCE_CLOSED_FORM, ONCE_OTHER, ONCE_NOT_FINITE = range(4)

# method codes: indices into METHOD_NAMES (solve_lcp's ``method``)
METHOD_NAMES = ("auto", "lemke", "murty", "enum", "pgs", "newton")
AUTO, LEMKE, MURTY, ENUM, PGS, NEWTON = range(6)
N_METHODS = len(METHOD_NAMES)

# outcomes (why a method ended)
OK = 0              # solved
RAY = 1             # Lemke: ray termination
MAXIT = 2           # max_iter reached
CHECK = 3           # a claimed solution failed the check (on the problem the method was given)
SINGULAR = 4        # Murty: singular principal submatrix
DIAG = 5            # PGS: a non-positive diagonal entry (INFO: its index, INFO_X: its value)
DIVERGED = 6        # PGS: diverged (INFO: the sweep)
LINESEARCH = 7      # Newton: the line search failed
NOBASIS = 8         # enumeration: no feasible complementary basis
PROOF_ROW = 9       # auto: a row of w = q + M z is negative for every z >= 0 (INFO: the row)
PROOF_PSD = 10      # auto: Lemke's ray with M positive semidefinite (INFO_X: least eigenvalue of (M + M^T)/2)
EXHAUSTED = 11      # auto: every method in its plan ended without a solution
SLOW = 12           # pgs probing for auto: converging too slowly to finish within its sweeps

# st[PSD]: 0 not looked at; the least eigenvalue computed (sf[INFO_X]); disproved by a negative diagonal entry or
# 2 x 2 principal minor; not tested (k above auto.PSD_MAX_K)
PSD_NONE, PSD_EIGENVALUE, PSD_MINOR, PSD_UNTESTED = 0, 1, 2, 3
