"""solve_lcp_many: many problems of one size in one compiled call, each answer the one solve_lcp gives (bit for
bit: the same compiled solve, the same workspace rules, the same hand-over to the sliced path)."""
import numpy as np
import pytest

from converters.errors import LCPError
from converters.lcp import LCPBatch, read_siconos_lcp, solve_lcp, solve_lcp_many
from converters.lcp.problems import murty_exponential, problem_set, random_p_matrix

METHODS = ["auto", "lemke", "murty", "pgs", "newton", "enum"]


def same(batch: LCPBatch, i: int, single) -> None:
    a = batch[i]
    for name in ("status", "method", "message", "iterations"):
        assert getattr(a, name) == getattr(single, name), name
    assert a.err == single.err or (np.isnan(a.err) and np.isnan(single.err))
    assert np.array_equal(a.z, single.z) and np.array_equal(a.w, single.w)


@pytest.mark.parametrize("method", METHODS)
def test_each_answer_is_solve_lcps_on_random_p_matrix_problems(method):
    """Closed forms (k <= 2, triangular M), auto's plan and its messages, PGS refusing a nonsymmetric M: every
    branch of the compiled call against the one-problem entry."""
    rng = np.random.default_rng(7)
    for kind in ("spd", "pd", "triangular"):
        for k in range(1, 9):
            Ms = np.array([random_p_matrix(rng, k, kind) for _ in range(6)])
            qs = rng.standard_normal((6, k))
            batch = solve_lcp_many(Ms, qs, method=method)
            assert len(batch) == 6 and batch.z.shape == (6, k)
            for i in range(6):
                same(batch, i, solve_lcp(Ms[i], qs[i], method=method))
            assert batch.solved.all() or method == "pgs"


def test_each_answer_is_solve_lcps_on_the_peer_collection_and_the_problem_set(peer):
    cases = [(read_siconos_lcp(path).M, read_siconos_lcp(path).q) for path in sorted(peer.glob("lcp_*.dat"))]
    cases += [(case.M, case.q) for case in problem_set()]
    statuses = set()
    for M, q in cases:
        batch = solve_lcp_many(np.array([M, M]), np.array([q, -np.abs(q)]))
        for i, qi in enumerate((q, -np.abs(q))):
            same(batch, i, solve_lcp(np.ascontiguousarray(M, float), np.ascontiguousarray(qi, float)))
        statuses.update(batch.status)
    assert {"solved", "no_solution"} <= statuses


def test_a_problem_beyond_the_first_slice_of_work_is_solved_by_solve_lcp_itself():
    """Murty's example at k = 16 takes 2^16 - 1 pivots, more than one slice: handed to solve_lcp."""
    M, q = murty_exponential(16)
    batch = solve_lcp_many(np.array([M, M]), np.array([q, np.ones(16)]), method="murty", fast_paths=False)
    assert batch.status == ("solved", "solved") and batch.iterations[0] == 2 ** 16 - 1
    same(batch, 0, solve_lcp(M, q, method="murty", fast_paths=False))
    same(batch, 1, solve_lcp(M, np.ones(16), method="murty", fast_paths=False))
    with_closed_forms = solve_lcp_many(np.array([M]), np.array([q]), method="murty")     # triangular M: substitution
    assert with_closed_forms.iterations[0] == 0 and with_closed_forms.message[0].startswith("closed form")


@pytest.mark.parametrize("Ms, qs, match", [
    (np.eye(2)[None], np.ones((1, 3)), r"Ms must be \(P, k, k\) and qs \(P, k\)"),
    (np.eye(2), np.ones(2), r"Ms must be \(P, k, k\)"),
    (np.zeros((1, 0, 0)), np.zeros((1, 0)), "k >= 1"),
    (np.array([np.eye(2), [[np.nan, 0.0], [0.0, 1.0]]]), -np.ones((2, 2)), r"Ms\[1\] and qs\[1\] must be finite"),
])
def test_bad_batches_are_refused_naming_the_problem(Ms, qs, match):
    with pytest.raises(LCPError, match=match):
        solve_lcp_many(Ms, qs)


def test_a_bad_method_or_tolerance_is_refused():
    with pytest.raises(LCPError, match="method must be one of"):
        solve_lcp_many(np.eye(2)[None], -np.ones((1, 2)), method="simplex")
    with pytest.raises(LCPError, match=r"tol must be in \[1e-16, 0.01\]; got 1.0"):
        solve_lcp_many(np.eye(2)[None], -np.ones((1, 2)), tol=1.0)
