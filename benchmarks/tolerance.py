"""A tolerance study through the command line, end to end (a fresh process: its start, the model's compile per
sample, the sweep's store and its summary included), and its yield against a larger reference study's.

Run: .venv/bin/python benchmarks/tolerance.py [--samples N] [--reference M] [--workers W]. Prints measured numbers
only (2 shared cores: noisy): the 48 V to 12 V buck (L = 100 uH, C = 100 uF, R = 10 ohm at D = 0.25, Ron = 50 mohm,
rL = 20 mohm) with C 5 % (normal), L 10 % (uniform) and R 1 % (normal), its periodic steady states (the stepper at
T/200, batched), the specs vout_ripple < 12 mV and efficiency > 0.98; the study's wall time and samples per second
(target: at least 1,000 per second), its yield with the 95 % interval, the reference's (another seed, M samples:
default 10 x N) and whether the interval holds it.
"""
from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

STUDY = ["sweep", "buck", "-p", "Vin=48", "-p", "D=0.25", "-p", "L=100u", "-p", "C=100u", "-p", "R=10",
         "-p", "Ron=0.05", "-p", "rL=0.02", "--tolerance", "C=5%", "--tolerance", "L=10%:uniform",
         "--tolerance", "R=1%", "--steady", "--spec", "vout_ripple<12m", "--spec", "efficiency>0.98",
         "--no-progress", "--json"]


def study(samples: int, seed: int, workers: int | None, where: Path) -> tuple[dict, float]:
    argv = [sys.executable, "-m", "validation.cli", *STUDY, "--samples", str(samples), "--seed", str(seed),
            "--out", str(where / f"study-{samples}-{seed}")]
    if workers:
        argv += ["--workers", str(workers)]
    start = time.perf_counter()
    done = subprocess.run(argv, capture_output=True, text=True, check=True)
    return json.loads(done.stdout), time.perf_counter() - start


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--samples", type=int, default=10_000)
    parser.add_argument("--reference", type=int, default=None)
    parser.add_argument("--workers", type=int, default=None)
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        found, wall = study(args.samples, 0, args.workers, Path(tmp))
        s = found["study"]
        print(f"tolerance study, {args.samples:,} samples: {wall:.1f} s end to end ({args.samples / wall:,.0f} samples/s; "
              f"the sweep itself {found['points_per_s']:,.0f} points/s; target 1,000 samples/s)")
        print(f"  yield {100 * s['yield']:.2f} % (95 % interval {100 * s['yield_low']:.2f} to {100 * s['yield_high']:.2f} %)")
        reference = args.reference or 10 * args.samples
        ref, ref_wall = study(reference, 1, args.workers, Path(tmp))
        r = ref["study"]
        inside = s["yield_low"] <= r["yield"] <= s["yield_high"]
        print(f"reference, {reference:,} samples (seed 1): yield {100 * r['yield']:.2f} % (95 % interval "
              f"{100 * r['yield_low']:.2f} to {100 * r['yield_high']:.2f} %) in {ref_wall:.1f} s; inside the study's "
              f"interval: {inside}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
