"""solve_lcp's entry paths, on what users run: one problem per call, and many small problems in one call.

Run: .venv/bin/python benchmarks/lcp_entry.py. Each workload runs in a fresh process (2 shared cores: noisy; best
of REPEATS), side by side in one run:

- ``report lcp``: the report's two LCP sections (the project's problem set and Siconos' collection, every method
  on every problem: what ``pcsuite report lcp`` computes, in process), with the number of solve_lcp calls;
- ``lcp solve``: ``pcsuite lcp solve`` of one collection file, end to end as a fresh process (cold);
- a loop of 20,000 small problems (k = 3, a nonsymmetric P-matrix, a different q each: Lemke or a closed form
  answers each in one compiled call; a symmetric M sends auto's PGS probe, and its eigenvalue, to the sliced path,
  ~20 us a problem either way): ``solve_lcp`` once per problem against one ``solve_lcp_many`` call, per problem.

Until 2026-11-27 solve_lcp had a hand-written CPython C entry (``converters/lcp/_fast.c``, 630 lines recycling
result objects by reference count). Measured then with this script's first two workloads side by side, C entry
against the Python thin path: report lcp 54.9 against 58.6 ms (1.07), lcp solve 259 against 260 ms (1.005); only
a micro-benchmark of one call gained (0.23 against 2.03 us, 8.6x). No user-level workload lost more than 20 %
without it, so it was retired (docs/architecture.md); a loop of small problems takes solve_lcp_many.

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

from record import Figures

ROOT = Path(__file__).resolve().parents[1]
REPEATS = 3

PRELUDE = """
import sys, time, json
import converters.lcp.solve as solve_module
from converters.lcp import solve_lcp, solve_lcp_many
calls = [0]
real = solve_module.solve_lcp
def counting(*a, **k):
    calls[0] += 1
    return real(*a, **k)
"""

WORKLOADS = {
    "report lcp": PRELUDE + """
from validation import sections, peer
peer.solve_lcp = counting
sections.lcp_project_section(); sections.lcp_peer_section()          # warm
calls[0] = 0
start = time.perf_counter()
sections.lcp_project_section(); sections.lcp_peer_section()
print(json.dumps({"s": time.perf_counter() - start, "calls": calls[0]}))
""",
    "20,000 problems: solve_lcp each": PRELUDE + """
import numpy as np
M = np.array([[4.0, 1, 0], [0.5, 3, 1], [0, 1.5, 2]])
qs = np.random.default_rng(1).standard_normal((20000, 3))
for q in qs[:2000]:
    solve_lcp(M, q)
start = time.perf_counter()
for q in qs:
    solve_lcp(M, q)
print(json.dumps({"s": (time.perf_counter() - start) / len(qs), "calls": len(qs)}))
""",
    "20,000 problems: solve_lcp_many": PRELUDE + """
import numpy as np
M = np.array([[4.0, 1, 0], [0.5, 3, 1], [0, 1.5, 2]])
qs = np.random.default_rng(1).standard_normal((20000, 3))
Ms = np.broadcast_to(M, (len(qs), 3, 3))
solve_lcp_many(Ms[:2000], qs[:2000])
start = time.perf_counter()
batch = solve_lcp_many(Ms, qs)
assert batch.solved.all()
print(json.dumps({"s": (time.perf_counter() - start) / len(qs), "calls": 1}))
""",
}


def run(name: str) -> dict:
    best = None
    for _ in range(REPEATS):
        done = subprocess.run([sys.executable, "-c", WORKLOADS[name]], cwd=ROOT, capture_output=True, text=True,
                              timeout=600)
        if done.returncode:
            raise SystemExit(f"{name} failed:\n{done.stderr[-2000:]}")
        out = json.loads(done.stdout.strip().splitlines()[-1])
        best = out if best is None or out["s"] < best["s"] else best
    return best


def cold_cli() -> float:
    best = float("inf")
    for _ in range(REPEATS):
        start = time.perf_counter()
        subprocess.run([sys.executable, "-m", "validation.cli", "lcp", "solve",
                        "validation/data/siconos-lcp/lcp_exp_murty.dat", "--json"], cwd=ROOT, capture_output=True,
                       check=True, timeout=120)
        best = min(best, time.perf_counter() - start)
    return best


def main() -> None:
    figures = Figures("lcp_entry", "solve_lcp's entry paths: one problem per call, and many small problems in one call")
    times = {name: run(name) for name in WORKLOADS}
    report = times["report lcp"]
    print(f"report lcp                         {report['s'] * 1e3:8.2f} ms  ({report['calls']:,} solve_lcp calls)")
    best = f"best of {REPEATS} fresh processes"
    figures.add("report_lcp_ms", report["s"] * 1e3, "ms",
                f"the report's two LCP sections (the project's problem set and Siconos' collection, every method on "
                f"every problem), timed after one warm-up pass; {best}")
    figures.add("report_lcp_calls", report["calls"], "", "solve_lcp calls the report's two LCP sections make", digits=1)
    cold = cold_cli()
    print(f"lcp solve (fresh process)          {cold * 1e3:8.2f} ms")
    figures.add("lcp_solve_cold_s", cold, "s",
                f"`pcsuite lcp solve validation/data/siconos-lcp/lcp_exp_murty.dat --json` as a fresh process, end to "
                f"end; best of {REPEATS}")
    each, many = times["20,000 problems: solve_lcp each"]["s"], times["20,000 problems: solve_lcp_many"]["s"]
    print(f"20,000 problems of k = 3, per problem: solve_lcp {each * 1e6:.2f} us, solve_lcp_many {many * 1e6:.2f} us "
          f"({each / many:.1f}x)")
    loop = "20,000 problems of k = 3 (a nonsymmetric P-matrix, a different q each), after 2,000 to warm up"
    figures.add("solve_lcp_us", each * 1e6, "us", f"{loop}: solve_lcp once per problem, per problem; {best}")
    figures.add("solve_lcp_many_us", many * 1e6, "us", f"{loop}: one solve_lcp_many call, per problem; {best}")
    figures.add("many_speedup", each / many, "x", f"{loop}: solve_lcp per problem over solve_lcp_many per problem")
    figures.save()


if __name__ == "__main__":
    main()
