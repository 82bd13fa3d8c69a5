"""The voltage-mode buck (Hamill, Deane and Jefferies 1992): its period-1 orbit, Floquet multipliers and first period
doubling against a computation independent of the package (scipy expm and root finding on the raw
matrices), saltation multipliers against finite differences, the stepper's orbits converging to the event
method's, and bad input."""
import numpy as np
import pytest
from scipy.linalg import expm
from scipy.optimize import brentq, fsolve

from converters.analysis.continuation import OrbitFamily, follow
from converters.analysis.periodic import shoot
from converters.errors import ParameterError
from converters.methods.event import EventDriven
from converters.methods.theta import Theta
from converters.models import get_model
from converters.models.path import ParameterPath

MODEL = get_model("buck", "voltage-mode")
CLASSIC = dict(L=20e-3, C=47e-6, R=22.0, Vref=11.3, A=8.4, VL=3.8, VU=8.2, T=400e-6)


def independent_orbit(Vin, guess=(0.6, 12.0, 0.3)):
    """The period-1 orbit OFF on [0, d T), ON on [d T, T) (CCM), from x' = A x + E with the buck's matrices
    (tests/models/hand.py), and its monodromy matrix with the saltation matrix S = I + (f+ - f-) n^T / (n^T f- + dg/dt)."""
    L, C, R, Vref, A, VL, VU, T = (CLASSIC[k] for k in ("L", "C", "R", "Vref", "A", "VL", "VU", "T"))
    Am = np.array([[0.0, -1.0 / L], [1.0 / C, -1.0 / (R * C)]])
    E_on = np.array([Vin / L, 0.0])
    slope = (VU - VL) / T

    def flow(E, tau, x):
        Z = np.zeros((3, 3))
        Z[:2, :2], Z[:2, 2] = Am, E
        return (expm(tau * Z) @ np.append(x, 1.0))[:2]

    def equations(u):
        x0, d = u[:2], u[2]
        x_s = flow(np.zeros(2), d * T, x0)
        x_T = flow(E_on, (1 - d) * T, x_s)
        return np.append(x_T - x0, A * (x_s[1] - Vref) - (VL + slope * d * T))

    solution, info, ok, message = fsolve(equations, guess, full_output=True, xtol=1e-13)
    assert np.abs(equations(solution)).max() < 1e-11, message
    x0, d = solution[:2], solution[2]
    x_s = flow(np.zeros(2), d * T, x0)
    f_off, f_on = Am @ x_s, Am @ x_s + E_on
    n = np.array([0.0, A])                                    # gradient of s = A (vC - Vref) - ramp(t)
    S = np.eye(2) + np.outer(f_on - f_off, n) / (n @ f_off - slope)
    M = expm((1 - d) * T * Am) @ S @ expm(d * T * Am)
    return x0, d, M


def event_family(periods=1):
    return OrbitFamily(ParameterPath(MODEL, MODEL.resolve({}), "Vin"), EventDriven(), periods)


@pytest.mark.parametrize("Vin", [20.0, 22.0, 28.0, 34.0])
def test_the_period_1_orbit_and_its_multipliers_against_an_independent_computation(Vin):
    """Stable (20, 22 V) and unstable (28, 34 V) period-1 orbits: state and monodromy matrix."""
    x0, d, M = independent_orbit(Vin)
    family = event_family()
    orbit = family.orbit(Vin, x0 + [1e-3, 1e-2], tol=1e-13)
    assert orbit.converged
    assert orbit.x0 == pytest.approx(x0, abs=1e-10)
    assert orbit.jacobian == pytest.approx(M, abs=1e-9)
    assert np.sort_complex(orbit.multipliers) == pytest.approx(np.sort_complex(np.linalg.eigvals(M)), abs=1e-9)
    assert orbit.stable == (Vin < 24.5)


def test_the_first_period_doubling_against_an_independent_computation():
    """det(M + I) = 0 of the independent monodromy matrix, by Brent's method, against the continuation."""
    exact = brentq(lambda v: np.linalg.det(independent_orbit(v)[2] + np.eye(2)), 24.0, 25.0, xtol=1e-12)
    branch = follow(event_family(), 20.0, 26.0, np.zeros(2))
    doublings = [b for b in branch.bifurcations if b.kind == "period-doubling"]
    assert len(doublings) == 1
    assert doublings[0].value == pytest.approx(exact, abs=1e-6)
    assert exact == pytest.approx(24.5166, abs=1e-4)         # the value the note and the README give


@pytest.mark.parametrize("Vin, periods", [(22.0, 1), (28.0, 2), (31.5, 4), (33.0, 4)])
def test_saltation_multipliers_agree_with_finite_differences(Vin, periods):
    """The exact Jacobian of the k-period map (state-transition and saltation matrices at every switching)
    against central differences of the same map, on stable and unstable orbits of period 1, 2 and 4: the
    differences approach it at second order in their step (the 4-period map is strongly curved: 5e-7 off at
    a relative step of 1e-6) and agree to 1e-6 at a step of 1e-7."""
    family = event_family(periods)
    one = family.period_map(Vin, 1)
    x = np.array([0.6, 12.0])
    for _ in range(300):
        x = one.end(x)
    orbit = family.orbit(Vin, x, tol=1e-13)
    assert orbit.converged and orbit.jacobian_kind == "exact"
    period_map = family.period_map(Vin)

    def central(rel):
        fd = np.empty((2, 2))
        for j in range(2):
            e = np.zeros(2)
            e[j] = rel * (1.0 + abs(orbit.x0[j]))
            fd[:, j] = (period_map.end(orbit.x0 + e) - period_map.end(orbit.x0 - e)) / (2 * e[j])
        return fd
    exact = np.sort_complex(orbit.multipliers)
    assert np.abs(exact - np.sort_complex(np.linalg.eigvals(central(1e-7)))).max() <= 1e-6
    coarse, fine = (np.abs(central(rel) - orbit.jacobian).max() for rel in (1e-4, 1e-5))
    assert 50 < coarse / fine < 200                                # second order towards the exact Jacobian


def test_the_steppers_orbits_converge_to_the_event_methods():
    """Backward Euler at order 1 (fitted slope of log error against log h) and theta = 0.5 to < 1e-6 V at T/400,
    on the stable period-1 orbit at 22 V (the switching instant located inside the step)."""
    p = MODEL.resolve({"Vin": 22.0})
    problem = MODEL.problem(p, MODEL.period(p))
    exact = shoot(problem, EventDriven(), warm_up=200, tol=1e-13).x0
    T = MODEL.period(p)
    steps = np.array([200, 400, 800, 1600])
    errors = [np.abs(shoot(problem, Theta(h=T / s, theta=1.0), x_guess=exact, tol=1e-12).x0 - exact).max()
              for s in steps]
    slope = np.polyfit(np.log(T / steps), np.log(errors), 1)[0]
    assert slope == pytest.approx(1.0, abs=0.05)
    assert errors[-1] < 3e-4
    trapezoidal = shoot(problem, Theta(h=T / 400, theta=0.5), x_guess=exact, tol=1e-12).x0
    assert np.abs(trapezoidal - exact).max() < 1e-6


@pytest.mark.parametrize("given, message", [
    ({"VU": 3.0}, r"VU \(ramp high level\) must be above VL = 3.8 V; got VU = 3 V"),
    ({"VL": 8.2}, r"VU \(ramp high level\) must be above VL = 8.2 V; got VU = 8.2 V"),
    ({"A": 0}, r"A \(amplifier gain of vcon = A \(vout - Vref\)\) must be in \(0, inf\); got 0"),
    ({"latch": 0.5}, r"latch must be 0 or 1; got 0.5"),
    ({"Vin": -1}, r"Vin .* must be in \(0, inf\) V; got -1"),
])
def test_bad_parameters_get_one_clear_line(given, message):
    with pytest.raises(ParameterError, match=message):
        MODEL.resolve(given)


def test_the_latch_allows_one_switching_per_period():
    """Without the latch, a fast rise of vC can cross the ramp twice in a period; with it the switch holds
    until the period ends. At 34 V (chaotic) both run; the latched run never switches twice between resets."""
    p = MODEL.resolve({"Vin": 34.0, "latch": 1})
    run = EventDriven().solve(MODEL.problem(p, 200 * MODEL.period(p), x0=[0.6, 12.0]), np.array([0.6, 12.0]))
    events = run.events
    switches = events[events["kind"] == "switch"]
    on_times = switches.loc[switches["config"] == 0, "time"].to_numpy()
    periods = np.floor(on_times / MODEL.period(p) + 1e-12)
    assert np.unique(periods).size == periods.size            # at most one turn-on per period
