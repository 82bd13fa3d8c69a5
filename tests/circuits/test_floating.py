"""Nodes the circuit leaves floating: while every diode that ties a group of nodes to the rest blocks, nothing sets
their common potential (a bridge rectifier's output fed from a source that rests at 0, a two-switch forward's
winding between its clamp diodes once its current has reset). The ideal circuit gives no value there (the LCP
picks one of many, SPICE's comes from its leakages), so simulate warns and compare refuses to compare such an
output; a difference across the floating nodes is set, and a node behind an off diode and an inductor (a DCM buck's
switch node) is set by the inductor's current and is not floating.

Closed forms: the bridge from PULSE(0 Vpk) blocks all four diodes exactly while the source is at 0 (with C
charged, a source at 0 reverse-biases all four), half the period less the edges' e = 1e-6 T; the forward's idle
interval (S1, S2 open and the primary's current reset) is 1 - 2 D of the period (the reset lasts the on time).
"""
import math
from pathlib import Path

import numpy as np
import pytest

from converters.errors import ParameterError
from converters.models import Circuit
from converters.run import run_converter, run_summary
from validation.circuit_compare import compare_circuit

NETLISTS = Path(__file__).resolve().parents[2] / "netlists" / "circuits"


def bridge_from_zero(tmp_path, output="v(p)"):
    """The shipped bridge rectifier fed by PULSE(0 Vpk) (every diode blocks while the source rests at 0), its
    output ``output``."""
    text = (NETLISTS / "bridge-rectifier.cir").read_text().replace("PULSE({-Vpk}", "PULSE(0")
    text = text.replace(".meas tran vout_mean AVG v(p,n)", f".meas tran vout_mean AVG {output}")
    path = tmp_path / "bridge0.cir"
    path.write_text(text)
    return Circuit.from_netlist(path)


def test_the_compile_finds_the_common_potential_of_the_bridge_output(tmp_path):
    """One configuration (the source's level 0), one shift: v(p) and v(n) together by 1/sqrt(2) each (a unit
    vector), the source's nodes unmoved, and each diode's voltage moved by the same magnitude."""
    circuit = bridge_from_zero(tmp_path)
    c = circuit.compiled(circuit.resolve({}))
    found = [f for f in c.floating if f is not None]
    assert len(found) == len(c.configurations) == 2
    for signals, ports in found:
        assert signals.shape[1] == 1
        row = dict(zip(c.signal_names, np.abs(signals[:, 0])))
        assert row["v(p)"] == pytest.approx(1 / math.sqrt(2), rel=1e-12)
        assert row["v(n)"] == pytest.approx(1 / math.sqrt(2), rel=1e-12)
        assert row["v(a)"] == row["v(a0)"] == 0.0
        assert all(v == 0.0 for name, v in row.items() if name.startswith("i("))
        np.testing.assert_allclose(np.abs(ports[:, 0]), 1 / math.sqrt(2), rtol=1e-12)


@pytest.mark.parametrize("method", ["lcp", "event"])
def test_the_bridge_output_floats_while_its_source_rests(tmp_path, method):
    """v(p) floats half the period less the edges (closed form above) on both methods' orbits; v(p,n) never; the
    summary warns naming the nodes, the diodes and the difference to measure."""
    circuit = bridge_from_zero(tmp_path)
    p = circuit.resolve({})
    T = circuit.period(p)
    tr = run_converter(circuit, {}, steady=True, method=method, periods=2)
    t1 = float(tr.t[-1])
    shares = circuit.floating_shares(tr, p, ["vout", "v(n)", "v(p,n)", "v(a)", "i(r1)"], t1 - 2 * T, t1)
    assert set(shares) == {"vout", "v(n)"}
    assert shares["vout"] == pytest.approx(0.5, abs=2e-3)
    summary = run_summary(tr)
    warning = next(w for w in summary["warnings"] if "not set by the circuit" in w)
    assert warning.startswith("v(p) (50 % of the time) is not set by the circuit: while D1, D2, D3 and D4 block, "
                              "nodes p, n float")
    assert "(v(p,n))" in warning


def test_a_set_output_gets_no_warning(tmp_path):
    """The same bridge measured across its output: no warning; nor the shipped DCM buck (R = 10 ohm: K = 2L/(RT)
    = 0.2 < 1 - D), whose switch node behind the blocked diode is set by the inductor's zero current."""
    for circuit in (bridge_from_zero(tmp_path, "v(p,n)"), Circuit.from_netlist(NETLISTS / "buck.cir")):
        tr = run_converter(circuit, {}, steady=True, periods=2)
        summary = run_summary(tr)
        assert not any("not set by the circuit" in w for w in summary.get("warnings", []))
    p = circuit.resolve({})
    t1 = float(tr.t[-1])
    assert "off" in " ".join(tr.mode_fractions(1))          # the DCM interval is there
    assert circuit.floating_shares(tr, p, ["v(sw)", "v(out)"], t1 - circuit.period(p), t1) == {}


@pytest.mark.parametrize("method", ["lcp", "event"])
def test_the_forward_winding_floats_in_the_idle_interval(method):
    """The two-switch forward (D = 0.4): v(pa) and v(pb) float for 1 - 2 D = 0.2 of the period, its output never."""
    circuit = Circuit.from_netlist(NETLISTS / "two-switch-forward.cir")
    p = circuit.resolve({})
    T = circuit.period(p)
    tr = run_converter(circuit, {}, steady=True, method=method, periods=1)
    t1 = float(tr.t[-1])
    shares = circuit.floating_shares(tr, p, ["v(pa)", "v(pb)", "v(pa,pb)", "vout", "v(x)"], t1 - T, t1)
    assert set(shares) == {"v(pa)", "v(pb)"}
    assert shares["v(pa)"] == pytest.approx(1 - 2 * p["d"], abs=2e-3)


def test_compare_refuses_a_floating_output_before_running_ngspice(tmp_path, monkeypatch):
    """compare of the bridge's v(p): one line naming the output and the nodes, before ngspice starts."""
    import validation.spice as spice

    def no_ngspice(*args, **kwargs):
        raise AssertionError("ngspice ran")
    monkeypatch.setattr(spice, "run_spice_retrying", no_ngspice)
    with pytest.raises(ParameterError, match=r"compare: bridge0.cir's output v\(p\) \(50 % of the time\) is not "
                                             r"set by the circuit: while D1, D2, D3 and D4 block, nodes p, n float"):
        compare_circuit(bridge_from_zero(tmp_path))


@pytest.mark.parametrize("method", ["lcp", "event"])
def test_a_sweep_point_whose_output_floats_is_failed(tmp_path, method):
    """A sweep of the bridge read at v(p): every point failed with the reason (the batched stepper's path and the
    event method's per-point path); read at v(p,n) every point is ok, below the source's 10 V peak."""
    from converters.sweeps.ensemble import ModelSweep

    points = [(0, {"R": 50.0}), (1, {"R": 100.0})]
    for output, ok in (("v(p)", False), ("v(p,n)", True)):
        bridge_from_zero(tmp_path, output)
        rows = ModelSweep(str(tmp_path / "bridge0.cir"), method=method, steady=True).rows(points)
        assert [row["status"] == "ok" for row in rows] == [ok, ok]
        if not ok:
            assert all("no value to measure: v(p) (50 % of the time) is not set by the circuit" in row["message"]
                       for row in rows)
        else:
            assert all(0.0 < row["vout_mean"] < 10.0 for row in rows)


def test_the_warning_names_the_floating_group_behind_the_output_only(tmp_path):
    """Two bridges from PULSE(0 Vpk) sources in one file float as two groups at once: v(p) is named with its own
    nodes p, n and diodes D1-D4, not the second bridge's p2, n2 and D5-D8 (the shift that moves v(p) most moves
    those of its own group alone)."""
    text = (NETLISTS / "bridge-rectifier.cir").read_text().replace("PULSE({-Vpk}", "PULSE(0")
    text = text.replace(".meas tran vout_mean AVG v(p,n)", ".meas tran vout_mean AVG v(p)")
    second = ("Vs2 b0 0 PULSE(0 {Vpk} {T/2 - e/2} {e} {e} {T/2 - e} {T})\nR02 b0 b {Rs}\nD5 b p2 DMOD\n"
              "D6 0 p2 DMOD\nD7 n2 b DMOD\nD8 n2 0 DMOD\nC2 p2 n2 {C}\nR2 p2 n2 {R}\n.model DMOD D")
    path = tmp_path / "two-bridges.cir"
    path.write_text(text.replace(".model DMOD D", second))
    circuit = Circuit.from_netlist(path)
    p = circuit.resolve({})
    T = circuit.period(p)
    tr = run_converter(circuit, {}, steady=True, periods=1)
    t1 = float(tr.t[-1])
    both = circuit.floating_shares(tr, p, ["vout", "v(p2)"], t1 - T, t1)
    assert both == pytest.approx({"vout": 0.5, "v(p2)": 0.5}, abs=2e-3)
    assert circuit.floating_text(p, {"vout": both["vout"]}).startswith(
        "v(p) (50 % of the time) is not set by the circuit: while D1, D2, D3 and D4 block, nodes p, n float")
    assert circuit.floating_text(p, {"v(p2)": both["v(p2)"]}).startswith(
        "v(p2) (50 % of the time) is not set by the circuit: while D5, D6, D7 and D8 block, nodes p2, n2 float")
    assert "nodes p, n, p2, n2 float" in circuit.floating_text(p, both)
