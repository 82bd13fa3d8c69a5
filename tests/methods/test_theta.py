"""The theta time-stepper on circuits with closed-form answers: accuracy, order, complementarity."""
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import brentq

from validation.core_checks import parallel_rlc_exact

from ..oracle_circuits import diode_bridge, half_wave_rectifier
from converters.errors import ParameterError, SimulationError
from converters.problems import Configuration, LCSProblem, Schedule
from converters.methods import BackwardEuler, Theta
from converters.simulate import simulate

L, C, R = 1e-2, 1e-6, 1e3
W0 = 1.0 / np.sqrt(L * C)


def observed_order(hs, errors):
    return np.polyfit(np.log(hs), np.log(errors), 1)[0]


@pytest.mark.parametrize("theta,order", [(1.0, 1.0), (0.5, 2.0)])
def test_order_on_a_stretch_without_switching(theta, order):
    # vC(0) = -10 V: the diode blocks until vC crosses 0 at t = pi / (2 w0) = 157 us; the LC tank
    # rings freely, vC = -10 cos(w0 t). Stop at 150 us.
    problem = half_wave_rectifier(V0=-10.0, t_end=1.5e-4)
    hs = 1.5e-4 / 2.0 ** np.arange(7, 12)
    errors = []
    for h in hs:
        tr = simulate(problem, Theta(h, theta))
        assert not tr.active.any()
        errors.append(abs(tr.x[-1, 0] - (-10.0 * np.cos(W0 * tr.t[-1]))))
    tolerance = 0.15 if theta == 1.0 else 0.2
    assert observed_order(hs, errors) == pytest.approx(order, abs=tolerance)


def test_backward_euler_order_one_with_the_diode_conducting():
    # vC > 0 throughout [0, 100 us]: u = vC / R is active at every step (D = R > 0): parallel RLC.
    problem = half_wave_rectifier(V0=10.0, t_end=1e-4)
    hs = 1e-4 / 2.0 ** np.arange(5, 10)
    errors = []
    for h in hs:
        tr = simulate(problem, BackwardEuler(h))
        assert tr.active[1:].all()
        errors.append(abs(tr.x[-1, 0] - parallel_rlc_exact([tr.t[-1]], L, C, R, 10.0)[0, 0]))
    assert observed_order(hs, errors) == pytest.approx(1.0, abs=0.15)


def test_diode_bridge_converges_to_a_fine_step_solution():
    problem = diode_bridge(t_end=2e-3)
    fine = simulate(problem, BackwardEuler(2e-8))
    hs = np.array([8e-6, 4e-6, 2e-6, 1e-6])
    errors = []
    for h in hs:
        tr = simulate(problem, BackwardEuler(h))
        reference = np.interp(tr.t, fine.t, fine.x[:, 0])
        errors.append(np.abs(tr.x[:, 0] - reference).max())
    assert observed_order(hs, errors) >= 0.8
    # With ideal diodes the tank always sees R: the bridge is a parallel RLC in closed form.
    exact = parallel_rlc_exact(fine.t, L, C, R, 10.0)
    vc_error, il_error = np.abs(fine.x - exact).max(axis=0)
    assert vc_error < 1e-2 and il_error < 1e-4  # measured 7.3e-3 V and 7.3e-5 A at h = 20 ns


def test_diode_bridge_rectifies_and_keeps_complementarity():
    tr = simulate(diode_bridge(t_end=5e-3), BackwardEuler(1e-6))
    assert tr.general_solves == 0  # k = 4 solved inline
    load_voltage = tr.u[1:, 0] + tr.u[1:, 1]
    np.testing.assert_allclose(load_voltage, np.abs(tr.x[1:, 0]), atol=1e-9)
    assert tr.u.min() >= 0.0 and tr.y.min() >= -1e-9
    assert np.abs(tr.u * tr.y).max() <= 1e-9


def _exact_half_wave_events(t_end, V0=10.0):
    """Zero crossings of vC: the diode releases going down, activates going up (piecewise closed form)."""
    t, state, conducting, events = 0.0, np.array([V0, 0.0]), True, []
    while True:
        resistance = R if conducting else np.inf
        vc = lambda s: parallel_rlc_exact([s], L, C, resistance, *state)[0, 0]
        lo = 1e-9
        while np.sign(vc(lo + 1e-5)) == np.sign(vc(lo)):
            lo += 1e-5
        s = brentq(vc, lo, lo + 1e-5, xtol=1e-16)
        t += s
        if t > t_end:
            return np.array(events)
        state = parallel_rlc_exact([s], L, C, resistance, *state)[0]
        state[0] = 0.0
        events.append(t)
        conducting = not conducting


def test_sub_step_event_estimates_converge_and_beat_the_grid():
    exact = _exact_half_wave_events(5e-3)
    hs = np.array([4e-6, 2e-6, 1e-6, 5e-7])
    errors = []
    for h in hs:
        tr = simulate(half_wave_rectifier(), BackwardEuler(h))
        estimate = tr.events["time"].to_numpy()
        grid = tr.t[tr.events["step"].to_numpy() + 1]
        assert len(estimate) == len(exact) == 16
        assert tr.events["kind"].tolist()[:2] == ["release", "activate"]
        errors.append(np.abs(estimate - exact).max())
        assert errors[-1] < np.abs(grid - exact).max()
    assert observed_order(hs, errors) >= 0.8


def test_trajectory_to_pandas_has_named_columns():
    tr = simulate(half_wave_rectifier(t_end=1e-4), BackwardEuler(1e-6))
    frame = tr.to_pandas()
    assert list(frame.columns) == ["time", "vC", "iL", "u_diode", "y_diode", "active_diode", "config"]
    assert len(frame) == tr.steps + 1 == 101
    assert frame["config"].iloc[0] == "rlcd"


def test_switched_configurations_follow_the_schedule():
    # An RC charged through a switch: ON connects Vin = 1 V through R = 1, OFF lets it discharge.
    on = Configuration(A=[[-1.0]], B=[[0.0]], C=[[0.0]], D=[[1.0]], E=[1.0], name="on")
    off = Configuration(A=[[-1.0]], B=[[0.0]], C=[[0.0]], D=[[1.0]], name="off")
    problem = LCSProblem((on, off), Schedule.pwm(1.0, 0.5), x0=[0.0], t_span=(0.0, 1.0))
    tr = simulate(problem, Theta(1e-3, 0.5))
    v_half = 1 - np.exp(-0.5)
    assert tr.x[tr.t == 0.5][0, 0] == pytest.approx(v_half, rel=1e-6)
    assert tr.x[-1, 0] == pytest.approx(v_half * np.exp(-0.5), rel=1e-6)


def test_a_step_lcp_without_solution_is_a_clear_error():
    # An inductor current source driven into a diode that can only block: M = -h/L < 0, q < 0.
    bad = Configuration(A=[[0.0]], B=[[-1.0]], C=[[1.0]], D=[[0.0]], E=[-1.0], name="bad")
    problem = LCSProblem((bad,), Schedule.constant(), x0=[0.0], t_span=(0.0, 1e-3))
    with pytest.raises(SimulationError, match=r"step LCP at t = 0 s has no solution"):
        simulate(problem, BackwardEuler(1e-4))


def test_simulate_rejects_a_foreign_method_and_bad_x0():
    problem = half_wave_rectifier(t_end=1e-4)
    with pytest.raises(ParameterError, match=r"method must be a pcsuite method \(lcp: Theta, event: EventDriven, "
                                             r"smooth: Smoothing, moreau: MoreauJean, spice: Spice\); got 'euler'"):
        simulate(problem, "euler")
    with pytest.raises(ParameterError, match=r"x0 must be 2 finite numbers"):
        simulate(problem, BackwardEuler(1e-6), x0=[np.nan, 0.0])


def test_graded_steps_start_at_grade_h_after_each_switching_instant_and_grow_to_h():
    from converters.methods.theta import time_grid
    A = np.array([[-1.0]])
    c = Configuration(A=A, B=np.zeros((1, 1)), C=np.zeros((1, 1)), D=np.ones((1, 1)), E=np.zeros(1), F=np.ones(1))
    T, h = 1.0, 0.05
    problem = LCSProblem([c, c], Schedule(period=T, starts=(0.0, 0.3), configs=(0, 1)), x0=np.zeros(1),
                         t_span=(0.0, 2 * T))
    method = Theta(h=h, grade=0.01, growth=1.5)
    t = time_grid(problem, h, method.graded)
    steps = np.diff(t)
    for instant in (0.0, 0.3, 1.0, 1.3):
        j = int(np.flatnonzero(np.isclose(t, instant, atol=1e-12))[0])
        first = steps[j:j + len(method.graded)]
        np.testing.assert_allclose(first[0], 0.01 * h, rtol=1e-12)
        np.testing.assert_allclose(first[1:] / first[:-1], 1.5, rtol=1e-9)
    assert steps.max() <= h * (1 + 1e-9) and steps.min() >= 1e-3 * h
    assert len(method.graded) == 12                        # 0.01 h * 1.5^11 < h <= 0.01 h * 1.5^12
    assert np.array_equal(np.diff(time_grid(problem, h, ())), np.diff(time_grid(problem, h)))


@pytest.mark.parametrize("option, value", [("grade", 1.0), ("grade", -0.1), ("growth", 1.0), ("growth", 11.0)])
def test_a_grading_outside_its_range_is_refused_naming_it(option, value):
    with pytest.raises(ParameterError, match=rf"{option} .*must be in .*got {value}"):
        Theta(h=1e-6, **{option: value})


def test_graded_steps_reach_the_multipliers_exact_orbit_with_a_tenth_of_the_uniform_steps():
    """The 4-stage Cockcroft-Walton multiplier (k = 8 diodes, each RS C = T/20 transfer at the square wave's
    edges): against the event method's exact periodic orbit, the stepper graded after each edge (first step h/100,
    growth 1.2) at h = T/20, 62 steps a period, is closer than the uniform stepper at T/160 (measured: 4.1e-5
    against 8.3e-5; the uniform one needs T/640 for 2.9e-5)."""
    from pathlib import Path
    from tempfile import TemporaryDirectory

    from converters.models import Circuit
    from converters.run import steady_orbit
    from netlists.generators import cockcroft_walton
    with TemporaryDirectory() as tmp:
        path = Path(tmp) / "cw4.cir"
        path.write_text(cockcroft_walton(4))
        circuit = Circuit.from_netlist(path)
    p = circuit.resolve({})
    T = circuit.period(p)
    exact = steady_orbit(circuit, p, method="event").mean("vout")
    graded = steady_orbit(circuit, p, method=Theta(h=T / 20, theta=0.5, grade=0.01))
    uniform = steady_orbit(circuit, p, method=Theta(h=T / 160, theta=0.5))
    assert graded.steps == 62 and uniform.steps == 160
    assert abs(graded.mean("vout") / exact - 1) < 5e-5
    assert abs(uniform.mean("vout") / exact - 1) > 6e-5


def test_sets_alike_but_for_their_sources_share_one_elimination_to_the_bit():
    """Configurations that differ only in E, F (a PULSE source's levels) share the elimination of I - dt theta A
    (the first such set leads): every set's matrices are those it gets when built alone, to the last bit."""
    from dataclasses import fields, replace

    from converters.methods.discretize import _leaders, step_matrices
    rng = np.random.default_rng(5)
    n, k, h = 6, 3, 1e-2
    A = -np.eye(n) + 0.3 * rng.standard_normal((n, n))
    B, C, D = rng.standard_normal((n, k)), rng.standard_normal((k, n)), np.eye(k)
    c0 = Configuration(A=A, B=B, C=C, D=D, E=rng.standard_normal(n), F=rng.standard_normal(k))
    c1 = Configuration(A=A.copy(), B=B.copy(), C=C.copy(), D=D.copy(), E=rng.standard_normal(n),
                       F=rng.standard_normal(k))                                # equal values, arrays of their own
    c2 = replace(c0, A=A + 1e-3)
    configs, dts = [c0, c1, c2, c1, c0], np.array([h, h, h, h / 2, h / 2])
    assert _leaders(configs, dts).tolist() == [0, 0, 2, 3, 3]
    together = step_matrices(configs, dts, 0.5)
    for s, (c, dt) in enumerate(zip(configs, dts)):
        alone = step_matrices([c], np.array([dt]), 0.5)
        for field in fields(together):
            assert np.array_equal(getattr(together, field.name)[s], getattr(alone, field.name)[0]), (s, field.name)


@pytest.mark.parametrize("stages", [3, 5])
def test_the_last_periods_active_sets_as_guesses_change_no_bit(stages):
    """The step loop guesses each step's active set from the same step a period earlier (a graded multiplier:
    1.6 flips a step from the last step's set, 0.003 from the last period's): the guess changes how many pivots
    a step takes, never its answer (k = 6: the inline solver; k = 10: the pivoting). Its sets of one step size in
    the two source levels share their eliminations."""
    from pathlib import Path
    from tempfile import TemporaryDirectory

    from converters.compiled import kernel, register_state
    from converters.methods.discretize import _leaders
    from converters.methods.theta import StepPlan, _set_configuration
    from converters.models import Circuit
    from netlists.generators import cockcroft_walton
    with TemporaryDirectory() as tmp:
        path = Path(tmp) / "cw.cir"
        path.write_text(cockcroft_walton(stages))
        circuit = Circuit.from_netlist(path)
    p = circuit.resolve({})
    T = circuit.period(p)
    plan = StepPlan.build(circuit.problem(p, 30 * T), Theta(h=T / 10, theta=0.5, grade=0.001, growth=1.5))
    local, _, _, set_configs, set_dts = plan.period
    period = local.size - 1
    leaders = _leaders([_set_configuration(plan.problem, c, 0.5) for c in set_configs], set_dts)
    assert period == 42 and len(set(leaders.tolist())) < 0.6 * len(set_dts)
    runs = []
    for guess in (0, period):
        x, u, y, _ = plan.advance(plan.problem.x0)
        m = plan.mats
        status = kernel("run_steps")(plan.which, m.Phi, m.Gamma, m.H, m.C, m.F, m.M, m.Phi_b, m.Gamma_b, m.CPhi,
                                     m.q0, x, u, y, 0, plan.problem.k <= 8, guess, register_state(plan.problem.n))
        assert tuple(status) == (0, plan.which.size)
        runs.append((x, u, y))
    assert (runs[0][1][-period:] > 0).any(axis=0).sum() == plan.problem.k        # every diode conducts
    for a, b in zip(*runs):
        assert np.array_equal(a, b)


def test_a_steady_run_whose_step_does_not_divide_the_period_repeats_the_orbits_period():
    """h = 33 ns does not divide the buck's 10 us period (303.03 steps): Newton's period map runs [0, T] ending on a
    short step, and the run returned from the orbit must repeat that grid period by period. Gridded whole from 0,
    its steps straddled the period starts and its periods were not the orbit's: the capacitor current's mean over
    the 10 periods read 5.1e-6 A (0 on an orbit, to rounding) and vout's mean differed from the orbit's by 3e-7."""
    from converters.run import run_converter, run_summary
    path = Path(__file__).resolve().parents[2] / "netlists" / "circuits" / "buck.cir"
    run = run_converter(str(path), steady=True, h=33e-9)
    orbit = run_converter(str(path), steady=True, h=33e-9, periods=1)
    T = 1e-5
    assert np.allclose(np.diff(run.t[run.t > run.t[-1] - T]), np.diff(orbit.t[orbit.t > orbit.t[-1] - T]), rtol=0,
                       atol=1e-15)
    summary = run_summary(run)
    assert abs(summary["measurements"]["i(c1)"]["mean"]) < 1e-10
    assert summary["vout_mean"] == pytest.approx(orbit.mean("vout", t0=orbit.t[0], t1=orbit.t[-1]), rel=1e-12)
