"""Every file a command writes is readable by group and others under umask 022 (mkstemp and mkdtemp would
make them 0600 and 0700), directories listable too."""
import os
import stat

import pytest

from validation.cli import main


@pytest.fixture
def umask_022():
    previous = os.umask(0o022)
    yield
    os.umask(previous)


def _unreadable(root):
    bad = []
    for path in [root, *root.rglob("*")]:
        mode = stat.S_IMODE(path.stat().st_mode)
        need = 0o055 if path.is_dir() else 0o044
        if mode & need != need:
            bad.append(f"{path.relative_to(root.parent)} {oct(mode)}")
    return bad


def test_every_command_writes_files_others_can_read(tmp_path, capsys, umask_022, ngspice):
    out = tmp_path / "out"
    out.mkdir()
    runs = [
        ["simulate", "buck", "--periods", "5", "--out", str(out / "w.csv")],
        ["simulate", "buck", "--periods", "5", "--out", str(out / "w.parquet")],
        ["compare", "buck", "--plot", str(out / "compare.png")],
        ["sweep", "buck", "--grid", "D=0.3:0.6:3", "--steady", "--no-progress", "--out", str(out / "sweep")],
        ["gdcm-map", "buck", "--size", "3", "3", "--no-spice", "--out", str(out / "map")],
        ["bifurcation", "buck", "--control", "voltage-mode", "--param", "Vin=20:26", "--points", "12",
         "--transient", "20", "--record", "8", "--max-period", "2", "--diagram", str(out / "diagram.png")],
        ["mech", "simulate", "bouncing-ball", "--t-end", "0.5", "--out", str(out / "ball.csv")],
        ["report", "lcp", "--out", str(out / "report")],
    ]
    for argv in runs:
        assert main(argv) == 0, argv
        capsys.readouterr()
    written = sorted(p.name for p in out.iterdir())
    assert written == ["ball.csv", "ball.csv.json", "compare.png", "diagram.png", "map", "report", "sweep", "w.csv",
                       "w.csv.json", "w.parquet"]
    assert _unreadable(out) == []


def test_waveform_files_carry_their_metadata_and_units(tmp_path, capsys):
    import json

    import pyarrow.parquet as pq
    assert main(["simulate", "buck", "-p", "L=22uH", "--periods", "5", "--out", str(tmp_path / "w.parquet")]) == 0
    meta = json.loads(pq.read_schema(tmp_path / "w.parquet").metadata[b"pcsuite"])
    assert meta["converter"] == "buck" and meta["method"] == "lcp" and meta["options"]["params"]["L"] == 22e-6
    assert meta["units"] == {"time": "s", "iL": "A", "vC": "V", "vout": "V", "switch": "1", "i_in": "A",
                             "i_switch": "A", "v_switch": "V", "i_diode": "A", "v_diode": "V", "i_cap": "A", "mode": ""}
    assert main(["simulate", "buck", "--periods", "5", "--out", str(tmp_path / "w.csv")]) == 0
    sidecar = json.loads((tmp_path / "w.csv.json").read_text())
    assert sidecar["converter"] == "buck" and sidecar["units"]["iL"] == "A"
