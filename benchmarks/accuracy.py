"""Accuracy on request against the best hand-picked setting and ngspice, measured side by side (issue 18).

For each trade-off case (buck, boost, Cuk in CCM and DCM/GDCM) and R in {1e-3, 1e-5, 1e-7}: the time
``accurate_steady`` (``--rtol R``) takes to give every value it reports (vout's mean and ripple, the
inductor currents' RMS and peak, the mode fractions) within R of the exact orbit's; the cheapest
hand-picked setting doing the same, chosen knowing the answer (stepper theta 1 or 0.5 at 25 .. 102,400
steps per period, or the event method; --steady and the same measures); their ratio (target <= 3); and the
cheapest ngspice setting whose mean vout reaches R (from the exact orbit, 10 periods) where one does.
``auto_error`` is the largest true error of the auto run's values, ``auto_estimate`` its largest estimate. Best of 3 wall times each; 2 shared cores, so ratios are noisy.

Usage: python benchmarks/accuracy.py [--no-spice]
"""
from __future__ import annotations

import math
import numbers
import sys
from pathlib import Path

import pandas as pd

sys.path.insert(0, str(Path(__file__).resolve().parent))
from record import Figures  # noqa: E402  (benchmarks/record.py; also when tradeoff.py runs this)

from validation.tradeoff import accuracy_on_request  # noqa: E402

TARGET = 3.0


def main(spice: bool = True) -> int:
    table = accuracy_on_request(spice=spice)
    pd.set_option("display.width", 200)
    shown = table.assign(auto_ms=1e3 * table["auto_s"], hand_ms=1e3 * table["best_hand_s"])
    columns = ["case", "rtol", "auto_method", "auto_steps", "auto_ms", "auto_mean_error", "auto_error",
               "auto_estimate", "best_hand", "hand_ms", "ratio"] + (["spice", "spice_s"] if spice else [])
    print(shown[columns].to_string(index=False, float_format=lambda v: f"{v:.3g}"))
    met = (table["auto_error"] <= table["rtol"]).all()
    worst = table["ratio"].max()
    print(f"every target met: {met}; time to meet R / best hand-picked: median {table['ratio'].median():.2f}, "
          f"worst {worst:.2f} (target <= {TARGET:g}: {'PASS' if worst <= TARGET else 'FAIL'})")
    save_figures(table, spice)
    return 0 if met and worst <= TARGET else 1


def _number(value) -> bool:
    return isinstance(value, numbers.Real) and math.isfinite(value)


def save_figures(table: pd.DataFrame, spice: bool) -> None:
    """The figures of one run: per case and R, and the ranges the docs quote; ``results/accuracy.json``."""
    figures = Figures("accuracy", "accuracy on request (--rtol R) against the best hand-picked setting and ngspice"
                      + ("" if spice else " (--no-spice)"))
    for row in table.itertuples():
        run = f"{row.case}, R = {row.rtol:g}"
        key = f"{row.case.replace('-', '_')}_r{-math.log10(row.rtol):.0f}"
        how = row.auto_method + (f", {row.auto_steps:.0f} steps per period" if _number(row.auto_steps) else "")
        figures.add(f"{key}_auto_ms", row.auto_s * 1e3, "ms", f"{run}: --rtol R's time to give every reported value "
                    f"within R of the exact orbit ({how}; best of 3)")
        if math.isfinite(row.best_hand_s):
            figures.add(f"{key}_hand_ms", row.best_hand_s * 1e3, "ms", f"{run}: the cheapest hand-picked setting "
                        f"meeting R, chosen knowing the answer ({row.best_hand}; --steady, best of 3)")
            figures.add(f"{key}_ratio", row.ratio, "x", f"{run}: --rtol's time over the best hand-picked setting's",
                        target=f"<= {TARGET:g}x")
        if spice and math.isfinite(row.spice_s):
            figures.add(f"{key}_spice_ms", row.spice_s * 1e3, "ms", f"{run}: ngspice from the exact orbit, 10 periods, "
                        f"the cheapest setting whose mean vout is within R ({row.spice}; best of 3)")
    targets = ", ".join(f"{r:g}" for r in table["rtol"].unique())
    cases = f"{table['case'].nunique()} trade-off cases x R in {{{targets}}}"
    figures.add("auto_ms_min", 1e3 * table["auto_s"].min(), "ms", f"--rtol's time to meet R, fastest of the {cases}")
    figures.add("auto_ms_max", 1e3 * table["auto_s"].max(), "ms", f"--rtol's time to meet R, slowest of the {cases}")
    figures.add("ratio_min", table["ratio"].min(), "x", f"--rtol's time over the best hand-picked setting's, lowest "
                f"of the {cases}")
    figures.add("ratio_median", table["ratio"].median(), "x", f"--rtol's time over the best hand-picked setting's, "
                f"median of the {cases}")
    figures.add("ratio_max", table["ratio"].max(), "x", f"--rtol's time over the best hand-picked setting's, worst "
                f"of the {cases}", target=f"<= {TARGET:g}x")
    figures.add("targets_met", int((table["auto_error"] <= table["rtol"]).sum()), "",
                f"runs whose every value is within R (of {len(table)})", digits=1)
    if spice:
        for rtol, group in table.groupby("rtol", sort=False):
            key, reached = f"r{-math.log10(rtol):.0f}", group[group["spice_s"].notna()]
            figures.add(f"spice_reaches_{key}", len(reached), "", f"cases (of {len(group)}) where ngspice from the "
                        f"exact orbit reaches R = {rtol:g} in its mean vout", digits=1)
            if len(reached):
                settings = ", ".join(sorted(set(reached["spice"])))
                figures.add(f"spice_{key}_ms_min", 1e3 * reached["spice_s"].min(), "ms", f"ngspice's time to reach "
                            f"R = {rtol:g}, fastest case ({settings})")
                figures.add(f"spice_{key}_ms_max", 1e3 * reached["spice_s"].max(), "ms", f"ngspice's time to reach "
                            f"R = {rtol:g}, slowest case ({settings})")
    figures.save()


if __name__ == "__main__":
    sys.exit(main(spice="--no-spice" not in sys.argv))
