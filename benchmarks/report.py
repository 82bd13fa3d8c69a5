"""The default report end to end: its wall time and the size of the folder it writes (the report's own target:
under 50 MB).

Run: .venv/bin/python benchmarks/report.py   (or `make bench`). Runs `pcsuite report default` as a user does, in a
fresh process, into a temporary folder; needs ngspice (its scenes compare against it). Several minutes.
"""
from __future__ import annotations

import subprocess
import sys
import tempfile
import time
from pathlib import Path

from record import Figures


def folder_size(path: Path) -> int:
    return sum(p.stat().st_size for p in path.rglob("*") if p.is_file())


def main() -> None:
    figures = Figures("report", "the default report (`pcsuite report default`) as a fresh process")
    with tempfile.TemporaryDirectory() as scratch:
        out = Path(scratch) / "default"
        start = time.perf_counter()
        done = subprocess.run([sys.executable, "-m", "validation.cli", "report", "default", "--out", str(out)],
                              capture_output=True, text=True)
        wall = time.perf_counter() - start
        if done.returncode != 0:
            print(done.stdout[-2000:], done.stderr[-2000:])
            raise SystemExit(f"pcsuite report default exited {done.returncode}")
        size = folder_size(out)
    print(f"pcsuite report default: {wall:.1f} s wall, {size / 1e6:.1f} MB written")
    figures.add("wall_s", wall, "s", "the default suite (19 scenes with ngspice, every section), wall time",
                digits=3)
    figures.add("wall_min", wall / 60, "min", "the same, in minutes", digits=2)
    figures.add("size_mb", size / 1e6, "MB", "the folder it writes", target="< 50 MB")
    figures.save()


if __name__ == "__main__":
    main()
