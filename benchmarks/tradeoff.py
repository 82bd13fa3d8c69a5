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


def main(out: Path) -> int:
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
    print("\naccuracy on request (benchmarks/accuracy.py): --rtol R against the best hand-picked setting and ngspice")
    accuracy_main()
    return 0


if __name__ == "__main__":
    sys.exit(main(Path(sys.argv[1]) if len(sys.argv) > 1 else DEFAULT_OUT))
