"""The converter library against the closed-form CCM/DCM relations (Erickson and Maksimovic, ch. 5; the PRC of Siconos' PowerConverter example)."""
import numpy as np
import pytest

from converters.errors import ParameterError
from converters.models import analytic, get_converter
from converters.run import run_converter
from validation.defaults import OPERATING_POINTS, THRESHOLDS

TOLERANCE = THRESHOLDS["closed_form"]

@pytest.mark.parametrize("name,params,mode", OPERATING_POINTS)
def test_steady_state_mean_output_matches_the_conversion_ratio(name, params, mode):
    run = run_converter(name, params, steady=True)
    p = run.metadata["params"]
    assert analytic.predicted_mode(p, name) == mode
    expected = analytic.conversion_ratio(p, name) * p["Vin"]
    vout = run.mean("vout", periods=10)
    assert vout == pytest.approx(expected, rel=TOLERANCE[mode])
    # Charge balance of the output capacitor: mean current delivered equals |vout| / R (on backward Euler's run:
    # its end-point rule is the scheme's own discrete balance)
    conv = get_converter(name)
    be = run_converter(name, params, steady=True, theta=1.0)
    window = be.t >= be.t[-1] - 10 * be.period * (1 + 1e-12)
    current = conv.output_node_current(be.samples(window))
    delivered = float(np.diff(be.t[window]) @ current[1:]) / (be.t[-1] - be.t[window][0])
    assert delivered == pytest.approx(abs(be.mean("vout", periods=10)) / p["R"], rel=3e-4)
    fractions = run.mode_fractions()
    held = {"CCM": 0.0, "DCM": 0.05}[mode]
    held_fraction = fractions.get("DCM", 0.0) + fractions.get("GDCM-OFF", 0.0)
    assert (held_fraction > held) if mode == "DCM" else held_fraction == 0.0


def test_buck_dcm_idle_fraction_and_first_order_convergence():
    p = get_converter("buck").resolve({})
    _, _, idle = analytic.dcm_fractions(p, "buck")
    run = run_converter("buck", {}, steady=True)  # h = T/1000
    assert run.mode_fractions()["DCM"] == pytest.approx(idle, abs=0.01)
    # backward Euler's first order (the default's theta 0.5 is 2.6e-6 V off at T/1000: below the digits' reach)
    # The exact ideal periodic mean (the event method's orbit) is 6.962476 V; its 7 digits resolve
    # errors down to ~1e-6 V, so h stops at T/800 (error 1.9e-5 V there).
    errors = []
    hs = np.array([1e-7, 5e-8, 2.5e-8, 1.25e-8])
    for h in hs:
        run = run_converter("buck", {}, h=h, steady=True, steady_tol=1e-10, theta=1.0)
        errors.append(abs(run.mean("vout", periods=10) - 6.962476))
    order = np.polyfit(np.log(hs), np.log(errors), 1)[0]
    assert 0.8 <= order <= 1.2


def test_cuk_gdcm_appears_exactly_below_the_boundary():
    base = {"D": 0.4, "L2": "100u"}
    # Ke = L1 L2 / (L1 + L2); K = 2 Ke f / R against (1 - D)^2 = 0.36: 0.18, 0.33, 0.57, 1.0.
    for L1, expect_gdcm in (("10u", True), ("20u", True), ("40u", False), ("100u", False)):
        run = run_converter("cuk", {**base, "L1": L1}, steady=True)
        p = run.metadata["params"]
        below = analytic.k_factor(p, "cuk") < analytic.k_crit(p["D"], "cuk")
        assert below == expect_gdcm
        modes = run.modes()
        in_gdcm = modes == "GDCM-OFF"
        assert in_gdcm.any() == expect_gdcm
        if expect_gdcm:
            i1, i2 = run.state("i1")[in_gdcm], run.state("i2")[in_gdcm]
            assert np.abs(i1 + i2).max() <= 1e-9
            assert np.abs(i1).min() > 1e-3  # both currents non-zero: generalised DCM, not plain DCM


def test_boost_off_phase_holds_only_with_vc_at_least_vin():
    # GDCM in the boost OFF phase (iL held at 0) needs C (A x + E) <= 0 at iL = 0: (Vin - vC)/L <= 0.
    run = run_converter("boost", {"D": 0.3, "R": 50}, steady=True)
    held = run.modes() == "DCM"
    assert held.any()
    vin = run.metadata["params"]["Vin"]
    assert run.state("vC")[held].min() >= vin
    # From rest with vC < Vin the inductor charges through the diode even with the switch off:
    start = run_converter("boost", {"D": 0.0, "R": 50}, periods=2)
    assert (start.modes()[1:] != "DCM").all()
    assert start.state("iL")[1:].min() > 0.0


def test_prc_mean_output_over_the_last_millisecond():
    # the default: theta = 0.5, h = T/1000 = 18 ns (the Siconos settings, h = 50 ns: 0.6130 V); converged (h -> 0):
    # 0.6135 V.
    run = run_converter("prc", {}, t_end=2e-3)
    assert run.mean("vout", periods=55) == pytest.approx(0.6135, rel=2e-3)
    # The often-quoted 0.605 V is backward Euler at h = 50 ns, damped by its O(h) error:
    damped = run_converter("prc", {}, t_end=2e-3, theta=1.0, h=5e-8)
    assert damped.mean("vout", periods=55) == pytest.approx(0.605, rel=1e-2)


@pytest.mark.parametrize("name,params,match", [
    ("buck", {"L": 0}, r"L \(inductance\) must be in \(0, inf\) H; got 0.0"),
    ("buck", {"C": "-1u"}, r"C \(output capacitance\) must be in \(0, inf\) F; got -1e-06"),
    ("boost", {"R": -5}, r"R \(load resistance\) must be in \(0, inf\) ohm; got -5.0"),
    ("buck", {"D": 1.2}, r"D \(duty ratio\) must be in \[0, 1\]; got 1.2"),
    ("cuk", {"f_sw": 0}, r"f_sw \(switching frequency\) must be in \(0, inf\) Hz; got 0.0"),
    ("buck", {"Lx": 1}, r"unknown parameter 'Lx' for buck; valid names: Vin, L, C, R, f_sw, D"),
    ("buck", {"L": "10uF"}, r"L: the unit 'F' in '10uF' contradicts the parameter \(its unit is H\)"),
    ("prc", {"Lr": float("nan")}, r"Lr must be a finite number; got nan"),
])
def test_bad_parameters_are_refused(name, params, match):
    with pytest.raises(ParameterError, match=match):
        run_converter(name, params, periods=1)


def test_step_must_be_below_the_period_and_the_converter_must_exist():
    with pytest.raises(ParameterError, match=r"h must be positive and below the switching period \(1e-05 s\); got 2e-05"):
        run_converter("buck", {}, h=2e-5, periods=1)
    with pytest.raises(ParameterError, match=r"CONVERTER must be one of buck, boost, buck-boost, cuk, prc or a netlist FILE.cir; got 'sepic'"):
        run_converter("sepic", {})


@pytest.mark.parametrize("duty", [0.0, 1.0])
def test_duty_zero_and_one_are_single_configurations(duty):
    run = run_converter("buck", {"D": duty, "L": "100u"}, steady=True)
    expected = 12.0 * duty  # D = 0: decays to 0 V; D = 1: settles at Vin
    assert run.signal("vout")[-1] == pytest.approx(expected, abs=0.02)
    assert set(run.config.tolist()) == {0 if duty == 1.0 else 1}


def test_parasitics_enter_only_when_given_and_lower_the_output():
    ideal = run_converter("buck", {"L": "100u"}, steady=True)
    assert "rL" not in ideal.metadata["params"]
    lossy = run_converter("buck", {"L": "100u", "rL": 0.1, "Vf": 0.5}, steady=True)
    # CCM buck with DCR and diode drop: Vout = (D Vin - (1 - D) Vf) R / (R + rL) (volt-second balance)
    expected = (0.4 * 12 - 0.6 * 0.5) * 10 / 10.1
    assert lossy.mean("vout", periods=10) == pytest.approx(expected, rel=5e-4)
