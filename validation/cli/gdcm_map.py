"""``pcsuite gdcm-map CONVERTER``: the D-K map of the conduction mode (prediction, LCP, ngspice)."""
from __future__ import annotations

import json
from pathlib import Path


def add(sub) -> None:
    from ..defaults import K_RANGES
    gmap = sub.add_parser("gdcm-map", help="D-K map of the conduction mode: prediction, LCP and ngspice")
    gmap.add_argument("converter", choices=list(K_RANGES))
    gmap.add_argument("--size", type=int, nargs=2, default=[30, 30], metavar=("N_D", "N_K"))
    gmap.add_argument("--no-spice", action="store_true", help="LCP and prediction only")
    gmap.add_argument("--workers", type=int, default=2, help="parallel ngspice processes (default 2)")
    gmap.add_argument("--out", type=Path, default=None, help="directory for map.csv and map.png")
    gmap.add_argument("--json", action="store_true", help="print the summary as JSON")
    gmap.set_defaults(run=run)


def run(args) -> int:
    from ..gdcm import dk_map, map_plot, map_summary
    from ..io import atomic_write_bytes
    n_d, n_k = args.size
    frame = dk_map(args.converter, n_d, n_k, spice=not args.no_spice, spice_workers=args.workers)
    summary = map_summary(frame)
    if args.out is not None:
        atomic_write_bytes(args.out / "map.csv", frame.drop(columns=["x0"], errors="ignore").to_csv(index=False).encode())
        atomic_write_bytes(args.out / "map.png", map_plot(frame))
    if args.json:
        print(json.dumps(summary, default=float))
    else:
        for key, value in summary.items():
            print(f"  {key:<28} {value:.4g}" if isinstance(value, float) else f"  {key:<28} {value}")
    return 0
