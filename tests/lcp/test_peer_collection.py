"""The Siconos peer collection: our Lemke and enumeration against what Siconos' own solve."""
import numpy as np
import pytest

from converters.errors import LCPError

from converters.lcp import read_siconos_lcp, solve_lcp
from validation.peer import ours_differs, peer_table, siconos_expects_failure

PEER_NAMES = ["CPS_1", "CPS_2", "CPS_3", "CPS_4", "CPS_4bis", "CPS_5", "Pang_isolated_sol",
              "Pang_isolated_sol_perturbed", "deudeu", "deudeu_block", "enum_fails", "exp_murty",
              "exp_murty2", "inf_sol_perturbed", "mmc", "ortiz", "ortiz_block", "tobenna", "trivial",
              "trivial_block"]


def test_the_collection_holds_the_twenty_problems(peer):
    assert sorted(p.stem.removeprefix("lcp_") for p in peer.glob("lcp_*.dat")) == sorted(PEER_NAMES)


@pytest.mark.parametrize("name", PEER_NAMES)
@pytest.mark.parametrize("method", ["lemke", "enum"])
def test_solves_what_siconos_solves(peer, name, method):
    problem = read_siconos_lcp(peer / f"lcp_{name}.dat")
    siconos_fails = siconos_expects_failure(name, method)
    if method == "enum" and problem.M.shape[0] > 12:
        assert ours_differs(name, method)  # refused by specification, and the report says so
        with pytest.raises(LCPError, match=r"k must be <= 12"):
            solve_lcp(problem.M, problem.q, method=method)
        return
    result = solve_lcp(problem.M, problem.q, method=method, tol=1e-6, fast_paths=False)
    if siconos_fails:
        # Where Siconos fails we may fail too; where we succeed, the residual must be real.
        if result.solved:
            assert result.err <= 1e-6 and ours_differs(name, method)
        return
    assert result.status == "solved", (name, method, result.message)
    assert result.err <= 1e-6


def test_block_and_dense_twins_hold_the_same_problem(peer):
    for name in ("ortiz", "trivial", "deudeu"):
        dense, block = (read_siconos_lcp(peer / f"lcp_{n}.dat") for n in (name, name + "_block"))
        np.testing.assert_array_equal(dense.M, block.M)
        np.testing.assert_array_equal(dense.q, block.q)


def test_every_difference_from_siconos_is_explained(peer):
    rows = peer_table(peer)
    assert len(rows) == 20 * 5
    unexplained = [(r["problem"], r["method"]) for r in rows if r["differs"] and not r["explanation"]]
    assert unexplained == []
