"""The periodic-orbit engine: exact period-map Jacobians against finite differences, Floquet multipliers,
the distance test at light loads (slowly contracting maps), and failures reported, never guessed."""
import numpy as np
import pytest

from converters.analysis.gdcm import ccm_orbit
from converters.analysis.periodic import newton_orbit, shoot
from converters.errors import SimulationError
from converters.methods import EventDriven, Theta
from converters.methods.base import FiniteDifferenceMap, PeriodMap
from converters.models import get_converter
from converters.run import run_converter, run_summary
from converters.simulate import simulate

POINTS = {"DCM buck": ("buck", {}), "GDCM Cuk": ("cuk", {"L1": "10u", "L2": "10u"})}
METHODS = {"backward Euler": lambda T: Theta(T / 1000, 1.0), "theta 0.5": lambda T: Theta(T / 1000, 0.5),
           "event": lambda T: EventDriven()}


def central_differences(end, x, rel=1e-6):
    """Central differences with steps rel (1 + |x_j|): exact on an affine piece of the map up to rounding."""
    jac = np.empty((x.size, x.size))
    for j in range(x.size):
        dx = rel * (1.0 + abs(x[j]))
        e = np.zeros(x.size)
        e[j] = dx
        jac[:, j] = (end(x + e) - end(x - e)) / (2.0 * dx)
    return jac


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("point", POINTS)
def test_exact_period_map_jacobian_and_floquet_multipliers_match_finite_differences(point, method):
    name, params = POINTS[point]
    conv = get_converter(name)
    p = conv.resolve(params)
    T = conv.period(p)
    problem = conv.problem(p, T)
    m = METHODS[method](T)
    orbit = shoot(problem, m, ccm_orbit(problem).x0, warm_up=30, tol=1e-9)
    assert orbit.converged and orbit.jacobian_kind == "exact"
    period_map = m.period_map(problem)
    for x in (orbit.x0, orbit.x0 * (1 + 1e-3)):            # on the orbit, and next to it
        _, jac = period_map(x)
        fd = central_differences(period_map.end, x)
        assert np.abs(jac - fd).max() <= 1e-6 * max(1.0, np.abs(jac).max())     # measured 1e-9 .. 3e-8
    exact = np.sort_complex(np.linalg.eigvals(orbit.jacobian))
    approx = np.sort_complex(np.linalg.eigvals(central_differences(period_map.end, orbit.x0)))
    assert np.abs(exact - approx).max() <= 1e-6
    assert orbit.stable and 0.9 < orbit.spectral_radius < 1.0
    # The held pair takes one dimension away: a multiplier at zero (the DCM's iL = 0, the GDCM's i1 + i2 = 0).
    assert np.abs(orbit.multipliers).min() < 1e-12


def test_finite_difference_maps_say_so():
    conv = get_converter("buck")
    p = conv.resolve({})
    T = conv.period(p)
    m = Theta(T / 1000, 1.0)
    fd = FiniteDifferenceMap(m.period_map(conv.problem(p, T)).end)
    orbit = newton_orbit(fd, np.zeros(2), tol=1e-8)
    assert orbit.converged and orbit.jacobian_kind == "finite differences"
    assert orbit.evaluations >= 3 * (orbit.iterations + 1)           # n + 1 spans per Jacobian


LIGHT_LOADS = {"boost": ("boost", {"D": 0.3, "L": "10u", "R": "10k"}, 1e-5),
               "cuk": ("cuk", {"D": 0.95, "L1": "1m", "L2": "1m", "R": 5}, 1e-6),
               "buck-boost": ("buck-boost", {"D": 0.7, "L": "22u", "R": "5k", "f_sw": "250k"}, 1e-6)}


@pytest.mark.parametrize("method", ["lcp", "event"])
@pytest.mark.parametrize("point", LIGHT_LOADS)
def test_steady_state_at_light_load_is_within_its_tolerance_of_the_methods_own_orbit(point, method):
    """The map contracts slowly here (1 - rho ~ 1e-5): the old cycle-to-cycle test stopped 251.885 V short
    of the boost's 252.000 V and 6.6e-5 from the Cuk's orbit. Now: within the tolerance, or a failure."""
    name, params, tol = LIGHT_LOADS[point]
    run = run_converter(name, params, method=method, steady=True, steady_tol=tol)
    orbit = run.metadata["orbit"]
    assert orbit["converged"] and orbit["distance"] <= 0.1 * tol and orbit["spectral_radius"] > 0.9998
    # The method's own orbit, 100 times tighter, found again from the other end (from rest):
    conv = get_converter(name)
    p = conv.resolve(params)
    T = conv.period(p)
    ref = shoot(conv.problem(p, T), _method(method, run), np.zeros(len(conv.state_names)), warm_up=5, tol=0.01 * tol)
    assert ref.converged and ref.distance <= 0.01 * tol
    assert np.abs(run.x[0] - ref.x0).max() / (1 + np.abs(ref.x0).max()) <= tol
    if point == "boost" and method == "lcp":
        # the stepper's own orbit (theta 0.5, h = T/1000; the exact orbit is at 260.6291 V, backward Euler's at 252.000)
        assert run_summary(run)["vout_mean"] == pytest.approx(260.7805, abs=5e-4)


def _method(key, run):
    options = run.metadata["method_options"]
    return Theta(options["h"], options["theta"]) if key == "lcp" else EventDriven(**options)


def test_steady_counts_every_period_it_simulates_and_returns_the_span_asked_for():
    run = run_converter("buck", {}, steady=True)
    orbit = run.metadata["orbit"]
    assert run.t[-1] == pytest.approx(20 * run.period)                     # 20 periods on the orbit by default
    assert run.metadata["steady_periods"] == orbit["evaluations"] + 20    # warm-up and Newton's spans included
    short = run_converter("buck", {}, steady=True, periods=3)
    assert short.t[-1] == pytest.approx(3 * short.period) and short.metadata["steady_periods"] == orbit["evaluations"] + 3


def test_a_tolerance_beyond_double_precision_is_a_clear_failure():
    with pytest.raises(SimulationError, match=r"Newton shooting did not find the periodic orbit of boost: the residual "
                                              r"is at the rounding level"):
        run_converter("boost", {"D": 0.3, "L": "10u", "R": "10k"}, steady=True, steady_tol=1e-13)


DCM_BOOST = """Boost in DCM: 12 V, 200 kHz, D 0.3, 4.7 uH, 47 uF, 100 ohm
.param Vin=12 L=4.7u C=47u R=100 f_sw=200k D=0.3
.param T={1/f_sw} e={1e-6/f_sw}
Vin in 0 DC {Vin}
Vg gate 0 PULSE(1 0 {D*T - e/2} {e} {e} {(1-D)*T - e} {T})
L1 in sw {L}
S1 sw 0 gate 0 SWMOD
D1 sw out DMOD
C1 out 0 {C}
R1 out 0 {R}
.model SWMOD SW(VT=0.5)
.model DMOD D
.tran {T/1000} {2000*T} 0 {T/200} UIC
.end
"""


def test_an_orbit_rounding_resolves_to_the_tolerance_asked_is_taken_and_a_refusal_names_that_tolerance(tmp_path):
    """Newton aims at a tenth of --steady-tol. A DCM boost's orbit (1 - rho = 2.7e-3) is resolved by rounding to
    4.6e-12: asked 1e-11 it was refused ("> tol 1e-12", a tolerance nobody asked for); it is taken now, vout
    within 4.3e-8 of the DCM closed form Vin (1 + sqrt(1 + 4 D^2 / K)) / 2, K = 2 L / (R T) (its ripple the rest).
    Asked 1e-12, it is refused, and the message names the 1e-12 asked."""
    path = tmp_path / "dcm-boost.cir"
    path.write_text(DCM_BOOST)
    run = run_converter(str(path), {}, method="event", steady=True, steady_tol=1e-11)
    assert run.metadata["orbit"]["distance"] <= 1e-11
    D, L, R, T = 0.3, 4.7e-6, 100.0, 5e-6
    closed = 12.0 * (1 + np.sqrt(1 + 4 * D * D / (2 * L / (R * T)))) / 2
    assert run.mean("vout", t0=0.0, t1=T) == pytest.approx(closed, rel=1e-7)
    with pytest.raises(SimulationError, match=r"Newton aims at a tenth of the tolerance asked, 1e-12, and takes an "
                                              r"orbit rounding resolves to that tolerance itself"):
        run_converter(str(path), {}, method="event", steady=True, steady_tol=1e-12)


class _Rotation(PeriodMap):
    """x -> R x + b with a multiplier exactly at 1: no isolated orbit."""

    def __call__(self, x0):
        self.evaluations += 1
        jac = np.array([[1.0, 0.0], [0.0, 0.5]])
        return jac @ x0 + np.array([1.0, 0.0]), jac


def test_a_non_isolated_orbit_is_reported_not_guessed():
    orbit = newton_orbit(_Rotation(), np.zeros(2))
    assert not orbit.converged and "multiplier at 1" in orbit.message


@pytest.mark.parametrize("span", [{"periods": 3}, {"t_end": 3.3337e-5}])     # whole periods; ending inside a step
def test_the_span_returned_is_the_stepper_run_from_the_orbit(span):
    """run_converter(steady=True) repeats the step plan of Newton's period map over the span asked for: the run
    is the one simulate() gives from the orbit, to the last bit."""
    run = run_converter("buck", {}, steady=True, **span)
    conv = get_converter("buck")
    p = conv.resolve({})
    ref = simulate(conv.problem(p, run.t[-1], run.x[0]), run.algorithm)
    for key in ("t", "x", "u", "y", "config"):
        np.testing.assert_array_equal(getattr(run, key), getattr(ref, key))
    assert run.events.equals(ref.events)


def test_steady_shoots_from_rest_with_no_fixed_warm_up():
    """Newton starts from rest; plain periods only where no step fraction helps (the buck: 5 periods in all)."""
    run = run_converter("buck", {}, steady=True)
    orbit = run.metadata["orbit"]
    assert orbit["converged"] and orbit["evaluations"] <= 8
    assert run.metadata["steady_periods"] == orbit["evaluations"] + 20


@pytest.mark.parametrize("kwargs,message", [
    (dict(tol=1e308), "tol must be in [1e-15, 0.1] (the distance to the orbit, in state units); got 1e+308"),
    (dict(tol=float("nan")), "tol must be in [1e-15, 0.1]"),
    (dict(tol=0.0), "tol must be in [1e-15, 0.1]"),
    (dict(warm_up=10**9), "warm_up must be an integer in [0, 100,000]; got 1000000000"),
    (dict(warm_up=-1), "warm_up must be an integer in [0, 100,000]; got -1"),
    (dict(warm_up=1.5), "warm_up must be an integer in [0, 100,000]; got 1.5"),
    (dict(periods=True), "periods must be an integer in [1, 100,000]; got True"),
    (dict(periods=1.5), "periods must be an integer in [1, 100,000]; got 1.5"),
    (dict(max_iter=-1), "max_iter must be an integer in [1, 10,000]; got -1"),
    (dict(polish="no"), "polish must be True or False; got 'no'"),
    (dict(x_guess=[0.0] * 3), "x_guess must be a vector of length 2; got shape 3"),
    (dict(x_guess=[np.nan, 0.0]), "x_guess must contain only finite numbers"),
])
def test_shooting_refuses_what_it_cannot_honour(kwargs, message):
    # tol = 1e308 had "converged" at x = (4.64, 0.378) (the orbit is (0, 6.95)); warm_up = 10^9 hung
    from converters.errors import ParameterError
    conv = get_converter("buck")
    p = conv.resolve({})
    problem = conv.problem(p, conv.period(p))
    with pytest.raises(ParameterError) as refused:
        shoot(problem, Theta(h=conv.period(p) / 200), **kwargs)
    assert str(refused.value).startswith(message)


class _LimitedMap:
    """P(x) = x / 2 (orbit 0), whose evaluations after the first ``calls`` reach a limit (the command line's alarm
    raising TimeLimitReached inside a period run), or leave the map's domain (a ParameterError)."""
    evaluations, jacobian_kind = 0, "exact"

    def __init__(self, calls, error):
        self.calls, self.error = calls, error

    def __call__(self, x):
        self.evaluations += 1
        if self.evaluations > self.calls:
            raise self.error
        return 0.5 * np.asarray(x), 0.5 * np.eye(len(x))


def test_newton_stops_on_a_limit_and_halves_a_step_out_of_the_maps_domain():
    """A trial the map refuses as out of its domain (ParameterError) is a step too long, halved; a limit reached in
    the map (ResourceError: --time-limit's alarm, the memory limit, the event method's substeps) ends the run. It was
    taken for a trial out of the domain: the alarm fired once inside the event method's period run, Newton halved its
    step, and `simulate --steady --method event --time-limit 5` on a 10 ps mode ran past 100 s."""
    from converters.errors import ParameterError, TimeLimitReached
    with pytest.raises(TimeLimitReached, match="time limit"):
        newton_orbit(_LimitedMap(1, TimeLimitReached("the time limit of 5 s")), np.ones(2))
    refused = newton_orbit(_LimitedMap(1, ParameterError("below the surface")), np.ones(2), max_iter=5)
    assert not refused.converged
    # a refusal of a mode only the trial enters (the event method's substeps, a memory estimate) is a step too long
    from converters.errors import ResourceError
    refused = newton_orbit(_LimitedMap(1, ResourceError("the stiffest mode's time constant")), np.ones(2), max_iter=5)
    assert not refused.converged


class _LatchMap(PeriodMap):
    """A 1-D map with a loop's three regions: saturated (30 <= x < 1000: x drifts down 5 a period, its multiplier
    1 - 1e-6, an integrator with the loop open), latched (x < -1e6: an affine map with its fixed point at -4e6,
    multiplier 1 - 1e-6) and regulating (x < 30: the orbit at 20, multiplier 0.5; or, with ``settles`` False, a
    drift up one a period that never settles)."""

    def __init__(self, settles=True):
        super().__init__()
        self.settles = settles

    def __call__(self, x0):
        self.evaluations += 1
        x = float(x0[0])
        if x < -1e6:
            p, j = -4e6 + (1 - 1e-6) * (x + 4e6), 1 - 1e-6
        elif x < 30:
            p, j = (0.5 * x + 10, 0.5) if self.settles else (x + 1, 1.0)
        else:
            p, j = (1 - 1e-6) * x - 5, 1 - 1e-6
        return np.array([p]), np.array([[j]])


def _latch_problem(x0):
    from types import SimpleNamespace
    return SimpleNamespace(period=1.0, t_span=(0.0, 1.0), x0=np.array([x0]), n=1)


def test_an_orbit_newton_jumps_to_stands_only_where_the_settled_transient_returns_to_it():
    """Newton from the saturated region: its step (residual / (1 - multiplier), 5e6) lands in the latched region,
    whose affine map it solves next: a fixed point the circuit would take ~2e7 periods to reach, while its
    transient settles at 20 within 32 periods. The transient's orbit is taken; a latched start's own orbit, which
    the transient does approach, stands as Newton found it (same iterations: a sweep's serial and batched engines
    agree); where the transient settles on nothing, the remote orbit comes with a warning."""
    from converters.analysis.periodic import REMOTE_PERIODS, periods_to_reach
    first = newton_orbit(_LatchMap(), np.array([100.0]), tol=1e-9)
    assert first.converged and first.x0[0] == pytest.approx(-4e6)
    assert periods_to_reach(first, np.array([100.0]), 1e-9) > REMOTE_PERIODS
    orbit = shoot(_latch_problem(100.0), None, tol=1e-9, period_map=_LatchMap())
    assert orbit.converged and orbit.x0[0] == pytest.approx(20.0) and orbit.transient == 32 and not orbit.warning
    latched = shoot(_latch_problem(-2e6), None, tol=1e-9, period_map=_LatchMap())
    direct = newton_orbit(_LatchMap(), np.array([-2e6]), tol=1e-9)
    assert latched.x0[0] == direct.x0[0] and latched.iterations == direct.iterations and not latched.warning
    assert latched.evaluations > direct.evaluations + 32                      # the transient it was checked on
    lost = shoot(_latch_problem(100.0), None, tol=1e-9, period_map=_LatchMap(settles=False))
    assert lost.converged and lost.x0[0] == pytest.approx(-4e6)
    assert "did not return to it: the circuit may settle elsewhere" in lost.warning
    assert lost.summary()["warning"] == lost.warning


@pytest.mark.parametrize("multipliers, says", [
    ([-2.00834, 0.3], "a multiplier at -2.00834): the circuit does not settle on it (a period-doubled orbit, or chaos)"),
    ([1.2, 0.5], "a multiplier at 1.2): the circuit does not settle on it (another orbit, a latch, or a runaway)"),
    ([0.957132 + 0.298j, 0.957132 - 0.298j], "a multiplier at 0.957132+0.298j): the circuit does not settle on it (a "
     "complex pair: an oscillation about it at about 4.8e+03 Hz, modulo the switching frequency")])
def test_an_unstable_orbit_is_named_by_where_its_leading_multiplier_leaves_the_unit_circle(multipliers, says):
    """A complex pair at r e^(i theta) adds an oscillation of theta / (2 pi T) (here 0.30183 rad at 100 kHz: 4804 Hz,
    a type II buck's loop against its input filter's resonance); the stepper's refusal had said "a period-doubled
    orbit, or chaos" for every multiplier."""
    from converters.analysis.periodic import instability
    why = instability(np.array(multipliers), 1e-5)
    assert says in why and why.startswith(f"unstable (Floquet spectral radius {abs(multipliers[0]):.6g}")
    assert instability(np.array([0.999, -0.5]), 1e-5) == ""


@pytest.mark.parametrize("method", ["lcp", "event"])
def test_a_circuits_orbit_is_resolved_relative_to_its_own_size(method):
    """The buck is linear in its source: its orbit from 1.2e-8 V is 1e-9 of the one from 12 V. Newton had measured
    the distance relative to 1 + max |x| (state units), so it stopped at 1e-10 V absolute: 1.5 % of the 7 nV
    output (6.8515 where 6.9529 was exact, scaled), and the --steady run warned "has not settled: use --steady"."""
    from converters.run import steady_orbit
    conv = get_converter("buck")
    big = steady_orbit(conv, conv.resolve({"Vin": 12.0}), method=method, tol=1e-12)
    for scale in (1e-5, 1e-9, 1e-12):
        small = steady_orbit(conv, conv.resolve({"Vin": 12.0 * scale}), method=method, tol=1e-12)
        np.testing.assert_allclose(small.x[0] / scale, big.x[0], rtol=1e-9, atol=1e-9 * np.abs(big.x[0]).max())
