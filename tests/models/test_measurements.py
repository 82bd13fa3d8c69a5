"""Measurements of a run: every signal's mean, RMS, min, max and ripple; the element currents and voltages;
each parasitic's loss and the efficiency, against closed forms and the energy balance on the exact orbit."""
import math
from dataclasses import replace

import numpy as np
import pytest

from converters.methods import EventDriven
from converters.models import get_model
from converters.run import run_converter, steady_state
from converters.simulate import simulate


def _exact_period(name, params, samples=20000):
    model = get_model(name)
    p = model.resolve(params)
    T = model.period(p)
    orbit = steady_state(model, p, EventDriven(), tol=1e-11)
    tr = replace(simulate(model.problem(p, T, orbit.x0), EventDriven(output_step=T / samples)), labels=model.labels(p))
    return model, p, T, tr


def test_the_ccm_bucks_ripple_and_inductor_rms_match_their_closed_forms():
    """12 V -> 6 V, 100 uH, 100 uF, 5 ohm, 100 kHz: Delta_i = (Vin - Vout) D T / L = 0.3 A, the output
    ripple Delta_i / (8 f C) = 3.75 mV (measured 2.6e-4 off), the inductor RMS sqrt(I^2 + Delta_i^2 / 12)
    (measured 1.3e-6 off); the acceptance bounds are 1 % and 0.1 %."""
    model, p, T, tr = _exact_period("buck", {"L": "100u", "C": "100u", "R": 5, "D": 0.5})
    table = tr.measurements(t0=0.0, t1=T)
    delta_i = (12.0 - 6.0) * 0.5 * T / 100e-6
    assert table.loc["iL", "ripple"] == pytest.approx(delta_i, rel=1e-3)
    assert table.loc["vout", "ripple"] == pytest.approx(delta_i / (8 * 100e3 * 100e-6), rel=1e-2)
    current = table.loc["vout", "mean"] / 5.0
    assert table.loc["iL", "rms"] == pytest.approx(math.sqrt(current ** 2 + delta_i ** 2 / 12), rel=1e-3)
    assert table.loc["iL", "unit"] == "A" and table.loc["vout", "unit"] == "V"
    assert list(table.columns) == ["unit", "mean", "rms", "min", "max", "ripple"]


PARASITIC = {"rL": 0.05, "Ron": 0.02, "Vf": 0.4, "Rd": 0.01, "rC": 0.03}


@pytest.mark.parametrize("name", ["buck", "boost", "buck-boost"])
@pytest.mark.parametrize("load", [10, 200], ids=["ccm", "dcm"])
@pytest.mark.parametrize("io", [None, 0.2], ids=["R", "R+Io"])
def test_input_power_is_output_power_plus_the_element_losses_on_the_exact_orbit(name, load, io):
    """With a load current Io beside R too: vout through the ESR carries what reaches the output node less what both
    loads draw, and the output power is vout^2 / R + Io vout."""
    given = {**PARASITIC, "R": load} if io is None else {**PARASITIC, "R": load, "Io": io}
    model, p, T, tr = _exact_period(name, given, samples=1000)
    power = model.power(tr, p, 0.0, T)
    assert abs(power["balance"]) <= 1e-6, power          # measured <= 4e-12
    assert set(power["losses_W"]) == set(PARASITIC) and all(v > 0 for v in power["losses_W"].values())
    assert 0.8 < power["efficiency"] < 1.0
    # the diode's conduction loss is its forward drop times its mean current
    assert power["losses_W"]["Vf"] == pytest.approx(0.4 * tr.mean("i_diode", t0=0.0, t1=T), rel=1e-12)


CUK_PARASITIC = {"rL1": 0.05, "rL2": 0.1, "Ron": 0.02, "Vf": 0.4, "Rd": 0.01}


@pytest.mark.parametrize("load", [10, 50], ids=["ccm", "gdcm"])
def test_the_cuks_parasitic_losses_close_the_energy_balance(load):
    """The Cuk takes its inductors' DCR (rL1, rL2), the switch's Ron and the diode's Vf and Rd (-p rL=... is
    refused with the valid names); input = output + losses to 1.3e-13 measured."""
    model, p, T, tr = _exact_period("cuk", {**CUK_PARASITIC, "R": load, "L1": "10u", "L2": "10u"}, samples=1000)
    power = model.power(tr, p, 0.0, T)
    assert abs(power["balance"]) <= 1e-6 and set(power["losses_W"]) == set(CUK_PARASITIC)
    assert 0.85 < power["efficiency"] < 0.97
    from converters.errors import ParameterError
    with pytest.raises(ParameterError, match="unknown parameter 'rL' for cuk; valid names: .*rL1, rL2"):
        model.resolve({"rL": 0.1})


@pytest.mark.parametrize("name,load", [("buck", 2.4), ("boost", 10)])
def test_the_trapezoidal_steppers_power_converges_at_second_order_in_ccm(name, load):
    """theta = 0.5 integrates its samples by the linear rule; a switch current that jumps to zero at an edge was
    integrated over half the step after it, a first-order error that follows the split step's length (the 48 V
    buck's input power stayed 5.5e-5 off from T/1600 to T/12800). Read in its own configuration, the step after
    an edge leaves the order at 2 in CCM: the error quarters with each halving of h. (In DCM the stepper's own
    state is about first order through the diode's turn-off inside a step: accuracy on request estimates it.)"""
    from converters.methods import Theta
    params = {**PARASITIC, "Vin": 48, "f_sw": "250k", "L": "24u", "C": "22u", "D": 0.2606, "R": load}
    model, p, T, exact = _exact_period(name, params, samples=1000)
    reference = model.power(exact, p, 0.0, T)
    errors = []
    for steps in (800, 1600, 3200):
        method = Theta(h=T / steps, theta=0.5)
        orbit = steady_state(model, p, method, tol=1e-11)
        tr = replace(simulate(model.problem(p, T, orbit.x0), method), labels=model.labels(p))
        power = model.power(tr, p, 0.0, T)
        errors.append(max(abs(power[k] - reference[k]) / reference[k] for k in ("input_W", "output_W")))
    assert errors[-1] < 1e-8
    assert 3.0 < errors[0] / errors[1] < 5.0 and 3.0 < errors[1] / errors[2] < 5.0


def test_element_signals_obey_kirchhoff_in_both_phases():
    model, p, T, tr = _exact_period("boost", {"R": 200, **PARASITIC}, samples=1000)
    s = tr.samples()
    e = model.elements(s, p)
    iL = s.x[:, 0]
    assert np.allclose(e["i_switch"] + e["i_diode"], iL, atol=1e-12)        # boost: the node after L
    assert np.allclose(e["i_in"], iL)
    held = np.asarray(tr.modes()) == "DCM"
    assert held.any() and np.allclose(e["v_switch"][held], p["Vin"], atol=1e-9)   # L voltage zero, iL = 0


def test_the_summary_carries_measurements_and_power_over_the_periods_it_says(capsys):
    import json

    from validation.cli import main
    assert main(["simulate", "buck", "-p", "rL=0.1", "--periods", "3", "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["window_periods"] == 3
    assert {"iL", "vout", "i_in", "i_switch", "i_diode", "v_switch", "v_diode"} <= set(summary["measurements"])
    assert summary["power"]["losses_W"]["rL"] > 0
    run = run_converter("buck", {"rL": 0.1}, periods=3)
    assert run.measurements(periods=3).loc["vout", "mean"] == pytest.approx(summary["measurements"]["vout"]["mean"])


def test_a_run_plots_its_last_periods_with_units_the_operating_point_and_its_modes(tmp_path, capsys):
    from validation.cli import main
    run = run_converter("buck", {"Vin": "48V", "f_sw": "250kHz", "L": "22uH", "D": 0.25, "R": 2}, steady=True)
    fig = run.plot()
    axes = fig.axes
    assert [ax.get_ylabel() for ax in axes] == ["iL (A)", "vC (V)", "vout (V)", "mode"]
    assert axes[-1].get_xlabel().endswith("(us)")
    assert "Vin = 48" in fig._suptitle.get_text() and "L = 22u" in fig._suptitle.get_text()
    fig.canvas.draw()
    assert all(ax.yaxis.get_offset_text().get_text() == "" for ax in axes)         # no offset notation
    assert {t.get_text() for t in axes[-1].get_legend().get_texts()} == {"CCM-ON", "CCM-OFF"}
    for suffix, magic in ((".png", b"\x89PNG"), (".svg", b"<?xml")):
        target = tmp_path / f"w{suffix}"
        assert main(["simulate", "buck", "--periods", "20", "--plot", str(target)]) == 0
        assert target.read_bytes()[:5].startswith(magic)
    assert main(["simulate", "buck", "--plot", str(tmp_path / "w.jpg")]) == 2
    assert "--plot must end in .png, .svg or .html" in capsys.readouterr().err


@pytest.mark.parametrize("params", [{}, {"L1": "10u", "L2": "10u"}], ids=["ccm", "gdcm"])
def test_the_lossy_cuk_agrees_with_ngspice_on_the_same_circuit(params, ngspice, capsys):
    """The exact orbit of the lossy Cuk against ngspice's settled run of the same netlist: the means within
    2e-4 (measured 6.5e-5 in CCM, 3.6e-5 in GDCM), the diode's near-ideal model the floor."""
    import json

    from validation.cli import main
    model, p, T, tr = _exact_period("cuk", {**CUK_PARASITIC, **params}, samples=1000)
    exact = tr.mean("vout", t0=0.0, t1=T)
    argv = [item for k, v in {**CUK_PARASITIC, **params}.items() for item in ("-p", f"{k}={v}")]
    assert main(["simulate", "cuk", *argv, "--method", "spice", "--steady", "--json"]) == 0
    spice = json.loads(capsys.readouterr().out)
    assert spice["spice_settled"]
    assert spice["vout_mean"] == pytest.approx(exact, rel=2e-4)
