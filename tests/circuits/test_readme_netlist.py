"""The README's own-circuit example runs as printed (its netlist block taken from the README itself)."""
import json
from pathlib import Path

import pytest

from validation.cli import main

README = Path(__file__).resolve().parents[2] / "README.md"


def test_the_readmes_netlist_runs_and_gives_the_bucks_ccm_mean(tmp_path, capsys):
    text = README.read_text()
    start = text.index("Buck 48 V -> 12 V\n")
    path = tmp_path / "buck48.cir"
    path.write_text(text[start:text.index("```", start)])
    assert main(["simulate", str(path), "-p", "D=0.3", "--steady", "--method", "event", "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["vout_mean"] == pytest.approx(0.3 * 48, rel=2e-3)        # CCM: D Vin (the 1 ps edges aside)
    assert {"v(out)", "i(l1)", "i(d1)"} <= set(summary["measurements"])
    assert set(summary["mode_fractions"]) == {"S1", "D1"}
