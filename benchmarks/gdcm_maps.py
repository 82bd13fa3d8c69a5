"""The four LCP-only D-K maps (buck, boost, buck-boost, Cuk; 30 x 30 points each), one process.

Per point: closed-form and exact (matrix-exponential CCM orbit) prediction, the stepper's periodic
orbit (h = T/1000: 5 warm-up periods, Newton shooting with the exact Jacobian on one reused step plan)
and its mode class. Side by side on 30 points of the buck map: ``run_converter(steady=True)`` (20 warm-up
periods, the same shooting, then 20 periods simulated from the orbit), for the ratio.
Target (issue 6): the four maps in under 20 s.
"""
from __future__ import annotations

import time

from converters.run import run_converter
from validation.gdcm import _lcp_point, dk_grid, dk_map, map_summary


def main():
    _lcp_point(dk_grid("buck", 2, 2).to_dict("records")[0])  # load the compiled kernels
    start = time.perf_counter()
    for name in ("buck", "boost", "buck-boost", "cuk"):
        frame = dk_map(name, 30, 30, spice=False, progress=False)
        s = map_summary(frame)
        print(f"{name:<11} {s['points']} points in {s['lcp_wall_s']:.2f} s; far-from-boundary disagreements "
              f"{s['far_disagreements']}, near {s['near_disagreements']}, not converged {s['not_converged']}")
    total = time.perf_counter() - start
    print(f"four LCP maps: {total:.2f} s (target < 20 s) -> {'PASS' if total < 20 else 'FAIL'}")
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


if __name__ == "__main__":
    main()
