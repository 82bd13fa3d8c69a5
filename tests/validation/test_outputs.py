"""Outputs: pcsuite never deletes or moves what it did not write, refuses a bad output path with one line before
a run (and again at write time), writes every file and report whole, cleans the leftovers of a killed writer,
and lets concurrent writers of one output take turns."""
import json
import os
import stat
import subprocess
import sys
import textwrap
import threading
import time
from pathlib import Path

import pytest

from converters.errors import ParameterError
from validation import io as vio
from validation.cli import main
from validation.report import Section, write_report

ROOT = Path(__file__).resolve().parents[2]


def tree(root: Path) -> dict:
    """Everything under ``root``: relative path -> kind and content (a file's bytes, a link's target)."""
    out = {}
    for path in sorted(root.rglob("*")):
        rel = path.relative_to(root).as_posix()
        mode = os.lstat(path).st_mode
        if stat.S_ISLNK(mode):
            out[rel] = ("link", os.readlink(path))
        elif stat.S_ISDIR(mode):
            out[rel] = ("dir",)
        elif stat.S_ISREG(mode):
            out[rel] = ("file", path.read_bytes())
        else:
            out[rel] = ("other", stat.S_IFMT(mode))
    return out


def cli(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def one_line(err: str) -> str:
    assert err.endswith("\n") and err.count("\n") == 1, err
    assert err.startswith("pcsuite: error: ")
    return err[len("pcsuite: error: "):-1]


@pytest.fixture
def no_suite(monkeypatch):
    """The suite must not run: a refusal comes before it."""
    from validation import suite

    def ran(*args, **kwargs):
        raise AssertionError("the suite ran before the output was checked")
    monkeypatch.setattr(suite, "run_suite", ran)


def _legacy_report(path: Path) -> None:
    (path / "scenes" / "buck-dcm").mkdir(parents=True)
    (path / "index.html").write_text("<html>old</html>")
    (path / "metrics.json").write_text(json.dumps({"suite": "default", "sections": {}}))
    (path / "summary.csv").write_text("section,result,reason\n")
    (path / "scenes" / "buck-dcm" / "overlay.png").write_bytes(b"png")


def _report(path: Path, marker: str = "first") -> Path:
    return write_report([Section("s", f"<p>{marker}</p>", files={"a.txt": marker.encode(),
                                                                  "scenes/x/b.txt": b"b"})], path, "t")


# --- A: --out of pcsuite report ------------------------------------------------------------------------------

def _setup_refused(kind: str, tmp: Path) -> tuple[str, str]:
    """A path --out must refuse, and the exact message."""
    cwd = tmp / "cwd"
    if kind == "user directory":
        (cwd / "d" / "sub").mkdir(parents=True)
        (cwd / "d" / "sub" / "f").write_text("x")
        return "d", "--out d: an existing directory that is not a pcsuite report (it holds sub/); choose another --out or remove it"
    if kind == "regular file":
        (cwd / "userfile.txt").write_text("mine")
        return "userfile.txt", "--out userfile.txt: an existing file, not a directory; choose another --out"
    if kind == "symlink":
        (cwd / "real").mkdir()
        (cwd / "link").symlink_to("real")
        return "link", "--out link: a symbolic link; give the directory's own path or choose another --out"
    if kind == "fifo":
        os.mkfifo(cwd / "pipe")
        return "pipe", "--out pipe: a FIFO (named pipe), not a directory; choose another --out"
    if kind == "device":
        return "/dev/null", "--out /dev/null: a character device, not a directory; choose another --out"
    if kind in (".", "..", "/"):
        return kind, f"--out {kind}: names the current directory or one of its ancestors; choose a new or empty directory"
    if kind == "cwd":
        return str(cwd), f"--out {cwd}: names the current directory or one of its ancestors; choose a new or empty directory"
    if kind == "older report":
        (cwd / "old").mkdir()
        _legacy_report(cwd / "old")
        return "old", ("--out old: a report written by an older pcsuite (no .pcsuite-report.json), whose files cannot be "
                       "told apart from files added to it; choose another --out or remove it")
    if kind == "report with a user file":
        _report(cwd / "r")
        (cwd / "r" / "scenes" / "x" / "notes.txt").write_text("my notes")
        return "r", ("--out r: an existing directory that is not only a pcsuite report (it holds scenes/x/notes.txt); "
                     "choose another --out or remove it")
    if kind == "report with a user directory":
        _report(cwd / "r")
        (cwd / "r" / "mine").mkdir()
        return "r", ("--out r: an existing directory that is not only a pcsuite report (it holds mine/); choose another "
                     "--out or remove it")
    if kind == "report edited":
        _report(cwd / "r")
        (cwd / "r" / "a.txt").write_text("edited by hand")
        return "r", "--out r: a pcsuite report whose a.txt was changed after pcsuite wrote it; choose another --out or remove it"
    if kind == "unwritable parent":
        return "/proc/report", ("--out /proc/report: cannot write in /proc (creating a file there fails: No such file or "
                                "directory)")
    raise AssertionError(kind)


REFUSED = ["user directory", "regular file", "symlink", "fifo", "device", ".", "..", "/", "cwd", "older report",
           "report with a user file", "report with a user directory", "report edited", "unwritable parent"]


@pytest.mark.parametrize("kind", REFUSED)
def test_report_out_refuses_what_pcsuite_did_not_write_before_the_run(kind, tmp_path, monkeypatch, capsys, no_suite):
    (tmp_path / "cwd").mkdir()
    target, message = _setup_refused(kind, tmp_path)
    monkeypatch.chdir(tmp_path / "cwd")
    before = tree(tmp_path)
    code, out, err = cli(capsys, "report", "lcp", "--out", target)
    assert code == 2 and out == ""
    assert one_line(err) == message
    assert tree(tmp_path) == before                         # nothing written, moved or deleted


def test_report_out_checks_again_at_write_time(tmp_path, monkeypatch, capsys):
    """A user file that appears in --out during the run: refused at the swap, the user's file and the directory
    as they were, the new report's staging removed."""
    from validation import suite
    out = tmp_path / "r"
    out.mkdir()

    def run_suite(*args, **kwargs):
        (out / "mine.txt").write_text("written during the run")
        return [], [Section("s", "<p>x</p>", files={"a.txt": b"a"})]
    monkeypatch.setattr(suite, "run_suite", run_suite)
    code, _, err = cli(capsys, "report", "lcp", "--out", out)
    assert code == 2
    assert one_line(err) == (f"--out {out}: an existing directory that is not a pcsuite report (it holds mine.txt); "
                             "choose another --out or remove it")
    assert tree(tmp_path) == {"r": ("dir",), "r/mine.txt": ("file", b"written during the run")}


def test_an_earlier_report_is_replaced_whole_and_an_empty_directory_used(tmp_path):
    target = tmp_path / "r"
    target.mkdir()                                          # an existing empty directory may be used
    _report(target, "first")
    manifest = json.loads((target / ".pcsuite-report.json").read_text())
    assert sorted(manifest["files"]) == ["a.txt", "index.html", "metrics.json", "scenes/x/b.txt", "summary.csv"]
    assert manifest["pcsuite"] == "report" and manifest["suite"] == "t"
    write_report([Section("s", "<p>second</p>", files={"c.txt": b"second"})], target, "t")
    files = sorted(p.relative_to(target).as_posix() for p in target.rglob("*"))
    assert files == [".pcsuite-report.json", "c.txt", "index.html", "metrics.json", "summary.csv"]   # no mix
    assert "second" in (target / "index.html").read_text()
    assert [p.name for p in tmp_path.iterdir()] == ["r"]          # no staging or old tree left
    old = tmp_path / "old"
    old.mkdir()
    _legacy_report(old)
    before = tree(old)
    with pytest.raises(ParameterError, match=r"/old: a report written by an older pcsuite \(no .pcsuite-report.json\)"):
        _report(old)
    assert tree(old) == before


def test_section_file_names_are_checked_when_the_report_is_written(tmp_path):
    before = tree(tmp_path)
    for name, match in (("../escaped.txt", r"file '../escaped.txt': the part must be 1-64 letters.*got '..'"),
                        ("scenes/../../x", r"the part must be .*got '..'"),
                        ("/etc/x", r"the part must be .*got ''"),
                        ("index.html", r"file 'index.html' is already written by the report")):
        with pytest.raises(ParameterError, match=match):
            write_report([Section("s", "<p>x</p>", files={name: b"x"})], tmp_path / "r", "t")
    assert tree(tmp_path) == before and not (tmp_path.parent / "escaped.txt").exists()


# --- A: file outputs and the other directory outputs ----------------------------------------------------------

def _file_cases(tmp: Path):
    (tmp / "dir.csv").mkdir()
    (tmp / "dir.png").mkdir()
    (tmp / "sidecar.csv.json").mkdir()
    os.mkfifo(tmp / "pipe.cir")
    (tmp / "real.png").write_bytes(b"x")
    (tmp / "link.png").symlink_to("real.png")
    (tmp / "user").mkdir()
    (tmp / "user" / "notes.txt").write_text("mine")
    (tmp / "file").write_text("mine")
    proc = "cannot write in /proc (creating a file there fails: No such file or directory)"
    return [
        (["simulate", "buck", "--periods", "2", "--out", "/proc/x.csv"], f"--out /proc/x.csv: {proc}"),
        (["simulate", "buck", "--periods", "2", "--out", "/dev/full/x.csv"],
         "--out /dev/full/x.csv: cannot write in /dev/full (not a directory)"),
        (["simulate", "buck", "--periods", "2", "--out", tmp / "dir.csv"],
         f"--out {tmp}/dir.csv: an existing directory, not a regular file; choose another --out"),
        (["simulate", "buck", "--periods", "2", "--out", tmp / "sidecar.csv"],
         f"--out {tmp}/sidecar.csv.json: an existing directory, not a regular file; choose another --out"),
        (["simulate", "buck", "--periods", "2", "--plot", "/dev/null"],
         "--plot /dev/null: a character device, not a regular file; choose another --plot"),
        (["simulate", "buck", "--periods", "2", "--plot", tmp / "link.png"],
         f"--plot {tmp}/link.png: a symbolic link; give the file's own path or choose another --plot"),
        (["compare", "buck", "--plot", "/proc/x.png"], f"--plot /proc/x.png: {proc}"),
        (["netlist", "buck", "--out", "/proc/x.cir"], f"--out /proc/x.cir: {proc}"),
        (["netlist", "buck", "--out", tmp / "pipe.cir"],
         f"--out {tmp}/pipe.cir: a FIFO (named pipe), not a regular file; choose another --out"),
        (["bifurcation", "buck", "--control", "voltage-mode", "--param", "Vin=20:26", "--diagram", tmp / "dir.png"],
         f"--diagram {tmp}/dir.png: an existing directory, not a regular file; choose another --diagram"),
        (["mech", "simulate", "bouncing-ball", "--out", "/proc/x.csv"], f"--out /proc/x.csv: {proc}"),
        (["mech", "bifurcations", "friction", "--param", "A=0.1:0.2", "--diagram", "/dev/full/x.png"],
         "--diagram /dev/full/x.png: cannot write in /dev/full (not a directory)"),
        (["gdcm-map", "buck", "--no-spice", "--out", "/proc/m"], f"--out /proc/m: {proc}"),
        (["gdcm-map", "buck", "--no-spice", "--out", tmp / "user"],
         f"--out {tmp}/user: an existing directory that is not a pcsuite gdcm-map output (it holds notes.txt); choose "
         "another --out or remove it"),
        (["bench", "--quick", "--out", tmp / "user"],
         f"--out {tmp}/user: an existing directory that is not a pcsuite bench output (it holds notes.txt); choose "
         "another --out or remove it"),
        (["bench", "--quick", "--out", tmp / "file"],
         f"--out {tmp}/file: an existing file, not a directory; choose another --out"),
        (["sweep", "buck", "--grid", "D=0.3:0.6:3", "--no-progress", "--out", "/proc/sweep"], f"--out /proc/sweep: {proc}"),
    ]


def test_every_output_option_refuses_a_target_that_is_not_a_file_it_may_write(tmp_path, capsys):
    cases = _file_cases(tmp_path)
    before = tree(tmp_path)
    for argv, message in cases:
        started = time.process_time()
        code, _, err = cli(capsys, *argv)
        assert code == 2, argv
        assert one_line(err) == message, argv
        assert time.process_time() - started < 20, argv                  # CPU seconds: refused before the run
        assert tree(tmp_path) == before, argv


def test_the_sweep_store_refuses_a_directory_that_holds_no_sweep(tmp_path, capsys):
    (tmp_path / "d").mkdir()
    (tmp_path / "d" / "notes.txt").write_text("mine")
    before = tree(tmp_path)
    code, _, err = cli(capsys, "sweep", "buck", "--grid", "D=0.3:0.6:3", "--no-progress", "--out", tmp_path / "d")
    assert code == 2 and "is a non-empty directory that holds no sweep" in one_line(err)
    assert tree(tmp_path) == before


def test_atomic_write_bytes_checks_the_target_again_and_overwrites_a_regular_file(tmp_path):
    os.mkfifo(tmp_path / "pipe")
    (tmp_path / "dir").mkdir()
    for target, match in ((tmp_path / "dir", r"dir: an existing directory, not a regular file"),
                          (tmp_path / "pipe", r"pipe: a FIFO \(named pipe\), not a regular file"),   # never opened
                          (Path("/dev/null"), r"/dev/null: a character device, not a regular file"),
                          (Path("/proc/x.csv"), r"/proc/x.csv: cannot write in /proc \(No such file or directory\)"),
                          (Path("/dev/full/x"), r"/dev/full/x: cannot write in /dev/full \(not a directory\)")):
        with pytest.raises(ParameterError, match=match):
            vio.atomic_write_bytes(target, b"data")
    with pytest.raises(ParameterError, match=r"^--plot .*/dir: an existing directory"):    # the option, once known
        vio.check_output_file("--plot", tmp_path / "dir")
    with pytest.raises(ParameterError, match=r"^--plot .*/dir: an existing directory"):
        vio.atomic_write_bytes(tmp_path / "dir", b"data")
    target = tmp_path / "f.csv"
    target.write_text("old")
    old_umask = os.umask(0o022)
    try:
        vio.atomic_write_bytes(target, b"new")
    finally:
        os.umask(old_umask)
    assert target.read_bytes() == b"new" and stat.S_IMODE(target.stat().st_mode) == 0o644
    assert sorted(p.name for p in tmp_path.iterdir()) == ["dir", "f.csv", "pipe"]


def test_a_gdcm_map_directory_is_rewritten_only_while_it_holds_its_own_files(tmp_path, capsys):
    out = tmp_path / "map"
    argv = ["gdcm-map", "buck", "--size", "3", "3", "--no-spice", "--out", out]
    assert cli(capsys, *argv)[0] == 0
    first = tree(tmp_path)
    assert sorted(first) == ["map", "map/map.csv", "map/map.png"]
    assert cli(capsys, *argv)[0] == 0                       # its own earlier output: rewritten
    assert sorted(tree(tmp_path)) == sorted(first)
    (out / "notes.txt").write_text("mine")
    before = tree(tmp_path)
    code, _, err = cli(capsys, *argv)
    assert code == 2 and "(it holds notes.txt)" in one_line(err) and tree(tmp_path) == before


@pytest.mark.parametrize("earlier", [False, True], ids=["new directory", "earlier map"])
def test_a_full_disk_leaves_neither_new_map_file_or_the_earlier_pair(tmp_path, capsys, monkeypatch, earlier):
    """map.csv then map.png were each written atomically, so a disk that filled between them left a new map.csv
    beside no map.png (or beside the earlier map.png). Both are now staged before either is put in place."""
    import errno
    out = tmp_path / "map"
    argv = ["gdcm-map", "buck", "--size", "3", "3", "--no-spice", "--out", out]
    if earlier:
        assert cli(capsys, *argv[:3], "4", "4", *argv[5:])[0] == 0
    before = tree(tmp_path)
    real, calls = os.fsync, []

    def full_on_the_second(fd):                         # the second file's data does not fit
        calls.append(fd)
        if len(calls) == 2:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        return real(fd)
    monkeypatch.setattr(os, "fsync", full_on_the_second)
    code, out_text, err = cli(capsys, *argv)
    lines = err.replace("\r", "\n").strip().splitlines()           # the map's progress bar, then the error
    assert code == 2 and "Traceback" not in err
    assert lines[-1] == f"pcsuite: error: --out {out}: cannot write map.png (No space left on device)", err
    assert tree(tmp_path) == before                     # the earlier pair, or no directory at all


def test_a_fixed_name_directory_is_checked_again_when_written(tmp_path):
    from validation.bench import OUT_FILES
    out = tmp_path / "bench"
    with vio.locked_output_dir(out, "bench", OUT_FILES):
        vio.atomic_write_bytes(out / "bench.json", b"{}")
    (out / "mine.txt").write_text("mine")
    with pytest.raises(ParameterError, match=r"bench: an existing directory that is not a pcsuite bench output "
                                             r"\(it holds mine.txt\)"):
        with vio.locked_output_dir(out, "bench", OUT_FILES):
            pass
    with pytest.raises(ParameterError, match=r"bench: an existing directory that is not a pcsuite bench output"):
        vio.atomic_write_bytes(out / "bench.json", b"{}")          # the directory is known as bench's now
    assert (out / "bench.json").read_bytes() == b"{}" and (out / "mine.txt").read_text() == "mine"


# --- C: names that become file names ---------------------------------------------------------------------------

@pytest.mark.parametrize("value", ["buck-dcm", "a.b_c-1", "X" * 64, "0"])
def test_safe_names_pass(value):
    assert vio.safe_name("name", value) == value


@pytest.mark.parametrize("value", ["../../../../escaped", "..", ".", "", "a/b", "x' onerror='alert(1)", "-x", ".hidden",
                                   "X" * 65, "a b", "é", 5, None, "a\nb"])
def test_unsafe_names_are_refused(value):
    with pytest.raises(ParameterError, match=r"^scene name must be 1-64 letters, digits, '.', '_' or '-', starting with "
                                             r"a letter or digit \(it becomes a file name\); got "):
        vio.safe_name("scene name", value)


# --- F: leftovers of killed writers and concurrent writers -----------------------------------------------------

def _child(code: str) -> subprocess.Popen:
    """A Python child that runs ``code`` and prints 'ready' where it stops to be killed."""
    return subprocess.Popen([sys.executable, "-c", textwrap.dedent(code)], cwd=ROOT, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)


def _wait_ready(child: subprocess.Popen) -> None:
    line = child.stdout.readline()
    assert line.strip() == "ready", (line, child.stderr.read() if child.poll() is not None else "")


def _kill(child: subprocess.Popen) -> None:
    child.kill()
    child.wait()


STALL_FILE = """
import os, sys, time
from validation import io
def stall(fd):
    print("ready", flush=True)
    time.sleep(600)
io.os.fsync = stall
io.atomic_write_bytes(sys.argv[1] if len(sys.argv) > 1 else {target!r}, b"new" * 1000000)
"""


def test_a_writer_killed_while_writing_a_file_leaves_a_temporary_the_next_write_removes(tmp_path):
    target = tmp_path / "w.csv"
    target.write_bytes(b"old")
    child = _child(STALL_FILE.format(target=str(target)))
    _wait_ready(child)
    temps = [p.name for p in tmp_path.iterdir() if p.name != "w.csv"]
    assert len(temps) == 1 and temps[0].startswith(f".w.csv.{child.pid}.") and temps[0].endswith(".tmp")
    live = _child(STALL_FILE.format(target=str(target)))    # a live writer's temporary is never removed
    _wait_ready(live)
    _kill(child)
    assert target.read_bytes() == b"old"                    # the old content, whole
    vio.atomic_write_bytes(target, b"newer")
    assert target.read_bytes() == b"newer"
    left = sorted(p.name for p in tmp_path.iterdir())
    assert left[1:] == ["w.csv"] and left[0].startswith(f".w.csv.{live.pid}.")   # the dead one's is gone
    _kill(live)
    vio.atomic_write_bytes(target, b"newest")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["w.csv"] and target.read_bytes() == b"newest"


STALL_DIRECTORY = """
import time
from validation import io
with io.atomic_directory({target!r}) as staging:
    (staging / "a.txt").write_text("killed")
    print("ready", flush=True)
    time.sleep(600)
"""

STALL_AFTER_SWAP = """
import time
from validation import io
from validation.report import Section, write_report
def stall(*args, **kwargs):
    print("ready", flush=True)
    time.sleep(600)
io.shutil.rmtree = stall
write_report([Section("s", "<p>swapped</p>", files={{"a.txt": b"swapped"}})], {target!r}, "t")
"""


@pytest.mark.parametrize("moment", ["while staging", "after the swap"])
def test_a_report_writer_killed_leaves_nothing_the_next_write_does_not_remove(moment, tmp_path):
    target = tmp_path / "r"
    _report(target, "first")
    child = _child((STALL_DIRECTORY if moment == "while staging" else STALL_AFTER_SWAP).format(target=str(target)))
    _wait_ready(child)
    _kill(child)
    leftovers = [p.name for p in tmp_path.iterdir() if p.name != "r"]
    assert len(leftovers) == 1 and leftovers[0].startswith(f".r.{child.pid}.")
    expected = "first" if moment == "while staging" else "swapped"
    assert (target / "a.txt").read_text() == expected       # old or new, whole: never a mix
    assert vio._foreign(target, vio._Output(None, str(target), "report")) == ""
    _report(target, "second")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["r"]
    assert (target / "a.txt").read_text() == "second"


def _check_whole(target: Path, markers) -> str:
    """The report in ``target`` is one writer's, complete, and holds nothing else; its marker."""
    assert vio._foreign(target, vio._Output(None, str(target), "report")) == ""
    marker = (target / "a.txt").read_text()
    assert marker in markers and f"<p>{marker}</p>" in (target / "index.html").read_text()
    assert (target / "scenes" / "x" / "b.txt").read_text() == marker
    return marker


def test_concurrent_reports_into_one_directory_take_turns_and_the_last_stays_whole(tmp_path, monkeypatch):
    import validation.io as io
    target = tmp_path / "r"
    barrier = threading.Barrier(20)
    errors, done, swapped = [], [], []
    swap = io._swap

    def recording_swap(staging, into, output):       # runs under the parent's lock: the true order of the swaps
        swap(staging, into, output)
        swapped.append((into / "a.txt").read_text())
    monkeypatch.setattr(io, "_swap", recording_swap)

    def write(i):
        marker = f"writer-{i}"
        section = Section("s", f"<p>{marker}</p>", files={"a.txt": marker.encode(), "scenes/x/b.txt": marker.encode()})
        barrier.wait()
        try:
            write_report([section], target, "t")
            done.append(marker)
        except ParameterError as exc:         # a loser may fail, with one line
            errors.append(str(exc))
        except BaseException as exc:  # noqa: BLE001 - anything else is the failure this test looks for
            errors.append(f"UNEXPECTED {type(exc).__name__}: {exc}")
    threads = [threading.Thread(target=write, args=(i,)) for i in range(20)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    assert not [e for e in errors if e.startswith("UNEXPECTED") or "\n" in e]
    assert len(done) == 20 and sorted(swapped) == sorted(done)   # swaps serialise: every writer lands, in turn
    assert _check_whole(target, done) == swapped[-1]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["r"]


RACER = """
import sys, time
from validation.report import Section, write_report
marker, start = sys.argv[1], float(sys.argv[2])
while time.time() < start:
    pass
for _ in range(10):                 # many rounds: the swaps of 8 processes overlap again and again
    write_report([Section("s", f"<p>{marker}</p>", files={"a.txt": marker.encode(),
                                                          "scenes/x/b.txt": marker.encode()})], sys.argv[3], "t")
print(marker, time.time(), flush=True)
"""


@pytest.mark.slow
def test_concurrent_report_processes_each_land_whole(tmp_path):
    """8 processes, 10 reports each, into one directory at once: every one lands (no traceback, no error), the
    directory ends as one complete report, and nothing else is left beside it."""
    target = tmp_path / "r"
    start = time.time() + 3.0
    children = [subprocess.Popen([sys.executable, "-c", RACER, f"process-{i}", str(start), str(target)], cwd=ROOT,
                                 stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True) for i in range(8)]
    results = [child.communicate(timeout=120) + (child.returncode,) for child in children]
    assert [code for _, _, code in results] == [0] * 8, [err for _, err, _ in results]
    finished = sorted((float(out.split()[1]), out.split()[0]) for out, _, _ in results)
    assert _check_whole(target, [m for _, m in finished]) in [m for _, m in finished]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["r"]


def test_concurrent_writers_of_one_file_each_write_it_whole(tmp_path):
    target = tmp_path / "w.csv"
    barrier = threading.Barrier(20)
    errors = []

    def write(i):
        barrier.wait()
        try:
            vio.atomic_write_bytes(target, str(i).encode() * 100_000)
        except BaseException as exc:  # noqa: BLE001 - any failure is what this test looks for
            errors.append(exc)
    threads = [threading.Thread(target=write, args=(i,)) for i in range(20)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    assert errors == []
    data = target.read_bytes()
    assert any(data == str(i).encode() * 100_000 for i in range(20))          # one writer's, whole
    assert [p.name for p in tmp_path.iterdir()] == ["w.csv"]


def test_report_twice_into_one_directory_replaces_the_first(tmp_path, capsys):
    out = tmp_path / "r"
    assert cli(capsys, "report", "lcp", "--out", out)[0] == 0
    first = json.loads((out / ".pcsuite-report.json").read_text())
    assert sorted(first["files"]) == ["index.html", "lcp_peer.csv", "lcp_project.csv", "metrics.json", "summary.csv"]
    (out / "lcp_peer.csv").unlink()           # a file removed from a report is no user data: it may be replaced
    code, printed, _ = cli(capsys, "report", "lcp", "--out", out)
    assert code == 0 and printed.startswith(f"wrote {out}/index.html")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["r"]
    assert sorted(p.name for p in out.iterdir()) == [".pcsuite-report.json", *first["files"]]


@pytest.mark.slow
def test_a_waveform_csv_streams_to_its_file_and_lands_with_its_sidecar(tmp_path):
    """A CSV had been built whole as text, then as bytes (2.4 times the file at the peak: a 60 ms sliding-mode
    run's 577 MB of CSV peaked at 2.4 GB); written 4,000 rows at a time it holds 0.23 of this 16 MB file (a
    fixed few MB). The file is the text built whole, byte for byte."""
    import tracemalloc

    import numpy as np
    import pandas as pd

    from validation.cli.common import write_frame
    t = np.linspace(0.0, 1e-3, 200_000)
    frame = pd.DataFrame({"time": t, "iL": np.sin(1e4 * t), "vC": np.cos(1e4 * t), "vout": np.cos(1e4 * t) + 1e-3})
    path = tmp_path / "w.csv"
    tracemalloc.start()
    try:
        write_frame(frame, path, meta={"converter": "buck"})
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert path.read_bytes() == frame.to_csv(index=False).encode()
    assert peak < 0.5 * path.stat().st_size
    assert json.loads((tmp_path / "w.csv.json").read_text())["units"]["vout"] == "V"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["w.csv", "w.csv.json"]       # no temporary left
