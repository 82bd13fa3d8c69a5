"""Sweeps on disk: an ensemble's rows streamed into a Parquet dataset that survives an interruption.

Layout of a sweep directory::

    DIR/sweep.json          what was asked (model, method, parameters, points): the sweep's identity
    DIR/parts/*.parquet     one part per finished chunk, each written atomically (whole or absent)
    DIR/parts.jsonl         one line per part written: its name, rows, bytes and SHA-256
    DIR/summary.png         a metric over the grid (written when the sweep completes)
    DIR/.lock               held while a process writes (a second writer is refused)

Resuming is running the same sweep into the same directory: the indices already on disk are skipped, so an
interrupted sweep (SIGINT, a killed process, a lost machine) computes only its missing points and ends with
the dataset an uninterrupted run writes. A directory holding a different sweep, or anything else, is
refused, never overwritten. Resume trusts no part blindly: a part listed in ``parts.jsonl`` must have the
bytes listed there, and one that is not (a kill between a part's rename and its line) must have the sweep's
columns; every part must carry the sweep's digest (the SHA-256 of its identity, a netlist's content included, in
the part's Parquet metadata: another sweep's part copied in, the journal edited to match, is refused) and that of
its own rows (one edited in place with the journal deleted is refused); every part's indices must lie in the sweep
and appear once. Anything else in ``parts/`` (a copied part, another table, a link, a FIFO) is refused with one
line naming it, and nothing is changed. Read a sweep back with :func:`load_sweep` (or
``pandas.read_parquet(DIR / "parts")``).

A sweep in ngspice is the same :class:`converters.sweeps.ModelSweep` with ``method="spice"`` (the method measures
each point on its own run: :meth:`validation.ngspice.Spice.sweep_row`). A failed ngspice run ("timestep too small")
is a row; every run goes through the recycled, time-limited ngspice worker of :mod:`.spice` inside whichever worker
holds the chunk.
"""
from __future__ import annotations

import hashlib
import io
import json
import os
import stat
import time
import uuid
from dataclasses import asdict, dataclass, field, fields
from pathlib import Path

import numpy as np
import pandas as pd

from converters.errors import ParameterError
from converters.parallel import run_ensemble
from converters.sweeps import failed_row
from converters.validate import quoted

from .io import _kind, atomic_write_bytes, atomic_write_files, atomic_write_text

MANIFEST = "sweep.json"
PARTS = "parts"
JOURNAL = "parts.jsonl"
LOCK = ".lock"
#: 2: every part carries its sweep's digest (SWEEP_KEY in its Parquet metadata); a netlist's content is hashed.
#: 3: and the digest of its own rows (ROWS_KEY).
FORMAT = 3
SWEEP_KEY = b"pcsuite.sweep"
ROWS_KEY = b"pcsuite.rows"
#: A sweep.json is a few hundred bytes; a larger one is not a sweep's (and is not read whole).
MANIFEST_MAX_BYTES = 1 << 20


# --- the dataset --------------------------------------------------------------------------------------------

def describe(ensemble, points) -> dict:
    """The identity of a sweep: what is computed at which points (compared on resume; fields kept out of the
    comparison, as what is derived from the others, are left out)."""
    from converters.models import is_netlist
    identity = {f.name for f in fields(ensemble) if f.compare}
    settings = {k: v for k, v in asdict(ensemble).items() if k in identity}
    out = {"format": FORMAT, "ensemble": type(ensemble).__name__, **json.loads(json.dumps(settings)),
           "points": points.describe(), "size": int(points.size)}
    if is_netlist(ensemble.model):            # the circuit itself, not only its file's name
        out["model_sha256"] = hashlib.sha256(Path(ensemble.model).read_bytes()).hexdigest()
    return out


def digest(identity: dict) -> str:
    """The SHA-256 of a sweep's identity: every part carries it (its Parquet metadata), and resume takes only the
    parts that carry this sweep's."""
    return hashlib.sha256(json.dumps(identity, sort_keys=True).encode()).hexdigest()


def schema(ensemble, names):
    import pyarrow as pa
    kinds = {float: pa.float64(), int: pa.int64(), str: pa.string(), bool: pa.bool_()}
    columns = [("index", pa.int64()), *[(n, pa.float64()) for n in names], ("status", pa.string()),
              ("message", pa.string()), *[(k, kinds[t]) for k, t in ensemble.measures.items()],
              ("wall_s", pa.float64())]
    units = getattr(ensemble, "units", {}) or {}
    return pa.schema(columns, metadata={b"units": json.dumps(units, sort_keys=True).encode()})


def rows_digest(table) -> str:
    """The SHA-256 of a part's rows as JSON (its values, not its bytes: the same whatever writes the Parquet)."""
    return hashlib.sha256(json.dumps(table.to_pylist(), sort_keys=True, default=str).encode()).hexdigest()


def read_part(data: bytes, columns=None):
    """A part's Parquet bytes as an Arrow table, read on this thread.

    Read from a path or with Arrow's thread pools, a part leaves pool threads alive that Arrow tears down at
    interpreter exit; under load that teardown aborts the process now and then ("terminate called without an
    active exception", SIGABRT: apache/arrow#34314) after pcsuite has said everything. A part is small: reading its
    bytes on the calling thread starts no pool."""
    import pyarrow as pa
    import pyarrow.parquet as pq
    return pq.ParquetFile(pa.BufferReader(data)).read(columns=columns, use_threads=False)


class SweepStore:
    """A sweep directory (module docstring): claim it, find what is done, add parts, read it back."""

    def __init__(self, out, identity: dict, arrow_schema):
        self.out = Path(out)
        self.identity, self.digest = identity, digest(identity)
        self.schema = arrow_schema.with_metadata({**(arrow_schema.metadata or {}), SWEEP_KEY: self.digest.encode()})
        self._lock = None

    @property
    def parts(self) -> Path:
        return self.out / PARTS

    def claim(self) -> np.ndarray:
        """Take the directory (create it, or check it holds this very sweep) and return the indices on disk, every
        part verified (module docstring)."""
        out = self.out
        if out.is_symlink():                                        # as every other --out: no writes through a link
            raise ParameterError(f"--out {quoted(out)}: a symbolic link; give the directory's own path or choose "
                                 "another --out")
        if out.exists() and not out.is_dir():
            raise ParameterError(f"--out must be a directory; {str(out)!r} is a file")
        manifest = out / MANIFEST
        if out.exists() and any(out.iterdir()) and not os.path.lexists(manifest):
            raise ParameterError(f"--out {str(out)!r} is a non-empty directory that holds no sweep; choose a new "
                                 "or empty directory (nothing was written)")
        if os.path.lexists(manifest):
            held = self._identity_on_disk(manifest)
            earlier = held.get("format")
            if isinstance(earlier, int) and 0 < earlier < FORMAT and {"ensemble", "points"} <= set(held):
                raise ParameterError(f"--out {str(out)!r} holds a sweep of an earlier pcsuite (format "
                                     f"{held.get('format')!r}; this one writes {FORMAT}), which it cannot resume; "
                                     "read it with pandas.read_parquet, and choose another directory for the sweep "
                                     "(nothing was changed)")
            if held != self.identity:
                keys = sorted(k for k in set(held) | set(self.identity) if held.get(k) != self.identity.get(k))
                diff = "; ".join(f"{k}: {held.get(k)!r} on disk, {self.identity.get(k)!r} asked" for k in keys[:3])
                raise ParameterError(f"--out {str(out)!r} holds a different sweep ({diff}); resume it with the same "
                                     "arguments or choose another directory (nothing was changed)")
        out.mkdir(parents=True, exist_ok=True)
        self._take_lock()
        try:
            done, journal, adopt = self._verify()           # under the lock: no other writer adds parts meanwhile
            if not manifest.exists():
                atomic_write_text(manifest, json.dumps(self.identity, indent=1) + "\n")
            self.parts.mkdir(exist_ok=True)
            if adopt or journal.torn:
                atomic_write_text(out / JOURNAL, "".join(journal.lines) + "".join(adopt))
        except BaseException:
            self.release()
            raise
        return done

    def _refuse(self, problem: str) -> ParameterError:
        return ParameterError(f"--out {quoted(self.out)}: {problem}; remove it or choose another --out (nothing was "
                              "changed)")

    def _identity_on_disk(self, manifest: Path) -> dict:
        where = f"--out {str(self.out)!r}: its {MANIFEST}"
        try:
            info = os.lstat(manifest)
            if not stat.S_ISREG(info.st_mode):               # a FIFO would be waited on forever, a link followed
                raise ParameterError(f"{where} is {_what(info.st_mode)}, not the file a sweep writes; choose another "
                                     "directory")
            if info.st_size > MANIFEST_MAX_BYTES:
                raise ParameterError(f"{where} is not a pcsuite sweep's ({info.st_size:,} bytes); choose another "
                                     "directory")
            held = json.loads(manifest.read_text())
        except (OSError, ValueError) as exc:
            if isinstance(exc, ParameterError):
                raise
            raise ParameterError(f"{where} is unreadable ({exc}); choose another directory") from None
        if not isinstance(held, dict):
            holds = "null" if held is None else type(held).__name__
            raise ParameterError(f"{where} is not a pcsuite sweep's (it holds {holds}); choose another directory")
        return held

    def _take_lock(self):
        import fcntl
        path = self.out / LOCK
        # never through a link (it would create its target), never a FIFO's open that waits for a writer
        flags = os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW | os.O_NONBLOCK | os.O_CLOEXEC
        try:
            fd = os.open(path, flags, 0o666)
            mode = os.fstat(fd).st_mode
        except OSError as exc:
            try:
                what = _what(os.lstat(path).st_mode)
            except OSError:
                what = f"unusable ({exc.strerror})"
            raise ParameterError(f"--out {quoted(self.out)}: its {LOCK} is {what}, not the lock file a sweep creates; "
                                 "remove it or choose another --out") from None
        if not stat.S_ISREG(mode):
            os.close(fd)
            raise ParameterError(f"--out {quoted(self.out)}: its {LOCK} is {_what(mode)}, not the lock file a sweep "
                                 "creates; remove it or choose another --out")
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            os.close(fd)
            raise ParameterError(f"--out {str(self.out)!r}: another process is writing this sweep; wait for it or "
                                 "choose another directory") from None
        self._lock = fd

    def release(self):
        if self._lock is not None:
            os.close(self._lock)
            self._lock = None

    def done(self) -> np.ndarray:
        """The indices already stored (sorted), every part verified."""
        return self._verify()[0]

    def _verify(self):
        """(indices stored, the journal, journal lines for the verified parts it does not list), or a refusal
        naming the first part resume cannot trust."""
        journal = _Journal.read(self.out / JOURNAL, self._refuse)
        size = int(self.identity["size"])
        seen = np.zeros(size, dtype=bool)
        if not os.path.lexists(self.parts):
            return np.flatnonzero(seen), journal, []
        mode = os.lstat(self.parts).st_mode
        if not stat.S_ISDIR(mode):
            raise self._refuse(f"{PARTS} is {_what(mode)}, not the directory of parts a sweep writes")
        names = sorted(entry for entry in os.listdir(self.parts) if not entry.startswith((".", "_")))  # temporaries
        # the parts the journal lists first: a copy of one of them is the stranger
        names.sort(key=lambda name: name not in journal.parts)
        stored, adopt = [], []
        for name in names:
            path = self.parts / name
            where = f"{PARTS}/{quoted(name)}"
            info = os.lstat(path)
            if not stat.S_ISREG(info.st_mode):
                raise self._refuse(f"{where} is {_what(info.st_mode)}, not a part pcsuite wrote")
            if not name.endswith(".parquet"):
                raise self._refuse(f"{where} is not a part of this sweep (not a .parquet file)")
            data = path.read_bytes()
            listed = journal.parts.get(name)
            if listed is not None and (listed.get("bytes") != len(data)
                                       or listed.get("sha256") != hashlib.sha256(data).hexdigest()):
                raise self._refuse(f"{where} was changed after pcsuite wrote it (its size or SHA-256 is not the one "
                                   f"{JOURNAL} lists)")
            indices = self._indices(data, where, check_schema=listed is None)
            self._check_mark(data, where)
            outside = indices[(indices < 0) | (indices >= size)]
            if outside.size:
                raise self._refuse(f"{where} holds index {int(outside[0])}, outside the sweep's {size:,} points "
                                   f"[0, {size - 1:,}]")
            unique, counts = np.unique(indices, return_counts=True)
            if (counts > 1).any():
                raise self._refuse(f"{where} holds index {int(unique[counts > 1][0])} more than once")
            again = indices[seen[indices]]
            if again.size:
                owner = next(other for other, held in stored if np.isin(again[0], held))
                more = f" and {again.size - 1:,} more" if again.size > 1 else ""
                raise self._refuse(f"{where} holds indices also stored in {PARTS}/{quoted(owner)} (index "
                                   f"{int(again[0])}{more}); one of them is not a part this sweep wrote")
            self._check_rows(data, where)
            seen[indices] = True
            stored.append((name, indices))
            if listed is None:
                adopt.append(_Journal.line(name, len(indices), data))
        return np.flatnonzero(seen).astype(np.int64), journal, adopt

    def _check_mark(self, data: bytes, where: str) -> None:
        """Refuse a part that does not carry this sweep's digest (another sweep's part, copied in with the journal
        edited: its rows computed at other parameters)."""
        import pyarrow as pa
        import pyarrow.parquet as pq
        mark = (pq.ParquetFile(pa.BufferReader(data)).schema_arrow.metadata or {}).get(SWEEP_KEY, b"").decode()
        if mark != self.digest:
            held = f"another sweep's ({mark[:12]})" if mark else "no sweep's"
            raise self._refuse(f"{where} was written by {held}, not this one's ({self.digest[:12]}: the model, its "
                               "parameters, the points and the options in sweep.json)")

    def _check_rows(self, data: bytes, where: str) -> None:
        """Refuse a part whose rows are not those it was written with (ROWS_KEY): one edited in place, its metadata
        kept and the journal deleted, had been taken in (a vout_mean of 99 V, a D moved to 0.9)."""
        import pyarrow as pa
        import pyarrow.parquet as pq
        written = (pq.ParquetFile(pa.BufferReader(data)).schema_arrow.metadata or {}).get(ROWS_KEY, b"").decode()
        if written != rows_digest(read_part(data)):
            raise self._refuse(f"{where} was changed after pcsuite wrote it (its rows are not the ones it was written "
                               "with)")

    def _indices(self, data: bytes, where: str, check_schema: bool) -> np.ndarray:
        """A part's index column; for a part the journal does not list, its columns are checked first."""
        import pyarrow as pa
        import pyarrow.parquet as pq
        try:
            if check_schema:
                found = pq.ParquetFile(pa.BufferReader(data)).schema_arrow
                if not found.equals(self.schema, check_metadata=False):
                    difference = _schema_difference(found, self.schema)
                    raise self._refuse(f"{where} is not a part of this sweep ({difference})")
            column = read_part(data, columns=["index"]).column(0)
        except (pa.ArrowException, OSError, ValueError) as exc:
            if isinstance(exc, ParameterError):
                raise
            first = str(exc).splitlines()[0][:120] if str(exc) else type(exc).__name__
            raise self._refuse(f"{where} is not a part of this sweep (not a Parquet table: {first})") from None
        if column.null_count:
            raise self._refuse(f"{where} is not a part of this sweep (rows without an index)")
        return column.to_numpy().astype(np.int64)

    def write(self, rows: list[dict]) -> None:
        """One part, atomically, then its line in the journal."""
        import pyarrow as pa
        import pyarrow.parquet as pq
        table = pa.Table.from_pylist(rows, schema=self.schema)
        table = table.replace_schema_metadata({**(self.schema.metadata or {}), ROWS_KEY: rows_digest(table).encode()})
        buffer = io.BytesIO()
        pq.write_table(table, buffer)
        first = min(row["index"] for row in rows)
        name = f"part-{first:09d}-{uuid.uuid4().hex[:8]}.parquet"
        data = buffer.getvalue()
        atomic_write_bytes(self.parts / name, data)
        _Journal.append(self.out / JOURNAL, _Journal.line(name, len(rows), data))


def _schema_difference(found, wanted) -> str:
    """Where a part's columns first differ from a sweep's: a name, or a type under the same names (a part rewritten
    by pandas, its columns' names all kept, had been shown as two identical-looking lists)."""
    if found.names == wanted.names:
        name = next(f.name for f, w in zip(found, wanted) if not f.equals(w, check_metadata=False))
        return (f"its column {name} is {found.field(name).type}{'' if found.field(name).nullable else ' not null'}, "
                f"a part's {wanted.field(name).type}")
    columns = ", ".join(found.names[:8]) + (", ..." if len(found.names) > 8 else "")
    expected = ", ".join(wanted.names[:8]) + (", ..." if len(wanted.names) > 8 else "")
    return f"its columns: {columns}; a part's: {expected}"


def _what(mode: int) -> str:
    return "a directory" if stat.S_ISDIR(mode) else _kind(mode)


class _Journal:
    """``parts.jsonl``: one JSON line per part the sweep wrote (name, rows, bytes, SHA-256), appended after the
    part is in place. A last line without its newline is a kill's torn write: dropped, and rewritten away."""

    def __init__(self, lines: list[str], torn: bool):
        self.lines, self.torn = lines, torn
        self.parts = {json.loads(line)["part"]: json.loads(line) for line in lines}

    @staticmethod
    def line(name: str, rows: int, data: bytes) -> str:
        return json.dumps({"part": name, "rows": int(rows), "bytes": len(data),
                           "sha256": hashlib.sha256(data).hexdigest()}) + "\n"

    @classmethod
    def read(cls, path: Path, refuse) -> "_Journal":
        if not os.path.lexists(path):
            return cls([], False)
        mode = os.lstat(path).st_mode
        if not stat.S_ISREG(mode):
            raise refuse(f"{JOURNAL} is {_what(mode)}, not the list of parts a sweep writes")
        text = path.read_text(errors="replace")
        lines = text.splitlines(keepends=True)
        torn = bool(lines) and not lines[-1].endswith("\n")
        if torn:
            lines = lines[:-1]
        for number, line in enumerate(lines, 1):
            try:
                entry = json.loads(line)
                ok = isinstance(entry, dict) and isinstance(entry.get("part"), str)
            except ValueError:
                ok = False
            if not ok:
                raise refuse(f"{JOURNAL} line {number} is not a line pcsuite wrote (without the file, every part is "
                             "checked again)")
        return cls(lines, torn)

    @staticmethod
    def append(path: Path, line: str) -> None:
        fd = os.open(path, os.O_WRONLY | os.O_APPEND | os.O_CREAT | os.O_NOFOLLOW | os.O_CLOEXEC, 0o666)
        try:
            os.write(fd, line.encode())
            os.fsync(fd)
        finally:
            os.close(fd)


def load_sweep(out) -> pd.DataFrame:
    """A sweep's rows by index (all parts on disk, complete or not)."""
    parts = Path(out) / PARTS
    if not (Path(out) / MANIFEST).exists():
        raise ParameterError(f"{str(out)!r} holds no sweep ({MANIFEST} missing)")
    files = sorted(parts.glob("*.parquet")) if parts.is_dir() else []
    if not files:
        return pd.DataFrame()
    frame = pd.concat([read_part(f.read_bytes()).to_pandas(use_threads=False) for f in files], ignore_index=True)
    return frame.sort_values("index", kind="stable").reset_index(drop=True)


@dataclass
class SweepRun:
    out: Path
    size: int
    on_disk_before: int
    computed: int
    wall_s: float
    interrupted: bool = False

    @property
    def rate(self) -> float:
        return self.computed / self.wall_s if self.wall_s > 0 else float("nan")


def run_sweep(ensemble, points, out, *, backend="local", workers: int | None = None, chunk: int | None = None,
              progress: bool = True) -> SweepRun:
    """Compute the points of ``points`` not yet in ``out`` and stream their rows there (module docstring).

    The points' extremes are checked against the model's ranges before anything is written. An interruption
    (KeyboardInterrupt, SystemExit) stops the workers and leaves every finished chunk on disk; it propagates
    after the store is released."""
    for point in points.extremes():
        ensemble.validate(point)
    store = SweepStore(out, describe(ensemble, points), schema(ensemble, points.names))
    done = store.claim()
    try:
        missing = np.setdiff1d(np.arange(points.size, dtype=np.int64), done, assume_unique=False)
        clock = time.perf_counter()
        computed = run_ensemble(ensemble, points, backend=backend, workers=workers, indices=missing, chunk=chunk,
                                on_rows=store.write, progress=progress, label=f"sweep {ensemble.model}",
                                done=int(done.size))
        return SweepRun(Path(out), int(points.size), int(done.size), int(computed), time.perf_counter() - clock)
    finally:
        store.release()


# --- the summary plot ---------------------------------------------------------------------------------------

def _labelled(name: str, units: dict) -> str:
    unit = units.get(name, "")
    return f"{name} ({unit})" if unit not in ("", "1") else name


def _engineering(axis, name: str, units: dict) -> None:
    """An axis's ticks in engineering notation with the quantity's unit (90 uH, 12.5 mV), no offset; its label the
    quantity's name."""
    from matplotlib.ticker import EngFormatter, MaxNLocator, ScalarFormatter
    unit = units.get(name, "")
    if unit in ("", "1"):             # a ratio (an efficiency) reads 0.985, not 985 m
        formatter = ScalarFormatter(useOffset=False)
        formatter.set_scientific(False)
        axis.set_major_formatter(formatter)
    else:
        axis.set_major_formatter(EngFormatter(unit=unit, places=None))
    axis.set_major_locator(MaxNLocator(6))          # labels with a unit need room: at most six


def tolerance_plot(frame: pd.DataFrame, points, metrics, specs=(), units=None, title: str = "") -> bytes:
    """A tolerance study, a row per metric (``metrics``: a name or several): its histogram with its specs' bounds
    and the fraction meeting them, and the metric against the parameter it follows most closely (the largest |rank
    correlation|); the yield over every spec in the title; units on the axes."""
    from converters.sweeps.specs import study_summary

    from .plots import plt, png
    units = units or {}
    metrics = [metrics] if isinstance(metrics, str) else list(metrics)
    ok = (frame["status"] == "ok").to_numpy()
    fig, axes = plt.subplots(len(metrics), 2, figsize=(11, 4.2 * len(metrics)), squeeze=False)
    found = study_summary(frame, specs, points) if specs else None
    for (left, right), metric in zip(axes, metrics):
        values = (pd.to_numeric(frame[metric], errors="coerce").to_numpy() if metric in frame
                  else np.full(len(frame), np.nan))
        left.hist(values[ok & np.isfinite(values)], bins=min(60, max(10, int(np.sqrt(ok.sum())))), color="C0",
                  alpha=0.8)
        drawn = [(spec, row) for spec, row in zip(specs, found["specs"] if found else ()) if spec.metric == metric]
        for spec, _ in drawn:
            left.axvline(spec.limit, color="C3", lw=1.5, ls="--", label=f"spec {spec.text()}")
        left.set_xlabel(metric)
        left.set_ylabel("samples")
        _engineering(left.xaxis, metric, units)
        if drawn:
            left.set_title("; ".join(f"{100 * row['fraction']:.2f} % meet {spec.text()}" for spec, row in drawn),
                           fontsize=9)
            left.legend(fontsize=8)
        correlations = {}
        for name in points.names:
            x = frame[name].to_numpy(dtype=float)
            sel = ok & np.isfinite(values)
            if sel.sum() > 2 and np.ptp(x[sel]) > 0 and np.ptp(values[sel]) > 0:
                correlations[name] = pd.Series(x[sel]).corr(pd.Series(values[sel]), method="spearman")
        if correlations:
            name = max(correlations, key=lambda k: abs(correlations[k]))
            right.plot(frame[name][ok], values[ok], ".", ms=3, alpha=0.5)
            right.set_xlabel(name)
            _engineering(right.xaxis, name, units)
            right.set_title(f"against the parameter it follows most (Spearman {correlations[name]:+.2f})", fontsize=9)
            for spec, _ in drawn:
                right.axhline(spec.limit, color="C3", lw=1.5, ls="--")
        right.set_ylabel(metric)
        _engineering(right.yaxis, metric, units)
    failed = int((~ok).sum())
    heading = f"{title}  ({len(frame)} samples, {failed} failed)"
    if found:
        heading += (f"\nyield {100 * found['yield']:.2f} % (every spec; 95 % CI {100 * found['yield_low']:.2f} to "
                    f"{100 * found['yield_high']:.2f} %)")
    fig.suptitle(heading, fontsize=10)
    fig.tight_layout()
    return png(fig)


def summary_plot(frame: pd.DataFrame, points, metric: str = "vout_mean", title: str = "", units=None) -> bytes:
    """``metric`` over the sweep: a line over one parameter, a map over a 2-D grid (failed points grey, the
    conduction-mode boundaries drawn over it), a scatter over the first two parameters otherwise; failed
    points marked; units on the axes where ``units`` ({column: unit}) gives them."""
    from .plots import plt, png
    units = units or {}
    names = points.names
    ok = frame["status"] == "ok"
    values = pd.to_numeric(frame[metric], errors="coerce") if metric in frame else pd.Series(np.nan, index=frame.index)
    if len(names) == 1:                                   # a grid or Latin-hypercube line, in order
        axis = points.axes[0]
        frame = frame.sort_values(names[0], kind="stable").reset_index(drop=True)
        ok = frame["status"] == "ok"
        values = pd.to_numeric(frame[metric], errors="coerce")
        fig, ax = plt.subplots(figsize=(7, 4))
        ax.plot(frame[names[0]][ok], values[ok], ".-", lw=1, ms=3, label=metric)
        if (~ok).any():
            low = np.nanmin(values[ok]) if ok.any() else 0.0
            ax.plot(frame[names[0]][~ok], np.full((~ok).sum(), low), "x", color="#c44e52", label="failed")
        for mode in sorted(set(frame["mode"][ok].dropna())) if "mode" in frame else []:
            sel = ok & (frame["mode"] == mode)
            ax.plot(frame[names[0]][sel], values[sel], "o", ms=4, alpha=0.5, label=f"mode {mode}")
        ax.set_xscale("log" if axis.log else "linear")
        ax.set_xlabel(_labelled(names[0], units))
        ax.set_ylabel(_labelled(metric, units))
        ax.ticklabel_format(axis="y", useOffset=False, style="plain")
        ax.legend(fontsize=8)
    elif points.kind == "grid" and len(names) == 2:
        shape = points.shape
        full = np.full(points.size, np.nan)
        full[frame["index"].to_numpy()[ok.to_numpy()]] = values[ok].to_numpy()
        grid = full.reshape(shape)
        xs, ys = points.axes[1].values(), points.axes[0].values()
        fig, ax = plt.subplots(figsize=(7, 5))
        ax.set_facecolor("#bbbbbb")                       # failed or missing points show through in grey
        mesh = ax.pcolormesh(xs, ys, np.ma.masked_invalid(grid), shading="nearest", cmap="viridis")
        fig.colorbar(mesh, ax=ax, label=_labelled(metric, units))
        if "mode" in frame and frame["mode"][ok].nunique() > 1:
            codes = {m: k for k, m in enumerate(sorted(frame["mode"][ok].unique()))}
            code = np.full(points.size, np.nan)
            code[frame["index"].to_numpy()[ok.to_numpy()]] = [codes[m] for m in frame["mode"][ok]]
            ax.contour(xs, ys, code.reshape(shape), levels=np.arange(len(codes) - 1) + 0.5, colors="white",
                       linewidths=1.2)
            where = np.unravel_index(np.arange(points.size), shape)
            for mode, k in codes.items():                 # each mode named at the middle of its region
                sel = code == k
                ax.text(np.median(xs[where[1][sel]]), np.median(ys[where[0][sel]]), mode, color="white",
                        ha="center", va="center", fontsize=9, weight="bold")
            ax.set_title("white lines: conduction-mode boundaries", fontsize=9)
        ax.set_xscale("log" if points.axes[1].log else "linear")
        ax.set_yscale("log" if points.axes[0].log else "linear")
        ax.set_xlabel(_labelled(names[1], units))
        ax.set_ylabel(_labelled(names[0], units))
    else:
        fig, ax = plt.subplots(figsize=(7, 5))
        second = names[1] if len(names) > 1 else names[0]
        sc = ax.scatter(frame[names[0]][ok], frame[second][ok], c=values[ok], s=12, cmap="viridis")
        fig.colorbar(sc, ax=ax, label=_labelled(metric, units))
        if (~ok).any():
            ax.plot(frame[names[0]][~ok], frame[second][~ok], "x", color="#c44e52", label="failed")
            ax.legend(fontsize=8)
        ax.set_xlabel(_labelled(names[0], units))
        ax.set_ylabel(_labelled(second, units))
    failed = int((~ok).sum())
    fig.suptitle(f"{title}  ({len(frame)} points, {failed} failed)", fontsize=10)
    return png(fig)


def write_summary(out, points, metrics="vout_mean", title: str = "", specs=(), units=None,
                  scope_metrics=None) -> pd.DataFrame:
    """The summary plot of a complete sweep, written atomically beside its parts: a tolerance study's histogram and
    scatter per metric (``metrics``: a name or several), or the (first) metric over the sweep's points; over one
    parameter also ``summary.html``, a scope of ``scope_metrics`` (default: the plotted ones) over it."""
    frame = load_sweep(out)
    first = metrics if isinstance(metrics, str) else metrics[0]
    figure = (tolerance_plot(frame, points, metrics, specs, units, title) if points.kind == "tolerance"
              else summary_plot(frame, points, first, title, units))
    files = {Path(out) / "summary.png": figure}
    if len(points.names) == 1 and points.kind != "tolerance" and len(frame) >= 2:
        # a line over one parameter: also as a scope (zoom, cursors: the metric's change between two points)
        from .scope import of_sweep, scope_files
        names = list(scope_metrics or ([metrics] if isinstance(metrics, str) else metrics))
        page = of_sweep(frame, points.names[0], names, units, points.axes[0].log, title or "sweep summary")
        files.update({Path(out) / name: data for name, data in scope_files(page, "summary.html").items()})
    atomic_write_files(files)
    return frame


__all__ = ["SweepStore", "SweepRun", "run_sweep", "load_sweep", "summary_plot", "write_summary",
           "describe"]
