"""The package as a user gets it: the sdist, a wheel built from it and one from the source tree (``python -m
build``; the latter is what ``pip install .`` makes), that wheel installed into a fresh venv (not editable: only what
the wheel holds is there), and ``pcsuite`` run from a directory outside the checkout. Every file the packages read
at run time must ship (defaults.toml, the scenes, the Siconos collection, the C source of solve_lcp's entry point the
ahead-of-time build compiles), and the install must work with numba's JIT alone, after ``python -m
converters.build_kernels`` in site-packages, and from a read-only site-packages.

1.5 to 3 minutes on two busy cores: the builds 11 s, the fresh venv and its install 25 s (the dependencies come
from pip's cache, which ``make setup`` filled), the ahead-of-time build 45-75 s, each first JIT run 6 s. ``make
package-check`` runs this file alone."""
from __future__ import annotations

import json
import math
import os
import shutil
import subprocess
import sys
import tarfile
import tomllib
import zipfile
from pathlib import Path

import pytest

pytestmark = [pytest.mark.slow, pytest.mark.package]

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("converters", "validation", "netlists")
#: Files made by builds and runs, never shipped (the ahead-of-time module is built for one machine's CPU).
BUILT = (".pyc", ".nbi", ".nbc", ".so", ".pyd")
#: The ahead-of-time module and its record (converters.compiled).
KERNEL_FILES = ("_kernels",)
LCP_FILE = "lcp_ortiz.dat"                 # k = 4, solved by Lemke: more than a closed form
#: The checkout's own pcsuite (the editable install running these tests): the numbers the wheel must give.
HERE = [sys.executable, "-m", "validation.cli"]


def _run(args, timeout=900, **kwargs) -> subprocess.CompletedProcess:
    result = subprocess.run([str(a) for a in args], capture_output=True, text=True, timeout=timeout, **kwargs)
    assert result.returncode == 0, (f"{' '.join(map(str, args))} exited {result.returncode}\n"
                                    f"stdout: {result.stdout[-3000:]}\nstderr: {result.stderr[-3000:]}")
    return result


def _source_files() -> list[str]:
    """The checkout's files as a fresh clone has them, with the working tree's edits (tracked and new files, not
    what .gitignore leaves out: no .venv, no built kernels, no stale build/ or egg-info)."""
    listed = _run(["git", "-C", ROOT, "ls-files", "-z", "--cached", "--others", "--exclude-standard"]).stdout
    return sorted(name for name in listed.split("\0") if name and (ROOT / name).is_file())


def _is_built(name: str) -> bool:
    return name.endswith(BUILT) or Path(name).name.split(".")[0] in KERNEL_FILES


def _built_kernels(root: Path) -> list[Path]:
    return sorted(p for p in (root / "converters").iterdir() if p.is_file() and _is_built(p.name))


def _package_data(files) -> set[str]:
    """The non-Python files inside the packages: what the code reads beside itself (or ships as reference)."""
    return {name for name in files if name.split("/")[0] in PACKAGES and not name.endswith(".py")
            and not _is_built(name)}


@pytest.fixture(scope="module")
def dist(tmp_path_factory):
    """(sdist, the wheel built from it, the wheel built from the source tree, the source files): from a copy of
    the checkout."""
    files = _source_files()
    tmp = tmp_path_factory.mktemp("package")
    source = tmp / "src"
    for name in files:
        (source / name).parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(ROOT / name, source / name)
    for path in _built_kernels(ROOT):      # as in a checkout after make setup: `pip install .` must leave them out
        shutil.copy2(path, source / path.relative_to(ROOT))
    _run([sys.executable, "-m", "build", "--outdir", tmp / "dist", source])             # the wheel from the sdist
    _run([sys.executable, "-m", "build", "--wheel", "--outdir", tmp / "direct", source])  # as `pip install .`
    sdist, = (tmp / "dist").glob("pcsuite-*.tar.gz")
    wheel, = (tmp / "dist").glob("pcsuite-*.whl")
    direct, = (tmp / "direct").glob("pcsuite-*.whl")
    return sdist, wheel, direct, files


@pytest.fixture(scope="module")
def installed(dist, tmp_path_factory):
    """(the fresh venv's bin directory, a working directory outside the checkout, the environment to run in)."""
    tmp = tmp_path_factory.mktemp("installed")
    _run([sys.executable, "-m", "venv", tmp / "venv"])
    bin_dir = tmp / "venv" / "bin"
    _run([bin_dir / "python", "-m", "pip", "install", "-q", "-c", ROOT / "constraints.txt", dist[2]])
    elsewhere = tmp / "elsewhere"
    elsewhere.mkdir()
    env = {k: v for k, v in os.environ.items()
           if k not in ("PYTHONPATH", "VIRTUAL_ENV", "NUMBA_CACHE_DIR") and not k.startswith("PCSUITE_")}
    return bin_dir, elsewhere, env


def test_the_sdist_and_the_wheel_hold_every_file_the_packages_read(dist):
    sdist, wheel, direct, files = dist
    data = _package_data(files)
    assert {"validation/data/defaults.toml", "netlists/circuits/buck.cir"} <= data
    with tarfile.open(sdist) as archive:
        prefix = archive.getnames()[0].split("/")[0] + "/"
        in_sdist = {name.removeprefix(prefix) for name in archive.getnames()}
    with zipfile.ZipFile(wheel) as archive:
        in_wheel = set(archive.namelist())
        metadata = archive.read(next(n for n in in_wheel if n.endswith(".dist-info/METADATA"))).decode()
    with zipfile.ZipFile(direct) as archive:
        assert set(archive.namelist()) == in_wheel
    modules = {name for name in files if name.split("/")[0] in PACKAGES and name.endswith(".py")}
    for kind, members in (("sdist", in_sdist), ("wheel", in_wheel)):
        missing = sorted((data | modules) - members)
        assert not missing, f"the {kind} lacks {missing}"
        built = sorted(name for name in members if _is_built(name))
        assert not built, f"the {kind} holds {built}, built for one machine"
    # tomllib (3.11) is imported by validation.defaults and validation.scenes
    assert "Requires-Python: >=3.11" in metadata.splitlines()
    assert tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["requires-python"] == ">=3.11"


def test_the_installed_wheel_runs_from_anywhere_with_the_jit_and_then_ahead_of_time(installed):
    bin_dir, elsewhere, env = installed
    python, pcsuite = bin_dir / "python", bin_dir / "pcsuite"
    site = Path(_run([python, "-c", "import validation, sys; print(validation.__file__)"], cwd=elsewhere,
                     env=env).stdout.strip()).parents[1]
    assert site.is_relative_to(bin_dir.parent) and not site.is_relative_to(ROOT)

    listing = json.loads(_run([pcsuite, "list", "--json"], cwd=elsewhere, env=env).stdout)
    assert "buck" in listing["converters"]
    assert len(listing["scenes"]) == len(list((ROOT / "validation" / "scenes").glob("*.toml")))

    here = json.loads(_run([*HERE, "simulate", "buck", "--json"], cwd=elsewhere).stdout)
    jit = json.loads(_run([pcsuite, "simulate", "buck", "--json"], cwd=elsewhere, env=env).stdout)
    assert math.isfinite(jit["vout_mean"]) and 0 < jit["vout_mean"] < 12.0     # a buck from 12 V
    assert jit["vout_mean"] == here["vout_mean"]

    source = "from converters import compiled; print(compiled.source())"
    assert _run([python, "-c", source], cwd=elsewhere, env=env).stdout.startswith("jit: ")
    _run([python, "-m", "converters.build_kernels"], cwd=elsewhere, env=env)      # compiles lcp/_fast.c too
    assert _run([python, "-c", source], cwd=elsewhere, env=env).stdout.strip() == "ahead-of-time"
    ahead = json.loads(_run([pcsuite, "simulate", "buck", "--json"], cwd=elsewhere, env=env).stdout)
    assert ahead["vout_mean"] == jit["vout_mean"]

    problem = site / "validation" / "data" / "siconos-lcp" / LCP_FILE
    solved = json.loads(_run([pcsuite, "lcp", "solve", problem, "--json"], cwd=elsewhere, env=env).stdout)
    shipped = ROOT / "validation" / "data" / "siconos-lcp" / LCP_FILE
    reference = json.loads(_run([*HERE, "lcp", "solve", shipped, "--json"]).stdout)
    assert solved["status"] == "solved" and solved["err"] <= 1e-10
    assert (solved["method"], solved["z"], solved["w"]) == (reference["method"], reference["z"], reference["w"])

    netlist = site / "netlists" / "circuits" / "buck.cir"              # a shipped netlist, compiled by the wheel
    exact = ["--steady", "--method", "event", "--json"]
    compiled = json.loads(_run([pcsuite, "simulate", netlist, *exact], cwd=elsewhere, env=env).stdout)
    built_in = json.loads(_run([pcsuite, "simulate", "buck", *exact], cwd=elsewhere, env=env).stdout)
    assert compiled["vout_mean"] == pytest.approx(built_in["vout_mean"], rel=1e-9)


def _read_only(site: Path, args) -> list:
    """``args`` run with ``site`` mounted read-only (root writes anywhere else: a mount namespace of their own)."""
    mount = 'mount --bind "$0" "$0" && mount -o remount,bind,ro "$0" && exec "$@"'
    return ["unshare", "--mount", "sh", "-c", mount, site, *args]


def test_a_read_only_install_runs_with_the_jit_and_the_ahead_of_time_build_says_why_it_cannot(installed, tmp_path):
    """A site-packages the user cannot write (a system-wide install): numba caches in the user's cache directory,
    converters.kernel_cache leaves the tree alone, and the ahead-of-time build fails with one line, exit 1."""
    if shutil.which("unshare") is None or subprocess.run(["unshare", "--mount", "true"],
                                                         capture_output=True).returncode != 0:
        pytest.skip("mounting site-packages read-only needs unshare --mount (root)")
    bin_dir, elsewhere, env = installed
    python, pcsuite = bin_dir / "python", bin_dir / "pcsuite"
    site = Path(_run([python, "-c", "import validation; print(validation.__file__)"], cwd=elsewhere,
                     env=env).stdout.strip()).parents[1]
    env = {**env, "XDG_CACHE_HOME": str(tmp_path / "cache"), "PCSUITE_KERNELS": "jit"}

    probe = subprocess.run(_read_only(site, [python, "-c", f"open({str(site / 'probe')!r}, 'w')"]),
                           capture_output=True, text=True)
    assert probe.returncode != 0 and "Read-only file system" in probe.stderr, probe.stderr

    here = json.loads(_run([*HERE, "simulate", "buck", "--json"], cwd=elsewhere).stdout)
    jit = json.loads(_run(_read_only(site, [pcsuite, "simulate", "buck", "--json"]), cwd=elsewhere, env=env).stdout)
    assert jit["vout_mean"] == here["vout_mean"]
    assert list((tmp_path / "cache" / "numba").glob("*/*.nbc"))          # numba's user-wide cache took the kernels

    build = subprocess.run(_read_only(site, [python, "-m", "converters.build_kernels", "--force"]), cwd=elsewhere,
                           env=env, capture_output=True, text=True, timeout=900)
    assert build.returncode == 1, build.stderr
    assert "Traceback" not in build.stderr
    assert build.stderr.startswith("ahead-of-time kernels not built (OSError: [Errno 30] Read-only file system")
    assert build.stderr.rstrip().endswith("numba compiles them on first use instead")
