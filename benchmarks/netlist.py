"""Netlists: what compiling a circuit from its file costs, and what it saves against ngspice on the same file.

Run: .venv/bin/python benchmarks/netlist.py [--quick]. Prints ratios measured side by side in one run (2 shared
cores: noisy, each the best of REPEATS):

1. the buck from netlists/circuits/buck.cir against the hand-derived buck model: ns per step of the stepper over
   the same 2,000 periods (target: the same per-step cost; the compile itself is paid once per operating point and
   printed apart);
2. the N-stage Cockcroft-Walton multiplier (k = 2N diodes), N = 1, 2, 4, 8, 16, 32: the stepper's time per
   simulated period against ngspice on the same file at TMAX = T/50 ... T/400 (its convergence fallback where the
   defaults stop it), each with its mean output against the stepper's: ngspice's near-ideal diodes keep it moving
   by 1e-3 to 1e-2 per halving, far above the stepper's own error estimate, so "equal accuracy" is not reached and
   the table shows the cost at each TMAX with the disagreement it leaves; and the
   growth of the cost with N; against Siconos 4.4's own time loop on the same LCS and steps (EulerMoreauOSI, its
   Lemke; benchmarks/peers.py's script) where python3-siconos is installed (``make bench``), at N <= 8.
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
#: ngspice's TMAX as fractions of T (compare's default is T/200).
SPICE_TMAX = (1 / 50, 1 / 100, 1 / 200, 1 / 400)


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


def spice_period(circuit, p, periods: int, fraction: float):
    """(wall s, ngspice run's mean vout over the last 10 periods) at TMAX = fraction T, ngspice's convergence
    fallback (validation.spice.CONVERGENCE_FALLBACK) taken where the defaults stop it, as compare does."""
    from netlists import SpiceOptions
    from netlists.circuit import circuit_netlist
    from validation.spice import CONVERGENCE_FALLBACK, SpiceError, circuit_trajectory, run_spice
    T = circuit.period(p)
    for options in (SpiceOptions(tmax_fraction=fraction), SpiceOptions(tmax_fraction=fraction, **CONVERGENCE_FALLBACK)):
        netlist = circuit_netlist(circuit, p, periods * T, options, diode_currents=False)
        start = time.perf_counter()
        try:
            result = run_spice(netlist)
        except SpiceError as failure:
            reason = str(failure).split(": ", 1)[-1][:100]
            continue
        wall = time.perf_counter() - start
        return wall, circuit_trajectory(circuit, p, netlist, result, (periods - 10) * T).mean(
            "vout", t0=(periods - 10) * T, t1=periods * T)
    raise RuntimeError(reason)


def siconos_period(problem, h: float, theta: float, t_end: float):
    """(wall s, final state) of Siconos' own time loop (benchmarks/peers.py's script: EulerMoreauOSI, its Lemke)
    on the same LCS, or None where python3-siconos is missing."""
    import json
    import subprocess
    import tempfile

    from peers import SICONOS_SCRIPT, SYSTEM_PYTHON, siconos_available
    if siconos_available():
        return None
    work = Path(tempfile.mkdtemp(prefix="pcsuite-cw-siconos-"))
    spec = {"h": h, "t_end": t_end, "period": problem.switching.period, "starts": list(problem.switching.starts),
            "order": list(problem.switching.configs), "theta": theta, "x0": list(map(float, problem.x0)),
            "configs": [{key: np.atleast_1d(getattr(c, key)).tolist() for key in "ABCDEF"}
                        for c in problem.configurations]}
    (work / "spec.json").write_text(json.dumps(spec))
    (work / "script.py").write_text(SICONOS_SCRIPT)
    done = subprocess.run([SYSTEM_PYTHON, str(work / "script.py"), str(work / "spec.json"), str(work / "x.npy")],
                          capture_output=True, text=True, check=True)
    return json.loads(done.stdout.splitlines()[-1])["wall_s"], np.load(work / "x.npy")[-1]


def multiplier(stages: list, periods: int, siconos_periods: int) -> None:
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
        spice = []                      # (TMAX fraction, s/period, mean vout) at T/50 ... T/400
        for fraction in SPICE_TMAX:
            try:
                wall, mean = spice_period(circuit, p, periods, fraction)
                spice.append((fraction, wall / periods, mean))
            except RuntimeError as failure:            # ngspice's own convergence: said, not hidden
                print(f"  N = {n}: ngspice at TMAX = T/{1 / fraction:.0f}: {failure}")
        sic = None
        if n <= 8:
            short = circuit.problem(p, siconos_periods * T)
            sic = siconos_period(short, method.h, method.theta, siconos_periods * T)
            if sic is not None:
                same = simulate(short, method).x[-1]
                sic = (sic[0] / siconos_periods, float(np.abs(sic[1] - same).max() / np.abs(same).max()))
        rows.append((n, 2 * n, wall_lcp / periods, spice, mean_lcp, error, sic))
    print(f"Cockcroft-Walton multiplier, {periods} periods from rest (stepper theta 0.5, h = T/400; Siconos "
          f"{siconos_periods} periods, same LCS, same steps):")
    print("   N    k   LCP s/period   vout (V)   its error   Siconos s/period   Siconos/LCP   Siconos' end state apart")
    for n, k, lcp, spice, mean, error, sic in rows:
        sic_text = f"{sic[0]:16.3e}   {sic[0] / lcp:11.1f}   {sic[1]:.1e}" if sic else f"{'-':>16}   {'-':>11}   -"
        print(f"  {n:2d}  {k:3d}   {lcp:12.3e}   {mean:9.4f}   {error:.1e}   {sic_text}")
    print("  ngspice on the same file, TMAX halved (its mean vout still moving: no TMAX reaches the stepper's error):")
    print("   N   TMAX    s/period   ngspice/LCP   vout (V)   vs the stepper")
    for n, k, lcp, spice, mean, error, sic in rows:
        for fraction, wall, spice_mean in spice:
            print(f"  {n:2d}  T/{1 / fraction:<4.0f} {wall:10.3e}   {wall / lcp:11.1f}   {spice_mean:9.4f}   "
                  f"{spice_mean / mean - 1:+.1e}")
    if len(rows) > 1:
        growth = np.polyfit(np.log([r[0] for r in rows]), np.log([r[2] for r in rows]), 1)[0]
        print(f"  the stepper's cost grows as N^{growth:.2f}")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true", help="fewer periods and stages")
    args = parser.parse_args(argv)
    buck_per_step(200 if args.quick else 2000)
    multiplier([1, 2, 4] if args.quick else [1, 2, 4, 8, 16, 32], 100 if args.quick else 400, 5 if args.quick else 20)
    return 0


if __name__ == "__main__":
    sys.exit(main())
