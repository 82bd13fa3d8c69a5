"""The compiled principal-pivoting solver the step loops use above MAX_INLINE_K pairs (a Cockcroft-Walton ladder's
2N diodes): its solutions against Lemke's, from any start, and a k = 16 circuit stepped without the general solver,
step for step equal to the same run solved by Lemke."""
from __future__ import annotations

import numpy as np
import pytest

from converters.compiled import MAX_INLINE_K
from converters.lcp import solve_lcp
from converters.lcp.murty import sizes, solve_warm
from converters.lcp.state import ST_SIZE

def workspace(k):
    floats, ints = sizes(k)
    return np.empty(k), np.empty(floats), np.empty(ints, dtype=np.int64), np.empty(ST_SIZE, dtype=np.int64)


def _p_matrix(rng, k):
    """Positive definite, not symmetric (an SPD part plus a skew part): a P-matrix, one solution for every q."""
    a = rng.normal(size=(k, k))
    skew = rng.normal(size=(k, k))
    return a @ a.T / k + 0.1 * np.eye(k) + (skew - skew.T)


@pytest.mark.parametrize("k", [9, 16, 40])
def test_pivoting_finds_lemkes_solution_from_any_start(k):
    rng = np.random.default_rng(k)
    z, fw, iw, st = workspace(k)
    for trial in range(40):
        M, q = _p_matrix(rng, k), rng.normal(size=k)
        active = rng.random(k) < 0.5                   # a wrong guess: the solver must flip its way out
        flips = solve_warm(M, q, z, active, fw, iw, st, 1000, np.abs(M).max())
        assert flips >= 0
        reference = solve_lcp(M, q, method="lemke")
        assert reference.solved
        np.testing.assert_allclose(z, reference.z, atol=1e-10 * (1 + np.abs(reference.z).max()))
        w = q + M @ z
        assert z.min() >= 0 and w.min() >= -1e-10 and abs(z @ w) <= 1e-9
        assert np.array_equal(active, z > 0)              # the active set it leaves is the solution's
        again = solve_warm(M, q, z, active, fw, iw, st, 1000, np.abs(M).max())
        assert again == 0                                 # warm: the set still holds, no flip


def test_pivoting_gives_up_on_a_singular_block_instead_of_guessing():
    k = MAX_INLINE_K + 1
    M = np.zeros((k, k))
    q = -np.ones(k)
    z, fw, iw, st = workspace(k)
    assert solve_warm(M, q, z, np.ones(k, dtype=np.bool_), fw, iw, st, 100, 0.0) == -1


def test_a_ladder_of_16_diodes_steps_without_the_general_solver_and_equals_lemke_step_by_step():
    """N = 8 stages (k = 16 > MAX_INLINE_K): every step solved in the compiled loop (it had been 400 Lemke calls
    a period, in Python), the states equal to those of the same steps solved one by one by Lemke."""
    from converters.methods import Theta
    from converters.methods.theta import StepPlan
    from converters.models import Circuit
    from converters.simulate import simulate
    from netlists.generators import cockcroft_walton
    circuit = Circuit.from_netlist("cw8.cir", text=cockcroft_walton(8))
    p = circuit.resolve({})
    T = circuit.period(p)
    problem, method = circuit.problem(p, 3 * T), Theta(h=T / 400, theta=0.5)
    assert problem.k == 16 > MAX_INLINE_K
    tr = simulate(problem, method)
    assert tr.general_solves == 0
    plan = StepPlan.build(problem, method)
    mats, which = plan.mats, plan.which
    x = tr.x[0].copy()
    for j in range(which.shape[0]):
        s = which[j]
        free = mats.Phi[s] @ x + mats.Gamma[s]
        result = solve_lcp(mats.M[s], mats.C[s] @ free + mats.F[s], method="lemke")
        assert result.solved
        x = free + mats.H[s] @ result.z
        np.testing.assert_allclose(tr.x[j + 1], x, atol=1e-9 * (1 + np.abs(x).max()))
