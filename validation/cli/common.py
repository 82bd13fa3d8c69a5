"""Helpers shared by the subcommands: parameter options, the method options, waveform files."""
from __future__ import annotations

from pathlib import Path

from converters.errors import ParameterError


def add_params(parser) -> None:
    parser.add_argument("-p", dest="params", action="append", default=[], metavar="NAME=VALUE",
                        help="parameter value, SPICE suffixes allowed (repeatable)")


def check_out(path: Path | None, suffixes=(".csv", ".parquet")) -> None:
    if path is not None and path.suffix.lower() not in suffixes:
        raise ParameterError(f"--out must end in {' or '.join(suffixes)}; got {str(path)!r}")


#: Units of waveform columns by name (states by their first letter: i* currents, v* voltages).
_UNITS = {"time": "s", "vout": "V", "iref": "A", "switch": "1", "mode": ""}


def column_units(columns) -> dict:
    return {c: _UNITS.get(c, "A" if c.startswith("i") else "V" if c.startswith("v") else "") for c in columns}


def write_frame(frame, path: Path, meta: dict | None = None) -> None:
    """A waveform table as CSV or Parquet, written atomically (never a partial file in place of a good one).
    ``meta`` (converter, parameters, method and its options) and the columns' units (default: a converter's,
    by :func:`column_units`) travel with it: in the
    Parquet schema's metadata (key ``pcsuite``), or in a JSON sidecar ``FILE.csv.json`` beside a CSV."""
    import json

    from ..io import atomic_write_bytes
    frame = frame.copy()
    if "mode" in frame:
        frame["mode"] = frame["mode"].astype(str)
    meta = dict(meta or {})
    meta.setdefault("units", column_units(frame.columns))
    info = json.dumps(meta, default=_plain).encode()
    if path.suffix.lower() == ".csv":
        atomic_write_bytes(path, frame.to_csv(index=False).encode())
        atomic_write_bytes(path.with_name(path.name + ".json"), info)
        return
    import io

    import pyarrow as pa
    import pyarrow.parquet as pq
    table = pa.Table.from_pandas(frame, preserve_index=False)
    table = table.replace_schema_metadata({**(table.schema.metadata or {}), b"pcsuite": info})
    buffer = io.BytesIO()
    pq.write_table(table, buffer)
    atomic_write_bytes(path, buffer.getvalue())


def _plain(value):
    try:
        return float(value)
    except (TypeError, ValueError):
        return str(value)
