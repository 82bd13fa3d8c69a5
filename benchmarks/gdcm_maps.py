"""The four LCP-only D-K maps (buck, boost, buck-boost, Cuk; 30 x 30 points each), one process.

Per point: closed-form and exact (matrix-exponential CCM orbit) prediction, the stepper's periodic
orbit (h = T/1000: 5 warm-up periods, Newton shooting with the exact Jacobian on one reused step plan)
and its mode class. Side by side on 30 points of the buck map: ``run_converter(steady=True)`` (20 warm-up
periods, the same shooting, then 20 periods simulated from the orbit), for the ratio.
Target (issue 6): the four maps in under 20 s.
"""
from __future__ import annotations

import time

from record import Figures  # benchmarks/record.py (this script's folder is sys.path[0])

from converters.run import run_converter
from validation.defaults import BOUNDARY_BAND
from validation.gdcm import _lcp_point, dk_grid, dk_map, map_summary


def main():
    figures = Figures("gdcm_maps", "the four LCP-only D-K maps in one process, and their cost per point")
    _lcp_point(dk_grid("buck", 2, 2).to_dict("records")[0])  # load the compiled kernels
    start = time.perf_counter()
    for name in ("buck", "boost", "buck-boost", "cuk"):
        frame = dk_map(name, 30, 30, spice=False, progress=False)
        s = map_summary(frame)
        print(f"{name:<11} {s['points']} points in {s['lcp_wall_s']:.2f} s; far-from-boundary disagreements "
              f"{s['far_disagreements']}, near {s['near_disagreements']}, not converged {s['not_converged']}")
        key = name.replace("-", "_")
        figures.add(f"{key}_s", s["lcp_wall_s"], "s", f"{name} D-K map, {s['points']} points (30 x 30), LCP only")
        figures.add(f"{key}_far_disagreements", s["far_disagreements"], "",
                    f"{name} D-K map: points more than {BOUNDARY_BAND:.0%} from the closed-form boundary where "
                    "the LCP's mode disagrees with the closed form", digits=1)
        figures.add(f"{key}_near_disagreements", s["near_disagreements"], "",
                    f"{name} D-K map: points within {BOUNDARY_BAND:.0%} of the closed-form boundary where the LCP's "
                    "mode disagrees with the closed form", digits=1)
        figures.add(f"{key}_not_converged", s["not_converged"], "",
                    f"{name} D-K map: points whose orbit did not converge", digits=1)
    total = time.perf_counter() - start
    print(f"four LCP maps: {total:.2f} s (target < 20 s) -> {'PASS' if total < 20 else 'FAIL'}")
    figures.add("four_maps_s", total, "s", "the four LCP-only D-K maps (buck, boost, buck-boost, Cuk; 30 x 30 points "
                "each), one process", target="< 20 s")
    rows = dk_grid("buck", 30, 30).to_dict("records")[::30]
    t0 = time.perf_counter()
    for r in rows:
        _lcp_point(r)
    fast = (time.perf_counter() - t0) / len(rows)
    t0 = time.perf_counter()
    for r in rows:
        run_converter("buck", {"D": r["D"], "R": r["R"]}, steady=True)
    slow = (time.perf_counter() - t0) / len(rows)
    print(f"per point: map path {fast * 1e3:.2f} ms, run_converter(steady=True) {slow * 1e3:.2f} ms "
          f"(ratio {slow / fast:.1f}x)")
    figures.add("per_point_map_ms", fast * 1e3, "ms", f"per point of the buck map's path (closed-form and exact "
                f"prediction, the stepper's orbit at h = T/1000 and its mode), mean over {len(rows)} points")
    figures.add("per_point_run_converter_ms", slow * 1e3, "ms", f"per point through run_converter(steady=True) "
                f"(20 warm-up periods, shooting, 20 periods returned), mean over the same {len(rows)} points")
    figures.add("run_converter_over_map", slow / fast, "x", "run_converter(steady=True)'s time per point over the "
                "map path's")
    figures.save()


if __name__ == "__main__":
    main()
