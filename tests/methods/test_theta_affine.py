"""The one-pair stepper as two affine maps of the step's start (theta_kernels.branch_maps): step by step
against the plain NumPy step it replaces, its exact Jacobian against the product of the one-step derivatives,
the degenerate steps, the state in registers against the state in the rows of x, and plans over a longer span."""
import numpy as np
import pytest

from converters.errors import SimulationError
from converters.methods import Theta
from converters.methods.theta import StepPlan
from converters.compiled import NO_SOLUTION, OK, register_state
from converters.methods.theta_kernels import run_scalar
from converters.models import get_converter
from converters.problems import Configuration, LCSProblem, Schedule


def reference_steps(plan, x):
    """The step from each x[j] as written before: x_free = Phi x + Gamma, q = C x_free + F, u = max(0, -q / M),
    x+ = x_free + H u, y = q + M u (NumPy, one pair)."""
    m, s = plan.mats, plan.which
    x_free = np.einsum("jil,jl->ji", m.Phi[s], x[:-1]) + m.Gamma[s]
    q = np.einsum("jl,jl->j", m.C[s, 0], x_free) + m.F[s, 0]
    M = m.M[s, 0, 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        u = np.where(q < 0.0, -q / M, 0.0)
    return x_free + m.H[s, :, 0] * u[:, None], u, q + M * u


@pytest.mark.parametrize("theta", [1.0, 0.5])
def test_the_one_pair_kernel_is_the_numpy_step_to_rounding_step_by_step_on_a_dcm_buck(theta):
    conv = get_converter("buck")
    p = conv.resolve({})                                   # DCM: the diode holds iL = 0 for a third of each period
    T = conv.period(p)
    plan = StepPlan.build(conv.problem(p, 40 * T), Theta(T / 1000, theta))
    x, u, y, _ = plan.advance(plan.problem.x0)
    x_ref, u_ref, y_ref = reference_steps(plan, x)
    held = u_ref > 0.0
    assert 10_000 < held.sum() < 30_000                    # both branches, many times (13,440 held of 40,000)
    np.testing.assert_array_equal(u[1:, 0] > 0.0, held)    # the same branch at every step
    scale = np.abs(x).max(axis=0)
    assert np.all(np.abs(x[1:] - x_ref).max(axis=0) <= 1e-13 * scale)     # measured 2e-16
    assert np.abs(u[1:, 0] - u_ref).max() <= 1e-13 * np.abs(u_ref).max()
    assert np.abs(y[1:, 0] - y_ref).max() <= 1e-13 * np.abs(y_ref).max()


def test_the_state_in_registers_and_in_the_rows_of_x_give_the_same_run_bit_for_bit():
    conv = get_converter("buck")
    p = conv.resolve({})
    T = conv.period(p)
    plan = StepPlan.build(conv.problem(p, 5 * T), Theta(T / 1000, 1.0))
    m = plan.mats
    runs = []
    for state in (register_state(2), None):
        x, u, y = np.zeros((plan.t.size, 2)), np.zeros((plan.t.size, 1)), np.zeros((plan.t.size, 1))
        assert run_scalar(plan.which, m.Phi_b, m.Gamma_b, m.CPhi, m.q0, m.M, x, u, y, 0, state) == (OK, plan.which.size)
        runs.append((x, u, y))
    for a, b in zip(*runs):
        np.testing.assert_array_equal(a, b)


def _random_one_pair_problem(n, seed, t_end=2.0):
    """A stable random LCS with one pair (a diode-like D = 0.1) switched between two configurations."""
    rng = np.random.default_rng(seed)
    configs = []
    for name in ("a", "b"):
        A = rng.normal(size=(n, n))
        A -= (np.abs(np.linalg.eigvals(A)).max() + 0.5) * np.eye(n)
        configs.append(Configuration(A=A, B=rng.normal(size=(n, 1)), C=rng.normal(size=(1, n)), D=[[0.1]],
                                     E=rng.normal(size=n), F=[0.05], name=name))
    return LCSProblem(tuple(configs), Schedule.pwm(0.25, 0.4), x0=rng.normal(size=n), t_span=(0.0, t_end))


@pytest.mark.parametrize("n", [1, 3, 8])        # 8 > MAX_REGISTER_STATES: the state in the rows of x
def test_the_kernel_matches_the_numpy_step_for_other_sizes(n):
    problem = _random_one_pair_problem(n, seed=n)
    plan = StepPlan.build(problem, Theta(1e-3, 1.0))
    x, u, y, _ = plan.advance(problem.x0)
    x_ref, u_ref, y_ref = reference_steps(plan, x)
    assert 0 < (u_ref > 0).sum() < u_ref.size
    np.testing.assert_array_equal(u[1:, 0] > 0.0, u_ref > 0.0)
    assert np.all(np.abs(x[1:] - x_ref).max(axis=0) <= 1e-13 * np.abs(x).max(axis=0))
    assert np.abs(u[1:, 0] - u_ref).max() <= 1e-13 * np.abs(u_ref).max()


@pytest.mark.parametrize("point", [("buck", {}), ("buck", {"D": 0.7, "R": 2}), ("cuk", {"L1": "10u", "L2": "10u"})])
def test_the_exact_jacobian_is_the_product_of_the_one_step_derivatives(point):
    name, params = point
    conv = get_converter(name)
    p = conv.resolve(params)
    T = conv.period(p)
    plan = StepPlan.build(conv.problem(p, T), Theta(T / 1000, 1.0))
    x, u, _, _ = plan.advance(np.full(plan.problem.n, 0.5))
    m = plan.mats
    product = np.eye(plan.problem.n)
    for j, s in enumerate(plan.which):
        step = m.Phi[s].copy()
        if u[j + 1, 0] > 0.0:                  # held: d u / d x = -(C Phi) / M
            step -= np.outer(m.H[s, :, 0], m.C[s, 0] @ m.Phi[s]) / m.M[s, 0, 0]
        product = step @ product
    jac = plan.jacobian(u)
    assert np.abs(jac - product).max() <= 1e-12 * np.abs(product).max()


def _scalar_problem(B, E, x0, D=0.0):
    """x' = B u + E, y = x + D u: M = D + h B."""
    config = Configuration(A=[[0.0]], B=[[B]], C=[[1.0]], D=[[D]], E=[E], name="c")
    return LCSProblem((config,), Schedule.constant(), x0=[x0], t_span=(0.0, 1e-3))


def test_a_step_whose_m_is_not_positive_is_free_while_q_is_not_negative_and_has_no_solution_after():
    # M = -h < 0: x falls by h = 1e-4 per step from 2e-4; the step is free while q = x_free >= 0 (q = 0 exactly at
    # the second step) and has no solution at the first step where q < 0 (the third).
    problem = _scalar_problem(B=-1.0, E=-1.0, x0=2e-4)
    plan = StepPlan.build(problem, Theta(1e-4, 1.0))
    assert plan.mats.M[0, 0, 0] < 0.0
    x = np.zeros((plan.t.size, 1))
    u, y = np.zeros_like(x), np.zeros_like(x)
    x[0] = problem.x0
    m = plan.mats
    status, j = run_scalar(plan.which, m.Phi_b, m.Gamma_b, m.CPhi, m.q0, m.M, x, u, y, 0, register_state(1))
    assert status == NO_SOLUTION and j == 2
    np.testing.assert_array_equal(x[:3, 0], [2e-4, 1e-4, 0.0])
    np.testing.assert_array_equal(u[1:3, 0], [0.0, 0.0])
    np.testing.assert_array_equal(y[1:3, 0], [1e-4, 0.0])
    with pytest.raises(SimulationError, match=r"step LCP at t = 0.0002 s has no solution"):
        plan.advance(problem.x0)
    # M = 0 exactly (D = 0, B = 0): q >= 0 is a free step; q < 0 has no solution.
    still = _scalar_problem(B=0.0, E=0.0, x0=1.0)
    assert StepPlan.build(still, Theta(1e-4, 1.0)).advance(still.x0)[1].max() == 0.0
    stuck = _scalar_problem(B=0.0, E=0.0, x0=-1.0)
    with pytest.raises(SimulationError, match=r"has no solution"):
        StepPlan.build(stuck, Theta(1e-4, 1.0)).advance(stuck.x0)


@pytest.mark.parametrize("periods", [20, 3.3337])     # whole periods; a span that ends inside a step
def test_a_plan_over_a_longer_span_is_the_plan_built_for_it(periods):
    conv = get_converter("buck")
    p = conv.resolve({})
    T = conv.period(p)
    method = Theta(T / 1000, 0.5)
    x0 = np.array([0.3, 5.0])
    plan = StepPlan.build(conv.problem(p, T), method).spanning(periods * T, x0)
    fresh = StepPlan.build(conv.problem(p, periods * T, x0), method)
    for key in ("t", "step_config", "which"):
        np.testing.assert_array_equal(getattr(plan, key), getattr(fresh, key))
    for key in fresh.mats.__dataclass_fields__:
        np.testing.assert_array_equal(getattr(plan.mats, key), getattr(fresh.mats, key))
    np.testing.assert_array_equal(plan.trajectory(x0).x, fresh.trajectory(x0).x)
