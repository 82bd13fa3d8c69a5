"""GDCM: the general single-diode condition from the matrices, the exact and closed-form
predictions, LCP and ngspice mode detection, D-K maps and the Cuk's reduced dynamics."""
import json

import numpy as np
import pytest
from scipy.linalg import expm

from converters.analysis import gdcm
from converters.models import analytic
from converters.analysis.modes import mode_intervals
from converters.run import steady_orbit
from converters.errors import ParameterError
from converters.models import get_converter
from validation.gdcm import BOUNDARY_BAND, dk_map, gdcm_check, map_summary


def test_general_condition_reproduces_the_cuk_formulas_of_the_reference():
    cuk = get_converter("cuk")
    p = cuk.resolve({"L1": "10u", "L2": "30u"})
    on, off = cuk.configurations(p)
    cond = gdcm.gdcm_condition(off)
    assert cond.possible and cond.CB == pytest.approx(1 / 10e-6 + 1 / 30e-6, rel=1e-12)
    assert cond.reduced_dimension == 3
    Le = 10e-6 * 30e-6 / 40e-6
    rng = np.random.default_rng(3)
    x = rng.normal(size=(20, 4)) * [1.0, 20.0, 1.0, 10.0]
    i1, v1, i2, v2 = x.T
    # derived (docs/theory.md, GDCM): u = Le ((v1 - Vin)/L1 + v2/L2); drift C(Ax + E) = (Vin - v1)/L1 - v2/L2.
    assert np.allclose(cond.multiplier(x), Le * ((v1 - 12.0) / 10e-6 + v2 / 30e-6), rtol=1e-12)
    assert np.allclose(cond.drift(x), (12.0 - v1) / 10e-6 - v2 / 30e-6, rtol=1e-12)
    assert np.allclose(cond.on_set(x), i1 + i2, atol=1e-15)
    # The reduced flow keeps C x + F constant: C P = 0.
    assert np.abs(off.C @ cond.P).max() < 1e-12
    assert gdcm.gdcm_condition(on).possible  # Cuk ON: v1 = 0 possible (GDCM-ON)


def test_condition_is_refused_where_the_pair_cannot_hold_the_state():
    buck = get_converter("buck")
    on, off = buck.configurations(buck.resolve({}))
    assert not gdcm.gdcm_condition(on).possible           # C = 0: the reverse voltage is Vin
    assert "C B = 0" in gdcm.gdcm_condition(on).reason
    assert gdcm.gdcm_condition(off).CB == pytest.approx(1e5)
    lossy = buck.configurations(buck.resolve({"Rd": 0.1, "Ron": 0.05}))[0]
    assert "D = " in gdcm.gdcm_condition(lossy).reason and not gdcm.gdcm_condition(lossy).possible
    prc = get_converter("prc")
    with pytest.raises(ParameterError, match="k = 1; configuration 'drive\\+' has k = 4"):
        gdcm.gdcm_condition(prc.configurations(prc.resolve({}))[0])


@pytest.mark.parametrize("name,D", [("buck", 0.4), ("boost", 0.3), ("buck-boost", 0.6), ("cuk", 0.5)])
def test_exact_boundary_lies_within_one_percent_of_the_closed_form(name, D):
    """Bisection on R for the exact (matrix-exponential) boundary; small ripple puts it next to Kcrit."""
    conv = get_converter(name)
    base = conv.resolve({"D": D})
    induct = conv.effective_inductance(base) if name == "cuk" else base["L"]
    lo, hi = 0.5 * analytic.k_crit(D, name), 2.0 * analytic.k_crit(D, name)
    for _ in range(40):
        K = np.sqrt(lo * hi)
        mode = gdcm.exact_mode(conv, {"D": D, "R": 2 * induct * base["f_sw"] / K})["mode"]
        lo, hi = (K, hi) if mode != "CCM" else (lo, K)
    assert lo / analytic.k_crit(D, name) == pytest.approx(1.0, abs=1e-2)


def test_mode_intervals_merge_glitches_and_measure_fractions():
    t = np.array([0.0, 0.001, 0.4, 0.4003, 0.7, 1.0])
    labels = np.array(["X", "CCM-ON", "Y", "CCM-OFF", "DCM"])   # labels[j] holds on [t[j], t[j+1])
    raw = mode_intervals(t, labels, 0.0, 1.0, 1.0)
    assert [iv["mode"] for iv in raw] == ["X", "CCM-ON", "Y", "CCM-OFF", "DCM"]
    merged = mode_intervals(t, labels, 0.0, 1.0, 1.0, min_run_fraction=0.002)
    # The glitch at the start joins the run after it, the one inside joins the run before it.
    assert [(iv["mode"], round(iv["fraction"], 4)) for iv in merged] == [
        ("CCM-ON", 0.4003), ("CCM-OFF", 0.2997), ("DCM", 0.3)]


@pytest.mark.parametrize("name", ["buck", "boost", "buck-boost", "cuk"])
def test_lcp_map_matches_the_closed_form_away_from_the_boundary(name):
    frame = dk_map(name, 12, 12, spice=False, progress=False)
    s = map_summary(frame)
    assert s["lcp_errors"] == 0 and s["not_converged"] == 0
    assert s["far_disagreements"] == 0
    assert frame["lcp"].isin(["CCM", get_converter(name).off_held_label]).all()
    assert 20 <= (frame["lcp"] != "CCM").sum() <= 124   # both modes well represented
    near = frame.loc[frame["lcp"] != frame["predicted"], "distance"].abs()
    assert (near <= BOUNDARY_BAND).all()


@pytest.mark.usefixtures("ngspice")
@pytest.mark.parametrize("name", ["buck", "boost", "buck-boost", "cuk"])
def test_ngspice_modes_agree_with_the_lcp_on_a_map(name):
    frame = dk_map(name, 10, 10, spice=True, spice_workers=1, progress=False)
    s = map_summary(frame)
    assert s["spice_errors"] == 0
    assert s["spice_agreement"] >= 0.98
    # A disagreement is only possible where the held interval is a fraction of a percent of T.
    off = frame[frame["spice"] != frame["lcp"]]
    assert (off[["lcp_held", "spice_held"]].fillna(0).max(axis=1) < 0.01).all()
    # Away from the boundary both simulators find the predicted mode (Cuk: GDCM wherever predicted),
    # where the held interval is at least 0.5 % of T (at D = 0.95 it is below 1 - D = 5 % of T and
    # shrinks to ~0.1 % within 3 % of the boundary, under ngspice's turn-off resolution).
    far = frame[(frame["distance"].abs() > BOUNDARY_BAND)]
    assert (far["lcp"] == far["predicted"]).all()
    resolvable = far[(far["lcp"] == "CCM") | (far["lcp_held"] >= 5e-3)]
    assert (resolvable["spice"] == resolvable["predicted"]).all()


@pytest.mark.usefixtures("ngspice")
def test_cuk_gdcm_in_both_simulators_with_the_constraint_exact():
    result = gdcm_check("cuk", {"L1": "10u", "L2": "10u"})
    assert result["predicted"] == result["lcp"] == result["spice"] == "GDCM-OFF" and result["agree"]
    held = result["gdcm_constraint"]["GDCM-OFF"]
    assert held["configuration"] == "OFF" and held["max_abs_Cx_plus_F"] <= 1e-9
    assert held["max_drift"] <= 0.0 and held["min_multiplier"] >= 0.0
    # Held fraction: both simulators within 0.5 % of T of each other.
    assert abs(result["held_fraction"]["lcp"] - result["held_fraction"]["spice"]) < 5e-3


def _held_stretch(h):
    cuk = get_converter("cuk")
    p = cuk.resolve({"L1": "10u", "L2": "10u"})
    orbit = steady_orbit(cuk, p, h=h, theta=1.0)       # backward Euler: its step is what the tests check
    held = np.flatnonzero(np.asarray(orbit.modes()).astype(str) == "GDCM-OFF")
    return cuk, p, orbit, held


def test_during_cuk_gdcm_the_lcp_step_is_backward_euler_on_the_reduced_dynamics():
    cuk, p, orbit, held = _held_stretch(1e-8)
    cond = gdcm.gdcm_condition(cuk.configurations(p)[1])
    i1, i2 = orbit.x[held, 0], orbit.x[held, 2]
    assert np.abs(i1 + i2).max() <= 1e-9 and np.abs(i1).min() > 1e-3
    j = held[1:]                      # steps wholly inside the held stretch
    j = j[np.isin(j - 1, held)]
    lhs = orbit.x[j] - orbit.x[j - 1]
    rhs = 1e-8 * cond.reduced_rhs(orbit.x[j])
    assert np.abs(lhs - rhs).max() <= 1e-9 * np.abs(orbit.x).max()


def test_cuk_gdcm_follows_the_exact_reduced_flow_with_first_order_error():
    errors = []
    for h in (4e-8, 2e-8, 1e-8):
        cuk, p, orbit, held = _held_stretch(h)
        cond = gdcm.gdcm_condition(cuk.configurations(p)[1])
        a, b = held[0], held[-1]
        n = 4
        aug = np.zeros((n + 1, n + 1))
        aug[:n, :n], aug[:n, n] = cond.A_red, cond.E_red
        # From the state where the LCP entered the GDCM, over a fixed 2 us, by the exact reduced flow.
        steps = int(round(2e-6 / h))
        assert b - a > steps
        exact = (expm(aug * 2e-6) @ np.append(orbit.x[a], 1.0))[:n]
        assert abs(exact[0] + exact[2]) < 1e-9            # the exact reduced flow keeps i1 + i2 = 0
        errors.append(np.abs(orbit.x[a + steps] - exact).max())
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert errors[-1] < 1e-3 and (orders > 0.8).all() and (orders < 1.2).all()


@pytest.mark.usefixtures("ngspice")
def test_cli_gdcm_json_and_prc_combinations(capsys):
    from validation.cli import main
    assert main(["gdcm", "buck", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert {"predicted", "lcp", "spice", "agree"} <= set(out) and out["lcp"] == out["spice"] == "DCM"
    assert out["intervals"]["lcp"][-1]["mode"] == "DCM"
    assert out["intervals"]["lcp"][-1]["fraction"] == pytest.approx(analytic.dcm_fractions(out["params"], "buck")[2],
                                                                     abs=0.01)
    assert main(["gdcm", "prc", "--json"]) == 0
    prc = json.loads(capsys.readouterr().out)
    assert prc["lcp"]["D1+D4"] == pytest.approx(prc["spice"]["D1+D4"], abs=0.01) and prc["agree"]
    assert prc["lcp"]["D2+D3"] == pytest.approx(prc["spice"]["D2+D3"], abs=0.01)
    # named as the waveform file's mode column names them (D2+D3, not the pairs' order D3+D2)
    labels = set(get_converter("prc").mode_labels)
    assert set(prc["lcp"]) <= labels and set(prc["spice"]) <= labels
    assert sum(prc["lcp"].values()) == pytest.approx(1.0, abs=1e-9)
    assert main(["gdcm", "prc"]) == 0           # the text says what "agree" compares (it did not)
    assert capsys.readouterr().out.splitlines()[-1] == (f"agree (the modes held more than 1 % of the period; largest "
                                                        f"fraction difference {prc['max_fraction_difference']:.2g})")
    assert main(["gdcm", "boost", "-p", "D=1.5"]) == 2
    assert "D (duty ratio) must be in [0, 1]; got 1.5" in capsys.readouterr().err


@pytest.mark.usefixtures("ngspice")
@pytest.mark.parametrize("params", [{"D": 0.5, "C1": "130n"}, {"D": 0.6, "C1": "100n"}])
def test_cuk_gdcm_on_is_predicted_found_and_constrained(params):
    """A small coupling capacitor lets v1 reach zero while the switch is on: the diode conducts with the
    switch (GDCM-ON). The exact prediction sees it (the small-ripple closed form cannot); both simulators
    find it; on the held interval v1 = 0 exactly and the multiplier is positive. (This used to crash.)"""
    result = gdcm_check("cuk", params)
    assert result["prediction"]["closed_form"] == "CCM"
    assert result["predicted"] == result["lcp"] == result["spice"] == "GDCM-ON" and result["agree"]
    held = result["gdcm_constraint"]["GDCM-ON"]
    assert held["configuration"] == "ON" and held["max_abs_Cx_plus_F"] <= 1e-9 and held["min_multiplier"] > 0.0
    assert abs(result["held_fraction"]["lcp"] - result["held_fraction"]["spice"]) < 5e-3


@pytest.mark.usefixtures("ngspice")
def test_a_held_interval_below_what_a_side_resolves_agrees_with_a_note_and_the_exact_fraction_is_given():
    """A buck at R = 3.327 ohm, 0.001 % past its exact DCM boundary (R = 3.326673 ohm, the tester's exact orbit):
    held 3.6909462e-5 of T (0.3105337598 at R = 10 ohm; an independent exact orbit: matrix exponentials, the
    diode's turn-off by Brent's method, Newton on the period map). The LCP at T/1000 read DCM, held 0.0010 (a whole
    step), ngspice CCM (its runs shorter than
    5e-4 of T are glitches), and gdcm said DISAGREE, exit 1, with no reason. The exact held fraction is the event
    method's; ngspice's CCM is within what it resolves, and a note says so. At R = 10 ohm every side agrees with
    no note."""
    edge = gdcm_check("buck", {"R": 3.327})
    assert edge["predicted"] == "DCM" and edge["spice"] == "CCM" and edge["agree"]
    assert edge["held_fraction"]["exact"] == pytest.approx(3.6909462e-5, abs=1e-9)
    assert edge["resolution"] == {"lcp": pytest.approx(1e-3), "spice": 5e-4}
    assert edge["notes"] == ["spice reads CCM where the exact orbit is DCM (held 3.7e-05 of T): within what it "
                             "resolves (0.0005 of T)"]
    deep = gdcm_check("buck", {"R": 10})
    assert deep["agree"] and deep["notes"] == [] and deep["held_fraction"]["exact"] == pytest.approx(0.3105337598,
                                                                                                       abs=1e-9)


def test_one_rule_judges_a_side_against_the_exact_held_fraction_to_what_it_resolves():
    """The gdcm command and the report's scenes judge by judge_held (two copies of the rule had differed: the
    report's said nothing of a disagreement). A side reading CCM 3.7e-5 of T from the exact DCM agrees at a
    resolution of 5e-4 T, with a note; at 1e-5 T it disagrees and the note names the side and both fractions."""
    from validation.gdcm import judge_held
    agree, notes = judge_held("DCM", 3.7e-5, {"lcp": ("DCM", 4e-5, 1e-3), "spice": ("CCM", 0.0, 5e-4)})
    assert agree and notes == ["spice reads CCM where the exact orbit is DCM (held 3.7e-05 of T): within what it "
                               "resolves (0.0005 of T)"]
    agree, notes = judge_held("DCM", 3.7e-5, {"spice": ("CCM", 0.0, 1e-5)})
    assert not agree and notes == ["spice reads CCM, held 0 of T, where the exact orbit is DCM, held 3.7e-05 of T "
                                   "(3.7e-05 apart; it resolves 1e-05)"]
