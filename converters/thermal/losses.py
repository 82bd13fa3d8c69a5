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

from collections.abc import Callable, Iterable, Mapping
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
#: The ground's names: its voltage is zero.
GROUND = ("v(0)", "v(gnd)")


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
    #: () -> (|current| at the conduction's quadrature nodes, the nodes' weights): read when first needed
    quadrature: Callable[[], tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]]
    on_edges: tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]
    off_edges: tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]
    span: float
    #: The conduction's sums at the on-state table's temperatures and the least table value read, where the
    #: compiled pass gave them (:func:`.kernels.conduction_sums`); None: read here.
    conduction: tuple[npt.NDArray[np.float64], float] | None = None

    @property
    def current(self) -> npt.NDArray[np.float64]:
        """|current| at the conduction's quadrature nodes."""
        return self._nodes()[0]

    @property
    def weight(self) -> npt.NDArray[np.float64]:
        """The nodes' weights over the window's length, zero where the device does not conduct."""
        return self._nodes()[1]

    def _nodes(self) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
        if "_node_values" not in self.__dict__:
            self.__dict__["_node_values"] = self.quadrature()
        return self.__dict__["_node_values"]

    def __post_init__(self) -> None:
        # the tables read at the run's currents and voltages once, at each of their temperatures (Table.slices),
        # and summed with the quadrature's weights: a loss at a junction temperature is then a blend of two sums
        d, cache = self.description, self.__dict__
        table = d.conduction
        if table is None:
            cache["_conduction"] = None
        elif self.conduction is None:
            cache["_conduction"] = table.weighted_sum(table.slices(self.current), self.weight * self.current)
        else:
            cache["_conduction"] = table.summed(self.conduction[0], self.conduction[1] >= 0.0, lambda last: float(
                table.blend(table.slices(self.current), last) @ (self.weight * self.current)))
        for key, energy, (v, i) in (("_on", d.turn_on, self.on_edges), ("_off", d.turn_off, self.off_edges)):
            cache[key] = None if energy is None or not v.size else _energies(energy, v, i, self.span)

    def total_W(self, tj: float) -> float:
        """The device's losses at the junction temperature ``tj`` (W): :meth:`losses`' total."""
        cache = self.__dict__
        return sum(cache[key](tj) for key in ("_conduction", "_on", "_off") if cache[key] is not None)

    def losses(self, tj: float) -> DeviceLosses:
        cache = self.__dict__

        def read(key: str) -> float:
            return 0.0 if cache[key] is None else cache[key](tj)
        return DeviceLosses(self.name, self.description.kind, tj, read("_conduction"), read("_on"), read("_off"),
                            int(self.on_edges[0].size), int(self.off_edges[0].size))


def _energies(table: Table, voltage: npt.NDArray[np.float64], current: npt.NDArray[np.float64],
              span: float) -> Callable[[float], float]:
    """``tj -> the table's energies at the edges (voltage, current) summed over the window's span`` (W), as
    :meth:`Table.weighted_sum` reads them; a (voltage, current, temperature) table summed at its temperatures in one
    compiled pass (:func:`.kernels.energy_sums`)."""
    weights = np.full(voltage.size, 1.0 / span)
    if len(table.axes) != 3:
        return table.weighted_sum(table.slices(voltage, current), weights)
    from .kernels import energy_sums
    sums = np.zeros(table.axes[2].size)
    lowest = energy_sums(np.ascontiguousarray(voltage, dtype=float), np.ascontiguousarray(current, dtype=float),
                         table.axes[0], table.axes[1], table.by_last, sums)
    return table.summed(sums / span, lowest >= 0.0,
                        lambda last: float(table.blend(table.slices(voltage, current), last) @ weights))


def device_losses(model: Any, p: dict, tr: Trajectory, descriptions: Mapping[str, DeviceDescription],
                  tj: Mapping[str, float], t0: float, t1: float) -> dict[str, DeviceLosses]:
    """Each described device's losses over [t0, t1] of ``tr`` (a run of the netlist ``model`` at ``p``), its
    tables read at ``tj[name]`` (degC). ``descriptions`` maps element names (``s1``, ``d1``) to descriptions."""
    return {name: w.losses(float(tj[name])) for name, w in waveforms(model, p, tr, descriptions, t0, t1).items()}


def waveforms(model: Any, p: dict, tr: Trajectory, descriptions: Mapping[str, DeviceDescription],
              t0: float, t1: float, window: Window | None = None) -> dict[str, Waveforms]:
    """Each described device's :class:`Waveforms` over [t0, t1] of ``tr`` (``window``: the window's reading, to
    share with other means over it). The devices are read together: their currents, conduction and blocked
    voltages as columns of one array per set of points."""
    compiled = model.compiled(p)
    elements = {e.name.lower(): e for e in model.netlist.elements}
    names = list(descriptions)
    for name in names:
        element, description = elements.get(name.lower()), descriptions[name]
        if element is None or element.kind not in "SD":
            raise ParameterError(f"a thermal description names {name!r}, which is no switch (S) or diode (D) of "
                                 f"the circuit ({', '.join(n for n, e in elements.items() if e.kind in 'SD')})")
        if description.kind == "Diode" and element.kind != "D" or description.kind != "Diode" and element.kind != "S":
            on = "a diode" if element.kind == "D" else "a switch"
            raise ParameterError(f"{name}: a {description.kind} description on {on}")
    devices = [elements[name.lower()] for name in names]
    window = window or Window(model, p, tr, t0, t1, device_signals(devices))
    read = window.read
    before, after = _edges_of_period(tr, window.row_indices)
    # a switch conducts while closed (its channel either way, with the same drop), a diode while its current is
    # positive; each device's column of the switches' states, or None for a diode
    closed = np.array(compiled.closed, dtype=bool).reshape(len(compiled.closed), -1)
    switch_of = [compiled.switch_names.index(e.name.lower()) if e.kind == "S" else None for e in devices]

    currents = tuple(f"i({e.name.lower()})" for e in devices)
    terminals = tuple(f"v({node})" for e in devices for node in e.nodes[:2])
    diodes = np.array([k is None for k in switch_of], dtype=bool)
    by_switch = closed[:, [k if k is not None else 0 for k in switch_of]]
    memo: dict[Any, Any] = {}
    D = len(devices)

    def current(s: Samples) -> npt.NDArray[np.float64]:
        if id(s) not in memo:                   # the samples kept with the values: their id stays theirs
            memo[id(s)] = (read.many(currents + terminals, s), s)
        return memo[id(s)][0][:, :D]

    def blocked(s: Samples) -> npt.NDArray[np.float64]:
        # a diode blocks v(cathode) - v(anode), a switch either polarity: read at the magnitude
        current(s)
        v = memo[id(s)][0]
        return np.abs(v[:, D::2] - v[:, D + 1::2])

    peak = np.max(np.abs(current(window.rows)), axis=0, initial=0.0)

    def conducting(s: Samples) -> npt.NDArray[np.bool_]:
        if ("on", id(s)) not in memo:
            memo["on", id(s)] = (np.where(diodes, current(s) > CONDUCTING * peak,
                                          by_switch[np.asarray(s.config, dtype=int)]), s)
        return memo["on", id(s)][0]

    nodes: list[Any] = []

    tables = [descriptions[name].conduction for name in names]

    def quadrature() -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:      # every device's, once
        if not nodes:
            nodes.append(window.quadrature(current, conducting, _kinks(tables)))
        return nodes[0]
    sums = None
    if window.rule == "linear" and devices and all(t is None or len(t.axes) == 2 for t in tables):
        sums = _conduction_compiled(window, current(window.rows), current(window.edge_starts), diodes,
                                    CONDUCTING * peak, by_switch, tables)
    was, now = conducting(before), conducting(after)
    v_before, v_after = blocked(before), blocked(after)
    i_before, i_after = np.abs(current(before)), np.abs(current(after))
    out = {}
    for d, name in enumerate(names):
        ons, offs = np.flatnonzero(~was[:, d] & now[:, d]), np.flatnonzero(was[:, d] & ~now[:, d])
        out[name] = Waveforms(name, descriptions[name], lambda d=d: (quadrature()[0][:, d], quadrature()[1][:, d]),
                              (v_before[ons, d], i_after[ons, d]), (v_after[offs, d], i_before[offs, d]), t1 - t0,
                              None if sums is None else (sums[0][d], float(sums[1][d])))
    return out


def _kinks(tables: list[Table | None]) -> npt.NDArray[np.float64]:
    """(K, devices): the currents where |i| v_on(|i|) has a kink for each device's on-state table (0, and each
    point of its current axis either way), padded with 0 (a repeated cut is a piece of zero length)."""
    points = [[0.0] + [s * float(x) for x in (t.axes[0] if t is not None else ()) if x > 0 for s in (1.0, -1.0)]
              for t in tables]
    out = np.zeros((max(map(len, points), default=1), len(tables)))
    for d, p in enumerate(points):
        out[:len(p), d] = p
    return out


def _conduction_compiled(window: Window, current: npt.NDArray[np.float64], current_starts: npt.NDArray[np.float64],
                         diode: npt.NDArray[np.bool_], threshold: npt.NDArray[np.float64],
                         closed: npt.NDArray[np.bool_], tables: list[Table | None]) -> tuple[
                             npt.NDArray[np.float64], npt.NDArray[np.float64]]:
    """The on-state tables' weighted sums at each of their temperatures over :meth:`Window.quadrature`'s nodes of
    a linearly read run, in one compiled pass (:func:`.kernels.conduction_sums`): (sums, least values read), a row
    per device (``current``'s columns); a device without a table reads a zero drop."""
    from .kernels import conduction_sums
    D = len(tables)
    A = max((t.axes[0].size for t in tables if t is not None), default=1)
    T = max((t.axes[1].size for t in tables if t is not None), default=1)
    axes, sizes = np.zeros((D, A)), np.ones(D, dtype=np.int64)
    values, temperatures = np.zeros((D, T, A)), np.ones(D, dtype=np.int64)
    for d, table in enumerate(tables):
        if table is not None:
            sizes[d], temperatures[d] = table.axes[0].size, table.axes[1].size
            axes[d, :sizes[d]] = table.axes[0]
            values[d, :temperatures[d], :sizes[d]] = table.values.T
    sums, lowest = np.zeros((D, T)), np.zeros(D)
    conduction_sums(np.asarray(window.rows.t, dtype=float), np.ascontiguousarray(current),
                    np.asarray(window.rows.config, dtype=np.int64), np.ascontiguousarray(current_starts).reshape(-1, D),
                    np.asarray(window.edge_starts.config, dtype=np.int64), np.asarray(window.edges, dtype=np.int64),
                    diode, np.ascontiguousarray(threshold, dtype=float), np.ascontiguousarray(closed), axes, sizes,
                    values, temperatures, sums, lowest)
    return sums, lowest


def device_signals(elements: Iterable[Any]) -> list[str]:
    """The signals a netlist's elements' losses or powers are read from: each one's current and its two nodes'
    voltages."""
    return [name for e in elements for name in (f"i({e.name.lower()})", f"v({e.nodes[0]})", f"v({e.nodes[1]})")]


class _Signals:
    """The model's signals read once per set of samples, together in one pass (the devices and the power balance
    share nodes, edges and points: :meth:`NetlistModel.signal_table`); a signal that follows a SIN or gate
    waveform (a gate's node) is read alone, when asked."""

    def __init__(self, model: Any, p: dict, names: Iterable[str] | None = None) -> None:
        self.model, self.p = model, p
        compiled = model.compiled(p)
        known = compiled.signal_names
        _, _, _, Ssin, Sgate = compiled.signal_stack()
        waved = {known[k] for k in np.flatnonzero(Ssin.any(axis=(0, 2)) | Sgate.any(axis=(0, 2)))}
        wanted = known if names is None else [n for n in dict.fromkeys(names) if n in known]
        self.names = [n for n in wanted if n not in waved]
        self.columns = {name: k for k, name in enumerate(self.names)}
        self.memo: dict[Any, tuple[npt.NDArray[np.float64], Samples]] = {}
        self.plans: dict[tuple[str, ...], Any] = {}

    def __call__(self, name: str, samples: Samples) -> npt.NDArray[np.float64]:
        if name in GROUND:
            return np.zeros(len(samples.t))
        column = self.columns.get(name)
        if column is not None:
            return self._table(samples)[:, column]
        key = (name, id(samples))
        if key not in self.memo:
            self.memo[key] = (np.asarray(self.model.signal(name, samples, self.p), dtype=float), samples)
        return self.memo[key][0]

    def many(self, names: tuple[str, ...], samples: Samples) -> npt.NDArray[np.float64]:
        """The signals ``names`` at the samples as columns, (points, names): one take of the table."""
        plan = self.plans.get(names)
        if plan is None:
            ground = np.array([n in GROUND for n in names], dtype=bool)
            plan = self.plans[names] = ((np.array([self.columns.get(n, 0) for n in names], dtype=np.int64), ground)
                                        if all(g or n in self.columns for n, g in zip(names, ground)) else False)
        if plan is False:
            return np.column_stack([self(n, samples) for n in names]) if names else np.zeros((len(samples.t), 0))
        columns, ground = plan
        out = self._table(samples)[:, columns]
        if ground.any():
            out[:, ground] = 0.0
        return out

    def _table(self, samples: Samples) -> npt.NDArray[np.float64]:
        if id(samples) not in self.memo:        # the samples are kept with the values: their id stays theirs
            self.memo[id(samples)] = (self.model.signal_table(samples, self.p, self.names), samples)
        return self.memo[id(samples)][0]


class Window:
    """A window [t0, t1] of a run and where a device's conduction loss is read over it: at the exact method's
    quadrature nodes on its exact pieces, or at the run's points (a step that starts at a switching edge read in its
    own configuration); the model's signals read once per set of points, the devices sharing them."""

    def __init__(self, model: Any, p: dict, tr: Trajectory, t0: float, t1: float,
                 names: Iterable[str] | None = None) -> None:
        self.read = _Signals(model, p, names)       # names: the signals read over it (default: all)
        self.tr, self.t0, self.t1, self.span = tr, t0, t1, t1 - t0
        # the run's own rule's points (Trajectory.integral's), kept: the signals read at them once, for every mean
        self.points = points = tr.integration_points(t0, t1)
        self.rule, self.blocks = points.rule, points.blocks
        self.row_indices = rows = tr.rows_between(t0, t1)
        self.rows = points.rows if points.rows is not None else tr.samples(rows)
        self.edges, self.edge_starts = points.edges, points.edge_starts

    def mean(self, function: Any) -> float:
        """The mean over the window of ``function(samples)`` (a product of signals read through :attr:`read`) by
        the run's own rule: :meth:`Trajectory.integral` at the window's points."""
        return self.tr.integral(function, self.t0, self.t1, self.points) / self.span

    def quadrature(self, current: Any, conducting: Any, kinks: npt.ArrayLike | None = None) -> tuple[
            npt.NDArray[np.float64], npt.NDArray[np.float64]]:
        """The nodes and weights of the mean of a function of a device's current: (|current| at the nodes, weights
        over the window's length, zero where the device does not conduct); a column per device where ``current``
        and ``conducting`` give one. Simpson's rule on each step of a run read linearly (its current linear
        there), each step cut where the current crosses one of ``kinks`` ((K,) or (K, devices): the currents where
        the function has a kink, as |i| v_on(|i|) at 0 and at an on-state table's points): exact for a function
        quadratic in the current between its kinks, as |i| v_on(|i|) is for a table linear there (uncut, a step
        across a table's point reads it to O(step^2) however fine the run: a dead time of one step stays one
        step at h and at 2h, and their difference would not show it)."""
        if self.rule == "exact":
            i = np.concatenate([np.abs(current(nodes)) for nodes, _ in self.blocks])
            w = np.concatenate([weights.reshape(-1, *(1,) * (np.ndim(on) - 1)) * on
                                for nodes, weights in self.blocks for on in (conducting(nodes),)])
            return i, w / self.span
        s = self.rows
        i, on = current(s), conducting(s)
        a, a_on = i[:-1].copy(), on[:-1].copy()
        # a step that starts at an edge: its own side
        a[self.edges], a_on[self.edges] = current(self.edge_starts), conducting(self.edge_starts)
        dt = (np.diff(s.t) / float(s.t[-1] - s.t[0])).reshape(-1, *(1,) * (i.ndim - 1))
        b = i[1:]
        if self.rule == "end":
            return np.abs(b), dt * on[1:]
        step = dt * a_on / 6.0
        if kinks is None:
            return np.abs(np.concatenate([a, 0.5 * (a + b), b])), np.concatenate([step, 4.0 * step, step])
        flat = a.ndim == 1
        a, b, step = (np.atleast_2d(v.T).T for v in (a, b, step))          # (steps, devices)
        c = np.asarray(kinks, dtype=float).reshape(len(kinks), -1)           # (K, devices)
        with np.errstate(divide="ignore", invalid="ignore"):
            cut = (c[None] - a[:, None]) / (b - a)[:, None]                 # where each kink is crossed
        cut = np.where(np.isfinite(cut), np.clip(cut, 0.0, 1.0), 0.0)
        ends = np.ones_like(a)[:, None]
        cuts = np.sort(np.concatenate([0.0 * ends, cut, ends], axis=1), axis=1)
        lo, hi = cuts[:, :-1], cuts[:, 1:]                                   # (steps, K + 1, devices)

        def at(s: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
            return (a[:, None] + s * (b - a)[:, None]).reshape(-1, a.shape[1])
        piece = (step[:, None] * (hi - lo)).reshape(-1, a.shape[1])
        i = np.abs(np.concatenate([at(lo), at(0.5 * (lo + hi)), at(hi)]))
        w = np.concatenate([piece, 4.0 * piece, piece])
        return (i[:, 0], w[:, 0]) if flat else (i, w)


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
