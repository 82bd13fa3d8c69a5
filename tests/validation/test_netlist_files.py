"""The standard netlists in netlists/*.cir: what the builder makes, run by ngspice on its own (``ngspice -b``),
their .meas mean of vout the same as ``pcsuite simulate --method spice`` on the same circuit."""
import json
import re
import shutil
import subprocess
from pathlib import Path

import pytest

from netlists import standard_netlist
from netlists.build import STANDARD_PERIODS
from validation.cli import main

DIRECTORY = Path(__file__).resolve().parents[2] / "netlists"
CONVERTERS = ("buck", "boost", "buck-boost", "cuk", "prc")


@pytest.mark.parametrize("name", CONVERTERS)
def test_each_shipped_netlist_is_what_the_builder_makes(name):
    assert (DIRECTORY / f"{name}.cir").read_text() == standard_netlist(name), "run: python -m netlists"


@pytest.mark.parametrize("name", CONVERTERS)
def test_ngspice_runs_the_file_alone_and_its_meas_mean_is_pcsuites(name, ngspice, tmp_path, capsys):
    binary = shutil.which("ngspice")
    out = subprocess.run([binary, "-b", str(DIRECTORY / f"{name}.cir")], capture_output=True, text=True, timeout=300,
                         cwd=tmp_path)
    assert out.returncode == 0, out.stderr[-2000:]
    meas = {m.group(1).lower(): float(m.group(2))
            for m in re.finditer(r"^(\w+)\s*=\s*([-+0-9.eE]+)\s+from=", out.stdout, re.MULTILINE)}
    assert {"vout_mean", "vout_ripple"} <= set(meas), out.stdout[-2000:]
    assert meas["vout_ripple"] > 0
    assert main(["simulate", name, "--method", "spice", "--periods", str(STANDARD_PERIODS), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["window_periods"] == 10
    assert meas["vout_mean"] == pytest.approx(summary["vout_mean"], rel=1e-5)      # measured <= 1.3e-7 (7 digits)
