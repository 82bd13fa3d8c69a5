"""The exact small-signal model about a periodic orbit: the averaged model where it is exact (the ideal CCM buck),
the steady state's own sensitivity at low frequency (the DCM buck's closed form), a sinusoid injected and simulated
to its periodic steady state at every frequency up to fs/2 (open and closed loops, CCM and DCM, an output that
steps at the switching), the loop gain's -1 at fs/2 where the voltage-mode buck doubles its period, and one clear
error for what it cannot take."""
import math
from pathlib import Path

import numpy as np
import pytest

from converters.analysis.smallsignal import (SmallSignalModel, frequency_response, injection_response, loop_gain,
                                             margins)
from converters.errors import ParameterError
from converters.run import resolve_model

NETLISTS = Path(__file__).resolve().parents[2] / "netlists" / "circuits"
CCM_BUCK = {"L": "100u", "C": "100u", "R": 10, "D": 0.4}          # K = 2 L / (R T) = 2 > 1 - D: CCM
DCM_BUCK = {"L": "10u", "C": "100u", "R": 10, "D": 0.4}           # K = 0.2 < 0.6: DCM


@pytest.mark.parametrize("params", [CCM_BUCK, {**CCM_BUCK, "L": "47u", "C": "220u", "R": 4.7, "D": 0.7}])
def test_the_ideal_ccm_bucks_control_to_output_is_the_averaged_model(params):
    """Vin / (1 + s L / R + s^2 L C): the switch node's pulses have the duty ratio's perturbation as their area's, so
    the response at w (not its sidebands) is the averaged model's exactly, at every frequency (issue: 1 % and 1 degree
    below fs/20)."""
    fr = frequency_response("buck", params, input="D", fmin=10.0, fmax=50e3, points=60)
    p = resolve_model("buck").resolve(params)
    s = 2j * np.pi * fr.frequency_hz
    averaged = p["Vin"] / (1 + s * p["L"] / p["R"] + s ** 2 * p["L"] * p["C"])
    ratio = fr.response / averaged
    assert np.abs(ratio - 1).max() < 1e-8
    below = fr.frequency_hz <= 5e3
    assert np.abs(np.abs(ratio[below]) - 1).max() < 0.01 and np.degrees(np.abs(np.angle(ratio[below]))).max() < 1.0


def test_the_ideal_ccm_bucks_output_impedance_is_its_filters():
    """A load current Io drawn beside R: vout / Io = -(s L || 1 / (s C) || R) exactly (the switch node does not see
    the load in CCM)."""
    fr = frequency_response("buck", {**CCM_BUCK, "Io": 0.0}, input="Io", fmin=10.0, fmax=50e3, points=40)
    s = 2j * np.pi * fr.frequency_hz
    Z = 1 / (1 / (s * 100e-6) + s * 100e-6 + 1 / 10.0)
    assert np.abs(fr.response / -Z - 1).max() < 1e-9
    assert fr.input_unit == "A" and fr.output_unit == "V"


def _mean_vout(params: dict) -> float:
    from converters.run import steady_orbit
    tr = steady_orbit("buck", params, method="event", tol=1e-13)
    return tr.mean("vout")


@pytest.mark.parametrize("name, h", [("D", 1e-5), ("Vin", 1e-4)])
def test_at_low_frequency_the_dcm_bucks_response_is_its_steady_states_sensitivity(name, h):
    """At w -> 0 the response is d(mean vout)/du of the periodic orbit (central differences of exact steady states),
    and near the small-ripple closed form (vout = M(D, K) Vin, M = 2 / (1 + u), u = sqrt(1 + 4 K / D^2), K = 2 L /
    (R T): d vout / dD = Vin 8 K / (u D^3 (1 + u)^2), d vout / d Vin = M) to its ripple's order, 1e-3; the averaged
    CCM model's Vin and D are 17 % and 35 % away."""
    p = resolve_model("buck").resolve(DCM_BUCK)
    K = 2 * p["L"] * p["f_sw"] / p["R"]
    D, u = p["D"], math.sqrt(1 + 4 * K / p["D"] ** 2)
    closed = {"D": p["Vin"] * 8 * K / (u * D ** 3 * (1 + u) ** 2), "Vin": 2 / (1 + u)}[name]
    response = frequency_response("buck", DCM_BUCK, input=name, frequency_hz=[1e-3]).response[0]
    value = float(p[name])
    central = (_mean_vout({**DCM_BUCK, name: value + h}) - _mean_vout({**DCM_BUCK, name: value - h})) / (2 * h)
    assert response.real == pytest.approx(central, rel=1e-6)
    assert abs(response.imag) < 1e-5 * abs(response)
    assert response.real == pytest.approx(closed, rel=1e-3)


CASES = [
    ("buck", "pwm", CCM_BUCK, "D", "vout"),
    ("buck", "pwm", DCM_BUCK, "D", "vout"),
    ("boost", "pwm", {"L": "10u", "C": "100u", "R": 10, "D": 0.4}, "D", "vout"),            # DCM
    # the boost's vout through the ESR steps when the diode starts to carry: the step moves with the turn-off
    ("boost", "pwm", {"L": "100u", "C": "100u", "R": 10, "D": 0.4, "rL": 0.1, "rC": 0.05}, "D", "vout"),
    ("buck", "pwm", {**CCM_BUCK, "rC": 0.05}, "Vin", "vout"),
    ("buck", "pwm", {**CCM_BUCK, "rC": 0.05}, "Vin", "iL"),
    ("buck", "voltage-mode", {}, "control", "vout"),
    ("buck", "voltage-mode", {}, "Vin", "vout"),
    ("buck", "voltage-mode", {"latch": 1, "Vin": 20}, "Vref", "vout"),
    pytest.param("buck", "voltage-loop", {}, "Vref", "vout", marks=pytest.mark.slow),        # 2.3 s
    ("buck", "voltage-loop", {"leading": 1}, "control", "vout"),
    ("buck", "current-loop", {}, "Vref", "vout"),
    ("buck", "current-loop", {}, "control", "iL"),
    (str(NETLISTS / "sepic.cir"), "pwm", {}, "d", "v(out)"),          # a netlist: its PULSE gate's duty ratio
]


@pytest.mark.parametrize("converter, control, params, name, output", CASES)
def test_the_exact_response_is_the_injected_sinusoids_fundamental_up_to_half_the_switching_frequency(
        converter, control, params, name, output):
    """The brute force an AC sweep does: the input perturbed by 1e-5 of its value, each frequency simulated to its
    periodic steady state with the event method, the output's fundamental over the common period (issue: 0.5 dB and
    3 degrees up to fs/2; measured at most 5e-4 dB and 3e-3 degrees)."""
    model = resolve_model(converter, control)
    small = SmallSignalModel(model, params, input=name, outputs=(output,))
    fs = 1.0 / small.T
    f, injected = injection_response(small, [fs / 200, fs / 20, fs / 7, 0.45 * fs], output)
    exact = small.response(f, output)
    ratio = injected / exact
    assert np.abs(20 * np.log10(np.abs(ratio))).max() < 5e-3
    assert np.degrees(np.abs(np.angle(ratio))).max() < 5e-2


def test_the_loop_gain_reaches_minus_one_at_half_the_switching_frequency_where_the_period_doubles():
    """Hamill, Deane and Jefferies' buck doubles its period at Vin = 24.516573 V (a Floquet multiplier through -1):
    there the closed loop's response at fs/2 is infinite and T = -Y / (1 + Y) tends to -1, the phase margin to 0."""
    vm = resolve_model("buck", "voltage-mode")
    fs = 2.5e3
    near = loop_gain(vm, {"Vin": 24.5165}, frequency_hz=[fs / 2])[0].response[0]
    far = loop_gain(vm, {"Vin": 22.0}, frequency_hz=[fs / 2])[0].response[0]
    assert abs(near + 1) < 1e-5
    assert abs(far + 1) > 0.05
    response, found = loop_gain(vm, {"Vin": 22.0})
    assert 0 < found.phase_margin_deg < 30 and found.crossover_hz < fs / 2
    assert np.abs(response.frd().frdata[0, 0] - response.response).max() == 0.0


def test_margins_are_located_on_the_function_not_the_grid():
    """T = 100 / (s (1 + s/10)) in rad/s, frequencies in Hz: crossover where |T| = 1, phase margin 180 + angle T."""
    def gain(f):
        s = 2j * np.pi * np.asarray(f, dtype=float)
        return 1000.0 / (s * (1 + s / 10.0)) / (1 + s / 1e5)
    found = margins(gain, np.geomspace(0.01, 1e6, 40))
    w = 2 * np.pi * found.crossover_hz
    assert abs(gain(found.crossover_hz)) == pytest.approx(1.0, abs=1e-9)
    assert found.phase_margin_deg == pytest.approx(180 + np.degrees(np.angle(gain(w / (2 * np.pi)))), abs=1e-9)
    at_180 = complex(gain(found.phase_crossover_hz))
    assert at_180.real < 0 and abs(at_180.imag) < 1e-9 * abs(at_180)      # on the negative real axis
    assert found.gain_margin_db == pytest.approx(-20 * np.log10(abs(gain(found.phase_crossover_hz))), abs=1e-9)


@pytest.mark.parametrize("converter, control, params, name, message", [
    ("buck", "pwm", CCM_BUCK, "f_sw", "changes the switching period"),
    ("buck", "pwm", CCM_BUCK, "control", "driven by a schedule: use input 'D'"),
    ("buck", "pwm", CCM_BUCK, "Vx", "input must be 'control' (a state-driven law) or one of the parameters"),
    ("buck", "pwm", CCM_BUCK, "rC", "has no value here"),
    ("boost", "smc", {}, "Iref", "has no switching period"),
    (str(NETLISTS / "rectifier-1ph.cir"), "pwm", {}, "vin", "has sinusoidal sources"),
])
def test_what_the_small_signal_model_cannot_take_is_refused_naming_it(converter, control, params, name, message):
    with pytest.raises(ParameterError, match=message.replace("(", r"\(").replace(")", r"\)")):
        SmallSignalModel(resolve_model(converter, control), params, input=name)


def test_a_single_loop_has_one_loop_gain_wherever_it_is_broken():
    """The compensated voltage loop broken at its comparator (T = -Y / (1 + Y)) and at its reference (T = Y / (1 - Y))
    is the same loop: the same T to 1e-9 at every frequency. Under peak current mode with an outer voltage loop the
    two differ: the comparator's is the inner current loop's (crossing near fs/2), the reference's the outer one."""
    from converters.models import get_model
    single = get_model("buck", "voltage-loop")
    at_comparator, m1 = loop_gain(single, {}, fmin=100.0, fmax=5e4, points=60)
    at_reference, m2 = loop_gain(single, {}, at="reference", fmin=100.0, fmax=5e4, points=60)
    assert np.abs(at_reference.response / at_comparator.response - 1).max() < 1e-9
    assert m1.crossover_hz == pytest.approx(m2.crossover_hz, rel=1e-9)
    double = get_model("buck", "current-loop")
    _, inner = loop_gain(double, {})
    _, outer = loop_gain(double, {}, at="reference")
    assert outer.crossover_hz < 0.1 * inner.crossover_hz and 30 < outer.phase_margin_deg < 90


def test_an_element_value_is_an_input_and_the_injection_check_refuses_it():
    """An inductance changes the modes' matrices: the exact model takes it (its five-point difference of the
    matrices), at zero frequency the derivative of the steady state's mean; the injection perturbs sources only."""
    small = SmallSignalModel(resolve_model("boost"), {"L": "10u", "R": 100}, input="L")
    assert small.dynamic and np.isfinite(small.response([0.0, 1e3, 4e4])).all()
    with pytest.raises(ParameterError, match="input 'L' changes the circuit's matrices; the injection check perturbs"):
        injection_response(small, [1e3])
