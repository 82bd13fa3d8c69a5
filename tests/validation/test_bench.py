"""The speed-accuracy trade-off and the stability map: the measurements, their acceptance logic, the
``pcsuite bench`` files and the report sections built from them."""
import json

import numpy as np
import pandas as pd
import pytest

from validation import sections, stability, tradeoff
from validation.cli import main


@pytest.fixture(scope="module")
def lcp_map():
    """Every extreme case with both LCP schemes (44 runs, each in its own process)."""
    return stability.stability_table(("LCP theta=1", "LCP theta=0.5"), progress=False)


@pytest.mark.slow
def test_no_well_posed_extreme_case_gives_nan_or_inf_with_the_lcp_stepper(lcp_map):
    assert len(lcp_map) == 2 * len(stability.extreme_cases())
    assert (lcp_map["status"] == "ok").all(), lcp_map.loc[lcp_map["status"] != "ok", "error"].tolist()
    assert lcp_map["finite"].all() and not lcp_map["diverged"].any()
    # Backward Euler only dissipates (its discrete energy balance is exact at the step end).
    euler = lcp_map[lcp_map["method"] == "LCP theta=1"]
    assert (euler["energy_residual"] <= 1e-12).all()
    assert euler.loc[euler["vary"] == "h", "energy_residual"].min() < -0.1          # h = T/2 damps hard
    # theta = 0.5 creates energy when a diode switches inside a step (complementarity at the step end):
    # above the threshold at h = T/2 only, and it vanishes as the step shrinks.
    trap = lcp_map[(lcp_map["method"] == "LCP theta=0.5") & (lcp_map["vary"] == "h")].set_index("value")
    assert trap.loc[0.5, "verdict"] == "energy created" and trap.loc[0.5, "energy_residual"] > 1e-3
    assert 0 < trap.loc[1e-2, "energy_residual"] < 1e-5 and abs(trap.loc[1e-4, "energy_residual"]) < 1e-9
    flagged = lcp_map[lcp_map["verdict"] != "ok"]
    assert list(zip(flagged["method"], flagged["vary"], flagged["value"])) == [("LCP theta=0.5", "h", 0.5)]


def test_ill_posed_requests_are_refused_with_one_line_naming_the_parameter():
    table = stability.ill_posed_table()
    assert table["refused"].all() and len(table) == len(stability.ILL_POSED)
    for row in table.itertuples():
        assert "\n" not in row.message and "got" in row.message
        assert row.message.split()[0] == row.parameter
    assert "must be in (0, inf) H; got 0.0" in table.set_index("parameter").loc["L", "message"]


def test_event_method_balances_energy_exactly_and_an_ngspice_failure_is_counted(monkeypatch):
    from validation import spice
    cases = [c for c in stability.extreme_cases() if (c["vary"], c["value"]) in (("D", 1e-4), ("L", 1e-6), ("R", 1e9))]
    table = stability.stability_table(("event", "smooth"), cases, progress=False)
    event = table[table["method"] == "event"]
    assert (event["verdict"] == "ok").all() and (event["energy_residual"].abs() < 1e-10).all()
    assert (table.loc[table["method"] == "smooth", "energy_residual"].abs() < 1e-3).all()

    def fail(netlist, *args, **kwargs):
        raise spice.SpiceError("ngspice: timestep too small; time = 1e-07, timestep = 1.25e-22")
    monkeypatch.setattr(spice, "run_spice", fail)       # the forked worker inherits the patch
    failed = stability.stability_table(("ngspice",), cases[:1], progress=False)
    assert failed["verdict"].tolist() == ["error"] and "timestep too small" in failed["error"].iloc[0]
    assert stability.stability_summary(failed)[["runs", "ok", "errors"]].values.tolist() == [[1, 0, 1]]


def test_acceptance_takes_the_fastest_run_at_least_as_accurate_as_the_ngspice_default():
    default = "TMAX=T/100 RELTOL=0.001 trap"
    rows = [("a", "ngspice trap", default, 0.2, 1e-4), ("a", "LCP theta=1", "h=T/100", 0.001, 1e-3),
            ("a", "LCP theta=1", "h=T/1000", 0.0015, 9e-5), ("a", "LCP theta=0.5", "h=T/300", 0.0019, 1e-6),
            ("a", "event", "tol=1e-07T", 0.05, 5e-9), ("a", "event", "tol=1e-13T", 0.1, 1e-14),
            ("b", "ngspice trap", default, 0.2, 1e-4), ("b", "LCP theta=1", "h=T/1000", 0.0021, 1e-5),
            ("b", "event", "tol=1e-13T", 0.3, 1e-14)]
    runs = pd.DataFrame(rows, columns=["case", "family", "setting", "wall_s", "error"])
    table = tradeoff.acceptance(runs).set_index("case")
    assert table.loc["a", "lcp_setting"] == "LCP theta=1 h=T/1000"
    assert table.loc["a", "lcp_speedup"] == pytest.approx(0.2 / 0.0015)
    assert table.loc["a", "event_setting"] == "tol=1e-07T" and table.loc["a", "result"] == "pass"
    assert table.loc["b", "lcp_speedup"] == pytest.approx(0.2 / 0.0021) and table.loc["b", "result"] == "fail"


def test_the_default_trade_sets_the_default_theta_beside_the_other_at_each_step():
    runs = pd.DataFrame([("a", "LCP theta=1", "h=T/100", 0.002, 8e-5, False), ("a", "LCP theta=0.5", "h=T/100", 0.001, 4e-6, True),
                         ("a", "LCP theta=1", "h=T/10", 0.001, 1e-2, True), ("a", "LCP theta=0.5", "h=T/10", 0.001, 5e-1, False),
                         ("a", "event", "tol=1e-13T", 0.1, 1e-14, np.nan)],
                        columns=["case", "family", "setting", "wall_s", "error", "default"])
    trade = tradeoff.default_trade(runs).set_index("setting")
    assert list(trade.index) == ["h=T/100", "h=T/10"]
    assert trade.loc["h=T/100", "default_theta"] == 0.5 and trade.loc["h=T/100", "other_theta"] == 1.0
    assert trade.loc["h=T/100", "error_gain"] == pytest.approx(20.0) and trade.loc["h=T/100", "time_cost"] == 0.5
    assert trade.loc["h=T/10", "default_theta"] == 1.0 and trade.loc["h=T/10", "error_gain"] == pytest.approx(50.0)
    html = sections._default_trade_html(tradeoff.default_trade(runs))
    assert "picked theta 0.5 at 1, theta 1 at 1 of the steps; at each step it is 20 to 50 times as accurate" in html
    assert "in 0.50 to 1.00 times its time" in html
    assert "not in these runs" in sections._default_trade_html(tradeoff.default_trade(runs.drop(columns="default")))


def test_tradeoff_measures_every_method_against_the_exact_solution(ngspice):
    sweep = {"lcp_steps": (100, 1000), "thetas": (1.0, 0.5), "event_tols": (1e-13,), "smooth": ((1e-3, 1e-6),),
             "spice": (tradeoff.SPICE_DEFAULT,)}
    runs, refs = tradeoff.tradeoff_table((tradeoff.CASES[1],), sweep, periods=20, progress=False)
    assert (runs["failure"] == "").all() and len(runs) == 7
    ref = refs.iloc[0]
    assert ref["diode_events_per_period"] == 1 and ref["exact_mean_vout_V"] == pytest.approx(6.962476, rel=1e-6)
    runs = runs.set_index(["family", "setting"])
    event = runs.loc[("event", "tol=1e-13T")]
    assert event["error"] < 1e-8 and event["err_event_T"] < 1e-9
    # Backward Euler: first order in h; theta = 0.5 at least ten times better at each h.
    e100, e1000 = runs.loc[("LCP theta=1", "h=T/100"), "error"], runs.loc[("LCP theta=1", "h=T/1000"), "error"]
    assert 5 < e100 / e1000 < 20
    assert runs.loc[("LCP theta=0.5", "h=T/1000"), "error"] < e1000 / 10
    # the default at every step here: theta 0.5 (no mode of the ideal DCM buck is faster than T/100)
    assert list(runs["default"].dropna()) == [False, False, True, True]
    # The diode's turn-off instant: within a step for the stepper.
    assert runs.loc[("LCP theta=1", "h=T/1000"), "err_event_T"] <= 1e-3 + 1e-12
    spice_default = runs.loc[("ngspice trap", "TMAX=T/100 RELTOL=0.001 trap")]
    assert 1e-7 < spice_default["error"] < 1e-2 and spice_default["wall_s"] > 0
    smooth = runs.loc[("smooth", "eps=0.001 solver_rtol=1e-06")]
    assert 1e-5 < smooth["error"] < 1e-2                                       # O(eps)


@pytest.mark.slow
def test_bench_cli_writes_its_files_and_the_report_shows_them(tmp_path, monkeypatch, capsys):
    from validation import bench, sections
    from validation.report import write_report
    out = tmp_path / "bench"
    assert main(["bench", "--quick", "--no-spice", "--only", "tradeoff", "--periods", "5", "--out", str(out),
                 "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert set(summary) == {"tradeoff"} and summary["tradeoff"]["failed_runs"] == 0
    assert sorted(p.name for p in out.iterdir()) == sorted([*bench.TRADEOFF_FILES, "bench.json"])  # no temporaries
    assert json.loads((out / "bench.json").read_text())["tradeoff"]["periods"] == 5
    stiffness = pd.read_csv(out / "stiffness.csv")
    growth = stiffness["stiffness_rho_T"].to_numpy()
    np.testing.assert_allclose(growth[1:] / growth[:-1], 10.0, rtol=0.1)        # stiffness ~ 1/eps
    monkeypatch.setattr(bench, "DEFAULT_OUT", out)
    section = sections.saved_bench_section("tradeoff")
    assert section.title == "Speed-accuracy trade-off" and "tradeoff.png" in section.html
    assert section.metrics["runs"] == summary["tradeoff"]["runs"] and section.metrics["failed_runs"] == 0
    assert (section.metrics["quick"], section.metrics["periods"], section.metrics["cases"]) == (True, 5, 3)
    assert ("Quick form: 27 runs, 9 settings for each of 3 of the 6 cases (buck-dcm, boost-dcm, cuk-gdcm), 5 periods "
            "each, without ngspice.") in section.html
    assert sections.saved_bench_section("stability") is None
    # a quick or partial run is not the full size the default report would show instead of measuring its own
    assert not bench.full_size(json.loads((out / "bench.json").read_text())["tradeoff"])
    assert bench.full_size({"quick": False, "spice": True, "periods": 200})
    assert not bench.full_size({"quick": False, "spice": False, "periods": 200})
    index = write_report([section], tmp_path / "report", "t")
    for name in ("tradeoff.png", "tradeoff.csv", "tradeoff_acceptance.csv"):
        assert (index.parent / name).stat().st_size > 0
    assert main(["bench", "--periods", "1", "--out", str(out)]) == 2
    assert "periods must be an integer in [2, 100000]; got 1" in capsys.readouterr().err


def test_the_default_report_measures_the_trade_off_and_the_stability_map_itself(tmp_path, monkeypatch, ngspice):
    """Nothing saved by make bench (a fresh clone): both sections of the default suite measure now, none is skipped,
    and the trade-off says it is the quick form and at what size. (Shrunk here: 5 periods, 3 settings per case, the
    stability map over two extremes.)"""
    from validation import bench, sections
    monkeypatch.setattr(bench, "DEFAULT_OUT", tmp_path / "bench")
    collect = bench.collect_tradeoff
    monkeypatch.setattr(bench, "collect_tradeoff", lambda **kwargs: collect(**kwargs, periods=5))
    monkeypatch.setattr(tradeoff, "QUICK", {"lcp_steps": (100,), "thetas": (0.5,), "event_tols": (1e-13,), "smooth": (),
                                            "spice": (tradeoff.SPICE_DEFAULT,)})
    cases = [c for c in stability.extreme_cases() if (c["vary"], c["value"]) in (("h", 0.5), ("R", 1e9))]
    monkeypatch.setattr(stability, "extreme_cases", lambda: cases)
    built = dict(sections.EXTRA_SECTIONS["default"])
    trade = built["Speed-accuracy trade-off"]()
    assert trade.status != "skipped" and trade.title == "Speed-accuracy trade-off"
    assert (trade.metrics["runs"], trade.metrics["failed_runs"], trade.metrics["quick"], trade.metrics["cases"]) == (
        9, 0, True, 3)
    assert [row["case"] for row in trade.metrics["acceptance"]] == ["buck-dcm", "boost-dcm", "cuk-gdcm"]
    assert ("Quick form: 9 runs, 3 settings for each of 3 of the 6 cases (buck-dcm, boost-dcm, cuk-gdcm), 5 periods "
            "each. <code>make bench</code> measures the full size (6 cases x 40 settings = 240 runs of 200 periods) "
            "and the next report shows it.") in trade.html
    assert "Measured for this report in " in trade.html
    stable = built["Numerical stability at the extremes"]()
    assert stable.status == "pass" and stable.metrics["runs"] == 2 + 5 and stable.metrics["lcp_nan_inf"] == 0
    assert stable.metrics["ill_posed_refused"] == len(stability.ILL_POSED)
    assert "Measured for this report in " in stable.html and "The whole map: 7 runs." in stable.html
    assert not (tmp_path / "bench").exists()                       # measured for the report, not saved


def test_a_full_size_bench_saved_by_make_bench_refines_the_default_report(tmp_path, monkeypatch):
    """The trade-off saved by a full-size pcsuite bench is shown (with its date and size) rather than measured."""
    from validation import bench, sections
    out = tmp_path / "bench"
    out.mkdir()
    runs = pd.DataFrame([{"case": case.name, "family": "LCP theta=1", "setting": f"h=T/{steps}", "wall_s": steps * 1e-5,
                          "error": 1e-2 / steps, "failure": ""} for case in tradeoff.CASES for steps in (100, 1000)])
    files = {"tradeoff.csv": runs, "tradeoff_acceptance.csv": pd.DataFrame([{"case": "buck-ccm", "result": "pass"}]),
             "tradeoff_references.csv": pd.DataFrame([{"case": "buck-ccm"}]),
             "stiffness.csv": pd.DataFrame([{"eps": 1e-3}])}
    for name, frame in files.items():
        frame.to_csv(out / name, index=False)
    (out / "tradeoff.png").write_bytes(b"png")
    (out / "bench.json").write_text(json.dumps({"tradeoff": {"quick": False, "spice": True, "periods": 200,
                                                             "date": "2026-01-02 03:04:05 UTC"}}))
    monkeypatch.setattr(bench, "DEFAULT_OUT", out)

    def measured(**kwargs):
        raise AssertionError("the saved full-size trade-off is shown, not measured again")
    monkeypatch.setattr(bench, "collect_tradeoff", measured)
    section = dict(sections.EXTRA_SECTIONS["default"])["Speed-accuracy trade-off"]()
    assert section.status == "pass" and (section.metrics["quick"], section.metrics["cases"]) == (False, 6)
    assert "Saved by pcsuite bench on 2026-01-02 03:04:05 UTC" in section.html
    assert ("Full size: 12 runs, 2 settings for each of 6 of the 6 cases (buck-ccm, buck-dcm, boost-ccm, boost-dcm, "
            "cuk-ccm, cuk-gdcm), 200 periods each.") in section.html


def test_the_reports_quick_trade_off_judges_accuracy_not_the_loaded_machines_speed():
    """Under another process's load an event run took 150-250 ms against ngspice's 120 ms, and the default report
    (its quick trade-off) failed: its verdict is on accuracy; make bench's full size judges the speed-ups."""
    import io

    import pandas as pd

    from validation.sections import tradeoff_section

    def csv(frame):
        buffer = io.StringIO()
        frame.to_csv(buffer, index=False)
        return buffer.getvalue().encode()
    runs = pd.DataFrame({"case": ["buck-dcm"] * 3, "family": ["ngspice", "LCP theta=1", "event"],
                         "setting": ["TMAX=T/100 RELTOL=0.001 trap", "h=T/1000", "tol=1e-13"],
                         "wall_s": [0.12, 0.001, 0.2], "error": [1e-3, 5e-4, 1e-12], "failure": ["", "", ""]})
    slow = pd.DataFrame([{"case": "buck-dcm", "spice_default_error": 1e-3, "spice_default_wall_s": 0.12,
                          "lcp_setting": "LCP theta=1 h=T/1000", "lcp_speedup": 120.0, "event_setting": "tol=1e-13",
                          "event_wall_s": 0.2, "result": "fail"}])
    files = {"tradeoff.csv": csv(runs), "tradeoff_acceptance.csv": csv(slow), "tradeoff_references.csv": csv(
        pd.DataFrame({"case": ["buck-dcm"]})), "stiffness.csv": csv(pd.DataFrame({"eps": [1e-4]}))}
    assert tradeoff_section(files, {"quick": True, "periods": 200}, "Measured.").ok
    assert not tradeoff_section(files, {"quick": False, "periods": 200}, "Measured.").ok
    inaccurate = slow.drop(columns=["event_setting"])
    files["tradeoff_acceptance.csv"] = csv(inaccurate)
    assert not tradeoff_section(files, {"quick": True, "periods": 200}, "Measured.").ok


def test_a_full_disk_while_saving_the_bench_leaves_the_earlier_set(tmp_path, monkeypatch):
    """The bench's tables, plots and bench.json were written one file at a time: a disk that filled after the first
    left a new table beside the earlier ones. They are staged together now."""
    import errno
    import os

    import validation.bench as bench
    from converters.errors import ParameterError
    monkeypatch.setattr(bench, "collect_stability", lambda spice, progress: (
        {name: f"new {name}".encode() for name in bench.STABILITY_FILES}, {"runs": 1}))
    out = tmp_path / "bench"
    out.mkdir()
    earlier = {name: f"earlier {name}".encode() for name in bench.STABILITY_FILES}
    for name, data in earlier.items():
        (out / name).write_bytes(data)
    (out / "bench.json").write_text("{}")
    real, calls = os.fsync, []

    def full_on_the_second(fd):
        calls.append(fd)
        if len(calls) == 2:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        return real(fd)
    monkeypatch.setattr(os, "fsync", full_on_the_second)
    with pytest.raises((OSError, ParameterError)):
        bench.run_bench(out, only="stability", progress=False)
    assert {name: (out / name).read_bytes() for name in earlier} == earlier
    assert (out / "bench.json").read_text() == "{}"
