"""What a scope page costs for a million-step run, and how fast it opens in Chromium.

The buck over 1,000 periods at its default step T/1000 (1,000,001 rows; iL, vC, vout and the switch command):
writing the scope (``simulate --plot FILE.html``'s part after the run), the page's weight (the overview it opens on)
and its data folder's (every step, in chunks read on zoom), the run's Parquet file for comparison; then in headless
Chromium, best of 3 fresh loads: navigation to ready (the acceptance: under 2 s), cursors set across the whole run
(the chunks at both cursors read, the sums between), and a zoom onto one switching period (its chunk read, every
row drawn).
"""
from __future__ import annotations

import shutil
import tempfile
import time
from pathlib import Path

from record import Figures  # benchmarks/record.py (this script's folder is sys.path[0])

from converters.run import run_converter
from validation.io import parquet_bytes
from validation.scope import of_trajectory, write_scope

REPEATS = 3


def _browser():
    from selenium import webdriver
    options = webdriver.ChromeOptions()
    options.binary_location = shutil.which("chromium")
    for arg in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
                "--disable-background-networking", "--disable-component-update", "--disable-sync", "--no-first-run",
                "--allow-file-access-from-files", "--window-size=1400,1000"):
        options.add_argument(arg)
    service = webdriver.ChromeService(executable_path=shutil.which("chromedriver"))
    return webdriver.Chrome(options=options, service=service)


def _ready(browser) -> None:
    while not browser.execute_script("return !!(window.pcsuiteScope && pcsuiteScope.ready)"):
        time.sleep(0.01)


def main() -> None:
    figures = Figures("scope", "a million-step run's scope page: its weight and how fast it opens in Chromium")
    tr = run_converter("buck", {}, periods=1000)
    rows = tr.t.size
    folder = Path(tempfile.mkdtemp(prefix="pcsuite-scope-bench-"))
    page = folder / "run.html"
    start = time.perf_counter()
    write_scope(of_trajectory(tr, title="buck, 1,000 periods"), page)
    write_s = time.perf_counter() - start
    page_mb = page.stat().st_size / 2**20
    data_mb = sum(p.stat().st_size for p in (folder / "run_files").iterdir()) / 2**20
    parquet_mb = len(parquet_bytes(tr.waveforms())) / 2**20
    print(f"buck, {rows:,} rows: scope written in {write_s:.2f} s; page {page_mb:.2f} MB, its data folder "
          f"{data_mb:.1f} MB (the run's Parquet file {parquet_mb:.1f} MB)")
    best = {"open": float("inf"), "cursors": float("inf"), "zoom": float("inf")}
    T = tr.period
    for _ in range(REPEATS):
        browser = _browser()
        try:
            browser.get(page.as_uri())
            _ready(browser)
            best["open"] = min(best["open"], browser.execute_script("return pcsuiteScope.readyAt") / 1e3)
            start = time.perf_counter()
            browser.execute_async_script("const done = arguments[arguments.length - 1];"
                                         f"pcsuiteScope.setCursors({T * 3.3!r}, {T * 996.6!r}).then(done, done);")
            best["cursors"] = min(best["cursors"], time.perf_counter() - start)
            start = time.perf_counter()
            browser.execute_script(f"pcsuiteScope.setView({T * 500!r}, {T * 501!r});")
            while len(browser.execute_script("return pcsuiteScope.shown('iL')[0]")) < 900:   # every row of it
                time.sleep(0.005)
            best["zoom"] = min(best["zoom"], time.perf_counter() - start)
        finally:
            browser.quit()
    shutil.rmtree(folder)
    print(f"Chromium, best of {REPEATS} fresh loads: open (navigation to ready) {best['open']:.3f} s (target < 2 s); "
          f"cursors across the run with their means {best['cursors']:.3f} s; zoom onto one period "
          f"{best['zoom']:.3f} s")
    case = f"buck over 1,000 periods ({rows:,} rows)"
    figures.add("write_s", write_s, "s", f"{case}: writing its scope")
    uplot = Path(__file__).resolve().parents[1] / "validation" / "data" / "scope" / "uPlot.iife.min.js"
    figures.add("uplot_kb", uplot.stat().st_size / 1e3, "kB", "uPlot's script, inlined into every scope page")
    figures.add("page_mb", page_mb, "MB", f"{case}: the page (its overview)", target="< 10 MB")
    figures.add("data_mb", data_mb, "MB", f"{case}: the page's data folder (every step, read on zoom)")
    figures.add("parquet_mb", parquet_mb, "MB", f"{case}: the run's Parquet file")
    figures.add("open_s", best["open"], "s", f"{case}: the page opened in headless Chromium, navigation to ready, "
                f"best of {REPEATS}", target="< 2 s")
    figures.add("cursors_s", best["cursors"], "s", f"{case}: two cursors set 993 periods apart, with every signal's "
                f"mean and RMS between them, best of {REPEATS}")
    figures.add("zoom_s", best["zoom"], "s", f"{case}: a zoom onto one period until its every row is drawn, best of "
                f"{REPEATS}")
    figures.save()


if __name__ == "__main__":
    main()
