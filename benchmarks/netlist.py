"""Netlists: what compiling a circuit from its file costs, and what it saves against ngspice on the same file.

Run: .venv/bin/python benchmarks/netlist.py [--quick]. Prints ratios measured side by side in one run (2 shared
cores: noisy, each the best of REPEATS):

1. the buck from netlists/circuits/buck.cir (the library's buck, compiled from that file) against the hand-derived
   matrices (tests/models/hand.py): ns per step of the stepper over the same 2,000 periods (target: the same
   per-step cost; the compile itself is paid once per operating point and printed apart);
2. the N-stage Cockcroft-Walton multiplier (k = 2N diodes), N = 1, 2, 4, 8, 16, 32, started on its periodic
   orbit: the stepper's time per simulated period against ngspice's on the same file at equal accuracy. Both do
   the same work, SPICE_PERIODS periods from the same state, and are judged on the same quantity, the mean vout
   over the last 10, against that run's own h -> 0 limit (the stepper's at two fine steps, extrapolated); each
   side's step (the stepper's h from T/100, ngspice's TMAX from T/200) halved until that error is TARGET; the same
   for the stepper graded after each switching instant (Theta's grade GRADE and growth GROWTH: steps from GRADE h
   growing to h, as SPICE grows its step back after a breakpoint; its h from T/10); the growth of the cost with N;
   and Siconos 4.4's own time loop on the same LCS and steps (EulerMoreauOSI, its Lemke; benchmarks/peers.py's
   script) where python3-siconos is installed (``make bench``), at N <= 8.
   Judging the stepper on its own periodic orbit instead (as this benchmark did) is not equal accuracy: the
   ladder's slowest multiplier is 1 - 3e-3 at N = 16, so an orbit's error is its per-period error amplified about
   330 times, where a 100-period run accumulates it at most a hundred times.
"""
from __future__ import annotations

import argparse
import math
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from converters.methods import Theta
from converters.models import Circuit, get_model
from converters.simulate import simulate
from record import Figures

ROOT = Path(__file__).resolve().parents[1]
REPEATS = 3
#: The accuracy both sides are asked for: compare's threshold on a mean.
TARGET = 1e-3
#: ngspice's TMAX and the stepper's h as fractions of T, halved until the error is TARGET; the reference's steps.
SPICE_TMAX = tuple(1 / (200 * 2 ** k) for k in range(7))
LCP_FRACTIONS = tuple(1 / (100 * 2 ** k) for k in range(7))
REFERENCE_STEPS = 25600
#: The orbit both sides start on: the stepper's at T/START_STEPS.
START_STEPS = 1600
#: The graded stepper (Theta's grade and growth: steps from GRADE h after each edge, growing by GROWTH to h), its h
#: from T/10 halved like the uniform one's (at N = 16: g = 0.01, r = 1.2 needed T/40, 82 steps a period; these T/10, 42).
GRADE, GROWTH = 0.001, 1.5
GRADED_FRACTIONS = tuple(1 / (10 * 2 ** k) for k in range(10))
#: ngspice is started on the orbit and run this many periods (its mean read over the last 10).
SPICE_PERIODS = 100


def best(function, repeats: int = REPEATS) -> tuple:
    out, fastest = None, math.inf
    for _ in range(repeats):
        start = time.perf_counter()
        out = function()
        fastest = min(fastest, time.perf_counter() - start)
    return fastest, out


def buck_per_step(periods: int, figures: Figures) -> None:
    circuit = get_model("buck")
    hand = _hand_models()["buck"]
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
    print(f"  final states equal to {np.abs(tr_c.x[-1] - tr_h.x[-1]).max():.2g}")
    run = f"buck, {periods:,} periods at T/1000 ({tr_c.steps:,} steps), backward Euler, best of {REPEATS}"
    figures.add("buck_netlist_ns_per_step", wall_c / tr_c.steps * 1e9, "ns/step",
                f"stepper on the buck compiled from netlists/circuits/buck.cir: {run}")
    figures.add("buck_hand_ns_per_step", wall_h / tr_h.steps * 1e9, "ns/step",
                f"stepper on the hand-derived buck matrices (tests/models/hand.py): {run}")
    figures.add("buck_netlist_over_hand", wall_c / wall_h, "x",
                f"netlist buck's time / hand-derived buck's time, {run}", target="1x (the same per-step cost)")
    figures.add("buck_compile_ms", compile_s * 1e3, "ms",
                f"reading and compiling netlists/circuits/buck.cir once (no cached compile), best of {REPEATS}")


def _hand_models() -> dict:
    """The hand-derived converters of the tests (tests/models/hand.py: a file of the test suite, not a package)."""
    import importlib.util
    spec = importlib.util.spec_from_file_location("hand", ROOT / "tests" / "models" / "hand.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.HAND


def cockcroft_walton(stages: int) -> Path:
    """The N-stage multiplier's netlist (netlists.generators.cockcroft_walton), written to a temporary file."""
    import tempfile

    from netlists.generators import cockcroft_walton as generate
    path = Path(tempfile.gettempdir()) / f"pcsuite-cw-{stages}.cir"
    path.write_text(generate(stages))
    return path


def spice_period(circuit, p, x0, periods: int, fraction: float):
    """(wall s, ngspice's mean vout over the last 10 of ``periods`` started on the orbit x0) at TMAX = fraction T,
    with the file's own .options (ABSTOL 1 uA) as compare takes them."""
    from netlists.circuit import circuit_netlist, file_spice_options
    from validation.spice import SpiceError, circuit_trajectory, run_spice
    T = circuit.period(p)
    options = replace(file_spice_options(circuit), tmax_fraction=fraction)
    netlist = circuit_netlist(circuit, p, periods * T, options, x0=x0, diode_currents=False)
    begin = time.perf_counter()
    try:
        result = run_spice(netlist)
    except SpiceError as failure:
        raise RuntimeError(str(failure).split(": ", 1)[-1][:100]) from None
    wall = time.perf_counter() - begin
    tr = circuit_trajectory(circuit, p, netlist, result, (periods - 10) * T)
    return wall, tr.mean("vout", t0=(periods - 10) * T, t1=periods * T)


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


def orbit_start(circuit, p: dict, h: float):
    """(x0, the slowest Floquet multiplier's modulus) of the stepper's periodic orbit at theta 0.5 and step h: the
    state both sides start from (Newton shooting)."""
    from converters.run import steady_state
    orbit = steady_state(circuit, p, Theta(h=h, theta=0.5), tol=1e-10)
    return orbit.x0, float(np.abs(orbit.multipliers).max())


def run_mean(circuit, p: dict, x0, h: float, periods: int, chunk: int = 10) -> float:
    """The stepper's (theta 0.5, step h) mean vout over the last 10 of ``periods`` periods from x0, run ``chunk``
    periods at a time (the reference's fine steps would not fit in memory at once)."""
    T = circuit.period(p)
    method, x = Theta(h=h, theta=0.5), np.asarray(x0, dtype=float)
    for _ in range(periods // chunk):
        tr = simulate(circuit.problem(p, chunk * T, x0=x), method)
        x = tr.x[-1]
    return replace(tr, labels=circuit.labels(p)).mean("vout", periods=10)


def refined(run, fractions, reference: float):
    """[(fraction, s/period, error)] of ``run(fraction)`` -> (wall s per period, mean), the step halved until the
    mean's error against the reference is at most TARGET (or a run would not fit in memory: said)."""
    from converters.errors import ResourceError
    out = []
    for fraction in fractions:
        try:
            wall, mean = run(fraction)
        except (RuntimeError, ResourceError) as failure:       # ngspice's own convergence, memory: said, not hidden
            print(f"       at T/{1 / fraction:.0f}: {str(failure)[:120]}")
            break
        out.append((fraction, wall, abs(mean / reference - 1)))
        if out[-1][2] <= TARGET:
            break
    return out


def multiplier(stages: list, periods: int, siconos_periods: int, figures: Figures) -> None:
    print(f"Cockcroft-Walton multiplier (netlists.generators: RS C = T/20, edges T/1000, 100 kohm): {periods} periods "
          f"from a state on its periodic orbit (the stepper's at T/{START_STEPS}), the same run on both sides. Error: "
          f"of the mean vout over the last 10 periods against that run's h -> 0 limit, the stepper's at T/"
          f"{REFERENCE_STEPS // 2} and T/{REFERENCE_STEPS} extrapolated (first order: 2 m(h/2) - m(h); its own error "
          f"about their difference, printed); each side's step (the stepper's h at theta 0.5, ngspice's TMAX) halved "
          f"until the error is {TARGET:g} (compare's threshold). ngspice's near-ideal diodes leave it ~6e-5 from the "
          "ideal circuit (their ~1 mV drops). rho: the slowest Floquet multiplier (an orbit's error is its per-period "
          "error over 1 - rho). Siconos: its own loop on the same LCS and steps (the stepper's last h).")
    print("   N    k   1 - rho    run's vout (V)  (+-)    | stepper: step  s/period   error | graded: step  s/period   "
          "error | ngspice: TMAX  s/period   error | ngspice/stepper  ngspice/graded | Siconos/stepper (end states apart)")
    costs = []
    for n in stages:
        circuit = Circuit.from_netlist(cockcroft_walton(n))
        p = circuit.resolve({})
        T = circuit.period(p)
        x0, rho = orbit_start(circuit, p, T / START_STEPS)
        fine = run_mean(circuit, p, x0, T / REFERENCE_STEPS, periods)
        half = run_mean(circuit, p, x0, T / (REFERENCE_STEPS // 2), periods)
        reference, uncertainty = 2 * fine - half, abs(fine - half)
        steps_taken = {}                                                # (fraction, grade) -> steps per period

        def lcp(fraction, grade=0.0):
            method = Theta(h=fraction * T, theta=0.5, grade=grade, growth=GROWTH)
            problem = circuit.problem(p, periods * T, x0=x0)
            simulate(problem, method)                                   # its compiled loop loaded
            wall, tr = best(lambda: simulate(problem, method))
            steps_taken[fraction, grade] = tr.steps / periods
            return wall / periods, replace(tr, labels=circuit.labels(p)).mean("vout", periods=10)

        def spice(fraction):
            wall, mean = spice_period(circuit, p, x0, periods, fraction)
            return wall / periods, mean
        stepper = refined(lcp, LCP_FRACTIONS, reference)
        graded = refined(lambda fraction: lcp(fraction, GRADE), GRADED_FRACTIONS, reference)
        ngspice = refined(spice, SPICE_TMAX, reference)
        sic_text, sic_ratio = "-", None
        if n <= 8:
            short = circuit.problem(p, siconos_periods * T, x0=x0)
            h = stepper[-1][0] * T
            sic = siconos_period(short, h, 0.5, siconos_periods * T)
            if sic is not None:
                same_method = Theta(h=h, theta=0.5)
                simulate(short, same_method)
                wall, tr = best(lambda: simulate(short, same_method))
                apart = float(np.abs(sic[1] - tr.x[-1]).max() / np.abs(tr.x[-1]).max())
                sic_text = f"{sic[0] / wall:8.1f} ({apart:.1e})"
                sic_ratio = (sic[0] / wall, apart)
        (hs, ws, es), (hg, wg, eg), (ht, wt, et) = stepper[-1], graded[-1], ngspice[-1]

        def ratio(e, w):
            return f"{wt / w:8.1f}" if e <= TARGET and et <= TARGET else "not reached"
        print(f"  {n:2d}  {2 * n:3d}   {1 - rho:.1e}   {reference:12.4f}  ({uncertainty / reference:.0e})   T/{1 / hs:<5.0f} "
              f"{ws:10.3e}  {es:.1e}   T/{1 / hg:<5.0f} {wg:10.3e}  {eg:.1e}   T/{1 / ht:<6.0f} {wt:10.3e}  {et:.1e}"
              f"   {ratio(es, ws):>11}  {ratio(eg, wg):>11}   {sic_text}", flush=True)
        costs.append((n, ws * hs))
        _multiplier_figures(figures, n, periods, rho, uncertainty / reference, stepper, graded, ngspice,
                            steps_taken, sic_ratio, siconos_periods)
    if len(costs) > 1:
        growth = np.polyfit(np.log([c[0] for c in costs]), np.log([c[1] for c in costs]), 1)[0]
        print(f"  the stepper's cost per step grows as N^{growth:.2f}")
        figures.add("cw_stepper_cost_growth", growth, "",
                    f"exponent g of the uniform stepper's cost per step ~ N^g over N = {costs[0][0]} .. {costs[-1][0]} "
                    "(a fit of log cost on log N, each N at the step it needed)", digits=2)


def _multiplier_figures(figures: Figures, n: int, periods: int, rho: float, uncertainty: float, stepper: list,
                        graded: list, ngspice: list, steps_taken: dict, sic_ratio, siconos_periods: int) -> None:
    """The N-stage multiplier's figures, keys ``cwN_...``: per side (stepper, graded, ngspice) the step it ended at
    (T/step), its cost per period and error there, and each step it tried on the way (``_error_T<step>``,
    ``_ms_per_period_T<step>``); the ratios where both sides reached TARGET; Siconos' where it ran."""
    run = f"{n}-stage Cockcroft-Walton (k = {2 * n} diodes), {periods} periods from its periodic orbit"
    judged = "error of the mean vout over the last 10 periods against the run's h -> 0 limit"
    figures.add(f"cw{n}_one_minus_rho", 1 - rho, "", f"{run}: 1 - the slowest Floquet multiplier's modulus "
                f"(the stepper's orbit at theta 0.5, T/{START_STEPS})", digits=2)
    figures.add(f"cw{n}_reference_uncertainty", uncertainty, "",
                f"{run}: the h -> 0 reference's relative uncertainty (its T/{REFERENCE_STEPS // 2} and "
                f"T/{REFERENCE_STEPS} means apart)", digits=1)
    sides = (("stepper", "the uniform stepper (theta 0.5)", "h", stepper, 0.0),
             ("graded", f"the graded stepper (theta 0.5, grade {GRADE:g}, growth {GROWTH:g})", "h", graded, GRADE),
             ("ngspice", "ngspice on the same file", "TMAX", ngspice, None))
    for side, what, step, path, grade in sides:
        for fraction, wall, error in path:
            at = f"{step} = T/{1 / fraction:.0f}"
            figures.add(f"cw{n}_{side}_ms_per_period_T{1 / fraction:.0f}", wall * 1e3, "ms",
                        f"{run}: {what} at {at}, wall time per simulated period "
                        + (f"(best of {REPEATS})" if grade is not None else "(one run)"))
            figures.add(f"cw{n}_{side}_error_T{1 / fraction:.0f}", error, "", f"{run}: {what} at {at}, {judged}",
                        digits=2)
        fraction, wall, error = path[-1]
        at = f"{step} = T/{1 / fraction:.0f}"
        reached = "reached" if error <= TARGET else "not reached"
        figures.add(f"cw{n}_{side}_step", 1 / fraction, "",
                    f"{run}: {what}, the step it ended at ({step} = T/this; halved until the error is {TARGET:g}: "
                    f"{reached})", digits=1)
        figures.add(f"cw{n}_{side}_ms_per_period", wall * 1e3, "ms",
                    f"{run}: {what} at the step it ended at, {at}, wall time per simulated period")
        figures.add(f"cw{n}_{side}_error", error, "", f"{run}: {what} at the step it ended at, {at}, {judged} "
                    f"(target {TARGET:g})", digits=2)
        if grade is not None and (fraction, grade) in steps_taken:
            figures.add(f"cw{n}_{side}_steps_per_period", steps_taken[fraction, grade], "",
                        f"{run}: {what} at {at}, steps taken per period", digits=1)
    spice_ok = ngspice[-1][2] <= TARGET
    for side, what, path in (("stepper", "uniform", stepper), ("graded", "graded", graded)):
        if spice_ok and path[-1][2] <= TARGET:
            figures.add(f"cw{n}_ngspice_over_{side}", ngspice[-1][1] / path[-1][1], "x",
                        f"{run}: ngspice's time per period / the {what} stepper's, each at the step that reached "
                        f"{TARGET:g} (ngspice TMAX = T/{1 / ngspice[-1][0]:.0f}, the stepper's h = "
                        f"T/{1 / path[-1][0]:.0f})")
    if sic_ratio is not None:
        ratio, apart = sic_ratio
        figures.add(f"cw{n}_siconos_over_stepper", ratio, "x",
                    f"{n}-stage Cockcroft-Walton, {siconos_periods} periods from its orbit: Siconos 4.4's own time loop "
                    f"(EulerMoreauOSI, its Lemke) / the stepper's time, same LCS and step T/{1 / stepper[-1][0]:.0f}")
        figures.add(f"cw{n}_siconos_end_states_apart", apart, "",
                    f"{n}-stage Cockcroft-Walton, {siconos_periods} periods: Siconos' and the stepper's end states "
                    "apart (relative, max norm)", digits=2)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true", help="fewer periods and stages")
    args = parser.parse_args(argv)
    figures = Figures("netlist", "netlists: the buck compiled from its file against the hand-derived matrices, and "
                      "the Cockcroft-Walton multiplier against ngspice at equal accuracy"
                      + (" (--quick: 200 buck periods, N = 1, 2, 4)" if args.quick else ""))
    buck_per_step(200 if args.quick else 2000, figures)
    multiplier([1, 2, 4] if args.quick else [1, 2, 4, 8, 16, 32], SPICE_PERIODS, 5 if args.quick else 20, figures)
    figures.save()
    return 0


if __name__ == "__main__":
    sys.exit(main())
