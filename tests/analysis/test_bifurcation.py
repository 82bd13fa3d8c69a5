"""Brute-force diagrams on the logistic map: periods, the onset of chaos, the Lyapunov exponent, and the same
rows for any number of workers."""
import numpy as np
import pytest

from converters.analysis.bifurcation import (aperiodic_onset, brute_force, detect_period, lyapunov_interval,
                                             period_windows)
from converters.errors import ParameterError

from .maps import MapFamily, MapMethod


def logistic(values, **options):
    # x0 = 0.3: from 0.5 the map at p = 4 goes to 1, then to the fixed point 0 (exactly, in floating point)
    return brute_force(MapFamily("logistic"), MapMethod(), values, [0.3], **{"transient": 2000, "record": 128,
                                                                             "workers": 1, **options})


def test_periods_follow_the_logistic_cascade():
    # between the closed-form doublings 3, 1 + sqrt(6) = 3.44949, 3.54409 (period 4 -> 8) and past the
    # Feigenbaum point 3.569946 (chaos), away from the boundaries where convergence slows
    values = [2.8, 3.2, 3.5, 3.56, 3.58, 3.62, 3.83]
    periods = [a.period for a in logistic(values)]
    assert periods == [1, 2, 4, 8, 0, 0, 3]          # 3.83: inside the period-3 window (from 1 + sqrt(8))


@pytest.mark.slow
def test_the_aperiodic_onset_is_the_feigenbaum_point_to_the_grid_spacing():
    values = np.linspace(3.55, 3.60, 51)            # spacing 1e-3
    attractors = logistic(values, record=256, transient=20000)
    onset = aperiodic_onset(attractors)
    assert onset == pytest.approx(3.569946, abs=2e-3)
    windows = period_windows(attractors)
    assert windows[0]["period"] == 8 and windows[-1]["period"] == 0


def test_lyapunov_exponents_against_closed_forms():
    """ln 2 on the fully chaotic map (p = 4); ln |2 - p| on the stable fixed point (p = 2.5); ln |p^2 (1 - 2x1)(1 - 2x2)|/2
    on the period-2 orbit."""
    a4, a25, a32 = logistic([4.0, 2.5, 3.2], lyapunov=True, record=20000, transient=100)
    assert a4.lyapunov == pytest.approx(np.log(2.0), abs=0.02) and a4.period == 0
    assert a25.lyapunov == pytest.approx(np.log(0.5), abs=1e-9)
    p = 3.2
    x1, x2 = ((p + 1) + np.array([-1, 1]) * np.sqrt((p - 3) * (p + 1))) / (2 * p)
    assert a32.lyapunov == pytest.approx(0.5 * np.log(abs(p * p * (1 - 2 * x1) * (1 - 2 * x2))), abs=1e-6)


def test_the_lyapunov_interval_contains_the_closed_form_and_is_exact_on_an_orbit():
    """Batch means with one tangent vector carried through: at p = 4 the 95 % interval over 40 blocks of 500 steps
    contains ln 2 (its half-width 0.001); on the stable period-2 orbit (p = 3.2) every block of an even
    number of steps is the closed form, so the interval collapses to it. Bad input: one line naming it."""
    family, method = MapFamily("logistic"), MapMethod()
    chaotic = method.period_map(family(4.0))
    exponent, half, blocks = lyapunov_interval(chaotic, [0.3], 100, 40, 500)
    assert blocks.shape == (40,) and 1e-4 < half < 0.01 and abs(exponent - np.log(2.0)) <= half
    p = 3.2
    x1, x2 = ((p + 1) + np.array([-1, 1]) * np.sqrt((p - 3) * (p + 1))) / (2 * p)
    exact = 0.5 * np.log(abs(p * p * (1 - 2 * x1) * (1 - 2 * x2)))
    exponent, half, _ = lyapunov_interval(method.period_map(family(p)), [0.3], 2000, 10, 50)
    assert exponent == pytest.approx(exact, abs=1e-9) and half <= 1e-9
    with pytest.raises(ParameterError, match="blocks"):
        lyapunov_interval(chaotic, [0.3], 0, 1, 10)


def test_workers_and_chunks_give_the_same_rows():
    values = np.linspace(2.9, 3.9, 40)
    serial = logistic(values, workers=1, chunk=7, transient=300, record=32)
    parallel = logistic(values, workers=2, chunk=7, transient=300, record=32)
    for a, b in zip(serial, parallel):
        assert a.value == b.value and a.period == b.period
        assert np.array_equal(a.samples, b.samples)


def test_detect_period_and_bad_input():
    samples = np.array([[1.0], [2.0], [1.0], [2.0], [1.0], [2.0]])
    assert detect_period(samples) == 2
    assert detect_period(samples + np.array([[0], [0], [1e-3], [0], [0], [0]])) == 0
    assert detect_period(samples.ravel()) == 2 and detect_period(samples.tolist()) == 2   # a vector, a list
    for bad, message in [(None, "samples must be a numeric vector; got None"),        # IndexError before
                         ([1.0, 2.0, np.nan], "samples must contain only finite numbers; got nan at index (2,)")]:
        with pytest.raises(ParameterError) as refused:
            detect_period(bad)
        assert str(refused.value) == message
    with pytest.raises(ParameterError, match=r"rtol must be in \(0, 1\]; got -1.0"):
        detect_period(samples, rtol=-1)
    for call in (aperiodic_onset, period_windows):                                   # TypeError before
        with pytest.raises(ParameterError, match="attractors must be a list of Attractor .from brute_force.; got None"):
            call(None)
    with pytest.raises(ParameterError, match="record must be an integer >= 1"):
        logistic([3.0], record=0)
    with pytest.raises(ParameterError, match="values must be finite numbers"):
        logistic([np.nan])


def test_a_value_that_fails_is_a_row_with_its_error():
    """The map's parameter outside what a model accepts: here a problem_of that refuses negative values."""
    class Refusing(MapFamily):
        def __call__(self, value):
            if value < 0:
                raise ParameterError(f"p must be >= 0; got {value}")
            return super().__call__(value)
    rows = brute_force(Refusing("logistic"), MapMethod(), [-1.0, 2.5], [0.5], transient=40, record=4, workers=1)
    assert rows[0].error == "ParameterError: p must be >= 0; got -1.0" and rows[0].samples.size == 0
    assert rows[1].period == 1 and not rows[1].error


class _VoltageModeAt:
    """Vin -> the shipped voltage-mode buck netlist's problem (picklable: a module-level class)."""

    def __call__(self, vin):
        from pathlib import Path

        from converters.models import Circuit
        model = Circuit.from_netlist(Path(__file__).resolve().parents[2] / "netlists" / "circuits" /
                                     "voltage-mode-buck.cir")
        p = model.resolve({"Vin": vin})
        return model.problem(p, model.period(p))


def test_the_steppers_diagram_strobes_a_comparator_netlist_whose_ramp_resets_just_before_each_period():
    """The shipped voltage-mode buck's ramp resets at the middle of its fall, 5e-9 T before each period's start: the
    stepper's grid had dropped the period starts (within h/1000 of the reset) and the brute-force diagram, which
    strobes the run there, failed every value ("2 values failed", exit 0). Its period-1 attractor at 20 V is the
    exact method's orbit to the stepper's accuracy."""
    from converters.analysis.periodic import shoot
    from converters.methods import EventDriven, Theta
    problem_of = _VoltageModeAt()
    problem = problem_of(20.0)
    T = problem.switching.period
    (attractor,) = brute_force(problem_of, Theta(h=T / 1000, theta=0.5), [20.0], problem.x0, transient=200, record=8)
    exact = shoot(problem, EventDriven(), problem.x0, tol=1e-10).x0
    assert attractor.period == 1
    assert np.abs(attractor.samples - exact).max() <= 1e-6 * np.abs(exact).max()
