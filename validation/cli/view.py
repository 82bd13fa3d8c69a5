"""``pcsuite view RUN.parquet|REPORT_DIR``: a stored run's scope in the browser (a local file: no server)."""
from __future__ import annotations

import sys

from converters.errors import ParameterError

from .common import given_path


def add(sub) -> None:
    view = sub.add_parser("view", help="open a stored run (simulate --out RUN.parquet), a report or a sweep in the "
                                       "browser")
    view.add_argument("path", type=given_path, help="RUN.parquet (a run's waveform file), a report's folder, a report "
                                                    "scene's folder, or a one-parameter sweep's folder")
    view.add_argument("--out", type=given_path, default=None,
                      help="where the run's scope page goes (FILE.html; default: a new temporary folder)")
    view.add_argument("--no-open", action="store_true", help="write the page and print its address only")
    view.set_defaults(run=run, no_time_limit=True)


def run(args) -> int:
    from converters.validate import quoted
    path = args.path
    if args.out is not None:
        from ..io import check_output_file
        check_output_file("--out", args.out)
        if args.out.suffix.lower() != ".html":
            raise ParameterError(f"--out must end in .html; got {str(args.out)!r}")
    if path.is_dir():
        if args.out is not None:
            raise ParameterError(f"--out applies to a run's file; {quoted(path)} is a folder whose pages exist already")
        page = next((path / name for name in ("index.html", "scope.html", "summary.html") if (path / name).is_file()),
                    None)
        if page is None:
            raise ParameterError(f"path must be a run's .parquet file, a report's folder (with index.html), a scene's "
                                 f"folder (with scope.html) or a sweep's (with summary.html); {quoted(path)} has none")
    elif path.suffix.lower() == ".parquet":
        page = _write_run_page(path, args.out)
    else:
        raise ParameterError(f"path must be a run's .parquet file or a report's folder; got {quoted(path)}"
                             + ("" if path.exists() else " (no such file)"))
    uri = page.resolve().as_uri()
    print(f"scope: {uri}")
    if not args.no_open:
        import webbrowser
        if not webbrowser.open(uri):
            print("no browser found here: open the address above in one", file=sys.stderr)
    return 0


def _write_run_page(path, out):
    import json

    import pyarrow.parquet as pq

    from converters.validate import quoted

    from ..scope import of_frame, write_scope
    if not path.is_file():
        raise ParameterError(f"path must be a run's .parquet file; {quoted(path)} does not exist")
    try:
        table = pq.read_table(path)
    except Exception as exc:                      # a file that is not Parquet, or a damaged one
        raise ParameterError(f"{quoted(path)} could not be read as Parquet: {str(exc).splitlines()[0]}") from None
    meta = {}
    raw = (table.schema.metadata or {}).get(b"pcsuite")
    if raw is not None:
        try:
            meta = json.loads(raw)
        except (ValueError, RecursionError):         # not JSON, or nested past what the parser takes
            meta = {}
        meta = meta if isinstance(meta, dict) else {}
    if out is None:
        import tempfile
        from pathlib import Path
        out = Path(tempfile.mkdtemp(prefix="pcsuite-view-")) / (path.stem + ".html")
    write_scope(of_frame(table.to_pandas(), meta, title=f"{path.name}: "
                         + ", ".join(str(meta[k]) for k in ("converter", "method") if meta.get(k))), out)
    return out
