"""`pcsuite simulate netlists/circuits/sync-buck-thermal.cir --steady --json`: each device's losses by kind, its
junction temperature, and a power balance that closes."""
import json
from pathlib import Path

import pytest

from validation.cli import main

NETLIST = Path(__file__).resolve().parents[2] / "netlists" / "circuits" / "sync-buck-thermal.cir"


def _run(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def test_the_shipped_thermal_example_gives_losses_junction_temperatures_and_a_balance_that_closes(capsys):
    code, out, err = _run(capsys, "simulate", str(NETLIST), "--steady", "--json")
    assert code == 0, err
    thermal = json.loads(out)["thermal"]
    devices, power = thermal["devices"], thermal["power"]
    assert set(devices) == {"s1", "s2", "d1", "d2"}
    s1, s2, d2 = devices["s1"], devices["s2"], devices["d2"]
    # the high side switches hard (both edges at 48 V), the low side at zero voltage (its body diode conducts
    # first), the low side's body diode recovers when the high side turns on
    assert s1["turn_on_W"] > 0.1 and s1["turn_off_W"] > 0.1 and s2["turn_on_W"] == s2["turn_off_W"] == 0.0
    assert d2["recovery_W"] > 0.05 and devices["d1"]["total_W"] == 0.0
    # the conduction losses: R_on(T_j) I_rms^2, the tables linear in current (8 mohm at 25, 12 mohm at 125 degC)
    r_on = 0.008 + 0.004 * (s2["tj_C"] - 25.0) / 100.0
    assert s2["conduction_W"] == pytest.approx(r_on * json.loads(out)["measurements"]["i(s2)"]["rms"] ** 2, rel=1e-6)
    # steady state: T_j = T_a + R_ha sum P + (R_ch + R_jc) P, to 0.1 K (the fixed point's own tolerance is 1e-6 K)
    total = sum(d["total_W"] for d in devices.values())
    for d in devices.values():
        assert d["tj_C"] == pytest.approx(40.0 + 2.0 * total + (0.5 + 1.0) * d["total_W"], abs=1e-5)
    assert power["output_W"] == pytest.approx(12.0 ** 2 / 1.2, rel=1e-3)
    assert power["device_losses_W"] == pytest.approx(total, rel=1e-12)
    assert abs(power["balance_W"]) <= 1e-5 * power["input_W"]
    assert power["efficiency"] == pytest.approx(power["output_W"] / (power["output_W"] + total), rel=1e-5)


@pytest.mark.parametrize("argv, message", [
    (["--thermal", "x.toml"], "--thermal reads the losses of the periodic steady state: give --steady"),
    (["--steady", "--thermal", "nosuch.toml"], "cannot read the thermal setup nosuch.toml"),
])
def test_a_thermal_setup_that_cannot_apply_is_refused_in_one_line(capsys, argv, message):
    code, out, err = _run(capsys, "simulate", str(NETLIST.with_name("sync-buck.cir")), *argv)
    assert code == 2 and out == "" and err.count("\n") == 1 and message in err


def test_a_setup_that_names_no_device_of_the_circuit_is_refused_by_name(capsys, tmp_path):
    setup = tmp_path / "setup.toml"
    setup.write_text(NETLIST.with_name("sync-buck-thermal.toml").read_text().replace("[devices.d2]", "[devices.q9]")
                     .replace('"example-', f'"{NETLIST.parent.as_posix()}/example-'))
    code, out, err = _run(capsys, "simulate", str(NETLIST), "--steady", "--thermal", str(setup))
    assert code == 2 and "names 'q9', which is no switch (S) or diode (D) of the circuit" in err


def test_a_sweep_point_gives_the_losses_and_temperatures_simulate_gives_there():
    """The thermal metrics of a sweep row (its one period run from the orbit: the high side's turn-on is the edge at
    the period's bound) against simulate's summary at the same step."""
    from converters.models import get_model
    from converters.run import run_converter
    from converters.sweeps import ModelSweep
    from converters.thermal.network import declared_setup, read_setup
    from converters.thermal.summary import thermal_summary
    metrics = ("thermal.efficiency", "thermal.losses_W", "tj.max", "tj.s1", "loss.s1", "loss.d2")
    row = ModelSweep(str(NETLIST), h_fraction=1e-3, metrics=metrics).row(0, {})
    assert row["status"] == "ok", row["message"]
    model = get_model(str(NETLIST))
    p = model.resolve({})
    tr = run_converter(model, p, steady=True)
    summary = thermal_summary(model, p, tr, read_setup(declared_setup(model.netlist.text, model.source)))
    expected = {"thermal.efficiency": summary["power"]["efficiency"],
                "thermal.losses_W": summary["power"]["device_losses_W"],
                "tj.max": max(d["tj_C"] for d in summary["devices"].values()), "tj.s1": summary["devices"]["s1"]["tj_C"],
                "loss.s1": summary["devices"]["s1"]["total_W"], "loss.d2": summary["devices"]["d2"]["total_W"]}
    for name, value in expected.items():
        assert row[name] == pytest.approx(value, rel=1e-6), name
    assert summary["devices"]["s1"]["turn_on_W"] > 0.3              # the edge the one-period run starts on


def test_a_thermal_metric_on_a_circuit_without_a_setup_is_refused_by_name():
    from converters.errors import ParameterError
    from converters.sweeps import ModelSweep
    with pytest.raises(ParameterError, match="need a netlist that names its thermal setup"):
        ModelSweep(str(NETLIST.with_name("sync-buck.cir")), metrics=("tj.max",))
    with pytest.raises(ParameterError, match="the thermal setup's devices are s1, s2, d1, d2"):
        ModelSweep(str(NETLIST), metrics=("tj.q7",))


@pytest.mark.slow
def test_the_reports_thermal_section_passes_its_checks_and_draws_its_maps():
    """The stepper's losses against the exact method's (a second resolution) within 1e-3 of the total, the balance
    within 1e-5, the temperatures on their closed form; 49 points of the efficiency map."""
    from validation.thermal import thermal_section
    section = thermal_section()
    assert section.ok, section.html[:2000]
    assert {"thermal_losses.png", "thermal_efficiency_map.png", "thermal_efficiency_map.csv"} <= set(section.files)
    assert section.metrics["efficiency"] == pytest.approx(0.98389, abs=1e-4)
    assert section.files["thermal_efficiency_map.csv"].decode().count("\n") == 50


def test_a_netlists_sweep_without_out_writes_its_folder_by_the_files_stem(capsys, tmp_path, monkeypatch):
    """The default folder of a netlist's sweep is sweep-STEM in the current directory (it had been
    sweep-netlists/circuits/NAME.cir/, folders nested from the path)."""
    monkeypatch.chdir(tmp_path)
    code, out, err = _run(capsys, "sweep", str(NETLIST), "--grid", "Vin=40:48:2", "--steady", "--metric", "tj.max",
                          "--no-progress", "--workers", "1")
    assert code == 0, err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["sweep-sync-buck-thermal"]


def _losses(capsys, *argv):
    code, out, err = _run(capsys, "simulate", str(NETLIST), "--steady", "--json", *argv)
    assert code == 0, err
    return json.loads(out)["thermal"]


@pytest.mark.parametrize("h", [None, "5e-8", "1e-7"])      # the default T/1000; a dead time (5e-8) of 1 and 1/2 step
def test_the_losses_error_estimate_bounds_their_error_against_the_exact_method(capsys, h):
    """The estimate sums the devices' absolute errors (none cancels another), each from the orbit at h against 2h,
    which is (2^p - 1) times the error at h for an order p: 3 times at the second order the stepper now reaches
    (1.7e-10, 4.2e-9 and 1.7e-8 of the total summed; 2.5e-6, 6.3e-5 and 6.3e-5 when the step after each switching
    edge started from the pair solved a step later, the idle body diode's -0.011 A among them). Before the
    shortest interval's rule the estimate looked below one step's dead time: at 1e-7 it said 2.5e-8."""
    exact = _losses(capsys, "--method", "event")
    thermal = _losses(capsys, *(["--h", h] if h else []))
    total = exact["power"]["device_losses_W"]
    errors = {d: abs(v["total_W"] - exact["devices"][d]["total_W"]) for d, v in thermal["devices"].items()}
    estimates = thermal["accuracy"]["device_error_W"]
    assert sum(errors.values()) / total <= thermal["accuracy"]["losses_error_estimate"]
    for device, error in errors.items():
        assert error <= estimates[device] <= 3.2 * error + 1e-12 * total, device


@pytest.mark.slow
def test_the_losses_error_estimate_comes_from_the_exact_orbit_where_the_steps_cannot_be_trusted(capsys, tmp_path):
    """A 1 ohm, 100 pF snubber on the switch node: its 100 ps make the default backward Euler at 10 ns, which damps
    the 3.39 MHz ring (Q 469) 98 times faster than the circuit does, and d2 starts conducting inside the first step
    after the switching; the orbits at h and 2h both miss it, and d2's loss was stated 2.1e-5 W for a 9.1e-5 W
    error (4.3x short). The estimate now is each device's distance from the exact method's orbit (at the same
    junction temperatures: within 2 % of the error against the exact run, whose own are a few mK apart). At its
    defaults simulate then answers with the exact run itself."""
    for name in ("sync-buck-thermal.cir", "sync-buck-thermal.toml", "example-mosfet.toml", "example-body-diode.toml"):
        text = (NETLIST.parent / name).read_text()
        if name.endswith(".cir"):
            text = text.replace("R1 out 0 {R}\n", "R1 out 0 {R}\nRsn sw sn 1\nCsn sn 0 100p\n")
        (tmp_path / name).write_text(text)
    # (--theta 1 as the default chooses it: given, the stepper's run is kept, not replaced by the exact one)
    code, out, err = _run(capsys, "simulate", str(tmp_path / "sync-buck-thermal.cir"), "--steady", "--json",
                          "--theta", "1")
    assert code == 0, err
    thermal = json.loads(out)["thermal"]
    code, out, err = _run(capsys, "simulate", str(tmp_path / "sync-buck-thermal.cir"), "--steady", "--json",
                          "--method", "event")
    exact = json.loads(out)["thermal"]
    assert thermal["accuracy"]["estimated_by"] == "the exact (event) method's orbit"
    for device in ("s1", "s2", "d2"):
        error = abs(thermal["devices"][device]["total_W"] - exact["devices"][device]["total_W"])
        assert error > 2e-5 and thermal["accuracy"]["device_error_W"][device] == pytest.approx(error, rel=2e-2)
