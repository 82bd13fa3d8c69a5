"""Controls compose with converters (converters.models.control): the loop's law around the converter's own circuit,
its parasitics and steps; the registry builds each (converter, control) model from the two."""
import pickle

import numpy as np
import pytest

from converters.errors import ParameterError
from converters.models import CONTROLS, CONVERTERS, DEFAULT_CONTROL, MODELS, Controlled, get_model
from converters.run import run_converter, run_summary


@pytest.mark.parametrize("key", [k for k in MODELS if k[1] != DEFAULT_CONTROL])
def test_a_control_closes_its_loop_around_the_converters_own_circuit(key):
    """The closed loop's configurations are its converter's at the same circuit values (the circuit is stated once,
    in the converter's netlist), with the controller's states after the circuit's (a compensator's), its parameters
    the converter's but those the loop sets, then the loop's own."""
    name, control = key
    model, converter, loop = MODELS[key], CONVERTERS[name], CONTROLS[control]
    assert isinstance(model, Controlled) and model.converter is converter and model.loop is loop
    p = model.resolve({})
    circuit = converter.resolve({k: v for k, v in p.items() if k in {q.name for q in converter.parameters}})
    n = len(converter.state_names)
    for ours, theirs in zip(model.configurations(p), converter.configurations(circuit), strict=True):
        assert ours.n == n + len(loop.controller_states(p))
        for m, block in (("A", np.s_[:n, :n]), ("B", np.s_[:n]), ("C", np.s_[:, :n]), ("D", np.s_[:]),
                         ("E", np.s_[:n]), ("F", np.s_[:])):
            np.testing.assert_array_equal(np.asarray(getattr(ours, m))[block], getattr(theirs, m))
        np.testing.assert_array_equal(np.asarray(ours.A)[:n, n:], 0.0)        # the controller does not act on the circuit
    names = [q.name for q in model.parameters]
    assert not set(loop.sets) & set(names)
    assert names[-len(loop.parameters):] == [q.name for q in loop.parameters]
    assert pickle.loads(pickle.dumps(model)) is model              # a sweep's worker gets the registry's model


@pytest.mark.parametrize("method, tol", [("event", 1e-9), ("lcp", 1e-3)])
def test_voltage_mode_senses_vout_through_the_capacitors_esr(method, tol):
    """With rC = 50 mOhm (and rL = 0.2 ohm) the comparator reads vout = a vC + b iL, not vC: at every closing of the
    switch A (vout - Vref) equals the ramp (event method: to 1.4e-13 V, measured; the stepper, which locates the
    closing inside its step: 4.7e-5 V), where A (vC - Vref) misses it by 11 mV or more."""
    tr = run_converter("buck", {"rC": 0.05, "rL": 0.2, "Vin": 20}, control="voltage-mode", method=method, periods=60)
    closings = tr.events.loc[(tr.events["kind"] == "switch") & (tr.events["config"] == 0), "time"].to_numpy()
    assert len(closings) > 40
    ramp = tr.signal("ramp")
    sensed = tr.signal("vcon") - ramp
    vc_only = 8.4 * (tr.state("vC") - 11.3) - ramp

    def at(signal, t):
        row = np.searchsorted(tr.t, t)
        return np.interp(t, tr.t[row - 1:row + 1], signal[row - 1:row + 1])

    assert max(abs(at(sensed, t)) for t in closings) < tol
    assert min(abs(at(vc_only, t)) for t in closings) > 1e-2
    p = get_model("buck", "voltage-mode").resolve({"rC": 0.05, "rL": 0.2, "Vin": 20})
    a, b = p["R"] / (p["R"] + 0.05), p["R"] * 0.05 / (p["R"] + 0.05)
    np.testing.assert_allclose(tr.signal("vout"), a * tr.state("vC") + b * tr.state("iL"), rtol=1e-12)


def test_voltage_mode_buck_takes_a_load_step_and_settles_on_the_closed_loops_orbit_after_it():
    """R 22 -> 11 ohm at 100 T (Vin 20 V: period 1 on both sides): the step response's final value is the periodic
    orbit of the same loop at R = 11 ohm, the run's last periods sit on it, and the power balance holds."""
    tr = run_converter("buck", {"Vin": 20, "t_step": "40m", "R_step": 11}, control="voltage-mode", method="event",
                       periods=400)
    summary = run_summary(tr, check=False)
    step = summary["step"]
    orbit = run_converter("buck", {"Vin": 20, "R": 11}, control="voltage-mode", method="event", steady=True)
    assert step["final_from"] == "steady state after the step"
    assert step["vout_final"] == pytest.approx(orbit.mean("vout", t0=orbit.t[0]), rel=1e-9)
    assert step["settled"] and step["vout_end"] == pytest.approx(step["vout_final"], rel=1e-6)
    # lossless and in CCM (K = 4.5, 2.3) the loop's averaged value v = Vin (VU + A Vref) / (VU - VL + A Vin)
    # does not depend on R: the load step barely moves vout (3.2 mV, measured; the ripple the comparator sees)
    averaged = 20 * (8.2 + 8.4 * 11.3) / (8.2 - 3.8 + 8.4 * 20)
    assert step["vout_before"] == pytest.approx(averaged, rel=2e-3)
    assert step["vout_final"] == pytest.approx(step["vout_before"], rel=1e-3)
    assert abs(summary["power"]["balance"]) < 1e-6


def test_the_comparators_input_senses_the_circuit_in_force_after_a_load_step():
    """vcon = A (vout - Vref) at every point, vout read behind the ESR with the load in force: after the step (R 22 ->
    11 ohm, rC 0.2 ohm) the ESR's divider is the stepped circuit's (vcon had read it with the nominal R: 0.95 V
    apart, measured)."""
    tr = run_converter("buck", {"Vin": 20, "rC": 0.2, "t_step": "8m", "R_step": 11}, control="voltage-mode",
                       method="event", periods=40)
    np.testing.assert_allclose(tr.signal("vcon"), 8.4 * (tr.signal("vout") - 11.3), rtol=0, atol=1e-12)
    closings = tr.events.loc[(tr.events["kind"] == "switch") & (tr.events["config"] == 0), "time"].to_numpy()
    after = closings[closings > 8e-3]
    rows = np.searchsorted(tr.t, after)
    assert len(after) > 10 and np.abs(tr.t[rows] - after).max() == 0.0          # the event instants are samples
    assert np.abs((tr.signal("vcon") - tr.signal("ramp"))[rows]).max() < 1e-9     # the law switches on that vcon


def test_a_control_names_where_it_applies_and_what_it_keeps():
    with pytest.raises(ParameterError, match=r"--control voltage-mode is available for buck only \(boost takes "
                                             r"--control pwm, smc, smc-implicit, peak-current, valley-current, current-loop, voltage-loop\); got 'boost'"):
        get_model("boost", "voltage-mode")
    with pytest.raises(ParameterError, match="unknown parameter 'rC' for boost --control smc"):
        get_model("boost", "smc").resolve({"rC": 0.1})
    with pytest.raises(ParameterError, match=r"Vin \(input voltage\) must be in \(0, inf\) V; got 0"):
        get_model("boost", "smc").resolve({"Vin": 0})
    with pytest.raises(ParameterError, match="has no PWM schedule"):
        get_model("buck", "voltage-mode").schedule(get_model("buck", "voltage-mode").resolve({}))
