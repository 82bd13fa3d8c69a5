"""solve_lcp's C entry point against the Python thin path, on what users run (not one call in a loop).

Run: .venv/bin/python benchmarks/lcp_entry.py. Each workload runs in a fresh process twice, side by side (2 shared
cores: noisy; best of REPEATS): once as installed (the ahead-of-time kernels and ``converters._lcpfast``, the
C entry), once with the C entry unloaded (``converters.compiled.fast_lcp`` returning None: solve_lcp is then the
Python thin path around the same ahead-of-time compiled solve). Printed: each workload's time both ways and their
ratio (Python / C), and how many solve_lcp calls it made. The workloads:

- ``report lcp``: the report's two LCP sections (the project's problem set and Siconos' collection, every method
  on every problem), what ``pcsuite report lcp`` computes, in process;
- ``lcp solve``: ``pcsuite lcp solve`` of one collection file, end to end as a fresh process (cold);
- and, for information only, one call of solve_lcp on a k = 3 problem in a loop (a micro-benchmark).

The step loops never call solve_lcp (their small LCPs are solved inline, compiled; a step the inline solvers
refuse goes to solve_lcp, which none of the shipped circuits' runs does: ``general_solves`` is 0), nor does the
event method but for a configuration entered with a diode forced (an impulse, a few per run at most).
"""
from __future__ import annotations

import json
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
REPEATS = 3

PRELUDE = """
import sys, time, json
if sys.argv[1] == "python":
    import converters.compiled as compiled
    compiled.fast_lcp = lambda: None
import converters.lcp.solve as solve_module
from converters.lcp import solve_lcp
calls = [0]
real = solve_module.solve_lcp
def counting(*a, **k):
    calls[0] += 1
    return real(*a, **k)
"""

WORKLOADS = {
    "report lcp": PRELUDE + """
from validation import sections, peer
import converters.lcp as lcp_package
peer.solve_lcp = counting
sections.lcp_project_section(); sections.lcp_peer_section()          # warm
calls[0] = 0
start = time.perf_counter()
sections.lcp_project_section(); sections.lcp_peer_section()
print(json.dumps({"s": time.perf_counter() - start, "calls": calls[0], "entry": type(real).__name__}))
""",
    "one call (for information)": PRELUDE + """
import numpy as np
M, q = np.array([[4.0, 1, 0], [1, 3, 1], [0, 1, 2]]), np.array([-1.0, 2.0, -3.0])
for _ in range(2000):
    solve_lcp(M, q)
start = time.perf_counter()
for _ in range(20000):
    solve_lcp(M, q)
print(json.dumps({"s": (time.perf_counter() - start) / 20000, "calls": 1, "entry": type(solve_lcp).__name__}))
""",
}


def run(name: str, mode: str) -> dict:
    best = None
    for _ in range(REPEATS):
        done = subprocess.run([sys.executable, "-c", WORKLOADS[name], mode], cwd=ROOT, capture_output=True, text=True,
                              timeout=600)
        if done.returncode:
            raise SystemExit(f"{name} ({mode}) failed:\n{done.stderr[-2000:]}")
        out = json.loads(done.stdout.strip().splitlines()[-1])
        best = out if best is None or out["s"] < best["s"] else best
    return best


def cold_cli(mode: str) -> float:
    code = ("import sys, time\nif sys.argv[1] == 'python':\n    import converters.compiled as c\n"
            "    c.fast_lcp = lambda: None\nfrom validation.cli import main\nsys.exit(main(sys.argv[2:]))")
    best = float("inf")
    for _ in range(REPEATS):
        start = time.perf_counter()
        subprocess.run([sys.executable, "-c", code, mode, "lcp", "solve",
                        "validation/data/siconos-lcp/lcp_exp_murty.dat", "--json"], cwd=ROOT, capture_output=True,
                       check=True, timeout=120)
        best = min(best, time.perf_counter() - start)
    return best


def main() -> None:
    print(f"{'workload':<26} {'C entry':>11} {'Python':>11} {'Python / C':>11}  calls")
    for name in WORKLOADS:
        c, python = run(name, "c"), run(name, "python")
        assert c["entry"] != python["entry"], (c, python)
        unit, scale = ("us", 1e6) if c["s"] < 1e-3 else ("ms", 1e3)
        print(f"{name:<26} {c['s'] * scale:8.2f} {unit} {python['s'] * scale:8.2f} {unit} "
              f"{python['s'] / c['s']:10.3f}   {c['calls']:,}")
    c, python = cold_cli("c"), cold_cli("python")
    print(f"{'lcp solve (fresh process)':<26} {c * 1e3:8.2f} ms {python * 1e3:8.2f} ms {python / c:10.3f}   1")


if __name__ == "__main__":
    main()
