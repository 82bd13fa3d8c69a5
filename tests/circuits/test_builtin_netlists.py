"""The built-in circuits as netlists (netlists/circuits/*.cir), compiled by modified nodal analysis, against the
hand-derived matrices (tests/models/hand.py, the independent oracle): the same periodic orbit to 1e-10 relative,
the same event instants and the same modes (GDCM included) at the exact operating points of the accuracy tests;
the library's converters (compiled from those files) have the hand matrices with every parasitic."""
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from converters.analysis.accuracy import mode_fractions, substep_events
from converters.models import Circuit
from converters.methods import EventDriven
from converters.run import steady_state
from converters.simulate import simulate

from ..analysis.points import POINTS as ACCURACY_POINTS
from ..models.hand import HAND

NETLISTS = Path(__file__).resolve().parents[2] / "netlists" / "circuits"
#: The accuracy tests' operating points (CCM, DCM at 0.37 % conduction, GDCM-ON, GDCM-OFF, 10 kHz to 1 MHz).
POINTS = {**ACCURACY_POINTS, "prc": ("prc", {}), "prc-n2": ("prc", {"n": 2.0})}
STATES = {"buck": {"iL": "i(l1)", "vC": "v(c1)"}, "boost": {"iL": "i(l1)", "vC": "v(c1)"},
          "buck-boost": {"iL": "i(l1)", "vC": "v(c1)"},
          "cuk": {"i1": "i(l1)", "v1": "v(c1)", "i2": "i(l2)", "v2": "v(c2)"},
          "prc": {"ir": "i(lr)", "vr": "v(cr)", "iLf": "i(lf)", "vo": "v(cf)"}}
PAIRS = {"diode": "d1", "D1": "d1", "D2": "d2", "D3": "d3", "D4": "d4"}
#: The hand models' mode labels in the netlist's words (closed switches and conducting diodes).
MODES = {"CCM-ON": "S1", "CCM-OFF": "D1", "DCM": "off", "GDCM-ON": "S1+D1", "GDCM-OFF": "off"}


def _period(model, p):
    T = model.period(p)
    try:
        orbit = steady_state(model, p, EventDriven(), tol=1e-11)
    except Exception:                       # near rho = 1 the orbit resolves to ~1e-11 only
        orbit = steady_state(model, p, EventDriven(), tol=1e-10)
    tr = replace(simulate(model.problem(p, T, orbit.x0), EventDriven(output_step=T / 4096)), labels=model.labels(p))
    events = substep_events(tr, T)
    edges = np.asarray(model.problem(p, T).switching.breakpoints(0.0, T), dtype=float)
    events = [e for e in events if not np.any(np.abs(np.concatenate([edges, [0.0, T]]) - e[2] * T) <= 1e-9 * T)]
    # simultaneous events (a bridge's commutation) in a fixed order
    events = sorted(events, key=lambda e: (round(e[2], 9), PAIRS.get(e[0], e[0]), e[1]))
    return orbit, tr, events, mode_fractions(tr, T, events, edges)


@pytest.mark.parametrize("key", list(POINTS))
def test_the_compiled_netlist_has_the_hand_models_orbit_events_and_modes(key):
    name, params = POINTS[key]
    hand = HAND[name]
    circuit = Circuit.from_netlist(NETLISTS / f"{name}.cir")
    p_hand, p_circuit = hand.resolve(params), circuit.resolve(params)
    assert circuit.period(p_circuit) == pytest.approx(hand.period(p_hand), rel=1e-15)
    orbit_h, tr_h, events_h, modes_h = _period(hand, p_hand)
    orbit_c, tr_c, events_c, modes_c = _period(circuit, p_circuit)
    order = [circuit.state_names.index(STATES[name][s]) for s in hand.state_names]
    x_h, x_c = orbit_h.x0, orbit_c.x0[order]
    assert np.abs(x_c - x_h).max() <= 1e-10 * np.abs(x_h).max()
    # which pair changes when (held/released names the port's own state, which follows the port form the compiler
    # chose: the conduction it means is compared through the modes below)
    assert [PAIRS[pair] for pair, _, _ in events_h] == [pair for pair, _, _ in events_c]
    for (_, _, a), (_, _, b) in zip(events_h, events_c):
        assert abs(a - b) <= 1e-10
    translated = {}
    for label, fraction in modes_h.items():
        mine = MODES.get(label, "+".join(sorted(label.split("+"))))
        translated[mine] = translated.get(mine, 0.0) + fraction
    ours = {"+".join(sorted(k.split("+"))) if "S" not in k else k: v for k, v in modes_c.items()}
    assert set(translated) == set(ours)
    for label, fraction in translated.items():
        assert ours[label] == pytest.approx(fraction, abs=1e-10)
    assert np.abs(tr_c.mean("vout", t0=0, t1=hand.period(p_hand)) - tr_h.mean("vout", t0=0, t1=hand.period(p_hand))) \
        <= 1e-10 * abs(tr_h.mean("vout", t0=0, t1=hand.period(p_hand)))


@pytest.mark.parametrize("name, problem", [("diode-bridge", "diode_bridge"), ("half-wave", "half_wave_rectifier")])
def test_the_siconos_diode_circuits_follow_the_hand_lcs_exactly(name, problem):
    """From vC(0) = 10 V, 5 ms: the compiled and the hand-derived LCS give the same exact (event-driven) states."""
    from .. import oracle_circuits as circuits
    hand = simulate(getattr(circuits, problem)(), EventDriven(output_step=1e-5))
    circuit = Circuit.from_netlist(NETLISTS / f"{name}.cir")
    compiled = simulate(circuit.problem(circuit.resolve({}), 5e-3), EventDriven(output_step=1e-5))
    order = [circuit.state_names.index(s) for s in ("v(c1)", "i(l1)")]
    assert np.abs(compiled.x[:, order] - hand.x).max() <= 1e-9 * np.abs(hand.x).max()
    assert len(compiled.events) == len(hand.events)


#: Each parasitic alone and all together, at values that move every matrix entry they enter.
PARASITICS = {"pwm2": [{}, {"rL": 0.03}, {"Ron": 0.05}, {"Vf": 0.7}, {"Rd": 0.02}, {"rC": 0.01},
                       {"rL": 0.03, "Ron": 0.05, "Vf": 0.4, "Rd": 0.02, "rC": 0.01, "R": 3.3, "Vin": 48}],
              "cuk": [{}, {"rL1": 0.03}, {"rL2": 0.07}, {"Ron": 0.05}, {"Vf": 0.7}, {"Rd": 0.02},
                      {"rL1": 0.03, "rL2": 0.07, "Ron": 0.05, "Vf": 0.4, "Rd": 0.02, "D": 0.7}],
              "prc": [{}, {"n": 2.0}, {"n": 0.5, "R": 10.0, "Vin": 5.0}]}


@pytest.mark.parametrize("name, params", [(name, params) for name in ("buck", "boost", "buck-boost", "cuk", "prc")
                                          for params in PARASITICS.get(name, PARASITICS["pwm2"])])
def test_the_library_converter_is_its_netlist_compiled_and_has_the_hand_matrices(name, params):
    """Every matrix of both configurations to 1e-13 relative (the ports the same: D3 and D4 of the PRC's bridge are
    currents where the hand derivation took D1 and D3, which the orbit test above compares)."""
    from converters.models import get_model
    model, hand = get_model(name), HAND[name]
    p = model.resolve(params)
    assert type(model).configurations is not type(hand).configurations
    compiled, derived = model.configurations(p), hand.configurations(hand.resolve(params))
    assert [c.name for c in compiled] == [c.name for c in derived]
    if name == "prc":          # the ports differ: the same system, compared on what does not depend on them
        for a, b in zip(compiled, derived):
            assert np.allclose(a.A, b.A, rtol=1e-13, atol=0) and np.allclose(a.E, b.E, rtol=1e-13, atol=0)
        return
    assert model.pair_currents == hand.pair_currents
    for a, b in zip(compiled, derived):
        for key in "ABCDEF":
            x, y = getattr(a, key), getattr(b, key)
            assert np.abs(x - y).max() <= 1e-13 * max(np.abs(y).max(), 1.0), (key, x, y)
