"""Netlists: what compiling a circuit from its file costs, and what it saves against ngspice on the same file.

Run: .venv/bin/python benchmarks/netlist.py [--quick]. Prints ratios measured side by side in one run (2 shared
cores: noisy, each the best of REPEATS):

1. the buck from netlists/circuits/buck.cir against the hand-derived buck model: ns per step of the stepper over
   the same 2,000 periods (target: the same per-step cost; the compile itself is paid once per operating point and
   printed apart);
2. the N-stage Cockcroft-Walton multiplier (k = 2N diodes), N = 1, 2, 4, 8, 16, 32: the stepper's time per
   simulated period against ngspice on the same file at equal accuracy (ngspice's TMAX halved until its mean output
   moves less than the stepper's own error estimate), and the growth of the cost with N; against Siconos (its
   LCP per step) where python3-siconos is installed, at N <= 8.
"""
from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np

from converters.methods import Theta
from converters.models import Circuit, get_model
from converters.simulate import simulate

ROOT = Path(__file__).resolve().parents[1]
REPEATS = 3


def best(function, repeats: int = REPEATS) -> tuple:
    out, fastest = None, math.inf
    for _ in range(repeats):
        start = time.perf_counter()
        out = function()
        fastest = min(fastest, time.perf_counter() - start)
    return fastest, out


def buck_per_step(periods: int) -> None:
    circuit = Circuit.from_netlist(ROOT / "netlists" / "circuits" / "buck.cir")
    hand = get_model("buck")
    p_c, p_h = circuit.resolve({}), hand.resolve({})
    T = hand.period(p_h)
    method = Theta(h=T / 1000, theta=1.0)
    from converters.models import netlist as module

    def read_and_compile():
        module._compile.cache_clear()           # no cached compile: the file read and compiled anew
        return Circuit.from_netlist(ROOT / "netlists" / "circuits" / "buck.cir")
    compile_s, _ = best(read_and_compile)
    problem_c, problem_h = circuit.problem(p_c, periods * T), hand.problem(p_h, periods * T)
    simulate(problem_c, method), simulate(problem_h, method)                     # compiled kernels loaded
    wall_c, tr_c = best(lambda: simulate(problem_c, method))
    wall_h, tr_h = best(lambda: simulate(problem_h, method))
    print(f"buck, {periods} periods at T/1000 ({tr_c.steps:,} steps), backward Euler:")
    print(f"  netlist {wall_c / tr_c.steps * 1e9:7.2f} ns/step, hand model {wall_h / tr_h.steps * 1e9:7.2f} ns/step: "
          f"ratio {wall_c / wall_h:.3f} (the netlist read and compiled once: {compile_s * 1e3:.1f} ms)")
    print(f"  final states equal to {np.abs(tr_c.x[-1][::-1] - tr_h.x[-1]).max():.2g}")


def cockcroft_walton(stages: int) -> Path:
    """The N-stage multiplier's netlist (netlists.generators.cockcroft_walton), written to a temporary file."""
    import tempfile

    from netlists.generators import cockcroft_walton as generate
    path = Path(tempfile.gettempdir()) / f"pcsuite-cw-{stages}.cir"
    path.write_text(generate(stages))
    return path


def multiplier(stages: list, periods: int) -> None:
    from netlists.circuit import circuit_netlist
    from validation.spice import SpiceError, circuit_trajectory, run_spice
    from netlists import SpiceOptions
    rows = []
    for n in stages:
        path = cockcroft_walton(n)
        circuit = Circuit.from_netlist(path)
        p = circuit.resolve({})
        T = circuit.period(p)
        method = Theta(h=T / 400, theta=0.5)
        problem = circuit.problem(p, periods * T)
        simulate(problem, method)
        wall_lcp, tr = best(lambda: simulate(problem, method))
        from dataclasses import replace
        tr = replace(tr, labels=circuit.labels(p))
        mean_lcp = tr.mean("vout", t0=(periods - 10) * T, t1=periods * T)
        coarse = replace(simulate(circuit.problem(p, periods * T), Theta(h=T / 200, theta=0.5)), labels=circuit.labels(p))
        error = abs(mean_lcp - coarse.mean("vout", t0=(periods - 10) * T, t1=periods * T)) / 3.0
        fraction, previous, spice_wall = 1 / 50, None, None
        while fraction > 1 / 3200:
            netlist = circuit_netlist(circuit, p, periods * T, SpiceOptions(tmax_fraction=fraction),
                                      diode_currents=False)
            start = time.perf_counter()
            try:
                result = run_spice(netlist)
            except SpiceError as failure:            # ngspice's own convergence: said, not hidden
                print(f"  N = {n}: ngspice at TMAX = T/{1 / fraction:.0f}: {str(failure).split(': ', 1)[-1][:120]}")
                previous, fraction = None, fraction / 2
                continue
            wall = time.perf_counter() - start
            mean = circuit_trajectory(circuit, p, netlist, result, (periods - 10) * T).mean(
                "vout", t0=(periods - 10) * T, t1=periods * T)
            if previous is not None and abs(mean - previous) <= max(error, 1e-12 * abs(mean)):
                spice_wall = wall
                break
            previous, fraction = mean, fraction / 2
        rows.append((n, 2 * n, wall_lcp / periods, spice_wall / periods if spice_wall else math.nan, mean_lcp, error))
    print(f"Cockcroft-Walton multiplier, {periods} periods from rest (stepper theta 0.5, h = T/400):")
    print("   N    k   LCP s/period   ngspice s/period   ngspice/LCP   vout (V)   its error")
    for n, k, lcp, spice, mean, error in rows:
        print(f"  {n:2d}  {k:3d}   {lcp:12.3e}   {spice:16.3e}   {spice / lcp:11.1f}   {mean:9.4f}   {error:.1e}")
    if len(rows) > 1:
        growth = np.polyfit(np.log([r[0] for r in rows]), np.log([r[2] for r in rows]), 1)[0]
        print(f"  the stepper's cost grows as N^{growth:.2f}")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true", help="fewer periods and stages")
    args = parser.parse_args(argv)
    buck_per_step(200 if args.quick else 2000)
    multiplier([1, 2, 4] if args.quick else [1, 2, 4, 8, 16, 32], 100 if args.quick else 400)
    return 0


if __name__ == "__main__":
    sys.exit(main())
