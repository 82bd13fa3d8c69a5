"""``pcsuite sweep``: a Parquet dataset written in parts, resumed after an interruption with only the missing
points computed, a directory never overwritten, failures stored as rows, bad input refused in one line."""
import json
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from validation.cli import main
from validation.sweep import load_sweep

SWEEP = ["sweep", "buck", "--grid", "D=0.2:0.8:100", "--grid", "R=2:40:100", "--steady", "--no-progress"]
CHILD = ("import signal, sys; signal.signal(signal.SIGINT, signal.default_int_handler); "
         "from validation.cli import main; sys.exit(main(sys.argv[1:]))")


def _summary(capsys) -> dict:
    return json.loads(capsys.readouterr().out.strip().splitlines()[-1])


def _same(a: pd.DataFrame, b: pd.DataFrame):
    assert list(a["index"]) == list(b["index"]) == list(range(len(a)))
    for column in ("D", "R", "status", "message", "mode", "iterations"):
        assert (a[column] == b[column]).all(), column
    numeric = ["vout_mean", "vout_ripple", "rms_state0", "held_fraction", "spectral_radius"]
    np.testing.assert_allclose(b[numeric].to_numpy(float), a[numeric].to_numpy(float), rtol=1e-12, atol=1e-12)


def _running(pid: str) -> bool:
    """Alive and not a zombie (a dead orphan waits for init to reap it)."""
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


@pytest.fixture(scope="module")
def uninterrupted(tmp_path_factory):
    out = tmp_path_factory.mktemp("whole") / "sweep"
    assert main(SWEEP + ["--scheduler", "batched", "--out", str(out)]) == 0
    return load_sweep(out)


@pytest.mark.parametrize("stop", ["SIGINT", "SIGKILL"])
@pytest.mark.slow
def test_an_interrupted_sweep_resumes_computing_only_the_missing_points(stop, tmp_path, capsys, uninterrupted):
    out = tmp_path / "sweep"
    child = subprocess.Popen([sys.executable, "-c", CHILD, *SWEEP, "--workers", "1", "--chunk", "250",
                              "--out", str(out)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 120
    while len(list((out / "parts").glob("*.parquet"))) < 2:           # two chunks stored, 38 to go
        assert child.poll() is None and time.monotonic() < deadline, child.communicate()
        time.sleep(0.02)
    workers = subprocess.run(["pgrep", "-P", str(child.pid)], capture_output=True, text=True).stdout.split()
    child.send_signal(getattr(signal, stop))
    _, err = child.communicate(timeout=60)
    stored = len(load_sweep(out))
    if stop == "SIGINT":
        assert child.returncode == 130
        assert f"interrupted: {stored:,} of 10,000 points are stored" in err and "Traceback" not in err
    else:
        assert child.returncode == -signal.SIGKILL
        time.sleep(1.0)                                                  # workers notice within 0.2 s
        assert workers and not [w for w in workers if _running(w)], "orphaned workers"
    assert 500 <= stored < 10_000 and stored % 250 == 0                  # whole parts only

    assert main(SWEEP + ["--out", str(out), "--json"]) == 0
    summary = _summary(capsys)
    assert summary["stored_before"] == stored
    assert summary["computed"] == 10_000 - stored                       # only the missing points
    assert summary["ok"] == 10_000 and summary["failed"] == 0
    resumed = load_sweep(out)
    _same(uninterrupted, resumed)                                        # as if never interrupted
    assert (out / "summary.png").read_bytes()[:4] == b"\x89PNG"

    assert main(SWEEP + ["--out", str(out), "--json"]) == 0             # complete: nothing to do
    assert _summary(capsys)["computed"] == 0


def test_a_directory_holding_another_sweep_or_other_files_is_refused_and_left_alone(tmp_path, capsys):
    out = tmp_path / "s"
    small = ["sweep", "buck", "--grid", "D=0.3:0.6:4", "--steady", "--no-progress", "--out", str(out)]
    assert main(small) == 0
    before = {p: p.read_bytes() for p in out.rglob("*") if p.is_file()}
    capsys.readouterr()
    assert main(small[:3] + ["D=0.3:0.6:5"] + small[4:]) == 2
    err = capsys.readouterr().err
    assert "holds a different sweep" in err and "D=0.3:0.6:4" in err and "nothing was changed" in err
    assert {p: p.read_bytes() for p in out.rglob("*") if p.is_file()} == before

    other = tmp_path / "mine"
    other.mkdir()
    (other / "thesis.tex").write_text("precious")
    assert main(small[:-1] + [str(other)]) == 2
    assert "non-empty directory that holds no sweep" in capsys.readouterr().err
    assert sorted(p.name for p in other.iterdir()) == ["thesis.tex"]


def test_a_symlinked_out_is_refused_as_on_every_other_command(tmp_path, capsys):
    (tmp_path / "real").mkdir()
    (tmp_path / "link").symlink_to("real")
    assert main(["sweep", "buck", "--grid", "D=0.3:0.6:3", "--no-progress", "--out", str(tmp_path / "link")]) == 2
    err = capsys.readouterr().err.strip()
    assert err == (f"pcsuite: error: --out {tmp_path}/link: a symbolic link; give the directory's own path or choose "
                   "another --out")
    assert list((tmp_path / "real").iterdir()) == []


def test_a_dask_scheduler_that_does_not_answer_leaves_no_sweep_directory(tmp_path, capsys, monkeypatch):
    from converters.errors import ParameterError
    from converters.parallel.cluster import DaskBackend
    asked = []

    def no_answer(self):
        asked.append(self.scheduler)
        raise ParameterError(f"scheduler: no Dask scheduler answers at {self.scheduler} (refused)")
    monkeypatch.setattr(DaskBackend, "client", no_answer)
    out = tmp_path / "s"
    assert main(["sweep", "buck", "--grid", "D=0.3:0.6:3", "--no-progress", "--scheduler", "tcp://127.0.0.1:9",
                 "--out", str(out)]) == 2
    assert asked == ["tcp://127.0.0.1:9"]
    assert "no Dask scheduler answers at tcp://127.0.0.1:9" in capsys.readouterr().err
    assert not out.exists()                                 # was: sweep.json written before the first chunk


def test_a_scheduler_address_where_something_else_answers_gets_one_line(tmp_path, capsys):
    # an HTTP server on the port: dask read its bytes as frame sizes, tried to allocate 3 EiB and crashed
    import socket
    import threading
    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen(4)

    def answer():
        while True:
            try:
                conn, _ = server.accept()
            except OSError:
                return
            with conn:
                conn.sendall(b"HTTP/1.1 200 OK\r\nContent-Length: 5\r\n\r\nhello" * 100)
    threading.Thread(target=answer, daemon=True).start()
    address = f"tcp://127.0.0.1:{server.getsockname()[1]}"
    out = tmp_path / "s"
    try:
        code = main(["sweep", "buck", "--grid", "D=0.3:0.6:3", "--no-progress", "--scheduler", address, "--out", str(out)])
    finally:
        server.close()
    err = capsys.readouterr().err
    assert code == 2 and len(err.strip().splitlines()) == 1, err
    assert err.startswith(f"pcsuite: error: scheduler: what answers at {address} is not a Dask scheduler (")
    assert not out.exists()


def test_a_second_writer_is_refused_while_the_first_holds_the_sweep(tmp_path, capsys):
    import fcntl
    out = tmp_path / "s"
    small = ["sweep", "buck", "--grid", "D=0.3:0.6:4", "--steady", "--no-progress", "--out", str(out)]
    assert main(small) == 0
    with open(out / ".lock", "a+") as held:
        fcntl.flock(held, fcntl.LOCK_EX | fcntl.LOCK_NB)
        assert main(small) == 2
    assert "another process is writing this sweep" in capsys.readouterr().err


@pytest.mark.parametrize("args, words", [
    (["--grid", "D=0.2:1.5:5"], ["D", "1.5"]),
    (["--grid", "D=0.2:0.5"], ["NAME=START:STOP:COUNT", "D=0.2:0.5"]),
    (["--grid", "D=0.2:0.5:3", "-p", "D=0.4"], ["D is both swept"]),
    (["--grid", "D=0.2:0.5:3", "--scheduler", "ftp://x"], ["scheduler", "ftp://x"]),
    (["--grid", "D=0.2:0.5:3", "--metric", "mode"], ["--metric", "vout_mean"]),
    (["--grid", "D=0.2:0.5:3", "--workers", "0"], ["--workers", "0"]),
    (["--grid", "D=1e9:2e9:3:log"], ["D"]),
    # a load step would be ignored (each point is the circuit before it): refused, in the base or on the grid
    (["--grid", "D=0.2:0.5:3", "-p", "t_step=1m", "-p", "R_step=5"], ["t_step, R_step", "not a step response"]),
    (["--grid", "t_step=1m:2m:2", "-p", "R_step=5"], ["R_step", "not a step response"]),
    (["--grid", "R_step=1:10:2", "--grid", "t_step=1m:2m:2"], ["R_step", "not a step response"]),
])
def test_bad_input_is_one_line_naming_the_parameter_and_nothing_is_written(args, words, tmp_path, capsys):
    out = tmp_path / "never"
    assert main(["sweep", "buck", *args, "--out", str(out), "--no-progress"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "Traceback" not in err
    for word in words:
        assert word in err
    assert not out.exists()


def test_a_lhs_sweep_stores_n_points_inside_the_ranges(tmp_path, capsys):
    out = tmp_path / "lhs"
    assert main(["sweep", "buck", "--grid", "D=0.2:0.8", "--grid", "R=2:40:log", "--lhs", "64", "--steady",
                 "--no-progress", "--out", str(out), "--json"]) == 0
    frame = load_sweep(out)
    assert len(frame) == 64 and (frame["status"] == "ok").all()
    assert frame["D"].between(0.2, 0.8).all() and frame["R"].between(2, 40).all()
    assert _summary(capsys)["ok"] == 64


def test_an_ngspice_sweep_runs_in_workers_and_a_failed_run_is_a_row(ngspice, tmp_path, monkeypatch):
    """Two buck points in ngspice started on the LCP orbit, through the same ModelSweep as every method: the same
    vout as the LCP sweep to 0.5 %; a failing run (ngspice's own error, forced at one point) is a row with its
    message."""
    from converters.parallel import run_ensemble
    from converters.sweeps import Axis, Grid, ModelSweep
    from validation import spice
    grid = Grid([Axis.parse("D=0.3:0.8:2"), Axis.parse("R=3:3:1")])   # K = 2L/RT = 1/3: DCM, CCM
    lcp = pd.DataFrame(run_ensemble(ModelSweep("buck"), grid, backend="serial")).set_index("index")
    rows = pd.DataFrame(run_ensemble(ModelSweep("buck", method="spice", periods=4), grid, backend="local", workers=2, chunk=1))
    rows = rows.set_index("index").sort_index()
    assert (rows["status"] == "ok").all(), rows["message"].tolist()
    np.testing.assert_allclose(rows["vout_mean"], lcp["vout_mean"], rtol=5e-3)
    assert (rows["settle"] < 1e-3).all() and (rows["spice_steps"] > 0).all()
    assert list(rows["mode"]) == list(lcp["mode"]) == ["DCM", "CCM"]

    real, calls = spice.run_spice, []

    def first_run_fails(netlist):                       # the first point's run fails as ngspice fails
        calls.append(netlist.converter)
        if len(calls) == 1:
            raise spice.SpiceError(f"ngspice failed on {netlist.converter}: doAnalyses: TRAN:  Timestep too small")
        return real(netlist)
    monkeypatch.setattr(spice, "run_spice", first_run_fails)
    mixed = run_ensemble(ModelSweep("buck", method="spice", periods=4), grid, backend="serial")
    assert [r["status"] for r in mixed] == ["failed", "ok"]
    assert mixed[0]["message"] == "SpiceError: ngspice failed on buck: doAnalyses: TRAN:  Timestep too small"
    assert mixed[0]["D"] == 0.3 and np.isnan(mixed[0].get("vout_mean", np.nan))
    assert mixed[1]["vout_mean"] == pytest.approx(rows.loc[1, "vout_mean"], rel=1e-9)


@pytest.mark.slow
def test_a_sweep_on_a_dask_scheduler_address_stores_the_local_rows(tmp_path, capsys):
    """--scheduler tcp://HOST:PORT: the same dataset as the local backend (a 2-worker LocalCluster here)."""
    import distributed
    small = ["sweep", "buck", "--grid", "D=0.2:0.8:10", "--grid", "R=2:40:10", "--steady", "--no-progress",
             "--chunk", "17"]
    assert main(small + ["--out", str(tmp_path / "local")]) == 0
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        assert main(small + ["--scheduler", cluster.scheduler_address, "--out", str(tmp_path / "dask"), "--json"]) == 0
    summary = _summary(capsys)
    assert summary["computed"] == 100 and summary["ok"] == 100
    _same(load_sweep(tmp_path / "local"), load_sweep(tmp_path / "dask"))


# --- resume verifies what it finds (issue 33) -------------------------------------------------------------------

SMALL = ["sweep", "buck", "--grid", "D=0.3:0.6:2", "--grid", "R=5:10:2", "--steady", "--no-progress", "--chunk", "2",
         "--scheduler", "batched"]


def _files(root: Path) -> dict:
    """Every entry under ``root`` (relative path -> bytes, link target or kind), to show nothing changed."""
    import os
    import stat
    out = {}
    for path in sorted(root.rglob("*")):
        mode = os.lstat(path).st_mode
        out[path.relative_to(root).as_posix()] = (os.readlink(path) if stat.S_ISLNK(mode) else path.read_bytes()
                                                  if stat.S_ISREG(mode) else stat.S_IFMT(mode))
    return out


def _table(frame: pd.DataFrame, path: Path, like: Path | None = None) -> None:
    """``frame`` as a Parquet file (with the columns' types of the part ``like``)."""
    import pyarrow as pa
    import pyarrow.parquet as pq
    schema = pq.read_schema(like) if like is not None else None
    pq.write_table(pa.Table.from_pandas(frame, schema=schema, preserve_index=False), path)


def _tamper(kind: str, out: Path, tmp_path: Path) -> str:
    """Put something in a complete 4-point sweep that resume must not trust; returns the part's name."""
    import os
    parts = sorted((out / "parts").glob("*.parquet"))
    first = pd.read_parquet(parts[0])
    if kind == "duplicate copy":                       # 6 rows for 4 points, exit 0, before
        (out / "parts" / "part-copy.parquet").write_bytes(parts[0].read_bytes())
        return "part-copy.parquet"
    if kind == "duplicate under a part's name":
        (out / "parts" / "part-000000000-0badcafe.parquet").write_bytes(parts[0].read_bytes())
        return "part-000000000-0badcafe.parquet"
    if kind == "bogus columns":                        # its indices counted as done, their rows without results
        parts[1].unlink()
        _table(pd.DataFrame({"index": [2, 3], "bogus": ["x", "y"]}), out / "parts" / "part-bogus.parquet")
        return "part-bogus.parquet"
    if kind == "index outside the grid":               # an IndexError after the sweep, before
        extra = first.copy()
        extra["index"] = [99, 100]
        _table(extra, out / "parts" / "part-outside.parquet", like=parts[0])
        return "part-outside.parquet"
    if kind == "index one past the last point":        # the sweep has indices 0 .. 3
        extra = first.iloc[:1].copy()
        extra["index"] = [4]
        _table(extra, out / "parts" / "part-past.parquet", like=parts[0])
        return "part-past.parquet"
    if kind == "changed, its size kept":               # only the SHA-256 tells: a value's 8 bytes replaced in place
        import struct
        data = parts[0].read_bytes()
        value = float(first.loc[0, "vout_mean"])
        edited = data.replace(struct.pack("<d", value), struct.pack("<d", value * (1 + 1e-9)))
        assert len(edited) == len(data) and edited != data
        parts[0].write_bytes(edited)
        assert pd.read_parquet(parts[0]).loc[0, "vout_mean"] == value * (1 + 1e-9)     # still a readable part
        return parts[0].name
    if kind == "changed after it was written":         # a value edited in a part pcsuite wrote
        changed = first.copy()
        changed.loc[0, "vout_mean"] = 1234.5
        _table(changed, parts[0], like=parts[0])
        return parts[0].name
    if kind == "edited, its journal deleted":          # '4 already stored', exit 0, before
        import pyarrow as pa
        import pyarrow.parquet as pq
        table = pq.read_table(parts[0])
        frame = table.to_pandas()
        frame.loc[0, "vout_mean"] = 99.0
        edited = pa.Table.from_pandas(frame, schema=table.schema, preserve_index=False)
        pq.write_table(edited.replace_schema_metadata(table.schema.metadata), parts[0])       # its metadata kept
        (out / "parts.jsonl").unlink()
        return parts[0].name
    if kind == "another sweep's part":                # its journal line dropped: '4 already stored', exit 0, before
        other = tmp_path / "other"
        assert main([*SMALL, "-p", "Vin=24", "--out", str(other)]) == 0
        theirs = sorted((other / "parts").glob("*.parquet"))[1]
        journal = out / "parts.jsonl"
        journal.write_text("".join(line for line in journal.read_text().splitlines(keepends=True)
                                   if parts[1].name not in line))
        parts[1].unlink()
        (out / "parts" / theirs.name).write_bytes(theirs.read_bytes())
        assert sorted(pd.read_parquet(out / "parts")["index"]) == [0, 1, 2, 3]      # the same indices, Vin 24's rows
        return theirs.name
    if kind == "symbolic link":
        elsewhere = tmp_path / "elsewhere.parquet"
        parts[1].rename(elsewhere)
        (out / "parts" / parts[1].name).symlink_to(elsewhere)
        return parts[1].name
    if kind == "not a parquet file":                   # pandas.read_parquet(DIR/parts) fails on it
        (out / "parts" / "notes.txt").write_text("mine")
        return "notes.txt"
    if kind == "FIFO":                                 # reading it waited forever, before
        os.mkfifo(out / "parts" / "part-fifo.parquet")
        return "part-fifo.parquet"
    raise AssertionError(kind)


TAMPERED = {"duplicate copy": "holds indices also stored in parts/", "duplicate under a part's name":
            "holds indices also stored in parts/", "bogus columns": "is not a part of this sweep (its columns: index, bogus",
            "index outside the grid": "holds index 99, outside the sweep's 4 points",
            "index one past the last point": "holds index 4, outside the sweep's 4 points [0, 3]",
            "changed, its size kept": "was changed after pcsuite wrote it", "changed after it was written":
            "was changed after pcsuite wrote it", "symbolic link": "is a symbolic link, not a part pcsuite wrote",
            "not a parquet file": "is not a part of this sweep (not a .parquet file)",
            "another sweep's part": "was written by another sweep's (",
            "edited, its journal deleted": "was changed after pcsuite wrote it (its rows are not the ones it was "
                                           "written with)",
            "FIFO": "is a FIFO (named pipe), not a part pcsuite wrote"}


@pytest.mark.parametrize("kind", list(TAMPERED))
@pytest.mark.slow
def test_resume_verifies_every_stored_part_and_refuses_one_it_did_not_write(kind, tmp_path):
    out = tmp_path / "s"
    env = {**__import__("os").environ, "PYTHONPATH": str(Path(__file__).resolve().parents[2])}
    run = lambda: subprocess.run([sys.executable, "-m", "validation.cli", *SMALL, "--out", str(out)],   # noqa: E731
                                 capture_output=True, text=True, env=env, timeout=60)
    assert run().returncode == 0
    name = _tamper(kind, out, tmp_path)
    before = _files(tmp_path)
    done = run()                                        # a subprocess: a FIFO had made it wait forever
    lines = done.stderr.strip().splitlines()
    assert done.returncode == 2 and len(lines) == 1 and "Traceback" not in done.stderr, done.stderr
    assert lines[0].startswith(f"pcsuite: error: --out {out}: parts/{name} "), lines[0]
    assert TAMPERED[kind] in lines[0] and lines[0].endswith("(nothing was changed)"), lines[0]
    assert _files(tmp_path) == before                   # refused whole: nothing written, nothing removed


THREADS = """
import os, sys
import numpy, pandas, pyarrow, pyarrow.parquet, scipy.linalg
from validation.cli import main
from validation.sweep import load_sweep
count = lambda: len(os.listdir("/proc/self/task"))
before = count()
refused = main(sys.argv[1:])
frame = load_sweep(sys.argv[-1])
print(refused, len(frame), before, count())
"""


def test_reading_a_sweep_back_starts_no_arrow_thread_pool(tmp_path):
    """Arrow's pool threads, torn down at interpreter exit, aborted a refused resume now and then under load
    (SIGABRT after the error line: "terminate called without an active exception"); verifying the parts and
    reading them back start no thread at all."""
    out = tmp_path / "s"
    env = {**__import__("os").environ, "PYTHONPATH": str(Path(__file__).resolve().parents[2])}
    assert main([*SMALL, "--out", str(out)]) == 0
    _tamper("index outside the grid", out, tmp_path)
    done = subprocess.run([sys.executable, "-c", THREADS, *SMALL, "--out", str(out)], capture_output=True,
                          text=True, env=env, timeout=60)
    assert done.returncode == 0, done.stderr
    refused, rows, before, after = map(int, done.stdout.split())
    assert (refused, rows) == (2, 6) and after == before, done.stdout


def test_a_part_stored_just_before_a_kill_is_verified_and_kept(tmp_path, capsys):
    """A kill between a part's rename and its line in parts.jsonl leaves a whole part the journal does not list:
    resume checks it like a stranger's (schema, indices, no duplicates), keeps it and lists it."""
    out = tmp_path / "s"
    assert main(SMALL + ["--out", str(out)]) == 0
    journal = out / "parts.jsonl"
    lines = journal.read_text().splitlines(keepends=True)
    assert len(lines) == 2 and all(json.loads(line)["rows"] == 2 for line in lines)
    journal.write_text(lines[0] + lines[1][:10])        # the last line torn by the kill
    capsys.readouterr()
    assert main(SMALL + ["--out", str(out), "--json"]) == 0
    assert _summary(capsys)["computed"] == 0
    assert [json.loads(line) for line in journal.read_text().splitlines()] == [json.loads(line) for line in lines]


@pytest.mark.parametrize("held", ["[1, 2]", "null", "\"sweep\"", "{\"format\": 1, \"points\": 5}"])
def test_a_sweep_json_that_is_not_a_sweeps_is_refused_in_one_line(held, tmp_path, capsys):
    """A list or null in sweep.json raised AttributeError or TypeError (a traceback) before."""
    out = tmp_path / "s"
    out.mkdir()
    (out / "sweep.json").write_text(held)
    assert main(SMALL + ["--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert len(err.splitlines()) == 1 and err.startswith(f"pcsuite: error: --out {str(out)!r}"), err
    assert ("its sweep.json is not a pcsuite sweep's" in err) or ("holds a different sweep" in err), err
    assert sorted(p.name for p in out.iterdir()) == ["sweep.json"]


@pytest.mark.parametrize("kind", ["symbolic link", "directory", "FIFO"])
def test_a_lock_that_is_not_a_regular_file_is_refused_and_nothing_is_created_where_it_points(kind, tmp_path):
    """``open(.lock, "a+")`` followed a planted link (creating its target) and failed on a directory with a traceback."""
    import os
    out = tmp_path / "s"
    assert main(SMALL + ["--out", str(out)]) == 0
    lock = out / ".lock"
    lock.unlink()
    (tmp_path / "elsewhere").mkdir()
    target = tmp_path / "elsewhere" / "planted"
    {"symbolic link": lambda: lock.symlink_to(target), "directory": lock.mkdir, "FIFO": lambda: os.mkfifo(lock)}[kind]()
    before = _files(tmp_path)
    done = subprocess.run([sys.executable, "-m", "validation.cli", *SMALL, "--out", str(out)], capture_output=True,
                          text=True, timeout=60, env={**os.environ, "PYTHONPATH": str(Path(__file__).resolve().parents[2])})
    assert done.returncode == 2 and len(done.stderr.splitlines()) == 1, done.stderr
    what = {"symbolic link": "a symbolic link", "directory": "a directory", "FIFO": "a FIFO (named pipe)"}[kind]
    assert done.stderr.startswith(f"pcsuite: error: --out {out}: its .lock is {what}, not the lock file a sweep "
                                  "creates"), done.stderr
    assert not target.exists() and _files(tmp_path) == before


@pytest.mark.slow
def test_a_scheduler_that_accepts_and_never_answers_is_refused_within_the_connect_timeout(tmp_path):
    """The handshake's read had no timeout: a server that accepts and stays silent held the sweep forever,
    --time-limit included. Now: 10 s, or --time-limit when shorter."""
    import os
    import socket
    import threading
    from concurrent.futures import ThreadPoolExecutor
    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen(16)
    held = []

    def accept():
        while True:
            try:
                held.append(server.accept()[0])             # kept open, never written to
            except OSError:
                return
    threading.Thread(target=accept, daemon=True).start()
    address = f"tcp://127.0.0.1:{server.getsockname()[1]}"
    env = {**os.environ, "PYTHONPATH": str(Path(__file__).resolve().parents[2])}

    def run(extra, out):
        start = time.monotonic()
        try:
            done = subprocess.run([sys.executable, "-m", "validation.cli", "sweep", "buck", "--grid", "D=0.3:0.6:3",
                                   "--no-progress", "--scheduler", address, "--out", str(out), *extra],
                                  capture_output=True, text=True, env=env, timeout=90)
        except subprocess.TimeoutExpired:
            return "timeout", "", time.monotonic() - start
        return done.returncode, done.stderr, time.monotonic() - start
    try:
        with ThreadPoolExecutor(2) as pool:
            plain, limited = pool.map(run, [[], ["--time-limit", "2"]], [tmp_path / "a", tmp_path / "b"])
    finally:
        server.close()
        for conn in held:
            conn.close()
    for (code, err, wall), seconds in ((plain, 10), (limited, 2)):
        assert code == 2 and len(err.splitlines()) == 1, (code, err)
        assert err == (f"pcsuite: error: scheduler: no Dask scheduler answered at {address} within {seconds} s (the "
                       "connection is accepted, the handshake never answered); check the address\n"), err
        assert wall >= seconds, wall                       # the timeout honoured (the 90 s guard: not hung)
    assert not (tmp_path / "a").exists() and not (tmp_path / "b").exists()


DCM_BOOST_STUDY = ["boost", "-p", "D=0.3", "-p", "R=50", "--tolerance", "L=10%", "--tolerance", "C=10%",
                   "--tolerance", "R=5%", "--samples", "200", "--spec", "vout_mean>25.3", "--steady", "--json"]


@pytest.mark.slow
def test_a_dcm_boost_tolerance_study_at_its_defaults_contains_the_exact_methods_yield(tmp_path, capsys):
    """The DCM boost (D 0.3, R 50 ohm; vout 24.97 V, spread ~0.31 V by L, C at 10 % and R at 5 %): at the default step
    T/200 the stepper's default theta (0.5: every time constant resolved) meets the exact event method's yield; the
    study states each metric's error against its spread. Backward Euler there (the sweep's old default) reads every
    sample ~0.6 % low: 6.25 % [4.1, 9.1] against the exact 16.5 % of 400 samples, the interval excluding it; its
    error at the nominal point is half the spread, and the study warns."""
    from converters.sweeps import ModelSweep
    from validation.cli.sweep import WELL_BELOW
    studies = {}
    for name, extra in (("default", []), ("event", ["--method", "event"])):
        assert main(["sweep", *DCM_BOOST_STUDY, "--out", str(tmp_path / name), *extra]) == 0
        studies[name] = json.loads(capsys.readouterr().out)["study"]
    exact, default = studies["event"], studies["default"]
    assert default["yield_low"] <= exact["yield"] <= default["yield_high"]
    assert abs(default["passed"] - exact["passed"]) <= 2
    accuracy = default["accuracy"]["metrics"]["vout_mean"]
    assert accuracy["ratio"] < WELL_BELOW and accuracy["spread"] == pytest.approx(0.31, rel=0.15)
    assert exact["accuracy"]["metrics"]["vout_mean"]["error"] == 0.0 and not default["accuracy"]["warnings"]
    euler = ModelSweep("boost", base={"D": 0.3, "R": 50}, theta=1.0)
    error, _ = euler.nominal_error(["vout_mean"])["vout_mean"]
    assert error / accuracy["spread"] > WELL_BELOW


def test_a_grid_sweeps_worst_sample_of_a_spec_names_its_point(tmp_path, capsys):
    """A spec on a grid (not a tolerance study) printed its worst value 'at' and no point."""
    assert main(["sweep", "buck", "--grid", "D=0.2:0.6:3", "--spec", "vout_mean<6", "--out", str(tmp_path / "g"),
                 "--no-progress"]) == 0
    (line,) = [line for line in capsys.readouterr().out.splitlines() if "meet it; worst" in line]
    assert line.strip().startswith("vout_mean<6: 33.33 % meet it; worst 9.8") and line.endswith(" V at D = 0.6")


def test_resume_refuses_a_sweep_whose_netlist_changed_since(tmp_path, capsys):
    """A netlist sweep is bound to the circuit itself: edit the file between the runs and resume is refused (its
    identity held the path only, and the parts of the old circuit were taken as this one's)."""
    circuit = tmp_path / "buck.cir"
    circuit.write_text((Path(__file__).resolve().parents[2] / "netlists" / "circuits" / "buck.cir").read_text())
    args = ["sweep", str(circuit), "--grid", "D=0.3:0.6:2", "--steady", "--no-progress", "--out", str(tmp_path / "s")]
    assert main(args) == 0
    circuit.write_text(circuit.read_text().replace(".param Vin=12", ".param Vin=24"))
    capsys.readouterr()
    assert main(args) == 2
    err = capsys.readouterr().err
    assert "holds a different sweep (model_sha256:" in err and len(err.strip().splitlines()) == 1


def test_a_netlist_tolerance_takes_a_parameter_name_as_p_and_grid_take_it(tmp_path, capsys):
    """A netlist's parameter names are case-insensitive as SPICE's: -p C= and --grid C= took 'C', --tolerance C=10%
    was refused ('not a parameter of the model; valid names: ..., c, ...')."""
    netlist = str(Path(__file__).resolve().parents[2] / "netlists" / "circuits" / "buck.cir")
    assert main(["sweep", netlist, "--tolerance", "C=10%", "--samples", "8", "--steady", "--no-progress", "--json",
                 "--out", str(tmp_path / "t")]) == 0
    study = json.loads(capsys.readouterr().out)
    assert study["ok"] == 8
    frame = load_sweep(tmp_path / "t")
    assert frame["c"].min() >= 0.9 * 100e-6 and frame["c"].max() <= 1.1 * 100e-6 and frame["c"].std() > 0


def test_a_netlist_tolerance_takes_its_nominal_from_p_under_either_case(tmp_path, capsys):
    """-p L=10u beside --tolerance L=10% reached the netlist as both L and l: "-p l is given twice" (the built-in
    buck takes the same two, as the tolerances guide shows). -p L= and -p l= together are one name given twice."""
    netlist = str(Path(__file__).resolve().parents[2] / "netlists" / "circuits" / "buck.cir")
    assert main(["sweep", netlist, "-p", "L=20u", "--tolerance", "L=10%", "--samples", "4", "--steady",
                 "--no-progress", "--json", "--out", str(tmp_path / "t")]) == 0
    assert json.loads(capsys.readouterr().out)["ok"] == 4
    frame = load_sweep(tmp_path / "t")
    assert frame["l"].min() >= 0.9 * 20e-6 and frame["l"].max() <= 1.1 * 20e-6       # about -p's 20u, not 10u
    assert main(["sweep", netlist, "-p", "L=20u", "-p", "l=30u", "--grid", "D=0.2:0.4:2", "--no-progress",
                 "--out", str(tmp_path / "u")]) == 2
    assert capsys.readouterr().err == ("pcsuite: error: -p L is given twice (as L and l; a netlist's names are "
                                       "case-insensitive)\n")
    assert not (tmp_path / "u").exists()


def test_a_sweep_from_rest_says_which_points_have_not_settled(tmp_path, capsys):
    """Without --steady a row measures the last of --periods periods from rest: the DCM boost at R = 200 ohm reads
    40.60 V after 50 periods, its periodic orbit 54.3735 V (the tester's exact orbit), and was stored 'ok' with no
    word. Its row now says it has not settled, and how far it may be (0.26, the moves' geometric decay; 0.34
    true); the command line counts such points; a buck that has settled (400 periods: 6.9625053 V against the
    orbit's 6.9624999) says nothing."""
    netlist = str(Path(__file__).resolve().parents[2] / "netlists" / "circuits" / "boost.cir")
    assert main(["sweep", netlist, "--grid", "R=200:200:1", "--no-progress", "--out", str(tmp_path / "b")]) == 0
    err = capsys.readouterr().err
    assert err.startswith("pcsuite: warning: 1 of the 1 points stored as ok have not settled (their measures are "
                          "the transient's")
    row = load_sweep(tmp_path / "b").iloc[0]
    assert row["status"] == "ok" and abs(row["vout_mean"] - 40.60) < 0.05
    away = float(row["message"].split("is about ")[1].split(" ")[0])
    true = abs(row["vout_mean"] - 54.3735) / row["vout_mean"]
    assert row["message"].startswith("not settled after 50 periods from rest") and true / 2 < away < 2 * true
    assert main(["sweep", "buck", "--grid", "R=10:10:1", "--periods", "400", "--no-progress", "--json",
                 "--out", str(tmp_path / "s")]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["unsettled"] == 0 and "warnings" not in summary
    assert load_sweep(tmp_path / "s").iloc[0]["message"] == ""
    # five periods are too few to read a decay from (9.94 V stored, before, as ok with no word); --json says it too
    assert main(["sweep", netlist, "--grid", "R=200:200:1", "--periods", "5", "--no-progress", "--json",
                 "--out", str(tmp_path / "f")]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["unsettled"] == 1 and summary["warnings"][0].startswith("1 of the 1 points stored as ok have not "
                                                                           "settled")
    assert load_sweep(tmp_path / "f").iloc[0]["message"].startswith("not settled as far as can be told: 5 periods")


def test_an_ngspice_sweep_runs_a_netlists_own_circuit(ngspice):
    """--method spice on a netlist had read a built-in model's probes on it: "KeyError: 'vout'" at every point. It
    runs the file's own circuit (as simulate --method spice does): the buck at D = 0.3 from the LCP's orbit, its
    mean 5.794489706 V (the tester's exact orbit) to ngspice's models' 1e-4, its modes the file's."""
    from converters.parallel import run_ensemble
    from converters.sweeps import Axis, Grid, ModelSweep
    netlist = str(Path(__file__).resolve().parents[2] / "netlists" / "circuits" / "buck.cir")
    (row,) = run_ensemble(ModelSweep(netlist, method="spice", steady=True, periods=4),
                          Grid([Axis.parse("D=0.3:0.3:1")]), backend="serial")
    assert row["status"] == "ok", row["message"]
    assert abs(row["vout_mean"] - 5.794489706) < 1e-4 * 5.794489706
    assert row["mode"] == "S1 > D1 > off" and abs(row["held_fraction"] - 0.378734556) < 5e-3 and row["message"] == ""
    # from rest, its rows say whether they have settled, as the LCP's do (40.5 V after 50 periods of the boost, its
    # orbit 54.37 V, had been stored as ok with no word)
    boost = str(Path(__file__).resolve().parents[2] / "netlists" / "circuits" / "boost.cir")
    (row,) = run_ensemble(ModelSweep(boost, method="spice", steady=False, periods=50),
                          Grid([Axis.parse("R=200:200:1")]), backend="serial")
    assert row["status"] == "ok" and row["message"].startswith("not settled after 50 periods from rest")


def test_a_metric_the_tolerances_do_not_move_gets_no_accuracy_warning(tmp_path, capsys):
    """The ideal CCM buck's mean is D Vin whatever L and R: its samples spread by rounding (~3e-14 V) and its error
    is rounding too, and the study warned "error 2.7e-15 is 0.2 of its spread ... the yield may be off"; with
    --samples 1, "inf of its spread (nan)". Neither is a warning now, and each says why."""
    args = ["sweep", "buck", "-p", "R=1", "--tolerance", "L=10%", "--steady", "--no-progress"]
    assert main([*args, "--tolerance", "R=5%", "--samples", "8", "--out", str(tmp_path / "a")]) == 0
    out, err = capsys.readouterr()
    assert "warning" not in err and "; the samples do not move it (standard deviation " in out
    assert main([*args, "--samples", "1", "--out", str(tmp_path / "b")]) == 0
    out, err = capsys.readouterr()
    assert "warning" not in err and "; one sample, no spread to weigh it against" in out


def test_a_sweep_of_an_earlier_format_is_named_as_such(tmp_path, capsys):
    """A directory of an earlier pcsuite's sweep (format 2: its parts carry no digest of their rows) was refused as
    "a different sweep (format: 2 on disk, 3 asked); resume it with the same arguments", which no arguments do."""
    args = ["sweep", "buck", "--grid", "D=0.2:0.5:2", "--steady", "--no-progress", "--out", str(tmp_path / "s")]
    assert main(args) == 0
    manifest = tmp_path / "s" / "sweep.json"
    manifest.write_text(manifest.read_text().replace('"format": 3', '"format": 2'))
    capsys.readouterr()
    assert main(args) == 2
    assert "holds a sweep of an earlier pcsuite (format 2; this one writes 3), which it cannot resume" in \
        capsys.readouterr().err


def test_a_spec_takes_its_metrics_unit_and_refuses_another(tmp_path, capsys):
    """vout_mean is in volts: "vout_mean<3V" had been refused ("the parameter takes no unit"); it reads as
    "vout_mean<3", and "3A" is refused naming the metric's unit."""
    results = []
    for spec in ("vout_mean<3V", "vout_mean<3"):
        assert main(["sweep", "buck", "--grid", "D=0.1:0.5:2", "--spec", spec, "--json",
                     "--out", str(tmp_path / spec.replace("<", "_"))]) == 0
        results.append(_summary(capsys)["study"])
    assert results[0] == results[1] and results[0]["passed"] == 1
    assert main(["sweep", "buck", "--grid", "D=0.1:0.5:2", "--spec", "vout_mean<3A", "--out", str(tmp_path / "a")]) == 2
    assert capsys.readouterr().err == ("pcsuite: error: --spec vout_mean: the unit 'A' in '3A' contradicts the "
                                       "parameter (its unit is V)\n")
