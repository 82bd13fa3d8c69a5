"""Scopes (validation.scope): the decimation keeps a one-step spike, the page's sums are the run's own measure, and
the page works in headless Chromium: no console error, cursors at two times give the mean and RMS pcsuite measures
between them (to 1e-9), a million-step run's page opens in under 2 s and weighs under 10 MB."""
import json
import time

import numpy as np
import pytest

from converters.errors import ParameterError
from converters.run import run_converter
from validation import scope as scope_module
from validation.cli import main
from validation.scope import Scope, Trace, minmax_rows, of_trajectory, write_scope


def _spiky(n=1_000_000, at=654_321):
    t = np.linspace(0.0, 1e-2, n)
    v = np.sin(2 * np.pi * 1e3 * t)
    v[at] = 7.5                      # one step wide
    v[at + 1000] = -9.0
    return t, v


def test_min_max_decimation_keeps_a_one_step_spike_and_every_row_of_a_short_run():
    t, v = _spiky()
    rows = minmax_rows(v, 2000)
    assert rows.size <= 4 * 2000 and np.all(np.diff(rows) > 0)
    assert v[rows].max() == 7.5 and v[rows].min() == -9.0
    assert rows[0] == 0 and rows[-1] == v.size - 1
    assert np.array_equal(minmax_rows(v[:8000], 2000), np.arange(8000))


@pytest.mark.parametrize("theta", [0.5, 1.0])
def test_the_pages_step_sums_are_the_runs_own_mean_and_rms(theta):
    """The linear rule with the edge steps read in their own configuration (theta 0.5), the end-point rule
    (theta 1): the sums the page adds are pcsuite's Trajectory.mean and rms, to 1e-12."""
    tr = run_converter("buck", {}, t_end=2e-4, theta=theta)
    trace = of_trajectory(tr, ["iL", "vout", "switch"]).traces[0]
    assert trace.rule == ("end" if theta == 1.0 else "linear")
    i, j = 1234, 15678
    for name in ("iL", "vout", "switch"):
        one, two = trace.step_terms(name)
        span = tr.t[j] - tr.t[i]
        assert one[i:j].sum() / span == pytest.approx(tr.mean(name, t0=tr.t[i], t1=tr.t[j]), rel=1e-12)
        assert np.sqrt(two[i:j].sum() / span) == pytest.approx(tr.rms(name, t0=tr.t[i], t1=tr.t[j]), rel=1e-12)
    if theta == 0.5:
        assert trace.edge_rows.size > 0 and "switch" in trace.edge_values


def test_a_scope_says_which_means_read_the_steppers_pair_share_at_each_steps_end():
    """A Cockcroft-Walton ladder's diode currents charge its capacitors: the run's mean reads their share by the
    end-point rule (the charge the stepper moved; Trajectory.mean), which the page's linear rule does not: the scope
    says so, for those signals only (a capacitor's voltage, a state, reads the same), and a stored run's page too.
    The synchronous buck's body diode, whose current the inductor's fixes (B's null space), is not named."""
    from pathlib import Path

    from validation.scope import of_frame, scope_meta
    circuits = Path(__file__).resolve().parents[2] / "netlists" / "circuits"
    tr = run_converter(str(circuits / "cockcroft-walton.cir"), steady=True, periods=1)
    trace = of_trajectory(tr, ["v(cs4)", "i(d8)", "i(r1)"]).traces[0]
    assert "means of i(d8) read the diodes' share at each step's end" in trace.note and "v(cs4)" not in trace.note
    assert "i(r1)" not in trace.note                 # the load's current is the output capacitor's voltage over R
    one, _ = trace.step_terms("i(d8)")
    page, run = one.sum() / (tr.t[-1] - tr.t[0]), tr.mean("i(d8)")
    assert abs(page / run - 1) > 0.03                # the page's linear rule: half a step of each jump (4.5 %)
    meta = scope_meta(tr, ["v(cs4)", "i(d8)"])
    frame = tr.to_pandas()[["time", "v(cs4)", "i(d8)"]]
    assert "means of i(d8)" in of_frame(frame, {"scope": meta}).traces[0].note
    sync = run_converter(str(circuits / "sync-buck-thermal.cir"), steady=True, periods=1)
    assert sync.pair_moved(["i(d1)", "i(d2)", "i(s2)", "i(l1)"]) == []


def test_a_scope_refuses_what_it_cannot_draw():
    with pytest.raises(ParameterError, match="non-decreasing, with 2 samples or more; got 1 samples"):
        Trace("run", np.zeros(1), {})
    with pytest.raises(ParameterError, match="signal 'v' has 3 samples where time has 2"):
        Trace("run", np.arange(2.0), {"v": np.zeros(3)})
    with pytest.raises(ParameterError, match="rule must be 'linear' or 'end'; got 'exact'"):
        Trace("run", np.arange(2.0), {}, rule="exact")
    tr = run_converter("buck", {}, t_end=2e-5)
    with pytest.raises(ParameterError, match="signals must be among iL, vC, .*; got 'nope'"):
        of_trajectory(tr, ["nope"])


def _open(browser, page, timeout=10.0):
    browser.get(page.resolve().as_uri())
    end = time.monotonic() + timeout
    while not browser.execute_script("return !!(window.pcsuiteScope && pcsuiteScope.ready)"):
        assert time.monotonic() < end, "the scope never became ready"
        time.sleep(0.05)


def _errors(browser):
    return [e for e in browser.get_log("browser") if e["level"] in ("SEVERE", "ERROR")]


def _cursors(browser, a, b):
    return browser.execute_async_script(
        "const done = arguments[arguments.length - 1];"
        f"pcsuiteScope.setCursors({a!r}, {b!r}).then(done, (e) => done(String(e)));")


def _measured(chromium, page, a, b):
    """Open ``page``, move the cursors to ``a`` and ``b``: (the times they took, the readout's cells); no console
    error on the way."""
    browser = chromium()
    try:
        _open(browser, page)
        measured = _cursors(browser, a, b)
        cells = _readout(browser)
        errors = _errors(browser)
    finally:
        browser.quit()
    assert errors == []
    return measured, cells


def _readout(browser):
    """The readout's cells as the page shows them: {(signal, source, quantity): value}."""
    cells = browser.execute_script(
        "return Array.from(document.querySelectorAll('#readout td[data-quantity]')).map((td) => "
        "[td.dataset.signal, td.dataset.source, td.dataset.quantity, td.dataset.value]);")
    return {(s, src, q): float(v) for s, src, q, v in cells if v not in ("undefined", "")}


@pytest.mark.parametrize("inline", [True, False], ids=["inline", "chunked"])
def test_cursors_at_two_times_show_the_mean_and_rms_pcsuite_measures(chromium, tmp_path, monkeypatch, inline):
    """The page in headless Chromium: no console error; cursors moved to two times (between samples: each snaps
    to the nearest) show the times they took and, per signal, the value there and the mean and RMS between them
    that Trajectory.mean and rms give over the same times, to 1e-9 relative; chunked, the page reads the chunks at
    the cursors from its data folder."""
    if not inline:
        monkeypatch.setattr(scope_module, "INLINE_BYTES", 0)
        monkeypatch.setattr(scope_module, "CHUNK_ROWS", 5000)      # cursors inside chunks, whole chunks between
    tr = run_converter("buck", {}, t_end=3e-4)
    page = tmp_path / "run.html"
    written = write_scope(of_trajectory(tr, title="buck"), page)
    assert len(written) == (1 if inline else 1 + -(-(tr.t.size - 1) // 5000))
    measured, cells = _measured(chromium, page, 1.234567e-4, 2.71828e-4)
    ta, tb = measured["A"], measured["B"]
    assert ta in tr.t and tb in tr.t
    assert abs(ta - 1.234567e-4) <= 1e-7 and abs(tb - 2.71828e-4) <= 1e-7      # the nearest samples (h = 1e-8)
    for name in ("iL", "vC", "vout", "switch"):
        source = tr.method
        assert cells[(name, source, "mean")] == pytest.approx(tr.mean(name, t0=ta, t1=tb), rel=1e-9)
        assert cells[(name, source, "rms")] == pytest.approx(tr.rms(name, t0=ta, t1=tb), rel=1e-9)
        row = int(np.flatnonzero(tr.t == ta)[0])
        assert cells[(name, source, "a")] == tr.signal(name)[row]


def test_stacked_charts_span_the_same_times_however_many_there_are(chromium, tmp_path):
    """Twelve charts, more than a screen holds: every plot area (and the mode band's) starts and ends at the same
    pixels, so a time lies under one x in all of them (charts made after the page's scroll bar appeared were
    narrower)."""
    t = np.linspace(0.0, 1e-3, 1001)
    values = {f"v{k}": np.sin(2 * np.pi * (k + 1) * 1e3 * t) for k in range(12)}
    modes = np.where(t < 5e-4, "ON", "OFF")
    page = tmp_path / "many.html"
    write_scope(Scope("many", (Trace("run", t, values, modes=modes),), tuple(values), {}), page)
    browser = chromium()
    try:
        _open(browser, page)
        areas = browser.execute_script("return pcsuiteScope.plotAreas()")
        errors = _errors(browser)
    finally:
        browser.quit()
    assert errors == [] and len(areas) == 13
    assert len({tuple(area) for area in areas}) == 1, areas


def test_gaps_and_hostile_names_neither_blank_the_page_nor_hide_a_spike(chromium, tmp_path):
    """NaN samples (a failed sweep point; a signal undefined for a while) made the page's JSON invalid (NaN) and
    blanked it; a NaN in a screen column hid that column's minimum. A column name from a file that opens an HTML
    comment and a script tag ended the page's data early. Now: the page opens without a console error, a NaN is a
    gap (null), the spike beside it is drawn, and the name shows as written."""
    t = np.linspace(0.0, 1.0, 200_001)
    v = np.sin(2 * np.pi * 5 * t)
    v[1000:1100] = np.nan
    v[1150] = -4.0                               # in the same screen column as the gap's end
    name = "<!--<script>v"
    page = tmp_path / "gaps.html"
    write_scope(Scope("gaps", (Trace("run", t, {name: v}),), (name,), {name: "V"}), page)
    rows = minmax_rows(v, 2000)
    assert np.nanmin(v[rows]) == -4.0 and np.isnan(v[rows]).any()
    browser = chromium()
    try:
        _open(browser, page)
        shown = browser.execute_script(f"return pcsuiteScope.shown({name!r})")
        labels = browser.execute_script("return Array.from(document.querySelectorAll('#controls label')).map("
                                        "(l) => l.textContent.trim())")
        errors = _errors(browser)
    finally:
        browser.quit()
    assert errors == []
    assert None in shown[1] and min(x for x in shown[1] if x is not None) == -4.0
    assert name in labels


def test_a_stored_files_hostile_metadata_is_refused_or_ignored_in_one_line(tmp_path, capsys):
    """Units as a list, edge rows past a double or fractional, JSON nested past the parser: ``view`` writes its page
    (the rule not trusted) or says why in one line, never a traceback; a folder's files it did not write stay."""
    import pandas as pd
    import pyarrow as pa
    import pyarrow.parquet as pq
    frame = pd.DataFrame({"time": np.arange(5.0), "v": np.arange(5.0)})
    for meta in ('{"units": ["V"], "scope": {"rule": "linear", "edge_rows": [1e400], "edge_values": {"v": [1]}}}',
                 '{"scope": {"rule": "linear", "edge_rows": [1.5], "edge_values": {"v": [1]}}}',
                 "[" * 100_000 + "]" * 100_000):
        table = pa.Table.from_pandas(frame, preserve_index=False)
        pq.write_table(table.replace_schema_metadata({b"pcsuite": meta.encode()}), tmp_path / "run.parquet")
        assert main(["view", str(tmp_path / "run.parquet"), "--out", str(tmp_path / "run.html"), "--no-open"]) == 0
        assert "linear rule on its samples" in (tmp_path / "run.html").read_text()
    capsys.readouterr()
    folder = tmp_path / "big_files"
    folder.mkdir()
    (folder / "test-common.js").write_text("mine")
    (folder / "t0-c999.js").write_text("an old chunk")
    t = np.linspace(0, 1, 600_000)
    monkey = scope_module.INLINE_BYTES
    scope_module.INLINE_BYTES = 0
    try:
        write_scope(Scope("big", (Trace("run", t, {"v": t}),), ("v",), {}), tmp_path / "big.html")
    finally:
        scope_module.INLINE_BYTES = monkey
    assert (folder / "test-common.js").read_text() == "mine" and not (folder / "t0-c999.js").exists()


def test_a_stored_event_run_says_its_page_does_not_integrate_its_exact_pieces(tmp_path, capsys):
    run = tmp_path / "event.parquet"
    assert main(["simulate", "buck", "--method", "event", "--t-end", "1e-4", "--out", str(run), "--json"]) == 0
    capsys.readouterr()
    assert main(["view", str(run), "--out", str(tmp_path / "event.html"), "--no-open"]) == 0
    assert scope_module.EXACT_NOTE in (tmp_path / "event.html").read_text()


def test_view_opens_a_stored_run_that_integrates_as_the_run_did(chromium, tmp_path, capsys):
    """``simulate --out RUN.parquet`` stores the run's rule and edge starts; ``pcsuite view`` reads them back: the
    cursors' mean of the switch command (a signal with an edge at each switching) is the run's own."""
    run = tmp_path / "run.parquet"
    assert main(["simulate", "buck", "--t-end", "2e-4", "--out", str(run), "--json"]) == 0
    capsys.readouterr()
    page = tmp_path / "view.html"
    assert main(["view", str(run), "--out", str(page), "--no-open"]) == 0
    assert capsys.readouterr().out.strip() == f"scope: {page.resolve().as_uri()}"
    tr = run_converter("buck", {}, t_end=2e-4)
    measured, cells = _measured(chromium, page, 1.00005e-4, 1.70003e-4)
    ta, tb = measured["A"], measured["B"]
    for name in ("iL", "switch"):
        assert cells[(name, "lcp", "mean")] == pytest.approx(tr.mean(name, t0=ta, t1=tb), rel=1e-9)
        assert cells[(name, "lcp", "rms")] == pytest.approx(tr.rms(name, t0=ta, t1=tb), rel=1e-9)


def test_a_one_parameter_sweeps_summary_is_a_scope_of_its_metrics(chromium, tmp_path, capsys):
    """``sweep`` over one parameter writes summary.html beside summary.png: each metric over the swept parameter;
    the cursors at two grid points read the stored metrics there (a 2-D grid gets no scope)."""
    import pandas as pd
    out = tmp_path / "sweep"
    assert main(["sweep", "buck", "--grid", "Vin=8:16:5", "--metric", "vout.mean", "--metric", "iL.rms", "--out",
                 str(out), "--no-progress", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["summary_scope"] == str(out / "summary.html")
    frame = pd.read_parquet(out / "parts").sort_values("Vin")
    measured, cells = _measured(chromium, out / "summary.html", 10.2, 13.9)
    assert (measured["A"], measured["B"]) == (10.0, 14.0)
    for metric in ("vout.mean", "iL.rms"):
        stored = dict(zip(frame["Vin"], frame[metric]))
        assert cells[(metric, "sweep", "a")] == stored[10.0] and cells[(metric, "sweep", "b")] == stored[14.0]
    grid = tmp_path / "grid"
    assert main(["sweep", "buck", "--grid", "Vin=8:16:2", "--grid", "R=5:10:2", "--out", str(grid), "--no-progress",
                 "--json"]) == 0
    assert not (grid / "summary.html").exists() and (grid / "summary.png").is_file()


@pytest.mark.parametrize("argv, message", [
    (["view", "{tmp}/none.parquet", "--no-open"],
     "path must be a run's .parquet file; {tmp}/none.parquet does not exist"),
    (["view", "{tmp}/bad.parquet", "--no-open"], "{tmp}/bad.parquet could not be read as Parquet"),
    (["view", "{tmp}/x.txt", "--no-open"], "path must be a run's .parquet file or a report's folder; got {tmp}/x.txt"),
    (["view", "{tmp}", "--no-open"], "a report's folder \\(with index.html\\), a scene's folder \\(with "
                                     "scope.html\\) or a sweep's \\(with summary.html\\); {tmp} has none"),
    (["view", "{tmp}/bad.parquet", "--out", "{tmp}/o.png"], "--out must end in .html; got '{tmp}/o.png'"),
])
def test_view_refuses_what_is_not_a_stored_run_in_one_line(tmp_path, capsys, argv, message):
    (tmp_path / "bad.parquet").write_text("not parquet")
    (tmp_path / "x.txt").write_text("")
    tmp = str(tmp_path)
    assert main([a.replace("{tmp}", tmp) for a in argv]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    import re
    assert re.search(message.replace("{tmp}", re.escape(tmp)), err), err


def test_a_stored_runs_malformed_scope_metadata_is_not_trusted():
    """A file's metadata saying edge rows out of range (or of the wrong length) is read as no rule at all: the page
    says it reads the linear rule on the samples."""
    import pandas as pd
    frame = pd.DataFrame({"time": np.arange(5.0), "v": np.arange(5.0)})
    for stored in ({"rule": "linear", "edge_rows": [9], "edge_values": {"v": [1.0]}},
                   {"rule": "linear", "edge_rows": [1, 2], "edge_values": {"v": [1.0]}},
                   {"rule": "exact"}, "nonsense", {"rule": "linear", "edge_rows": "x"}):
        trace = scope_module.of_frame(frame, {"scope": stored}).traces[0]
        assert trace.edge_rows.size == 0 and "linear rule on its samples" in trace.note
    good = scope_module.of_frame(frame, {"scope": {"rule": "end", "edge_rows": [], "edge_values": {}}}).traces[0]
    assert good.rule == "end" and good.note == ""


@pytest.mark.slow
def test_a_million_step_runs_page_opens_in_under_2_s_weighs_under_10_mb_and_keeps_a_spike(chromium, tmp_path):
    """A million-step run (the buck over 1,000 periods at its default T/1000) written by ``simulate --plot``: the
    page (its chunks in a folder beside it, read on zoom) under 10 MB, open in Chromium (navigation to ready) in
    under 2 s; and a million samples with a spike one step wide: the page's whole-run view draws it."""
    page = tmp_path / "run.html"
    assert main(["simulate", "buck", "--periods", "1000", "--plot", str(page), "--json"]) == 0
    size = page.stat().st_size
    assert size < 10 << 20, size
    t, v = _spiky()
    spiky = tmp_path / "spike.html"
    write_scope(Scope("spike", (Trace("run", t, {"v": v}),), ("v",), {"v": "V"}), spiky)
    browser = chromium()
    try:
        _open(browser, page)
        opened_ms = browser.execute_script("return pcsuiteScope.readyAt")
        rows = json.loads(browser.execute_script("return JSON.stringify(pcsuiteScope.shown('iL'))"))
        _open(browser, spiky)
        shown = browser.execute_script("return pcsuiteScope.shown('v')")
        # zoomed to 200,001 rows about the spike: drawn from every row (the chunks read), decimated in the page
        browser.execute_script(f"pcsuiteScope.setView({float(t[554_321])!r}, {float(t[754_321])!r})")
        end = time.monotonic() + 10
        while browser.execute_script("return pcsuiteScope.loading()") and time.monotonic() < end:
            time.sleep(0.05)
        zoomed = browser.execute_script("return pcsuiteScope.shown('v')")
        errors = _errors(browser)
    finally:
        browser.quit()
    assert errors == []
    assert opened_ms < 2000, opened_ms
    assert 1000 < len(rows[0]) <= 4 * 1400                 # decimated to the screen's columns
    assert max(shown[1]) == 7.5 and min(shown[1]) == -9.0
    assert max(zoomed[1]) == 7.5 and min(zoomed[1]) == -9.0 and zoomed[0][0] <= t[554_321] and len(zoomed[0]) > 2000
