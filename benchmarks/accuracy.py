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

import sys

import pandas as pd

from validation.tradeoff import accuracy_on_request

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
    return 0 if met and worst <= TARGET else 1


if __name__ == "__main__":
    sys.exit(main(spice="--no-spice" not in sys.argv))
