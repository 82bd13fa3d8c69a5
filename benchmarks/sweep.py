"""Parameter sweeps against their targets, measured side by side in one run.

* Throughput: the 10,000-point buck steady-state sweep (D = 0.2 .. 0.8 x R = 2 .. 40 ohm, 100 x 100, the
  LCP stepper at h = T/200, Newton on the period map per point), streamed to a Parquet dataset as
  ``pcsuite sweep`` does: batched in this process, then the local backend (this machine's cores; target
  >= 1,000 points/s), then a 2-worker Dask ``LocalCluster`` (target: within 1.5x of the local time; the
  cluster's start-up is printed apart, each backend warmed up first).
* Memory: 10,000- and 100,000-point sweeps each in a fresh process; the peak RSS of that process and of its
  largest worker: bounded means the 100k sweep's peaks are those of the 10k sweep (rows go to disk chunk by
  chunk; a chunk's points are made from their indices where it runs).

Usage: python benchmarks/sweep.py [--skip-memory] [--skip-dask]
"""
from __future__ import annotations

import json
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

LOCAL_TARGET = 1000.0           # points per second
DASK_TARGET = 1.5               # Dask time / local time
#: What each figure's label says was run.
THROUGHPUT = "buck steady-state sweep, D = 0.2 .. 0.8 x R = 2 .. 40 ohm, 100 x 100 = 10,000 points, h = T/200, to Parquet"


def _grid(n_side: int):
    from converters.sweeps import Axis, Grid
    return Grid([Axis.parse(f"D=0.2:0.8:{n_side}"), Axis.parse(f"R=2:40:{n_side}")])


def _sweep(backend, points, tag: str):
    from converters.sweeps import ModelSweep
    from validation.sweep import load_sweep, run_sweep
    with tempfile.TemporaryDirectory() as tmp:
        run = run_sweep(ModelSweep("buck", h_fraction=1 / 200), points, Path(tmp) / tag, backend=backend,
                        progress=False)
        frame = load_sweep(Path(tmp) / tag)
    assert len(frame) == points.size and frame["index"].is_unique, "a sweep lost or duplicated a point"
    return run.wall_s, int((frame["status"] == "ok").sum())


def throughput(figures, dask: bool = True):
    from converters.parallel import LocalBackend, default_workers
    points, warm = _grid(100), _grid(32)          # warm-up: a chunk for every worker
    results = {}
    for name, backend in (("batched (1 process)", "batched"), (f"local ({default_workers()} processes)",
                                                               LocalBackend())):
        _sweep(backend, warm, "warm")
        wall, ok = _sweep(backend, points, "run")
        results[name] = wall
        print(f"{name:28s} {points.size:,} points in {wall:6.2f} s = {points.size / wall:7,.0f} points/s "
              f"({ok:,} converged)", flush=True)
        key = "batched" if backend == "batched" else "local"
        figures.add(f"{key}_s", wall, "s", f"{THROUGHPUT}: {name}, wall time (warmed up first)")
        figures.add(f"{key}_points_per_s", points.size / wall, "points/s", f"{THROUGHPUT}: {name}",
                    target=None if key == "batched" else f">= {LOCAL_TARGET:,.0f} points/s")
        figures.add(f"{key}_converged", ok, "", f"{THROUGHPUT}: {name}, points converged")
    local = results[f"local ({default_workers()} processes)"]
    print(f"  local backend: {points.size / local:,.0f} points/s = {points.size / local / LOCAL_TARGET:.2f} x the "
          f"{LOCAL_TARGET:,.0f} points/s target", flush=True)
    figures.add("local_over_target", points.size / local / LOCAL_TARGET, "x",
                f"{THROUGHPUT}: the local backend's points/s / the {LOCAL_TARGET:,.0f} points/s target", target=">= 1x")
    if not dask:
        return
    import distributed
    clock = time.perf_counter()
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None)
    client = distributed.Client(cluster)
    started = time.perf_counter() - clock
    print(f"  Dask LocalCluster (2 workers) started in {started:.2f} s (not counted)", flush=True)
    figures.add("dask_start_s", started, "s", "Dask LocalCluster, 2 worker processes of 1 thread: its start-up "
                "(not counted in the sweep's time)")
    try:
        _sweep(client, warm, "warm")
        wall, ok = _sweep(client, points, "run")
    finally:
        client.close()
        cluster.close()
    print(f"{'Dask LocalCluster (2 workers)':28s} {points.size:,} points in {wall:6.2f} s = "
          f"{points.size / wall:7,.0f} points/s ({ok:,} converged)")
    print(f"  Dask / local time: {wall / local:.2f} (target <= {DASK_TARGET:g})", flush=True)
    name = "Dask LocalCluster, 2 worker processes of 1 thread"
    figures.add("dask_s", wall, "s", f"{THROUGHPUT}: {name}, wall time (warmed up first)")
    figures.add("dask_points_per_s", points.size / wall, "points/s", f"{THROUGHPUT}: {name}")
    figures.add("dask_converged", ok, "", f"{THROUGHPUT}: {name}, points converged")
    figures.add("dask_over_local", wall / local, "x", f"{THROUGHPUT}: the Dask cluster's time / the local backend's",
                target=f"<= {DASK_TARGET:g}x")


def memory_child(n_side: int):
    """Run in a fresh process: one sweep, then this process's and its largest worker's peak RSS (MB)."""
    from converters.parallel import LocalBackend
    wall, ok = _sweep(LocalBackend(), _grid(n_side), "mem")
    own = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    worker = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024
    print(json.dumps({"points": n_side ** 2, "wall_s": wall, "ok": ok, "self_mb": own, "worker_mb": worker}))


def memory(figures):
    peaks = []
    for n_side in (100, 317):
        out = subprocess.run([sys.executable, __file__, "--memory-child", str(n_side)], capture_output=True,
                             text=True, check=True).stdout
        peak = json.loads(out.strip().splitlines()[-1])
        peaks.append(peak)
        print(f"memory: {peak['points']:7,} points in {peak['wall_s']:6.1f} s: peak RSS {peak['self_mb']:6.0f} MB "
              f"(the sweep's process), {peak['worker_mb']:6.0f} MB (its largest worker)", flush=True)
        size = "10k" if n_side == 100 else "100k"
        run = (f"buck steady-state sweep of {n_side} x {n_side} = {peak['points']:,} points (h = T/200, to Parquet), "
               "local backend, in a fresh process")
        figures.add(f"memory_{size}_points", peak["points"], "", f"{run}: points")
        figures.add(f"memory_{size}_s", peak["wall_s"], "s", f"{run}: wall time")
        figures.add(f"memory_{size}_process_mb", peak["self_mb"], "MB", f"{run}: peak RSS of the sweep's process")
        figures.add(f"memory_{size}_worker_mb", peak["worker_mb"], "MB", f"{run}: peak RSS of its largest worker")
    small, large = peaks
    print(f"  100k / 10k peak RSS: {large['self_mb'] / small['self_mb']:.2f} (process), "
          f"{large['worker_mb'] / small['worker_mb']:.2f} (worker) for 10x the points")
    ratio = f"peak RSS of the {large['points']:,}-point sweep / the {small['points']:,}-point sweep's"
    figures.add("memory_process_ratio", large["self_mb"] / small["self_mb"], "x", f"{ratio}, the sweep's process",
                target="about 1x (bounded)")
    figures.add("memory_worker_ratio", large["worker_mb"] / small["worker_mb"], "x", f"{ratio}, its largest worker",
                target="about 1x (bounded)")


if __name__ == "__main__":
    if "--memory-child" in sys.argv:
        memory_child(int(sys.argv[sys.argv.index("--memory-child") + 1]))
    else:
        from record import Figures
        skipped = [flag for flag in ("--skip-dask", "--skip-memory") if flag in sys.argv]
        figures = Figures("sweep", "a 10,000-point buck steady-state sweep on each backend, and the memory of "
                          "10,000- and 100,000-point sweeps" + (f" ({', '.join(skipped)})" if skipped else ""))
        throughput(figures, dask="--skip-dask" not in sys.argv)
        if "--skip-memory" not in sys.argv:
            memory(figures)
        figures.save()
