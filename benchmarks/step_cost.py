"""Per-step cost of the compiled LCP time-stepper, and the compilation cost a second process pays.

Run: .venv/bin/python benchmarks/step_cost.py   (or `make bench`). Prints measured numbers only;
targets: <= 6 ns per step for the half-wave rectifier's compiled loop (n = 2, k = 1: one affine map per
step, the state in registers) over 10^6 steps, <= 20 ns for n <= 4, k <= 2; a second process pays < 0.5 s
to get the compiled loop. The loop comes from the ahead-of-time module built by ``make setup`` (numba.pycc) or,
with PCSUITE_KERNELS=jit or without that module, from numba's JIT and its on-disk cache: both are measured.
"""
from __future__ import annotations

import subprocess
import sys
import time

import numpy as np

from validation.core_checks import siconos_circuit
from converters.methods.discretize import step_matrices
from converters import compiled
from converters.compiled import register_state
from converters.methods import BackwardEuler
from converters.simulate import simulate
from record import Figures

REPEATS = 5


def kernel_cost(problem, h, steps, run_steps):
    """Best-of-REPEATS ns per step of the compiled loop alone (matrices and arrays prepared outside)."""
    mats = step_matrices([problem.configurations[0]], np.array([h]), 1.0)
    which = np.zeros(steps, dtype=np.int32)          # as the plan stores it
    x = np.empty((steps + 1, problem.n))
    u = np.zeros((steps + 1, problem.k))
    y = np.empty((steps + 1, problem.k))
    x[0] = problem.x0
    args = (which, mats.Phi, mats.Gamma, mats.H, mats.C, mats.F, mats.M, mats.Phi_b, mats.Gamma_b, mats.CPhi, mats.q0,
            x, u, y, 0, True, 0, register_state(problem.n))
    run_steps(*args)
    best = np.inf
    for _ in range(REPEATS):
        start = time.perf_counter()
        status, _ = run_steps(*args)
        best = min(best, time.perf_counter() - start)
        assert status == 0
    return best / steps * 1e9


def simulate_cost(problem, h):
    best = np.inf
    for _ in range(REPEATS):
        tr = simulate(problem, BackwardEuler(h))
        best = min(best, tr.wall_s)
    return best / tr.steps * 1e9, tr.steps


SECOND_PROCESS = """
import time
t0 = time.perf_counter()
from converters import compiled
from converters.methods import BackwardEuler
from converters.models.netlist import builtin
from converters.simulate import simulate
t1 = time.perf_counter()
# the two circuits compiled from their netlists before anything is timed (a netlist's compile is not a kernel's)
problems = [builtin(name).problem(builtin(name).resolve({}), 1e-4) for name in ("half-wave.cir", "diode-bridge.cir")]
t1b = time.perf_counter()
if compiled.source() != "ahead-of-time":
    from converters.lcp.kernels import masks_by_size
    masks_by_size(1)  # numba's own first-call set-up (type registries, its BLAS check imports scipy.linalg)
t2 = time.perf_counter()
for problem in problems:
    simulate(problem, BackwardEuler(1e-6))
t3 = time.perf_counter()
for problem in problems:
    simulate(problem, BackwardEuler(1e-6))
t4 = time.perf_counter()
t2 -= t1b - t1
print(f"{t1 - t0:.4f} {t2 - t1:.4f} {t3 - t2:.4f} {t4 - t3:.4f} {compiled.source()}")
"""


def second_process(**env):
    import os
    out = subprocess.run([sys.executable, "-c", SECOND_PROCESS], capture_output=True, text=True, check=True,
                         env={**os.environ, **env})
    imports, runtime_init, first, second, source = out.stdout.split(maxsplit=4)
    return float(imports), float(runtime_init), float(first) - float(second), source.strip()


def main():
    from converters.methods import theta_kernels
    figures = Figures("step_cost", "the compiled stepper's cost per step and a second process's start")
    source = compiled.source()
    print("pcsuite step-cost benchmark (best of %d); kernels: %s" % (REPEATS, compiled.source()))
    rect = siconos_circuit("half-wave.cir", 5e-3)
    ns = kernel_cost(rect, 5e-9, 1_000_000, compiled.kernel("run_steps"))
    ns_jit = kernel_cost(rect, 5e-9, 1_000_000, theta_kernels.run_steps)
    print(f"half-wave rectifier (n = 2, k = 1), 10^6 steps, compiled loop: {ns:6.1f} ns/step  "
          f"(target <= 6 ns: {'PASS' if ns <= 6 else 'FAIL'}; numba's JIT of the same source: {ns_jit:.1f} ns/step)")
    figures.add("rectifier_loop_ns", ns, "ns/step",
                f"half-wave rectifier (n = 2, k = 1), h = 5 ns, 10^6 steps, compiled loop alone ({source} kernels), "
                f"best of {REPEATS}", target="<= 6 ns/step")
    figures.add("rectifier_loop_jit_ns", ns_jit, "ns/step",
                f"the same loop from numba's JIT of the same source, best of {REPEATS}")
    ns_sim, steps = simulate_cost(rect, 5e-9)
    print(f"half-wave rectifier, simulate() end to end ({steps} steps):     {ns_sim:6.1f} ns/step "
          "(grid, matrices, allocation, events included)")
    figures.add("rectifier_simulate_ns", ns_sim, "ns/step",
                f"half-wave rectifier, 5 ms at h = 5 ns ({steps:,} steps), simulate(BackwardEuler) end to end (grid, "
                f"matrices, allocation, events included), best of {REPEATS}")
    bridge = siconos_circuit("diode-bridge.cir", 5e-3)
    ns_b = kernel_cost(bridge, 5e-9, 1_000_000, compiled.kernel("run_steps"))
    print(f"diode bridge (n = 2, k = 4), 10^6 steps, compiled loop:        {ns_b:6.1f} ns/step")
    figures.add("bridge_loop_ns", ns_b, "ns/step",
                f"diode bridge (n = 2, k = 4), h = 5 ns, 10^6 steps, compiled loop alone ({source} kernels), "
                f"best of {REPEATS}")
    ns_bs, steps = simulate_cost(bridge, 5e-9)
    print(f"diode bridge, simulate() end to end ({steps} steps):           {ns_bs:6.1f} ns/step")
    figures.add("bridge_simulate_ns", ns_bs, "ns/step",
                f"diode bridge, 5 ms at h = 5 ns ({steps:,} steps), simulate(BackwardEuler) end to end, "
                f"best of {REPEATS}")
    for env in ({}, {"PCSUITE_KERNELS": "jit"}):
        imports, runtime_init, compile_cost, source = second_process(**env)
        print(f"second process ({source}): getting the compiled kernels {compile_cost:.3f} s "
              f"(target < 0.5 s: {'PASS' if compile_cost < 0.5 else 'FAIL'}); besides: imports {imports:.3f} s"
              + (f", numba's one-time first-call set-up {runtime_init:.3f} s (any numba program pays it; most of it "
                 "is numba importing scipy.linalg for its BLAS check)" if source != "ahead-of-time" else ""))
        if source == "ahead-of-time":
            figures.add("second_process_aot_s", compile_cost, "s",
                        "a second process: getting the compiled kernels from the ahead-of-time module (the first "
                        "half-wave rectifier and diode bridge runs, 10^-4 s at h = 1 us, less the same runs again)",
                        target="< 0.5 s")
            figures.add("second_process_aot_imports_s", imports, "s",
                        "a second process, ahead-of-time kernels: importing pcsuite's modules the runs need")
        elif env:                       # without the ahead-of-time module the default run is the JIT's too
            figures.add("second_process_jit_s", compile_cost, "s",
                        "a second process, PCSUITE_KERNELS=jit: getting the compiled kernels from numba's disk cache "
                        "(the first half-wave rectifier and diode bridge runs less the same runs again)",
                        target="< 0.5 s")
            figures.add("second_process_jit_imports_s", imports, "s",
                        "a second process, PCSUITE_KERNELS=jit: importing pcsuite's modules the runs need")
            figures.add("jit_runtime_init_s", runtime_init, "s",
                        "a second process, PCSUITE_KERNELS=jit: numba's one-time first-call set-up (mostly its "
                        "import of scipy.linalg for its BLAS check)")
    figures.save()

if __name__ == "__main__":
    main()
