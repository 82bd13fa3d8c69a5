"""Per-call time of ``solve_lcp(M, q)`` (default method) against Siconos' fastest successful LCP solver,
problem by problem on the Siconos peer collection, measured side by side in one run.

Run: .venv/bin/python benchmarks/peer_lcp.py   (``run()`` returns the rows for another benchmark).

Siconos 4.4 (Debian's python3-siconos) is importable only by the system Python, so its side runs in a
worker process, ``/usr/bin/python3 -c WORKER``, fed the same M and q as JSON (it also reads each dense .dat
file with Siconos' own reader and says whether that agrees). In the worker, every LCP solver Siconos
offers is tried on each problem through ``lcp_driver_DenseMatrix`` with its default options (tolerance
1e-6 for most); a solver succeeds when its info flag is 0 and Siconos' own ``lcp_compute_error`` is at most
1e-6. Our side is ``solve_lcp(M, q)`` with every default (method auto, tol = 1e-10: a stricter test than
Siconos').

Timing: a warm process on each side; each measurement is a loop of n calls (n chosen so a loop takes about
10 ms), and the measurements alternate, ours then each successful Siconos solver, ``REPEATS`` times: the
medians are reported (the machine is shared; alternating spreads its noise over both sides). Our loop
times the whole call (validation, result object and all); the same loop with nothing in it is timed and
subtracted. Siconos' loop resets z and w to zero before each call (its iterative solvers would otherwise
restart from the previous solution); the same loop with the reset alone is timed and subtracted. So both
sides are charged for their call only. A
second Siconos time, for information, is that solver given a new (M, q) in each call as ``solve_lcp(M, q)`` is:
``lcp_driver_DenseMatrix(sn.LCP(M, q), zeros(k), zeros(k), options)`` (the options reused). A second time of
ours, also for information, is per problem of ``solve_lcp_many`` given the same problem n times in one call (the
entry for loops of small problems: the compiled solve with its workspace allocated once, no Python call per
problem); it tells how much of the difference is the call from Python and how much the algorithms.
"""
from __future__ import annotations

import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from converters.lcp import read_siconos_lcp, solve_lcp  # noqa: E402
from record import Figures  # noqa: E402
from validation.peer import peer_directory  # noqa: E402

SYSTEM_PYTHON = "/usr/bin/python3"
REPEATS = 7
LOOP_SECONDS = 0.01
#: Siconos' enumeration visits 2^k bases with no limit of its own: it is not tried above this k.
SICONOS_ENUM_MAX_K = 16
SUCCESS_ERR = 1e-6
#: The figures give ranges over the problems up to this size and each larger problem's own.
SMALL_K = 9

WORKER = r"""
import json, os, sys, time
# Siconos' solvers print on the C stdout: the answers go to a copy of it, the C stdout to /dev/null
answers = os.fdopen(os.dup(1), "w")
os.dup2(os.open(os.devnull, os.O_WRONLY), 1)
import numpy as np
import siconos
import siconos.numerics as sn

SKIP = {"NSGS_SBM"}   # sparse-block storage only (the driver refuses dense M)
names = sorted((n[len("SICONOS_LCP_"):], getattr(sn, n)) for n in dir(sn)
               if n.startswith("SICONOS_LCP_") and not n.endswith("_STR") and isinstance(getattr(sn, n), int)
               and hasattr(sn, n + "_STR"))
SOLVERS = {name: sid for name, sid in names if name not in SKIP}
problem = z = w = None
options = {}

def send(obj):
    answers.write(json.dumps(obj) + "\n")
    answers.flush()

send({"ready": True, "version": str(getattr(siconos, "version", "?")), "solvers": sorted(SOLVERS)})
for line in sys.stdin:
    cmd = json.loads(line)
    op = cmd["op"]
    if op == "load":
        M = np.array(cmd["M"], dtype=float)
        q = np.array(cmd["q"], dtype=float)
        problem = sn.LCP(M, q)
        problem_M, problem_q = M, q
        z, w = np.zeros(len(q)), np.zeros(len(q))
        options = {}
        agrees = None
        if cmd.get("file"):
            try:
                read = sn.newLCP()
                sn.linearComplementarity_newFromFilename(read, cmd["file"])
                if isinstance(read.M, np.ndarray):
                    agrees = bool(np.array_equal(read.M, M) and np.array_equal(np.asarray(read.q).ravel(), q))
            except Exception:
                agrees = None
        send({"loaded": True, "reader_agrees": agrees})
    elif op == "try":
        name = cmd["solver"]
        try:
            o = sn.SolverOptions(SOLVERS[name])
            z[:] = 0.0
            w[:] = 0.0
            start = time.perf_counter()
            info = sn.lcp_driver_DenseMatrix(problem, z, w, o)
            seconds = time.perf_counter() - start
            err = float(sn.lcp_compute_error(problem, z, w, 1e-6))
            options[name] = o
            send({"info": int(info), "err": err, "seconds": seconds, "tol": float(o.dparam[sn.SICONOS_DPARAM_TOL])})
        except Exception as exc:
            send({"error": " ".join(str(exc).split())[:200]})
    elif op == "time":
        name, n = cmd["solver"], cmd["calls"]
        o = options.get(name) or options.setdefault(name, sn.SolverOptions(SOLVERS[name]))
        driver, reset_z, reset_w = sn.lcp_driver_DenseMatrix, z.fill, w.fill
        start = time.perf_counter()
        for _ in range(n):
            reset_z(0.0)
            reset_w(0.0)
            driver(problem, z, w, o)
        total = time.perf_counter() - start
        start = time.perf_counter()
        for _ in range(n):
            reset_z(0.0)
            reset_w(0.0)
        send({"seconds": total - (time.perf_counter() - start)})
    elif op == "time_new":       # a new (M, q) each call, as solve_lcp(M, q) takes it: the problem and z, w built
        name, n = cmd["solver"], cmd["calls"]
        o = options.get(name) or options.setdefault(name, sn.SolverOptions(SOLVERS[name]))
        driver, LCP, zeros, k = sn.lcp_driver_DenseMatrix, sn.LCP, np.zeros, len(problem_q)
        start = time.perf_counter()
        for _ in range(n):
            driver(LCP(problem_M, problem_q), zeros(k), zeros(k), o)
        send({"seconds": time.perf_counter() - start})
"""


class Siconos:
    """The worker process; restarted (and the problem reloaded) if a solver crashes it."""

    def __init__(self):
        self.process = None
        self.problem = None
        version, self.solvers = self._start()
        package = subprocess.run(["dpkg-query", "-W", "-f=${Version}", "python3-siconos"], capture_output=True,
                                 text=True) if Path("/usr/bin/dpkg-query").exists() else None
        self.version = (f"python3-siconos {package.stdout.strip()}" if package is not None and package.returncode == 0
                        else f"siconos {version}")

    def _start(self):
        env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONHOME")}
        self.process = subprocess.Popen([SYSTEM_PYTHON, "-c", WORKER], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                        stderr=subprocess.DEVNULL, text=True, env=env, cwd="/")
        hello = self._read()
        return hello["version"], hello["solvers"]

    def _read(self):
        line = self.process.stdout.readline()
        if not line:
            raise EOFError("the Siconos worker exited")
        return json.loads(line)

    def _ask(self, cmd):
        self.process.stdin.write(json.dumps(cmd) + "\n")
        self.process.stdin.flush()
        return self._read()

    def load(self, name, M, q, file):
        self.problem = {"op": "load", "name": name, "M": M.tolist(), "q": q.tolist(), "file": str(file)}
        return self._ask(self.problem)

    def attempt(self, solver):
        try:
            return self._ask({"op": "try", "solver": solver})
        except (EOFError, BrokenPipeError):
            self._restart()
            return {"error": "crashed the worker"}

    def time(self, solver, calls, op="time"):
        """Seconds per call, or None when the solver crashed the worker this time. ``op``: ``time`` (the solver
        call alone) or ``time_new`` (the problem built from (M, q) in each call, the solver's options reused)."""
        try:
            return self._ask({"op": op, "solver": solver, "calls": calls})["seconds"] / calls
        except (EOFError, BrokenPipeError):
            self._restart()
            return None

    def _restart(self):
        self.close()
        self._start()
        self._ask(self.problem)

    def close(self):
        if self.process is not None:
            try:
                self.process.stdin.close()
            except BrokenPipeError:
                pass
            self.process.wait(timeout=10)
            self.process = None


def start_siconos():
    """The worker, or (None, reason) when /usr/bin/python3 cannot import siconos."""
    if not Path(SYSTEM_PYTHON).exists():
        return None, f"{SYSTEM_PYTHON} not found"
    probe = subprocess.run([SYSTEM_PYTHON, "-c", "import siconos.numerics"], capture_output=True, text=True, cwd="/",
                           env={k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONHOME")})
    if probe.returncode != 0:
        last = (probe.stderr.strip().splitlines() or ["no message"])[-1]
        return None, f"{SYSTEM_PYTHON} cannot import siconos ({last})"
    return Siconos(), ""


def ours_per_call(M, q, calls: int) -> float:
    """Seconds per ``solve_lcp(M, q)``, the loop's own cost (the same loop with nothing in it) subtracted, as it is
    from Siconos' loop."""
    start = time.perf_counter()
    for _ in range(calls):
        solve_lcp(M, q)
    total = time.perf_counter() - start
    start = time.perf_counter()
    for _ in range(calls):
        pass
    return (total - (time.perf_counter() - start)) / calls


def compiled_per_call(M, q, calls: int) -> float:
    """Seconds per problem of ``solve_lcp_many`` given ``calls`` copies of (M, q) in one call (the entry for loops of
    small problems: one compiled call, its workspace allocated once; a copy the compiled call does not answer is
    solved by solve_lcp within it, and counted)."""
    import numpy as np

    from converters.lcp import solve_lcp_many
    M, q = np.asarray(M, dtype=float), np.asarray(q, dtype=float)
    Ms, qs = np.repeat(M[None], calls, axis=0), np.repeat(q[None], calls, axis=0)    # built before the clock
    start = time.perf_counter()
    solve_lcp_many(Ms, qs)
    return (time.perf_counter() - start) / calls


def calls_for(seconds_per_call: float) -> int:
    return max(1, min(200_000, int(LOOP_SECONDS / max(seconds_per_call, 1e-9))))


def run(directory: Path | None = None, repeats: int = REPEATS, siconos: bool = True) -> list[dict]:
    """One row per problem: k, our status / method / err / us per call, Siconos' fastest successful solver
    and its us per call, the ratio ours / Siconos (None when Siconos has no success), the Siconos solvers
    that succeeded, and ``siconos_note`` when its side could not run."""
    directory = directory or peer_directory()
    worker, note = start_siconos() if siconos else (None, "Siconos side not requested")
    rows = []
    try:
        for path in sorted(directory.glob("lcp_*.dat")):
            p = read_siconos_lcp(path)
            k = p.q.shape[0]
            result = solve_lcp(p.M, p.q)                      # warm: compiled code loaded, caches filled
            ours_calls = calls_for(ours_per_call(p.M, p.q, 3))
            alone = compiled_per_call(p.M, p.q, 3)
            alone_calls = calls_for(alone) if alone is not None else 0
            successes, trials = {}, {}
            if worker is not None:
                loaded = worker.load(p.name, p.M, p.q, path)
                for solver in worker.solvers:
                    if solver == "ENUM" and k > SICONOS_ENUM_MAX_K:
                        trials[solver] = {"error": f"not tried: 2^{k} bases"}
                        continue
                    trials[solver] = attempt = worker.attempt(solver)
                    if "error" not in attempt and attempt["info"] == 0 and attempt["err"] <= SUCCESS_ERR:
                        successes[solver] = calls_for(attempt["seconds"])
            ours, compiled, theirs, crashed = [], [], {s: [] for s in successes}, set()
            for _ in range(repeats):                          # alternate: ours, then each Siconos solver
                ours.append(ours_per_call(p.M, p.q, ours_calls))
                if alone_calls:
                    compiled.append(compiled_per_call(p.M, p.q, alone_calls))
                for solver, calls in successes.items():
                    if solver not in crashed:
                        seconds = worker.time(solver, calls)
                        if seconds is None:
                            crashed.add(solver)
                            trials[solver] = {"error": "crashed the worker when called again"}
                        else:
                            theirs[solver].append(seconds)
            ours_us = 1e6 * statistics.median(ours)
            compiled_us = 1e6 * statistics.median(compiled) if compiled else None
            medians = {s: 1e6 * statistics.median(t) for s, t in theirs.items() if s not in crashed}
            unresolved = sorted(s for s, m in medians.items() if m <= 0.0)
            if unresolved:      # a median at or below its empty loop's: the machine's noise exceeds the call
                medians = {s: m for s, m in medians.items() if m > 0.0}
                print(f"{p.name}: {', '.join(unresolved)} timed at or below the empty loop (noise larger than the "
                      "call): left out")
            fastest = min(medians, key=medians.get) if medians else None
            new_us = None
            if fastest is not None:                   # the same solver, a new problem object per call
                new = [worker.time(fastest, successes[fastest], op="time_new") for _ in range(repeats)]
                new_us = 1e6 * statistics.median(new) if None not in new else None
            row = {"problem": p.name, "k": k, "status": result.status, "method": result.method, "err": result.err,
                   "us_per_call": ours_us, "siconos_solver": fastest,
                   "siconos_us_per_call": medians.get(fastest) if fastest else None,
                   "ratio": ours_us / medians[fastest] if fastest else None,
                   "siconos_new_us_per_call": new_us, "ratio_new": ours_us / new_us if new_us else None,
                   "compiled_us_per_call": compiled_us,
                   "ratio_compiled": compiled_us / medians[fastest] if fastest and compiled_us else None,
                   "siconos_successes": sorted(medians, key=medians.get), "siconos_us": medians,
                   "siconos_note": note}
            if worker is not None:
                row["siconos_version"] = worker.version
                row["siconos_reader_agrees"] = loaded.get("reader_agrees")
                row["siconos_failures"] = {s: (t.get("error") or f"info {t['info']}, err {t['err']:.2g}")
                                           for s, t in trials.items() if s not in medians}
            rows.append(row)
    finally:
        if worker is not None:
            worker.close()
    return rows


def key_of(name: str) -> str:
    """A problem's name as a figure key's part: ``mmc``, ``Pang_isolated_sol``."""
    return "".join(c if c.isalnum() or c == "_" else "_" for c in name)


def record_figures(figures: Figures, rows: list[dict]) -> None:
    """Over the problems ours solves: the ranges over those with k <= SMALL_K, each larger problem's own times and
    ratios, and the medians and counts over those Siconos solves too."""
    call = f"median of {REPEATS} alternating loops of ~{LOOP_SECONDS * 1e3:.0f} ms, the empty loop subtracted"
    columns = (("us", "us_per_call", "solve_lcp(M, q) (auto, tol 1e-10) per call"),
               ("siconos_us", "siconos_us_per_call", "Siconos' fastest successful solver per problem, its call alone "
                                                     "(problem object, z, w and options built once)"),
               ("siconos_new_us", "siconos_new_us_per_call", "the same Siconos solver given a new (M, q) each call "
                                                             "(sn.LCP(M, q), z, w built in the call; options reused)"),
               ("many_us", "compiled_us_per_call", "solve_lcp_many per problem (the same problem n times in one call)"))
    solved = [r for r in rows if r["status"] == "solved"]
    small = [r for r in solved if r["k"] <= SMALL_K]
    for key, column, label in columns:
        values = [r[column] for r in small if r.get(column) is not None]
        if values:
            where = f"over the {len(values)} problems with k <= {SMALL_K} of the Siconos peer collection solved; {call}"
            figures.add(f"{key}_small_min", min(values), "us", f"{label}: fastest {where}", digits=2)
            figures.add(f"{key}_small_max", max(values), "us", f"{label}: slowest {where}", digits=2)
    for r in solved:
        if r["k"] <= SMALL_K:
            continue
        name = key_of(r["problem"])
        for key, column, label in columns:
            if r.get(column) is not None:
                figures.add(f"{key}_{name}", r[column], "us", f"{label}, {r['problem']} (k = {r['k']}); {call}")
        for key, column, label in (("ratio", "ratio", "solve_lcp's time over Siconos' fastest call alone"),
                                   ("ratio_many", "ratio_compiled",
                                    "solve_lcp_many's time per problem over Siconos' fastest call alone")):
            if r.get(column) is not None:
                figures.add(f"{key}_{name}", r[column], "x", f"{label}, {r['problem']} (k = {r['k']})")
    for key, column, label in (("ratio", "ratio", "solve_lcp(M, q) per call over Siconos' fastest solver's call "
                                                  "alone"),
                               ("ratio_new", "ratio_new", "solve_lcp(M, q) per call over the same Siconos solver "
                                                          "given a new (M, q) each call"),
                               ("ratio_many", "ratio_compiled", "solve_lcp_many per problem over Siconos' fastest "
                                                                "solver's call alone")):
        ratios = [r[column] for r in solved if r.get(column) is not None]
        if ratios:
            over = f"over the {len(ratios)} problems of the Siconos peer collection both solve"
            figures.add(f"{key}_median", statistics.median(ratios), "x", f"{label}: median {over}")
            figures.add(f"{key}_faster", sum(1 for x in ratios if x < 1.0), "",
                        f"{label}: problems on which pcsuite is faster, {over}", digits=1)
            figures.add(f"{key}_problems", len(ratios), "", f"{label}: problems compared", digits=1)


def main():
    figures = Figures("peer_lcp", "solve_lcp per call against Siconos' fastest LCP solver on the Siconos peer "
                                  "collection")
    rows = run()
    note = rows[0]["siconos_note"] if rows else ""
    print("Siconos peer collection: solve_lcp(M, q) (default: auto, tol 1e-10) against Siconos' fastest successful "
          "LCP solver (info 0, err <= 1e-6)")
    print(f"median of {REPEATS} alternating loops of ~{LOOP_SECONDS * 1e3:.0f} ms, in us per call")
    if note:
        print(f"Siconos side skipped: {note}")
    print(f"{'problem':28s} {'k':>3s} {'ours: status':13s} {'method':17s} {'us/call':>9s}   "
          f"{'Siconos fastest':17s} {'us/call':>9s} {'ours/Siconos':>12s}   {'new (M, q):':>11s} {'us/call':>8s} "
          f"{'ours/it':>8s}   {'solve_lcp_many':>14s} {'/Siconos':>8s}")
    for r in rows:
        none = "(not run)" if r["siconos_note"] else "(none succeeds)"
        new = (f"   {'':11s} {r['siconos_new_us_per_call']:8.2f} {r['ratio_new']:8.2f}" if r.get("ratio_new") else "")
        if r.get("ratio_compiled"):
            new += f"   {r['compiled_us_per_call']:14.2f} {r['ratio_compiled']:8.2f}"
        sic = (f"{r['siconos_solver']:17s} {r['siconos_us_per_call']:9.2f} {r['ratio']:12.2f}{new}" if r["siconos_solver"]
               else f"{none:17s} {'':9s} {'':12s}")
        print(f"{r['problem']:28s} {r['k']:3d} {r['status']:13s} {r['method']:17s} {r['us_per_call']:9.2f}   {sic}")
    ratios = [r["ratio"] for r in rows if r["ratio"] is not None and r["status"] == "solved"]
    if ratios:
        faster = sum(1 for x in ratios if x < 1.0)
        print(f"median ratio ours/Siconos: {statistics.median(ratios):.2f} over {len(ratios)} problems "
              f"(ours faster on {faster}, slower on {len(ratios) - faster}; Siconos timed for its solver call alone, "
              "with the problem object, z, w and the options built once)")
        news = [r["ratio_new"] for r in rows if r.get("ratio_new") is not None and r["status"] == "solved"]
        if news:
            print(f"against the same Siconos solver given a new (M, q) each call (sn.LCP(M, q), z, w built in the "
                  f"call, as solve_lcp takes them; options reused): median ratio {statistics.median(news):.2f} "
                  f"(ours faster on {sum(1 for x in news if x < 1.0)} of {len(news)})")
        alone = [r["ratio_compiled"] for r in rows if r.get("ratio_compiled") is not None and r["status"] == "solved"]
        if alone:
            print(f"solve_lcp_many per problem (the same problem n times in one call: the compiled solve, no Python "
                  f"call per problem) "
                  f"against Siconos' call alone: median ratio {statistics.median(alone):.2f} (faster on "
                  f"{sum(1 for x in alone if x < 1.0)} of {len(alone)})")
    if rows and not note:
        tried = sorted({s for r in rows for s in [*r["siconos_us"], *r["siconos_failures"]]})
        differ = [r["problem"] for r in rows if r["siconos_reader_agrees"] is False]
        print(f"{rows[0]['siconos_version']}: {len(tried)} LCP solvers tried on each problem ({', '.join(tried)}); "
              "its reader " + (f"differs from ours on {', '.join(differ)}" if differ else
                               "reads the same M and q as ours from every dense file"))
    unsolved = [r["problem"] for r in rows if r["status"] != "solved"]
    if unsolved:
        print("not solved by ours: " + ", ".join(f"{r['problem']} ({r['status']}: {r['method']})" for r in rows
                                                if r["status"] != "solved"))
    record_figures(figures, rows)
    figures.save()


if __name__ == "__main__":
    main()
