"""The report: scenes load strictly, the page refers only to files that exist, and it works in a real
browser (headless Chromium: every image loads)."""
import re
import time
from functools import partial
from html.parser import HTMLParser
from pathlib import Path

import pytest

from converters.errors import ParameterError
from validation.scenes import load_scene, scenes_of


@pytest.fixture(scope="session")
def report(tmp_path_factory, ngspice):
    from validation.cli import main
    out = tmp_path_factory.mktemp("report") / "default"
    assert main(["report", "default", "--out", str(out)]) == 0
    return out / "index.html"


class _Refs(HTMLParser):
    def __init__(self):
        super().__init__()
        self.refs = []

    def handle_starttag(self, tag, attrs):
        for name, value in attrs:
            if name in ("src", "href") and value and not value.startswith(("#", "http", "mailto:")):
                self.refs.append(value)


def test_every_file_the_page_refers_to_exists(report):
    parser = _Refs()
    parser.feed(report.read_text())
    assert len(parser.refs) >= 3 * len(scenes_of("default"))
    missing = [ref for ref in parser.refs if not (report.parent / ref).is_file()]
    assert missing == []
    for name in ("summary.csv", "metrics.json"):
        assert (report.parent / name).stat().st_size > 0
    assert sorted(p.name for p in (report.parent / "scenes" / "buck-dcm").iterdir()) == [
        "lcp.parquet", "modes.png", "overlay.png", "scope.html", "spice.parquet"]


def test_the_default_report_is_under_50_mb_and_its_waveforms_are_the_compared_windows(report):
    """Every scene's waveforms are those of the window its comparison measures (the buck's last 10 of 30 periods:
    its 10 us period), compressed (zstd, floats byte-stream-split); the whole folder under 50 MB."""
    import pyarrow.parquet as pq
    size = sum(path.stat().st_size for path in report.parent.rglob("*") if path.is_file())
    assert size < 50 << 20, size
    for simulator in ("lcp", "spice"):
        path = report.parent / "scenes" / "buck-ccm" / f"{simulator}.parquet"
        time = pq.read_table(path, columns=["time"]).column(0).to_numpy()
        assert time[-1] - time[0] == pytest.approx(10 / 100e3, rel=1e-3), (simulator, time[0], time[-1])
        column = pq.ParquetFile(path).metadata.row_group(0).column(1)
        assert column.compression == "ZSTD" and "BYTE_STREAM_SPLIT" in column.encodings


def test_every_default_scene_passes_and_the_header_names_the_versions(report):
    text = report.read_text()
    for key in ("pcsuite", "numpy", "scipy", "PySpice", "ngspice-39", "machine", "date"):
        assert key in text
    summary = (report.parent / "summary.csv").read_text()
    assert ",fail" not in summary and summary.count(",pass") >= len(scenes_of("default")) + 1


def test_every_section_of_the_default_report_is_measured(report):
    """None skipped: the trade-off (quick form, or the full size a make bench saved) and the stability map (whole)
    are measured by the report itself."""
    import json
    metrics = json.loads((report.parent / "metrics.json").read_text())
    statuses = {title: section["status"] for title, section in metrics["sections"].items()}
    assert [title for title, status in statuses.items() if status not in ("pass", "fail")] == []
    assert "skipped" not in metrics["verdict"]
    trade = metrics["sections"]["Speed-accuracy trade-off"]
    assert (trade["quick"], trade["runs"], trade["cases"], trade["periods"]) in ((True, 33, 3, 200), (False, 240, 6, 200))
    assert trade["failed_runs"] == 0 and len(trade["acceptance"]) == trade["cases"]
    stable = metrics["sections"]["Numerical stability at the extremes"]
    assert (stable["runs"], stable["lcp_nan_inf"], stable["ill_posed_refused"]) == (98, 0, 6)
    page = report.read_text()
    assert ("Quick form: 33 runs, 11 settings for each of 3 of the 6 cases (buck-dcm, boost-dcm, cuk-gdcm), 200 periods "
            "each." in page) == trade["quick"]


def _logged(log, name):
    """A section that notes its start and end in ``log`` (one line each, appended)."""
    from validation.report import Section
    with open(log, "a") as out:
        out.write(f"start {name}\n")
    with open(log, "a") as out:
        out.write(f"end {name}\n")
    return Section(name, f"<p>{name}</p>")


def test_a_section_timed_by_wall_clock_runs_after_the_others_alone(tmp_path):
    from functools import partial

    from validation.report import runs_alone
    from validation.suite import run_suite
    log = tmp_path / "log"
    sections = [("a", partial(_logged, log, "a")), ("timed", runs_alone(partial(_logged, log, "timed"))),
                ("b", partial(_logged, log, "b")), ("c", partial(_logged, log, "c"))]
    scenes, results = run_suite("t", sections, workers=2, progress=False, scenes=[])
    assert scenes == [] and [s.title for s in results] == ["a", "timed", "b", "c"]
    assert all(s.status == "pass" for s in results)
    lines = log.read_text().splitlines()
    assert lines[-2:] == ["start timed", "end timed"] and sorted(lines[:-2]) == sorted(
        f"{when} {name}" for name in "abc" for when in ("start", "end"))


def _quick(full: bool = False):
    from validation.report import Section
    return Section("q", "<p>q</p>", form="full" if full else "quick")


def test_a_section_with_a_quick_form_runs_it_unless_the_report_asks_for_the_full_size(tmp_path):
    """run_suite hands full to the builders marked has_quick_form only; the page's summary says which sections ran
    quick and how to run them whole; metrics.json and summary.csv carry the form."""
    import json

    from validation.report import Section, has_quick_form, write_report
    from validation.suite import run_suite
    sections = [("q", has_quick_form(_quick)), ("one form", partial(Section, "one form", "<p>x</p>"))]
    for full, form in ((False, "quick"), (True, "full")):
        _, results = run_suite("t", sections, workers=1, progress=False, scenes=[], full=full)
        assert [s.form for s in results] == [form, ""]
    _, results = run_suite("t", sections, workers=1, progress=False, scenes=[])
    index = write_report(results, tmp_path / "r", "mine")
    page = index.read_text()
    assert ("Quick form (1 of 2 sections: fewer points than the full study, the same checks; <code>pcsuite report "
            "mine --full</code> runs them at full size): q.") in page
    assert json.loads((tmp_path / "r" / "metrics.json").read_text())["sections"]["q"]["form"] == "quick"
    assert (tmp_path / "r" / "summary.csv").read_text().splitlines()[1:] == ["q,pass,quick,", "one form,pass,,"]


def test_the_quick_form_changes_only_settings_the_full_study_has():
    """[mechanics.quick] replaces keys of [mechanics] (a misspelt key would be silently ignored): each exists there,
    of the same kind, and each changes something."""
    from validation.defaults import MECHANICS, MECHANICS_QUICK, mechanics_settings
    quick = mechanics_settings(full=False)
    assert mechanics_settings(full=True) is MECHANICS and set(quick) == set(MECHANICS)
    for key, value in MECHANICS_QUICK.items():
        assert key in MECHANICS and type(value) is type(MECHANICS[key]), key
        if isinstance(value, dict):
            assert set(value) <= set(MECHANICS[key]) and quick[key] == {**MECHANICS[key], **value}, key
            assert any(MECHANICS[key][k] != v for k, v in value.items()), key
        else:
            assert quick[key] == value != MECHANICS[key], key


def test_full_is_refused_for_a_suite_without_a_quick_form(capsys, tmp_path):
    from validation.cli import main
    assert main(["report", "lcp", "--full", "--out", str(tmp_path / "r")]) == 2
    err = capsys.readouterr().err
    assert err == ("pcsuite: error: --full runs the quick-form sections of a suite at full size; 'lcp' has none (the "
                   "suites with some: mechanics)\n") and not (tmp_path / "r").exists()


def test_the_page_loads_every_image_in_headless_chromium(report, chromium):
    browser = chromium()
    try:
        browser.get(report.as_uri())
        browser.execute_script("return document.readyState")
        images = browser.execute_script(
            "return Array.from(document.images).map(i => [i.getAttribute('src'), i.complete, i.naturalWidth]);")
        title = browser.title
        browser.get((report.parent / "scenes" / "buck-ccm" / "scope.html").as_uri())     # a scene's scope
        for _ in range(100):
            if browser.execute_script("return !!(window.pcsuiteScope && pcsuiteScope.ready)"):
                break
            time.sleep(0.05)
        scope = browser.execute_script("return [pcsuiteScope.ready, pcsuiteScope.shown('vout')[0].length, "
                                       "pcsuiteScope.modeStripes()]")
        errors = [e for e in browser.get_log("browser") if e["level"] in ("SEVERE", "ERROR")]
    finally:
        browser.quit()
    assert scope[0] and scope[1] > 100 and errors == []
    assert scope[2] == ["pcsuite", "ngspice"]                 # both simulators' modes in the band
    assert title == "pcsuite report: default"
    assert len(images) >= 2 * len(scenes_of("default"))
    broken = [src for src, complete, width in images if not (complete and width > 0)]
    assert broken == []


def test_a_scene_with_an_unknown_key_or_a_bad_value_is_refused(tmp_path):
    bad_key = tmp_path / "bad.toml"
    bad_key.write_text('converter = "buck"\nduty = 0.5\n')
    with pytest.raises(ParameterError, match=r"unknown key 'duty' in scene bad.toml; valid keys: name, converter"):
        load_scene(bad_key)
    bad_param = tmp_path / "range.toml"
    bad_param.write_text('converter = "buck"\n[params]\nD = 1.5\n')
    with pytest.raises(ParameterError, match=r"scene range.toml \[params\]: D \(duty ratio\) must be in \[0, 1\]; got 1.5"):
        load_scene(bad_param)
    nested = tmp_path / "nested.toml"
    nested.write_text('converter = "boost"\n[methods.lcp]\nstep = 1e-8\n')
    with pytest.raises(ParameterError, match=r"unknown key 'step' in scene nested.toml \[methods.lcp\]; valid keys: h, theta"):
        load_scene(nested)
    unknown_param = tmp_path / "param.toml"
    unknown_param.write_text('converter = "cuk"\n[params]\nL = "10u"\n')
    with pytest.raises(ParameterError, match=r"unknown key 'L' in scene param.toml \[params\]; valid keys: Vin, L1"):
        load_scene(unknown_param)


def test_a_failing_scene_is_reported_with_its_reason_not_fatal(tmp_path, monkeypatch):
    from validation import suite
    from validation.report import write_report
    scene = load_scene(Path(suite.__file__).with_name("scenes") / "buck-dcm.toml")

    def explode(*args, **kwargs):
        raise RuntimeError("ngspice exploded on purpose")
    monkeypatch.setattr(suite, "compare", explode)
    result = suite.run_scene(scene)
    assert not result.ok and "ngspice exploded on purpose" in result.reason
    index = write_report([suite.scenes_summary([result]), suite.scene_section(result)], tmp_path / "r", "t")
    text = index.read_text()
    assert "Failed:" in text and "ngspice exploded on purpose" in text
    assert re.search(r"<td[^>]*fail[^>]*>fail</td>", text)


def test_a_report_that_fails_while_writing_leaves_the_previous_one_whole(tmp_path):
    from validation.report import Section, write_report
    target = tmp_path / "r"
    write_report([Section("good", "<p>first</p>", files={"a.txt": b"first"})], target, "t")
    broken = Section("bad", "<p>second</p>", files={"a.txt": b"second", "b.txt": None})
    with pytest.raises(TypeError):
        write_report([broken], target, "t")
    assert (target / "a.txt").read_bytes() == b"first" and "first" in (target / "index.html").read_text()
    assert [p.name for p in tmp_path.iterdir()] == ["r"]  # no staging directory left behind


def test_each_section_is_pass_fail_or_skipped_with_a_reason_and_a_failure_fails_the_command(tmp_path, monkeypatch,
                                                                                           capsys):
    import json

    from validation import sections
    from validation.cli import main
    from validation.report import Section

    def boom():
        raise RuntimeError("a solver diverged on purpose")

    def empty():
        return Section("Nothing measured", "<p>no data</p>", skipped=True, reason="no saved results: run X")
    monkeypatch.setitem(sections.EXTRA_SECTIONS, "lcp", [*sections.EXTRA_SECTIONS["lcp"], ("Boom", boom),
                                                         ("Nothing measured", empty)])
    out = tmp_path / "r"
    assert main(["report", "lcp", "--out", str(out), "--workers", "1"]) == 1          # a failing section: exit 1
    printed = capsys.readouterr().out
    assert "FAIL" in printed and "failed: Boom: RuntimeError: a solver diverged on purpose" in printed
    assert "skipped: Nothing measured: no saved results: run X" in printed
    metrics = json.loads((out / "metrics.json").read_text())
    statuses = {title: s["status"] for title, s in metrics["sections"].items()}
    assert set(statuses.values()) == {"pass", "fail", "skipped"}
    assert statuses["Boom"] == "fail" and statuses["Nothing measured"] == "skipped"
    assert all(s["reason"] for s in metrics["sections"].values() if s["status"] != "pass")
    assert metrics["verdict"].startswith("FAIL: 1 of ")
    page = (out / "index.html").read_text()
    assert "<p class='verdict fail' id='verdict'>FAIL: 1 of" in page
    assert "<a href='#boom'>Boom</a>" in page and "<section class='section-fail'>" in page and "<section class='section-skipped'>" in page
    import pandas as pd
    summary = pd.read_csv(out / "summary.csv")
    assert list(summary.columns) == ["section", "result", "form", "reason"]
    assert set(summary["result"]) == {"pass", "fail", "skipped"}


def test_the_scenes_summary_gives_a_netlist_scenes_numbers_under_its_outputs_name(tmp_path):
    """A netlist scene's comparison keys its output as the file names it (v(out)_mean_lcp): the summary's numeric
    columns were empty (NaN) for every netlist scene."""
    from validation import suite
    scene = load_scene(Path(suite.__file__).with_name("scenes") / "buck-dcm.toml")
    metrics = {"v(out)_mean_lcp": 6.96, "v(out)_mean_spice": 6.9601, "v(out)_mean_rel_error": 1.4e-5,
               "v(i)_mean_lcp": 1.0, "mode_sequence_lcp": "S1 > D1 > off", "lcp_wall_s": 0.01, "spice_wall_s": 0.5}
    table = suite.scenes_summary([suite.SceneResult(scene, True, metrics=metrics)]).files["scenes.csv"].decode()
    import io

    import pandas as pd
    row = pd.read_csv(io.StringIO(table)).iloc[0]
    assert (row["vout_lcp_V"], row["vout_spice_V"], row["rel_error"]) == (6.96, 6.9601, 1.4e-5)
    assert row["spice/lcp time"] == pytest.approx(50.0)


def test_a_scenes_conduction_verdict_takes_the_exact_prediction_to_what_each_side_resolves(tmp_path, ngspice):
    """A buck at R = 3.327 ohm is DCM for 3.6909e-5 of T (an independent exact orbit). The report's verdict took the
    small-ripple closed form (K = 0.6011 > 0.6: CCM) and passed, where the gdcm command's exact prediction said DCM
    and DISAGREE. It takes the exact one, and both sides' CCM agree with it to what they resolve, noted."""
    from validation.suite import _run_pwm_scene
    (tmp_path / "edge.toml").write_text('converter = "buck"\ndescription = "at the DCM boundary"\n'
                                        '[params]\nR = 3.327\n')
    result = _run_pwm_scene(load_scene(tmp_path / "edge.toml"))
    gdcm = result.gdcm
    assert (gdcm["closed_form"], gdcm["predicted"], gdcm["lcp"], gdcm["spice"]) == ("CCM", "DCM", "CCM", "CCM")
    assert gdcm["agree"] and gdcm["exact_held"] == pytest.approx(3.6909462e-5, abs=1e-9)
    assert [note for note in result.notes if "within what it resolves" in note] == gdcm["notes"] and \
        len(gdcm["notes"]) == 2


def test_a_scenes_classes_and_their_judgement_take_one_resolution(tmp_path, ngspice):
    """A buck at R = 3.35 ohm is DCM for 2.6213329e-3 of T (an independent exact orbit: matrix exponentials, the
    diode's turn-off by Brent's method, a fixed point of the period map). The scene's classes dropped runs under
    1 % of T, so both sides read CCM, while the judgement took the LCP's step (1e-3 T) as what it resolves: the
    scene failed its gdcm_verdict with no note. Classes and judgement now take the scene's 1 % of T."""
    from validation.suite import _run_pwm_scene
    (tmp_path / "near.toml").write_text('converter = "buck"\ndescription = "near the DCM boundary"\n'
                                        '[params]\nR = 3.35\n')
    result = _run_pwm_scene(load_scene(tmp_path / "near.toml"))
    gdcm = result.gdcm
    assert (gdcm["predicted"], gdcm["lcp"], gdcm["spice"]) == ("DCM", "CCM", "CCM") and gdcm["agree"] and result.ok
    assert gdcm["exact_held"] == pytest.approx(2.6213329e-3, abs=1e-9)
    assert gdcm["notes"] == [f"{side} reads CCM where the exact orbit is DCM (held 0.0026 of T): within what it "
                             "resolves (0.01 of T)" for side in ("lcp", "spice")]
