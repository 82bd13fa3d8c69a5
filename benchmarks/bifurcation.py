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

from converters.analysis.bifurcation import aperiodic_onset, brute_force
from converters.analysis.continuation import OrbitFamily, cascade
from converters.methods.event import EventDriven
from converters.models import get_model
from converters.run import ParameterPath
from converters.parallel import default_workers
from validation.bifurcation import diagram_method
from validation.defaults import BIFURCATION

CONTINUATION_TARGET_S = 10.0
DIAGRAM_TARGET_S = 60.0


def main(event: bool = False):
    cfg = BIFURCATION
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
    seed = branches[0].points[0].x0
    values = np.linspace(start, stop, cfg["points"])
    T = model.period(base)
    methods = [("LCP stepper (theta 0.5, h = T/500)", diagram_method(model, base))]
    if event:
        methods.append(("event-driven (exact)", EventDriven(output_step=T)))
    for label, method in methods:
        clock = time.perf_counter()
        attractors = brute_force(path, method, values, seed, transient=cfg["transient"], record=cfg["record"])
        wall = time.perf_counter() - clock
        periods = len(values) * (cfg["transient"] + cfg["record"])
        print(f"brute force, {len(values)} values, {default_workers()} processes, {label}: {wall:.2f} s = "
              f"{wall / DIAGRAM_TARGET_S:.2f} of the {DIAGRAM_TARGET_S:g} s target ({periods / wall:,.0f} periods/s); "
              f"aperiodic from {aperiodic_onset(attractors):.4f}")


if __name__ == "__main__":
    main(event="--event" in sys.argv[1:])
