"""SIN sources in netlists: the AC steady state of an RC and the no-load peaks of single- and three-phase bridge
rectifiers, against closed forms."""
import math
from pathlib import Path

import pytest

from converters.models import Circuit
from converters.run import make_method, run_converter, run_summary, steady_state

NETLISTS = Path(__file__).resolve().parents[2] / "netlists" / "circuits"
RC = """RC low-pass on a 50 Hz sine
.param V=10 R=1k C=1u f=50
Vs in 0 SIN(0 {V} {f} 0 0 30)
R1 in out {R}
C1 out 0 {C}
.tran 10u 100m
.end
"""


def test_an_rc_driven_by_a_sine_settles_on_the_phasors_steady_state():
    """vC(t) = V / sqrt(1 + (w R C)^2) sin(w t + phi - atan(w R C)): the stepper's orbit (theta 0.5, T/1000) to 1e-5;
    the source's signal is exact at each sample, its RMS read on 1,000 samples a period (3e-6 short)."""
    circuit = Circuit.from_netlist("rc.cir", text=RC)
    p = circuit.resolve({})
    wrc = 2 * math.pi * 50 * 1e-3
    exact = 10 / math.sqrt(1 + wrc ** 2) * math.sin(math.radians(30) - math.atan(wrc))
    orbit = steady_state(circuit, p, make_method(circuit, p, "lcp"), tol=1e-12)
    assert orbit.x0[0] == pytest.approx(exact, rel=1e-5)
    summary = run_summary(run_converter(circuit, {}, steady=True))
    assert summary["measurements"]["v(in)"]["rms"] == pytest.approx(10 / math.sqrt(2), rel=1e-5)
    assert summary["measurements"]["v(out)"]["rms"] == pytest.approx(10 / math.sqrt(2 * (1 + wrc ** 2)), rel=1e-5)


@pytest.mark.parametrize("name, peak, modes", [
    ("rectifier-1ph", 325.0, {"off", "D1+D4", "D2+D3"}),
    ("rectifier-3ph", math.sqrt(3) * 325.0, {"off", "D1+D6", "D1+D2", "D3+D2", "D3+D4", "D5+D4", "D5+D6"})])
def test_a_bridge_rectifier_holds_the_peak_at_no_load_and_conducts_in_pairs(name, peak, modes):
    """No load: the capacitor holds the (line-to-line) peak; loaded, each pair of diodes conducts near its peak and
    no diode conducts alone (a bridge's output floats while they all block: no pair may read as conducting then)."""
    circuit = Circuit.from_netlist(NETLISTS / f"{name}.cir")
    unloaded = run_summary(run_converter(circuit, {"R": 1e8}, steady=True))
    assert unloaded["vout_mean"] == pytest.approx(peak, rel=1e-5)
    loaded = run_summary(run_converter(circuit, {}, steady=True))
    assert set(loaded["mode_fractions"]) == modes
    assert 0.8 * peak < loaded["vout_mean"] < peak


BRIDGE_LC = """bridge rectifier with an LC filter (its inductor current resets: every diode blocks for 0.415 of T)
Vs a0 0 SIN(0 325 50 0 0 0)
R0 a0 a 0.1
D1 a p DMOD
D2 0 p DMOD
D3 n a DMOD
D4 n 0 DMOD
L1 p q 10m
C1 q n 1m
R1 q n 50
.model DMOD D
.tran 20u 400m
.end
"""


def test_a_diode_at_zero_current_and_voltage_is_not_read_as_conducting():
    """While every diode blocks, the bridge's output floats and the LCP leaves D3 at u = y = 0 with 1e-16 A of
    rounding: the summary had read "D3 0.148371" (no loop lets D3 conduct alone) and "off 0.267883", where the exact
    orbit (Radau at rtol 1e-12 with the diode events located, a fixed point of the period map) conducts on
    [0.1493752, 0.4417371] T and its mirror: off 0.415276, each pair 0.292362. The stepper's fractions are within
    one step (1e-3 T) of those."""
    circuit = Circuit.from_netlist("bridge_lc.cir", text=BRIDGE_LC)
    fractions = run_summary(run_converter(circuit, {}, steady=True))["mode_fractions"]
    assert set(fractions) == {"off", "D1+D4", "D2+D3"}
    assert fractions["off"] == pytest.approx(0.415276, abs=1e-3)
    assert fractions["D1+D4"] == pytest.approx(0.292362, abs=1e-3)
    assert fractions["D2+D3"] == pytest.approx(0.292362, abs=1e-3)
