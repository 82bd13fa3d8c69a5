"""Scale-aware residuals: every method solves q or M of any magnitude, and no wrong answer is called solved."""
import numpy as np
import pytest

from converters.lcp import lcp_error, solve_lcp
from converters.lcp.problems import problem_set, random_p_matrix
from converters.lcp.result import SOLVED, finish
from converters.lcp.siconos import read_siconos_lcp

ALL = ["auto", "lemke", "murty", "enum", "pgs", "newton"]
Q_SCALES = [1e-200, 1e-100, 1.0, 1e100]
M_SCALES = [1e-150, 1e150]


def known_problems():
    """(name, M, z*, w*) with a known complementary pair; M symmetric positive definite (PGS converges too)."""
    rng = np.random.default_rng(7)
    M = random_p_matrix(rng, 6, "spd")
    z_star = np.array([0.8, 0.0, 1.5, 0.0, 0.25, 0.0])
    w_star = np.array([0.0, 0.6, 0.0, 1.3, 0.0, 0.45])
    yield "identity_3", np.eye(3), np.ones(3), np.zeros(3)
    yield "spd_6_mixed", M, z_star, w_star
    yield "spd_6_all_active", M, np.array([1.0, 2.0, 0.5, 1.0, 0.3, 0.7]), np.zeros(6)


PROBLEMS = list(known_problems())


TOL = 1e-12   # the iterative methods (pgs, newton) converge to it; the pivoting ones are exact up to rounding


def assert_solves(result, M, q, z_star, rel=1e-9):
    """solved; z >= 0, w >= -TOL and z.w ~ 0 relative to the problem's scale; z = z* to ``rel`` relative."""
    assert result.status == "solved", result.message
    z, w = result.z, result.w
    z_scale = np.abs(z_star).max()
    if z_scale == 0.0:   # q >= 0: z = 0 exactly
        np.testing.assert_array_equal(z, 0.0)
        z_scale = 1.0
    w_scale = max(np.abs(q).max(), np.abs(M).max() * z_scale)
    assert np.all(z >= 0.0)
    assert np.all(w >= -TOL * w_scale)
    assert np.all(np.minimum(z / z_scale, w / w_scale) <= TOL)    # complementary, pair by pair
    assert abs(z @ w) <= TOL * z_scale * w_scale * len(q)
    assert np.max(np.abs(z - z_star)) <= rel * z_scale
    assert_is_w_of(w, M, q, z)   # w is the original problem's, not the normalised one's


def assert_is_w_of(w, M, q, z):
    """w = q + M z up to the rounding of a k-term sum in any order: |w - (q + M z)| <= 2 k eps (|q| + |M| |z|)
    (the compiled residual sums in index order, numpy's BLAS in its own; a w of the normalised problem is off by
    its power-of-two factor, ~1e200 times more)."""
    bound = 2 * len(q) * np.finfo(float).eps * (np.abs(q) + np.abs(M) @ np.abs(z))
    assert np.all(np.abs(w - (q + M @ z)) <= bound)


@pytest.mark.parametrize("method", ALL)
@pytest.mark.parametrize("scale", Q_SCALES)
@pytest.mark.parametrize("name,M,z_star,w_star", PROBLEMS, ids=[p[0] for p in PROBLEMS])
def test_every_method_solves_q_of_any_magnitude(method, scale, name, M, z_star, w_star):
    q = scale * (w_star - M @ z_star)
    result = solve_lcp(M, q, method=method, tol=TOL, fast_paths=False)
    assert_solves(result, M, q, scale * z_star)


@pytest.mark.parametrize("method", ALL)
@pytest.mark.parametrize("m_scale", M_SCALES)
@pytest.mark.parametrize("name,M,z_star,w_star", PROBLEMS, ids=[p[0] for p in PROBLEMS])
def test_every_method_solves_M_of_any_magnitude(method, m_scale, name, M, z_star, w_star):
    q = w_star - M @ z_star
    result = solve_lcp(m_scale * M, q, method=method, tol=TOL, fast_paths=False)
    assert_solves(result, m_scale * M, q, z_star / m_scale)


@pytest.mark.parametrize("method", ALL)
def test_q_and_M_scaled_together(method):
    _, M, z_star, w_star = PROBLEMS[1]
    q = 1e-100 * (w_star - M @ z_star)
    result = solve_lcp(1e150 * M, q, method=method, tol=TOL, fast_paths=False)   # z ~ 1e-250: still representable
    assert_solves(result, 1e150 * M, q, 1e-250 * z_star)


@pytest.mark.parametrize("method", ALL)
def test_a_solution_that_is_not_representable_is_failed_not_solved(method):
    # z* = 1e-200 / 1e150 = 1e-350 underflows to 0 in double precision: w = q < 0 there
    result = solve_lcp(1e150 * np.eye(2), [-1e-200, -2e-200], method=method, fast_paths=False)
    assert result.status == "failed"
    assert "infeasible: w[" in result.message and "not representable" in result.message


@pytest.mark.parametrize("scale", [1e-200, 1e-100, 1e100])
@pytest.mark.parametrize("M,q,z_star,rule", [
    ([[2.0]], [-4.0], [2.0], "scalar"),
    ([[2.0]], [4.0], [0.0], "trivial"),
    ([[2.0, 1.0], [1.0, 2.0]], [-3.0, -3.0], [1.0, 1.0], "pair"),
    ([[2.0, 1.0], [1.0, 2.0]], [-2.0, 1.0], [1.0, 0.0], "pair"),
    ([[1.0, 2.0, 2.0], [0.0, 1.0, 2.0], [0.0, 0.0, 1.0]], [-5.0, -3.0, -1.0], [1.0, 1.0, 1.0], "triangular"),
    ([[2.0, 0.0, 0.0], [1.0, 2.0, 0.0], [1.0, 1.0, 2.0]], [-2.0, 1.0, -4.0], [1.0, 0.0, 1.5], "triangular"),
])
def test_fast_paths_at_any_magnitude(scale, M, q, z_star, rule):
    M, q, z_star = np.array(M), scale * np.array(q), scale * np.array(z_star)
    result = solve_lcp(M, q, tol=TOL)
    assert result.message == f"closed form ({rule})" and result.iterations == 0
    assert_solves(result, M, q, z_star)
    result = solve_lcp(M / scale, q / scale, tol=TOL)   # M = M0 / s, q = q0: z = s z0 again
    assert result.message == f"closed form ({rule})"
    assert_solves(result, M / scale, q / scale, z_star)


def test_the_issue_example_identity_and_q_minus_1e_200_is_solved_exactly():
    for method in ALL:
        result = solve_lcp(np.eye(3), [-1e-200] * 3, method=method, fast_paths=False)
        assert result.status == "solved", method
        np.testing.assert_allclose(result.z, 1e-200, rtol=1e-9)
        assert np.all(result.w >= -1e-10 * 1e-200)    # the default tol, relative to the scale 1e-200


def test_lcp_error_does_not_underflow_or_overflow():
    M, q, z = np.eye(2), np.array([3.0, -4.0]), np.array([1.0, 1.0])
    expected = np.sqrt(10) / 5     # see test_error_measure_matches_the_siconos_definition
    for scale in (1e-300, 1e-200, 1.0, 1e200, 1e300):
        assert lcp_error(M, scale * q, scale * z) == pytest.approx(expected, rel=1e-14), scale
    assert lcp_error(M, np.zeros(2), np.array([1e-200, 0.0])) == pytest.approx(1e-200, rel=1e-14)  # q = 0: absolute
    assert lcp_error(M, np.zeros(2), np.array([3e200, 4e200])) == pytest.approx(5e200, rel=1e-14)


@pytest.mark.parametrize("q,z,condition", [
    ([-1e-200] * 3, [0.0, 0.0, 0.0], "infeasible: w[0] = -1e-200 < 0"),      # the issue: err underflowed to 0
    ([-1e-200, -1e-200, 1e-200], [1e-200, 1e-200, -1e-205], "infeasible: z[2] = -1e-205 < 0"),
    ([-1e-200] * 3, [2e-200, 1e-200, 1e-200], "not complementary: z[0] = 2e-200 and w[0] = 1e-200"),
])
def test_finish_names_the_condition_a_claimed_solution_fails(q, z, condition):
    q = np.array(q)
    result = finish(np.eye(3), q, np.array(z), status=SOLVED, iterations=1, method="murty", tol=1e-10)
    assert result.status == "failed"
    assert result.message.startswith("murty: the claimed solution is ") and condition in result.message


@pytest.mark.parametrize("scale", [1e-200, 1.0, 1e200])
def test_rounding_noise_in_a_zero_z_is_judged_against_q_over_M_not_against_itself(scale):
    # true z = 0 (q > 0); a pivoting method may return 1e-17-sized noise, which is not a positive z_0 next to w_0 = 1
    M, q = np.eye(2), scale * np.array([1.0, 2.0])
    result = finish(M, q, scale * np.array([1e-17, 0.0]), status=SOLVED, iterations=1, method="murty", tol=1e-10)
    assert result.status == "solved" and result.err == pytest.approx(1e-17 / np.sqrt(5), rel=1e-12)
    noisy = finish(M, q, scale * np.array([1e-9, 0.0]), status=SOLVED, iterations=1, method="murty", tol=1e-10)
    assert noisy.status == "failed" and "not complementary: z[0]" in noisy.message   # 1e-9 relative is not noise


def test_finish_keeps_the_residual_check():
    # every w_i = -0.9e-10 is within tol of the scale max|q| = 1, but err = ||w|| / ||q|| = 1.8e-10 > tol
    M, q = np.eye(4), np.array([-1.0, -1e-3, -1e-3, -1e-3])
    z = -q - 0.9e-10
    result = finish(M, q, z, status=SOLVED, iterations=1, method="lemke", tol=1e-10)
    assert result.err == pytest.approx(1.8e-10, rel=1e-4)
    assert result.status == "failed" and "final residual err = 1.8e-10 exceeds tol = 1e-10" in result.message


@pytest.mark.parametrize("method", ["auto", "lemke", "murty", "enum"])
def test_scaling_the_peer_collection_changes_no_outcome(peer, method):
    """Solved / not solved on the Siconos collection is the same for q x 1e-100 and M x 1e100 as unscaled."""
    for path in sorted(peer.glob("lcp_*.dat")):
        p = read_siconos_lcp(path)
        if method == "enum" and p.M.shape[0] > 12:
            continue
        base = solve_lcp(p.M, p.q, method=method, tol=1e-6, fast_paths=False)
        for M, q in ((p.M, 1e-100 * p.q), (1e100 * p.M, p.q), (1e-150 * p.M, 1e100 * p.q)):
            scaled = solve_lcp(M, q, method=method, tol=1e-6, fast_paths=False)
            assert scaled.status == base.status, (p.name, scaled.message)
            if base.solved:
                z_ratio = np.abs(q).max() / np.abs(p.q).max() / (np.abs(M).max() / np.abs(p.M).max())
                np.testing.assert_allclose(scaled.z, z_ratio * base.z, rtol=1e-9,
                                           atol=1e-9 * z_ratio * np.abs(base.z).max())


def test_project_problem_set_outcomes_are_scale_free():
    for case in problem_set():
        base = solve_lcp(case.M, case.q, method="lemke", fast_paths=False)
        tiny = solve_lcp(case.M, 1e-200 * case.q, method="lemke", fast_paths=False)
        assert tiny.status == base.status, case.name
        if base.solved:
            np.testing.assert_allclose(tiny.z, 1e-200 * base.z, rtol=1e-9, atol=1e-209 * np.abs(base.z).max())


@pytest.mark.parametrize("scale", [1e-310, 1e-200, 1.0, 1e200])
def test_the_complementarity_test_decides_as_the_exact_quotients_do_at_its_tolerance(scale):
    """The check looks for the largest gap min(z_i / z_scale, w_i / w_scale) with reciprocals first and falls back
    to the quotients near tol: its verdict must be the quotients' own, for tol just below, at and just above the
    largest gap (at 1e-310 the scales are subnormal and their reciprocals overflow)."""
    from converters.lcp.result import CHECK_NOT_COMPLEMENTARY, CHECK_OK, check
    rng = np.random.default_rng(5)
    decided = 0
    for _ in range(300):
        k = int(rng.integers(1, 7))
        M = np.eye(k) + np.triu(rng.uniform(0.0, 0.1, (k, k)), 1)
        z = rng.uniform(0.5, 1.0, k) * scale                  # z_i and w_i both positive: a gap of w_i / w_scale
        w = rng.uniform(0.5, 1.0, k) * scale * rng.choice([1e-3, 1e-9, 1e-13], k)
        q = w - M @ z
        big_q, big_m = np.abs(q).max(), np.abs(M).max()
        z_scale = max(np.abs(z).max(), big_q / big_m)
        w_scale = max(big_q, big_m * np.abs(z).max())
        gap = max(min(zi / z_scale, wi / w_scale) for zi, wi in zip(z, w))
        if not 1e-16 < gap < 1e-2:
            continue
        for tol in (np.nextafter(gap, 0.0), gap, np.nextafter(gap, 1.0), gap * (1 - 1e-15), gap * (1 + 1e-15)):
            code = check(M, q, z, w, 0.0, tol)[0]
            assert code == (CHECK_OK if gap <= tol else CHECK_NOT_COMPLEMENTARY), (k, scale, gap, tol, code)
            decided += 1
    assert decided > 500


@pytest.mark.parametrize("k", [1, 2, 3, 4, 5, 7, 8, 9, 13])
def test_the_magnitudes_are_numpys_and_any_entry_that_is_not_finite_is_found(k):
    """max|q| and max|M| are kept as four running maxima (the remainder of k / 4 separately): the same numbers as
    numpy's, and a NaN or inf anywhere, in the blocks of four or in the remainder, makes the problem not finite."""
    from converters.lcp import engine
    from converters.lcp.result import max_abs, max_abs_matrix
    rng = np.random.default_rng(k)
    M, q = rng.standard_normal((k, k)) * 10.0 ** rng.integers(-5, 5, (k, k)), rng.standard_normal(k)
    assert engine.magnitudes(M, q)[2:] == (True, np.abs(q).max(), np.abs(M).max())
    assert max_abs(q) == np.abs(q).max() and max_abs_matrix(M) == np.abs(M).max()
    for bad in (np.nan, np.inf, -np.inf):
        for i in range(k):
            for j in range(k):
                Mb = M.copy()
                Mb[i, j] = bad
                assert not engine.magnitudes(Mb, q)[2], (bad, i, j)
            qb = q.copy()
            qb[i] = bad
            assert not engine.magnitudes(M, qb)[2], (bad, i)
