"""The voltage-mode buck's bifurcation study (Hamill, Deane and Jefferies 1992) against its targets, in one run.

* Continuation over Vin = 20 .. 36 V (the event method's exact maps; period doublings followed up to period 8):
  target under 10 s.
* The 800-point brute-force diagram (200 periods dropped, 64 kept at each value) on this machine's cores:
  target under 60 s; with the compiled stepper (theta 0.5, h = T/500, the default) and, side by side, the
  event method (exact, ``--event``).
Prints the wall times, their ratio to the targets, and what each found.
"""
from __future__ import annotations

import sys
import time

import numpy as np

from record import Figures  # benchmarks/record.py (this script's folder is sys.path[0])

from converters.analysis.bifurcation import aperiodic_onset, brute_force
from converters.analysis.continuation import OrbitFamily, cascade
from converters.methods.event import EventDriven
from converters.models import get_model
from converters.models.path import ParameterPath
from converters.parallel import default_workers
from validation.bifurcation import diagram_method
from validation.defaults import BIFURCATION

CONTINUATION_TARGET_S = 10.0
DIAGRAM_TARGET_S = 60.0


def main(event: bool = False):
    cfg = BIFURCATION
    figures = Figures("bifurcation", "the voltage-mode buck's continuation and brute-force bifurcation diagram")
    model = get_model(cfg["converter"], cfg["control"])
    base = model.resolve(dict(cfg["params"]))
    path = ParameterPath(model, base, cfg["param"])
    start, stop = cfg["start"], cfg["stop"]
    clock = time.perf_counter()
    branches = cascade(OrbitFamily(path, EventDriven(), 1), start, stop, np.zeros(2), max_period=cfg["max_period"])
    continuation = time.perf_counter() - clock
    doublings = sorted(b.value for br in branches for b in br.bifurcations if b.kind == "period-doubling")
    print(f"continuation {cfg['param']} = {start:g} .. {stop:g} (period doublings up to period {cfg['max_period']}): "
          f"{continuation:.2f} s = {continuation / CONTINUATION_TARGET_S:.2f} of the {CONTINUATION_TARGET_S:g} s target; "
          f"{sum(len(b.points) for b in branches)} orbits on {len(branches)} branches; doublings at "
          + ", ".join(f"{v:.6f}" for v in doublings))
    span = f"{cfg['param']} = {start:g} .. {stop:g}"
    unit = "V" if cfg["param"].startswith("V") else ""
    figures.add("continuation_s", continuation, "s",
                f"continuation over {span} with the period-doubling cascade to period {cfg['max_period']} "
                "(event method's exact maps)", target=f"< {CONTINUATION_TARGET_S:g} s")
    figures.add("continuation_orbits", sum(len(b.points) for b in branches), "",
                f"orbits the continuation over {span} found", digits=1)
    figures.add("continuation_branches", len(branches), "", f"branches the continuation over {span} followed", digits=1)
    for number, value in enumerate(doublings, 1):
        figures.add(f"doubling_{number}_{cfg['param']}", value, unit,
                    f"period doubling {number} of the continuation over {span} (at {cfg['param']})", digits=8)
    seed = branches[0].points[0].x0
    values = np.linspace(start, stop, cfg["points"])
    T = model.period(base)
    methods = [("LCP stepper (theta 0.5, h = T/500)", diagram_method(model, base))]
    if event:
        methods.append(("event-driven (exact)", EventDriven(output_step=T)))
    keys = {methods[0][0]: "stepper", "event-driven (exact)": "event"}
    for label, method in methods:
        clock = time.perf_counter()
        attractors = brute_force(path, method, values, seed, transient=cfg["transient"], record=cfg["record"])
        wall = time.perf_counter() - clock
        periods = len(values) * (cfg["transient"] + cfg["record"])
        print(f"brute force, {len(values)} values, {default_workers()} processes, {label}: {wall:.2f} s = "
              f"{wall / DIAGRAM_TARGET_S:.2f} of the {DIAGRAM_TARGET_S:g} s target ({periods / wall:,.0f} periods/s); "
              f"aperiodic from {aperiodic_onset(attractors):.4f}")
        key = keys[label]
        what = (f"brute-force diagram, {len(values)} values of {span}, {cfg['transient']} periods dropped and "
                f"{cfg['record']} kept at each, {default_workers()} processes, {label}")
        figures.add(f"diagram_{key}_s", wall, "s", what, target=f"< {DIAGRAM_TARGET_S:g} s")
        figures.add(f"diagram_{key}_periods_per_s", periods / wall, "periods/s",
                    f"simulated periods per second of the {what}")
        onset = aperiodic_onset(attractors)
        if onset is not None:
            figures.add(f"diagram_{key}_aperiodic_from", onset, unit,
                        f"{cfg['param']} from which the {what} finds no period", digits=5)
    figures.save()


if __name__ == "__main__":
    main(event="--event" in sys.argv[1:])
