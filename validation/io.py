"""Safe output: every file and every report directory appears whole or not at all, pcsuite never deletes or
moves anything it did not write, and a bad output path is refused with one line before a run starts.

- :func:`safe_name`: the one check for a value that becomes a file name (scene names, suite names, section
  files): 1-64 letters, digits, ``.``, ``_``, ``-``, starting with a letter or digit (never ``.``/``..``).
- :func:`check_output_file` (``--out F.csv``, ``--plot``, ``--diagram``, ...): a new file, or an existing regular
  file (replaced atomically: that is what an output option means), in a directory pcsuite can write. A
  directory, a device (``/dev/null``), a FIFO, a socket or a symbolic link is refused, and so is a parent that
  is missing or not a writable directory (``nodir/x.csv``, ``/proc``, ``/dev/full/x``). A path is shown as typed,
  or quoted as repr quotes it when it holds a character that does not print (a newline, an ESC).
- :func:`check_output_dir` (``pcsuite report --out``, ``gdcm-map --out``, ``bench --out``): a new or empty
  directory, or one holding nothing but an earlier output of the same command. A report directory carries
  :data:`MANIFEST` (every file it wrote, with sizes and SHA-256): it may be replaced only when it holds nothing
  else and nothing in it changed. Anything else (a user's directory, a file, a device, a symbolic link, the
  current directory or one of its ancestors, ``/``) is refused.
- :func:`atomic_write_bytes` and :func:`atomic_directory` apply the same checks again at write time (a long
  run gives time for things to change) and write through a temporary named ``.NAME.PID.XXXXXXXX.tmp`` beside the
  target; :func:`atomic_write_files` writes a set of files (gdcm-map's table and plot) that lands together. A
  file option's directory must exist: pcsuite does not create it. The writer holds an flock on its temporary;
  a temporary whose process is gone (``kill -9``) and which nobody holds is removed by the next write to the
  same target. Report swaps are serialised by an flock on the
  parent directory: concurrent reports into one directory each land whole, the last one stays.

The checks raise :class:`converters.errors.ParameterError` (one line, exit 2 on the command line) naming the
option (``--out``, ``--plot``, ...) when a command registered it by calling a ``check_*`` function first.
"""
from __future__ import annotations

import contextlib
import ctypes
import errno
import fcntl
import hashlib
import json
import os
import re
import shutil
import stat
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

from converters.errors import ParameterError
from converters.validate import quoted

#: The file a report directory carries: what pcsuite wrote there (relative path -> size and SHA-256).
MANIFEST = ".pcsuite-report.json"
#: A value that becomes a file name.
SAFE_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9._-]{0,63}")
#: Seconds a writer waits for another one's swap into the same directory.
LOCK_TIMEOUT = 120.0
_MANIFEST_MAX_BYTES = 16 << 20


def safe_name(what: str, value) -> str:
    """``value`` if it may be a file name (``SAFE_NAME``), else a one-line ParameterError naming ``what``."""
    if not (isinstance(value, str) and SAFE_NAME.fullmatch(value)):
        raise ParameterError(f"{what} must be 1-64 letters, digits, '.', '_' or '-', starting with a letter or digit "
                             f"(it becomes a file name); got {value!r}")
    return value


def umask() -> int:
    """The process's umask (read without changing it where Linux allows)."""
    try:
        with open("/proc/self/status") as status:
            for line in status:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except OSError:
        pass
    current = os.umask(0o022)
    os.umask(current)
    return current


# --- which option names a path (so that a write-time refusal names it too) ---------------------------------

@dataclass(frozen=True)
class _Output:
    flag: str | None
    shown: str
    kind: str = "file"              # "file", "report" or the name of a fixed-name directory output
    names: tuple = ()               # a fixed-name directory's files


_OUTPUTS: dict[str, _Output] = {}


def _key(path: Path) -> str:
    return os.path.abspath(path)


def _output(path: Path) -> _Output:
    return _OUTPUTS.get(_key(path)) or _Output(None, quoted(path))


def _label(output: _Output) -> str:
    return f"{output.flag} {output.shown}" if output.flag else output.shown


def _another(output: _Output) -> str:
    return f"another {output.flag}" if output.flag else "another path"


# --- file outputs --------------------------------------------------------------------------------------------

def check_output_file(flag: str, path) -> None:
    """Refuse, before a run, an output file pcsuite could not or must not write (module docstring); remember
    ``flag`` so that the write names it too. ``None`` (option not given) passes."""
    if path is None:
        return
    path = Path(path)
    output = _Output(flag, quoted(path))
    _OUTPUTS[_key(path)] = output
    _check_file(path, output)
    _check_parent(path, output, exists=True)


def check_output_parent(flag: str, path) -> None:
    """Refuse, before a run, an output whose parent is not a directory pcsuite can write in (for an output that
    checks the rest itself: the sweep store). ``None`` passes."""
    if path is not None:
        _check_parent(Path(path), _Output(flag, quoted(path)))


def _kind(mode: int) -> str:
    for test, name in ((stat.S_ISDIR, "an existing directory"), (stat.S_ISCHR, "a character device"),
                       (stat.S_ISBLK, "a block device"), (stat.S_ISFIFO, "a FIFO (named pipe)"),
                       (stat.S_ISSOCK, "a socket"), (stat.S_ISLNK, "a symbolic link")):
        if test(mode):
            return name
    return "not a regular file"


def _check_file(path: Path, output: _Output) -> None:
    if path.name.strip(".") == "" and len(path.name) <= 2:      # "", "." or ".."
        raise ParameterError(f"{_label(output)}: must end in a file name; choose {_another(output)}")
    try:
        mode = os.lstat(path).st_mode
    except FileNotFoundError:
        return
    except OSError as exc:       # a parent that is a file (ENOTDIR), a parent not searchable (EACCES)
        if exc.errno == errno.ENOTDIR:
            return               # _check_parent names the parent
        raise ParameterError(f"{_label(output)}: cannot inspect it ({exc.strerror})") from None
    if not stat.S_ISREG(mode):
        what = _kind(mode)
        hint = "; give the file's own path or" if stat.S_ISLNK(mode) else ", not a regular file;"
        raise ParameterError(f"{_label(output)}: {what}{hint} choose {_another(output)}")


def _check_parent(path: Path, output: _Output, probe: bool = True, exists: bool = False) -> None:
    """The nearest existing ancestor of ``path`` must be a directory pcsuite can create files in; with ``exists``
    (a file option) that must be its own directory: a file is written where it is named, and a missing directory
    is a typo more often than a wish (pcsuite does not create it)."""
    parent, mode = path.parent, None
    while mode is None:
        try:
            mode = os.stat(parent).st_mode
        except OSError as exc:
            if exc.errno not in (errno.ENOENT, errno.ENOTDIR):
                raise ParameterError(f"{_label(output)}: cannot write in {quoted(parent)} ({exc.strerror})") from None
            if parent == parent.parent:
                raise ParameterError(f"{_label(output)}: cannot write in {quoted(parent)} ({exc.strerror})") from None
            parent = parent.parent
    if not stat.S_ISDIR(mode):
        raise ParameterError(f"{_label(output)}: cannot write in {quoted(parent)} (not a directory)")
    if exists and parent != path.parent:
        raise ParameterError(f"{_label(output)}: its directory {quoted(path.parent)} does not exist; create it or "
                             f"choose {_another(output)}")
    if probe:
        _probe(parent, output)


def _probe(directory: Path, output: _Output) -> None:
    """Create and remove a file in ``directory`` (root passes every permission test; /proc refuses new files)."""
    try:
        fd, name = tempfile.mkstemp(prefix=f".pcsuite-probe.{os.getpid()}.", suffix=".tmp", dir=directory)
    except OSError as exc:
        raise ParameterError(f"{_label(output)}: cannot write in {quoted(directory)} "
                             f"(creating a file there fails: {exc.strerror})") from None
    os.close(fd)
    with contextlib.suppress(OSError):
        os.unlink(name)


def parquet_bytes(frame, metadata: bytes | None = None) -> bytes:
    """A table as Parquet bytes, as pcsuite writes every waveform (``simulate --out``, a report's scenes): zstd, the
    float columns byte-stream-split (sampled waveforms compress to about half of Parquet's default, snappy: 131 MB
    against 67 MB for the hysteretic buck's two runs), ``mode`` as text; ``metadata`` under the schema key
    ``pcsuite``."""
    import io

    import pyarrow as pa
    import pyarrow.parquet as pq
    if "mode" in frame:
        frame = frame.assign(mode=frame["mode"].astype(str))
    table = pa.Table.from_pandas(frame, preserve_index=False)
    if metadata is not None:
        table = table.replace_schema_metadata({**(table.schema.metadata or {}), b"pcsuite": metadata})
    floats = [field.name for field in table.schema if pa.types.is_floating(field.type)]
    others = [name for name in table.schema.names if name not in floats]      # a dictionary would take precedence
    buffer = io.BytesIO()
    pq.write_table(table, buffer, compression="zstd", use_dictionary=others or False,
                   use_byte_stream_split=floats or False)
    return buffer.getvalue()


def atomic_write_bytes(path, data: bytes) -> Path:
    """Write ``data`` to a temporary file beside ``path`` (named with this process's id, flocked while written),
    then rename it into place (mode 0666 & ~umask). The target must be a new or regular file in an existing,
    writable directory (checked again here); stale temporaries of dead writers to the same target are removed
    first."""
    atomic_write_files({path: data})
    return Path(path)


def atomic_write_files(files: dict) -> list[Path]:
    """Write several files (path -> bytes, or a function writing them into a binary handle: :func:`_stage`) so
    that they land together: every one is written to its temporary
    first (:func:`atomic_write_bytes`), and only when all are written in full are they renamed into place. A
    failure while writing (a full disk) leaves every target as it was: the earlier set, or none of the new
    files; a rename that fails puts back the files already replaced."""
    targets = [(Path(path), data) for path, data in files.items()]
    for path, _ in targets:
        _check_target(path)
    staged: list[tuple[Path, str, int]] = []
    try:
        for path, data in targets:
            staged.append(_stage(path, data))
        for path, _, _ in staged:
            _check_file(path, _output(path))                     # still not a directory, device, link...
        _replace_all([(tmp, path) for path, tmp, _ in staged])
    finally:
        for _, tmp, fd in staged:
            with contextlib.suppress(FileNotFoundError):
                os.unlink(tmp)                                   # left only when not renamed into place
            os.close(fd)
    return [path for path, _ in targets]


def _check_target(path: Path) -> None:
    output = _output(path)
    _check_file(path, output)
    guard = _OUTPUTS.get(_key(path.parent))
    if guard is not None and guard.names:       # a file of a fixed-name directory output (gdcm-map, bench)
        if path.name not in guard.names:
            raise ParameterError(f"{_label(guard)}: {path.name} is not one of its files ({', '.join(guard.names)})")
        _check_dir(path.parent, guard)
    _check_parent(path, output, probe=False, exists=True)      # a failing mkstemp says why
    _remove_stale(path.parent, path.name)


def _failed(path: Path, exc: OSError) -> ParameterError:
    """A write that failed, named by its option: a file option's, or its directory option's (gdcm-map, bench)."""
    guard = _OUTPUTS.get(_key(path.parent))
    if _key(path) not in _OUTPUTS and guard is not None and guard.names:
        return ParameterError(f"{_label(guard)}: cannot write {quoted(path.name)} ({exc.strerror or exc})")
    return ParameterError(f"{_label(_output(path))}: cannot write it ({exc.strerror or exc})")


def _stage(path: Path, data) -> tuple[Path, str, int]:
    """``data`` in full in a flocked temporary beside ``path``: (path, temporary, its open descriptor). ``data``:
    bytes, or a function that writes them into the binary handle it is given (a waveform's CSV, streamed: built
    whole as text and then as bytes it had taken 2.4 GB for 1.3 M rows)."""
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.{os.getpid()}.", suffix=".tmp", dir=path.parent)
    except OSError as exc:
        raise ParameterError(f"{_label(_output(path))}: cannot write in {quoted(path.parent)} "
                             f"({exc.strerror})") from None
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)
        with os.fdopen(fd, "wb", closefd=False) as handle:
            if callable(data):
                data(handle)
            else:
                handle.write(data)
            handle.flush()
            os.fsync(handle.fileno())
        os.chmod(tmp, 0o666 & ~umask())
    except BaseException as exc:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        os.close(fd)
        if isinstance(exc, OSError):
            raise _failed(path, exc) from None
        raise
    return path, tmp, fd


def _replace_all(moves: list[tuple[str, Path]]) -> None:
    """Rename each temporary onto its target; if one rename fails, the targets already replaced get their earlier
    content back (kept as hard links until every rename is done)."""
    import uuid
    kept: list[tuple[Path, str | None]] = []        # (target, its earlier content's link, or None: it was new)
    try:
        for tmp, path in moves:
            earlier = None
            if len(moves) > 1 and os.path.lexists(path):      # named as a temporary: a kill leaves a stale one
                earlier = str(path.parent / f".{path.name}.{os.getpid()}.{uuid.uuid4().hex[:8]}.tmp")
                os.link(path, earlier)
            try:
                os.replace(tmp, path)
            except OSError:
                if earlier:
                    os.unlink(earlier)
                raise
            kept.append((path, earlier))
    except OSError as exc:
        for path, earlier in reversed(kept):
            with contextlib.suppress(OSError):
                os.replace(earlier, path) if earlier else os.unlink(path)
        raise _failed(moves[len(kept)][1], exc) from None
    finally:
        for _, earlier in kept:
            if earlier:
                with contextlib.suppress(FileNotFoundError):
                    os.unlink(earlier)


def atomic_write_text(path, text: str) -> Path:
    return atomic_write_bytes(path, text.encode("utf-8"))


def _make_parent(path: Path, output: _Output) -> None:
    _check_parent(path, output, probe=False)          # a failing mkstemp says why
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ParameterError(f"{_label(output)}: cannot create {quoted(path.parent)} ({exc.strerror})") from None


# --- leftovers of dead writers -------------------------------------------------------------------------------

def _temp_pattern(name: str) -> re.Pattern:
    """Temporaries of target ``name``: .NAME.PID.XXXXXXXX.tmp (mkstemp/mkdtemp's random part has no dot)."""
    return re.compile(rf"\.{re.escape(name)}\.(\d+)\.[a-z0-9_]+\.tmp")


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OverflowError):
        return True
    return True


def _remove_stale(directory: Path, name: str) -> list[str]:
    """Remove the temporaries (files and staging directories) of target ``name`` in ``directory`` whose writer
    is dead: its pid is gone and nobody holds the temporary's flock. Returns the names removed."""
    pattern = _temp_pattern(name)
    removed = []
    try:
        entries = list(os.scandir(directory))
    except OSError:
        return removed
    for entry in entries:
        match = pattern.fullmatch(entry.name)
        if not match or int(match.group(1)) == os.getpid() or _alive(int(match.group(1))):
            continue
        is_dir = entry.is_dir(follow_symlinks=False)
        try:
            fd = os.open(entry.path, os.O_RDONLY | (os.O_DIRECTORY if is_dir else 0) | os.O_NOFOLLOW)
        except OSError:
            continue
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)     # held: a live writer (another pid namespace)
            if is_dir:
                shutil.rmtree(entry.path, ignore_errors=True)
            else:
                os.unlink(entry.path)
            removed.append(entry.name)
        except OSError:
            pass
        finally:
            os.close(fd)
    return removed


def _lock_fd(fd: int, what: str) -> None:
    """flock ``fd`` exclusively, waiting at most LOCK_TIMEOUT s."""
    deadline = time.monotonic() + LOCK_TIMEOUT
    while True:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            return
        except BlockingIOError:
            if time.monotonic() > deadline:
                raise ParameterError(f"{what}: another pcsuite process has held its lock for {LOCK_TIMEOUT:.0f} s; "
                                     "wait for it to finish or choose another output") from None
            time.sleep(0.005)


@contextlib.contextmanager
def _locked(directory: Path, what: str):
    """An exclusive flock on ``directory`` (none where it cannot be opened: a directory without read permission)."""
    try:
        fd = os.open(directory, os.O_RDONLY | os.O_DIRECTORY)
    except PermissionError:
        yield
        return
    try:
        _lock_fd(fd, what)
        yield
    finally:
        os.close(fd)


# --- directory outputs ---------------------------------------------------------------------------------------

def check_output_dir(flag: str | None, path, kind: str = "report", names: tuple = ()) -> None:
    """Refuse, before a run, a directory output pcsuite must not write (module docstring). ``kind`` "report":
    the directory is replaced whole and carries a manifest; otherwise ``names`` are the only files the command
    writes into it (an earlier output of it holds nothing else)."""
    if path is None:
        return
    path = Path(path)
    output = _Output(flag, quoted(path), kind, tuple(names))
    _OUTPUTS[_key(path)] = output
    _check_dir_locked(path, output)


def _check_dir_locked(path: Path, output: _Output) -> None:
    """:func:`_check_dir` while no other pcsuite writer swaps a report beside ``path`` (whose files would change
    under the check) or writes into a fixed-name directory ``path``."""
    where = path.parent if output.kind == "report" else path
    if not os.path.isdir(where) or (output.kind != "report" and os.path.islink(where)):
        _check_dir(path, output)
        return
    with _locked(where, _label(output)):
        _check_dir(path, output)


def _check_dir(path: Path, output: _Output) -> None:
    label = _label(output)
    real, cwd = Path(os.path.realpath(path)), Path(os.path.realpath(os.getcwd()))
    if real == cwd or real in cwd.parents:
        raise ParameterError(f"{label}: names the current directory or one of its ancestors; choose a new or "
                             "empty directory")
    if path.name.strip(".") == "" and len(path.name) <= 2:      # "", "." or ".."
        raise ParameterError(f"{label}: must end in a directory's own name (not . or ..); choose {_another(output)}")
    try:
        mode = os.lstat(path).st_mode
    except FileNotFoundError:
        mode = None
    except OSError as exc:
        if exc.errno != errno.ENOTDIR:
            raise ParameterError(f"{label}: cannot inspect it ({exc.strerror})") from None
        mode = None
    if mode is None:
        _check_parent(path, output)
        return
    if stat.S_ISLNK(mode):
        raise ParameterError(f"{label}: a symbolic link; give the directory's own path or choose {_another(output)}")
    if not stat.S_ISDIR(mode):
        what = "an existing file" if stat.S_ISREG(mode) else _kind(mode)
        raise ParameterError(f"{label}: {what}, not a directory; choose {_another(output)}")
    if output.kind == "report" and os.path.ismount(path):
        raise ParameterError(f"{label}: a mount point (it cannot be replaced); choose a directory inside it")
    problem = _foreign(path, output)
    if problem:
        raise ParameterError(f"{label}: {problem}; choose {_another(output)} or remove it")
    _probe(path.parent if output.kind == "report" else path, output)


def _foreign(path: Path, output: _Output) -> str:
    """Why directory ``path`` is not replaceable by this output ("" when it is: empty, or an earlier output)."""
    try:
        entries = sorted(os.listdir(path))
    except OSError as exc:
        return f"it cannot be listed ({exc.strerror})"
    if not entries:
        return ""
    if output.kind != "report":
        temps = [_temp_pattern(name) for name in output.names] + [_temp_pattern("pcsuite-probe")]
        for entry in entries:
            full = path / entry
            if entry in output.names and full.is_file() and not full.is_symlink():
                continue
            if any(p.fullmatch(entry) for p in temps):
                continue
            return (f"an existing directory that is not a pcsuite {output.kind} output (it holds "
                    f"{entry}{'/' if full.is_dir() and not full.is_symlink() else ''})")
        return ""
    return _foreign_report(path)


def _foreign_report(path: Path) -> str:
    try:
        return _foreign_report_files(path)
    except OSError as exc:
        return f"a file in it cannot be read ({exc.strerror}: {exc.filename})"


def _foreign_report_files(path: Path) -> str:
    manifest = path / MANIFEST
    if not manifest.is_file() or manifest.is_symlink():
        if _legacy_report(path):
            return (f"a report written by an older pcsuite (no {MANIFEST}), whose files cannot be told apart from "
                    "files added to it")
        extra = sorted(os.listdir(path))[0]
        slash = "/" if (path / extra).is_dir() and not (path / extra).is_symlink() else ""
        return f"an existing directory that is not a pcsuite report (it holds {extra}{slash})"
    files = _read_manifest(manifest)
    if files is None:
        return f"an existing directory whose {MANIFEST} is not a pcsuite manifest"
    folders = {parent for name in files for parent in Path(name).parents if str(parent) != "."}
    unlisted = []
    for root, dirs, names in os.walk(path, onerror=unlisted.append):
        rel = Path(root).relative_to(path)
        for name in sorted(dirs):
            entry = rel / name
            if (Path(root) / name).is_symlink() or entry not in folders:
                return f"an existing directory that is not only a pcsuite report (it holds {entry.as_posix()}/)"
        for name in sorted(names):
            entry = (rel / name).as_posix()
            if entry == MANIFEST:
                continue
            full = Path(root) / name
            if entry not in files or full.is_symlink() or not full.is_file():
                return f"an existing directory that is not only a pcsuite report (it holds {entry})"
            if full.stat().st_size != files[entry]["size"] or _sha256(full) != files[entry]["sha256"]:
                return f"a pcsuite report whose {entry} was changed after pcsuite wrote it"
    if unlisted:
        return f"a directory in it cannot be listed ({unlisted[0].strerror}: {unlisted[0].filename})"
    return ""


def _legacy_report(path: Path) -> bool:
    """A report of a pcsuite without manifests: index.html, summary.csv and metrics.json with suite and sections."""
    try:
        metrics = json.loads((path / "metrics.json").read_text())
    except (OSError, ValueError):
        return False
    return (isinstance(metrics, dict) and {"suite", "sections"} <= set(metrics)
            and (path / "index.html").is_file() and (path / "summary.csv").is_file())


def _read_manifest(manifest: Path) -> dict | None:
    try:
        if manifest.stat().st_size > _MANIFEST_MAX_BYTES:
            return None
        data = json.loads(manifest.read_text())
    except (OSError, ValueError):
        return None
    if not (isinstance(data, dict) and data.get("pcsuite") == "report" and isinstance(data.get("files"), dict)):
        return None
    files = data["files"]
    if not all(isinstance(v, dict) and isinstance(v.get("size"), int) and isinstance(v.get("sha256"), str)
               for v in files.values()):
        return None
    return files


def _sha256(path: Path) -> str:
    digest = hashlib.sha256()
    with open(path, "rb") as handle:
        for block in iter(lambda: handle.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def _write_manifest(staging: Path, extra: dict) -> None:
    files = {}
    for root, dirs, names in os.walk(staging):
        for name in dirs + names:
            full = Path(root) / name
            if full.is_symlink() or not (full.is_dir() or full.is_file()):
                raise ParameterError(f"{full.relative_to(staging)}: a report holds regular files and directories only")
        for name in names:
            full = Path(root) / name
            files[full.relative_to(staging).as_posix()] = {"size": full.stat().st_size, "sha256": _sha256(full)}
    files.pop(MANIFEST, None)
    text = json.dumps({"pcsuite": "report", "version": 1, **extra, "files": dict(sorted(files.items()))}, indent=1)
    (staging / MANIFEST).write_text(text + "\n")


@contextlib.contextmanager
def atomic_directory(target, manifest: dict | None = None):
    """Yield a temporary directory beside ``target``; on success it replaces ``target`` whole (with a manifest of
    every file written), on failure it is removed.

    ``target`` must be new, an empty directory or an earlier pcsuite report that holds nothing else (checked
    before and, under an flock on the parent directory, again at the swap). The swap exchanges the two
    directories in one step (Linux renameat2 RENAME_EXCHANGE) where the file system allows: a reader sees the
    old report or the new one, never a mix or none. ``manifest``: extra keys for the manifest (the suite)."""
    target = Path(target)
    output = _output(target)
    output = _Output(output.flag, output.shown, "report")
    _check_dir_locked(target, output)
    _make_parent(target, output)
    parent = target.parent
    _remove_stale(parent, target.name)
    try:
        staging = Path(tempfile.mkdtemp(prefix=f".{target.name}.{os.getpid()}.", suffix=".tmp", dir=parent))
    except OSError as exc:
        raise ParameterError(f"{_label(output)}: cannot write in {quoted(parent)} ({exc.strerror})") from None
    hold = os.open(staging, os.O_RDONLY | os.O_DIRECTORY)
    try:
        fcntl.flock(hold, fcntl.LOCK_EX)               # a live writer's staging is never taken for a leftover
        os.chmod(staging, 0o777 & ~umask())
        yield staging
        _write_manifest(staging, manifest or {})
        with _locked(parent, _label(output)):
            _check_dir(target, output)                # again: a long run gives time for changes
            _swap(staging, target, output)
    except OSError as exc:
        if isinstance(exc, ParameterError):
            raise
        raise ParameterError(f"{_label(output)}: cannot write the report ({exc.strerror or exc})") from None
    finally:
        shutil.rmtree(staging, ignore_errors=True)     # the new tree on failure, the old one after a swap
        os.close(hold)


_RENAME_NOREPLACE, _RENAME_EXCHANGE = 1, 2


def _renameat2(source: Path, target: Path, flags: int) -> bool:
    """Linux renameat2; False when unavailable (no symbol, or EINVAL/ENOSYS: the file system lacks the flag)."""
    try:
        call = ctypes.CDLL(None, use_errno=True).renameat2
    except (AttributeError, OSError):
        return False
    at_fdcwd = -100
    if call(at_fdcwd, os.fsencode(source), at_fdcwd, os.fsencode(target), flags) == 0:
        return True
    code = ctypes.get_errno()
    if code in (errno.EINVAL, errno.ENOSYS, errno.ENOTSUP):
        return False
    raise OSError(code, os.strerror(code), str(target))


def _swap(staging: Path, target: Path, output: _Output) -> None:
    """Put ``staging`` at ``target``; the old target (an empty directory or an earlier report, just checked) ends
    at ``staging``'s path, which the caller removes."""
    if not os.path.lexists(target):
        if not _renameat2(staging, target, _RENAME_NOREPLACE):
            os.rename(staging, target)
        return
    if _renameat2(staging, target, _RENAME_EXCHANGE):
        if _foreign(staging, output):           # something was added in the instant between check and swap
            _renameat2(staging, target, _RENAME_EXCHANGE)
            raise ParameterError(f"{_label(output)}: changed while the report was written; choose {_another(output)}")
        return
    aside = Path(tempfile.mkdtemp(prefix=f".{target.name}.{os.getpid()}.", suffix=".tmp", dir=target.parent))
    os.rmdir(aside)
    os.rename(target, aside)
    os.rename(staging, target)
    os.rename(aside, staging)


@contextlib.contextmanager
def locked_output_dir(path, kind: str, names: tuple):
    """Check a fixed-name directory output (``names`` only), create it, and hold an flock on it while the
    caller writes its files: two writers of one such directory take turns."""
    path = Path(path)
    known = _output(path)
    output = _Output(known.flag, known.shown, kind, tuple(names))
    _OUTPUTS[_key(path)] = output
    _check_dir(path, output)
    made = [folder for folder in (path, *path.parents) if not os.path.lexists(folder)]
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ParameterError(f"{_label(output)}: cannot create it ({exc.strerror})") from None
    try:
        with _locked(path, _label(output)):
            _check_dir(path, output)
            yield path
    except BaseException:
        for folder in made:                 # the directories made for a write that failed, when still empty
            with contextlib.suppress(OSError):
                os.rmdir(folder)
        raise
