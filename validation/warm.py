"""Compile every kernel once, before anything is timed: ``python -m validation.warm`` (``make warm``, and the test
session's first fixture, ``tests/conftest.py``).

numba's JIT compiles a kernel at its first call with new argument types and keeps it in its on-disk cache
(beside the sources, or in NUMBA_CACHE_DIR), until a kernel source changes (:mod:`converters.kernel_cache`). A
process where the ahead-of-time module is current runs the scheduled step loops from it, but the rest (the event
method's LCPs, the state-switched and relay loops, the batched steady states, Moreau-Jean, the LCP methods' sliced
runs) is the JIT's. Left to the first call, a cold compile (seconds to minutes on a loaded machine) lands in
whichever run or test touches the kernel first. Here small runs of the same commands a user types touch every
kernel with the argument types the package calls it with, in a process that forces the JIT
(``PCSUITE_KERNELS=jit``), so the ahead-of-time module's kernels are compiled too (the JIT is their fallback).

:func:`ensure` does it once: a stamp beside the caches records the kernel sources it was done for (and the cache
directory), and a current stamp costs one hash of the sources.
"""
from __future__ import annotations

import hashlib
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from converters import kernel_cache
from converters.compiled import MAX_REGISTER_STATES

PACKAGE = Path(kernel_cache.__file__).resolve().parent
CIRCUITS = Path(__file__).resolve().parents[1] / "netlists" / "circuits"
STAMP = "kernels-warm.sha256"

#: pcsuite commands whose runs call every kernel with the argument types the package uses: the stepper on circuits of
#: 1 to 6 states (the one-pair loop keeps the state in registers, one specialisation per n) and above (in rows),
#: with its exact Jacobian and Newton steps; the state-switched (comparator) and relay (sliding mode) loops; the
#: event method; the batched steady states; Moreau-Jean and the mechanical event method; each LCP method's sliced
#: run, enumeration's list of solutions and the many-problem solve.
COMMANDS = [
    ["simulate", "buck", "--periods", "2", "--steady"],
    ["simulate", "boost", "-p", "Ron=0.05", "--periods", "2"],
    ["simulate", "buck-boost", "-p", "Vf=0.7", "-p", "Rd=0.05", "--periods", "2", "--steady"],
    ["simulate", "cuk", "--periods", "2", "--steady"],
    ["simulate", "prc", "--periods", "2", "--steady"],
    ["simulate", "buck", "--method", "event", "--periods", "2", "--steady"],
    ["simulate", "buck", "--method", "smooth", "--periods", "2"],
    ["simulate", "boost", "--control", "smc", "--t-end", "1m"],
    ["simulate", "boost", "--control", "smc-implicit", "--t-end", "1m"],
    ["simulate", "buck", "--control", "voltage-loop", "--periods", "2", "--steady"],
    ["simulate", "buck", "--control", "peak-current", "--periods", "2", "--steady"],
    ["simulate", str(CIRCUITS / "half-wave.cir"), "--t-end", "1m"],
    ["simulate", str(CIRCUITS / "hysteretic-buck.cir"), "--t-end", "50u"],
    ["simulate", str(CIRCUITS / "sepic.cir"), "--periods", "2", "--steady"],
    ["simulate", str(CIRCUITS / "sync-buck-thermal.cir"), "--periods", "2", "--steady"],
    ["simulate", str(CIRCUITS / "flyback.cir"), "--periods", "2"],
    ["simulate", str(CIRCUITS / "rectifier-3ph.cir"), "--periods", "1"],
    ["simulate", str(CIRCUITS / "cockcroft-walton.cir"), "--periods", "1"],
    ["sweep", "buck", "--grid", "D=0.3:0.6:2", "--steady", "--scheduler", "batched", "--no-progress", "--out", "{tmp}/s"],
    *[command for n in range(1, MAX_REGISTER_STATES + 2) for command in (
        ["simulate", f"{{tmp}}/ladder{n}.cir", "--periods", "2", "--steady"],
        ["sweep", f"{{tmp}}/ladder{n}.cir", "--grid", "Rl1=50:100:2", "--steady", "--scheduler", "batched",
         "--no-progress", "--out", f"{{tmp}}/ladder{n}"])],
    ["mech", "simulate", "friction", "--periods", "2"],
    ["mech", "simulate", "cam-follower", "--periods", "2"],
    ["mech", "simulate", "cam-follower", "--method", "moreau", "--periods", "2"],
    ["mech", "simulate", "stick-slip", "--t-end", "5"],
    ["mech", "simulate", "bouncing-ball", "--method", "moreau", "--t-end", "1"],
    *[["lcp", "solve", "{tmp}/lcp.dat", "--method", method, "--no-fast-paths", "--time-limit", "600"]
      for method in ("auto", "lemke", "murty", "enum", "pgs", "newton")],
    ["lcp", "solve", "{tmp}/ray.dat", "--method", "lemke", "--no-fast-paths"],
]


def _lcps() -> None:
    """The many-problem solve, and each method's one-call solve (the commands above run the sliced ones)."""
    import numpy as np

    from converters.lcp import solve_lcp, solve_lcp_many
    M, q = np.array([[2.0, 1.0], [1.0, 2.0]]), np.array([-3.0, -3.0])
    for method in ("auto", "lemke", "murty", "enum", "pgs", "newton"):
        solve_lcp(M, q, method=method)
    solve_lcp(M * 1e10, q, time_limit=600.0)         # the sliced path's closed forms; z scaled back by 2^shift
    solve_lcp_many(np.stack([M, M]), np.stack([q, q]))


def ladder(n: int) -> str:
    """A pulsed source through an ideal diode into an RC ladder of n capacitors: n states, one pair."""
    stages = "".join(f"R{i} a{i - 1} a{i} 1\nC{i} a{i} 0 1u\n" for i in range(2, n + 1))
    return (f"RC ladder of {n}\nVs in 0 PULSE(0 10 0 1n 1n 5u 10u)\nD1 in a1 D1\nC1 a1 0 1u\nRl1 a1 0 100\n{stages}"
            ".model D1 D\n.tran 10n 100u\n")


#: A 2 x 2 LCP with one solution (z = (1, 1)) in the Siconos .dat format, and one where Lemke ends on a ray.
LCP_DAT = "2\n0\n2 2\n2 2\n2 1\n1 2\n-3 -3\n"
RAY_DAT = "3\n0\n3 3\n3 3\n-1 0 0\n0 -1 0\n0 0 -1\n-1 -1 -1\n"


def warm() -> None:
    """Run :data:`COMMANDS` and the LCP solves in this process (the caller forces the JIT: :func:`ensure`)."""
    from validation.cli import main
    with tempfile.TemporaryDirectory(prefix="pcsuite-warm.") as tmp:
        Path(tmp, "lcp.dat").write_text(LCP_DAT)
        Path(tmp, "ray.dat").write_text(RAY_DAT)
        for n in range(1, MAX_REGISTER_STATES + 2):
            Path(tmp, f"ladder{n}.cir").write_text(ladder(n))
        for argv in COMMANDS:
            argv = [part.replace("{tmp}", tmp) for part in argv]
            with open(os.devnull, "w") as quiet:
                streams, (sys.stdout, sys.stderr) = (sys.stdout, sys.stderr), (quiet, quiet)
                try:
                    code = main(argv)
                finally:
                    sys.stdout, sys.stderr = streams
            if code != 0 and argv[:2] != ["lcp", "solve"]:        # the ray's no_solution exits 1
                raise RuntimeError(f"warming the kernels: pcsuite {' '.join(argv)} exited {code}")
    _lcps()


def _digest() -> str:
    """The kernel sources, this file and the cache's place: what a finished warm-up was done for."""
    parts = [(PACKAGE / name).read_bytes() for name in kernel_cache.SOURCES] + [Path(__file__).read_bytes(),
                                                                               os.environ.get("NUMBA_CACHE_DIR", "").encode()]
    return hashlib.sha256(b"\0".join(parts)).hexdigest()


def _stamp() -> Path:
    return PACKAGE / "__pycache__" / STAMP


def ensure(progress=print) -> bool:
    """Warm the kernels unless a current stamp says it was done; True when it ran. The runs go to a child process
    with ``PCSUITE_KERNELS=jit``."""
    digest = _digest()
    try:
        if _stamp().read_text() == digest:
            return False
    except OSError:
        pass
    start = time.perf_counter()
    if progress:
        progress("compiling the kernels once (numba's JIT, cached on disk until a kernel source changes) ...")
    env = {**os.environ, "PCSUITE_KERNELS": "jit", "PYTHONPATH": os.pathsep.join(
        [str(PACKAGE.parent)] + ([os.environ["PYTHONPATH"]] if os.environ.get("PYTHONPATH") else []))}
    done = subprocess.run([sys.executable, "-m", "validation.warm", "--here"], env=env, capture_output=True, text=True)
    if done.returncode != 0:
        raise RuntimeError(f"warming the kernels failed:\n{done.stderr[-3000:]}")
    try:
        _stamp().parent.mkdir(exist_ok=True)
        temporary = _stamp().with_suffix(f".{os.getpid()}.tmp")
        temporary.write_text(digest)
        os.replace(temporary, _stamp())
    except OSError:
        pass                                       # a read-only install: warmed for this run only
    if progress:
        progress(f"kernels compiled in {time.perf_counter() - start:.0f} s")
    return True


if __name__ == "__main__":
    if sys.argv[1:] == ["--here"]:
        warm()
    else:
        ensure()
