"""Steady-state operating points per second through the public API, in one warm process.

``run_converter("buck", {"D": d}, steady=True)`` (Newton shooting from rest on the stepper's period map with its
exact Jacobian, then the 20 periods returned on the orbit, one step plan for both) over a sweep of D from 0.2 to
0.8 (R 10 ohm, the default: DCM throughout, as the issue measured it) and a sweep of R at D = 0.5 (0.5 .. 50 ohm,
log-spaced: CCM below 4 ohm, DCM above); ``steady_orbit`` (one period on the orbit, what the GDCM maps call) over
the D sweep. Target (issue "Performance against the live peers"): >= 1,000 operating points per second through
run_converter(steady=True).

Beside each, the previous pipeline on the same kernels, for the ratio: 20 periods from rest before Newton, a step
plan built for Newton's map and another for the span returned (``simulate`` of the model's problem from the orbit);
steady_orbit's with its 5 warm-up periods. Best of REPEATS interleaved passes (2 shared cores: noisy).

Each sweep keeps a point's run alive until the next call returns (``result = run_converter(...)`` in a loop);
the D sweep is measured again with each run freed before the next call ("run freed"): glibc then hands the
~1 MB a 20-period run holds back to the system, and the next call pays the page faults again (~1 us per
4 KiB page here; once a process has freed a larger array, glibc's raised trim threshold keeps the memory).

Run: .venv/bin/python benchmarks/steady_rate.py
"""
from __future__ import annotations

import time
from dataclasses import replace

import numpy as np

from converters.analysis.periodic import require, shoot
from converters.run import make_method, resolve_model, run_converter, steady_orbit
from converters.simulate import simulate
from record import Figures

REPEATS = 5
POINTS = 100
TARGET = 1000.0
D_SWEEP = "D sweep (R 10 ohm)"
FREED = "D sweep, run freed"
#: A figure's key for each run and sweep (``run_converter_d_sweep_rate``, ...).
RUN_KEYS = {"run_converter(steady=True)": "run_converter", "  previous pipeline": "previous_run_converter",
            "steady_orbit": "steady_orbit", "  previous steady_orbit": "previous_steady_orbit"}
SWEEP_KEYS = {D_SWEEP: "d_sweep", "R sweep (D 0.5)": "r_sweep", FREED: "d_sweep_freed"}
SWEEP_LABELS = {D_SWEEP: f"D 0.2 .. 0.8, R 10 ohm (DCM), {POINTS} points",
                "R sweep (D 0.5)": f"R 0.5 .. 50 ohm log-spaced at D 0.5 (CCM and DCM), {POINTS} points",
                FREED: f"D 0.2 .. 0.8, R 10 ohm, {POINTS} points, each run freed before the next call"}
RUN_LABELS = {"run_converter(steady=True)": "run_converter(steady=True)",
              "  previous pipeline": "the previous run_converter(steady=True) pipeline (20 periods from rest "
                                     "before Newton, two step plans)",
              "steady_orbit": "steady_orbit", "  previous steady_orbit": "the previous steady_orbit (5 warm-up "
                                                                        "periods before Newton)"}


def previous_run_converter(name, params, warm_up=20, periods=20, tol=1e-7):
    """run_converter(steady=True) as it was: a fixed warm-up, the orbit on one plan, the span on another."""
    model = resolve_model(name)
    p = model.resolve(params)
    method = make_method(model, p)
    T = model.period(p)
    problem = model.problem(p, T)
    orbit = require(shoot(problem, method, problem.x0, warm_up=warm_up, tol=tol))
    tr = simulate(model.problem(p, periods * T, orbit.x0), method)
    return replace(tr, labels=model.labels(p), metadata={**tr.metadata, "orbit": orbit.summary(),
                                                         "steady_periods": orbit.evaluations + periods})


def previous_steady_orbit(name, params):
    return previous_run_converter(name, params, warm_up=5, periods=1, tol=1e-8)


def simulated(run) -> float:
    """Periods simulated for a point: Newton's and its plain periods, then those returned."""
    meta = run.metadata
    return meta.get("steady_periods", meta["orbit"]["evaluations"] + round(run.t[-1] / run.period))


def measure(run):
    return simulated(run), bool(np.any(run.u > 0.0))


def sweeps():
    d_values = np.linspace(0.2, 0.8, POINTS)
    r_values = np.geomspace(0.5, 50.0, POINTS)
    return {D_SWEEP: [{"D": float(d)} for d in d_values],
            "R sweep (D 0.5)": [{"D": 0.5, "R": float(r)} for r in r_values]}


def main():
    figures = Figures("steady_rate", "buck steady-state operating points per second through the public API")
    cases = sweeps()
    runs = {
        "run_converter(steady=True)": lambda params: run_converter("buck", params, steady=True),
        "  previous pipeline": lambda params: previous_run_converter("buck", params),
        "steady_orbit": lambda params: steady_orbit("buck", params),
        "  previous steady_orbit": lambda params: previous_steady_orbit("buck", params),
    }
    jobs = [(run, sweep) for run in runs for sweep in cases if "steady_orbit" not in run or sweep.startswith("D")]
    for run, sweep in jobs:                                    # warm: every kernel compiled and loaded
        runs[run](cases[sweep][0])
    jobs += [(run, FREED) for run in runs if "steady_orbit" not in run]
    best = {job: np.inf for job in jobs}
    periods = {}
    for _ in range(REPEATS):
        for run, sweep in jobs:
            counts = []                     # (periods simulated, DCM) per point
            start = time.perf_counter()
            if sweep == FREED:              # each run freed before the next call starts
                for params in cases[D_SWEEP]:
                    counts.append(measure(runs[run](params)))
            else:                           # each run alive until the next one replaces it
                for params in cases[sweep]:
                    result = runs[run](params)
                    counts.append(measure(result))
            best[(run, sweep)] = min(best[(run, sweep)], time.perf_counter() - start)
            periods[(run, sweep)] = (np.mean([c[0] for c in counts]), sum(c[1] for c in counts))
    print(f"buck steady-state operating points per second, {POINTS} points per sweep, best of {REPEATS} interleaved "
          "passes (one warm process)")
    for run, sweep in jobs:
        rate = POINTS / best[(run, sweep)]
        mean_periods, held = periods[(run, sweep)]
        verdict = (f"  (target >= {TARGET:,.0f}: {'PASS' if rate >= TARGET else 'FAIL'})" if run.startswith("run_")
                   else "")
        print(f"{run:29s} {sweep:19s} {rate:7,.0f} points/s = {1e3 / rate:5.2f} ms/point; {mean_periods:5.1f} periods "
              f"simulated per point, {held} of {POINTS} points with a held diode (DCM){verdict}")
        key = f"{RUN_KEYS[run]}_{SWEEP_KEYS[sweep]}"
        figures.add(key + "_rate", rate, "points/s",
                    f"buck operating points per second, {RUN_LABELS[run]}, {SWEEP_LABELS[sweep]}, best of {REPEATS} "
                    "interleaved passes, one warm process",
                    target=f">= {TARGET:,.0f} points/s" if run.startswith("run_") else None)
        if not run.startswith(" "):
            figures.add(key + "_periods", mean_periods, "",
                        f"periods simulated per point (mean; shooting's and those returned), {RUN_LABELS[run]}, "
                        f"{SWEEP_LABELS[sweep]}")
    for run, previous in (("run_converter(steady=True)", "  previous pipeline"),
                          ("steady_orbit", "  previous steady_orbit")):
        for sweep in (*cases, FREED):
            if (run, sweep) in best:
                print(f"{run} over the {sweep}: {best[(previous, sweep)] / best[(run, sweep)]:.2f}x the previous "
                      "pipeline's rate")
                figures.add(f"{RUN_KEYS[run]}_{SWEEP_KEYS[sweep]}_speedup",
                            best[(previous, sweep)] / best[(run, sweep)], "x",
                            f"{run}'s rate over that of {RUN_LABELS[previous]}, run alongside, {SWEEP_LABELS[sweep]}",
                            digits=2)
    figures.save()


if __name__ == "__main__":
    main()
