"""A compensator written as an op-amp circuit in a netlist (netlists/circuits/voltage-loop-buck.cir) against the
built-in voltage loop's transfer function: the parts --design prints realise it, and the netlist's loop closes the
built-in one's as the amplifier becomes ideal (its gain Aol and its input impedance, which loads the output, both to
infinity)."""
import json
import math
from pathlib import Path

import numpy as np
import pytest

from converters.analysis.smallsignal import loop_gain
from converters.models.compensator import Compensator
from converters.run import resolve_model
from validation.cli import main

NETLIST = Path(__file__).resolve().parents[2] / "netlists" / "circuits" / "voltage-loop-buck.cir"
F = np.geomspace(100.0, 50e3, 40)


def parallel(a, b):
    return a * b / (a + b)


@pytest.mark.parametrize("comp", [
    Compensator(3716.39, (1358.07, 1358.07), (73633.7, 73633.7)),          # the built-in default: type III
    Compensator(2.0e4, (800.0, 3000.0), (40e3, 90e3)),                        # type III, distinct pairs
    Compensator(5.0e3, (2000.0,), (30e3,)),                                   # type II
    Compensator(1.0e3, (500.0,), ()),                                         # PI
    Compensator(1.0e3),                                                       # I
], ids=["type3-default", "type3", "type2", "pi", "i"])
def test_the_op_amp_parts_realise_the_compensators_transfer_function(comp):
    """Zf/Zi of the parts (Zi: Ri beside Rc + Cc; Zf: Ca + Rz beside Cb), written here from the impedances, is Gc."""
    parts = comp.components(10e3)
    s = 2j * math.pi * F
    zi = parts["Ri"] if "Cc" not in parts else parallel(parts["Ri"], parts["Rc"] + 1 / (s * parts["Cc"]))
    zf = parts.get("Rz", 0.0) + 1 / (s * parts["Ca"])
    if "Cb" in parts:
        zf = parallel(zf, 1 / (s * parts["Cb"]))
    assert np.abs(zf / zi / comp.transfer(F) - 1).max() < 1e-12


def test_parts_need_a_pole_above_each_zero():
    from converters.errors import ParameterError
    with pytest.raises(ParameterError, match="places each pole above its zero; got a zero at 5000 Hz and a pole at 1000"):
        Compensator(1e3, (5000.0,), (1000.0,)).components(10e3)


def test_the_op_amp_netlist_closes_the_built_in_loop_as_the_amplifier_becomes_ideal():
    """The netlist's loop gain differs from the built-in's (an ideal, buffered transfer function) by the load the
    compensator's input puts on v(out) and by the amplifier's finite gain: with Aol = 1e9 the difference falls
    tenfold per decade of Ri (first order: 9.7e-4 at 10 kohm, 9.7e-7 at 10 Mohm), and the shipped parts (10 kohm,
    Aol = 1e5) keep the designed crossover and margin (9,618.7 Hz and 60.03 degrees against 9,619.9 and 60.03)."""
    reference, found = loop_gain(resolve_model("buck", "voltage-loop"), {}, frequency_hz=F)
    netlist = resolve_model(str(NETLIST))
    errors = []
    for ri in (1e4, 1e5, 1e6, 1e7):
        response, _ = loop_gain(netlist, {"Aol": 1e9, "Ri": ri}, frequency_hz=F)
        errors.append(np.abs(response.response / reference.response - 1).max())
    rates = np.array(errors[:-1]) / np.array(errors[1:])
    assert np.all(np.abs(rates - 10.0) < 0.1), (errors, rates)
    assert errors[-1] < 1.5e-6
    _, shipped = loop_gain(netlist, {}, frequency_hz=F)
    assert shipped.crossover_hz == pytest.approx(found.crossover_hz, rel=2e-4)
    assert shipped.phase_margin_deg == pytest.approx(found.phase_margin_deg, abs=0.01)


def test_a_designed_compensators_parts_close_its_loop_in_the_netlist(capsys):
    """bode --design prints the parts; the netlist given the design's wi, fz, fp (its .param lines turn them into the
    same parts) closes the loop the design promises: crossover and margin as the built-in loop's to 1e-5 with a
    near-ideal amplifier (Aol = 1e9, Ri = 10 Mohm)."""
    assert main(["bode", "buck", "--control", "voltage-loop", "--design", "fc=5k,pm=50,ri=1e7", "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    design, parts = summary["design"], summary["components"]
    comp = Compensator(design["wi"], (design["fz1"], design["fz2"]), (design["fp1"], design["fp2"]))
    assert parts == pytest.approx(comp.components(1e7), rel=1e-15)
    values = {k: design[k] for k in ("wi", "fz1", "fz2", "fp1", "fp2")}
    _, closed = loop_gain(resolve_model(str(NETLIST)), {**values, "Aol": 1e9, "Ri": 1e7}, frequency_hz=F)
    assert closed.crossover_hz == pytest.approx(summary["margins"]["crossover_hz"], rel=1e-5)
    assert closed.phase_margin_deg == pytest.approx(summary["margins"]["phase_margin_deg"], abs=1e-3)
    assert abs(closed.crossover_hz / 5e3 - 1) < 0.05 and abs(closed.phase_margin_deg - 50) < 3


SENSED_RAMP = """Boost 12 V under a comparator: the switch's current sensed by an H source, a 1 V/T ramp added to it
.param Vin=12 L=22u C=100u R=12 f_sw=100k Rs=0.1 Vc=1.0 Va=1
.param T={1/f_sw} e={1e-6/f_sw}
Vin in 0 DC {Vin}
Vsense in lx DC 0
L1 lx sw {L}
S1 sw 0 vc xsum SWM
D1 sw out DM
C1 out 0 {C}
R1 out 0 {R}
Hsense cs 0 Vsense {Rs}
Vslope xsum cs {ramp}
Vctl vc 0 DC {Vc}
.model SWM SW(VT=0)
.model DM D
.tran {T/500} {1000*T} 0 {T/2000} UIC
.meas tran vout_avg AVG v(out) FROM={990*T} TO={1000*T}
.end
"""


@pytest.mark.parametrize("method", ["lcp", "event"])
def test_a_ramp_in_series_with_a_sensed_current_is_the_comparators_own(method):
    """The compensation ramp written in series with the current sense's H output (on the comparator's other input)
    was refused, "a state-driven switch with PULSE, SIN or PWL sources in the power circuit": the H output counted
    as the power circuit. It reaches only the switch's control, as the same ramp subtracted from the command does
    (accepted before): both give the same orbit, and the exact method's 23.3940669 V (with the PULSE's own slope,
    (VU - VL) / TR; the sawtooth over the whole period had read 23.3940748)."""
    from converters.models import Circuit
    from converters.run import run_converter, run_summary
    ramp = "PULSE(0 {Va} 0 {T - 2*e} {e} {e} {T})"
    added = Circuit.from_netlist("sensed.cir", text=SENSED_RAMP.replace("{ramp}", ramp))
    text = SENSED_RAMP.replace("S1 sw 0 vc xsum", "S1 sw 0 vcr cs")
    subtracted = Circuit.from_netlist("command.cir", text=text.replace(
        "Vslope xsum cs {ramp}", "Vslope vcr vc PULSE(0 {-Va} 0 {T - 2*e} {e} {e} {T})"))
    a = run_summary(run_converter(added, steady=True, method=method))["vout_mean"]
    b = run_summary(run_converter(subtracted, steady=True, method=method))["vout_mean"]
    assert a == pytest.approx(b, rel=1e-12) and a == pytest.approx(23.3940669, rel=1e-7)
