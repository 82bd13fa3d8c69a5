"""pcsuite bode: the exact response as JSON and a plot, the brute-force check beside it, a loop gain's margins, and
one clear line for bad input."""
import json

import numpy as np
import pytest

from validation.cli import main


def run_cli(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


@pytest.mark.slow
def test_bode_prints_the_averaged_bucks_response_and_its_injection_check(capsys, tmp_path):
    png = tmp_path / "bode.png"
    code, out, _ = run_cli(capsys, "bode", "buck", "-p", "L=100u", "--input", "duty", "--points", "50", "--check",
                           "--plot", str(png), "--json")
    assert code == 0
    summary = json.loads(out)
    f = np.array(summary["frequency_hz"])
    assert f.size == 50 and f[0] == pytest.approx(100.0) and f[-1] == pytest.approx(50e3)
    s = 2j * np.pi * f
    averaged = 12.0 / (1 + s * 100e-6 / 10.0 + s ** 2 * 100e-6 * 100e-6)
    assert np.abs(np.array(summary["magnitude_db"]) - 20 * np.log10(np.abs(averaged))).max() < 1e-7
    assert np.abs(np.array(summary["phase_deg"]) - np.degrees(np.unwrap(np.angle(averaged)))).max() < 1e-6
    check = summary["check"]
    assert len(check["frequency_hz"]) == 8 and max(check["frequency_hz"]) < 50e3
    assert np.abs(check["difference_db"]).max() < 1e-3 and np.abs(check["difference_deg"]).max() < 1e-2
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_bode_gives_the_voltage_mode_bucks_loop_gain_with_its_margins(capsys):
    code, out, _ = run_cli(capsys, "bode", "buck", "--control", "voltage-mode", "-p", "Vin=22", "--input", "loop")
    assert code == 0
    assert "loop gain T" in out and "phase margin" in out
    code, out, _ = run_cli(capsys, "bode", "buck", "--control", "voltage-mode", "-p", "Vin=22", "--input", "loop",
                           "--json")
    margins = json.loads(out)["margins"]
    assert 0 < margins["phase_margin_deg"] < 30 and 0 < margins["crossover_hz"] < 1250


def test_bode_gives_the_output_impedance_from_the_load_current(capsys):
    code, out, _ = run_cli(capsys, "bode", "buck", "-p", "L=100u", "--input", "iload", "--fmin", "1k", "--fmax", "2k",
                           "--points", "2", "--json")
    assert code == 0
    summary = json.loads(out)
    assert summary["input"] == "Io" and summary["input_unit"] == "A" and summary["params"]["Io"] == 0.0
    s = 2j * np.pi * 1e3
    Z = 1 / (1 / (s * 100e-6) + s * 100e-6 + 1 / 10.0)
    assert summary["magnitude_db"][0] == pytest.approx(20 * np.log10(abs(Z)), abs=1e-9)


@pytest.mark.parametrize("argv, message", [
    (["--input", "duty", "--plot", "x.txt"], "--plot must end in .png or .svg"),
    (["--input", "Q"], "input must be 'control'"),
    (["--input", "duty", "--fmin", "-3"], "fmin must be a frequency in (0, 1e+08] Hz"),
    (["--input", "duty", "--fmin", "5k", "--fmax", "1k"], "fmin must be below fmax"),
    (["--input", "loop"], "driven by a schedule"),
    (["--input", "L", "--check"], "input 'L' changes the circuit's matrices; the injection check perturbs"),
    (["--input", "duty", "--output", "nope"], "signal must be one of"),
])
def test_bad_bode_input_is_one_line_naming_it(capsys, argv, message):
    code, out, err = run_cli(capsys, "bode", "buck", *argv)
    assert code == 2 and out == ""
    assert err.count("\n") == 1 and message in err


def test_bode_designs_a_type_iii_compensator_and_gives_the_loop_it_closes(capsys, tmp_path):
    png = tmp_path / "design.png"
    code, out, _ = run_cli(capsys, "bode", "buck", "--control", "voltage-loop", "--design", "fc=10k,pm=60",
                           "--plot", str(png), "--json")
    assert code == 0
    summary = json.loads(out)
    design, margins = summary["design"], summary["margins"]
    assert design["compensator"] == "type III" and design["fz1"] == design["fz2"] < 10e3 < design["fp1"]
    assert margins["crossover_hz"] == pytest.approx(10e3, rel=0.05) and margins["phase_margin_deg"] == pytest.approx(
        60, abs=3)
    # the defaults are this design (rounded to 6 digits)
    from converters.models import get_model
    defaults = get_model("buck", "voltage-loop").resolve({})
    for key in ("wi", "fz1", "fz2", "fp1", "fp2"):
        assert defaults[key] == pytest.approx(design[key], rel=5e-6)          # 6 significant digits
    assert png.read_bytes()[:4] == b"\x89PNG"
    # a type II where the ESR's zero lifts the plant's phase; its own loop gain shows what the averaged modulator
    # gain misses (the ESR carries the inductor's ripple into vc: 2.3 degrees of margin, not 30)
    code, out, _ = run_cli(capsys, "bode", "buck", "--control", "voltage-loop", "--design", "fc=20k,pm=30,type=2",
                           "-p", "rC=0.1")
    assert code == 0 and "type II compensator" in out and "fz2=0" in out and "fp2=0" in out


@pytest.mark.parametrize("argv, message", [
    (["--design", "fc=10k"], "--design needs pm"),
    (["--design", "fc=10k,pm=60,type=4"], "--design takes fc=HZ,pm=DEGREES"),
    (["--design", "fc=10k,pm=60", "--input", "duty"], "--input and --check do not apply"),
    (["--design", "fc=10k,pm=95"], "phase_margin_deg must be in (0, 90)"),
    (["--design", "fc=10k,pm=60,ri=0"], "--design ri (the op-amp circuit's input resistor) must be above 0 ohm; got 0.0"),
])
def test_bad_design_input_is_one_line(capsys, argv, message):
    code, out, err = run_cli(capsys, "bode", "buck", "--control", "voltage-loop", *argv)
    assert code == 2 and out == "" and err.count("\n") == 1 and message in err


def test_design_needs_the_voltage_loop(capsys):
    code, out, err = run_cli(capsys, "bode", "buck", "--design", "fc=10k,pm=60")
    assert code == 2 and "--design designs the compensator of --control voltage-loop" in err


def test_bode_breaks_a_current_mode_controllers_outer_loop_at_its_reference(capsys):
    code, out, _ = run_cli(capsys, "bode", "buck", "--control", "current-loop", "--input", "vloop", "--json")
    assert code == 0
    summary = json.loads(out)
    assert summary["kind"] == "loop gain" and summary["input"] == "vloop"
    assert 1e3 < summary["margins"]["crossover_hz"] < 1e4 and 30 < summary["margins"]["phase_margin_deg"] < 90


VOLTAGE_MODE = "netlists/circuits/voltage-mode-buck.cir"


@pytest.mark.parametrize("command", [["sensitivity"], ["bode", "--input", "vin"]], ids=["sensitivity", "bode"])
def test_an_analysis_about_an_unstable_orbit_is_refused_or_says_so(capsys, command):
    """At Vin = 33 V the voltage-mode buck's period-1 orbit has a multiplier at -2.006 (simulate --steady refuses
    it): its sensitivities and responses were printed 'on the periodic steady state', exit 0, and bode's JSON had
    no spectral radius. At 22 V the orbit is stable (|-0.7528 +- 0.3354j| = 0.82413)."""
    code, out, err = run_cli(capsys, command[0], VOLTAGE_MODE, *command[1:], "-p", "Vin=33")
    assert code == 2 and out == "" and len(err.strip().splitlines()) == 1
    assert "is unstable (Floquet spectral radius 2.006" in err and "--unstable" in err
    code, out, err = run_cli(capsys, command[0], VOLTAGE_MODE, *command[1:], "-p", "Vin=33", "--unstable", "--json")
    summary = json.loads(out)
    assert code == 0 and summary["stable"] is False and summary["spectral_radius"] == pytest.approx(2.006, abs=1e-3)
    assert err.startswith("warning: the periodic orbit of voltage-mode-buck.cir is unstable")
    code, out, err = run_cli(capsys, command[0], VOLTAGE_MODE, *command[1:], "--json")
    summary = json.loads(out)
    assert code == 0 and err == "" and summary["stable"] is True
    assert summary["spectral_radius"] == pytest.approx(0.82413, abs=1e-5)


@pytest.mark.parametrize("command", [["sensitivity"], ["bode", "--input", "vin"]], ids=["sensitivity", "bode"])
def test_an_analysis_about_an_orbit_newton_could_not_confirm_says_so(capsys, monkeypatch, command):
    """shoot() marks a converged orbit far (in periods of its slowest mode) from where Newton started, which Newton
    from the settled transient did not return to (a loop latched at duty 1 beside the regulating orbit): simulate
    --steady warns; sensitivity and bode printed that orbit's numbers silently. Here the stable orbit of the
    voltage-mode buck carries such a warning: both say it on stderr and in the JSON."""
    from dataclasses import replace

    from converters.analysis import periodic
    shoot, words = periodic.shoot, "the orbit lies ~1e+06 periods of its slowest mode from where Newton started"
    monkeypatch.setattr(periodic, "shoot", lambda *a, **k: replace(shoot(*a, **k), warning=words))
    code, out, err = run_cli(capsys, command[0], VOLTAGE_MODE, *command[1:], "--json")
    summary = json.loads(out)
    assert code == 0 and summary["stable"] is True and summary["orbit_warning"] == words
    what = "sensitivities" if command[0] == "sensitivity" else "frequency responses"
    assert err.strip() == f"warning: {words}: its {what} are that orbit's"


@pytest.mark.parametrize("args, words", [
    (["--fmax", "1e300"], "fmax must be a frequency in (0, 1e+08] Hz (1000 times the switching frequency); got 1e+300"),
    (["--fmin", "1e-6", "--check"], "the check injects at frequencies down to fs/20,000 (5 Hz): at 1e-06 Hz its common "
                                    "period spans 1e+11 switching periods"),
    (["--fmin", "20k", "--fmax", "20k"], "one frequency is --fmin F --fmax F --points 1"),
    (["--fmin", "10k", "--fmax", "20k", "--points", "1"], "one frequency is --fmin F --fmax F --points 1"),
])
def test_a_frequency_range_bode_cannot_answer_is_one_line(capsys, args, words):
    """--fmax 1e300 printed a table of nan with exit 0; --fmin 1e-6 --check asked numpy for 745 GiB (a traceback)."""
    code, out, err = run_cli(capsys, "bode", "buck", "--input", "duty", *args)
    assert code == 2 and out == "" and len(err.strip().splitlines()) == 1 and words in err


def test_one_frequency_and_a_time_limit(capsys, monkeypatch):
    """bode at one frequency (refused before: fmin must be below fmax), its value that of the same frequency in a
    sweep; --time-limit, listed in its help, bounds the command (refused before). (--time-limit sets the variable
    every worker reads: put back afterwards, or later tests' subprocesses would inherit 60 s.)"""
    monkeypatch.setenv("PCSUITE_TIME_LIMIT", "60")         # recorded, so restored (absent) after the test
    code, out, _ = run_cli(capsys, "bode", "buck", "--input", "duty", "--fmin", "20k", "--fmax", "20k", "--points", "1",
                           "--json", "--time-limit", "60")
    one = json.loads(out)
    assert code == 0 and one["frequency_hz"] == [20000.0]
    code, out, _ = run_cli(capsys, "bode", "buck", "--input", "duty", "--fmin", "10k", "--fmax", "40k", "--points", "3",
                           "--json")
    three = json.loads(out)
    assert three["frequency_hz"][1] == pytest.approx(20000.0, rel=1e-12)
    assert one["magnitude_db"][0] == pytest.approx(three["magnitude_db"][1], abs=1e-9)
    assert one["phase_deg"][0] == pytest.approx(three["phase_deg"][1], abs=1e-7)


def test_one_frequencys_check_injects_once(capsys):
    """--check at one frequency had injected at eight copies of it (the same two, 49 kHz and 48.98 kHz, four times
    each at fs/2). It injects once, at the frequency moved off fs/2, and the two responses agree to 1e-7 dB."""
    code, out, _ = run_cli(capsys, "bode", "buck", "--input", "duty", "--fmin", "50k", "--fmax", "50k", "--points", "1",
                           "--check", "--json")
    check = json.loads(out)["check"]
    assert code == 0 and check["frequency_hz"] == [pytest.approx(48979.5918, rel=1e-9)]      # 1 - 1/49 of fs/2
    assert abs(check["difference_db"][0]) < 1e-7


def test_bode_says_when_it_shows_part_of_its_table_and_what_fs_over_2_reads(capsys):
    """--points 12 printed 11 rows with no word (the table shows at most 11); at fs/2 (the default --fmax) a sampled
    system's response depends on the injection's phase (a voltage-mode buck: 9.20 dB with a sine, 5.75 dB with a
    cosine, -3.49 dB at 45 degrees, a tester's injections) and the table's 4.81 dB is their average: said."""
    code, out, _ = run_cli(capsys, "bode", "buck", "--control", "voltage-mode", "-p", "Vin=24.4", "--input", "vin",
                           "--points", "12")
    assert code == 0
    assert "  (11 of the 12 frequencies shown; --json holds every one)" in out
    assert "at and above fs/2 an injection's response depends on its phase" in out
    code, out, _ = run_cli(capsys, "bode", "buck", "--control", "voltage-mode", "-p", "Vin=24.4", "--input", "vin",
                           "--points", "5", "--fmax", "1k")
    assert code == 0 and "frequencies shown" not in out and "fs/2" not in out
