"""Exact steady-state sensitivities (the implicit function theorem on the period map, read as the exact small-signal
model at zero frequency) against closed forms, exact scaling identities and finite differences of the steady state."""
import json
from pathlib import Path

import pytest

from converters.analysis.sensitivity import finite_difference, parse_metric, sensitivities
from converters.errors import ParameterError
from converters.run import resolve_model
from validation.cli import main

NETLISTS = Path(__file__).resolve().parents[2] / "netlists" / "circuits"
CCM_BUCK = {"L": "100u", "C": "100u", "R": 10, "D": 0.4}
DCM_BOOST = {"L": "10u", "R": 100, "D": 0.4}


def by_name(found) -> dict:
    return {row.parameter: row for row in found.rows}


def test_the_ideal_ccm_bucks_output_is_d_vin_whatever_its_filter_and_load():
    """vout = D Vin in CCM with ideal parts: d vout/dD = Vin, d vout/dVin = D, and L, C, R do not move the mean."""
    found = sensitivities("buck", CCM_BUCK)
    rows = by_name(found)
    assert found.metric_value == pytest.approx(4.8, rel=1e-12)
    assert rows["D"].derivative == pytest.approx(12.0, rel=1e-12)
    assert rows["Vin"].derivative == pytest.approx(0.4, rel=1e-12)
    for name in ("L", "C", "R"):
        assert abs(rows[name].normalised(found.metric_value)) < 1e-10, (name, rows[name])
    assert set(found.skipped) == {"f_sw"} and "changes the switching period" in found.skipped["f_sw"]
    # with a winding resistance, vout = D Vin R / (R + rL) in CCM: S_R = -S_rL = rL / (R + rL)
    found = sensitivities("buck", CCM_BUCK | {"rL": 0.1, "rC": 0.05})
    s = {row.parameter: row.normalised(found.metric_value) for row in found.rows}
    assert found.metric_value == pytest.approx(4.8 * 10 / 10.1, rel=1e-12)
    assert s["R"] == pytest.approx(0.1 / 10.1, rel=1e-9) and s["rL"] == pytest.approx(-0.1 / 10.1, rel=1e-9)
    assert abs(s["rC"]) < 1e-10 and abs(s["L"]) < 1e-10


def test_the_dcm_boosts_sensitivities_obey_its_scaling_identity():
    """Scaling L and R by a and C by 1/a (the inductor current by 1/a) leaves the boost's equations, so its mean
    output, unchanged: S_L + S_R - S_C = 0 exactly; and vout is homogeneous of degree one in Vin: S_Vin = 1."""
    found = sensitivities("boost", DCM_BOOST)
    s = {row.parameter: row.normalised(found.metric_value) for row in found.rows}
    from converters.run import run_converter
    assert "DCM" in set(run_converter("boost", DCM_BOOST, method="event", steady=True, periods=1).modes())
    assert abs(s["L"] + s["R"] - s["C"]) < 1e-9 and abs(s["L"]) > 0.4
    assert s["Vin"] == pytest.approx(1.0, abs=1e-10)


CASES = [("buck", CCM_BUCK | {"rL": 0.1, "rC": 0.05}, "vout", ("D", "L", "R", "rL", "rC")),
         ("boost", DCM_BOOST, "vout", ("D", "L", "R", "C", "Vin")),
         ("boost", DCM_BOOST, "iL", ("L", "R")),
         (str(NETLISTS / "flyback.cir"), {}, "vout", ("k", "lp", "ls", "d", "r")),
         (str(NETLISTS / "flyback.cir"), {}, "i(lp).mean", ("k", "rc"))]


@pytest.mark.parametrize("converter, params, metric, names", CASES,
                         ids=[f"{Path(c).name}-{m}" for c, _, m, _ in CASES])
def test_exact_sensitivities_are_the_finite_differences_of_the_steady_state(converter, params, metric, names):
    """Against a five-point central difference of the steady state (Newton to 1e-11, moves of 1e-4, four orbits per
    parameter): to 1e-6 relative, or, where the metric hardly moves (the buck's mean does not see its ESR, S ~ 1e-12;
    the DCM boost's C, S ~ 7e-8), to the difference's own resolution, 1e-11 / 1e-4 in the normalised sensitivity."""
    model = resolve_model(converter)
    found = sensitivities(model, params, metric=metric, parameters=names)
    assert [row.parameter for row in found.rows] and len(found.rows) == len(names)
    for row in found.rows:
        fd = finite_difference(model, params, metric, row.parameter, relative=1e-4, tol=1e-11)
        resolution = 1e-7 * abs(found.metric_value / row.value)
        assert abs(row.derivative - fd) <= 1e-6 * abs(fd) + resolution, (row, fd)
        if abs(row.normalised(found.metric_value)) > 1e-2:
            assert row.derivative == pytest.approx(fd, rel=1e-6)


def test_a_netlists_parasitics_at_zero_are_differentiated_one_sided():
    """The buck netlist's rl, rc (resistors) and rd (its diode's RS) at 0: their five-point moves to -2e-5 were
    refused by the elements, and each was "not taken". d vout / d rl and d rc: -0.6735335 and -0.1840987, the
    tester's one-sided differences of exact orbits (matrix exponentials, Brent's method) extrapolated to 0; rd:
    -0.16719076, those of the event method's orbits here. At a move of 1e-5 the matrices' rounding had put them
    1.2e-4 and 4e-4 off."""
    result = sensitivities(str(NETLISTS / "buck.cir"), {}, parameters=["rl", "rc", "rd"])
    assert not result.skipped
    derivative = {row.parameter: row.derivative for row in result.rows}
    for name, reference in [("rl", -0.6735335), ("rc", -0.1840987), ("rd", -0.16719076)]:
        assert derivative[name] == pytest.approx(reference, rel=1e-5), name


def test_a_closed_loop_with_an_integrator_holds_its_mean_at_the_reference():
    """The type III voltage loop's integrator makes mean(vout) = Vref on the orbit: S_Vref = 1 and every other
    parameter (the filter, the load, the parasitics, the compensator, the carrier, Vin) has S = 0."""
    found = sensitivities(resolve_model("buck", "voltage-loop"), {"rL": 0.05})
    s = {row.parameter: row.normalised(found.metric_value) for row in found.rows}
    assert s.pop("Vref") == pytest.approx(1.0, abs=1e-10)
    assert len(s) >= 10 and max(abs(v) for v in s.values()) < 1e-10, s


@pytest.mark.parametrize("text, expected", [("vout", ("vout", "mean")), ("v(out).mean", ("v(out)", "mean")),
                                            ("iL", ("iL", "mean")), ("i(l1).mean", ("i(l1)", "mean"))])
def test_a_metric_is_a_signal_with_an_optional_mean(text, expected):
    assert parse_metric(text) == expected


def test_what_has_no_exact_sensitivity_is_refused_naming_it():
    with pytest.raises(ParameterError, match=r"metric 'vout.ripple': exact sensitivities are taken of a signal's mean"):
        sensitivities("buck", CCM_BUCK, metric="vout.ripple")
    with pytest.raises(ParameterError, match="input 'f_sw' changes the switching period"):
        sensitivities("buck", CCM_BUCK, parameters=["f_sw"])
    with pytest.raises(ParameterError, match="parameter must be one of Vin, L, C, R, f_sw, D"):
        sensitivities("buck", CCM_BUCK, parameters=["Lx"])


def test_the_command_ranks_the_sensitivities_checks_them_and_draws_a_tornado(capsys, tmp_path):
    png = tmp_path / "tornado.png"
    assert main(["sensitivity", "boost", "-p", "L=10u", "-p", "R=100", "--param", "L", "--param", "D",
                 "--param", "C", "--check", "--plot", str(png), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    rows = summary["sensitivities"]
    assert [r["parameter"] for r in rows] == ["D", "L", "C"]             # ranked by |normalised|
    assert summary["unit"] == "V" and rows[1]["unit"] == "H"
    assert all(r["normalised_difference"] < 1e-8 for r in rows), rows
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert main(["sensitivity", "buck", "-p", "L=100u"]) == 0
    out = capsys.readouterr().out
    assert "mean(vout) = 4.8 V" in out and "not taken: f_sw" in out


@pytest.mark.parametrize("argv, message", [
    (["--metric", "vout.rms"], "exact sensitivities are taken of a signal's mean here"),
    (["--param", "Lx"], "parameter must be one of"),
    (["--metric", "vx"], "signal must be one of"),
    (["--plot", "x.pdf"], "--plot must end in .png or .svg"),
])
def test_bad_sensitivity_input_is_one_line(capsys, tmp_path, monkeypatch, argv, message):
    monkeypatch.chdir(tmp_path)
    code = main(["sensitivity", "buck", *argv])
    out, err = capsys.readouterr()
    assert code == 2 and out == "" and err.count("\n") == 1 and message in err
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("D", [0.0, 1.0])
def test_a_duty_ratio_where_the_converter_does_not_switch_is_refused_not_differentiated_to_zero(D):
    """At D = 0 (or 1) the buck does not switch and any move of D makes it: the derivative is one-sided (26.83 V
    per unit of D from above at D = 0, a tester's differences), where the small-signal model had read 0 (its
    schedule has no edge to move) and bode -inf dB."""
    with pytest.raises(ParameterError, match=r"adds or removes a switching edge \(a duty ratio of 0 or 1"):
        sensitivities("buck", {"D": D}, parameters=["D"])


def test_a_duty_ratio_a_move_from_one_takes_the_move_to_the_other_side():
    """D = 0.999: the move +1e-3 reaches 1, where the schedule loses its edge; it had been refused as "a duty ratio
    of 0 or 1". The move to the other side is the affine input's exact derivative: the brute-force difference of
    steady means agrees."""
    found = sensitivities("buck", {"D": 0.999}, parameters=["D"])
    (row,) = found.rows
    assert row.derivative == pytest.approx(finite_difference("buck", {"D": 0.999}, "vout", "D"), rel=1e-6)


@pytest.mark.parametrize("L, side", [("36.0168u", "ccm"), ("36.0167995u", "dcm"), ("30u", None)])
def test_an_orbit_at_a_border_of_its_modes_says_its_derivatives_are_one_sided(capsys, L, side):
    """The ideal boost at D = 0.4, R = 50 ohm meets its CCM/DCM border at L = 36.0168 uH (D (1 - D)^2 R T / 2 =
    36 uH with vout's ripple): there the mean has a kink. On the CCM side vout = Vin / (1 - D) whatever L (S_L ~ 0);
    on the DCM side S_L = (K / M) dM/dK with M = (1 + sqrt(1 + 4 D^2 / K)) / 2 at K = D (1 - D)^2: -2/7. Both
    sides printed their one-sided derivative with no word (only --check showed a 0.14 difference): each now says
    the orbit lies at a border (D1's current reaches 0 4e-9 of the period after S1 closes; a DCM interval of
    2.2e-10 of the period), in one line and in the JSON; an orbit 0.2 of the period from it (30 uH) says nothing.
    The frequency response says so too."""
    assert main(["sensitivity", str(NETLISTS / "boost.cir"), "-p", f"L={L}", "-p", "R=50", "--param", "L",
                 "--json"]) == 0
    out, err = capsys.readouterr()
    summary = json.loads(out)
    (row,) = summary["sensitivities"]
    if side is None:
        assert "border" not in summary and err == ""
        return
    assert row["normalised"] == (pytest.approx(0.0, abs=1e-3) if side == "ccm" else pytest.approx(-2 / 7, abs=1e-3))
    assert summary["border"].startswith("the orbit lies ")
    what = "D1's current would reach 0 4e-09 of the period after" if side == "ccm" else "a mode lasts 2.2e-10"
    assert what in summary["border"]
    assert err.count("\n") == 1 and "its sensitivities are one-sided there, and differ across it" in err
    assert main(["bode", str(NETLISTS / "boost.cir"), "-p", f"L={L}", "-p", "R=50", "--input", "duty",
                 "--points", "2", "--json"]) == 0
    out, err = capsys.readouterr()
    assert what in json.loads(out)["border"] and "its frequency responses are one-sided there" in err


@pytest.mark.parametrize("name, input", [("prc", "Vin"), ("two-switch-forward", "Vin"), ("boost", "R")])
def test_diodes_in_series_that_stop_together_are_no_border(name, input):
    """The series resonant converter's output bridge (two diodes carry one current) and the two-switch forward's
    clamps (D3, the primary, D4: one current) reach 0 together at every parameter value, one event: no border (each
    had been said to lie 0 and 5.8e-17 of the period from one). The shipped boost at its defaults: none either."""
    from converters.analysis.smallsignal import SmallSignalModel
    small = SmallSignalModel(resolve_model(str(NETLISTS / f"{name}.cir")), {}, input=input)
    assert small.border() == ""


@pytest.mark.parametrize("vref, border", [("20.2000001", 24.0), ("-8.2000001", 0.0), ("15", None)])
def test_a_comparator_held_at_a_duty_of_one_by_a_hair_lies_at_a_border(capsys, tmp_path, vref, border):
    """The voltage-mode buck with its amplifier's gain 1: at Vref = 20.2000001 V its control vcon = vout - Vref lies
    1e-7 V below the ramp's low end, so S1 stays on (vout = Vin = 24 V exactly, d vout / d Vref = 0) and the
    comparator's function comes within 1.8e-8 of the period of its threshold at each ramp reset: a hair of Vref
    lower and the loop switches (one-sided differences of exact orbits: 0 on one side, 0.84 on the other). One
    mode a period had been read as no border at all. Held at a duty of 0 by as much (Vref = -8.2000001 V: vout 0),
    the function is that close at the top of the ramp, as the mode ends at its reset (read after the reset, the
    margin had been the ramp's whole height). At 15 V the loop regulates, far from either end."""
    text = (NETLISTS / "voltage-mode-buck.cir").read_text()
    assert "A=8.4" in text
    path = tmp_path / "vm-gain1.cir"
    path.write_text(text.replace("A=8.4", "A=1"))
    assert main(["sensitivity", str(path), "-p", f"Vref={vref}", "--param", "Vref", "--json"]) == 0
    out, err = capsys.readouterr()
    summary = json.loads(out)
    if border is None:
        assert "border" not in summary and err == ""
        return
    assert summary["value"] == pytest.approx(border, abs=1e-12) and summary["sensitivities"][0]["derivative"] == 0.0
    assert "the comparator's switching function" in summary["border"]
    assert "its sensitivities are one-sided there" in err


def test_an_analysis_says_what_its_circuit_says_with_every_run(capsys, tmp_path):
    """A comparator's ramp falling over 1e-3 of its period is taken as a sawtooth reset at the fall's middle, which
    simulate says with every run; sensitivity and bode, reading the same orbit, had said nothing."""
    path = tmp_path / "slow-fall.cir"
    path.write_text((NETLISTS / "voltage-mode-buck.cir").read_text().replace(".param e={1e-8*T}",
                                                                              ".param e={5e-4*T}"))
    for argv in (["sensitivity", str(path), "--param", "Vin"], ["bode", str(path), "--input", "vin", "--points", "2"]):
        assert main([*argv, "--json"]) == 0
        out, err = capsys.readouterr()
        (note,) = json.loads(out)["warnings"]
        assert note.startswith("voltage source VRAMP's ramp is taken as a sawtooth") and f"warning: {note}" in err
