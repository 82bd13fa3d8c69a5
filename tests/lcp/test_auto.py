"""method="auto" (the default): its choice by size and structure, its fallbacks, its proofs of non-existence,
and the peer collection solved whenever it has a solution."""
import json

import numpy as np
import pytest

from converters.lcp import read_siconos_lcp, solve_lcp
from converters.lcp.problems import murty_exponential, problem_set, random_p_matrix
from validation.cli import main

from .test_peer_collection import PEER_NAMES

#: The one peer problem without a solution: w1 = -1e-4 - z2 - z3 < 0 for every z >= 0 (see validation/peer.py).
NO_SOLUTION = {"Pang_isolated_sol_perturbed"}


@pytest.mark.parametrize("name", PEER_NAMES)
def test_auto_solves_every_peer_problem_that_has_a_solution(peer, name):
    problem = read_siconos_lcp(peer / f"lcp_{name}.dat")
    result = solve_lcp(problem.M, problem.q)      # every default: auto, tol 1e-10
    assert result.method.startswith("auto:")
    if name in NO_SOLUTION:
        assert result.status == "no_solution" and result.method == "auto:lemke"
        assert result.message.startswith("auto: no solution exists: w[0] = q[0] + sum_j M[0,j] z_j <= q[0] < 0")
        return
    assert result.status == "solved", result.message
    assert result.err <= 1e-10
    np.testing.assert_array_equal(result.z, np.maximum(result.z, 0.0))


def test_auto_is_the_default_of_solve_lcp_and_of_the_cli(capsys, tmp_path, peer):
    M, q = np.array([[4.0, 0.1, 0.0], [0.1, 4.0, 0.1], [0.0, 0.1, 4.0]]), np.array([-1.0, 2.0, -1.0])   # PGS
    assert solve_lcp(M, q).method == solve_lcp(M, q, method="auto").method == "auto:pgs"
    trivial = read_siconos_lcp(peer / "lcp_trivial.dat")    # diagonal: triangular with a positive diagonal
    assert solve_lcp(trivial.M, trivial.q).method == solve_lcp(trivial.M, trivial.q, method="auto").method == \
        "auto:closed form"
    code = main(["lcp", "solve", str(peer / "lcp_CPS_3.dat"), "--json"])
    out = json.loads(capsys.readouterr().out)
    assert code == 0 and out["status"] == "solved" and out["method"] == "auto:enum"
    assert "lemke ended on a ray" in out["message"] and out["message"].endswith("solved by enum")
    code = main(["lcp", "solve", str(peer / "lcp_tobenna.dat"), "--method", "auto"])
    assert code == 0 and "method = auto:lemke, status = solved" in capsys.readouterr().out


@pytest.mark.parametrize("M,q,method", [
    ([[2.0]], [-1.0], "auto:closed form"),                                            # k = 1
    ([[2.0, 1.0], [1.0, 2.0]], [-3.0, 1.0], "auto:closed form"),                      # k = 2
    (np.eye(5), np.ones(5), "auto:closed form"),                                      # q >= 0
    ([[4.0, 0.1, 0.0], [0.1, 4.0, 0.1], [0.0, 0.1, 4.0]], [-1.0, 2.0, -1.0], "auto:pgs"),   # symmetric, dominant
    ([[4.0, 1.0, 0.0], [1.0, 4.0, 1.0], [0.0, 1.0, 4.0]], [-1.0, -1.0, -1.0], "auto:lemke"),  # PGS: 12 sweeps
    ([[1.0, 2.0, 0.0], [0.0, 1.0, 2.0], [0.5, 0.0, 1.0]], [-1.0, -1.0, -1.0], "auto:lemke"),  # P, not symmetric
    ([[1.0, 2.0, 0.0], [0.0, 1.0, 2.0], [0.0, 0.0, 1.0]], [-1.0, -1.0, -1.0], "auto:closed form"),  # triangular
])
def test_auto_chooses_by_size_and_structure(M, q, method):
    result = solve_lcp(M, q)
    assert result.solved and result.method == method
    assert result.message in ("", "closed form (pair)", "closed form (scalar)", "closed form (trivial)",
                              "closed form (triangular)")


def test_pgs_gives_way_to_lemke_at_once_when_it_converges_slowly():
    rng = np.random.default_rng(3)
    Q, _ = np.linalg.qr(rng.standard_normal((50, 50)))
    M = Q @ np.diag(np.logspace(0, -4, 50)) @ Q.T
    M = 0.5 * (M + M.T)                     # symmetric positive definite, condition number 1e4
    result = solve_lcp(M, rng.standard_normal(50))
    assert result.solved and result.method == "auto:lemke" and result.message == ""   # PGS giving way is no news
    diagonal = M + np.diag(4.0 * np.abs(M).sum(axis=1))   # strongly diagonally dominant: PGS in a few sweeps
    result = solve_lcp(diagonal, rng.standard_normal(50))
    assert result.solved and result.method == "auto:pgs" and result.iterations <= 25


def test_after_lemkes_ray_auto_falls_back_to_enumeration_then_newton(peer):
    game = read_siconos_lcp(peer / "lcp_CPS_3.dat")      # a bimatrix game: Lemke's ray proves nothing
    result = solve_lcp(game.M, game.q)
    assert result.solved and result.method == "auto:enum"
    assert result.message == ("auto: lemke ended on a ray (which proves nothing here: M is not positive "
                              "semidefinite: a diagonal entry or a 2 x 2 principal minor of (M + M^T)/2 is "
                              "negative); solved by enum")
    assert solve_lcp(game.M, game.q, method="lemke").status == "failed"     # the ray proves nothing (was no_solution)
    M = np.zeros((14, 14))                # the game and 10 independent unknowns: k = 14 > 12, no enumeration
    M[:4, :4], M[4:, 4:] = game.M, 2.0 * np.eye(10)
    result = solve_lcp(M, np.concatenate([game.q, -np.ones(10)]))
    assert result.solved and result.method == "auto:newton" and result.err <= 1e-10
    assert result.message.endswith("solved by newton")


def test_no_solution_only_with_a_proof():
    # a row of w = q + M z negative for every z >= 0
    result = solve_lcp(-np.eye(3), -np.ones(3))
    assert result.status == "no_solution" and "w[0] = q[0] + sum_j M[0,j] z_j <= q[0] < 0" in result.message
    # M positive semidefinite (copositive-plus): Lemke's ray proves it; w1 + w2 = -2 whatever z
    M = np.array([[1.0, -1.0, 0.0], [-1.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
    result = solve_lcp(M, -np.ones(3))
    assert result.status == "no_solution" and result.method == "auto:lemke"
    assert "M is positive semidefinite" in result.message and "hence copositive-plus: no solution exists" in \
        result.message
    # no solution either (w2 > 0 forces z2 = 0, then w3 = -3 - 2 z3 < 0), but no cheap proof: failed, saying why
    M = np.array([[0.0, 1.0, 3.0], [2.0, 1.0, 0.0], [0.0, 3.0, -2.0]])
    result = solve_lcp(M, [2.0, 1.0, -3.0])
    assert result.status == "failed" and result.method == "auto:newton"
    assert result.message.startswith("auto: no method of the plan found a solution (lemke ended on a ray")
    assert "enum found no feasible complementary basis among the 2^3 = 8" in result.message
    assert "newton reached max_iter (1000) steps" in result.message
    assert result.message.endswith("and no proof that none exists (a row of w negative for every z >= 0, or "
                                   "Lemke's ray with M positive semidefinite)")


def test_auto_on_the_project_problem_set():
    for case in problem_set():
        result = solve_lcp(case.M, case.q)
        assert result.status == ("solved" if case.solvable else "no_solution"), (case.name, result.message)
        if case.solvable:
            assert result.err <= 1e-10, case.name


def test_max_iter_applies_to_each_method_of_the_plan():
    M, q = murty_exponential(8)                     # without the closed form for a triangular M
    result = solve_lcp(M, q, max_iter=3, fast_paths=False)
    assert result.solved and result.method == "auto:lemke" and result.iterations == 2
    M = random_p_matrix(np.random.default_rng(2), 20, "pd")
    result = solve_lcp(M, -np.ones(20), max_iter=1)
    assert result.status == "failed" and "lemke reached max_iter (1) pivots" in result.message
    assert "newton reached max_iter (1) steps" in result.message


def test_auto_takes_no_options():
    with pytest.raises(ValueError, match=r"option 'omega' does not apply to method 'auto'"):
        solve_lcp(np.eye(2), -np.ones(2), omega=1.5)


def test_auto_stops_at_the_time_limit(ticking_clock):
    """Looks at the clock of 10 ms each (tests/lcp/conftest.py): stopped at the 50th or just after."""
    M = random_p_matrix(np.random.default_rng(4), 1500, "pd")    # Lemke: ~1500 pivots of 1500 x 1502
    result = solve_lcp(M, -np.ones(1500), time_limit=0.5)
    assert 50 <= ticking_clock.reads <= 70, ticking_clock.reads
    assert result.status == "failed" and result.method == "auto:lemke"
    assert result.message.startswith(f"auto: lemke (after {result.iterations} pivots) reached the time limit of 0.5 s")
