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
        cache["_on"] = None if d.turn_on is None or not self.on_edges[0].size else d.turn_on.slices(*self.on_edges)
        cache["_off"] = (None if d.turn_off is None or not self.off_edges[0].size
                         else d.turn_off.slices(*self.off_edges))

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
              t0: float, t1: float, window: Window | None = None) -> dict[str, Waveforms]:
    """Each described device's :class:`Waveforms` over [t0, t1] of ``tr`` (``window``: the window's reading, to
    share with other means over it)."""
    compiled = model.compiled(p)
    elements = {e.name.lower(): e for e in model.netlist.elements}
    window = window or Window(model, p, tr, t0, t1)
    read = window.read
    before, after = _edges_of_period(tr, window.row_indices)
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
            return read(f"i({element_name.lower()})", s)

        def blocked(s: Samples, a: str = a, b: str = b) -> npt.NDArray[np.float64]:
            # a diode blocks v(cathode) - v(anode), a switch either polarity: read at the magnitude
            return np.abs(read(f"v({a})", s) - read(f"v({b})", s))

        if element.kind == "S":
            k = compiled.switch_names.index(element.name.lower())
            closed_by = np.array([c[k] for c in compiled.closed], dtype=bool)

            def conducting(s: Samples) -> npt.NDArray[np.bool_]:
                return closed_by[np.asarray(s.config, dtype=int)]
        else:
            peak = float(np.max(np.abs(current(window.rows)), initial=0.0))

            def conducting(s: Samples) -> npt.NDArray[np.bool_]:
                return current(s) > CONDUCTING * peak

        i, weight = window.quadrature(current, conducting)
        was, now = conducting(before), conducting(after)
        ons, offs = np.flatnonzero(~was & now), np.flatnonzero(was & ~now)
        out[name] = Waveforms(name, description, i, weight,
                              (blocked(before)[ons], np.abs(current(after))[ons]),
                              (blocked(after)[offs], np.abs(current(before))[offs]), t1 - t0)
    return out


class _Signals:
    """The model's signals read once per set of samples (the devices share nodes and edges)."""

    def __init__(self, model: Any, p: dict) -> None:
        self.model, self.p = model, p
        self.memo: dict[tuple[str, int], tuple[npt.NDArray[np.float64], Samples]] = {}

    def __call__(self, name: str, samples: Samples) -> npt.NDArray[np.float64]:
        key = (name, id(samples))
        if key not in self.memo:                # the samples are kept with the values: their id stays theirs
            self.memo[key] = (np.asarray(self.model.signal(name, samples, self.p), dtype=float), samples)
        return self.memo[key][0]


class Window:
    """A window [t0, t1] of a run and where a device's conduction loss is read over it: at the exact method's
    quadrature nodes on its exact pieces, or at the run's points (a step that starts at a switching edge read in its
    own configuration); the model's signals read once per set of points, the devices sharing them."""

    def __init__(self, model: Any, p: dict, tr: Trajectory, t0: float, t1: float) -> None:
        self.read = _Signals(model, p)
        self.rule = tr.rule if tr.rule != "exact" or tr.exact is not None else "linear"
        self.row_indices = rows = tr.rows_between(t0, t1)
        self.rows = tr.samples(rows)
        self.t0, self.t1, self.span = t0, t1, t1 - t0
        if self.rule == "exact":
            assert tr.exact is not None
            self.blocks = list(tr.exact.quadrature_blocks(t0, t1))
        else:
            self.edges, _, self.edge_starts = tr.edges(rows)

    def quadrature(self, current: Any, conducting: Any) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
        """The nodes and weights of the mean of a function of a device's current: (|current| at the nodes, weights
        over the window's length, zero where the device does not conduct). Simpson's rule on each step of a run read
        linearly (its current linear there): exact for a drop linear in the current, as the run's own RMS is (its
        (a^2 + a b + b^2) / 3)."""
        if self.rule == "exact":
            i = np.concatenate([np.abs(current(nodes)) for nodes, _ in self.blocks])
            w = np.concatenate([weights * conducting(nodes) for nodes, weights in self.blocks])
            return i, w / self.span
        s = self.rows
        i, on = current(s), conducting(s)
        a, a_on = i[:-1].copy(), on[:-1].copy()
        # a step that starts at an edge: its own side
        a[self.edges], a_on[self.edges] = current(self.edge_starts), conducting(self.edge_starts)
        dt = np.diff(s.t) / float(s.t[-1] - s.t[0])
        b = i[1:]
        if self.rule == "end":
            return np.abs(b), dt * on[1:]
        step = dt * a_on / 6.0
        return np.abs(np.concatenate([a, 0.5 * (a + b), b])), np.concatenate([step, 4.0 * step, step])


def _edges_of_period(tr: Trajectory, rows: npt.NDArray[np.int_]) -> tuple[Samples, Samples]:
    """The samples before and after each switching edge of a window that is one period of a periodic run
    (:meth:`Trajectory.edges`), and the edge at the window's bound when the run starts there: a run of one period
    from the orbit begins in the configuration its last row ends, so that edge is at its last row (the state
    there is the first row's, by periodicity) with the first row's configuration and pair variables after it."""
    _, before, after = tr.edges(rows)
    if tr.config is None or tr.u is None or tr.y is None or tr.config[rows[0]] == tr.config[rows[-1]]:
        return before, after
    first, last = rows[:1], rows[-1:]
    at_end = tr.samples(last)
    wrapped = Samples(at_end.t, at_end.x, tr.u[first], tr.y[first], tr.config[first],
                      None if tr.relay is None else tr.relay[first], None if tr.held is None else tr.held[first])

    def join(a: Samples, b: Samples) -> Samples:
        def cat(x: npt.NDArray[Any] | None, y: npt.NDArray[Any] | None) -> npt.NDArray[Any] | None:
            return None if x is None or y is None else np.concatenate([x, y])
        return Samples(np.concatenate([a.t, b.t]), np.concatenate([a.x, b.x]), cat(a.u, b.u), cat(a.y, b.y),
                       cat(a.config, b.config), cat(a.relay, b.relay), cat(a.held, b.held))
    return join(before, at_end), join(after, wrapped)
