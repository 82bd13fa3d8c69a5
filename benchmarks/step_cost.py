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

from converters.models.circuits import diode_bridge, half_wave_rectifier
from converters.methods.discretize import step_matrices
from converters import compiled
from converters.compiled import register_state
from converters.methods import BackwardEuler
from converters.simulate import simulate

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
from converters.models.circuits import half_wave_rectifier, diode_bridge
from converters import compiled
from converters.methods import BackwardEuler
from converters.simulate import simulate
t1 = time.perf_counter()
if compiled.source() != "ahead-of-time":
    from converters.lcp.kernels import masks_by_size
    masks_by_size(1)  # numba's own first-call set-up (type registries, its BLAS check imports scipy.linalg)
t2 = time.perf_counter()
simulate(half_wave_rectifier(t_end=1e-4), BackwardEuler(1e-6))
simulate(diode_bridge(t_end=1e-4), BackwardEuler(1e-6))
t3 = time.perf_counter()
simulate(half_wave_rectifier(t_end=1e-4), BackwardEuler(1e-6))
simulate(diode_bridge(t_end=1e-4), BackwardEuler(1e-6))
t4 = time.perf_counter()
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
    print("pcsuite step-cost benchmark (best of %d); kernels: %s" % (REPEATS, compiled.source()))
    rect = half_wave_rectifier(t_end=5e-3)
    ns = kernel_cost(rect, 5e-9, 1_000_000, compiled.kernel("run_steps"))
    ns_jit = kernel_cost(rect, 5e-9, 1_000_000, theta_kernels.run_steps)
    print(f"half-wave rectifier (n = 2, k = 1), 10^6 steps, compiled loop: {ns:6.1f} ns/step  "
          f"(target <= 6 ns: {'PASS' if ns <= 6 else 'FAIL'}; numba's JIT of the same source: {ns_jit:.1f} ns/step)")
    ns_sim, steps = simulate_cost(rect, 5e-9)
    print(f"half-wave rectifier, simulate() end to end ({steps} steps):     {ns_sim:6.1f} ns/step "
          "(grid, matrices, allocation, events included)")
    bridge = diode_bridge(t_end=5e-3)
    ns_b = kernel_cost(bridge, 5e-9, 1_000_000, compiled.kernel("run_steps"))
    print(f"diode bridge (n = 2, k = 4), 10^6 steps, compiled loop:        {ns_b:6.1f} ns/step")
    ns_bs, steps = simulate_cost(bridge, 5e-9)
    print(f"diode bridge, simulate() end to end ({steps} steps):           {ns_bs:6.1f} ns/step")
    for env in ({}, {"PCSUITE_KERNELS": "jit"}):
        imports, runtime_init, compile_cost, source = second_process(**env)
        print(f"second process ({source}): getting the compiled kernels {compile_cost:.3f} s "
              f"(target < 0.5 s: {'PASS' if compile_cost < 0.5 else 'FAIL'}); besides: imports {imports:.3f} s"
              + (f", numba's one-time first-call set-up {runtime_init:.3f} s (any numba program pays it; most of it "
                 "is numba importing scipy.linalg for its BLAS check)" if source != "ahead-of-time" else ""))


if __name__ == "__main__":
    main()
