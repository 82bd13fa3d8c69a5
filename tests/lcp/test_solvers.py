"""LCP solvers against exact answers, each other, and their own failure modes."""
import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from converters.errors import LCPError
from converters.lcp import lcp_error, solve_lcp
from converters.lcp.problems import murty_exponential, problem_set, random_p_matrix

P_SOLVERS = ["lemke", "murty", "newton"]  # guaranteed on every P-matrix
ALL = ["auto", "lemke", "murty", "enum", "pgs", "newton"]


@settings(max_examples=60, deadline=None)
@given(k=st.integers(1, 30), seed=st.integers(0, 2**32 - 1), kind=st.sampled_from(["pd", "spd", "triangular"]))
def test_p_matrix_lcps_are_solved_by_every_applicable_solver(k, seed, kind):
    rng = np.random.default_rng(seed)
    M, q = random_p_matrix(rng, k, kind), rng.standard_normal(k)
    solvers = P_SOLVERS + (["pgs"] if kind == "spd" else []) + (["enum"] if k <= 10 else [])
    results = {m: solve_lcp(M, q, method=m, tol=1e-10, fast_paths=False) for m in solvers}
    for method, result in results.items():
        assert result.status == "solved", (method, result.message)
        assert result.err <= 1e-9, (method, result.err)
    if k <= 10:
        reference = results["enum"]
        assert len(reference.solutions) == 1  # P-matrix: exactly one solution
        for method, result in results.items():
            np.testing.assert_allclose(result.z, reference.z, atol=1e-7 * (1 + np.abs(reference.z).max()))


@settings(max_examples=300, deadline=None)
@given(q=st.lists(st.sampled_from([-2.0, -1.0, -1.0 + 1e-12, -1.0 - 1e-12, -1.0 + 1e-9, -1e-12, 0.0, 1e-12, 1.0]),
                  min_size=1, max_size=8))
def test_lemkes_first_pivot_is_the_lexicographic_rule_in_closed_form(q):
    """Lemke's first pivot (z0 enters) is written in closed form: the least q_i, the last of the rows tied with it.
    It must pick the row the lexicographic test itself picks on the initial tableau (ties within its tolerance)."""
    from converters.lcp.lemke import _lexmin_rows
    from converters.lcp import lemke, state as S
    q = np.array(q)
    k = q.shape[0]
    C = np.zeros((k, k + 2))
    C[:, k], C[:, k + 1] = -1.0, q                                   # the initial tableau: -M = 0, the z0 column
    place = np.r_[-1 - np.arange(k), np.arange(k), k].astype(np.int64)
    expected = _lexmin_rows(C, place, np.arange(k), k, k, k, -1.0, np.zeros(k, dtype=np.int64))
    if np.all(q >= 0.0):
        return                                                       # no pivot: z = 0
    nf, ni = lemke.sizes(k)
    fw, iw, st_ = np.zeros(nf), np.zeros(ni, dtype=np.int64), np.zeros(S.ST_SIZE, dtype=np.int64)
    lemke.run(np.eye(k), q, np.zeros(k), fw, iw, st_, 1e-10, 1, 10**6, lemke.PIVOT_TOL)   # max_iter 1: one pivot
    basis = iw[:k]
    assert basis[expected] == 2 * k and list(basis).count(2 * k) == 1      # z0 is basic in that row


def test_lemke_reports_no_solution_for_minus_identity():
    result = solve_lcp(-np.eye(3), -np.ones(3), method="lemke")
    assert result.status == "no_solution"
    assert result.message == ("lemke: ray termination, and no solution exists: w[0] = q[0] + sum_j M[0,j] z_j <= "
                              "q[0] < 0 for every z >= 0")


def test_lemkes_ray_is_no_solution_only_with_a_proof(peer):
    from converters.lcp import read_siconos_lcp
    # M positive semidefinite (eigenvalues 0 and 2) and w1 + w2 = -2 for every z: Lemke's ray is a proof
    result = solve_lcp(np.array([[1.0, -1.0], [-1.0, 1.0]]), np.array([-1.0, -1.0]), method="lemke", fast_paths=False)
    assert result.status == "no_solution" and "M is positive semidefinite" in result.message
    # CPS_3: Lemke ends on a ray, yet z = (0.1, 0, 0.1, 0) solves it (auto finds it by enumeration): was no_solution
    cps3 = read_siconos_lcp(peer / "lcp_CPS_3.dat")
    result = solve_lcp(cps3.M, cps3.q, method="lemke")
    assert result.status == "failed" and "which proves nothing here (M is not positive semidefinite" in result.message
    assert "a solution may exist; try method='auto'" in result.message
    solved = solve_lcp(cps3.M, cps3.q)
    assert solved.solved and solved.err <= 1e-10


def test_enumeration_lists_both_vertices_of_the_seed_psd_example():
    result = solve_lcp([[1, 1], [1, 1]], [-1, -1], method="enum")
    assert result.status == "solved"
    found = sorted(tuple(np.round(s, 12)) for s in result.solutions)
    assert found == [(0.0, 1.0), (1.0, 0.0)]


@pytest.mark.parametrize("k", [4, 6, 8])
def test_murty_takes_two_to_the_k_minus_one_pivots_on_its_exponential_example(k):
    M, q = murty_exponential(k)
    result = solve_lcp(M, q, method="murty", fast_paths=False)
    assert result.solved and result.iterations == 2**k - 1
    np.testing.assert_allclose(result.z, np.eye(k)[-1])  # z = (0, ..., 0, 1)


@pytest.mark.parametrize("method", ALL)
def test_every_solver_on_a_known_2x2_solution(method):
    M = np.array([[2.0, 1.0], [1.0, 2.0]])
    z_star, w_star = np.array([1.0, 0.0]), np.array([0.0, 3.0])
    q = w_star - M @ z_star
    result = solve_lcp(M, q, method=method, fast_paths=False)
    assert result.solved
    np.testing.assert_allclose(result.z, z_star, atol=1e-9)
    np.testing.assert_allclose(result.w, w_star, atol=1e-9)


def test_error_measure_matches_the_siconos_definition():
    M, q, z = np.eye(2), np.array([3.0, -4.0]), np.array([1.0, 1.0])
    w = q + M @ z  # (4, -3)
    expected = np.linalg.norm(z - np.maximum(0, z - w)) / 5.0  # (1 - 0, 1 - 4) -> (1, -3)
    assert lcp_error(M, q, z) == pytest.approx(expected)
    assert expected == pytest.approx(np.sqrt(10) / 5)
    assert lcp_error(M, np.zeros(2), np.zeros(2)) == 0.0  # q = 0 guard


@pytest.mark.parametrize("M,q,z", [
    ([[2.0]], [-4.0], [2.0]),          # k = 1: z = -q/M
    ([[2.0]], [4.0], [0.0]),           # q >= 0
    ([[2.0, 1.0], [1.0, 2.0]], [-3.0, -3.0], [1.0, 1.0]),  # k = 2, both active
])
def test_fast_paths_give_the_exact_solution_without_pivoting(M, q, z):
    result = solve_lcp(M, q)
    assert result.solved and result.iterations == 0 and "closed form" in result.message
    np.testing.assert_allclose(result.z, z)


@settings(max_examples=60, deadline=None)
@given(k=st.integers(3, 10), seed=st.integers(0, 2**32 - 1), lower=st.booleans())
def test_a_triangular_m_with_a_positive_diagonal_is_solved_by_substitution_as_enumeration_solves_it(k, seed, lower):
    from .reference import enumerate_bases
    rng = np.random.default_rng(seed)
    M, q = random_p_matrix(rng, k, "triangular"), rng.standard_normal(k)
    M = M.T.copy() if lower else M
    result = solve_lcp(M, q)
    rule = "trivial" if np.all(q >= 0) else "triangular"      # q >= 0 is tried first: z = 0
    assert result.solved and result.method == "auto:closed form" and result.message == f"closed form ({rule})"
    assert result.iterations == 0 and result.err <= 1e-12
    reference = enumerate_bases(M, q, tol=1e-10)            # pure Python, every basis: the one solution
    assert len(reference.solutions) == 1
    np.testing.assert_allclose(result.z, reference.z, rtol=1e-10, atol=1e-12 * (1 + np.abs(reference.z).max()))
    for method in ("lemke", "murty"):                      # the closed form also answers a named method
        assert solve_lcp(M, q, method=method).message == f"closed form ({rule})"


@pytest.mark.parametrize("k", [6, 40, 300])
def test_murtys_exponential_example_is_exact_by_substitution_where_pivoting_takes_2_to_the_k(k):
    M, q = murty_exponential(k)                             # least-index Murty: 2^k - 1 pivots
    result = solve_lcp(M, q)
    assert result.solved and result.message == "closed form (triangular)" and result.err == 0.0
    np.testing.assert_array_equal(result.z, np.eye(k)[-1])  # z = (0, ..., 0, 1), exactly
    np.testing.assert_array_equal(result.w, np.r_[np.ones(k - 1), 0.0])


@pytest.mark.parametrize("M", [
    [[1.0, 2.0, 0.0], [0.0, 0.0, 2.0], [0.0, 0.0, 1.0]],     # a zero on the diagonal: not a P-matrix
    [[1.0, 2.0, 0.0], [0.0, -1.0, 2.0], [0.0, 0.0, 1.0]],    # a negative one
    [[1.0, 2.0, 0.0], [0.0, 1.0, 2.0], [1e-300, 0.0, 1.0]],   # one entry below the diagonal: not triangular
    [[1.0, 0.0, 0.0], [2.0, 1.0, 0.0], [3.0, 4.0, 1.0]],     # lower triangular: applies (the control)
])
def test_the_triangular_rule_applies_only_to_a_triangular_m_with_a_positive_diagonal(M):
    from converters.lcp.fastpaths import triangular
    M = np.array(M)
    z = triangular(M, -np.ones(3))
    applies = bool(np.all(np.diag(M) > 0) and (np.array_equal(M, np.triu(M)) or np.array_equal(M, np.tril(M))))
    assert (z is not None) == applies
    if applies:
        np.testing.assert_array_equal(z, [1.0, 0.0, 0.0])   # z0 = 1; row 1: -1 + 2 > 0, z1 = 0; row 2: -1 + 3 > 0


def test_project_problem_set_outcomes():
    for case in problem_set():
        result = solve_lcp(case.M, case.q, method="lemke", fast_paths=False)
        assert result.status == ("solved" if case.solvable else "no_solution"), case.name
        if case.solvable:
            assert result.err <= 1e-10, case.name


def test_pgs_divergence_is_reported_not_returned_as_nan():
    case = next(c for c in problem_set() if c.name == "p_pd_20")  # non-symmetric: PGS diverges
    result = solve_lcp(case.M, case.q, method="pgs", fast_paths=False)
    assert result.status == "failed" and "diverged" in result.message
    assert np.all(np.isfinite(result.z))


@pytest.mark.parametrize("kwargs,match", [
    (dict(M=[[1.0, 2.0]], q=[1.0]), r"M must be square \(k x k\); got shape 1x2"),
    (dict(M=np.eye(2), q=[1.0, 2.0, 3.0]), r"q must be a vector of length 2; got shape 3"),
    (dict(M=[[np.nan]], q=[1.0]), r"M must contain only finite numbers; got nan"),
    (dict(M=[[1.0]], q=[np.inf]), r"q must contain only finite numbers; got inf"),
    (dict(M=np.eye(2), q=[1, 1], method="simplex"),
     r"method must be one of auto, lemke, murty, enum, pgs, newton; got 'simplex'"),
    (dict(M=np.eye(2), q=[1, 1], tol=0.0), r"tol must be in \[1e-16, 0.01\]; got 0.0"),
    (dict(M=np.eye(2), q=[1, 1], max_iter=0), r"max_iter must be an integer in \[1, 1000000000\]; got 0"),
    (dict(M=np.eye(13), q=-np.ones(13), method="enum"), r"k must be <= 12; got k = 13"),
])
def test_bad_input_names_the_parameter_range_and_value(kwargs, match):
    with pytest.raises(LCPError, match=match):
        solve_lcp(**kwargs)
    assert issubclass(LCPError, ValueError)
