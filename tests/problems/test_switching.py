"""State-driven switching laws as problem data: hysteresis, ramp with latch, the implicit relay; their
validation, and the stepper and the event method against closed forms."""
import numpy as np
import pytest

from converters.errors import ParameterError
from converters.methods import EventDriven, Smoothing, Theta
from converters.problems import (Comparators, Configuration, LCSProblem, Ramp, Relay, StateSwitching,
                                 SwitchingFunction)
from converters.simulate import simulate

#: A complementarity pair that never acts (y = 1 > 0, so u = 0): these problems are switched, not complementary.
IDLE = dict(B=[[0.0], [0.0]], C=[[0.0, 0.0]], D=[[0.0]], F=[1.0])


def relaxation_oscillator(band=0.25, t_end=5.0, method_latch=False):
    """x' = +1 in 'up' (entered when x falls below -band), -1 in 'down' (above +band); z counts time in 'up'.
    Closed form: a triangle wave between -band and +band of period 4 band."""
    up = Configuration(A=np.zeros((2, 2)), E=[1.0, 1.0], name="up", **IDLE)
    down = Configuration(A=np.zeros((2, 2)), E=[-1.0, 0.0], name="down", **IDLE)
    law = StateSwitching(SwitchingFunction(c=[1.0, 0.0]), below=0, above=1, band=band)
    return LCSProblem((up, down), law, x0=[0.0, 0.0], t_span=(0.0, t_end), state_names=("x", "z"))


@pytest.mark.parametrize("method", [Theta(0.01, 1.0), Theta(0.01, 0.5), EventDriven()], ids=["BE", "theta", "event"])
def test_hysteresis_switches_exactly_at_the_band(method):
    """The dynamics are piecewise linear in time, so the stepper's interpolated crossing is exact too."""
    tr = simulate(relaxation_oscillator(), method)
    switches = tr.events[tr.events["kind"] == "switch"]
    # x0 = 0: s = 0 is not negative, so 'down' first; -band is reached at 0.25, then a switch every 2 band.
    times = switches["time"].to_numpy()
    expected = 0.25 + 0.5 * np.arange(times.size)
    np.testing.assert_allclose(times, expected, atol=1e-12)
    assert switches["config"].tolist()[:3] == [0, 1, 0]
    assert np.abs(tr.state("x")).max() <= 0.25 + 1e-12
    assert times.size == 10
    assert tr.state("z")[-1] == pytest.approx(2.5, abs=1e-9)          # up on [0.25 + m, 0.75 + m], m = 0..4


def ramp_latch(level=0.3, latch=True, periods=4):
    """A constant level c compared with a unit sawtooth: 'below' (z' = 1) once the ramp passes c, until the
    period ends; closed form: z grows by 1 - c per period."""
    hold = Configuration(A=np.zeros((2, 2)), E=[0.0, 1.0], name="below", **IDLE)
    idle = Configuration(A=np.zeros((2, 2)), E=[0.0, 0.0], name="above", **IDLE)
    law = StateSwitching(SwitchingFunction(c=[1.0, 0.0], ramp=Ramp(0.0, 1.0, 1.0)), below=0, above=1, latch=latch)
    return LCSProblem((hold, idle), law, x0=[level, 0.0], t_span=(0.0, float(periods)), state_names=("c", "z"))


@pytest.mark.parametrize("latch", [True, False])
@pytest.mark.parametrize("method", [Theta(1e-3, 1.0), EventDriven()], ids=["BE", "event"])
def test_a_ramp_resets_every_period_and_a_latch_holds_one_switching(method, latch):
    tr = simulate(ramp_latch(0.3, latch), method)
    assert tr.state("z")[-1] == pytest.approx(4 * 0.7, abs=1e-9)
    switches = tr.events[tr.events["kind"] == "switch"]
    into_below = switches.loc[switches["config"] == 0, "time"].to_numpy()
    np.testing.assert_allclose(into_below, 0.3 + np.arange(4), atol=1e-9)
    # Every reset back to 'above' is a switching event too, in both methods.
    np.testing.assert_allclose(switches.loc[switches["config"] == 1, "time"], np.arange(1, 4), atol=1e-12)


@pytest.mark.parametrize("method", [Theta(1e-3, 1.0), EventDriven()], ids=["BE", "event"])
def test_the_ramp_phase_counts_from_t_zero_whatever_the_start(method):
    """ramp(t) = low + slope (t mod T): a run from t = 0.5 is in the middle of a ramp period."""
    from dataclasses import replace
    tr = simulate(replace(ramp_latch(0.3, True), t_span=(0.5, 4.0)), method)
    assert tr.state("z")[-1] == pytest.approx(0.5 + 3 * 0.7, abs=1e-9)
    switches = tr.events[tr.events["kind"] == "switch"]
    np.testing.assert_allclose(switches["time"].to_numpy()[:4], [1.0, 1.3, 2.0, 2.3], atol=1e-9)


IDLE3 = dict(B=[[0.0]] * 3, C=[[0.0] * 3], D=[[0.0]], F=[1.0])


def two_oscillators(t_end=2.0):
    """Two relaxation oscillators on one law: x' = +-1 switched by channel 0 at x = -+0.25, w' = +-2 by channel 1
    at w = -+0.1; z' = 1 while both are up (the table's one configuration of both channels below). Closed form:
    x turns at 0.25 + 0.5 m, w at 0.05 + 0.1 m."""
    configs = []
    for bits in range(4):
        up0, up1 = not bits & 1, not bits & 2
        configs.append(Configuration(A=np.zeros((3, 3)), E=[1.0 if up0 else -1.0, 2.0 if up1 else -2.0,
                                                            float(up0 and up1)], name=f"c{bits}", **IDLE3))
    channels = (StateSwitching(SwitchingFunction(c=[1.0, 0.0, 0.0]), below=0, above=1, band=0.25),
                StateSwitching(SwitchingFunction(c=[0.0, 1.0, 0.0]), below=0, above=1, band=0.1))
    return LCSProblem(tuple(configs), Comparators(channels, table=(0, 1, 2, 3)), x0=[0.0, 0.0, 0.0],
                      t_span=(0.0, t_end), state_names=("x", "w", "z"))


@pytest.mark.parametrize("method", [Theta(0.01, 1.0), Theta(0.003, 0.5), EventDriven()], ids=["BE", "theta", "event"])
def test_several_comparators_switch_each_at_its_own_band(method):
    tr = simulate(two_oscillators(), method)
    switches = tr.events[tr.events["kind"] == "switch"]
    times = np.sort(switches["time"].to_numpy())
    expected = np.sort(np.concatenate([0.25 + 0.5 * np.arange(4), 0.05 + 0.1 * np.arange(20)]))
    np.testing.assert_allclose(times, expected, atol=1e-12)
    assert np.abs(tr.state("x")).max() <= 0.25 + 1e-12 and np.abs(tr.state("w")).max() <= 0.1 + 1e-12
    # z: x rises on [0.25, 0.75] and [1.25, 1.75], w on [0.05, 0.15] + 0.2 m: both on three 0.1-long pieces of
    # each, 0.6 in all (piecewise-linear states: exact to rounding)
    assert tr.state("z")[-1] == pytest.approx(0.6, abs=1e-12)


def two_phase_ramps(level=0.3, periods=4):
    """Two latched ramp comparators on one level, the second's ramp delayed by half a period: z1' = 1 while
    channel 0 is below (after its ramp passes the level), z2' = 1 while channel 1 is. Closed form: channel 0
    enters below at 0.3 + m, channel 1 at 0.8 + m; channel 1 starts below (its ramp at 0.5 > 0.3)."""
    configs = [Configuration(A=np.zeros((3, 3)), E=[0.0, float(not bits & 1), float(not bits & 2)],
                             name=f"c{bits}", **IDLE3) for bits in range(4)]
    channels = tuple(StateSwitching(SwitchingFunction(c=[1.0, 0.0, 0.0], ramp=Ramp(0.0, 1.0, 1.0, delay=delay)),
                                    below=0, above=1, latch=True) for delay in (0.0, 0.5))
    return LCSProblem(tuple(configs), Comparators(channels, table=(0, 1, 2, 3)), x0=[level, 0.0, 0.0],
                      t_span=(0.0, float(periods)), state_names=("c", "z1", "z2"))


@pytest.mark.parametrize("method", [Theta(1e-3, 1.0), EventDriven()], ids=["BE", "event"])
def test_interleaved_ramps_each_reset_at_their_own_delay(method):
    problem = two_phase_ramps()
    assert problem.switching.period == 1.0
    tr = simulate(problem, method)
    assert tr.state("z1")[-1] == pytest.approx(4 * 0.7, abs=1e-9)
    assert tr.state("z2")[-1] == pytest.approx(0.5 + 3 * 0.7 + 0.2, abs=1e-9)
    switches = tr.events[tr.events["kind"] == "switch"]
    times = np.sort(switches["time"].to_numpy())
    # channel 0: below at 0.3 + m, reset above at 1, 2, 3; channel 1: reset above at 0.5 + m, below at 0.8 + m
    expected = np.sort(np.concatenate([0.3 + np.arange(4), np.arange(1, 4), 0.5 + np.arange(4), 0.8 + np.arange(4)]))
    np.testing.assert_allclose(times, expected, atol=1e-9)


def test_the_relay_holds_the_sliding_surface_without_chatter():
    """x' = -1 + 2 z, z in [0, 1], -(x - 1/2) in N_[0,1](z): x rises at +1 to 1/2 and stays there with the
    equivalent control z = 1/2 (no switching)."""
    low = Configuration(A=np.zeros((2, 2)), E=[-1.0, 0.0], name="low", **IDLE)
    high = Configuration(A=np.zeros((2, 2)), E=[1.0, 0.0], name="high", **IDLE)
    problem = LCSProblem((low, high), Relay(SwitchingFunction(c=[1.0, 0.0], d=-0.5), low=0, high=1), x0=[0.0, 0.0],
                         t_span=(0.0, 1.0), state_names=("x", "z"))
    tr = simulate(problem, Theta(1e-3, 1.0))
    settled = tr.t > 0.502
    assert np.abs(tr.state("x")[settled] - 0.5).max() < 1e-12
    assert np.abs(tr.relay[settled] - 0.5).max() < 1e-12
    assert tr.relay[tr.t < 0.499].min() == 1.0                       # full on until the surface is reached
    for method, match in ((EventDriven(), "the implicit relay is a time-stepping scheme"),
                          (Smoothing(), "the smoothing method integrates time schedules only")):
        with pytest.raises(ParameterError, match=match):
            simulate(problem, method)


@pytest.mark.parametrize("build,match", [
    (lambda: StateSwitching(SwitchingFunction([1.0]), below=0, above=0), "below and above must be different"),
    (lambda: StateSwitching(SwitchingFunction([1.0]), below=0, above=1, band=-1), r"band \(hysteresis half-width\) must be >= 0"),
    (lambda: StateSwitching(SwitchingFunction([1.0]), below=0, above=1, latch=True), "latch needs a ramp"),
    (lambda: StateSwitching(SwitchingFunction([1.0], ramp=Ramp(0, 1, 1)), below=0, above=1, clocked=True),
     r"clocked needs latch"),
    (lambda: StateSwitching(SwitchingFunction([1.0], ramp=Ramp(0, 1, 1)), below=0, above=1, latch=True, clocked="y"),
     r"clocked must be True or False; got 'y'"),
    (lambda: StateSwitching(SwitchingFunction([1.0], ramp=Ramp(0, 1, 1)), below=0, above=1, latch=True, limit=1.0),
     r"limit .* must be in \(0, 1\) on a latched law; got 1.0"),
    (lambda: StateSwitching(SwitchingFunction([1.0], ramp=Ramp(0, 1, 1)), below=0, above=1, limit=0.5),
     r"on a latched law; got 0.5 without latch"),
    (lambda: StateSwitching(SwitchingFunction([1.0]), below=0, above=1, initial=2), r"initial must be below \(0\) or above \(1\)"),
    (lambda: Relay(SwitchingFunction([1.0], ramp=Ramp(0, 1, 1)), low=0, high=1), "without a ramp"),
    (lambda: Ramp(0.0, 1.0, 0.0), r"ramp period must be positive"),
    (lambda: Ramp(0.0, 1.0, 1.0, delay=1.0), r"ramp delay must be in \[0, period = 1\) s; got 1.0"),
    (lambda: Comparators((StateSwitching(SwitchingFunction([1.0]), below=0, above=1),), table=(0, 1)),
     "channels must hold 2 to 8"),
    (lambda: Comparators((StateSwitching(SwitchingFunction([1.0]), below=1, above=0),) * 2, table=(0, 1, 2, 3)),
     r"channels\[0\] must be a StateSwitching with below=0, above=1"),
    (lambda: Comparators((StateSwitching(SwitchingFunction([1.0]), below=0, above=1),) * 2, table=(0, 1, 2)),
     r"table must have 2\^2 = 4 entries"),
    (lambda: Comparators(tuple(StateSwitching(SwitchingFunction([1.0], ramp=Ramp(0, 1, p)), below=0, above=1)
                               for p in (1.0, np.pi)), table=(0, 1, 2, 3)), "have no common period"),
    (lambda: SwitchingFunction([np.nan]), "must contain only finite numbers"),
    (lambda: StateSwitching(SwitchingFunction([1.0]), below=-1, above=1), r"below must be a configuration index"),
])
def test_switching_laws_refuse_bad_definitions(build, match):
    with pytest.raises(ParameterError, match=match):
        build()


def test_a_problem_checks_its_law_against_its_configurations():
    one = Configuration(A=np.zeros((2, 2)), name="one", **IDLE)
    with pytest.raises(ParameterError, match=r"switching configs must be indices in \[0, 0\]; got 1"):
        LCSProblem((one,), StateSwitching(SwitchingFunction([1.0, 0.0]), below=0, above=1), x0=[0, 0], t_span=(0, 1))
    with pytest.raises(ParameterError, match=r"one coefficient per state \(n = 2\); got 3"):
        LCSProblem((one, one), StateSwitching(SwitchingFunction([1.0, 0.0, 0.0]), below=0, above=1), x0=[0, 0],
                   t_span=(0, 1))


def test_a_jump_at_a_state_driven_switching_enters_the_exact_jacobian():
    """Switching into a configuration whose diode is violated (y = b - 1 < 0) makes the state jump; the
    period map's Jacobian carries the jump's projection with the saltation (checked against differences)."""
    from converters.methods.base import FiniteDifferenceMap
    A = np.array([[0.0, 0.0], [0.0, -1.0]])
    below = Configuration(A=A, B=[[0.0], [1.0]], C=[[0.0, 1.0]], D=[[0.0]], E=[1.0, 0.0], F=[0.0], name="below")
    above = Configuration(A=A, B=[[0.0], [1.0]], C=[[0.0, 1.0]], D=[[0.0]], E=[-1.0, 2.0], F=[-1.0], name="above")
    law = StateSwitching(SwitchingFunction(c=[1.0, 0.0]), below=0, above=1, band=0.25)
    problem = LCSProblem((below, above), law, x0=[0.1, 0.2], t_span=(0.0, 0.9), state_names=("a", "b"))
    assert "impulse" in set(simulate(problem, EventDriven()).events["kind"])
    period_map = EventDriven().period_map(problem)
    _, jac = period_map(np.array([0.1, 0.2]))
    _, fd = FiniteDifferenceMap(period_map.end)(np.array([0.1, 0.2]))
    np.testing.assert_allclose(jac, fd, atol=1e-6)
    assert jac[1, 0] == pytest.approx(-0.951229, abs=1e-6)
