"""converters.limits.keep_freed_memory: malloc keeps a run's freed arrays for the next run (counted in page
faults, not timed), and its environment variable is read like every other size."""
import os
import subprocess
import sys
import warnings
from pathlib import Path

import pytest

from converters import limits

ROOT = Path(__file__).resolve().parents[1]

FAULTS = """
import ctypes, resource
# A page fault per 2 MiB where the kernel hands out huge pages: numpy asks for them on its 4 MiB arrays (madvise) and
# a kernel with transparent huge pages "always" gives them unasked. The process declines both, so each fault is
# one 4 KiB page whatever the machine's setting.
PR_SET_THP_DISABLE = 41
if ctypes.CDLL(None, use_errno=True).prctl(PR_SET_THP_DISABLE, 1, 0, 0, 0) != 0:
    raise OSError(ctypes.get_errno(), "prctl(PR_SET_THP_DISABLE)")
from numpy._core.multiarray import _set_madvise_hugepage
_set_madvise_hugepage(False)
from converters.methods import BackwardEuler
from converters.models import get_model
from converters.simulate import simulate
model = get_model("buck")
problem = model.problem(model.resolve({}), 5e-3)
method = BackwardEuler(50e-9)
faults = []
for _ in range(6):
    before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
    tr = simulate(problem, method)                       # 100k steps: 5 MB of grid, x, u, y
    faults.append(resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before)
    grid = tr.t.nbytes // resource.getpagesize()         # the run's time grid alone, in pages
    del tr
print(max(faults[2:]), grid)      # the heap reaches its working size over the first two runs
"""


def _faults(pad: str, **malloc) -> tuple[int, int]:
    """(the most page faults of a repeated run, the pages of its time grid)."""
    env = {**os.environ, limits.MALLOC_PAD_ENV: pad, **malloc}
    done = subprocess.run([sys.executable, "-c", FAULTS], capture_output=True, text=True, cwd=ROOT, env=env,
                          timeout=120, check=True)
    faults, grid = (int(word) for word in done.stdout.split())
    return faults, grid


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="mallopt is glibc's (Linux)")
def test_a_repeated_run_reuses_its_freed_memory_instead_of_faulting_it_in_again():
    # the control at glibc's own fixed threshold (128 KiB): its dynamic one depends on the heap's history
    (kept, _), (returned, grid) = _faults("64M"), _faults("0", MALLOC_MMAP_THRESHOLD_="131072")
    # the control's run allocates its output anew past the threshold, so each page of its time grid (195) at least is
    # faulted in again (587 or 392 pages in all, measured, by what else the checkout's compiled code allocates)
    assert returned >= grid >= 195
    assert kept <= 20                      # measured 0


@pytest.mark.parametrize("raw, pad", [("0", None), ("64M", 64 << 20), ("1G", 1 << 30), ("1e8", 100_000_000)])
def test_the_pad_is_read_as_a_size(monkeypatch, raw, pad):
    monkeypatch.setenv(limits.MALLOC_PAD_ENV, raw)
    calls = []
    monkeypatch.setattr(limits, "_mallopt", lambda parameter, value: calls.append((parameter, value)) or 1)
    assert limits.keep_freed_memory() is (pad is not None)
    assert calls == ([] if pad is None else [(limits._M_MMAP_THRESHOLD, 32 << 20), (limits._M_TOP_PAD, pad)])


@pytest.mark.parametrize("raw", ["2G", "abc", "-1", "nan", "1e400", "1e" + "9" * 5000])    # OverflowError, ValueError before
def test_a_bad_pad_is_a_warning_naming_the_variable_and_the_default_is_used(monkeypatch, raw):
    monkeypatch.setenv(limits.MALLOC_PAD_ENV, raw)
    calls = []
    monkeypatch.setattr(limits, "_mallopt", lambda parameter, value: calls.append((parameter, value)) or 1)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        assert limits.keep_freed_memory() is True
    assert len(caught) == 1 and str(caught[0].message).startswith(f"{limits.MALLOC_PAD_ENV} must be")
    named = repr(raw) if len(raw) <= 80 else f"...{raw[-10:]} ({len(raw)} characters)'"       # a long one shortened
    assert named in str(caught[0].message) and "using the default 64M" in str(caught[0].message)
    assert calls[-1] == (limits._M_TOP_PAD, limits.DEFAULT_MALLOC_PAD)


def test_the_command_line_says_a_bad_pad_in_one_line_and_runs():
    env = {**os.environ, limits.MALLOC_PAD_ENV: "abc"}
    done = subprocess.run([sys.executable, "-m", "validation.cli", "simulate", "buck", "--periods", "2", "--json"],
                          capture_output=True, text=True, cwd=ROOT, env=env, timeout=120)
    assert done.returncode == 0 and '"steps"' in done.stdout
    assert done.stderr == ("pcsuite: warning: PCSUITE_MALLOC_PAD must be a size in bytes such as 512M, 4G or 2e9; "
                           "got 'abc'; using the default 64M\n")
