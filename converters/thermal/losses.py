"""A device's losses over a window of a netlist's run, from its description's tables.

As PLECS computes them with ideal switches: the circuit runs as it is; each device's losses are read from its
tables at the run's currents and voltages and at a given junction temperature.

* conduction: the mean over the window of v_on(|i|, Tj) |i| while the device conducts (a switch while closed, its
  channel conducting either way with the same drop; a diode while its current is positive), integrated by the
  run's own rule (the exact method's quadrature on its exact pieces);
* turn-on and turn-off: at each of the device's switching edges in the window, E_on(V blocked before the edge,
  I conducted after it, Tj) and E_off(V blocked after it, I conducted before it, Tj) (a diode's turn-off energy is
  its reverse recovery), summed and divided by the window's length. The values before and after an edge are the
  circuit's at the edge's instant in the configuration it ends and in the one it begins
  (:meth:`converters.trajectory.Trajectory.edges`).
"""
from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from ..errors import ParameterError
from ..trajectory import Samples, Trajectory
from .description import DeviceDescription
from .tables import Table

#: A diode conducts where its current exceeds this fraction of its largest in the window (an ideal diode's current
#: is zero to rounding when it blocks).
CONDUCTING = 1e-9


@dataclass(frozen=True)
class DeviceLosses:
    """One device's losses over a window (W) at the junction temperature ``tj`` (degC)."""

    name: str
    kind: str
    tj: float
    conduction_W: float
    turn_on_W: float
    turn_off_W: float
    turn_ons: int
    turn_offs: int

    @property
    def total_W(self) -> float:
        return self.conduction_W + self.turn_on_W + self.turn_off_W

    def summary(self) -> dict[str, Any]:
        off = "recovery_W" if self.kind == "Diode" else "turn_off_W"
        return {"kind": self.kind, "tj_C": self.tj, "conduction_W": self.conduction_W, "turn_on_W": self.turn_on_W,
                off: self.turn_off_W, "total_W": self.total_W, "turn_ons": self.turn_ons, "turn_offs": self.turn_offs}


@dataclass(frozen=True)
class Waveforms:
    """What a device's losses are read from, taken once from a run: the conduction's quadrature (the device's
    |current| at the nodes, each node's weight over the window's length, zero where it does not conduct) and, at
    its edges, the (blocked voltage, current) of each turn-on and each turn-off. Its losses at a junction
    temperature are then a few table reads (:meth:`losses`), as the temperature is iterated."""

    name: str
    description: DeviceDescription
    current: npt.NDArray[np.float64]
    weight: npt.NDArray[np.float64]
    on_edges: tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]
    off_edges: tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]
    span: float

    def __post_init__(self) -> None:
        # the tables read at the run's currents and voltages once, at each of their temperatures (Table.slices):
        # an evaluation at a junction temperature is then a blend of two of them
        d, cache = self.description, self.__dict__
        cache["_drop"] = None if d.conduction is None else d.conduction.slices(self.current)
        cache["_on"] = None if d.turn_on is None else d.turn_on.slices(*self.on_edges)
        cache["_off"] = None if d.turn_off is None else d.turn_off.slices(*self.off_edges)

    def losses(self, tj: float) -> DeviceLosses:
        d, cache = self.description, self.__dict__

        def energy(table: Table | None, slices: npt.NDArray[np.float64] | None) -> float:
            return 0.0 if table is None or slices is None else float(table.blend(slices, tj).sum()) / self.span
        conduction = (0.0 if d.conduction is None else
                      float(self.weight @ (d.conduction.blend(cache["_drop"], tj) * self.current)))
        return DeviceLosses(self.name, d.kind, tj, conduction, energy(d.turn_on, cache["_on"]),
                            energy(d.turn_off, cache["_off"]), int(self.on_edges[0].size), int(self.off_edges[0].size))


def device_losses(model: Any, p: dict, tr: Trajectory, descriptions: Mapping[str, DeviceDescription],
                  tj: Mapping[str, float], t0: float, t1: float) -> dict[str, DeviceLosses]:
    """Each described device's losses over [t0, t1] of ``tr`` (a run of the netlist ``model`` at ``p``), its
    tables read at ``tj[name]`` (degC). ``descriptions`` maps element names (``s1``, ``d1``) to descriptions."""
    return {name: w.losses(float(tj[name])) for name, w in waveforms(model, p, tr, descriptions, t0, t1).items()}


def waveforms(model: Any, p: dict, tr: Trajectory, descriptions: Mapping[str, DeviceDescription],
              t0: float, t1: float) -> dict[str, Waveforms]:
    """Each described device's :class:`Waveforms` over [t0, t1] of ``tr``."""
    compiled = model.compiled(p)
    elements = {e.name.lower(): e for e in model.netlist.elements}
    rows = tr.rows_between(t0, t1)
    _, before, after = tr.edges(rows)
    out = {}
    for name, description in descriptions.items():
        element = elements.get(name.lower())
        if element is None or element.kind not in "SD":
            raise ParameterError(f"a thermal description names {name!r}, which is no switch (S) or diode (D) of "
                                 f"the circuit ({', '.join(n for n, e in elements.items() if e.kind in 'SD')})")
        if description.kind == "Diode" and element.kind != "D" or description.kind != "Diode" and element.kind != "S":
            raise ParameterError(f"{name}: a {description.kind} description on a {'diode' if element.kind == 'D' else 'switch'}")
        a, b = element.nodes[:2]

        def current(s: Samples, element_name: str = name) -> npt.NDArray[np.float64]:
            return np.asarray(model.signal(f"i({element_name.lower()})", s, p), dtype=float)

        def blocked(s: Samples, a: str = a, b: str = b) -> npt.NDArray[np.float64]:
            # a diode blocks v(cathode) - v(anode), a switch either polarity: read at the magnitude
            return np.abs(np.asarray(model.signal(f"v({a})", s, p) - model.signal(f"v({b})", s, p), dtype=float))

        if element.kind == "S":
            k = compiled.switch_names.index(element.name.lower())
            closed_by = np.array([c[k] for c in compiled.closed], dtype=bool)

            def conducting(s: Samples) -> npt.NDArray[np.bool_]:
                return closed_by[np.asarray(s.config, dtype=int)]
        else:
            peak = float(np.max(np.abs(current(tr.samples(rows))), initial=0.0))

            def conducting(s: Samples) -> npt.NDArray[np.bool_]:
                return current(s) > CONDUCTING * peak

        i, weight = _quadrature(tr, rows, current, conducting, t0, t1)
        was, now = conducting(before), conducting(after)
        ons, offs = np.flatnonzero(~was & now), np.flatnonzero(was & ~now)
        out[name] = Waveforms(name, description, i, weight,
                              (blocked(before)[ons], np.abs(current(after))[ons]),
                              (blocked(after)[offs], np.abs(current(before))[offs]), t1 - t0)
    return out


def _quadrature(tr: Trajectory, rows: npt.NDArray[np.int_], current: Any, conducting: Any, t0: float,
                t1: float) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
    """(|current| at the nodes, weights over the window's length, zero where the device does not conduct) of the
    mean of a function of the current over [t0, t1]: the exact method's quadrature on its exact pieces, or, on a
    run read linearly between its points, Simpson's rule on each step's current (linear there): exact for a drop
    linear in the current, as the run's own RMS is (its (a^2 + a b + b^2) / 3); the end-point rule on a run read
    so."""
    if tr.rule == "exact" and tr.exact is not None:
        blocks = list(tr.exact.quadrature_blocks(t0, t1))
        i = np.concatenate([np.abs(current(nodes)) for nodes, _ in blocks])
        w = np.concatenate([weights * conducting(nodes) for nodes, weights in blocks])
        return i, w / (t1 - t0)
    samples = tr.samples(rows)
    i, on = current(samples), conducting(samples)
    a, a_on = i[:-1].copy(), on[:-1].copy()
    edges, _, after = tr.edges(rows)
    a[edges], a_on[edges] = current(after), conducting(after)      # a step that starts at an edge: its own side
    dt = np.diff(samples.t) / float(samples.t[-1] - samples.t[0])
    b = i[1:]
    if tr.rule == "end":
        return np.abs(b), dt * on[1:]
    step = dt * a_on / 6.0
    return np.abs(np.concatenate([a, 0.5 * (a + b), b])), np.concatenate([step, 4.0 * step, step])
