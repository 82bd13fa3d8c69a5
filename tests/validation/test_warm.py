"""validation.warm: the kernels are compiled once per checkout and kernel sources, in a child process that forces
numba's JIT; a current stamp makes it a no-op, and any kernel source or the cache's place changing makes it run
again."""
import subprocess

import pytest

from validation import warm


@pytest.fixture
def stamped(tmp_path, monkeypatch):
    """warm's stamp in tmp_path, and the child process replaced by a recorder of what it was asked to run."""
    runs = []

    def child(argv, env, **kwargs):
        runs.append((argv, env))
        return subprocess.CompletedProcess(argv, 0, "", "")
    monkeypatch.setattr(warm, "_stamp", lambda: tmp_path / "__pycache__" / warm.STAMP)
    monkeypatch.setattr(warm.subprocess, "run", child)
    return runs


def test_a_warm_up_runs_once_in_a_child_that_forces_the_jit_and_leaves_a_stamp(stamped, tmp_path):
    assert warm.ensure(progress=None)
    (argv, env), = stamped
    assert argv[1:] == ["-m", "validation.warm", "--here"] and env["PCSUITE_KERNELS"] == "jit"
    assert (tmp_path / "__pycache__" / warm.STAMP).read_text() == warm._digest()
    assert not warm.ensure(progress=None) and len(stamped) == 1            # current: nothing runs


@pytest.mark.parametrize("change", ["kernel source", "cache directory"])
def test_a_changed_kernel_source_or_cache_directory_warms_again(stamped, tmp_path, monkeypatch, change):
    sources = tmp_path / "converters"
    for name in warm.kernel_cache.SOURCES:                                  # a copy of the kernel sources
        (sources / name).parent.mkdir(parents=True, exist_ok=True)
        (sources / name).write_bytes((warm.PACKAGE / name).read_bytes())
    monkeypatch.setattr(warm, "PACKAGE", sources)
    assert warm.ensure(progress=None)
    if change == "kernel source":
        with open(sources / "lcp" / "lemke.py", "a") as lemke:
            lemke.write("# an edit\n")
    else:
        monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "elsewhere"))
    assert warm.ensure(progress=None) and len(stamped) == 2


def test_a_failed_warm_up_says_why_and_leaves_no_stamp(tmp_path, monkeypatch):
    monkeypatch.setattr(warm, "_stamp", lambda: tmp_path / warm.STAMP)
    monkeypatch.setattr(warm.subprocess, "run", lambda argv, **k: subprocess.CompletedProcess(argv, 1, "", "boom"))
    with pytest.raises(RuntimeError, match="warming the kernels failed:\nboom"):
        warm.ensure(progress=None)
    assert not (tmp_path / warm.STAMP).exists()
