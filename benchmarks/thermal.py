"""The cost of device losses and junction temperatures on a periodic steady-state run.

netlists/circuits/sync-buck-thermal.cir (48 V to 12 V, 10 A, 100 kHz; four devices on one heatsink): the steady
state and its summary (``run_converter(steady=True)`` and ``run_summary``: Newton, the span returned, the accuracy
estimate) against the same with the thermal summary after it (the losses read from the tables at each junction
temperature as the temperatures are iterated, the heatsink, the power balance). Alternated in one warm process,
best of 15 each; the ratio is what the thermal summary adds. And a 1,000-point sweep of it over input voltage and
load (40 x 25, the local backend) with and without the thermal metrics (each point's efficiency with the devices'
losses, its hottest junction and the high side's losses), alternated, best of 2 each.
"""
from __future__ import annotations

import time
from pathlib import Path

from record import Figures  # benchmarks/record.py (this script's folder is sys.path[0])

from converters.models import get_model
from converters.parallel import run_ensemble
from converters.sweeps import Axis, Grid, ModelSweep
from converters.run import run_converter, run_summary
from converters.thermal.network import declared_setup, read_setup
from converters.thermal.summary import thermal_summary

NETLIST = Path(__file__).resolve().parents[1] / "netlists" / "circuits" / "sync-buck-thermal.cir"
REPEATS = 15
SWEEP_REPEATS = 3
TARGET = 1.2


def main() -> None:
    figures = Figures("thermal", "the cost of losses and junction temperatures on a steady-state run")
    model = get_model(str(NETLIST))
    p = model.resolve({})

    def plain():
        return run_summary(run_converter(model, p, steady=True))

    def with_thermal():
        tr = run_converter(model, p, steady=True)
        summary = run_summary(tr)
        summary["thermal"] = thermal_summary(model, p, tr, read_setup(declared_setup(model.netlist.text,
                                                                                     model.source)))
        return summary
    plain(), with_thermal()
    best = {"plain": float("inf"), "thermal": float("inf")}
    for _ in range(REPEATS):
        for key, fn in (("plain", plain), ("thermal", with_thermal)):
            start = time.perf_counter()
            fn()
            best[key] = min(best[key], time.perf_counter() - start)
    ratio = best["thermal"] / best["plain"]
    case = "sync-buck-thermal.cir, periodic steady state and its summary"
    print(f"{case}: {best['plain'] * 1e3:.1f} ms; with losses and junction temperatures {best['thermal'] * 1e3:.1f} ms "
          f"({ratio:.3f}x; target <= {TARGET}x)")
    figures.add("steady_ms", best["plain"] * 1e3, "ms", f"{case}, best of {REPEATS}")
    figures.add("thermal_ms", best["thermal"] * 1e3, "ms", f"{case} with the thermal summary, best of {REPEATS}")
    figures.add("ratio", ratio, "x", "what the thermal summary adds to a steady-state run (with over without)",
                target=f"<= {TARGET:g}x")
    grid = Grid([Axis.parse("Vin=36:60:40"), Axis.parse("R=1.2:4.8:25")])
    sweeps = {"plain": ModelSweep(str(NETLIST)),
              "thermal": ModelSweep(str(NETLIST), metrics=("thermal.efficiency", "tj.max", "loss.s1"))}
    wall = {"plain": float("inf"), "thermal": float("inf")}
    for _ in range(SWEEP_REPEATS):
        for key, ensemble in sweeps.items():
            start = time.perf_counter()
            rows = run_ensemble(ensemble, grid, backend="local")
            wall[key] = min(wall[key], time.perf_counter() - start)
            ok = sum(row["status"] == "ok" for row in rows)
    sweep_ratio = wall["thermal"] / wall["plain"]
    print(f"1,000-point sweep: {wall['plain']:.2f} s; with the thermal metrics {wall['thermal']:.2f} s "
          f"({sweep_ratio:.3f}x; target <= {TARGET}x; {ok} points ok)")
    figures.add("sweep_s", wall["plain"], "s",
                f"the example's 1,000-point sweep (Vin x R), local backend, best of {SWEEP_REPEATS}")
    figures.add("sweep_thermal_s", wall["thermal"], "s", f"the same with the thermal metrics, best of {SWEEP_REPEATS}")
    figures.add("sweep_ratio", sweep_ratio, "x", "what the thermal metrics add to a 1,000-point sweep",
                target=f"<= {TARGET:g}x")
    figures.save()


if __name__ == "__main__":
    main()
