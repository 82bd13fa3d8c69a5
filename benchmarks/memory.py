"""The memory estimates every run is checked against (converters.limits), against the measured peak.

Each case runs in a fresh process: its peak resident set above the process's baseline (imports done), with the
waveform file written as `pcsuite simulate --out` writes it, against ``Method.memory_estimate`` (or
``validation.spice``'s ngspice estimate). A ratio above 1 means the estimate is on the safe side; the limit's
purpose (refuse before allocating) needs ratios >= 1 and not far above (a ratio of 10 would refuse runs that fit).

    python benchmarks/memory.py
"""
from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

CHILD = r"""
import json, resource, sys, tempfile
from pathlib import Path
method, periods, h = sys.argv[1], int(sys.argv[2]), sys.argv[3]
from converters.models import get_model
from converters.run import make_method, run_converter, run_summary
from validation.cli.common import write_frame
model = get_model("buck"); p = model.resolve({})
base = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
if method == "spice":
    from netlists import model_netlist
    from validation.spice import BYTES_PER_POINT_VECTOR, check_spice_memory, run_spice, spice_points, spice_trajectory
    net = model_netlist(model, p, periods * model.period(p))
    vectors = sum(1 for line in net.text.splitlines() if line[:1].isalpha()) + 4
    estimate = spice_points(net) * vectors * BYTES_PER_POINT_VECTOR
    result = run_spice(net)
    tr = spice_trajectory(model, p, net, result, result.time[-1] - 10 * model.period(p))
    samples = result.time.size
    peak = max(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss, resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss) * 1024
else:
    m = make_method(model, p, method, h)
    estimate = m.memory_estimate(model.problem(p, periods * model.period(p)))
    tr = run_converter("buck", {}, method=m, periods=periods)
    run_summary(tr)
    samples = tr.t.size
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
write_frame(tr.waveforms(), Path(tempfile.mkdtemp()) / "w.parquet")
peak = max(peak, resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024)
print(json.dumps({"samples": int(samples), "estimate": estimate, "peak": peak - base, "base": base}))
"""

CASES = [("lcp", 2000, "1e-8"), ("lcp", 500, "1e-8"), ("event", 1000, "1e-8"), ("smooth", 100, "1e-8"),
         ("spice", 2000, "1e-8")]
#: A case's method in words, for the figures' labels.
METHODS = {"lcp": "the LCP stepper", "event": "the event method", "smooth": "smoothing", "spice": "ngspice"}


def main() -> None:
    from record import Figures
    figures = Figures("memory", "the memory estimate every run is checked against, against the measured peak of a "
                      "fresh process (the buck, its waveform file written)")
    print(f"{'method':8s} {'samples':>10s} {'estimate':>10s} {'peak':>10s} {'estimate/peak':>14s}")
    for method, periods, h in CASES:
        out = subprocess.run([sys.executable, "-c", CHILD, method, str(periods), h], capture_output=True, text=True,
                             cwd=ROOT, check=True)
        row = json.loads(out.stdout.strip().splitlines()[-1])
        print(f"{method:8s} {row['samples']:>10,d} {row['estimate'] / 2**20:>8.0f} MB {row['peak'] / 2**20:>8.0f} MB "
              f"{row['estimate'] / row['peak']:>14.2f}")
        key = f"{method}{periods}"
        run = (f"buck, {periods:,} periods, {METHODS[method]}" + (f" at h = {h} s" if method != "spice" else "")
               + f" ({row['samples']:,} samples), waveform file written, in a fresh process")
        figures.add(f"{key}_samples", row["samples"], "", f"{run}: samples stored", digits=1)
        figures.add(f"{key}_estimate_mb", row["estimate"] / 2**20, "MB", f"{run}: the estimate checked before the run")
        figures.add(f"{key}_peak_mb", row["peak"] / 2**20, "MB", f"{run}: measured peak RSS above the process's "
                    "baseline (imports done)")
        figures.add(f"{key}_estimate_over_peak", row["estimate"] / row["peak"], "x", f"{run}: estimate / measured peak",
                    target=">= 1x and not far above")
        figures.add(f"{key}_peak_bytes_per_sample", row["peak"] / row["samples"], "",
                    f"{run}: measured peak in bytes per stored sample", digits=2)
        figures.add(f"{key}_estimate_bytes_per_sample", row["estimate"] / row["samples"], "",
                    f"{run}: the estimate in bytes per stored sample", digits=2)
        figures.add(f"{key}_baseline_mb", row["base"] / 2**20, "MB", f"{run}: the process's peak RSS after the script's imports, "
                    "before the run (subtracted from the peak; left out of the estimate)")
    figures.save()


if __name__ == "__main__":
    main()
