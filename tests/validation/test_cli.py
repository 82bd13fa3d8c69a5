"""The pcsuite command line: outputs as documented (docs/guide/command-line.md), one-line errors, no partial files."""
import json
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest

from validation.cli import main


def run_cli(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def test_lcp_solve_json_lists_all_basic_solutions(capsys, peer):
    code, out, _ = run_cli(capsys, "lcp", "solve", str(peer / "lcp_CPS_1.dat"), "--method", "enum", "--json")
    data = json.loads(out)
    assert code == 0 and data["status"] == "solved" and data["err"] == 0.0
    assert sorted(map(tuple, data["solutions"])) == [(0.0, 1.0), (1.0, 0.0)]
    assert set(data) >= {"status", "z", "w", "err", "iterations", "solutions"}


def test_lcp_solve_reports_no_solution_with_exit_code_one(capsys, tmp_path):
    path = tmp_path / "lcp_neg.dat"
    path.write_text("2\n0\n2\n2\n2 2\n-1 0\n0 -1\n-1 -1\n")
    code, out, _ = run_cli(capsys, "lcp", "solve", str(path), "--json")
    assert code == 1 and json.loads(out)["status"] == "no_solution"


@pytest.mark.parametrize("converter, control, span", [("buck", "pwm", {"periods": 1}),
                                                       ("boost", "smc", {"t_end": 50 * 2e-8}),
                                                       ("buck", "pwm", {"t_end": 50 * 1e-8})])
def test_the_one_time_set_up_runs_before_the_timed_run_for_every_kind_of_model(monkeypatch, converter, control, span):
    """simulate's setup_s: a coarse period of a periodic model; 50 default steps of a model without a fixed period
    (the sliding-mode boost: h 20 ns) or with a step (the buck with t_step: h = T/1000 = 10 ns)."""
    import converters.run
    from validation.cli.simulate import _set_up
    calls = []
    monkeypatch.setattr(converters.run, "run_converter", lambda model, p, **kw: calls.append(kw))
    params = {"t_step": 1e-3, "R_step": 5} if "t_end" in span and converter == "buck" else {}
    assert _set_up(converter, params, control, "lcp", False, {}) >= 0.0
    assert len(calls) == 1
    for key, value in span.items():
        assert calls[0][key] == pytest.approx(value, rel=1e-12)


def test_simulate_json_summary_and_csv_columns(capsys, tmp_path):
    target = tmp_path / "buck.csv"
    code, out, _ = run_cli(capsys, "simulate", "buck", "-p", "L=100u", "--periods", "50", "--out", str(target), "--json")
    assert code == 0
    summary = json.loads(out)
    assert set(summary) >= {"converter", "method", "options", "steps", "wall_s", "vout_mean", "mode_fractions"}
    assert summary["converter"] == "buck" and summary["steps"] == 50_000
    assert sum(summary["mode_fractions"].values()) == pytest.approx(1.0)
    frame = pd.read_csv(target)
    assert list(frame.columns) == ["time", "iL", "vC", "vout", "switch", "i_in", "i_switch", "v_switch", "i_diode",
                                   "v_diode", "i_cap", "mode"]
    assert set(frame["mode"]) <= {"CCM-ON", "CCM-OFF", "DCM"}
    assert set(frame["switch"]) == {0, 1}


def test_simulate_steady_reports_periods_and_cuk_columns(capsys, tmp_path):
    target = tmp_path / "cuk.parquet"
    code, out, _ = run_cli(capsys, "simulate", "cuk", "--steady", "--out", str(target), "--json")
    summary = json.loads(out)
    # every period simulated: Newton's (from rest, no fixed warm-up) and the 20 returned
    assert code == 0 and summary["steady_periods"] > 20 and summary["periods"] == 20
    assert summary["vout_mean"] == pytest.approx(-8.0, rel=1e-3)
    assert list(pd.read_parquet(target).columns) == ["time", "i1", "v1", "i2", "v2", "vout", "switch", "i_in", "i_switch",
                                                     "i_diode", "mode"]


@pytest.mark.parametrize("argv,match", [
    (["simulate", "buck", "-p", "L=-1"], "L (inductance) must be in (0, inf) H; got -1.0"),
    (["simulate", "buck", "-p", "C=0"], "C (output capacitance) must be in (0, inf) F; got 0.0"),
    (["simulate", "buck", "-p", "R=0"], "R (load resistance) must be in (0, inf) ohm; got 0.0"),
    (["simulate", "buck", "-p", "D=1.5"], "D (duty ratio) must be in [0, 1]; got 1.5"),
    (["simulate", "buck", "-p", "f_sw=-1k"], "f_sw (switching frequency) must be in (0, inf) Hz; got -1000.0"),
    (["simulate", "buck", "--h", "1e-4"], "h must be positive and below the switching period (1e-05 s); got 0.0001"),
    (["simulate", "flyback"], "CONVERTER must be one of buck, boost, buck-boost, cuk, prc or a netlist FILE.cir; got 'flyback'"),
    (["simulate", "buck", "-p", "Q=1"], "unknown parameter 'Q' for buck; valid names: Vin, L, C, R, f_sw, D, rL"),
    (["simulate", "buck", "-p", "L"], "-p takes NAME=VALUE (e.g. -p L=10u); got 'L'"),
    (["simulate", "buck", "--method", "magic"], "argument --method: invalid choice: 'magic'"),
])
def test_bad_input_is_one_line_nonzero_exit_and_no_file(capsys, tmp_path, argv, match):
    target = tmp_path / "out.csv"
    try:
        code = main(argv + ["--out", str(target)])
    except SystemExit as exc:  # argparse's own errors (same one-line format)
        code = exc.code
    _, err = capsys.readouterr()
    assert code != 0
    lines = err.strip().splitlines()
    assert len(lines) == 1 and match in lines[0]
    assert not target.exists()


def test_a_failed_run_leaves_an_existing_file_untouched(capsys, tmp_path):
    target = tmp_path / "keep.csv"
    target.write_text("good data\n")
    code = main(["simulate", "buck", "-p", "L=0", "--out", str(target)])
    assert code != 0 and target.read_text() == "good data\n"
    assert [p.name for p in tmp_path.iterdir()] == ["keep.csv"]  # no temporary left behind


def test_list_shows_every_converter_with_units(capsys):
    code, out, _ = run_cli(capsys, "list", "--json")
    info = json.loads(out)
    assert code == 0 and list(info["converters"]) == ["buck", "boost", "buck-boost", "cuk", "prc"]
    buck = {p["name"]: p for p in info["converters"]["buck"]["parameters"]}
    assert buck["L"]["unit"] == "H" and buck["L"]["default"] == 1e-5 and buck["rL"]["optional"]


def test_list_names_every_report_suite_without_importing_the_report():
    from validation.scenes import EXTRA_SUITES, suite_names
    from validation.sections import EXTRA_SECTIONS
    assert sorted(EXTRA_SUITES) == sorted(EXTRA_SECTIONS)
    code = ("import sys, io, contextlib, json\nfrom validation.cli import main\nbuf = io.StringIO()\n"
            "with contextlib.redirect_stdout(buf):\n    main(['list', '--json'])\n"
            "print(json.dumps([json.loads(buf.getvalue())['suites'], sorted(m for m in ('numba', 'pandas', "
            "'matplotlib', 'scipy') if m in sys.modules)]))")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                          cwd=Path(__file__).resolve().parents[2])
    suites, heavy = json.loads(done.stdout)
    assert suites == sorted(set(suite_names()) | set(EXTRA_SECTIONS)) and heavy == []


def test_console_script_runs_as_a_program():
    out = subprocess.run([sys.executable, "-m", "validation.cli", "simulate", "buck", "-p", "D=2"],
                         capture_output=True, text=True)
    assert out.returncode == 2
    assert out.stderr.strip() == "pcsuite: error: D (duty ratio) must be in [0, 1]; got 2.0"


def test_a_window_shorter_than_a_step_is_still_measured(capsys):
    code, out, _ = run_cli(capsys, "simulate", "boost", "--control", "smc-implicit", "--t-end", "3u", "--json")
    assert code == 0 and json.loads(out)["steps"] == 3


LIGHT_DCM = ["buck-boost", "-p", "D=0.7", "-p", "L=22u", "-p", "R=5k", "-p", "f_sw=250k"]
LIGHT_DCM_EXACT = -179.08860175                    # the exact (event-driven) orbit's mean of vout


def test_simulate_rtol_reports_each_value_with_its_error_estimate_method_and_h(capsys):
    code, out, err = run_cli(capsys, "simulate", *LIGHT_DCM, "--rtol", "1e-4", "--json")
    assert code == 0 and "warning" not in err
    summary = json.loads(out)
    accuracy = summary["accuracy"]
    assert accuracy["met"] and accuracy["rtol"] == 1e-4 and accuracy["method"] == "lcp"
    assert accuracy["h"] == pytest.approx(4e-6 / accuracy["steps_per_period"]) and accuracy["theta"] == 0.5
    mean = accuracy["quantities"]["vout_mean"]
    assert summary["vout_mean"] == mean["value"]
    assert abs(mean["value"] - LIGHT_DCM_EXACT) / 179.0886 <= 1e-4                   # measured 4.8e-6
    assert mean["relative_error_estimate"] <= 1e-4 / 4
    assert set(accuracy["quantities"]) >= {"vout_mean", "vout_ripple", "iL_rms", "iL_peak", "fraction_DCM"}
    (event,) = accuracy["events"]
    assert event["pair"] == "diode" and event["time_T"] == pytest.approx(0.7469041, abs=1e-5)
    assert summary["mode_fractions"]["DCM"] == pytest.approx(1 - 0.7469041, abs=1e-5)


def test_a_steady_run_1_percent_off_warns_and_the_default_is_not(capsys):
    """Backward Euler at the default step reads the light-load DCM buck-boost 1.05 % low and says so; the default
    (theta 0.5: the step resolves every time constant) reads it 2.0e-5 off, with no warning. Its diode's peak,
    which jumps at the switch's turn-off, is the right limit at that edge (the new configuration's pair at the
    edge's state): the exact orbit's 1.5272727 A, D T Vin / L = 0.7 * 4 us * 12 V / 22 uH (the sample a step later
    had read 1.4947 A, 2.1 % low, and a warning said so)."""
    code, out, err = run_cli(capsys, "simulate", *LIGHT_DCM, "--steady", "--json")
    summary = json.loads(out)
    assert code == 0 and abs(summary["vout_mean"] / LIGHT_DCM_EXACT - 1) < 3e-5
    assert summary["orbit"]["stable"] and summary["accuracy"]["vout_mean_error_estimate"] < 1e-3
    assert summary["measurements"]["i_diode"]["max"] == pytest.approx(0.7 * 4e-6 * 12 / 22e-6, rel=1e-9)
    assert summary["accuracy"]["measurement_error_estimates"]["i_diode"] < 1e-3 and "warnings" not in summary
    code, out, err = run_cli(capsys, "simulate", *LIGHT_DCM, "--steady", "--json", "--theta", "1")
    summary = json.loads(out)
    assert code == 0 and abs(summary["vout_mean"] / LIGHT_DCM_EXACT - 1) == pytest.approx(1.05e-2, rel=0.01)
    assert summary["accuracy"]["vout_mean_error_estimate"] == pytest.approx(1.05e-2, rel=0.01)
    (warning,) = summary["warnings"]
    assert warning.startswith("vout mean may be 1.1e-02 off (more than 0.001): the step is too coarse: use --rtol "
                              "1e-4 (or a smaller --h); efficiency may be 2.2e-02 off (more than 0.001; input power "
                              "1.4e-03): the step is too coarse: use --method event (exact at the switchings), a "
                              "smaller --h, or --rtol; measurements may be off by more than 0.01 (vout mean 1.1e-02, "
                              "vC mean 1.1e-02, v_diode mean 1.1e-02 and 2 more")
    code, out, err = run_cli(capsys, "simulate", *LIGHT_DCM, "--steady", "--theta", "1")
    assert "warning: vout mean may be 1.1e-02 off" in err


@pytest.mark.parametrize("argv, message", [
    (["--rtol", "1e-4", "--h", "1n"], "--rtol chooses the method and its step; give either --rtol or --h"),
    (["--rtol", "1e-4", "--method", "event"], "give either --rtol or --method"),
    (["--rtol", "0"], r"rtol must be in [1e-10, 0.1]; got 0"),
    (["--rtol", "abc"], "rtol"),
    (["--solver-rtol", "1e-8"], "--solver-rtol does not apply to --method lcp (its options: --theta, --grade, --growth, and --h)"),
    (["--method", "event", "--theta", "1"], "--theta does not apply to --method event (its options: none, and --h)"),
    (["--method", "smooth", "--theta", "1", "--eps", "1e-3"],
     "--theta does not apply to --method smooth (its options: --eps, --solver-rtol, and --h)"),
])
def test_accuracy_flags_are_never_ignored(capsys, argv, message):
    code, out, err = run_cli(capsys, "simulate", "buck", *argv)
    assert code == 2 and message in err and len(err.strip().splitlines()) == 1


def test_the_smoothing_solver_tolerance_is_solver_rtol(capsys):
    code, out, _ = run_cli(capsys, "simulate", "buck", "--method", "smooth", "--solver-rtol", "1e-8", "--periods", "2",
                           "--json")
    assert code == 0 and json.loads(out)["options"]["solver_rtol"] == 1e-8


def test_ngspice_options_on_simulate_and_compare(capsys, ngspice):
    code, out, _ = run_cli(capsys, "simulate", "buck", "--method", "spice", "--spice-tmax", "20n", "--spice-reltol",
                           "1e-4", "--spice-method", "trap", "--periods", "20", "--json")
    options = json.loads(out)["options"]
    assert code == 0 and options["tmax_fraction"] == pytest.approx(2e-3) and options["reltol"] == 1e-4
    assert options["method"] == "trap"
    code, out, _ = run_cli(capsys, "compare", "buck", "--spice-method", "trap", "--json")
    assert code == 0 and json.loads(out)["spice_options"]["method"] == "trap"
    code, _, err = run_cli(capsys, "simulate", "buck", "--spice-tmax", "20n")
    assert code == 2 and "--spice-tmax does not apply to --method lcp (its options: --theta, --grade, --growth, and --h)" in err
    code, _, err = run_cli(capsys, "simulate", "buck", "--method", "spice", "--spice-tmax", "20u")
    assert code == 2 and "--spice-tmax must be in (0, 1e-05) s" in err


def test_steps_and_periods_mean_what_they_say(capsys):
    code, out, _ = run_cli(capsys, "simulate", "buck", "--steady", "--periods", "7", "--json")
    summary = json.loads(out)
    assert code == 0 and summary["periods"] == 7 and summary["steps"] == 7000       # the run returned
    assert summary["steady_periods"] > 7                   # and every period simulated to reach the orbit
    assert summary["window_periods"] == 7


def test_a_gdcm_scene_is_labelled_gdcm(ngspice):
    from validation.scenes import load_scene
    from validation.suite import run_scene
    scene = load_scene(Path(__file__).resolve().parents[2] / "validation" / "scenes" / "cuk-gdcm.toml")
    result = run_scene(scene)
    assert result.gdcm["predicted"] == result.gdcm["lcp"] == result.gdcm["spice"] == "GDCM" and result.ok


def test_spice_steady_starts_on_the_lcp_orbit_and_runs_until_ngspice_settles(capsys, ngspice):
    code, out, _ = run_cli(capsys, "simulate", "cuk", "--method", "spice", "--steady", "--json")
    spice = json.loads(out)
    code_lcp, out, _ = run_cli(capsys, "simulate", "cuk", "--steady", "--json")
    lcp = json.loads(out)
    assert code == code_lcp == 0 and spice["spice_settled"] and spice["spice_settle"] <= 1e-5
    assert spice["steady_periods"] % 20 == 0 and spice["steady_periods"] >= 20
    assert spice["vout_mean"] == pytest.approx(lcp["vout_mean"], rel=1e-3)      # the diode's drop apart


def _strict(text: str):
    """json.loads refusing NaN and the infinities, as strict parsers (RFC 8259) do."""
    def refuse(constant):
        raise ValueError(f"not JSON: {constant}")
    return json.loads(text, parse_constant=refuse)


def test_json_output_is_strict_json_with_null_where_a_value_is_not_finite(capsys, tmp_path):
    # D = 0: no input power, the efficiency 0/0 (it printed NaN)
    code, out, _ = run_cli(capsys, "simulate", "buck", "-p", "D=0", "--periods", "20", "--json")
    assert code == 0 and _strict(out)["power"]["efficiency"] is None
    # M of 1e-320: z = q / M overflows (it printed Infinity and NaN)
    path = tmp_path / "lcp_tiny.dat"
    path.write_text("2\n0\n2 2\n2 2\n1e-320 0 0 1e-320\n-1 -1\n")
    code, out, _ = run_cli(capsys, "lcp", "solve", str(path), "--json")
    data = _strict(out)
    assert code != 0 and data["status"] != "solved" and None in data["z"]


def test_ctrl_c_is_one_line_and_the_shells_code(capsys, monkeypatch):
    from validation.cli import simulate

    def interrupted(args):
        raise KeyboardInterrupt
    monkeypatch.setattr(simulate, "run", interrupted)
    code, out, err = run_cli(capsys, "simulate", "buck")
    assert code == 130 and err == "pcsuite: interrupted\n" and out == ""


def test_a_sweep_where_no_point_succeeds_exits_with_one(capsys, tmp_path, monkeypatch):
    monkeypatch.setenv("PCSUITE_MAX_MEMORY", "4G")      # --max-memory sets it for the process: restored after the test
    code, out, _ = run_cli(capsys, "sweep", "buck", "--grid", "D=0.1:0.9:3", "--periods", "100000", "--max-memory", "16M",
                           "--no-progress", "--out", str(tmp_path / "s"), "--json")       # each point above the limit
    summary = json.loads(out)
    assert code == 1 and summary["ok"] == 0 and summary["failed"] == 3
    code, out, _ = run_cli(capsys, "sweep", "buck", "--grid", "D=0.1:0.9:3", "--periods", "20", "--no-progress",
                           "--out", str(tmp_path / "t"), "--json")
    assert code == 0 and json.loads(out)["ok"] == 3


def test_a_bad_time_limit_in_the_environment_is_refused_by_every_command(capsys, monkeypatch):
    """PCSUITE_TIME_LIMIT=abc was refused only by the runs that use a time limit (ngspice, iterative LCP solves)."""
    monkeypatch.setenv("PCSUITE_TIME_LIMIT", "abc")
    code, out, err = run_cli(capsys, "simulate", "buck", "--periods", "2")
    assert code == 2 and out == ""
    assert err == "pcsuite: error: PCSUITE_TIME_LIMIT must be a number of seconds in [0.1, 604800]; got 'abc'\n"


def test_an_ngspice_run_from_rest_says_whether_it_has_settled(capsys, ngspice):
    # --method spice from rest gave no accuracy and no warning; lcp and event warned for the same run
    code, out, _ = run_cli(capsys, "simulate", "buck", "--method", "spice", "--periods", "20", "--json")
    summary = json.loads(out)
    assert code == 0 and summary["accuracy"]["transient"] > 0.1
    assert summary["warnings"][0].startswith(f"vout mean may be {summary['accuracy']['transient']:.1e} off")
    code, out, _ = run_cli(capsys, "simulate", "buck", "--method", "spice", "--json")          # 500 periods
    summary = json.loads(out)
    assert summary["accuracy"]["transient"] < 1e-5 and "warnings" not in summary


def test_a_smoothed_run_that_has_not_settled_warns(capsys):
    # the smoothing method's own error is not estimated, but a transient is: it printed 9.07 V with no warning
    code, out, _ = run_cli(capsys, "simulate", "buck", "--method", "smooth", "--periods", "20", "--json")
    summary = json.loads(out)
    assert code == 0 and summary["accuracy"]["checked"] is False and summary["accuracy"]["transient"] > 0.1
    assert summary["warnings"][0].startswith(f"vout mean may be {summary['accuracy']['transient']:.1e} off")


@pytest.mark.parametrize("args, remedy", [(("cuk",), "use --steady"),
                                          (("cuk", "--steady", "--theta", "1"), "the step is too coarse")])
def test_a_warning_about_the_efficiency_names_an_efficiency_that_is_printed(capsys, args, remedy):
    """The ideal Cuk warned 'efficiency may be 5.7e-03 off' with no efficiency printed (the power line was shown
    only with losses); from rest the warning's cause is the transient its power balance still carries, not the
    step."""
    code, out, err = run_cli(capsys, "simulate", *args)
    (warning,) = [line for line in err.splitlines() if line.startswith("warning:")]
    efficiency = warning.split("efficiency may be ")[1]
    assert code == 0 and remedy in efficiency
    (line,) = [line for line in out.splitlines() if line.startswith("power over the last")]
    assert "efficiency" in line and "losses: none: ideal parts" in line


def test_the_time_limits_alarm_fires_again_if_its_stop_is_taken_for_something_else():
    """The alarm's stop is raised inside whatever runs; a handler on the way that takes it for a failed trial (Newton
    shooting did) would have left the run without a limit: the alarm is armed again for a second as it raises, and
    the command's one line cancels it."""
    import signal

    from converters.errors import TimeLimitReached
    from validation.cli import _time_is_up, main
    handler = _time_is_up(2.0)
    try:
        with pytest.raises(TimeLimitReached, match="time limit of 2 s"):
            handler(signal.SIGALRM, None)
        assert 0.5 < signal.getitimer(signal.ITIMER_REAL)[0] <= 1.0
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0.0)
    signal.setitimer(signal.ITIMER_REAL, 5.0)
    try:
        assert main(["simulate", "buck", "--h", "-1"]) == 2             # an error's one line ends the alarm
        assert signal.getitimer(signal.ITIMER_REAL)[0] == 0.0
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0.0)


@pytest.mark.parametrize("handler", ["ParameterError", "ResourceError", "ValueError", "Exception"])
def test_the_time_limits_stop_passes_every_handler_of_a_failed_trial_point_or_section(handler):
    """The alarm's stop lands inside whatever runs: Newton's trial (except ParameterError), a sweep's point or a
    report's section (except Exception) took it for their own failure and carried on (until the re-armed alarm hit
    something else). A BaseException, as Ctrl-C is, none of them takes it."""
    import signal

    from converters import errors
    from converters.errors import TimeLimitReached
    from validation.cli import _time_is_up
    caught = getattr(errors, handler, None) or {"ValueError": ValueError, "Exception": Exception}[handler]
    try:
        with pytest.raises(TimeLimitReached, match="time limit of 2 s"):
            try:
                _time_is_up(2.0)(signal.SIGALRM, None)
            except caught:
                pytest.fail(f"except {handler} took the time limit's stop")
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0.0)


def test_an_exact_run_too_short_to_check_says_so_instead_of_a_traceback(capsys):
    """The event method on a comparator loop over one period: its flows are exact and the run is too short for its
    window to be compared with the one before, so nothing is estimated; the summary printer read an estimate that
    was not there (KeyError, a traceback after the result)."""
    netlist = Path(__file__).resolve().parents[2] / "netlists" / "circuits" / "type2-loop-buck.cir"
    assert main(["simulate", str(netlist), "--method", "event", "--periods", "1"]) == 0
    out = capsys.readouterr().out
    assert "accuracy: exact flows (no step error); whether the run has settled is not estimated" in out


@pytest.mark.parametrize("duty, word", [("1", "opens"), ("0", "closes")])
def test_compare_refuses_a_duty_ratio_at_which_nothing_switches(capsys, duty, word):
    """At D = 1 (or 0) the buck's switch never opens (closes): its ripple is 0 and compare's relative checks divided
    by it, a FAIL at 8.9e7 (ngspice's RON leaving 8.9e-5 V) that said nothing of why."""
    from validation.cli import main
    assert main(["compare", "buck", "-p", f"D={duty}"]) == 2
    assert capsys.readouterr().err == (f"pcsuite: error: compare checks a switching converter; at D = {duty} the "
                                       f"switch never {word}: give D in (0, 1) (simulate runs the DC circuit)\n")
