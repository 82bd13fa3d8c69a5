"""``pcsuite gdcm-map CONVERTER``: the D-K map of the conduction mode (prediction, LCP, ngspice)."""
from __future__ import annotations

from .common import MAX_WORKERS, check_workers, given_path, integer, json_text

SIZE_RANGE = (2, 1000)
OUT_FILES = ("map.csv", "map.png")
#: A map point's row (its columns, the ngspice run's record) and the plot's share, measured generously.
BYTES_PER_POINT = 4000


def add(sub) -> None:
    from ..defaults import K_RANGES
    gmap = sub.add_parser("gdcm-map", help="D-K map of the conduction mode: prediction, LCP and ngspice")
    gmap.add_argument("converter", choices=list(K_RANGES))
    gmap.add_argument("--size", type=integer(*SIZE_RANGE), nargs=2, default=[30, 30], metavar=("N_D", "N_K"),
                      help=f"points along D and along K, each in [{SIZE_RANGE[0]}, {SIZE_RANGE[1]}] (default 30 30)")
    gmap.add_argument("--no-spice", action="store_true", help="LCP and prediction only")
    gmap.add_argument("--workers", type=integer(1, MAX_WORKERS), default=None,
                      help=f"parallel ngspice processes, in [1, {MAX_WORKERS}] (default 2)")
    gmap.add_argument("--out", type=given_path, default=None, help="directory for map.csv and map.png")
    gmap.add_argument("--json", action="store_true", help="print the summary as JSON")
    gmap.set_defaults(run=run, no_time_limit=_without_spice)


def _without_spice(args) -> bool:
    """--time-limit bounds the map's ngspice runs: with --no-spice there are none (the LCP map solves no LCP
    iteratively)."""
    return args.no_spice


def run(args) -> int:
    from converters.errors import ParameterError
    from converters.limits import check_memory

    from ..gdcm import dk_map, map_plot, map_summary
    from ..io import atomic_write_files, check_output_dir, locked_output_dir
    check_output_dir("--out", args.out, "gdcm-map", OUT_FILES)         # before the run
    n_d, n_k = args.size
    for name, value in (("N_D", n_d), ("N_K", n_k)):
        if not SIZE_RANGE[0] <= value <= SIZE_RANGE[1]:
            raise ParameterError(f"--size {name} must be in [{SIZE_RANGE[0]}, {SIZE_RANGE[1]}]; got {value}")
    if args.workers is not None:
        if args.no_spice:
            raise ParameterError(f"--workers sets the ngspice processes; it does not apply with --no-spice (got "
                                 f"--workers {args.workers})")
        check_workers(args.workers)
    check_memory(f"gdcm-map: {n_d} x {n_k} points", n_d * n_k * BYTES_PER_POINT, remedy="a smaller --size")
    frame = dk_map(args.converter, n_d, n_k, spice=not args.no_spice,
                   spice_workers=2 if args.workers is None else args.workers)
    summary = map_summary(frame)
    if args.out is not None:
        table, picture = frame.drop(columns=["x0"], errors="ignore").to_csv(index=False).encode(), map_plot(frame)
        with locked_output_dir(args.out, "gdcm-map", OUT_FILES):     # checked again; two writers take turns
            # the table and its plot land together: a full disk leaves the earlier pair, or neither new file
            atomic_write_files({args.out / "map.csv": table, args.out / "map.png": picture})
    if args.json:
        print(json_text(summary))
    else:
        for key, value in summary.items():
            print(f"  {key:<28} {value:.4g}" if isinstance(value, float) else f"  {key:<28} {value}")
    return 0
