"""pcsuite mech: list, simulate (files and JSON), bifurcations (types and values), one-line errors; the
report's cheaper sections (the studies themselves: tests/analysis/test_mechanics.py)."""
import json

import numpy as np
import pandas as pd
import pytest

from validation.cli import main


def run_cli(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def test_mech_list_names_every_model(capsys):
    code, out, _ = run_cli(capsys, "mech", "list", "--json")
    models = json.loads(out)
    assert code == 0 and set(models) == {"friction", "stick-slip", "cam-follower", "bouncing-ball"}
    assert models["cam-follower"]["parameters"]["rpm"]["default"] == 358.0


@pytest.mark.slow
def test_mech_simulate_writes_the_trajectory(capsys, tmp_path):
    target = tmp_path / "f.parquet"
    code, out, _ = run_cli(capsys, "mech", "simulate", "cam-follower", "-p", "rpm=358", "--out", str(target))
    assert code == 0 and "wrote" in out
    frame = pd.read_parquet(target)
    assert list(frame.columns) == ["time", "x", "v", "gap_cam", "force_cam", "mode"]
    assert frame["gap_cam"].min() > -1e-9 and set(frame["mode"]) <= {"contact", "flight"}
    code, out, _ = run_cli(capsys, "mech", "simulate", "friction", "-p", "A=5", "-p", "omega=2.5", "--method", "moreau",
                           "--json")
    summary = json.loads(out)
    assert code == 0 and summary["method"] == "moreau" and summary["events"]["stick"] >= 19


@pytest.mark.slow
def test_mech_bifurcations_lists_the_sliding_bifurcations_with_type_and_value(capsys):
    code, out, _ = run_cli(capsys, "mech", "bifurcations", "friction", "-p", "A=5", "--param", "omega=2.75:2.85",
                           "--json")
    result = json.loads(out)
    assert code == 0
    kinds = [(b["type"], b["value"]) for b in result["bifurcations"]]
    assert [k for k, _ in kinds] == ["switching-sliding"]
    assert kinds[0][1] == pytest.approx(2.7992, rel=5e-3)
    assert result["bifurcations"][0]["sliding"] and result["branches"][0]["complete"]


@pytest.mark.parametrize("argv, message", [
    (["simulate", "pendulum"], "MODEL must be one of friction, stick-slip, cam-follower, bouncing-ball; got 'pendulum'"),
    (["simulate", "friction", "-p", "A=-1"], "A (forcing amplitude) must be in [0, inf) N; got -1"),
    (["simulate", "friction", "--h", "1"], "h must be in (0,"),
    (["simulate", "friction", "--out", "x.txt"], "--out must end in .csv or .parquet"),
    (["bifurcations", "bouncing-ball", "--param", "e=0.1:0.5"], "the bouncing ball on a fixed floor has no bifurcations to follow"),
    (["bifurcations", "friction", "--param", "omega=-1:3"], "the path of omega must lie in (0, inf)"),
    (["bifurcations", "friction", "--param", "zeta=1:2"], "--param must name a parameter of friction"),
    (["bifurcations", "cam-follower", "--param", "k=100:200"], "the cam-follower's diagram is against rpm"),
    (["bifurcations", "friction", "--param", "omega=2:3", "--diagram", "d.txt"], "--diagram must end in .png or .svg"),
])
def test_bad_input_gets_one_clear_line(capsys, argv, message):
    code, out, err = run_cli(capsys, "mech", *argv)
    assert code == 2 and out == "" and err.count("\n") == 1 and message in err


@pytest.mark.slow
def test_the_agreement_and_cam_sections_pass():
    from validation.mechanics import agreement_section, cam_section
    section = agreement_section()
    assert section.ok, section.metrics
    cam = cam_section()
    assert cam.ok and "cam_impacts.png" in cam.files
    impacts = cam.metrics["impacts_per_rpm"]
    assert impacts["100"] == 0 and impacts["175"] > 0 and impacts["355"] + impacts["360"] > 0


def test_the_two_block_sections_time_unit_is_the_one_the_code_uses(monkeypatch):
    """The report states the time unit its runs are measured in: the slower block's period, 2 pi sqrt(m1 / (k1 +
    kc)) = 4.443 s at k1 = 1 < k2 = 1.5 (it had read 2 pi sqrt(m / (k2 + kc)), block 2's 3.974 s). The diagram and
    the exponents are replaced by stand-ins: the text is what is checked."""
    import validation.mechanics as mech
    from converters.models.mechanics import get_mechanical
    monkeypatch.setattr(mech, "two_block_diagram", lambda *a, **k: [])
    monkeypatch.setattr("converters.parallel.parallel_map", lambda task, values, **k: [
        {"V": V, "regime": "periodic", "period": 1, "closing": (1e-12, 1e-12), "lyapunov": 0.0, "half_width": 0.01,
         "sections": 400} for V in values])
    monkeypatch.setattr("validation.mechanics_plots.diagram_figure", lambda *a, **k: b"")
    model = get_mechanical("stick-slip")
    unit = model.time_scale(model.resolve({}))
    assert unit == pytest.approx(2 * np.pi * np.sqrt(1.0 / 2.0), rel=1e-15)
    section = mech.two_block_section()
    assert f"{unit:.4g} s here, block 1's" in section.html and "k2 + kc" not in section.html


def test_the_two_block_section_fails_where_a_regime_is_undetermined(monkeypatch):
    """The section passes on physics, not on the absence of errors: one velocity whose states neither close into a
    cycle nor have an exponent above zero fails it (stand-ins for the runs)."""
    import validation.mechanics as mech
    monkeypatch.setattr(mech, "two_block_diagram", lambda *a, **k: [])
    monkeypatch.setattr("validation.mechanics_plots.diagram_figure", lambda *a, **k: b"")

    def regimes(kind):
        return lambda task, values, **k: [{"V": V, "regime": kind if V == values[0] else "periodic", "period": 1,
                                           "closing": (1e-12, 1e-12), "lyapunov": 0.0, "half_width": 0.01,
                                           "sections": 400} for V in values]
    monkeypatch.setattr("converters.parallel.parallel_map", regimes("chaotic"))
    assert mech.two_block_section().ok
    monkeypatch.setattr("converters.parallel.parallel_map", regimes("undetermined"))
    section = mech.two_block_section()
    assert not section.ok and "undetermined" in section.html




def test_a_study_imported_from_its_old_place_still_works_with_a_warning_naming_the_new_one():
    """The studies moved to converters.analysis.mechanics; validation.mechanics keeps the report's sections."""
    import validation.mechanics as sections
    from converters.analysis.mechanics import chattering_orbit
    with pytest.warns(DeprecationWarning, match="converters.analysis.mechanics.chattering_orbit"):
        assert sections.chattering_orbit is chattering_orbit
    with pytest.raises(AttributeError):
        sections.no_such_study
