"""Switches driven by sources that do not repeat (a PWL without r=, a PULSE without PER): each change of such a
switch is a step of the run, located exactly on the waveform, the run split there as a built-in's at t_step.

netlists/circuits/buck-load-step.cir: an ideal buck whose S2 connects R2 beside R1 where v(step) crosses VT = 0.5
on its ramp from 0 V at 3 ms to 1 V at 3.002 ms, i.e. at 3.001 ms. In CCM at both loads the ideal buck's periodic
steady state has mean vout = D Vin (the inductor's volt-second balance) and mean i(L1) = vout / R_load (the
capacitor's charge balance), exactly; the phases are 300 and 200 periods against R C = 0.1 ms (the LC transient
decays as exp(-t / 2RC): e^-15 of 4.8 V by the step, e^-30 after it): the closed forms hold to 3e-7 before the
step and to rounding after it.
"""
import math
from pathlib import Path

import numpy as np
import pytest

from converters.circuits.netlist import NetlistError
from converters.errors import ParameterError
from converters.models import Circuit
from converters.run import run_converter
from validation.cli import main

NETLISTS = Path(__file__).resolve().parents[2] / "netlists" / "circuits"
STEP = NETLISTS / "buck-load-step.cir"
VIN, D, R, R2, T = 12.0, 0.4, 10.0, 5.0, 1e-5


def _variant(old: str, new: str) -> Circuit:
    text = STEP.read_text()
    assert old in text
    return Circuit.from_netlist("variant.cir", text=text.replace(old, new))


@pytest.mark.parametrize("method", ["lcp", "event"])
def test_a_gate_that_does_not_repeat_is_a_step_of_the_run_with_the_closed_forms_on_both_sides(method):
    circuit = Circuit.from_netlist(STEP)
    p = circuit.resolve({})
    assert circuit.step_times(p) == [pytest.approx(3.001e-3, rel=1e-14)]
    assert circuit.period(p) == pytest.approx(T, rel=1e-14)
    tr = run_converter(circuit, {}, method=method)
    before, after = (2.9e-3, 3e-3), (4.9e-3, 5e-3)
    vout = {w: tr.mean("vout", t0=w[0], t1=w[1]) for w in (before, after)}
    current = {w: tr.mean("i(l1)", t0=w[0], t1=w[1]) for w in (before, after)}
    assert vout[before] == pytest.approx(D * VIN, rel=1e-6) and vout[after] == pytest.approx(D * VIN, rel=1e-11)
    assert current[before] == pytest.approx(vout[before] / R, rel=1e-6)
    assert current[after] == pytest.approx(vout[after] * (1 / R + 1 / R2), rel=1e-11)
    modes = np.asarray(tr.modes()).astype(str)
    closed = np.array(["S2" in m.split("+") for m in modes])
    assert not closed[tr.t < 3.001e-3 - 1e-12].any() and closed[tr.t > 3.001e-3 + 1e-12].all()


def test_a_single_pulse_gate_closes_its_switch_and_opens_it_again_with_the_schedule_of_before():
    """PULSE(0 1 3m 2u 2u 1m) without PER: up through 0.5 V at 3.001 ms, down through it 1 ms + 1 us later."""
    circuit = _variant("PWL(0 0 3m 0 3.002m 1)", "PULSE(0 1 3m 2u 2u 1m)")
    p = circuit.resolve({})
    compiled = circuit.compiled(p)
    assert circuit.step_times(p) == [pytest.approx(3.001e-3, rel=1e-14), pytest.approx(4.003e-3, rel=1e-14)]
    first, (_, during), (_, last) = compiled.law, *compiled.phases
    assert last == first and during.configs != first.configs
    assert [compiled.closed[c][1] for c in first.configs] == [False, False]
    assert [compiled.closed[c][1] for c in during.configs] == [True, True]


def test_a_one_shot_gate_with_hysteresis_changes_at_the_band_edge():
    """VH = 0.2: the switch closes where v(step) rises through VT + VH = 0.7 V: at 3.0014 ms on the 2 us ramp."""
    circuit = _variant(".model SWMOD SW(VT=0.5)", ".model SWMOD SW(VT=0.5)\n.model SWH SW(VT=0.5 VH=0.2)")
    circuit = Circuit.from_netlist("variant.cir", text=circuit.netlist.text.replace("step 0 SWMOD", "step 0 SWH"))
    assert circuit.step_times(circuit.resolve({})) == [pytest.approx(3.0014e-3, rel=1e-14)]


@pytest.mark.parametrize("old, new, words", [
    ("S2 out r2 step 0 SWMOD", "S2 out r2 step gate SWMOD",
     ["switch S2", "adds a source that repeats (VG)", "periodic or one-shot"]),
    (".model SWMOD SW(VT=0.5)", ".model SWMOD SW(VT=0.5)\n.model SWH SW(VT=0.3 VH=0.4)",
     ["switch S2", "at t = 0 (0 V) lies inside the hysteresis band VT +- VH = 0.3 +- 0.4 V"]),
])
def test_a_one_shot_gate_the_compiler_cannot_take_is_refused_naming_the_switch(old, new, words):
    text = STEP.read_text().replace(old, new)
    if "SWH" in new:
        text = text.replace("step 0 SWMOD", "step 0 SWH")
    with pytest.raises(NetlistError) as error:
        Circuit.from_netlist("bad.cir", text=text)
    message = str(error.value)
    assert message.startswith("bad.cir:") and all(w in message for w in words), message


def test_a_load_step_has_no_periodic_steady_state_and_says_so(capsys):
    assert main(["simulate", str(STEP), "--steady"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "a PWL or PULSE that does not repeat" in err[0], err
    with pytest.raises(ParameterError, match="needs a periodic circuit"):
        run_converter(Circuit.from_netlist(STEP), {}, steady=True)


@pytest.mark.spice
def test_compare_runs_the_load_step_from_rest_over_the_files_run_and_passes(capsys, ngspice):
    """ngspice runs the same file (its S2 on the PWL gate); compare reads the last 10 of the file's 500 periods,
    after the step: vout's mean 2.3e-4 and ripple 8.5e-5 apart (measured), the same modes."""
    from validation.circuit_compare import compare_circuit
    result = compare_circuit(Circuit.from_netlist(STEP))
    m = result.metrics
    assert result.passed, (result.rows, result.notes)
    assert m["v(out)_mean_rel_error"] < 1e-3 and m["spice_periods"] == 500 and not math.isnan(m["v(out)_mean_spice"])
    assert m["mode_sequence_lcp"] == m["mode_sequence_spice"] == "S1+S2 > S2+D1"


def test_a_sweep_or_a_bifurcation_of_a_circuit_with_a_step_is_refused_not_answered_for_the_circuit_before_it(capsys,
                                                                                                           tmp_path):
    """Each point's problem would be the circuit before the step (its schedule at t = 0): the answer would ignore
    the load step. Both commands refuse it in one line, nothing written."""
    out = tmp_path / "s"
    assert main(["sweep", str(STEP), "--grid", "r=5:10:2", "--steady", "--no-progress", "--scheduler", "batched",
                 "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "has a step at 0.003001 s" in err[0] and not out.exists(), err
    assert main(["bifurcation", str(STEP), "--param", "r=5:10", "--points", "0"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "branch" not in err[0] and "a switch driven by a PWL or PULSE" in err[0], err


@pytest.mark.parametrize("method", ["lcp", "event"])
def test_a_gates_node_voltage_follows_its_waveform_not_a_level(method):
    """v(gate) is the PWM PULSE (1 V while S1 conducts: its mean over a period is D), v(step) the one-shot PWL
    (0 V before 3 ms, its ramp to 1 V, then 1 V); they had read the sources' first values throughout (v(gate) 1 V,
    v(step) 0 V after the step)."""
    from converters.circuits.compile import waveform_at
    circuit = Circuit.from_netlist(STEP)
    tr = run_converter(circuit, {}, method=method)
    gate, step = (next(e for e in circuit.netlist.elements if e.name == name).waveform for name in ("vg", "vstep"))
    t = np.asarray(tr.t, dtype=float)
    np.testing.assert_allclose(tr.signal("v(gate)"), waveform_at(gate, t), atol=1e-12)
    np.testing.assert_allclose(tr.signal("v(step)"), waveform_at(step, t), atol=1e-12)
    assert tr.mean("v(gate)", t0=4.9e-3, t1=5e-3) == pytest.approx(D, abs=1e-3)       # the 1e-6 T edges aside
    assert tr.signal("v(step)")[t > 3.002e-3].min() == 1.0 and tr.signal("v(step)")[t < 3e-3].max() == 0.0
