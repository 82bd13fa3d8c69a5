"""pcsuite bifurcation: the voltage-mode buck's route to chaos against the literature, the CCM/DCM border
collision of the PWM buck against its exact CCM orbit, ngspice's period-2 orbit, the report section, and
one clear line for bad input."""
import json

import numpy as np
import pytest
from scipy.optimize import brentq

from converters.analysis.gdcm import ccm_orbit
from converters.models import get_converter
from validation.bifurcation import parse_path, spice_orbit
from validation.cli import main
from validation.defaults import BIFURCATION, PUBLISHED_BIFURCATIONS, THRESHOLDS


def run_cli(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


@pytest.mark.slow
def test_the_cascade_doubles_where_the_literature_says(capsys):
    """Period doublings of the period-1, -2 and -4 orbits (continuation only), each with a multiplier at -1."""
    code, out, _ = run_cli(capsys, "bifurcation", "buck", "--control", "voltage-mode", "--param", "Vin=20:36",
                           "--points", "0", "--max-period", "4", "--json")
    assert code == 0
    summary = json.loads(out)
    doublings = [b for b in summary["bifurcations"] if b["type"] == "period-doubling"]
    assert [b["period"] for b in doublings] == [1, 2, 4]
    for b, expected in zip(doublings, (24.516573, 31.117902, 32.087627)):
        assert set(b) >= {"type", "value", "period", "multipliers"}
        assert b["value"] == pytest.approx(expected, abs=1e-5)
        assert b["multipliers"][0] == pytest.approx([-1.0, 0.0], abs=1e-5)
        assert b["stable_before"] and not b["stable_after"]
    limit = THRESHOLDS["bifurcation"]["published_abs"]
    assert abs(doublings[0]["value"] - PUBLISHED_BIFURCATIONS["first_doubling"]) <= limit
    assert abs(doublings[1]["value"] - PUBLISHED_BIFURCATIONS["second_doubling"]) <= limit
    assert [b["period"] for b in summary["branches"]] == [1, 2, 4]
    assert all(b["complete"] for b in summary["branches"])
    assert summary["branches"][1]["stable"][0] == pytest.approx([24.516573, 31.117902], abs=1e-5)


def test_the_ccm_dcm_border_collision_of_the_pwm_buck_is_where_the_exact_ccm_orbit_grazes_zero(capsys):
    """Along D the buck's orbit leaves DCM where its CCM orbit's inductor current touches zero at the period
    start (the end of the OFF phase): brentq on the exact CCM orbit (matrix exponentials) against the located
    border collision."""
    buck = get_converter("buck")
    exact = brentq(lambda D: ccm_orbit(buck.problem(buck.resolve({"D": D}), 1e-5)).x0[0], 0.7, 0.9, xtol=1e-14)
    code, out, _ = run_cli(capsys, "bifurcation", "buck", "--control", "pwm", "--param", "D=0.7:0.9", "--points", "0",
                           "--json")
    bifurcations = json.loads(out)["bifurcations"]
    assert code == 0 and [b["type"] for b in bifurcations] == ["border-collision"]
    assert bifurcations[0]["value"] == pytest.approx(exact, abs=1e-7)
    assert "vanish: diode held (y = 0) in OFF" in bifurcations[0]["detail"]


@pytest.mark.slow
def test_a_small_diagram_is_written_and_summarised(capsys, tmp_path):
    target = tmp_path / "diagram.svg"
    code, out, _ = run_cli(capsys, "bifurcation", "buck", "--param", "Vin=30:34", "--points", "60", "--max-period", "2",
                           "--workers", "2", "--diagram", str(target), "--json")
    assert code == 0
    summary = json.loads(out)
    assert target.read_bytes().lstrip().startswith(b"<?xml") and summary["diagram"]["file"] == str(target)
    diagram = summary["diagram"]
    assert diagram["points"] == 60 and diagram["errors"] == 0
    assert diagram["aperiodic_onset"] == pytest.approx(PUBLISHED_BIFURCATIONS["chaos"], abs=0.15)
    stretches = [w["period"] for w in diagram["windows"] if w["count"] >= 3]   # a lone value next to a doubling
    assert stretches[:2] == [2, 4] and stretches[-1] == 0                     # converges slowly: not a stretch


@pytest.mark.parametrize("argv, message", [
    (["--param", "Vin=20:36", "-p", "VU=3"], "VU (ramp high level) must be above VL = 3.8 V; got VU = 3 V"),
    (["--param", "Vin=20:36", "-p", "A=0"], "A (amplifier gain of vcon = A (vout - Vref)) must be in (0, inf); got 0"),
    (["--param", "Vin=-5:36"], "the path of Vin must lie in (0, inf); got -5:36"),
    (["--param", "Vin=20"], "--param takes NAME=START:STOP (e.g. --param Vin=20:36); got 'Vin=20'"),
    (["--param", "Vin=20:abc"], "Vin (path stop)"),
    (["--param", "Lx=1:2"], "--param must name a parameter of buck --control voltage-mode"),
    (["--param", "VL=3:9"], "VU (ramp high level) must be above VL = 9 V"),
    (["--param", "Vin=20:20"], "the path of Vin must have START != STOP; got 20:20"),
    (["--param", "Vin=20:36", "--diagram", "out.txt"], "--diagram must end in .png or .svg; got 'out.txt'"),
    (["--param", "Vin=20:36", "--points", "0", "--diagram", "d.png"], "--diagram needs the brute-force diagram"),
    (["--param", "Vin=20:36", "--max-period", "0"], "max_period must be an integer >= 1; got 0"),
    (["--param", "Vin=20:36", "--state", "q"], "state must be one of iL, vC; got 'q'"),
    (["--param", "Vin=20:36", "--workers", "0"], "--workers must be an integer in [1, 64]; got 0"),
])
def test_bad_input_gets_one_clear_line(capsys, tmp_path, argv, message):
    code, out, err = run_cli(capsys, "bifurcation", "buck", *argv)
    assert code == 2 and out == ""
    assert err.count("\n") == 1 and message in err
    assert not (tmp_path / "d.png").exists()


def test_a_model_without_a_period_is_refused(capsys):
    code, _, err = run_cli(capsys, "bifurcation", "boost", "--control", "smc", "--param", "Vin=5:8")
    assert code == 2 and "has no fixed switching period" in err


def test_parse_path_accepts_spice_suffixes():
    assert parse_path("R=10:1k") == ("R", 10.0, 1000.0)


@pytest.mark.spice
def test_ngspice_settles_on_the_period_2_orbit_of_the_event_method(ngspice):
    """From rest at Vin = 28 V (300 periods, TMAX = T/1000): period 2, each point within 1 % of the exact orbit."""
    cfg = BIFURCATION
    result = spice_orbit({}, "buck", "voltage-mode", "Vin", 28.0, cfg["spice_periods"], cfg["spice_window"],
                         cfg["spice_tmax_fraction"])
    assert result["spice_period"] == 2 and result["event_converged"]
    assert result["max_rel_difference"] <= THRESHOLDS["bifurcation"]["spice_orbit_rel"]
    assert np.ptp(result["event_samples"]) > 0.01          # a genuine period-2 orbit (its two points 21 mV apart)
    assert result["max_rel_difference"] < 5e-5              # measured 1.1e-5: ngspice's own switching jitter


@pytest.mark.spice
@pytest.mark.slow
def test_the_report_section_passes_its_checks(ngspice):
    from validation.bifurcation import bifurcation_section
    section = bifurcation_section()
    assert section.ok, section.metrics
    assert {"bifurcation_diagram.png", "bifurcations.csv", "branches.csv"} <= set(section.files)
    m = section.metrics
    assert m["branch_agreement"]["values_compared"] >= 40
    assert m["diagram"]["aperiodic_onset"] == pytest.approx(PUBLISHED_BIFURCATIONS["chaos"], abs=0.1)
    assert m["feigenbaum"]["accumulation"] == pytest.approx(32.28, abs=0.01)


def test_steady_refuses_an_unstable_orbit_and_reports_stability(capsys):
    """At 28 V the period-1 orbit exists but is unstable (multiplier -1.486): it is not the circuit's steady state."""
    code, out, err = run_cli(capsys, "simulate", "buck", "--control", "voltage-mode", "-p", "Vin=28", "--steady")
    assert code == 2 and out == ""
    # the exact multiplier (the event method's, which confirms the stepper's -1.48843 at T/1000 as the circuit's)
    assert "the periodic orbit of buck --control voltage-mode is unstable (Floquet spectral radius 1.48442" in err
    code, out, _ = run_cli(capsys, "simulate", "buck", "--control", "voltage-mode", "-p", "Vin=22", "--steady",
                           "--method", "event", "--json")
    orbit = json.loads(out)["orbit"]
    assert code == 0 and orbit["stable"] and orbit["spectral_radius"] == pytest.approx(0.824133, abs=1e-6)   # |-0.7528 +- 0.3354j|


@pytest.mark.slow
def test_a_diagram_with_isolated_values_without_a_period_does_not_read_periodic_everywhere(capsys):
    """Along Vin 20..36 V at 9 values one value has no period within the record (the diagram's JSON says so) and
    fewer than aperiodic_onset's three in a row: the text had read "periodic everywhere"."""
    code, out, _ = run_cli(capsys, "bifurcation", "buck", "--control", "voltage-mode", "--param", "Vin=20:36",
                           "--points", "9", "--json")
    windows = json.loads(out)["diagram"]["windows"]
    isolated = sum(w["count"] for w in windows if w["period"] == 0)
    assert code == 0 and isolated == 1
    code, out, _ = run_cli(capsys, "bifurcation", "buck", "--control", "voltage-mode", "--param", "Vin=20:36",
                           "--points", "9")
    assert code == 0 and "no aperiodic range (1 isolated value without a period)" in out
    assert "periodic everywhere" not in out


@pytest.mark.slow
def test_a_diagram_period_the_continuation_does_not_hold_stable_there_is_warned_of(capsys):
    """Vin 20..36 V at 9 values, each started from the previous one's end: the stepper at T/500 settles at 30 V on a
    period-6 cycle (at T/1000 too), where the exact method and the stepper at T/250 and T/2000 settle on the period-2
    orbit the continuation holds stable over 24.5166..31.1179 V (the published doublings). The diagram's JSON lists
    the value and the command warns, naming the continuation's stable period."""
    code, out, err = run_cli(capsys, "bifurcation", "buck", "--control", "voltage-mode", "--param", "Vin=20:36",
                             "--points", "9", "--transient", "2000", "--json")
    assert code == 0
    assert {"value": 30.0, "period": 6, "stable_period": 2} in json.loads(out)["diagram"]["unconfirmed"]
    code, out, err = run_cli(capsys, "bifurcation", "buck", "--control", "voltage-mode", "--param", "Vin=20:36",
                             "--points", "9", "--transient", "2000")
    assert code == 0 and ("is not the stable orbit's the continuation holds there (the first: 6 at 30, where period "
                          "2 is stable)") in err
