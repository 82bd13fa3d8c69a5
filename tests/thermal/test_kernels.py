"""The compiled passes of the losses (converters/thermal/kernels.py) against the numpy forms they replace: the
signal table against the model's one-signal reads, the conduction's and switching energies' sums against
Window.quadrature and Table.weighted_sum, to rounding, inside the tables' temperatures and outside them (where a
clip at zero may act)."""
from pathlib import Path

import numpy as np
import pytest

from converters.models import get_model
from converters.run import run_converter
from converters.thermal import DeviceDescription, ThermalChain, energy_table, on_state_table
from converters.thermal.losses import CONDUCTING, Window, _kinks, waveforms
from converters.thermal.network import declared_setup, read_setup

CIRCUITS = Path(__file__).resolve().parents[2] / "netlists" / "circuits"


def _run(name, **kwargs):
    model = get_model(str(CIRCUITS / name))
    p = model.resolve({})
    return model, p, run_converter(model, p, **kwargs)


@pytest.mark.parametrize("name", ["sync-buck-thermal.cir", "rectifier-1ph.cir"])   # gate waveforms; a SIN source
def test_the_signal_table_is_each_signals_own_read(name):
    model, p, tr = _run(name, periods=2)
    names = model.compiled(p).signal_names
    for rows in (np.arange(tr.t.size), np.arange(0, tr.t.size, max(tr.t.size // 40, 1))):   # compiled; gathered
        samples = tr.samples(rows)
        for subset in (None, names[::-2]):
            table = model.signal_table(samples, p, subset)
            for k, signal in enumerate(names if subset is None else subset):
                own = model.signal(signal, samples, p)
                assert np.allclose(table[:, k], own, rtol=1e-12, atol=1e-12 * (1.0 + np.abs(own).max())), signal


def _reference(window, description, name, model, p, tj, cut=True):
    """A switch's conduction loss by the numpy forms: Window.quadrature (its steps cut at the table's kinks, or
    not) and Table.weighted_sum."""
    read = window.read
    compiled = model.compiled(p)
    k = compiled.switch_names.index(name)
    closed = np.array([c[k] for c in compiled.closed], dtype=bool)
    table = description.conduction
    i, w = window.quadrature(lambda s: read(f"i({name})", s), lambda s: closed[np.asarray(s.config, dtype=int)],
                             _kinks([table])[:, 0] if cut else None)
    return table.weighted_sum(table.slices(i), w * i)(tj)


def test_a_step_across_a_kink_of_the_on_state_table_is_integrated_exactly():
    # the low side's current runs from about 8 A to 12 A: across a kink at 10 A (0.1 V there, 0.6 V at 40 A)
    drop = on_state_table("drop", [0.0, 10.0, 40.0], [25.0, 125.0], [[0.0, 0.1, 0.6], [0.0, 0.15, 0.8]])
    description = DeviceDescription("Q", "MOSFET", None, None, drop, ThermalChain("foster", (0.5,), (1e-3,)))
    model, p, tr = _run("sync-buck-thermal.cir", steady=True)
    T = model.period(p)
    t1 = float(tr.t[-1])
    window = Window(model, p, tr, t1 - T, t1)
    compiled = waveforms(model, p, tr, {"s2": description}, t1 - T, t1, window)["s2"].losses(25.0).conduction_W
    cut, uncut = (_reference(window, description, "s2", model, p, 25.0, c) for c in (True, False))
    # the run's current linear on each step: the integral by 64 sub-steps each (midpoints), independent of the cuts
    rows = window.rows
    i = np.abs(model.signal("i(s2)", rows, p))
    a = i[:-1].copy()
    a[window.edges] = np.abs(model.signal("i(s2)", window.edge_starts, p))
    on = np.array([c[model.compiled(p).switch_names.index("s2")] for c in model.compiled(p).closed])
    on_at = on[np.asarray(rows.config, dtype=int)][:-1]
    on_at[window.edges] = on[np.asarray(window.edge_starts.config, dtype=int)]
    f = (np.arange(64) + 0.5) / 64
    sub = a[:, None] + f * (i[1:] - a)[:, None]
    dense = float(np.sum(np.diff(rows.t)[:, None] * on_at[:, None] * sub * np.interp(sub, [0, 10, 40], [0, 0.1, 0.6]))
                  / 64 / T)
    assert compiled == pytest.approx(cut, rel=1e-12)
    assert cut == pytest.approx(dense, rel=1e-9)             # 1.2e-11 (the midpoints' own error at the kinks)
    assert abs(uncut - dense) > 10 * abs(cut - dense)      # uncut 3.4e-10: a step across the kink read to O(h^2)


@pytest.mark.parametrize("tj", [60.0, 10.0, 190.0])      # inside the tables' temperatures, below, above
def test_the_compiled_conduction_and_energies_are_the_numpy_forms(tj):
    model, p, tr = _run("sync-buck-thermal.cir", steady=True)
    setup = read_setup(declared_setup(model.netlist.text, model.source))
    T = model.period(p)
    t1 = float(tr.t[-1])
    window = Window(model, p, tr, t1 - T, t1)
    assert window.rule == "linear"                       # the compiled pass's case
    read = waveforms(model, p, tr, {d: m.description for d, m in setup.devices.items()}, t1 - T, t1, window)
    for name in ("s1", "s2"):
        description = setup.devices[name].description
        assert read[name].losses(tj).conduction_W == pytest.approx(
            _reference(window, description, name, model, p, tj), rel=1e-12)
        for edges, table, kind in ((read[name].on_edges, description.turn_on, "turn_on_W"),
                                   (read[name].off_edges, description.turn_off, "turn_off_W")):
            if edges[0].size:
                numpy_form = table.weighted_sum(table.slices(*edges), np.full(edges[0].size, 1.0 / T))(tj)
                assert getattr(read[name].losses(tj), kind) == pytest.approx(numpy_form, rel=1e-12)
    assert read["s1"].losses(tj).turn_on_W > 0 and read["s1"].losses(tj).conduction_W > 0


def test_a_table_read_below_zero_is_clipped_by_the_compiled_pass_as_by_the_numpy_form():
    # a drop tabulated from 10 A on: extrapolated to the low side's smaller currents (8 to 12 A) it falls below
    # zero, and an energy tabulated from 10 A likewise; the compiled sums cannot be used there, the clip acts
    chain = ThermalChain("foster", (0.5,), (1e-3,))
    drop = on_state_table("drop", [10.0, 12.0], [25.0, 125.0], [[0.1, 0.5], [0.2, 0.7]])
    energy = energy_table("E", [0.0, 48.0], [10.0, 12.0], [25.0, 125.0],
                          [[[0.0, 0.0], [0.0, 4e-6]], [[0.0, 0.0], [0.0, 5e-6]]])
    description = DeviceDescription("Q", "MOSFET", energy, energy, drop, chain)
    model, p, tr = _run("sync-buck-thermal.cir", steady=True)
    T = model.period(p)
    t1 = float(tr.t[-1])
    window = Window(model, p, tr, t1 - T, t1)
    read = waveforms(model, p, tr, {"s2": description}, t1 - T, t1, window)["s2"]
    reference = _reference(window, description, "s2", model, p, 60.0)
    assert read.losses(60.0).conduction_W == pytest.approx(reference, rel=1e-12)
    i, w = read.current, read.weight
    unclipped = float((drop.slices(i) @ (w * i)) @ [0.65, 0.35])     # 60 degC: 0.35 of the way to 125
    assert abs(unclipped - reference) > 1e-3 * reference               # the clip acts: the test can fail
    assert CONDUCTING > 0
    # s1 turns on at its valley current (about 8 A): the energy read there below zero, clipped
    s1 = waveforms(model, p, tr, {"s1": description}, t1 - T, t1, window)["s1"]
    v, i = s1.on_edges
    numpy_form = energy.weighted_sum(energy.slices(v, i), np.full(v.size, 1.0 / T))(60.0)
    assert s1.losses(60.0).turn_on_W == pytest.approx(numpy_form, rel=1e-12)
    assert abs(float(energy.slices(v, i).sum(axis=1) @ [0.65, 0.35]) / T - numpy_form) > 1e-3 * numpy_form
