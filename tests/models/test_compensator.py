"""Voltage-mode control with a compensator: its realisation is its transfer function, the k-factor design meets its
crossover and phase margin on the exact loop gain, the closed loop regulates to Vref, and a load step's recovery is
the exact model's prediction."""
import math

import numpy as np
import pytest

from converters.analysis.smallsignal import SmallSignalModel, design_compensator, loop_gain
from converters.errors import ParameterError
from converters.methods import EventDriven
from converters.models.compensator import Compensator
from converters.run import resolve_model, run_converter, steady_state

PLANT = {"L": "100u", "C": "100u", "R": 10}
FS = 1e5


@pytest.fixture(scope="module")
def design():
    return design_compensator("buck", PLANT, crossover_hz=FS / 10, phase_margin_deg=60, vref=5.0)


@pytest.mark.parametrize("compensator", [Compensator(3e3), Compensator(3e3, (500.0,)),
                                         Compensator(3e3, (1e3,), (30e3,)),
                                         Compensator(3e3, (1e3, 2e3), (30e3, 60e3))])
def test_the_realisation_is_the_transfer_function(compensator):
    """Cc (sI - Ac)^-1 Bc + Dc = wi / s prod (1 + s/wz) / (1 + s/wp) at every frequency (I, PI, type II, type III)."""
    Ac, Bc, Cc, Dc = compensator.matrices()
    f = np.geomspace(1.0, 1e6, 30)
    realised = np.array([Cc @ np.linalg.solve(2j * np.pi * x * np.eye(len(Bc)) - Ac, Bc) + Dc for x in f])
    assert np.abs(realised / compensator.transfer(f) - 1).max() < 1e-12


def test_a_type_iii_design_meets_its_crossover_and_phase_margin_on_the_exact_loop_gain(design):
    """fc = fs/10 and 60 degrees designed on the exact control-to-output at the duty ratio giving 5 V (k-factor);
    measured on the exact loop gain of the closed loop: 9,620 Hz (3.8 % low: the carrier samples vc with its
    ripple) and 60.03 degrees (issue: within 5 % and 3 degrees)."""
    assert design.compensator.kind == "type III" and design.duty == pytest.approx(5 / 12, rel=1e-9)
    params = {**PLANT, "Vref": 5.0, **design.compensator.as_dict()}
    response, margins = loop_gain(resolve_model("buck", "voltage-loop"), params)
    assert margins.crossover_hz == pytest.approx(FS / 10, rel=0.05)
    assert margins.phase_margin_deg == pytest.approx(60.0, abs=3.0)
    # the design's own arithmetic: |Gc Fm Gvd| = 1 and the phase margin at fc on the plant it was designed on
    plant = SmallSignalModel("buck", {**PLANT, "D": design.duty}, input="D").response([FS / 10])[0]
    loop = design.compensator.transfer(FS / 10) * plant
    assert abs(loop) == pytest.approx(1.0, rel=1e-9)
    assert 180 + math.degrees(np.angle(loop)) == pytest.approx(60.0, abs=1e-6)


@pytest.mark.parametrize("method, tol", [("event", 1e-9), ("lcp", 1e-4)])
def test_the_integrator_regulates_the_mean_output_to_vref(design, method, tol):
    params = {**PLANT, "Vref": 5.0, **design.compensator.as_dict()}
    tr = run_converter(resolve_model("buck", "voltage-loop"), params, method=method, steady=True, periods=2)
    assert tr.mean("vout") == pytest.approx(5.0, abs=tol * 5.0)



@pytest.mark.parametrize("kind", ["type III", "PI"])
def test_with_an_esr_and_a_load_current_the_loop_senses_the_output_node(design, kind):
    """With rC > 0 the buck's output is a vC + b (iL - Io) (b = R rC / (R + rC)): the sensed offset -b Io enters
    the integrator (the mean of vout is Vref exactly, not Vref - b Io = 4.975 V) and the comparator's direct term
    (a PI's Dc = wi / wz1: the switch turns off where the compensator's output vc, computed from the output node's
    voltage, meets the carrier; without the offset the two differ by Dc b Io = 24 mV). Exact flows (event method)."""
    compensator = design.compensator if kind == "type III" else Compensator(3e3, (500.0,))
    assert compensator.kind == kind
    params = {**PLANT, "Vref": 5.0, **compensator.as_dict(), "rC": 0.05, "Io": 0.5}
    tr = run_converter(resolve_model("buck", "voltage-loop"), params, method="event", steady=True, periods=2)
    assert tr.metadata["orbit"]["spectral_radius"] < 1.0
    assert tr.mean("vout") == pytest.approx(5.0, abs=5e-9)
    T = 1 / FS
    events = tr.events[tr.events["kind"] == "switch"]
    crossings = events["time"][np.abs(np.remainder(events["time"] / T + 0.5, 1.0) - 0.5) > 1e-6].to_numpy()
    waves = tr.waveforms()
    at = np.flatnonzero(np.isin(waves["time"].to_numpy(), crossings))
    # one crossing a period, sampled at its instant (on both sides: the configuration changes there)
    assert len(crossings) == 2 and len(at) == 4 and np.unique(waves["time"].to_numpy()[at]).size == 2
    np.testing.assert_allclose(waves["vc"].to_numpy()[at], waves["carrier"].to_numpy()[at], rtol=0, atol=1e-9)

def test_a_load_steps_recovery_is_the_exact_models_prediction(design):
    """R 10 -> 5 ohm (a 0.5 A step) from the orbit: the per-period means of vout follow the exact model's closed-loop
    output impedance driven by a 0.5 A step (its Fourier synthesis): the undershoot 60.3 against 68.1 mV, the
    overshoot 12.1 against 11.7 mV, out of a 10 mV band for 0.27 against 0.25 ms (measured; the model's response is
    the component at each frequency, and a period's mean also holds the switching sidebands')."""
    model = resolve_model("buck", "voltage-loop")
    base = {**PLANT, "Vref": 5.0, **design.compensator.as_dict()}
    orbit = steady_state(model, model.resolve(base), EventDriven())
    T = 1 / FS
    tr = run_converter(model, {**base, "t_step": "1m", "R_step": 5}, method="event", t_end="2m", x0=orbit.x0)
    simulated = np.array([tr.mean("vout", t0=1e-3 + j * T, t1=1e-3 + (j + 1) * T) for j in range(100)]) - 5.0
    small = SmallSignalModel(model, {**base, "Io": 0.0}, input="Io", outputs=("vout",))
    P, K = 2e-3, np.arange(1, 400, 2)                     # a 0.5 A square wave of period P: its odd harmonics
    t = np.linspace(0, P / 2, 20001)
    wave = np.real(np.sum((small.response(K / P, "vout") / (1j * np.pi * K))[None, :]
                          * np.exp(2j * np.pi * np.outer(t, K / P)), axis=1))
    deviation = wave - wave[-1]
    predicted = np.array([deviation[(t >= j * T) & (t < (j + 1) * T)].mean() for j in range(100)])
    assert simulated.min() == pytest.approx(predicted.min(), rel=0.15)
    assert simulated.max() == pytest.approx(predicted.max(), rel=0.10)

    def out_of_band(x, band=0.01):
        return (np.flatnonzero(np.abs(x) > band)[-1] + 1) * T
    assert out_of_band(simulated) == pytest.approx(out_of_band(predicted), rel=0.2)


@pytest.mark.parametrize("control, params", [
    ("voltage-loop", {**PLANT, "Vref": 5.0, "wi": 3716.385, "fz1": 1358.07, "fz2": 1358.07, "fp1": 73633.7,
                      "fp2": 73633.7}),
    ("voltage-mode", {"Vin": 20, "latch": 1}),
    ("peak-current", {"Iref": 0.6, "ma": 2e4}),
])
def test_a_load_step_at_a_period_start_is_clocked_there(control, params):
    """A run split at a load step that falls on a clock edge starts its second part with the clock's decision (s
    against the band), as every period does: a 1 % step then moves vout by what the loop's output impedance says.
    The law had kept the configuration of the period before (the switch off for a whole period): a 45 mV dip for a
    5 mA step on the compensated buck, where the orbit moves 0.6 mV."""
    model = resolve_model("buck", control)
    p = model.resolve(params)
    orbit = steady_state(model, p, EventDriven())
    T = model.period(p)
    R2 = p["R"] * 0.99
    stepped = run_converter(model, {**params, "t_step": 100 * T, "R_step": R2}, method="event", t_end=130 * T,
                            x0=orbit.x0)
    plain = run_converter(model, {**params, "R": R2}, method="event", t_end=30 * T, x0=orbit.x0)
    after = np.array([stepped.mean("vout", t0=(100 + j) * T, t1=(101 + j) * T) for j in range(30)])
    same = np.array([plain.mean("vout", t0=j * T, t1=(j + 1) * T) for j in range(30)])
    assert np.abs(after - same).max() < 1e-9 * abs(same).max()


def test_what_a_design_cannot_give_is_refused():
    with pytest.raises(ParameterError, match="a type2 compensator boosts the phase by less than 90 degrees"):
        design_compensator("buck", PLANT, crossover_hz=FS / 10, phase_margin_deg=60, vref=5.0, kind="type2")
    with pytest.raises(ParameterError, match=r"crossover_hz must be in \(0, fs/2 = 50000 Hz\)"):
        design_compensator("buck", PLANT, crossover_hz=FS, phase_margin_deg=60, vref=5.0)
    with pytest.raises(ParameterError, match="as many zeros as poles"):
        Compensator(1e3, (), (1e3,))


@pytest.mark.slow
def test_the_report_section_shows_the_loop_before_and_after_and_passes():
    from validation.sections import control_section
    section = control_section()
    assert section.ok and section.status == "pass"
    assert section.metrics["crossover_hz"] == pytest.approx(9619.81, rel=1e-4)
    assert section.files["loop_gain.png"][:4] == b"\x89PNG" and "before and after" in section.html
