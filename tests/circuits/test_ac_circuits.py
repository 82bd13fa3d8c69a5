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


SIN_GATE = """SIN gate just above its threshold near its peak: buck
.param Vin=100 L=100u C=100u R=10 VT=0.999 PH=2.8125
Vin in 0 DC {Vin}
Vg g 0 SIN(0 1 10k 0 0 {PH})
S1 in sw g 0 SWMOD
D1 0 sw DMOD
L1 sw out {L}
C1 out 0 {C}
R1 out 0 {R}
.model SWMOD SW(VT={VT})
.model DMOD D
.tran 0.1u 20m 0 0.1u UIC
.end
"""


@pytest.mark.parametrize("phase", [0.0, 2.8125, 1.0])
@pytest.mark.parametrize("method", ["event", "lcp"])
def test_a_sine_gate_above_its_threshold_only_near_its_peak_closes_its_switch_at_every_phase(phase, method):
    """S1 closes while sin(w t + phase) > 0.999: 1.4236 % of the period around the peak, (pi - 2 asin(0.999)) / 2 pi.
    The gate's sine is crossed on pieces of 1/64 of its period; at phase 2.8125 deg (half a piece) the peak lay
    mid-piece, both ends at 0.998795, and the pulse was lost: "no fixed switching period", or with a second switch
    vout 0 V "within ~0" where it is 2.58 V. The phase only shifts the orbit in time: vout is the same at each."""
    model = Circuit.from_netlist("sin-gate.cir", text=SIN_GATE)
    summary = run_summary(run_converter(model, {"PH": phase}, steady=True, method=method))
    duty = (math.pi - 2 * math.asin(0.999)) / (2 * math.pi)
    assert summary["mode_fractions"]["S1"] == pytest.approx(duty, abs=1e-9 if method == "event" else 1e-6)
    reference = run_summary(run_converter(model, {"PH": 0.0}, steady=True, method="event"))["vout_mean"]
    assert reference == pytest.approx(3.134261157, rel=1e-8)     # solve_ivp at rtol 1e-12, closed-form instants
    assert summary["vout_mean"] == pytest.approx(reference, rel=1e-9 if method == "event" else 1e-5)


def test_a_period_the_parameters_give_where_the_files_own_have_none_sets_the_default_step():
    """At the file's VT = 1.5 the sine never reaches its switch's threshold (no period); -p VT=0.99 gives one. The
    default step's fraction was taken of the file's own period, infinite: a ZeroDivisionError."""
    model = Circuit.from_netlist("sin-gate.cir", text=SIN_GATE.replace("VT=0.999 PH=2.8125", "VT=1.5 PH=0"))
    assert not model.periodic(model.resolve({}))
    p = model.resolve({"VT": 0.99})
    assert model.default_h(p) == pytest.approx(1e-7)          # T/1000 (the file's own step is T/1000 too)
    summary = run_summary(run_converter(model, {"VT": 0.99}, steady=True))
    assert summary["mode_fractions"]["S1"] == pytest.approx((math.pi - 2 * math.asin(0.99)) / (2 * math.pi), abs=1e-6)
