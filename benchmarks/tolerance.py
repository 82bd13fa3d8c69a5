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
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

STUDY = ["sweep", "buck", "-p", "Vin=48", "-p", "D=0.25", "-p", "L=100u", "-p", "C=100u", "-p", "R=10",
         "-p", "Ron=0.05", "-p", "rL=0.02", "--tolerance", "C=5%", "--tolerance", "L=10%:uniform",
         "--tolerance", "R=1%", "--steady", "--spec", "vout_ripple<12m", "--spec", "efficiency>0.98",
         "--no-progress", "--json"]
#: The study in words, for the figures' labels.
ABOUT = ("48 V to 12 V buck (L 100 uH, C 100 uF, R 10 ohm, D 0.25), C 5 % normal, L 10 % uniform, R 1 % normal, "
         "steady states at T/200, specs vout_ripple < 12 mV and efficiency > 0.98")
#: A metric's or parameter's value in the unit the docs write it in: (scale, unit).
SHOWN = {"vout_ripple": (1e3, "mV"), "efficiency": (100.0, "%"), "L": (1e6, "uH"), "C": (1e6, "uF"), "R": (1.0, "ohm")}


def study(samples: int, seed: int, workers: int | None, where: Path) -> tuple[dict, float]:
    argv = [sys.executable, "-m", "validation.cli", *STUDY, "--samples", str(samples), "--seed", str(seed),
            "--out", str(where / f"study-{samples}-{seed}")]
    if workers:
        argv += ["--workers", str(workers)]
    start = time.perf_counter()
    done = subprocess.run(argv, capture_output=True, text=True, check=True)
    return json.loads(done.stdout), time.perf_counter() - start


def record_study(figures, prefix: str, summary: dict, wall: float, samples: int, seed: int) -> None:
    """One study's figures (keys ``PREFIX_...``): its time and rate end to end, the sweep's own rate, the yield with
    its interval, and per spec the share of samples meeting it and the worst sample."""
    s = summary["study"]
    run = f"tolerance study, {samples:,} samples (seed {seed}) of the {ABOUT}"
    figures.add(f"{prefix}_s", wall, "s", f"{run}: wall time end to end through the command line (a fresh process: "
                "start, compile, store, summary plot)")
    figures.add(f"{prefix}_samples_per_s", samples / wall, "samples/s", f"{run}: samples per second end to end",
                target=">= 1,000 samples/s" if prefix == "study" else None)
    figures.add(f"{prefix}_sweep_points_per_s", summary["points_per_s"], "points/s",
                f"{run}: the sweep itself (as the command reports it)")
    figures.add(f"{prefix}_failed", s["failed_points"], "", f"{run}: samples that failed (counted as failing every spec)")
    for key, word in (("yield", "yield"), ("yield_low", "yield, 95 % interval's low end"),
                      ("yield_high", "yield, 95 % interval's high end")):
        figures.add(f"{prefix}_{key}", 100 * s[key], "%", f"{run}: {word}", digits=4)
    for spec in s["specs"]:
        metric = re.match(r"\w+", spec["spec"]).group(0)
        scale, unit = SHOWN.get(metric, (1.0, ""))
        figures.add(f"{prefix}_{metric}_pass", 100 * spec["fraction"], "%",
                    f"{run}: samples meeting {spec['spec']}", digits=4)
        figures.add(f"{prefix}_{metric}_worst", scale * spec["worst_value"], unit,
                    f"{run}: {metric} of the sample with the least margin on {spec['spec']}", digits=4)
        for name, value in spec["worst_point"].items():
            scale, unit = SHOWN.get(name, (1.0, ""))
            figures.add(f"{prefix}_{metric}_worst_{name}", scale * value, unit,
                        f"{run}: {name} of the sample with the least margin on {spec['spec']}")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--samples", type=int, default=10_000)
    parser.add_argument("--reference", type=int, default=None)
    parser.add_argument("--workers", type=int, default=None)
    args = parser.parse_args(argv)
    from record import Figures
    figures = Figures("tolerance", "a tolerance study through the command line, end to end, and its yield against a "
                      "larger reference study's")
    with tempfile.TemporaryDirectory() as tmp:
        found, wall = study(args.samples, 0, args.workers, Path(tmp))
        s = found["study"]
        print(f"tolerance study, {args.samples:,} samples: {wall:.1f} s end to end ({args.samples / wall:,.0f} samples/s; "
              f"the sweep itself {found['points_per_s']:,.0f} points/s; target 1,000 samples/s)")
        print(f"  yield {100 * s['yield']:.2f} % (95 % interval {100 * s['yield_low']:.2f} to {100 * s['yield_high']:.2f} %)")
        record_study(figures, "study", found, wall, args.samples, 0)
        reference = args.reference or 10 * args.samples
        ref, ref_wall = study(reference, 1, args.workers, Path(tmp))
        r = ref["study"]
        inside = s["yield_low"] <= r["yield"] <= s["yield_high"]
        print(f"reference, {reference:,} samples (seed 1): yield {100 * r['yield']:.2f} % (95 % interval "
              f"{100 * r['yield_low']:.2f} to {100 * r['yield_high']:.2f} %) in {ref_wall:.1f} s; inside the study's "
              f"interval: {inside}")
        record_study(figures, "reference", ref, ref_wall, reference, 1)
        figures.add("reference_inside", float(inside), "", f"the reference's yield inside the study's 95 % interval "
                    "(1 yes, 0 no)", target="1")
    figures.save()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
