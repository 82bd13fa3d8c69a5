"""Sliding-mode control of the boost (Sira-Ramirez 1987; the relay as an LCP: Acary and Brogliato 2008) on the generic core: the boost LCS with a
hysteresis law (the stepper locates each switching inside its step; the event method exactly) or the
implicit relay law (an LCP of size 3 per step), the PI outer loop with a load step, and ngspice."""
from dataclasses import replace

import numpy as np
import pytest
from scipy.linalg import expm
from scipy.optimize import brentq

from converters.analysis.periodic import autonomous_orbit
from converters.errors import ParameterError
from converters.lcp import solve_lcp
from converters.methods import EventDriven
from converters.models import get_model
from converters.models.sliding import iref0, predicted_frequency, switching_frequency
from converters.run import run_converter, run_summary
from converters.simulate import simulate
from netlists import build_smc_netlist
from validation.scenes import SCENE_DIR, load_scene

SMC = get_model("boost", "smc")
P = SMC.resolve({})          # Vin 10 V, L 1 mH, C 100 uF, R 40 ohm, Vref 20 V, band 0.05 A


def independent_cycle(Vin=10.0, L=1e-3, C=100e-6, R=40.0, iref=1.0, band=0.05):
    """The exact hysteresis cycle computed here without pcsuite: ON (iL rises at Vin/L from iref - band to
    iref + band, vC decays into R), then OFF (the diode conducts: a linear 2-state flow) until iL falls
    back to iref - band; the fixed point in vC by Brent's method; the mean by augmented matrix exponentials.
    Returns (mean vout, switching frequency)."""
    t_on = 2 * band * L / Vin
    A_off = np.array([[0.0, -1 / L, 0.0], [1 / C, -1 / (R * C), 0.0], [0.0, 0.0, 0.0]])
    A_off[0, 2] = Vin / L                                   # augmented state (iL, vC, 1)

    def off_flow(v0):
        """(time to iL = iref - band, vC there) from (iref + band, v0)."""
        x0 = np.array([iref + band, v0, 1.0])
        t_hit = brentq(lambda t: (expm(A_off * t) @ x0)[0] - (iref - band), 1e-9, 1e-3, xtol=1e-18, rtol=1e-15)
        return t_hit, (expm(A_off * t_hit) @ x0)[1]

    def cycle(v):
        v_after_on = v * np.exp(-t_on / (R * C))
        return off_flow(v_after_on)[1] - v

    v_star = brentq(cycle, 15.0, 30.0, xtol=1e-14, rtol=1e-15)
    v_on_end = v_star * np.exp(-t_on / (R * C))
    t_off, _ = off_flow(v_on_end)
    integral_on = v_star * R * C * (1 - np.exp(-t_on / (R * C)))
    # The OFF integral of vC: a fourth augmented state accumulating it.
    A4 = np.zeros((4, 4))
    A4[:3, :3] = A_off
    A4[3, 1] = 1.0
    integral_off = (expm(A4 * t_off) @ np.array([iref + band, v_on_end, 1.0, 0.0]))[3]
    period = t_on + t_off
    return (integral_on + integral_off) / period, 1.0 / period


@pytest.fixture(scope="module")
def exact_cycle():
    """The event method's exact cycle: Newton on its return map to the switch closing (a Poincare map)."""
    problem = SMC.problem(P, 1e-3, [0.95, 20.0])
    orbit = autonomous_orbit(problem, EventDriven(), [0.95, 20.0], config=0, tol=1e-13)
    assert orbit.converged and orbit.jacobian_kind == "exact"
    one = replace(simulate(SMC.problem(P, orbit.period, orbit.x0, initial=0), EventDriven()), labels=SMC.labels(P))
    return orbit, one.mean("vout"), 1.0 / orbit.period


def test_a_request_where_sliding_cannot_exist_is_refused():
    with pytest.raises(ParameterError, match=r"Vref must be above Vin = 10 V .*got Vref = 10 V"):
        SMC.resolve({"Vref": 10})
    with pytest.raises(ParameterError, match=r"Vref must be above Vin = 24 V .*got Vref = 20 V"):
        run_converter("boost", {"Vin": 24}, control="smc")
    with pytest.raises(ParameterError, match="t_step and R_step go together"):
        SMC.resolve({"t_step": "5m"})
    with pytest.raises(ParameterError, match=r"band \(hysteresis half-band on the current error\) must be in \(0, inf\)"):
        SMC.resolve({"band": 0})
    with pytest.raises(ParameterError, match=r"h must be in \(0, 5e-07\] s"):
        run_converter("boost", {}, control="smc", h=1e-6)
    with pytest.raises(ParameterError, match="Vref"):
        build_smc_netlist({"Vref": "20\n.control\nshell touch /tmp/x\n.endc"}, 1e-3)
    with pytest.raises(ParameterError, match=r"--periods does not apply to boost --control smc"):
        run_converter("boost", {}, control="smc", periods=3)


def test_the_event_method_gives_the_exact_hysteresis_cycle(exact_cycle):
    orbit, v_mean, frequency = exact_cycle
    # Measured independently (scipy expm and brentq, above): 20.000203 V, 50 001.6 Hz.
    v_ind, f_ind = independent_cycle()
    assert v_mean == pytest.approx(20.000203, abs=5e-7) and frequency == pytest.approx(50001.6, abs=0.05)
    assert v_mean == pytest.approx(v_ind, rel=1e-10) and frequency == pytest.approx(f_ind, rel=1e-10)
    assert orbit.residual < 1e-12
    # The cycle is attracting (one multiplier from the slow output dynamics, the other 0: the section).
    assert 0.9 < orbit.spectral_radius < 1.0
    # A plain event-driven run from the cycle stays on it to 1e-8 over 100 cycles.
    run = run_converter(SMC, P, method="event", t_end=100 / frequency, x0=orbit.x0)
    assert run.mean("vout", t0=0.0) == pytest.approx(v_mean, rel=1e-8)
    assert switching_frequency(run, 0.0) == pytest.approx(frequency, rel=1e-8)


def test_the_stepper_converges_to_the_exact_cycle_at_first_order(exact_cycle):
    orbit, v_exact, f_exact = exact_cycle
    period = 1.0 / f_exact
    divisions = np.array([100, 200, 400, 800])
    v_err, f_err = [], []
    for div in divisions:
        run = run_converter(SMC, P, h=period / div, t_end=200 * period, x0=orbit.x0)
        v_err.append(abs(run.mean("vout", t0=20 * period) / v_exact - 1.0))
        f_err.append(abs(switching_frequency(run, 20 * period) / f_exact - 1.0))
    hs = period / divisions
    v_order = np.polyfit(np.log(hs), np.log(v_err), 1)[0]
    f_order = np.polyfit(np.log(hs), np.log(f_err), 1)[0]
    assert v_order >= 0.9 and f_order >= 0.9           # measured 1.00 and 0.99
    assert v_err[-1] < 5e-5 and f_err[-1] < 5e-5


def test_hysteresis_controller_regulates_and_switches_at_the_predicted_frequency():
    run = run_converter(SMC, P, t_end=30e-3)
    s = run_summary(run)
    assert s["vout_mean"] == pytest.approx(20.0, rel=1e-4)                  # Iref = Vref^2/(R Vin) = 1 A
    assert s["switching_frequency_Hz"] == pytest.approx(predicted_frequency(P, s["vout_mean"]), rel=1e-3)
    assert s["switching_frequency_Hz"] == pytest.approx(50e3, rel=1e-3)
    # Switching instants are placed inside the step: the current turns exactly at Iref +- band.
    w = run.t >= 28e-3
    assert run.state("iL")[w].max() == pytest.approx(iref0(P) + 0.05, abs=2e-6)
    assert run.state("iL")[w].min() == pytest.approx(iref0(P) - 0.05, abs=2e-6)
    assert not run.active[:, 0].any()   # the diode never blocks a current: no DCM under this control


def test_switching_frequency_does_not_depend_on_the_step_beyond_its_own_accuracy():
    """With the crossing placed inside the step, h = T_sw/100 already gives the frequency to 1e-3."""
    f = [switching_frequency(run_converter(SMC, P, h=h, t_end=20e-3), 18e-3) for h in (2e-7, 1e-7, 2e-8)]
    assert max(f) / min(f) - 1.0 < 1e-3


@pytest.mark.parametrize("control, measure", [("smc", "switching_frequency_Hz"), ("smc-implicit", "lambda_mean")])
def test_the_summary_says_how_accurate_its_measures_are_and_the_estimate_is_first_order(control, measure):
    """run_summary's accuracy for a model without a fixed period: the same run at 2h estimates the error at h as
    |Q(h) - Q(2h)|; backward Euler is first order, so the distance to the run at h/4 is 3/4 of that (measured
    0.746-0.751 on both laws)."""
    model = get_model("boost", control)
    run = run_converter(model, P, t_end=10e-3, theta=1.0)      # backward Euler (theta 0.5: 0.32, a safe estimate)
    s = run_summary(run)
    h = run.algorithm.h
    fine = run_summary(run_converter(model, P, t_end=10e-3, h=h / 4, theta=1.0))
    estimates = s["accuracy"]["estimates"]
    for name in ("vout_mean", measure):
        ratio = abs(s[name] - fine[name]) / abs(fine[name]) / estimates[name]["discretization"]
        assert 0.6 <= ratio <= 0.9, (name, ratio)
    # the window's measurements: vout's mean is the summary's; iL swings by the hysteresis band 2 x 0.05 A, or
    # (implicit relay) sits on Iref = Vref^2 / (R Vin) = 1 A without chatter
    iL = s["measurements"]["iL"]
    assert s["measurements"]["vout"]["mean"] == pytest.approx(s["vout_mean"], rel=1e-12) and iL["unit"] == "A"
    if control == "smc":
        assert iL["ripple"] == pytest.approx(2 * P["band"], abs=1e-5)
    else:
        assert iL["ripple"] <= 1e-9 and iL["mean"] == pytest.approx(1.0, abs=1e-9)


def test_a_run_that_has_not_settled_says_so():
    short = run_summary(run_converter(SMC, P, t_end=5e-3))   # vout still rising towards Vref: 19.07 V at 5 ms
    transient = short["accuracy"]["estimates"]["vout_mean"]["transient"]
    assert transient > 1e-2
    assert short["warnings"] == [f"vout_mean may be {short['accuracy']['estimates']['vout_mean']['error_estimate']:.1e} "
                                 "off (relative; more than 0.001): the run has not settled: use a longer --t-end"]
    settled = run_summary(run_converter(SMC, P, t_end=30e-3))
    assert settled["accuracy"]["estimates"]["vout_mean"]["error_estimate"] < 1e-4 and "warnings" not in settled
    exact = run_summary(run_converter(SMC, P, t_end=5e-3, method="event"))    # exact flows: the transient only
    assert exact["accuracy"]["estimates"]["vout_mean"]["discretization"] is None
    assert exact["accuracy"]["estimates"]["vout_mean"]["transient"] == pytest.approx(transient, rel=0.05)


def test_implicit_relay_step_is_the_reference_lcp_and_the_clip_formula():
    rng = np.random.default_rng(5)
    Vin, L, h = 10.0, 1e-3, 1e-6
    for _ in range(50):
        i, v, iref = rng.uniform(0.5, 1.5), rng.uniform(11, 30), rng.uniform(0.5, 1.5)
        m, q = h * v / L, -(i + h * Vin / L - iref)
        # the relay as an LCP (Acary and Brogliato 2008): M' = [[M, I], [-I, 0]], q' = [q + M lb; ub - lb] with lb = 0, ub = 1.
        result = solve_lcp(np.array([[m, 1.0], [-1.0, 0.0]]), np.array([q, 1.0]), method="lemke")
        assert result.solved
        clip = np.clip((i + h * Vin / L - iref) * L / (h * v), 0.0, 1.0)
        assert result.z[0] == pytest.approx(clip, abs=1e-12)


def test_implicit_variant_settles_at_vin_over_v_without_chatter():
    implicit = get_model("boost", "smc-implicit")
    run = run_converter(implicit, P, t_end=30e-3)
    s = implicit.summary(run, P, 2e-3)
    assert abs(s["lambda_mean"] - s["vin_over_v"]) <= 1e-6
    assert s["lambda_spread"] <= 1e-6                                     # no switching chatter
    lam = 1.0 - run.signal("switch")[run.t >= 28e-3]
    assert ((lam > 0.0) & (lam < 1.0)).all()                               # inside the band, not on a bound
    assert s["vout_mean"] == pytest.approx(20.0, rel=5e-3)
    assert run.relay is not None and run.method == "lcp"


def test_pi_loop_restores_vref_after_the_load_halves():
    p = {"Ki": 100, "t_step": 15e-3, "R_step": 20}
    for control in ("smc", "smc-implicit"):
        model = get_model("boost", control)
        run = run_converter(model, p, t_end=40e-3)
        s = model.summary(run, run.metadata["params"], 2e-3)
        assert s["vout_mean"] == pytest.approx(20.0, rel=1e-3)
        assert 5e-3 < s["recovery_time_s"] < 15e-3
        assert run.state_names == ("iL", "vC", "z")                        # the PI integral is a state
    # Without the integral the current reference stays at Vref^2/(R Vin): v falls to sqrt(Iref R_step Vin).
    plain = run_converter(SMC, {"t_step": 15e-3, "R_step": 20}, t_end=40e-3)
    assert SMC.summary(plain, plain.metadata["params"], 2e-3)["vout_mean"] == pytest.approx(np.sqrt(1.0 * 20 * 10),
                                                                                          rel=2e-3)


@pytest.mark.usefixtures("ngspice")
@pytest.mark.parametrize("name", ["boost-smc", "boost-smc-load-step", "boost-smc-implicit"])
def test_sliding_mode_scenes_pass_in_both_simulators(name):
    from validation.suite import run_scene
    result = run_scene(load_scene(SCENE_DIR / f"{name}.toml"))
    assert result.ok, result.reason
    m = result.metrics
    if name == "boost-smc-implicit":
        assert m["lambda_minus_vin_over_v"] <= 1e-6 and m["lambda_spread"] <= 1e-6
        return
    assert m["vout_ref_rel_lcp"] <= 5e-3 and m["vout_ref_rel_spice"] <= 5e-3
    assert m["frequency_rel_lcp"] <= 0.05 and m["frequency_rel_spice"] <= 0.05
    assert m["frequency_lcp_vs_spice"] <= 0.05
    if name == "boost-smc-load-step":
        assert np.isfinite(m["recovery_lcp_s"]) and np.isfinite(m["recovery_spice_s"])
        assert m["recovery_lcp_vs_spice"] <= 0.1
