"""The speed-accuracy trade-off of every method and the stability map, in one run (issue 8).

Runs ``pcsuite bench`` (all six cases, the full sweep, 200 periods per run, with ngspice) and prints,
measured side by side in this one run on this machine:

  * per case, the ngspice default (.tran TMAX = T/100, RELTOL 1e-3, trap): its error and time; the
    fastest LCP run at least as accurate and the ratio of times (target >= 100); the fastest event run
    with error < 1e-8 and the ratio of times (target > 1);
  * per case and method family, the cheapest run reaching each accuracy level (1e-2 ... 1e-10);
  * the stability map's counts per method;
  * accuracy on request (``benchmarks/accuracy.py``): per case and R in {1e-3, 1e-5, 1e-7}, the time to meet
    R against the best hand-picked setting (target <= 3x) and against ngspice where it can reach R.

Files go to reports/bench/ (or the directory given as the first argument); ``make report`` then shows this full-size
trade-off in place of the quick form it measures itself.
"""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pandas as pd

from validation.bench import DEFAULT_OUT, read_csv, run_bench

sys.path.insert(0, str(Path(__file__).resolve().parent))
from accuracy import main as accuracy_main  # noqa: E402  (the sibling benchmark, run as part of this one)
from record import Figures  # noqa: E402

LEVELS = (1e-2, 1e-4, 1e-6, 1e-8, 1e-10)


def cheapest_per_level(runs: pd.DataFrame) -> pd.DataFrame:
    """case x family: the wall time (ms) of the fastest run with error below each level."""
    rows = []
    for (case, family), group in runs.groupby(["case", "family"], sort=False):
        row = {"case": case, "family": family}
        for level in LEVELS:
            ok = group[group["error"] < level]
            row[f"<{level:g}"] = f"{ok['wall_s'].min() * 1e3:.3g}" if len(ok) else "-"
        rows.append(row)
    return pd.DataFrame(rows)


def _finite(value) -> bool:
    return isinstance(value, (int, float, np.floating, np.integer)) and bool(np.isfinite(value))


def save_figures(figures: Figures, summary: dict, runs: pd.DataFrame, stiffness: pd.DataFrame) -> None:
    """What ``pcsuite bench`` measured (its summary, tradeoff.csv and stiffness.csv), as ``results/tradeoff.json``."""
    trade, stability = summary["tradeoff"], summary["stability"]
    periods = trade["periods"]
    figures.add("runs", trade["runs"], "", f"trade-off runs: {len(trade['cases'])} cases, every method and setting, "
                f"{periods} periods each from the exact orbit", digits=1)
    figures.add("failed_runs", trade["failed_runs"], "", "trade-off runs that failed (counted, listed in the report)",
                digits=1)
    figures.add("tradeoff_s", trade["wall_s"], "s", "the whole trade-off: the exact references, every run one at a "
                "time, the smoothing's stiffness table")
    figures.add("stability_runs", stability["runs"], "", "stability map runs: the buck with one parameter at an "
                "extreme at a time, every method from rest, each in its own process", digits=1)
    figures.add("stability_s", stability["wall_s"], "s", "the whole stability map and the ill-posed requests")
    figures.add("bench_s", trade["wall_s"] + stability["wall_s"], "s", "pcsuite bench: the trade-off and the "
                "stability map")
    counts = pd.DataFrame(stability["summary"])
    for column, key in (("ok", "ok"), ("NaN/inf", "nan_inf"), ("diverged", "diverged"),
                        ("energy created", "energy_created"), ("errors", "errors"), ("timeouts", "timeouts"),
                        ("crashed", "crashed")):
        if column in counts:
            figures.add(f"stability_{key}", int(counts[column].sum()), "",
                        f"stability map runs with the verdict {column!r} (of {stability['runs']})", digits=1)
    figures.add("ill_posed", stability["ill_posed"], "", "ill-posed requests put to the stability map", digits=1)
    figures.add("ill_posed_refused", stability["ill_posed_refused"], "", "ill-posed requests refused before any run",
                digits=1)
    # Per case: the ngspice default against the fastest LCP run at least as accurate and the fastest exact event run.
    default = "the ngspice default (.tran TMAX = T/100, RELTOL 1e-3, trap)"
    for row in trade["acceptance"]:
        case, key = row["case"], row["case"].replace("-", "_")
        if not _finite(row.get("spice_default_wall_s")):
            continue
        figures.add(f"{key}_spice_ms", row["spice_default_wall_s"] * 1e3, "ms", f"{case}: {default}, {periods} periods")
        figures.add(f"{key}_spice_error", row["spice_default_error"], "", f"{case}: {default}'s relative error (the "
                    "larger of mean vout's and the inductor current RMS's)", digits=2)
        if _finite(row.get("lcp_wall_s")):
            figures.add(f"{key}_lcp_ms", row["lcp_wall_s"] * 1e3, "ms", f"{case}: the fastest LCP run at least as "
                        f"accurate as the ngspice default ({row['lcp_setting']}), {periods} periods")
            figures.add(f"{key}_lcp_error", row["lcp_error"], "", f"{case}: that LCP run's relative error", digits=2)
            figures.add(f"{key}_lcp_ratio", row["lcp_speedup"], "x", f"{case}: the ngspice default's time over that "
                        "LCP run's", target=">= 100x")
        if _finite(row.get("event_wall_s")):
            figures.add(f"{key}_event_ms", row["event_wall_s"] * 1e3, "ms", f"{case}: the fastest event run with error "
                        f"< 1e-8 ({row['event_setting']}), {periods} periods")
            figures.add(f"{key}_event_error", row["event_error"], "", f"{case}: that event run's relative error",
                        digits=2)
            figures.add(f"{key}_event_ratio", row["event_vs_spice"], "x", f"{case}: the ngspice default's time over "
                        "that event run's", target="> 1x")
    # Per stepper family and accuracy level: the cheapest run below it, its range over the cases that reach it.
    ok = runs[np.isfinite(runs["error"]) & np.isfinite(runs["wall_s"])]
    for family, name in (("LCP theta=0.5", "theta05"), ("LCP theta=1", "theta1")):
        group = ok[ok["family"] == family]
        for level in LEVELS:
            cheapest = group[group["error"] < level].groupby("case")["wall_s"].min()
            what = f"{family} (the cheapest run per case with relative error below {level:g}, {periods} periods)"
            tag = f"{name}_below_1e{-np.log10(level):.0f}"
            figures.add(f"{tag}_cases", len(cheapest), "", f"cases (of {runs['case'].nunique()}) {family} brings below "
                        f"{level:g}", digits=1)
            if len(cheapest):
                figures.add(f"{tag}_min_ms", cheapest.min() * 1e3, "ms", f"{what}: fastest case")
                figures.add(f"{tag}_max_ms", cheapest.max() * 1e3, "ms", f"{what}: slowest case")
    event = ok[ok["family"] == "event"]
    if len(event):
        what = f"event runs (every case and tolerance, {periods} periods)"
        figures.add("event_min_ms", event["wall_s"].min() * 1e3, "ms", f"{what}: fastest")
        figures.add("event_max_ms", event["wall_s"].max() * 1e3, "ms", f"{what}: slowest")
        figures.add("event_error_min", event["error"].min(), "", f"{what}: smallest relative error", digits=2)
        figures.add("event_error_max", event["error"].max(), "", f"{what}: largest relative error", digits=2)
    smooth = ok[(ok["family"] == "smooth") & ~ok["case"].str.endswith("ccm")]
    if len(smooth):
        what = f"smoothing runs on the DCM/GDCM cases ({periods} periods)"
        figures.add("smooth_dcm_min_s", smooth["wall_s"].min(), "s", f"{what}: fastest")
        figures.add("smooth_dcm_max_s", smooth["wall_s"].max(), "s", f"{what}: slowest")
        eps = smooth["setting"].str.extract(r"eps=([^ ]+)")[0]
        for value, group in smooth.groupby(eps, sort=False):
            tag = f"smooth_eps1e{-np.log10(float(value)):.0f}"
            figures.add(f"{tag}_dcm_error_min", group["error"].min(), "", f"{what}, eps = {value}: smallest relative "
                        "error", digits=2)
            figures.add(f"{tag}_dcm_error_max", group["error"].max(), "", f"{what}, eps = {value}: largest relative "
                        "error", digits=2)
    for row in stiffness.itertuples():
        tag = f"stiffness_eps1e{-np.log10(row.eps):.0f}"
        figures.add(f"{tag}_rho_T", row.stiffness_rho_T, "", f"smoothing, eps = {row.eps:g}: stiffness max|lambda| T "
                    "along the run (the DCM buck, 5 periods, Radau, solver rtol 1e-6)")
        figures.add(f"{tag}_rhs", row.rhs_evaluations, "", f"smoothing, eps = {row.eps:g}: Radau's right-hand-side "
                    "evaluations (the DCM buck, 5 periods, solver rtol 1e-6)", digits=1)
    spice = runs[runs["family"].astype(str).str.startswith("ngspice")]
    if len(spice):
        figures.add("spice_runs", len(spice), "", "ngspice runs in the trade-off", digits=1)
        failed = spice["failure"].notna() & (spice["failure"].astype(str).str.strip() != "")
        figures.add("spice_failed", int(failed.sum()), "", "ngspice runs that failed", digits=1)
        good = spice[np.isfinite(spice["error"])]
        if len(good):
            figures.add("spice_error_min", good["error"].min(), "", "the smallest relative error of any ngspice run "
                        "(any case, TMAX, RELTOL, method)", digits=2)
        fine = good[good["setting"].astype(str).str.startswith("TMAX=T/1000 RELTOL=1e-05")]
        if len(fine):
            figures.add("spice_t1000_r1e5_min_s", fine["wall_s"].min(), "s", f"ngspice at TMAX = T/1000, RELTOL 1e-5 "
                        f"(trap or gear, {periods} periods): fastest run")
            figures.add("spice_t1000_r1e5_max_s", fine["wall_s"].max(), "s", f"ngspice at TMAX = T/1000, RELTOL 1e-5 "
                        f"(trap or gear, {periods} periods): slowest run")
    figures.save()


def main(out: Path) -> int:
    figures = Figures("tradeoff", "every method's speed against its accuracy on six cases (buck, boost, Cuk; CCM and "
                      "DCM/GDCM), and the stability map: pcsuite bench")
    summary = run_bench(out)
    runs = read_csv((out / "tradeoff.csv").read_bytes())
    accept = pd.DataFrame(summary["tradeoff"]["acceptance"])
    with pd.option_context("display.width", 220, "display.max_columns", 30, "display.float_format", "{:.3g}".format):
        print(f"\ntrade-off: {len(runs)} runs, {summary['tradeoff']['periods']} periods each, "
              f"{summary['tradeoff']['wall_s']:.0f} s")
        for row in accept.itertuples():
            lcp = getattr(row, "lcp_speedup", np.nan)
            event = getattr(row, "event_vs_spice", np.nan)
            print(f"{row.case:<10} ngspice default err {row.spice_default_error:.2e} in "
                  f"{row.spice_default_wall_s * 1e3:7.1f} ms | {row.lcp_setting:<22} {row.lcp_wall_s * 1e3:6.2f} ms "
                  f"-> {lcp:6.0f}x (target >= 100) | event {row.event_setting} err {row.event_error:.1e} "
                  f"{row.event_wall_s * 1e3:6.1f} ms -> {event:4.1f}x (target > 1) | {row.result.upper()}")
        print("\nwall time (ms) of the cheapest run below each relative error:")
        print(cheapest_per_level(runs).to_string(index=False))
        print(f"\nstability: {summary['stability']['runs']} runs in {summary['stability']['wall_s']:.0f} s; "
              f"ill-posed refused {summary['stability']['ill_posed_refused']} of {summary['stability']['ill_posed']}")
        print(pd.DataFrame(summary["stability"]["summary"]).to_string(index=False))
    passed = all(r == "pass" for r in accept["result"])
    print(f"\nacceptance (every case): {'PASS' if passed else 'FAIL'}; files in {out}/")
    save_figures(figures, summary, runs, read_csv((out / "stiffness.csv").read_bytes()))
    print("\naccuracy on request (benchmarks/accuracy.py): --rtol R against the best hand-picked setting and ngspice")
    accuracy_main()
    return 0


if __name__ == "__main__":
    sys.exit(main(Path(sys.argv[1]) if len(sys.argv) > 1 else DEFAULT_OUT))
