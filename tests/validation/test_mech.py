"""pcsuite mech: list, simulate (files and JSON), bifurcations (types and values), one-line errors; the
report's cheaper sections; the two-block system's chaotic and periodic regimes."""
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
def test_two_blocks_on_a_belt_chaos_at_low_speed_periodic_above():
    from validation.mechanics import lyapunov_of_flow, two_block_diagram
    assert lyapunov_of_flow("stick-slip", {"V": 0.1}) > 0.05
    assert abs(lyapunov_of_flow("stick-slip", {"V": 0.8})) < 0.03          # a periodic orbit: the flow's zero
    rows = two_block_diagram({}, "V", [0.1, 0.8], workers=1)
    distinct = [len({round(v, 4) for v in r.states[:, 1]}) for r in rows]
    assert distinct[0] > 8 and distinct[1] == 1


@pytest.mark.slow
def test_the_agreement_and_cam_sections_pass():
    from validation.mechanics import agreement_section, cam_section
    section = agreement_section()
    assert section.ok, section.metrics
    cam = cam_section()
    assert cam.ok and "cam_impacts.png" in cam.files
    impacts = cam.metrics["impacts_per_rpm"]
    assert impacts["100"] == 0 and impacts["175"] > 0 and impacts["355"] + impacts["360"] > 0


@pytest.mark.slow
def test_complete_chattering_at_175_rpm_and_incomplete_at_358():
    """The seed's 175 rpm: each revolution's impacts accumulate (completed in closed form), the follower then
    riding the cam; Siconos' 358 rpm: impacts that never accumulate before the next lift."""
    from validation.mechanics import chattering_table
    table = chattering_table({}, [100.0, 175.0, 358.0], workers=1).set_index("rpm")
    assert table.loc[100.0, "regime"] == "no impacts"
    assert table.loc[175.0, "regime"] == "complete chattering" and table.loc[175.0, "accumulations_per_revolution"] == 1
    assert table.loc[358.0, "regime"] == "incomplete chattering" and table.loc[358.0, "impacts_per_revolution"] > 1


def test_the_two_block_sections_time_unit_is_the_one_the_code_uses(monkeypatch):
    """The report states the time unit its runs are measured in: the slower block's period, 2 pi sqrt(m1 / (k1 +
    kc)) = 4.443 s at k1 = 1 < k2 = 1.5 (it had read 2 pi sqrt(m / (k2 + kc)), block 2's 3.974 s). The diagram and
    the exponents are replaced by stand-ins: the text is what is checked."""
    import validation.mechanics as mech
    from converters.models.mechanics import get_mechanical
    monkeypatch.setattr(mech, "two_block_diagram", lambda *a, **k: [])
    monkeypatch.setattr(mech, "lyapunov_of_flow", lambda *a, **k: 0.0)
    monkeypatch.setattr("validation.mechanics_plots.diagram_figure", lambda *a, **k: b"")
    model = get_mechanical("stick-slip")
    unit = model.time_scale(model.resolve({}))
    assert unit == pytest.approx(2 * np.pi * np.sqrt(1.0 / 2.0), rel=1e-15)
    section = mech.two_block_section()
    assert f"{unit:.4g} s here, block 1's" in section.html and "k2 + kc" not in section.html


@pytest.mark.slow
def test_complete_chattering_ends_where_its_ride_left_reaches_zero():
    """The period-one complete-chattering orbit (from the detachment, its impacts accumulate, it rides the cam to the
    next detachment) ends near 253 rpm where the ride left reaches zero; located to 1e-6 rpm from the side where it
    exists, the ride shrinking linearly into it; and the attractor from rest changes regime there: every revolution
    accumulates 0.02 rpm below it, not every one 0.02 rpm above."""
    from validation.mechanics import _Chattering, chattering_transition, ride_left
    found = chattering_transition({}, 250.0, 254.0)
    assert found["side"] == "below" and found["width"] <= 1e-6 and 0.0 < found["last"]["ride"] <= 1e-6
    assert found["rpm"] == pytest.approx(252.99229, abs=2e-5)
    r1, r2 = (ride_left({}, found["rpm"] - d)["ride"] for d in (0.02, 0.01))
    assert r1 > r2 > 0.0
    assert found["rpm"] - 0.01 + r2 * 0.01 / (r1 - r2) == pytest.approx(found["rpm"], abs=1e-3)
    assert ride_left({}, found["rpm"] + 0.01)["ride"] is None
    below, above = (_Chattering({}, transient=2, record=4)(found["rpm"] + d) for d in (-0.02, 0.02))
    assert below["regime"] == "complete chattering" and below["accumulations_per_revolution"] == 1.0
    assert above["accumulations_per_revolution"] < 1.0


@pytest.mark.slow
def test_domain_of_attraction_at_A_3_6_two_converged_orbits_and_a_resolved_boundary():
    """The seed's domain of attraction (A = 3.6, omega = 1.067): every initial state of the grid reaches one of two
    period-one orbits (converged by Newton on the event method's exact map, residual below 1e-10, stable), and a
    grid twice finer changes no cell off the basin boundary."""
    from validation.mechanics import basins, resolution_check
    box = dict(params={"A": 3.6, "omega": 1.067}, x_range=(-4.0, 4.0), v_range=(-4.0, 4.0))
    coarse = basins(n=20, refine=1, backend="local", workers=2, **box)
    fine = basins(n=39, refine=1, backend="local", workers=2, **box)
    serial = basins(n=5, refine=1, backend="serial", **box)     # the backends agree, state for state
    assert (serial.labels == basins(n=5, refine=1, backend="local", workers=2, **box).labels).all()
    assert len(coarse.attractors) == 2 and (coarse.labels >= 0).all() and (fine.labels >= 0).all()
    for a in coarse.attractors:
        assert a["period"] == 1 and a["residual"] < 1e-10 and max(a["multipliers"]) < 1.0
    sticking = [a for a in coarse.attractors if a["points"][0][1] == pytest.approx(1.0, abs=1e-12)]
    assert len(sticking) == 1                       # one of them starts each period stuck to the belt (v = Vdr)
    check = resolution_check(coarse, fine)
    assert check["off_boundary"] == 0 and 0 < check["boundary_cells"] < check["cells"]
