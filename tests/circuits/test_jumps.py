"""A switch closing across charged capacitances: the charges jump by conservation, the energy 1/2 C dv^2 is lost.

The closed forms (Acary, Bonnefon and Brogliato 2011, ch. 2: an ideal switch closing a loop of capacitors is an
impulse of current): two capacitors C1 at v1 and C2 at v2 joined share the charge, v+ = (C1 v1 + C2 v2)/(C1 + C2),
and lose 1/2 C1 C2/(C1 + C2) (v1 - v2)^2 (what the capacitors held minus what they hold); a capacitor shorted
loses all of 1/2 C v^2. The stepper folds the jump into the steps of the configuration it enters (a projection:
the steps inside it leave the state where it is), the event method applies it where the configuration is entered."""
import math

import numpy as np
import pytest

from converters.models import Circuit
from converters.run import run_converter, run_summary

SHARE = """two capacitors joined by a switch at t = {ts}
R1 a 0 1meg
R2 b 0 1meg
C1 a 0 1u
C2 b 0 3u
S1 a b g 0 SMOD
Vg g 0 PWL(0 0 {t0} 0 {t1} 1)
.model SMOD SW(VT=0.5)
.ic v(a)=10 v(b)=2
.tran 1u 1m
.end
"""


@pytest.mark.parametrize("method, tol", [("event", 1e-12), ("lcp", 1e-9)])
def test_two_capacitors_joined_by_a_switch_share_their_charge_and_lose_the_closed_form_energy(tmp_path, method, tol):
    """C1 = 1 uF at 10 V and C2 = 3 uF at 2 V, each with 1 Mohm (tau 1 s and 3 s): the gate's ramp crosses 0.5 V at
    ts = 0.50005 ms, where the switch joins them: v+ = (v1 + 3 v2)/4 and 1/2 (3/4 uF) (v1 - v2)^2 lost (27.3 uJ
    less the ramp's decay); then one capacitor of 4 uF across 0.5 Mohm (tau 2 s). A refusal before ("a loop of
    capacitors and closed switches")."""
    ts = 0.5e-3 + 0.5e-7
    path = tmp_path / "share.cir"
    path.write_text(SHARE.format(ts=ts, t0=0.5e-3, t1=0.5001e-3))
    tr = run_converter(Circuit.from_netlist(path), method=method)
    v1, v2 = 10.0 * math.exp(-ts / 1.0), 2.0 * math.exp(-ts / 3.0)
    joined = (1e-6 * v1 + 3e-6 * v2) / 4e-6
    lost = 0.5 * 0.75e-6 * (v1 - v2) ** 2
    jumps, energy = tr.jump_losses()
    assert jumps == 1 and energy == pytest.approx(lost, rel=tol)
    end = joined * math.exp(-(1e-3 - ts) / 2.0)
    np.testing.assert_allclose([tr.signal("v(a)")[-1], tr.signal("v(b)")[-1]], end, rtol=tol)
    before = tr.t < ts - 1e-9
    np.testing.assert_allclose(tr.signal("v(a)")[before], 10.0 * np.exp(-tr.t[before]), rtol=tol)


SHORT = """a capacitor a switch shorts every period
Vin in 0 DC 10
R1 in c 1k
C1 c 0 1u
S1 c 0 g 0 SMOD
Vg g 0 PULSE(0 1 0.9m 1n 1n 0.1m 1m)
.model SMOD SW(VT=0.5)
.tran 1u 10m
.end
"""


@pytest.mark.parametrize("method, tol", [("event", 1e-11), ("lcp", 1e-6)])
def test_a_capacitor_shorted_by_a_switch_every_period_loses_half_c_v_squared_each_time(tmp_path, method, tol):
    """C1 = 1 uF charges through 1 kohm from 10 V for d = 0.9 ms - 1 ns (the gate's crossings at the middle of its
    1 ns edges) and is shorted the rest of each 1 ms period: it jumps to 0 V at each closing from
    v = 10 (1 - e^(-d / 1 ms)) = 5.934 V, losing 1/2 C v^2 = 17.6 uJ (17.6 mW at 1 kHz), and holds 0 V while the
    switch carries 10 mA; the orbit's multipliers are 0 (the jump forgets the state)."""
    path = tmp_path / "short.cir"
    path.write_text(SHORT)
    tr = run_converter(Circuit.from_netlist(path), method=method, steady=True)
    summary = run_summary(tr)
    d = 0.9e-3 - 1e-9
    v = 10.0 * (1.0 - math.exp(-d / 1e-3))
    losses = summary["losses"]
    assert losses["jumps"] == 10
    assert losses["redistribution_W"] == pytest.approx(0.5e-6 * v * v * 1e3, rel=tol)
    m = summary["measurements"]
    assert m["v(c)"]["max"] == pytest.approx(v, rel=tol)
    # the mean: d of the charging curve, the rest at 0 V
    mean = 10.0 * (d - 1e-3 * (1.0 - math.exp(-d / 1e-3))) / 1e-3
    assert m["v(c)"]["mean"] == pytest.approx(mean, rel=tol)
    assert summary["orbit"]["spectral_radius"] < 1e-9
