"""A vendor's worked example of a switch's losses and junction temperature, run as a circuit.

STMicroelectronics, B5973D "2 A step down switching regulator for automotive applications", datasheet DocID14117
Rev 4, section 8.3 (thermal considerations), equations 23 to 27: a 12 V to 3.3 V buck at 2 A and 250 kHz, duty
cycle 0.3 (above V_OUT / V_IN to cover the losses), its internal switch taken at R_DS(on) = 0.4 ohm ("up to 0.5 ohm
at 150 degC: we can consider a value of 0.4 ohm"), T_SW = 70 ns ((t_rise + t_fall) / 2), I_Q = 2.5 mA, R_th(j-a)
about 42 degC/W, T_A about 70 degC:
    P_TOT = R_DS(on) I_OUT^2 D + V_IN I_OUT T_SW F_SW + V_IN I_Q = 0.4 2^2 0.3 + 12 2 70e-9 250e3 + 12 2.5e-3 ~ 0.93 W,
    T_J = T_A + R_th(j-a) P_TOT = 70 + 0.93 42 ~ 110 degC.
Here the same circuit (the load 1.8 ohm: 2 A at D V_IN = 3.6 V) with a description whose on-state drop is 0.4 ohm
times the current and whose turn-on and turn-off energies are each V I T_SW / 2 (the datasheet's linear
commutation), a junction-to-ambient chain of 42 K/W and the case at the ambient: the switch's conduction and
switching losses are the datasheet's first two terms (the conduction's within the inductor's ripple,
(Delta I)^2 / 12 beside I^2: 2e-4), and with its third term (the IC's quiescent draw, not a switch's loss) the
junction temperature the datasheet prints, at the precision it prints it."""
import json

import pytest

from validation.cli import main

V_IN, D, F_SW, I_OUT, R_ON, T_SW, I_Q, R_TH, T_A = 12.0, 0.3, 250e3, 2.0, 0.4, 70e-9, 2.5e-3, 42.0, 70.0
L = 100e-6

NETLIST = f"""B5973D's worked example as an ideal buck
*pcsuite thermal setup.toml
.param T={1 / F_SW} e={1e-6 / F_SW}
Vin in 0 DC {V_IN}
Vg gate 0 PULSE(1 0 {{{D}*T - e/2}} {{e}} {{e}} {{(1-{D})*T - e}} {{T}})
S1 in sw gate 0 SWMOD
D1 0 sw DMOD
L1 sw out {L}
C1 out 0 100u
R1 out 0 1.8
.model SWMOD SW(VT=0.5)
.model DMOD D
.tran {{T/1000}} {{200*T}} UIC
.end
"""
E_EDGE = 0.5 * V_IN * I_OUT * T_SW          # J: each edge's energy at 12 V, 2 A (linear in both: a bilinear table)
DEVICE = f"""[device]
name = "B5973D's switch as its datasheet's example takes it"
kind = "MOSFET"
[conduction]
current = [0, 4]
temperature = [25, 150]
v_on = [[0, {4 * R_ON}], [0, {4 * R_ON}]]
[turn_on]
voltage = [0, {V_IN}]
current = [0, {I_OUT}]
temperature = [25, 150]
energy = [[[0, 0], [0, {E_EDGE}]], [[0, 0], [0, {E_EDGE}]]]
[turn_off]
voltage = [0, {V_IN}]
current = [0, {I_OUT}]
temperature = [25, 150]
energy = [[[0, 0], [0, {E_EDGE}]], [[0, 0], [0, {E_EDGE}]]]
[thermal]
kind = "foster"
R = [{R_TH}]
tau = [1.0]
"""
SETUP = f"""ambient = {T_A}
[devices.s1]
description = "switch.toml"
"""


def test_the_datasheets_worked_example_of_a_bucks_switch_losses_and_junction_temperature(tmp_path, capsys):
    (tmp_path / "b5973d.cir").write_text(NETLIST)
    (tmp_path / "switch.toml").write_text(DEVICE)
    (tmp_path / "setup.toml").write_text(SETUP)
    code = main(["simulate", str(tmp_path / "b5973d.cir"), "--steady", "--json"])
    out, err = capsys.readouterr()
    assert code == 0, err
    s1 = json.loads(out)["thermal"]["devices"]["s1"]
    conduction = R_ON * I_OUT ** 2 * D                          # 0.48 W, the datasheet's first term
    switching = V_IN * I_OUT * T_SW * F_SW                      # 0.42 W, its second
    ripple = (V_IN - D * V_IN) * D / (F_SW * L)                 # A, peak to peak
    assert s1["conduction_W"] == pytest.approx(conduction * (1 + ripple ** 2 / 12 / I_OUT ** 2), rel=1e-4)
    assert s1["conduction_W"] == pytest.approx(conduction, rel=1e-3)
    assert s1["turn_on_W"] + s1["turn_off_W"] == pytest.approx(switching, rel=1e-4)
    p_tot = s1["total_W"] + V_IN * I_Q
    assert round(p_tot, 2) == 0.93                               # "P_TOT ~ 0.93 W"
    assert s1["tj_C"] == pytest.approx(T_A + R_TH * s1["total_W"], abs=1e-6)
    assert abs(T_A + R_TH * p_tot - 110.0) < 1.0                 # "T_J ~ 110 degC" (70 + 0.93 x 42 = 109.06)
