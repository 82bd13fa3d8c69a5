"""The method contract: every registered method validates its options, declares its order, solves the
closed-form reference problems into Trajectories, and converges at the order it declares."""
import math
import subprocess
import sys

import numpy as np
import pytest

from converters.errors import ParameterError
from converters.methods import METHODS, EventDriven, Method, Smoothing, Theta
from converters.methods.base import ErrorKind, load_methods
from converters.problems import Configuration, LCSProblem, Schedule
from converters.simulate import simulate
from converters.trajectory import Trajectory

L, R, V, I0 = 1e-3, 1.0, 1.0, 1.0
T_STAR = L / R * math.log(1 + R * I0 / V)        # the freewheeling current reaches zero here (0.693 ms)


def freewheel(t_end):
    """An inductor current i0 decaying through R against V, freewheeling through a diode that blocks when it
    reaches zero: L i' = -R i - V + u, 0 <= u _|_ i >= 0 (u: the diode's reverse voltage; D = 0)."""
    config = Configuration(A=[[-R / L]], B=[[1 / L]], C=[[1.0]], D=[[0.0]], E=[-V / L], name="freewheel")
    return LCSProblem((config,), Schedule.constant(), x0=[I0], t_span=(0.0, t_end), state_names=("i",),
                      pair_names=("diode",))


def freewheel_exact(t):
    t = np.asarray(t, dtype=float)
    return np.where(t < T_STAR, (I0 + V / R) * np.exp(-R * t / L) - V / R, 0.0)


def switched_rc(t_end=1.0):
    """An RC charged through a switch for half of each 1 s period (a pair that never acts: y = 1)."""
    idle = dict(B=[[0.0]], C=[[0.0]], D=[[0.0]], F=[1.0])
    on = Configuration(A=[[-1.0]], E=[1.0], name="on", **idle)
    off = Configuration(A=[[-1.0]], name="off", **idle)
    return LCSProblem((on, off), Schedule.pwm(1.0, 0.5), x0=[0.0], t_span=(0.0, t_end))


RC_EXACT = (1 - math.exp(-0.5)) * math.exp(-0.5)


def test_the_registry_holds_every_method_by_its_command_line_name():
    from validation.ngspice import Spice            # ngspice: an entry point above the core
    assert list(load_methods()) == ["lcp", "event", "smooth", "moreau", "spice"] and METHODS["spice"] is Spice
    assert [cls.key for cls in METHODS.values()] == list(METHODS)
    assert all(issubclass(cls, Method) and cls.description for cls in METHODS.values())
    assert Theta(1e-6, 1.0).order == 1 and Theta(1e-6, 0.5).order == 2
    assert EventDriven().order == math.inf and Smoothing().order == 1 and METHODS["moreau"](h=1e-3).order == 1
    assert {key: cls.domains for key, cls in METHODS.items()} == {
        "lcp": ("lcs",), "event": ("lcs", "mechanical"), "smooth": ("lcs",), "moreau": ("mechanical",),
        "spice": ("circuit",)}
    # how each one's error is estimated: what the accuracy checks read instead of a key (typed, and its traits)
    assert {key: cls.error_kind for key, cls in METHODS.items()} == {
        "lcp": ErrorKind.STEP, "event": ErrorKind.EXACT, "smooth": ErrorKind.MODEL, "moreau": ErrorKind.STEP,
        "spice": ErrorKind.MODEL}
    assert {key: (cls.fixed_step, cls.exact) for key, cls in METHODS.items()} == {
        "lcp": (True, False), "event": (False, True), "smooth": (False, False), "moreau": (True, False),
        "spice": (False, False)}
    assert Theta(1e-6, 0.5).coarsened() == Theta(2e-6, 0.5) and Theta(1e-6, 1.0).step == 1e-6
    with pytest.raises(ValueError, match="no fixed step"):
        EventDriven().coarsened()


def test_a_backend_registered_as_an_entry_point_loads_on_first_use_by_name():
    """ngspice is a method like the others: get_method("spice") in a process that never imported validation loads
    it from the package's entry points (before, it existed only once validation.ngspice had been imported)."""
    code = ("import sys; from converters.methods.base import METHODS, get_method; "
            "assert 'spice' not in METHODS and 'validation.ngspice' not in sys.modules; "
            "print(get_method('spice').__module__, list(METHODS))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "validation.ngspice ['lcp', 'event', 'smooth', 'moreau', 'spice']"


@pytest.mark.parametrize("key,options,match", [
    ("lcp", {"eps": 1e-3}, r"unknown option 'eps' for method 'lcp'; valid options: h, theta"),
    ("event", {"h": 1e-6}, r"unknown option 'h' for method 'event'; valid options: event_tol, sample_fraction"),
    ("smooth", {"theta": 0.5}, r"unknown option 'theta' for method 'smooth'; valid options: eps, solver_rtol, atol"),
])
def test_no_method_swallows_an_unknown_option(key, options, match):
    with pytest.raises(ParameterError, match=match):
        METHODS[key].from_options(step=1e-6, **options)


@pytest.mark.parametrize("make", [lambda: Theta(1e-5, 1.0), lambda: Theta(1e-5, 0.5), lambda: EventDriven(),
                                  lambda: Smoothing(eps=1e-4, solver_rtol=1e-10)], ids=["backward-euler", "theta-0.5",
                                                                                 "event", "smooth"])
def test_every_method_solves_the_freewheeling_diode_into_a_trajectory(make):
    method = make()
    tr = simulate(freewheel(1.5e-3), method)
    assert isinstance(tr, Trajectory) and tr.method == method.key and tr.state_names == ("i",)
    assert tr.t[0] == 0.0 and tr.t[-1] == pytest.approx(1.5e-3)
    # The diode blocks at T_STAR: every method holds the current at zero after it (smoothing: at -eps V).
    after = tr.t > T_STAR + 2e-5
    assert np.abs(tr.x[after, 0]).max() <= (2e-4 if method.key == "smooth" else 1e-12)
    activate = tr.events[tr.events["kind"] == "activate"]
    assert len(activate) == 1 and activate["time"].iloc[0] == pytest.approx(T_STAR, abs=1e-5)


@pytest.mark.parametrize("theta", [1.0, 0.5])
@pytest.mark.parametrize("problem,exact", [(lambda: freewheel(0.5e-3), float(freewheel_exact(0.5e-3))),
                                           (switched_rc, RC_EXACT)], ids=["freewheel", "switched-rc"])
def test_the_stepper_converges_at_its_declared_order(theta, problem, exact):
    method_of = (lambda h: Theta(h, theta))
    span = problem().t_span[1]
    hs = span / 2.0 ** np.arange(6, 11)
    errors = [abs(simulate(problem(), method_of(h)).x[-1, 0] - exact) for h in hs]
    order = np.polyfit(np.log(hs), np.log(errors), 1)[0]
    assert order == pytest.approx(method_of(hs[0]).order, abs=0.15)


def test_smoothing_converges_at_its_declared_order_in_eps():
    eps = np.array([1e-2, 1e-3, 1e-4])
    errors = [abs(simulate(freewheel(1.5e-3), Smoothing(eps=e, solver_rtol=1e-10)).x[-1, 0]) for e in eps]
    order = np.polyfit(np.log(eps), np.log(errors), 1)[0]
    assert order == pytest.approx(Smoothing().order, abs=0.1)              # held at i = -eps V: O(eps)
    assert errors[1] == pytest.approx(1e-3 * V, rel=0.05)


@pytest.mark.parametrize("problem,exact", [(lambda: freewheel(0.5e-3), float(freewheel_exact(0.5e-3))),
                                           (lambda: freewheel(1.5e-3), 0.0), (switched_rc, RC_EXACT)],
                         ids=["freewheel", "freewheel-blocked", "switched-rc"])
@pytest.mark.parametrize("event_tol", [1e-13, 1e-7])
def test_the_event_method_is_exact_whatever_its_tolerance(problem, exact, event_tol):
    """Declared order inf: the error is rounding, and the tolerance sets only where the event is placed."""
    tr = simulate(problem(), EventDriven(event_tol=event_tol))
    assert abs(tr.x[-1, 0] - exact) <= 1e-12
    times = [event[0] for event in tr.exact.event_list()]
    if times:
        assert times[0] == pytest.approx(T_STAR, abs=2 * event_tol * 1.5e-3 + 1e-16)
