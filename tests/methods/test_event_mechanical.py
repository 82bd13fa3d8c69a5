"""The event method on mechanical problems: impacts against the bouncing ball's closed form, exact Jacobians
against finite differences (crossing, sticking: the sliding projector), one long run against repeated short
ones, the cam's detachment against k c + m c'' = 0, and bad input."""
import numpy as np
import pytest

from converters.analysis.periodic import shoot
from converters.errors import ParameterError
from converters.methods import EventDriven
from converters.models.mechanics import accumulation_time, get_mechanical
from converters.models.mechanics.cam import CamOffset, profile
from converters.problems.mechanical import MechanicalProblem, UnilateralContact
from converters.simulate import simulate

FRICTION = get_mechanical("friction")


@pytest.mark.parametrize("e", [0.5, 0.8])
def test_the_bouncing_ball_accumulates_at_its_closed_form_time_and_each_impact_scales_by_e(e):
    model = get_mechanical("bouncing-ball")
    p = model.resolve({"e": e})
    exact = accumulation_time(p["H"], p["g"], e)
    events = simulate(model.problem(p, 1.2 * exact), EventDriven()).events
    chatter = events.loc[events["kind"] == "chatter", "time"].to_numpy()
    assert chatter.size == 1 and chatter[0] == pytest.approx(exact, rel=1e-6)
    impacts = events.loc[events["kind"] == "impact", "time"].to_numpy()
    assert impacts[0] == pytest.approx(np.sqrt(2 * p["H"] / p["g"]), rel=1e-12)
    flights = np.diff(impacts)
    assert flights[1:] / flights[:-1] == pytest.approx(np.full(flights.size - 1, e), abs=1e-6)


def _orbit(A, omega):
    p = FRICTION.resolve({"A": A, "omega": omega})
    problem = FRICTION.problem(p, FRICTION.period(p))
    return problem, shoot(problem, EventDriven(), warm_up=100, tol=1e-10)


@pytest.mark.parametrize("A, omega, sticks", [(5.0, 2.5, True), (5.0, 1.6, False)])
def test_the_exact_jacobian_agrees_with_finite_differences_and_sticking_projects(A, omega, sticks):
    """Saltation at the crossings; entering stick, the sliding projector: a multiplier exactly 0."""
    problem, orbit = _orbit(A, omega)
    assert orbit.converged and orbit.jacobian_kind == "exact"
    period_map = EventDriven().period_map(problem)
    fd = np.empty((2, 2))
    for j in range(2):
        e = np.zeros(2)
        e[j] = 1e-6 * (1.0 + abs(orbit.x0[j]))
        fd[:, j] = (period_map.end(orbit.x0 + e) - period_map.end(orbit.x0 - e)) / (2 * e[j])
    assert np.abs(fd - orbit.jacobian).max() <= 1e-6
    kinds = [e[1] for e in period_map.events(orbit.x0)]
    assert ("stick" in kinds) == sticks
    assert (np.abs(orbit.multipliers).min() < 1e-12) == sticks


def test_a_stick_force_exceeding_the_limit_inside_one_step_is_not_missed():
    """A = 0.5, omega = 2.9031: the stick flow is trivial (the integrator strides), and the stick force exceeds
    static friction only briefly; one run over 4 T and four runs over T must agree."""
    p = FRICTION.resolve({"A": 0.5, "omega": 2.9031})
    T = FRICTION.period(p)
    x0 = np.array([0.13434974, 1.0])
    long = EventDriven().period_map(FRICTION.problem(p, 4 * T)).end(x0)
    one = EventDriven().period_map(FRICTION.problem(p, T))
    x = x0
    for _ in range(4):
        x = one.end(x)
    assert np.abs(long - x).max() < 1e-8


def test_the_cam_follower_detaches_where_the_spring_cannot_follow_the_cam():
    from scipy.optimize import brentq
    model = get_mechanical("cam-follower")
    p = model.resolve({})
    T = model.period(p)
    events = simulate(model.problem(p, T), EventDriven()).events
    first = events.loc[events["kind"] == "detach", "time"].to_numpy()[0]
    grid = np.linspace(0.0, T, 20001)
    margin = model.detachment_margin(p, grid)
    k = int(np.flatnonzero((margin[:-1] >= 0) & (margin[1:] < 0))[0])      # the first time k c + m c'' < 0
    zero = brentq(lambda t: float(model.detachment_margin(p, t)), grid[k], grid[k + 1], xtol=1e-15)
    assert first == pytest.approx(zero, abs=1e-9)
    assert events["kind"].iloc[0] == "detach" and (events["time"] > first).any()   # no impact at the release


def test_the_cam_profile_and_its_derivatives():
    """Derivatives against central differences; the lift continuous at the joints, its second derivative not
    (the cam is piecewise smooth: its profile's second derivative jumps at the joints)."""
    beta = np.linspace(0.05, np.pi - 0.05, 2001)
    h, h1, h2 = profile(beta)
    d = 1e-6
    assert h1 == pytest.approx((profile(beta + d)[0] - profile(beta - d)[0]) / (2 * d), abs=2e-5)
    joints = np.pi / 2 + np.array([1.050328174371336, 1.22173047639603])
    smooth = np.all(np.abs(beta[:, None] - joints[None, :]) > 1e-3, axis=1) & (np.abs(beta - np.pi / 2) > 1e-3)
    assert h2[smooth] == pytest.approx(((profile(beta + d)[1] - profile(beta - d)[1]) / (2 * d))[smooth], abs=1e-4)
    for joint in np.concatenate([[np.pi / 2], joints]):
        left, right = profile(np.array([joint - 1e-9]))[0], profile(np.array([joint + 1e-9]))[0]
        assert left == pytest.approx(right, abs=1e-6)
    jump = profile(np.array([np.pi / 2 + 1e-9]))[2] - profile(np.array([np.pi / 2 - 1e-9]))[2]
    assert abs(jump[0]) > 0.1
    c, c1, c2 = CamOffset(2 * np.pi * 358 / 60).position(np.array([0.0]))
    assert c[0] == pytest.approx(0.1) and c1[0] == pytest.approx(0.0)


def test_bad_mechanical_input_gets_one_clear_line():
    with pytest.raises(ParameterError, match="restitution e must be in"):
        UnilateralContact([1.0], 1.5)
    with pytest.raises(ParameterError, match="mass must be a symmetric positive definite"):
        MechanicalProblem(mass=[[-1.0]], damping=[[0.0]], stiffness=[[1.0]], force=None)
    model = get_mechanical("bouncing-ball")
    p = model.resolve({})
    with pytest.raises(ParameterError, match="x0 must keep every gap >= 0"):
        simulate(model.problem(p, 1.0, x0=[-0.1, 0.0]), EventDriven())
    with pytest.raises(ParameterError, match=r"e \(Newton restitution\) must be in \[0, 1\)"):
        model.resolve({"e": 1.0})
