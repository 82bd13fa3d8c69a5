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


def write_frame(frame, path: Path) -> None:
    """A waveform table as CSV or Parquet, written atomically (never a partial file in place of a good one)."""
    from ..io import atomic_write_bytes
    frame = frame.copy()
    if "mode" in frame:
        frame["mode"] = frame["mode"].astype(str)
    if path.suffix.lower() == ".csv":
        data = frame.to_csv(index=False).encode()
    else:
        import io
        buffer = io.BytesIO()
        frame.to_parquet(buffer, index=False)
        data = buffer.getvalue()
    atomic_write_bytes(path, data)
