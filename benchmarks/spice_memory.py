"""Memory of the calling process over 50 ngspice runs (PySpice keeps memory; the worker absorbs it).

Prints the resident set size of this process before and after, and the time per run.
"""
from __future__ import annotations

import os
import time

from netlists import build_netlist
from record import Figures
from validation.spice import run_spice


def rss_mb() -> float:
    with open(f"/proc/{os.getpid()}/status") as status:
        for line in status:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024.0
    return float("nan")


def main(runs: int = 50):
    netlist = build_netlist("buck", {}, 2e-4)
    run_spice(netlist)
    before = rss_mb()
    start = time.perf_counter()
    for _ in range(runs):
        run_spice(netlist)
    elapsed = time.perf_counter() - start
    after = rss_mb()
    print(f"{runs} ngspice runs (buck, 20 periods): caller RSS {before:.1f} MB -> {after:.1f} MB "
          f"(growth {after - before:+.1f} MB, target < 50 MB); {elapsed / runs * 1e3:.0f} ms per run")
    figures = Figures("spice_memory", f"the calling process's memory over {runs} ngspice runs (PySpice keeps memory; "
                      "the worker absorbs it)")
    run = f"{runs} ngspice runs of the buck, 20 periods (2e-4 s), one before them"
    figures.add("runs", runs, "", "ngspice runs measured", digits=1)
    figures.add("rss_before_mb", before, "MB", f"{run}: the caller's RSS before them")
    figures.add("rss_after_mb", after, "MB", f"{run}: the caller's RSS after them")
    figures.add("rss_growth_mb", after - before, "MB", f"{run}: the caller's RSS growth", target="< 50 MB", digits=2)
    figures.add("ms_per_run", elapsed / runs * 1e3, "ms", f"{run}: wall time per run, worker included")
    figures.save()


if __name__ == "__main__":
    main()
