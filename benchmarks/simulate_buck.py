"""`pcsuite simulate buck` on the DCM buck case, in a warm process.

Vin 12 V, 100 kHz, D 0.4, L 10 uH, C 100 uF, R 10 ohm, 5 ms from rest, h = 50 ns (100,000 steps).
Prints the time per step of the whole simulate path (problem building, grid, matrices, compiled
loop, events) and of the CLI command in-process, best of 5 after one warm-up run.
"""
from __future__ import annotations

import contextlib
import io
import time

from converters.run import run_converter
from validation.cli import main as cli
from record import Figures

REPEATS = 5


def best_of(fn):
    fn()
    best = float("inf")
    for _ in range(REPEATS):
        start = time.perf_counter()
        result = fn()
        best = min(best, time.perf_counter() - start)
    return best, result


def main():
    figures = Figures("simulate_buck", "pcsuite simulate buck on the DCM buck case in a warm process")
    case = "buck DCM (Vin 12 V, 100 kHz, D 0.4, L 10 uH, C 100 uF, R 10 ohm), 5 ms from rest, h = 50 ns"
    wall, run = best_of(lambda: run_converter("buck", {}, h=50e-9, t_end=5e-3))
    steps = run.steps
    print(f"buck DCM, 5 ms, h = 50 ns: {steps} steps")
    print(f"  run_converter (API):        {wall * 1e3:7.2f} ms  = {wall / steps * 1e9:6.1f} ns/step "
          f"(its own wall_s {run.wall_s / steps * 1e9:.1f} ns/step)")
    figures.add("steps", steps, "", f"{case}: steps", digits=1)
    figures.add("api_ms", wall * 1e3, "ms", f"{case}, run_converter warm (API), best of {REPEATS} after a warm-up")
    figures.add("api_ns", wall / steps * 1e9, "ns/step",
                f"{case}, run_converter warm (API) per step end to end, best of {REPEATS}")
    figures.add("api_wall_s_ns", run.wall_s / steps * 1e9, "ns/step",
                f"{case}, run_converter's own wall_s per step (the last of the best-of-{REPEATS} calls)")
    argv = ["simulate", "buck", "--h", "50n", "--t-end", "5m", "--json"]

    def command():
        with contextlib.redirect_stdout(io.StringIO()):
            return cli(argv)
    wall_cli, _ = best_of(command)
    print(f"  pcsuite simulate buck (CLI): {wall_cli * 1e3:7.2f} ms  = {wall_cli / steps * 1e9:6.1f} ns/step "
          "(argument parsing and JSON summary included)")
    figures.add("cli_ms", wall_cli * 1e3, "ms",
                f"{case}, `pcsuite simulate buck --h 50n --t-end 5m --json` in process, warm (argument parsing, "
                f"one-period set-up and JSON summary included), best of {REPEATS}")
    figures.add("cli_ns", wall_cli / steps * 1e9, "ns/step", f"{case}, the same CLI command per step")
    vout = run.mean('vout', periods=10)
    print(f"  vout mean, last 10 periods: {vout:.6f} V")
    figures.add("vout_mean", vout, "V", f"{case}: vout mean over the last 10 periods", digits=7)
    figures.save()

if __name__ == "__main__":
    main()
