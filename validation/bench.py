"""``pcsuite bench``: the speed-accuracy trade-off and the stability map, written to one directory.

Files (each written atomically): tradeoff.csv (one row per run), tradeoff_references.csv (the exact
values), tradeoff_acceptance.csv (per case: ngspice default against the LCP stepper and the event
method), tradeoff.png (Pareto plot), stiffness.csv (smoothing: stiffness against eps), stability.csv,
stability_summary.csv, ill_posed.csv, and bench.json (date, versions, options, acceptance, counts).
The default validation report measures both itself, the trade-off in its quick form; when this directory holds a
full-size trade-off (``make bench``), the report shows that instead (:mod:`validation.sections`).
"""
from __future__ import annotations

import io
import json
import time
from pathlib import Path

import pandas as pd

from converters.errors import ParameterError

from .io import atomic_write_files, check_output_dir, locked_output_dir
from .report import csv_bytes as _csv

DEFAULT_OUT = Path("reports/bench")
PARTS = ("tradeoff", "stability")
TRADEOFF_FILES = ("tradeoff.csv", "tradeoff_references.csv", "tradeoff_acceptance.csv", "tradeoff.png",
                  "stiffness.csv")
STABILITY_FILES = ("stability.csv", "stability_summary.csv", "ill_posed.csv")
STIFFNESS_EPS = (1e-2, 1e-3, 1e-4, 1e-5, 1e-6)

#: --periods of the trade-off runs.
PERIODS_RANGE = (2, 100_000)


def read_csv(data: bytes) -> pd.DataFrame:
    return pd.read_csv(io.BytesIO(data), keep_default_na=False, na_values=["", "nan", "NaN"])


def collect_tradeoff(quick: bool = False, spice: bool = True, periods: int | None = None,
                     progress: bool = True) -> tuple[dict, dict]:
    """Run the trade-off: (files by name, summary). ``quick``: the DCM cases and a short sweep (the form the
    default report measures itself)."""
    from .tradeoff import CASES, FULL, PERIODS, QUICK, acceptance, pareto_plot, stiffness_table, tradeoff_table
    start = time.perf_counter()
    cases = CASES[1::2] if quick else CASES
    periods = PERIODS if periods is None else periods
    runs, refs = tradeoff_table(cases, QUICK if quick else FULL, spice=spice, periods=periods, progress=progress)
    accept = acceptance(runs)
    stiffness = stiffness_table(STIFFNESS_EPS)
    files = {"tradeoff.csv": _csv(runs), "tradeoff_references.csv": _csv(refs),
             "tradeoff_acceptance.csv": _csv(accept), "tradeoff.png": pareto_plot(runs),
             "stiffness.csv": _csv(stiffness)}
    summary = {"runs": len(runs), "failed_runs": int((runs["failure"] != "").sum()), "periods": periods,
               "quick": quick, "spice": spice, "cases": [case.name for case in cases],
               "wall_s": time.perf_counter() - start,
               "acceptance": accept.to_dict(orient="records")}
    return files, summary


def collect_stability(spice: bool = True, progress: bool = True) -> tuple[dict, dict]:
    """Run the stability map and the ill-posed requests: (files by name, summary)."""
    from .stability import METHODS, ill_posed_table, stability_summary, stability_table
    start = time.perf_counter()
    methods = METHODS if spice else tuple(m for m in METHODS if m != "ngspice")
    table = stability_table(methods, progress=progress)
    counts = stability_summary(table)
    refused = ill_posed_table()
    files = {"stability.csv": _csv(table), "stability_summary.csv": _csv(counts), "ill_posed.csv": _csv(refused)}
    summary = {"runs": len(table), "spice": spice, "wall_s": time.perf_counter() - start,
               "summary": counts.to_dict(orient="records"),
               "ill_posed_refused": int(refused["refused"].sum()), "ill_posed": len(refused)}
    return files, summary


def run_bench(out: Path = DEFAULT_OUT, quick: bool = False, spice: bool = True, only: str | None = None,
              periods: int | None = None, progress: bool = True) -> dict:
    """Run the trade-off and/or the stability map and write their files into ``out``; returns the summary.

    Files of a part not run are left as they are; bench.json holds one summary per part (with its date
    and the environment), the parts run now replacing their earlier summaries."""
    if only not in (None, *PARTS):
        raise ParameterError(f"only must be one of {', '.join(PARTS)}; got {only!r}")
    low, high = PERIODS_RANGE
    if periods is not None and not (isinstance(periods, int) and low <= periods <= high):
        raise ParameterError(f"periods must be an integer in [{low}, {high}]; got {periods!r}")
    from .environment import environment
    out = Path(out)
    stamp = {"date": time.strftime("%Y-%m-%d %H:%M:%S %Z"), "environment": environment()}
    summary: dict = {}
    files: dict[str, bytes] = {}
    if only in (None, "tradeoff"):
        part_files, summary["tradeoff"] = collect_tradeoff(quick, spice, periods, progress)
        files.update(part_files)
    if only in (None, "stability"):
        part_files, summary["stability"] = collect_stability(spice, progress)
        files.update(part_files)
    for part in summary.values():
        part.update(stamp)
    with locked_output_dir(out, "bench", OUT_FILES):   # checked again; two writers take turns
        saved = _read_json(out / "bench.json")        # a part not run keeps its earlier summary
        files["bench.json"] = json.dumps({**saved, **summary}, indent=2, default=float).encode()
        # the tables, plots and summary land together: a full disk leaves the earlier set, never half of each
        atomic_write_files({out / name: data for name, data in files.items()})
    return summary


#: Every file ``pcsuite bench`` writes into its directory: a directory holding anything else is not its output.
OUT_FILES = (*TRADEOFF_FILES, *STABILITY_FILES, "bench.json")


def check_out(out=None, flag: str = "--out") -> None:
    """Refuse, before the runs, an output directory bench must not write into (validation.io.check_output_dir):
    it must be new, empty, or hold only files of an earlier ``pcsuite bench``."""
    check_output_dir(flag, DEFAULT_OUT if out is None else out, "bench", OUT_FILES)


def _read_json(path: Path) -> dict:
    try:
        return json.loads(path.read_text())
    except (OSError, ValueError):
        return {}


def full_size(summary: dict) -> bool:
    """Whether a saved trade-off summary is the full-size measurement (``make bench``): every case and the whole sweep,
    with ngspice, over at least the default periods per run."""
    from .tradeoff import PERIODS
    return (summary.get("quick") is False and summary.get("spice") is True
            and isinstance(summary.get("periods"), int) and summary["periods"] >= PERIODS)


def read_bench(directory: Path = DEFAULT_OUT, part: str = "tradeoff") -> tuple[dict, dict] | None:
    """The saved files of one part and its summary from a previous ``pcsuite bench``, or None."""
    directory = Path(directory)
    names = TRADEOFF_FILES if part == "tradeoff" else STABILITY_FILES
    if not all((directory / name).is_file() for name in names):
        return None
    files = {name: (directory / name).read_bytes() for name in names}
    return files, _read_json(directory / "bench.json").get(part, {})
