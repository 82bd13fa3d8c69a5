"""Versions, machine and date recorded in every report header."""
from __future__ import annotations

import datetime as _dt
import os
import platform
import re
import shutil
import subprocess
from importlib import metadata


def _version(dist: str) -> str:
    try:
        return metadata.version(dist)
    except metadata.PackageNotFoundError:
        return "not installed"


def ngspice_version() -> str:
    """The system ngspice's version line (e.g. 'ngspice-39.3'), or 'not found'."""
    exe = shutil.which("ngspice")
    if exe is None:
        return "not found"
    try:
        out = subprocess.run([exe, "--version"], capture_output=True, text=True, timeout=20,
                             stdin=subprocess.DEVNULL).stdout
    except (OSError, subprocess.TimeoutExpired):
        return "not runnable"
    match = re.search(r"ngspice-[\w.+-]+", out)
    if match:
        return match.group(0)
    return out.strip().splitlines()[0] if out.strip() else "unknown"


def environment() -> dict:
    return {
        "pcsuite": _version("pcsuite"), "python": platform.python_version(), "numpy": _version("numpy"),
        "scipy": _version("scipy"), "numba": _version("numba"), "pandas": _version("pandas"),
        "PySpice": _version("PySpice"), "ngspice": ngspice_version(),
        "machine": f"{platform.node()} ({platform.machine()}, {os.cpu_count()} cores, {platform.platform()})",
        "date": _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%d %H:%M:%S UTC"),
    }
