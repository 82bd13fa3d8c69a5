"""Sinusoidal inputs (AC sources) in the stepper: each step of the period its own E and F, the same every period."""
import math

import numpy as np
import pytest

from converters.analysis.periodic import shoot
from converters.errors import ParameterError
from converters.methods import EventDriven, Theta
from converters.problems import Configuration, LCSProblem, Schedule, Sinusoids
from converters.simulate import simulate

R, C, V, F = 1e3, 1e-6, 10.0, 50.0          # an RC low-pass driven by 10 V at 50 Hz: omega R C = 0.314


def _rc(t_end: float, theta_pair=None) -> LCSProblem:
    omega = 2 * math.pi * F
    config = Configuration(A=[[-1 / (R * C)]], B=[[0.0]], C=[[0.0]], D=[[1.0]], F=[1.0])     # a pair never held
    inputs = Sinusoids(omega=[omega], phase=[0.0], E=[[[V / (R * C)]]], F=[[[0.0]]])
    return LCSProblem((config,), Schedule(period=1 / F, starts=(0.0,), configs=(0,)), x0=[0.0], t_span=(0.0, t_end),
                      inputs=inputs)


@pytest.mark.parametrize("theta, order", [(0.5, 2.0), (1.0, 1.0)])
def test_the_steppers_periodic_orbit_under_a_sinusoid_converges_to_the_exact_one_at_its_order(theta, order):
    """The exact steady state: x(0) = V (0 - omega R C) / (1 + (omega R C)^2) (the phasor's imaginary part at t = 0)."""
    T, wrc = 1 / F, 2 * math.pi * F * R * C
    exact = V * (-wrc) / (1 + wrc ** 2)
    errors = []
    for steps in (200, 400, 800):
        problem = _rc(T)
        orbit = shoot(problem, Theta(h=T / steps, theta=theta), [0.0], tol=1e-12)
        errors.append(abs(orbit.x0[0] - exact))
    rates = [math.log2(a / b) for a, b in zip(errors, errors[1:])]
    assert all(abs(rate - order) < 0.1 for rate in rates), (errors, rates)
    assert errors[-1] < (2e-5 if theta == 0.5 else 5e-3) * V


def test_a_sinusoid_must_repeat_with_the_period_and_only_the_stepper_takes_it():
    with pytest.raises(ParameterError, match="each sinusoid must repeat with the switching law's period"):
        config = Configuration(A=[[-1.0]], B=[[0.0]], C=[[0.0]], D=[[1.0]], F=[1.0])
        LCSProblem((config,), Schedule(period=0.015, starts=(0.0,), configs=(0,)), x0=[0.0], t_span=(0.0, 1.0),
                   inputs=Sinusoids(omega=[2 * math.pi * 50], phase=[0.0], E=[[[1.0]]], F=[[[0.0]]]))
    with pytest.raises(ParameterError, match="sinusoidal inputs .*use --method lcp"):
        simulate(_rc(0.02), EventDriven())
    with pytest.raises(ParameterError, match="whole steps of whole periods"):
        simulate(_rc(0.02), Theta(h=0.02 / 333.3, theta=0.5))
