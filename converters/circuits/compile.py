"""A netlist compiled into a linear complementarity system: modified nodal analysis per switch configuration.

Per configuration (which switches are closed, which level each piecewise-constant source holds), the circuit
is a resistive network once each capacitor is a voltage source at its state, each inductor a current source
at its state and each ideal diode a port (Acary, Bonnefon and Brogliato, "Nonsmooth Modeling and Simulation
for Switched Circuits", Springer 2011, ch. 2). Modified nodal analysis solves it for every node voltage and
branch current as a linear function of (x, u, the sources): the capacitors' currents and the inductors'
voltages give x' = A x + B u + E, the ports y = C x + D u + F, and every other quantity a signal.

The port of each diode is chosen per configuration: u = i_D (a current source; y = -v_D) where the network
leaves its current free, u = -v_D (a voltage source; y = i_D) where an inductor or another port fixes it
(the choice made by hand for the built-in converters). Capacitors in a loop with DC voltage sources, 0 ohm
resistors and closed ideal switches have voltages that are not independent: the loop's constraint is kept by the
current circulating in it (:meth:`_Network.solve_loops`), and a configuration whose closed switches make such a
loop is entered by a jump of the charges onto it (:meth:`_Compiler.jump`; a capacitance across a switch that
closes, the energy 1/2 C dv^2 lost). A configuration the network cannot solve otherwise is refused naming the
elements: a loop of voltage sources and closed switches with no capacitor, an uncoupled inductor whose only path is
cut (a current interrupted), a node with no path to ground. Inductors in a cutset with DC current sources (in series) are
the dual of a loop of capacitors: their currents tied, the cutset's potential keeping them so, a switch that opens
onto such a cutset a jump of the fluxes. Ideal diodes whose ports are the same (in parallel, or in series with nothing between)
give an LCP without a unique solution and are refused too, unless sources alone reverse-bias them (both
blocked: u = 0 is unique). An ideal diode whose terminals closed ideal switches join (a MOSFET's body diode
while the switch conducts) has 0 V whatever its current: the switch carries it all, the diode's pair never holds.

Switches are ideal (closed: a 0 V branch, or ``RON`` when its model gives one; open: no branch), as is a 0 ohm
resistor (a parasitic set to zero: a 0 V branch); a diode's model ``RS`` is a series resistance. A switch (S: its control the voltage V(nc+) - V(nc-) against the model's
``VT`` +- ``VH``; W: the current through its controlling V source against ``IT`` +- ``IH``) whose control is a
combination of independent sources (a PULSE gate) is driven by a time schedule: its threshold crossings (with
the hysteresis) located exactly on the piecewise-linear waveform; one whose control depends on the states is a
state-driven law (a comparator). A gate that does not repeat (a PWL without r=, a PULSE without PER) makes
phases: each of its switch's crossings is an instant where the run is split and the next phase's schedule takes
over (a load step). A PULSE source in the power circuit follows its edges as ramps, a state of the LCS
(:data:`EDGE_RAMPED`), or, where they are short beside its levels, switches between them at the edges' middle.
"""
from __future__ import annotations

import copy
import itertools
import math
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any, TypedDict, TypeVar, cast

import numpy as np
import numpy.typing as npt

from ..errors import ParameterError
from ..problems import Configuration, Jump, Schedule
from .netlist import Element, Netlist, NetlistError, Pulse, Pwl, Sin, Waveform, with_models

if TYPE_CHECKING:
    import threading

    from ..problems import Comparators, Ramp, StateSwitching

    #: A switching law: a Schedule (time-driven), a StateSwitching (a comparator) or Comparators (several).
    Law = Schedule | StateSwitching | Comparators

#: Arrays of numbers: one circuit's, or a batch's with a leading axis per point.
_Array = npt.NDArray[np.float64]
#: A configuration's signal maps: (Sx, Su, s0, Ssin, Sgate) (:attr:`Compiled.signal_maps`).
_Maps = tuple[_Array, ...]
#: What :meth:`_Compiler.lcs` gives per circuit: (configuration, signal maps, (E, F) of the SIN sources).
_Lcs = tuple[Configuration, _Maps, tuple[_Array, _Array]]
#: A configuration's switch states and source levels, as :meth:`_Compiler.network` keys them.
_Here = tuple[tuple[tuple[str, bool], ...], tuple[tuple[str, int], ...]]
#: A configuration as :meth:`_Compiler.run` keys it: (switches closed, source levels, ramps' slopes, oscillators
#: running).
_Key = tuple[tuple[bool, ...], tuple[int, ...], tuple[float, ...], tuple[bool, ...]]
_T = TypeVar("_T")


class Invariant(TypedDict):
    """What a circuit holds fixed (:meth:`_Compiler.invariants`)."""

    kind: str                        # "loop", "cutset" or "charge"
    constraint: str
    value: float
    unit: str


#: The diode's port: a current source (u = i_D, y = -v_D) or a voltage source (u = -v_D, y = i_D).
CURRENT, VOLTAGE = "current", "voltage"
#: The port forms found per circuit structure and configuration (:meth:`_Compiler.network`), and how many are kept.
_FORMS: dict[tuple[object, ...], tuple[str, ...]] = {}
MAX_KEPT_FORMS = 4096


@dataclass(frozen=True, kw_only=True)
class Compiled:
    """The LCS of a netlist: configurations, the switching law, names, and each configuration's signal maps."""

    configurations: tuple[Configuration, ...]
    law: Law                         # the switching law: a Schedule (time-driven) or a StateSwitching (a comparator)
    state_names: tuple[str, ...]     # "v(c1)", "i(l1)" (capacitor voltages and inductor currents)
    pair_names: tuple[str, ...]      # diode names ("d1"); "none" for a circuit without diodes
    pair_currents: tuple[tuple[bool, ...], ...]     # per configuration, per pair: u is the diode current
    switch_names: tuple[str, ...]
    closed: tuple[tuple[bool, ...], ...]            # per configuration: which switches are closed
    signal_names: tuple[str, ...]    # "v(node)", "i(element)"
    signal_maps: tuple[_Maps, ...]   # per configuration: (Sx (S, n), Su (S, k), s0 (S,), Ssin (S, m), Sgate (S, g))
    period: float
    x0: _Array
    units: dict[str, str] = field(default_factory=dict)
    #: The SIN sources as sinusoidal inputs: (omega (m,), phase (m,), E (configs, m, n), F (configs, m, k)), or None.
    inputs: tuple[_Array, _Array, _Array, _Array] | None = None
    #: The gate sources (PULSE or PWL reaching only switch controls) whose waveforms the Sgate columns of the signal
    #: maps multiply at each sample's time: a gate's node voltage follows its waveform, not a level.
    gates: tuple[Waveform, ...] = ()
    #: Switches driven by sources that do not repeat (a PWL without r=, a PULSE without PER: a load step's switch):
    #: ((t, law), ...), the law in force from each instant t > 0 on (``law`` before the first).
    phases: tuple[tuple[float, Law], ...] = ()
    #: What the circuit holds fixed (:meth:`_Compiler.invariants`): ({"kind", "constraint", "value", "unit"}, ...).
    invariants: tuple[Invariant, ...] = ()
    #: What the file asks for that the circuit cannot hold, said as a warning with every run (:meth:`_Compiler.moved`).
    notes: tuple[str, ...] = ()
    #: The stored energy's weights, (capacitances (n_c,), inductance matrix (n_L, n_L)) in the states' order, for the
    #: energy balance (:func:`converters.analysis.accuracy.energy_balance`); () where not known (a batch's points).
    energy: tuple[_Array, ...] = ()
    #: Per configuration, the node potentials nothing but diodes ties to the rest of the circuit (:meth:`_Compiler.
    #: floating`): (what each signal does along them (S, m), what each diode's voltage does (k, m)), or None.
    floating: tuple[tuple[_Array, _Array] | None, ...] = ()
    #: The power circuit's PULSE sources run as steps at the middle of their edges: ((title, period, ((the edge's
    #: middle in [0, period), its width), ...)), ...).
    power_edges: tuple[tuple[str, float, tuple[tuple[float, float], ...]], ...] = ()
    #: The power circuit's PULSE sources whose edges are ramps of the LCS: ((title, TR, TF), ...).
    ramped_edges: tuple[tuple[str, float, float], ...] = ()

    def signal_rows(self, row: int) -> tuple[_Array, ...]:
        """Signal ``row``'s maps stacked over the configurations: (Sx (configs, n), Su, s0, Ssin, Sgate), built once
        (a long exact run reads its signals block by block)."""
        # frozen: the cache is not a field
        cache: dict[int, tuple[_Array, ...]] = self.__dict__.setdefault("_signal_rows", {})
        if row not in cache:
            cache[row] = tuple(np.array([m[i][row] for m in self.signal_maps]) for i in range(5))
        return cache[row]

    def signal_stack(self, names: tuple[str, ...] | None = None) -> tuple[_Array, ...]:
        """The signals' maps (every signal's, or those of ``names`` in their order) stacked over the configurations:
        (Sx (configs, S, n), Su, s0, Ssin, Sgate), built once per set of names
        (:meth:`converters.models.netlist.NetlistModel.signal_table` reads them all at once)."""
        stacks: dict[tuple[str, ...] | None, tuple[_Array, ...]] = self.__dict__.setdefault("_signal_stacks", {})
        if names not in stacks:
            every = stacks.get(None)
            if every is None:
                every = stacks[None] = tuple(np.array([m[i] for m in self.signal_maps]) for i in range(5))
            if names is not None:
                unknown = [name for name in names if name not in self.signal_names]
                if unknown:
                    raise ValueError(f"signal must be one of {', '.join(self.signal_names)}; got {unknown[0]!r}")
                columns = [self.signal_names.index(name) for name in names]
                stacks[names] = tuple(np.ascontiguousarray(a[:, columns]) for a in every)
        return stacks[names]

    def law_at(self, t: float) -> Law:
        """The switching law in force at time t."""
        law = self.law
        for start, later in self.phases:
            if t >= start:
                law = later
        return law



#: A network with more unknowns than this has its factorisations run where a time limit can stop them.
LARGE_NETWORK = 400
#: The threads of factorisations a time limit stopped waiting for (:func:`interruptible`).
ABANDONED: list[threading.Thread] = []


def interruptible(function: Callable[..., _T], matrix: npt.NDArray[Any], *args: Any, **kwargs: Any) -> _T:
    """``function(matrix, ...)``, run for a large matrix in a thread the caller waits on in short slices, so that
    the command's --time-limit alarm (a signal, handled between bytecodes) stops the compile while LAPACK works
    (numpy lets go of the GIL there): a 3,000-stage RC ladder's SVDs ran 114 s past a 10 s limit. The thread is a
    daemon: a run stopped by its limit leaves it to the process's exit."""
    if np.shape(matrix)[-1] <= LARGE_NETWORK:
        return function(matrix, *args, **kwargs)
    import threading
    box: dict[str, Any] = {}

    def work() -> None:
        try:
            box["value"] = function(matrix, *args, **kwargs)
        except BaseException as exc:           # handed back to the caller's thread
            box["error"] = exc
    thread = threading.Thread(target=work, name="pcsuite-compile", daemon=True)
    thread.start()
    try:
        while thread.is_alive():
            thread.join(0.05)
    except BaseException:
        ABANDONED.append(thread)            # still in LAPACK: the command line ends the process without it
        raise
    if "error" in box:
        raise box["error"]
    return cast(_T, box["value"])

def compile_netlist(netlist: Netlist) -> Compiled:
    """The LCS of ``netlist`` (its values already final: overrides applied by the reader)."""
    return _compiled(netlist)[1]


def _compiled(netlist: Netlist) -> tuple[_Compiler, Compiled]:
    """(the compiler, its LCS) of ``netlist``: compiled again with a power PULSE's edges as ramps where, run as
    steps, an edge outlasts the circuit's fastest time constant (:meth:`_Compiler.slow_edges`)."""
    compiler = _Compiler(with_models(netlist))
    compiled = compiler.run()
    slow = compiler.slow_edges(compiled)
    if slow:
        compiler = _Compiler(with_models(netlist), edged=slow)
        compiled = compiler.run()
    return compiler, compiled


def compile_points(netlists: list[Netlist]) -> list[Compiled | None]:
    """The LCS of each netlist, those alike but for their values (a tolerance study's points: the same file with
    other R, L, C, couplings, gains, DC sources, RS and RON) compiled together: the first of each group alone,
    the others' networks stamped and solved as one stack with its port forms and schedule
    (:meth:`_Compiler.rerun`): the same numbers as a compile of each, to the bit. A point the group cannot take
    is None (compile it alone: :func:`compile_netlist` gives its own result or error); so is every point of a
    group whose first fails."""
    out: list[Compiled | None] = [None] * len(netlists)
    groups: dict[tuple[object, ...], list[int]] = {}
    for i, netlist in enumerate(netlists):
        groups.setdefault(_structure(netlist), []).append(i)
    for indices in groups.values():
        try:
            first, out[indices[0]] = _compiled(netlists[indices[0]])
        except NetlistError:
            continue
        if len(indices) > 1 and first.batchable():
            for i, compiled in zip(indices[1:], first.rerun([netlists[i] for i in indices[1:]],
                                                            cast(Compiled, out[indices[0]]))):
                out[i] = compiled
    return out


def _structure(netlist: Netlist) -> tuple[object, ...]:
    """What must be equal for two netlists to share a compile's structure: the file, every element but its value
    (a resistor's being 0, a short, is structure; a DC source's value is not; other waveforms are), whether an
    element has an IC, the models' parameters but RS and RON (their being 0 is structure), the .ic nodes."""
    elements = tuple((e.name, e.kind, e.nodes, e.model, e.control, e.kind == "R" and e.value == 0,
                      None if isinstance(e.waveform, float) else e.waveform, e.ic is None) for e in netlist.elements)
    models = tuple((name, m.kind, tuple(sorted((key, value != 0 if key in ("RS", "RON") else value)
                                               for key, value in m.params.items())))
                   for name, m in netlist.models.items())
    return netlist.text, netlist.path, elements, models, tuple(sorted(netlist.ic))


#: Elements that join their first two nodes by a branch whose current the circuit decides (a voltage, a resistance,
#: a switch or diode that may conduct); capacitors join them too, but conserve the charge they move.
_JOINING = "RLVEHDSW"


def _root(parent: dict[str, str], n: str) -> str:
    """The root of node ``n`` in a union-find forest (``parent``; a node not yet seen is its own root)."""
    while parent.setdefault(n, n) != n:
        parent[n] = parent[parent[n]]
        n = parent[n]
    return n


def inductor_loops(inductors: Sequence[Element]) -> list[_Array]:
    """The independent loops of inductors alone (a cycle of the graph of the inductors' branches: two in parallel,
    a triangle of three), each as its sign per inductor (+1 where the loop runs from the inductor's first node to its
    second): sum(sign v_L) = 0 around it, so its flux sign^T M i is conserved, whatever the switches and diodes do."""
    parent: dict[str, str] = {}
    tree: dict[str, list[tuple[str, int, int]]] = {}           # node: [(neighbour, inductor, +1 along it)]

    def find(n: str) -> str:
        return _root(parent, n)

    def path(a: str, b: str) -> list[tuple[int, int]]:
        """The tree's branches from a to b, each (inductor, +1 where traversed from its first node)."""
        seen: dict[str, list[tuple[int, int]]] = {a: []}
        frontier = [a]
        while frontier:
            node = frontier.pop()
            for other, index, direction in tree.get(node, []):
                if other not in seen:
                    seen[other] = seen[node] + [(index, direction)]
                    frontier.append(other)
        return seen[b]
    loops = []
    for index, e in enumerate(inductors):
        a, b = e.nodes[0], e.nodes[1]
        if find(a) == find(b):
            sign = np.zeros(len(inductors))
            sign[index] = 1.0                                   # a -> b through the inductor, back b -> a in the tree
            for other, direction in path(b, a):
                sign[other] += direction
            loops.append(sign)
        else:
            parent[find(a)] = find(b)
            tree.setdefault(a, []).append((b, index, 1))
            tree.setdefault(b, []).append((a, index, -1))
    return loops


def charge_islands(netlist: Netlist) -> list[tuple[tuple[str, ...], tuple[str, ...]]]:
    """Sets of nodes joined to the rest of the circuit (ground included) only through capacitors, whatever the
    switches and diodes do: each set's net charge is conserved (the capacitors' currents into it sum to zero), so
    it is where the run started it, and without a hold every start would have a periodic orbit of its own (a
    multiplier at 1; :meth:`_Compiler.hold_islands`). [(nodes, capacitors)], names upper case; a set touched by a
    current source is left out (its charge is driven, not conserved)."""
    parent: dict[str, str] = {}

    def find(n: str) -> str:
        return _root(parent, n)

    driven: set[str] = set()
    for e in netlist.elements:
        if e.kind in _JOINING and len(e.nodes) >= 2:
            parent[find(e.nodes[0])] = find(e.nodes[1])
        elif e.kind in "IGF":
            driven.update(e.nodes[:2])
        for n in e.nodes:
            find(n)
    groups: dict[str, list[str]] = {}
    for n in parent:
        groups.setdefault(find(n), []).append(n)
    ground = find("0")
    out = []
    for root, nodes in groups.items():
        capacitors = [e.name.upper() for e in netlist.elements if e.kind == "C" and
                      (find(e.nodes[0]) == root) != (find(e.nodes[1]) == root)]
        if root != ground and capacitors and not driven & set(nodes):
            out.append((tuple(nodes), tuple(capacitors)))
    return out


class _Compiler:
    #: The constraints of the loops of capacitors and cutsets of inductors that hold in every configuration, where
    #: the circuit has some (:meth:`_Network.solve_loops` sets it; read with getattr, unset without)
    loops: _Array

    def __init__(self, netlist: Netlist, edged: frozenset[str] = frozenset()):
        self.nl = netlist
        self.ramp_notes: list[str] = []             # comparators' ramps whose retrace is not instantaneous
        self.path = netlist.path
        els = netlist.elements
        self.by_kind = {k: [e for e in els if e.kind == k] for k in "RLCKVIEGFHDSW"}
        names = [e.name for e in els]
        duplicate = next((n for n in names if names.count(n) > 1), None)
        if duplicate:
            first = [e for e in els if e.name == duplicate][1]
            raise self.error(first, f"{first.title}: the name is used twice")
        for e in els:
            if e.kind in "FHW":
                ctrl = next((v for v in self.by_kind["V"] if v.name == e.control[0]), None)
                if ctrl is None:
                    raise self.error(e, f"{e.title}: its controlling source {e.control[0].upper()} is not a V source "
                                        "of the netlist")
            if e.kind == "K":
                for name in e.control:
                    if not any(l.name == name for l in self.by_kind["L"]):
                        raise self.error(e, f"{e.title}: {name.upper()} is not an inductor of the netlist")
        if netlist.tran is None:
            raise NetlistError(f"{self.path}: no .tran (pcsuite and ngspice both run the transient it states)")
        nodes = [n for n in netlist.nodes if n != "0"]
        if "0" not in netlist.nodes:
            raise NetlistError(f"{self.path}: no ground node (0)")
        #: Nodes joined to the rest only through capacitors: (sign per capacitor, +1 where its first node is in the
        #: island, -1 where its second is), their charge sum(sign C v) held where the run starts (:meth:`lcs`)
        self.islands: list[_Array] = []
        for island, capacitors in charge_islands(netlist):
            inside = set(island)
            self.islands.append(np.array([(e.nodes[0] in inside) - (e.nodes[1] in inside) if e.name.upper() in
                                          capacitors else 0 for e in self.by_kind["C"]], dtype=float))
            if len(capacitors) == 1 and all(len([e for e in els if n in e.nodes]) == 1 for n in island):
                cap = next(e for e in els if e.name.upper() == capacitors[0])
                raise self.error(cap, f"{cap.title}: node{'s' if len(island) > 1 else ''} {', '.join(island)} "
                                      f"connect{'' if len(island) > 1 else 's'} to nothing but this capacitor: it keeps "
                                      "its initial charge forever (no current can reach it); connect the node, or "
                                      "remove the capacitor")
        self.nodes = nodes
        self.node_index = {n: i for i, n in enumerate(nodes)}
        self.capacitors, self.inductors = self.by_kind["C"], self.by_kind["L"]
        self.diodes, self.switches = self.by_kind["D"], [e for e in els if e.kind in "SW"]
        self.sources = self.by_kind["V"] + self.by_kind["I"]
        self.n = len(self.capacitors) + len(self.inductors)
        if self.n == 0:
            raise NetlistError(f"{self.path}: no capacitor or inductor: the circuit has no state")
        self.k = max(1, len(self.diodes))
        # every diode's series resistance as an inner node and a resistor
        self.diode_rs = {d.name: self.nl.models[cast(str, d.model)].params.get("RS", 0.0) for d in self.diodes}
        for d in self.diodes:
            if self.diode_rs[d.name] < 0:
                raise self.error(d, f"{d.title}: model {d.model} RS must be >= 0")
            self.node_index.setdefault(f"{d.name}#a", len(self.node_index)) if self.diode_rs[d.name] else None
        #: Whether a configuration closes a switch across capacitors (:meth:`jump`)
        self.switch_loops = False
        #: 0 ohm resistors (a parasitic set to zero): 0 V branches, as closed ideal switches
        self.shorts = [r for r in self.by_kind["R"] if r.value == 0]
        self.switch_ron = {s.name: self.nl.models[cast(str, s.model)].params.get("RON", 0.0) for s in self.switches}
        self.mutual = self.inductance_matrix()
        #: Loops of inductors alone (two in parallel): sign per inductor around each, its flux sign^T M i conserved
        #: (the loop's voltages sum to zero), held where the run starts (:meth:`hold_fluxes`)
        self.flux_loops: list[_Array] = inductor_loops(self.inductors)
        #: One circuit: (); a batch of P circuits alike but for their values: (P,), each value's P numbers in
        #: ``batch`` (:meth:`rerun`)
        self.lead: tuple[int, ...]
        self.batch: dict[tuple[str, str | None], _Array]
        self.lead, self.batch = (), {}
        #: The networks solved so far: (switch states, source levels) -> (network, port forms).
        self.solved: dict[_Here, tuple[_Network, tuple[str, ...]]] = {}
        #: PWL sources in the power circuit: ramps, each a state of the LCS (its value), its slope per phase
        self.ramps = [s for s in self.sources if isinstance(s.waveform, Pwl) and self.in_power_circuit(s)]
        #: PULSEs in the power circuit whose edges are ramps of their own (:func:`_edged`, or named in ``edged``):
        #: each a state of the LCS, its value, at its edges' slopes on them and held on its levels (:meth:`lcs`); the
        #: others step between their levels at the middle of their edges
        self.edged = [s for s in self.sources if isinstance(s.waveform, Pulse) and self.in_power_circuit(s)
                      and (_edged(s.waveform) or s.name in edged)]
        #: SIN sources with a delay or damping: oscillators, each two states of the LCS (e^(-THETA t') sin and cos of
        #: 2 pi FREQ t' + PHASE, t' = t - TD: the damped rotation they follow), frozen before TD
        self.oscillators = [s for s in self.sources if isinstance(s.waveform, Sin) and (s.waveform.td or s.waveform.theta)]
        for o in self.oscillators:
            if not self.in_power_circuit(o):
                raise self.error(o, f"{o.title}: a SIN with a delay or damping (TD, THETA) in a switch's control is not "
                                    "compiled; in the power circuit it is")
            if cast(Sin, o.waveform).td < 0 or cast(Sin, o.waveform).theta < 0:
                raise self.error(o, f"{o.title}: its SIN delay TD and damping THETA must be >= 0; got TD = "
                                    f"{cast(Sin, o.waveform).td:g} s, THETA = {cast(Sin, o.waveform).theta:g} 1/s")

    def check_steps(self, s: Element, w: Pulse) -> None:
        """A power PULSE run as steps (an edge without a width beside one with it, or edges short beside its
        levels: :func:`_edged`): refused where its edges take more than STEP_EDGE_FRACTION of its period, said
        where more than EDGE_SAID of its shorter level."""
        if max(w.tr, w.tf) > STEP_EDGE_FRACTION * w.per * (1.0 + 1e-9):     # (a file's T/1000 by rounding)
            raise self.error(s, f"{s.title}: a PULSE in the power circuit with an edge of no width switches between "
                                f"its levels at the middle of its edges, so its edges must take at most "
                                f"{STEP_EDGE_FRACTION:g} of its period (PER = {w.per:.4g} s: TR, TF <= "
                                f"{STEP_EDGE_FRACTION * w.per:.4g} s); got TR = {w.tr:.4g} s, TF = {w.tf:.4g} s (give "
                                "both edges a width: they are then followed as ramps)")
        level = min(w.pw, w.per - w.pw - w.tr - w.tf)           # the shorter of its two levels
        edge = max(w.tr, w.tf)
        if edge > EDGE_SAID * level:
            self.ramp_notes.append(
                f"{s.title}: its edges ({edge:.3g} s) are run as steps at their middle (one has no width), "
                f"{edge / level:.2g} of its shorter level ({level:.3g} s): what its edges shape (its rms, a diode's "
                "peak or conduction time) may be off by that order, which no estimate sees; give both a width")

    def slow_edges(self, compiled: Compiled) -> frozenset[str]:
        """The power PULSEs run as steps whose edges (both with a width) outlast the fastest time constant of
        ``compiled``'s flows: the mode settles within the edge, so what it carries there follows the ramp (a 10 V
        edge of 1 us into 10 ohm and 10 nF drives 0.1 A, its step at the middle 1 A), which no estimate of the
        steps sees. Those are compiled edged (:func:`_compiled`)."""
        stepped = [s for s in self.sources if isinstance(s.waveform, Pulse) and self.in_power_circuit(s)
                   and s not in self.edged and min(s.waveform.tr, s.waveform.tf) > 0.0]
        if not stepped:
            return frozenset()
        from ..methods.theta import fastest_rate
        rate = fastest_rate(compiled.configurations)
        return frozenset(s.name for s in stepped if max(cast(Pulse, s.waveform).tr, cast(Pulse, s.waveform).tf) * rate
                         > EDGE_TIME_CONSTANTS)

    def error(self, element: Element, what: str) -> NetlistError:
        return NetlistError(f"{self.path}:{element.line}: {what}")

    def batchable(self) -> bool:
        """Whether :meth:`rerun` takes this circuit's other values: a schedule of PULSE or PWL gates (a comparator's
        law depends on the values), no ramp or delayed SIN (states of their own), no loop of capacitors or node
        held by its charge (:meth:`_Network.solve_loops`, :meth:`hold_islands`: solved one circuit at a time)."""
        return hasattr(self, "built") and not (self.state_rows or self.ramps or self.edged or self.oscillators
                                               or self.islands
                                               or self.flux_loops or getattr(self, "loops", None) is not None
                                               or self.switch_loops)

    def rerun(self, netlists: list[Netlist], compiled: Compiled) -> list[Compiled | None]:
        """The compiles of ``netlists``, each this circuit (its :meth:`run` gave ``compiled``) with other values:
        every configuration's networks stamped for all points at once (G per point, R shared), solved as one
        stack, with this compile's port forms and schedule. None for a point that needs a compile of its own: a
        gate's DC value that moves the schedule, coupled inductances not positive definite, a network its values
        make singular with these forms, two diodes' ports alike."""
        P = len(netlists)
        numbers = np.array([[e.value if e.value is not None else float(e.waveform) if isinstance(e.waveform, float)
                             else math.nan for e in netlist.elements] for netlist in netlists]).reshape(P, -1)
        column = {e.name: j for j, e in enumerate(self.nl.elements)}
        ok = np.ones(P, dtype=bool)
        driving = {name for drive in self.drives.values() if drive for name in drive}
        for source in self.sources:               # a DC level in a switch's control moves the schedule
            if source.name in driving and isinstance(source.waveform, float):
                ok &= numbers[:, column[source.name]] == float(source.waveform)
        batch: dict[tuple[str, str | None], _Array] = {
            (e.name, None): numbers[:, column[e.name]] for e in self.nl.elements
            if e.kind in "RLCKEGFH" or (e.kind in "VI" and isinstance(e.waveform, float))}
        for elements, key, kept in ((self.diodes, "RS", self.diode_rs), (self.switches, "RON", self.switch_ron)):
            for e in elements:
                if kept[e.name]:
                    batch[(e.name, key)] = np.array([netlist.models[cast(str, e.model)].params.get(key, 0.0)
                                                     for netlist in netlists])
        m = len(self.inductors)
        mutual = np.zeros((P, m, m))
        index = {l.name: i for i, l in enumerate(self.inductors)}
        i: int | np.signedinteger[Any]              # an inductor's index here, a point's below
        for i, l in enumerate(self.inductors):
            mutual[:, i, i] = batch[(l.name, None)]
        for k in self.by_kind["K"]:
            a, b = (index[name] for name in k.control)
            mutual[:, a, b] = mutual[:, b, a] = batch[(k.name, None)] * np.sqrt(mutual[:, a, a] * mutual[:, b, b])
        if m:
            ok &= np.linalg.eigvalsh(mutual).min(axis=-1) > 1e-12 * np.abs(mutual).max(axis=(-2, -1))
        while True:
            if not ok.any():
                return [None] * P
            view = copy.copy(self)
            view.lead, view.mutual = (int(ok.sum()),), mutual[ok]
            view.batch = {key: values[ok] for key, values in batch.items()}
            networks = []
            for switch_state, levels, _, _ in self.built:
                forms = list(self.solved[(tuple(switch_state.items()), tuple(levels.items()))][1])
                networks.append((_Network(view, switch_state, levels, forms), forms))
            singular = np.zeros(view.lead, dtype=bool)
            for network, _ in networks:
                singular |= network.nullity() > 0
            if not singular.any():
                break
            ok[np.flatnonzero(ok)[singular]] = False
        per_point: list[list[_Lcs]] = [[] for _ in range(view.lead[0])]
        for (network, forms), (switch_state, _, slopes, running) in zip(networks, self.built):
            for p, result in enumerate(cast(list[_Lcs], view.lcs(network.solve(checked=True), forms, switch_state,
                                                                 slopes, running))):
                per_point[p].append(result)
        # the switches' controls (their sources' coefficients, which the schedule follows) must be this compile's
        # to the bit: a divider or a gain in a gate's path changes them (its point is compiled alone)
        first = self.solved[(tuple(self.built[0][0].items()), tuple(self.built[0][1].items()))][0]
        same_drive = np.ones(view.lead, dtype=bool)
        for switch in self.switches:
            if self.drives.get(switch.name):
                same_drive &= (view.control(networks[0][0], switch)[:, self.n + self.k:]
                               == self.control(first, switch)[self.n + self.k:]).all(axis=-1)
        out: list[Compiled | None] = [None] * P
        for i, results, same in zip(np.flatnonzero(ok), per_point, same_drive):
            if not same:
                continue
            try:
                for config, (switch_state, _, _, _) in zip((r[0] for r in results), self.built):
                    self.check_unique_ports(config, switch_state)
            except NetlistError:
                continue
            inputs = compiled.inputs
            if inputs is not None:
                inputs = (inputs[0], inputs[1], np.array([r[2][0] for r in results]),
                          np.array([r[2][1] for r in results]))
            out[i] = replace(compiled, configurations=tuple(r[0] for r in results),
                             signal_maps=tuple(r[1] for r in results), x0=self.initial_state(netlists[i]),
                             inputs=inputs, energy=())
        return out

    def value(self, element: Element, model_key: str | None = None) -> float | _Array:
        """An element's value (its model's RS or RON with ``model_key``): a number, or a batch's P numbers."""
        key = (element.name, model_key)
        if key in self.batch:
            return self.batch[key]
        if model_key is None:
            return cast(float, element.value) if element.kind not in "VI" else float(cast(float, element.waveform))
        return (self.diode_rs if model_key == "RS" else self.switch_ron)[element.name]

    # --- the inductance matrix (K couplings) -------------------------------------------------------------------

    def inductance_matrix(self) -> _Array:
        m = len(self.inductors)
        L = np.diag([l.value for l in self.inductors]).astype(float)
        index = {l.name: i for i, l in enumerate(self.inductors)}
        for k in self.by_kind["K"]:
            a, b = (index[name] for name in k.control)
            if a == b:
                raise self.error(k, f"{k.title}: couples {k.control[0].upper()} with itself")
            L[a, b] = L[b, a] = cast(float, k.value) * math.sqrt(L[a, a] * L[b, b])
        if m and np.linalg.eigvalsh(L).min() <= 1e-12 * np.abs(L).max():
            couplings = ", ".join(k.name.upper() for k in self.by_kind["K"])
            raise NetlistError(f"{self.path}: the coupled inductances ({couplings}) are not positive definite (a "
                               "coupling of 1 makes the currents dependent: use a coupling below 1)")
        return L

    # --- drives and the schedule -------------------------------------------------------------------------------

    def run(self) -> Compiled:
        self.state_rows: dict[str, _Array] = {}
        drives = {s.name: self.switch_drive(s) for s in self.switches}
        self.drives = drives
        if self.state_rows:
            return self.run_state_driven(drives)
        period = self.period()
        power = [s for s in self.sources if isinstance(s.waveform, Pulse) and self.in_power_circuit(s)]
        self.check_ramps()
        for s in power:
            w = cast(Pulse, s.waveform)
            if not math.isfinite(w.per):
                raise self.error(s, f"{s.title}: a single pulse in the power circuit: give it a period (PER)")
            if s not in self.edged:
                self.check_steps(s, w)
                continue
            flat = w.pw + (w.per - w.tr - w.pw - w.tf)
            if flat < EDGE_FLAT * w.per * (1.0 - 1e-9):
                raise self.error(s, f"{s.title}: its levels hold for {flat / w.per:.3g} of its period (PW and PER - TR "
                                    f"- PW - TF); its ramp is pinned on the periodic orbit by its levels, which must "
                                    f"hold for at least {EDGE_FLAT:g} of it (for a smooth periodic source use SIN)")
        once = {name: d for name, d in drives.items() if d and any(_once(self.source(n).waveform) for n in d)}
        corners = ({t for r in self.ramps for t, _ in cast(Pwl, r.waveform).points if t > 0.0}
                   | {cast(Sin, o.waveform).td for o in self.oscillators if cast(Sin, o.waveform).td > 0.0})
        phase_times, phase_states = self.phases(once, corners)
        repeating = {name: d for name, d in drives.items() if name not in once}
        starts, periodic_keys = self.schedule_keys(period, repeating, power)
        names = [s.name for s in self.switches]

        # a periodic key with the one-shot switches' states and the ramps' slopes of a phase
        def full(key: tuple[tuple[bool, ...], tuple[int, ...]], state: dict[str, bool], start: float) -> _Key:
            held = dict(zip(repeating, key[0]))
            return (tuple(held[n] if n in held else state[n] for n in names), key[1],
                    tuple(_slope(cast(Pwl, r.waveform), start) for r in self.ramps),
                    tuple(start >= cast(Sin, o.waveform).td for o in self.oscillators))
        phase_keys = [[full(key, state, start) for key in periodic_keys]
                      for state, start in zip(phase_states, [0.0, *phase_times])]
        distinct = list(dict.fromkeys(key for keys_ in phase_keys for key in keys_))
        configs: list[Configuration]
        pair_currents: list[tuple[bool, ...]]
        closed: list[tuple[bool, ...]]
        maps: list[_Maps]
        per_config_sinusoids: list[tuple[_Array, _Array]]
        configs, pair_currents, closed, maps, per_config_sinusoids = [], [], [], [], []
        floats: list[tuple[_Array, _Array] | None] = []
        #: each configuration's (switch states, source levels, slopes, running): what :meth:`rerun` solves again
        self.built: list[tuple[dict[str, bool], dict[str, int], tuple[float, ...], tuple[bool, ...]]] = []
        for key in distinct:
            switch_state = dict(zip([s.name for s in self.switches], key[0]))
            levels = dict(zip([s.name for s in power], key[1]))
            self.built.append((switch_state, levels, key[2], key[3]))
            config, forms, signals, sinusoids = self.configuration(switch_state, levels, key[2], key[3])
            per_config_sinusoids.append(sinusoids)
            configs.append(config)
            pair_currents.append(tuple(f == CURRENT for f in forms))
            closed.append(tuple(key[0]))
            maps.append(signals)
            floats.append(self.floating(switch_state, levels))
        sines = [cast(Sin, self.sources[c - self.n - self.k].waveform) for c in self.sinusoid_columns()[0]]
        laws = [self.schedule(period, starts, [distinct.index(k) for k in keys_], bool(sines)) for keys_ in phase_keys]
        schedule = laws[0]
        periodic = math.isfinite(schedule.period)
        inputs: tuple[_Array, _Array, _Array, _Array] | None = None
        if sines:
            E_sin = np.array([e for e, _ in per_config_sinusoids])
            F_sin = np.array([f for _, f in per_config_sinusoids])
            inputs = (np.array([2 * math.pi * w.freq for w in sines]), np.array([math.radians(w.phase) for w in sines]),
                      E_sin, F_sin)
        state_names = (tuple(f"v({c.name})" for c in self.capacitors) + tuple(f"i({l.name})" for l in self.inductors)
                       + tuple(f"pwl({r.name})" for r in self.ramps) + tuple(f"pulse({e.name})" for e in self.edged)
                       + tuple(f"{f}({o.name})" for o in self.oscillators for f in ("sin", "cos")))
        return Compiled(configurations=tuple(configs), law=schedule, state_names=state_names,
                        pair_names=tuple(d.name for d in self.diodes) or ("none",), pair_currents=tuple(pair_currents),
                        switch_names=tuple(s.name for s in self.switches), closed=tuple(closed),
                        signal_names=self.signal_names(), signal_maps=tuple(maps),
                        period=period if periodic else math.inf, x0=self.initial_state(), units=self.units(),
                        inputs=inputs, gates=self.gate_waveforms(), phases=tuple(zip(phase_times, laws[1:])),
                        invariants=self.invariants(state_names), notes=self.moved(state_names), energy=self.energy(),
                        floating=tuple(floats),
                        power_edges=tuple((s.title, cast(Pulse, s.waveform).per, _edge_middles(cast(Pulse, s.waveform)))
                                          for s in power if s not in self.edged),
                        ramped_edges=tuple((e.title, cast(Pulse, e.waveform).tr, cast(Pulse, e.waveform).tf)
                                           for e in self.edged))

    @staticmethod
    def schedule(period: float, starts: list[float], index: list[int], sines: bool) -> Schedule:
        """The schedule of configurations ``index`` from ``starts`` (consecutive repeats merged): periodic where the
        configuration changes within the period or a SIN source runs, else constant."""
        merged_starts: list[float]
        merged: list[int]
        merged_starts, merged = [], []
        for t, c in zip(starts, index):
            if not merged or merged[-1] != c:
                merged_starts.append(t)
                merged.append(c)
        if math.isfinite(period) and (len(merged) > 1 or sines):
            return Schedule(period=period, starts=tuple(merged_starts), configs=tuple(merged))
        return Schedule.constant(merged[0])

    def check_ramps(self) -> None:
        """A PWL in the power circuit is compiled where it does not repeat and does not jump (each of its segments a
        ramp the state follows exactly); refused otherwise, naming it."""
        for r in self.ramps:
            w = cast(Pwl, r.waveform)
            if not _once(w):
                raise self.error(r, f"{r.title}: a PWL that repeats (r=) in the power circuit is not compiled (a ramp "
                                    "here is a state of the LCS, which a periodic steady state cannot pin); a PWL "
                                    "without r= is (a soft start, a load profile)")
            jump = next((t0 for (t0, _), (t1, _) in zip(w.points, w.points[1:]) if t1 <= t0), None)
            if jump is not None:
                raise self.error(r, f"{r.title}: its PWL jumps at t = {jump:g} s (two points at one time); in the power "
                                    "circuit give the step a rise time (a state cannot jump)")

    def source(self, name: str) -> Element:
        return next(x for x in self.sources if x.name == name)

    def phases(self, once: dict[str, dict[str, float]],
               corners: Iterable[float] = ()) -> tuple[tuple[float, ...], list[dict[str, bool]]]:
        """(the instants t > 0 where a switch driven by sources that do not repeat changes, or a ramp in the power
        circuit turns (``corners``), the states of those switches in each phase: before the first instant, then from
        each on)."""
        changes: dict[str, tuple[bool, list[tuple[float, bool]]]] = {}
        for name, coefficients in once.items():
            switch = next(x for x in self.switches if x.name == name)
            repeating = [n for n in coefficients if not _once(self.source(n).waveform)
                         and not isinstance(self.source(n).waveform, float)]
            if repeating:
                raise self.error(switch, f"{switch.title}: its control adds a source that repeats ({repeating[0].upper()}) "
                                         "to one that does not: a gate is periodic or one-shot, not both")
            changes[name] = self.one_shot_events(switch, coefficients)
        times = sorted({t for _, events in changes.values() for t, _ in events} | set(corners))
        states: list[dict[str, bool]] = []
        for start in [0.0, *times]:
            state: dict[str, bool] = {}
            for name, (initial, events) in changes.items():
                state[name] = initial
                for t, closed in events:
                    if t <= start:
                        state[name] = closed
            states.append(state)
        return tuple(times), states

    def one_shot_events(self, switch: Element, coefficients: dict[str, float]) -> tuple[bool, list[tuple[float, bool]]]:
        """(state at t = 0, [(t > 0, closed)]) of a switch whose control is made of sources that do not repeat: its
        crossings of VT + VH (closing) and VT - VH (opening) over the whole run (after its last corner the control
        holds)."""
        vt, vh = self.threshold(switch)
        corners: set[float] | _Array
        corners = {0.0}
        for name in coefficients:
            w = self.source(name).waveform
            if isinstance(w, Pulse):
                corners.update(np.cumsum([w.td, w.tr, w.pw, w.tf]).tolist())
            elif isinstance(w, Pwl):
                corners.update(t for t, _ in w.points)
        corners = np.array(sorted(t for t in corners if math.isfinite(t) and t >= 0.0))
        values = self.waveform_value(coefficients, corners)
        if abs(values[0] - vt) <= vh:
            names, unit = (("VT", "VH"), "V") if switch.kind == "S" else (("IT", "IH"), "A")
            raise self.error(switch, f"{switch.title}: its control at t = 0 ({values[0]:g} {unit}) lies inside the "
                                     f"hysteresis band {names[0]} +- {names[1]} = {vt:g} +- {vh:g} {unit}: its state is "
                                     "not defined")
        initial = bool(values[0] > vt)
        events = _crossings(corners, values, vt + vh, vt - vh, initial)
        return initial, [(t, closed) for t, closed in events if t > 0.0]

    def run_state_driven(self, drives: dict[str, dict[str, float] | None]) -> Compiled:
        """Switches driven by the circuit's own quantities (comparators), with switches that follow one of them or
        its complement (a synchronous rectifier's gate on the same comparator), the others by DC: one configuration
        per combination of the comparators' states, configuration sum(closed_j << j), and a
        :class:`~converters.problems.StateSwitching` law (one comparator) or a
        :class:`~converters.problems.Comparators` law (several: interleaved phases), each channel's ramp its own
        (none: an autonomous circuit)."""
        from ..problems import Comparators, StateSwitching, SwitchingFunction
        from ..problems.switching import MAX_CHANNELS, common_period
        if any(d for d in drives.values() if d is not None and any(
                isinstance(self.source(name).waveform, (Pulse, Pwl)) for name in d)):
            names = ", ".join(n.upper() for n in self.state_rows)
            raise NetlistError(f"{self.path}: {names} driven by the circuit's own quantities beside PULSE gates: "
                               "comparators' switches with the others at DC is what is compiled yet")
        if any(isinstance(x.waveform, (Pulse, Sin, Pwl)) and self.in_power_circuit(x) for x in self.sources):
            raise NetlistError(f"{self.path}: a state-driven switch with PULSE, SIN or PWL sources in the power "
                               "circuit is not compiled yet")
        leaders: list[tuple[Element, _Array]]
        followers: dict[str, tuple[int, bool, float]]
        leaders, followers = [], {}              # followers: name -> (leader index, same, scale)
        for name, row in self.state_rows.items():
            switch = next(x for x in self.switches if x.name == name)
            found = next(((j, *following) for j, (leader, row0) in enumerate(leaders)
                          if (following := self.follows(leader, row0, switch, row)) is not None), None)
            if found is None:
                leaders.append((switch, row))
            else:
                followers[name] = found
        m = len(leaders)
        if m > MAX_CHANNELS:
            raise NetlistError(f"{self.path}: {m} comparators (switches driven by the circuit's own quantities that "
                               f"follow no other); at most {MAX_CHANNELS} are compiled")
        fixed = {}
        for other in self.switches:
            if other.name not in self.state_rows:
                value = sum(c * float(cast(float, self.source(src).waveform))
                            for src, c in (drives[other.name] or {}).items())
                fixed[other.name] = value > self.threshold(other)[0]
        pieces: list[list[_Array]]
        configs: list[Configuration]
        pair_currents: list[tuple[bool, ...]]
        closed: list[tuple[bool, ...]]
        maps: list[_Maps]
        index_of: list[int]
        pieces, configs, pair_currents, closed, maps, index_of = [], [], [], [], [], []
        floats: list[tuple[_Array, _Array] | None] = []
        why: dict[int, str] = {}                # the combinations with no configuration: the compiler's reason
        for index in range(2 ** m):
            on = [bool(index >> j & 1) for j in range(m)]
            state = {**fixed, **{leader.name: on[j] for j, (leader, _) in enumerate(leaders)},
                     **{f: on[j] == same for f, (j, same, _) in followers.items()}}
            try:
                config, forms, signals, _ = self.configuration(state, {})
            except NetlistError as refused:
                if m == 1:
                    raise
                index_of.append(-1)    # the comparators' switches together short a source: a run that gets there stops
                why[index] = str(refused).split(": ", 1)[-1] if str(refused).startswith(self.nl.path) else str(refused)
                continue
            index_of.append(len(configs))
            configs.append(config)
            pair_currents.append(tuple(f == CURRENT for f in forms))
            closed.append(tuple(state[x.name] for x in self.switches))
            maps.append(signals)
            floats.append(self.floating(state, {}))
            solution = self.network(state, {})[0]
            pieces.append([self.control(solution, leader) for leader, _ in leaders])
            for f, (j, _, scale) in followers.items():
                other = next(x for x in self.switches if x.name == f)
                if np.abs(self.control(solution, other) - scale * pieces[-1][j]).max() > 1e-9 * np.abs(pieces[-1][j]).max():
                    raise self.error(other, f"{other.title}: its control is {scale:g} x {leaders[j][0].title}'s in one "
                                            "configuration, not in another: it does not follow that comparator")
        channels: list[StateSwitching] = []
        for j, (leader, _) in enumerate(leaders):
            rows = [piece[j] for piece in pieces]
            if any(np.abs(r - rows[0]).max() > 1e-9 * max(np.abs(rows[0]).max(), 1e-300) for r in rows[1:]):
                raise self.error(leader, f"{leader.title}: its control changes with a switch's state (its own or "
                                         "another comparator's): a comparator whose input a switch moves is not "
                                         "compiled")
            c, d, ramp = self.state_law(leader, rows[0])
            channels.append(StateSwitching(SwitchingFunction(c=c, d=d, ramp=ramp), below=0, above=1,
                                           band=self.threshold(leader)[1]))
        # channel j below (its s = VT - V under -VH) closes its switch: bit j of the law's states set is open
        table = tuple(index_of[(2 ** m - 1) ^ bits] for bits in range(2 ** m))
        if not configs:
            self.configuration({**fixed, **{leader.name: True for leader, _ in leaders}}, {})     # its refusal
        law: Law
        law = (StateSwitching(channels[0].function, below=table[0], above=table[1], band=channels[0].band) if m == 1
               else Comparators(tuple(channels), table, names=tuple(leader.name for leader, _ in leaders),
                                words=("closed", "open"),
                                reasons=tuple(why.get((2 ** m - 1) ^ bits, "") for bits in range(2 ** m))))
        periods = [ch.period for ch in channels if math.isfinite(ch.period)]
        state_names = tuple(f"v({x.name})" for x in self.capacitors) + tuple(f"i({x.name})" for x in self.inductors)
        return Compiled(configurations=tuple(configs), law=law, state_names=state_names,
                        pair_names=tuple(d.name for d in self.diodes) or ("none",), pair_currents=tuple(pair_currents),
                        switch_names=tuple(x.name for x in self.switches), closed=tuple(closed),
                        signal_names=self.signal_names(), signal_maps=tuple(maps),
                        period=common_period(periods) if periods else math.inf, x0=self.initial_state(),
                        units=self.units(), gates=self.gate_waveforms(), invariants=self.invariants(state_names),
                        notes=self.moved(state_names), energy=self.energy(), floating=tuple(floats))

    def period(self) -> float:
        """The common period of the periodic sources (PULSE, SIN, a repeating PWL: their least common multiple), inf
        without one."""
        for s in self.sources:
            w = s.waveform
            if isinstance(w, Pulse) and math.isfinite(w.per) and w.td >= w.per:
                raise self.error(s, f"{s.title}: a PULSE delay TD = {w.td:g} s of a whole period ({w.per:g} s) or "
                                    "more: the waveform is not periodic from t = 0")
        named = [(s, "PULSE", s.waveform.per) for s in self.sources
                 if isinstance(s.waveform, Pulse) and math.isfinite(s.waveform.per)]
        named += [(s, "SIN", 1.0 / s.waveform.freq) for s in self.sources
                  if isinstance(s.waveform, Sin) and s.waveform.freq > 0 and s not in self.oscillators]
        named += [(s, "PWL", s.waveform.period) for s in self.sources
                  if isinstance(s.waveform, Pwl) and not _once(s.waveform)]
        if not named:
            return math.inf
        from ..problems.switching import common_period
        try:
            return common_period([period for _, _, period in named])
        except ParameterError:
            # pcsuite compiles a circuit's switching over the common period of its sources, a transient too (a
            # comparator's crossings are found within it): ngspice needs none
            listed = ", ".join(f"{s.name.upper()} ({kind}) {period:.9g} s" for s, kind, period in named)
            longest = max(period for _, _, period in named)
            raise NetlistError(f"{self.path}: the sources' periods have no common period, which pcsuite compiles a "
                               f"circuit's switching over (a transient too): each must be a fraction of the longest "
                               f"({longest:.9g} s) with a denominator up to 1000; {listed}") from None

    def in_power_circuit(self, source: Element) -> bool:
        """False for a gate driver: a source whose nodes reach, through resistors and other voltage sources (a
        controlled one's output too: a current sense's H output beside a compensation ramp), only switch control
        terminals and ground (its value then decides when switches close, not the circuit's dynamics)."""
        power = {n for e in self.nl.elements if e.kind in "LCDSWGF" for n in e.nodes[:2]}
        power |= {n for e in self.by_kind["I"] for n in e.nodes}
        seen, todo = set(), [n for n in source.nodes if n != "0"]
        while todo:
            node = todo.pop()
            if node in seen:
                continue
            seen.add(node)
            if node in power:
                return True
            for e in self.nl.elements:
                ends = e.nodes if e.kind in "RV" else e.nodes[:2] if e.kind in "EH" else ()
                if node in ends:
                    todo += [m for m in ends if m != "0" and m not in seen]
        return False

    def follows(self, switch: Element, row0: _Array, other: Element, row: _Array) -> tuple[bool, float] | None:
        """(same, scale) of a second state-driven switch whose control is ``scale`` times the first's: closed with
        it (same: scale > 0 and the same thresholds) or exactly when it is open (its complement: scale < 0 and the
        thresholds swapped: S2 on v(vcon) - v(ramp) beside S1 on v(ramp) - v(vcon), both VT = 0); None otherwise
        (a comparator of its own)."""
        scale = float(row @ row0 / (row0 @ row0))
        near: Callable[[float, float], bool]
        near = lambda a, b: abs(a - b) <= 1e-9 * max(1.0, abs(a), abs(b))       # noqa: E731
        if np.abs(row - scale * row0).max() <= 1e-9 * np.abs(row).max():
            (vt0, vh0), (vt, vh) = self.threshold(switch), self.threshold(other)
            closes, opens = (vt + vh) / scale, (vt - vh) / scale
            if scale > 0 and near(closes, vt0 + vh0) and near(opens, vt0 - vh0):
                return True, scale
            if scale < 0 and near(closes, vt0 - vh0) and near(opens, vt0 + vh0):
                return False, scale
        return None

    def threshold(self, switch: Element) -> tuple[float, float]:
        """(threshold, hysteresis) of a switch's model: VT, VH (V) of an S switch's SW, IT, IH (A) of a W's CSW."""
        params = self.nl.models[cast(str, switch.model)].params
        keys = ("VT", "VH") if switch.kind == "S" else ("IT", "IH")
        return params.get(keys[0], 0.0), abs(params.get(keys[1], 0.0))

    def control(self, solution: _Network, switch: Element) -> _Array:
        """The row of a switch's control quantity in a solved network: V(nc+) - V(nc-) of an S switch, the current
        through the controlling V source of a W switch."""
        if switch.kind == "W":
            return solution.current(next(v for v in self.by_kind["V"] if v.name == switch.control[0]))
        return solution.voltage(switch.nodes[2]) - solution.voltage(switch.nodes[3])

    def switch_drive(self, switch: Element) -> dict[str, float] | None:
        """The switch's control (:meth:`control`) as {source name: coefficient} where sources alone fix it; None
        (and its row in ``state_rows``) where it depends on the states: a comparator."""
        # any configuration the network can be solved in will do (a switch's control terminals draw no current): the
        # first of every switch state (a synchronous buck cannot be solved with both switches open, nor closed); if
        # none can, the network's own refusal (the loop or cutset it names) is the one to give
        names = [s.name for s in self.switches]
        states = (itertools.product((False, True), repeat=len(names)) if len(names) <= 10
                  else [(False,) * len(names), (True,) * len(names)])
        solution: _Network | None
        failure: NetlistError | None
        solution, failure = None, None
        for state in states:
            try:
                solution = self.network(dict(zip(names, state)), {})[0]
                break
            except NetlistError as error:
                failure = failure or error
        if solution is None:
            assert failure is not None          # every state was tried: each refusal kept the first
            raise failure
        row = self.control(solution, switch)
        scale = max(np.abs(row).max(initial=0.0), 1e-300)
        if np.abs(row[:self.n + self.k]).max(initial=0.0) > 1e-12 * scale:
            self.state_rows[switch.name] = row          # a comparator on the circuit's own quantities
            return None
        return {s.name: row[self.n + self.k + i] for i, s in enumerate(self.sources) if row[self.n + self.k + i] != 0.0}

    def state_law(self, switch: Element, row: _Array) -> tuple[_Array, float, Ramp | None]:
        """The StateSwitching of a switch whose control voltage V = c.x + (sources) depends on the states: with
        s = VT - V the switch closes when s falls below -VH and opens when it rises above +VH (SW's thresholds VT
        +- VH); a sawtooth PULSE in its control (its width, fall and rest RETRACE_TAKEN of its period at most) is the
        law's ramp.
        Returns (function pieces: c, d, ramp) or raises naming what it cannot take."""
        from ..problems import Ramp
        n, k = self.n, self.k
        if np.abs(row[n:n + k]).max(initial=0.0) > 1e-12 * max(np.abs(row).max(), 1e-300):
            raise self.error(switch, f"{switch.title}: its control voltage depends on a diode's current or voltage; a "
                                     "comparator here reads node voltages and branch currents of the states only")
        ramp: Ramp | None
        d, ramp = self.threshold(switch)[0], None
        for i, src in enumerate(self.sources):
            a = row[n + k + i]
            if a == 0.0:
                continue
            w = src.waveform
            if isinstance(w, Pulse):
                # its rise takes the period but for its width, its fall and any rest at V1 (PER - TR): a PULSE that
                # rose over half its period and rested at V1 for the other half had been read as the sawtooth over
                # the whole period (a voltage-mode loop's gain 4.9 dB high, its mean 2.1 % off, its period doubling
                # the sawtooth's)
                if (ramp is not None or not math.isfinite(w.per) or not 0.0 < w.tr <= w.per
                        or w.per - w.tr > RETRACE_TAKEN * w.per * (1 + 1e-9) or w.tr + w.tf + w.pw > w.per * (1 + 1e-12)
                        or w.td >= w.per):
                    raise self.error(src, f"{src.title}: in {switch.title}'s control a PULSE must be one sawtooth "
                                          "ramp: PULSE(V1 V2 TD TR TF PW PER) rising over TR, with its width, its "
                                          f"fall and any rest at V1 (PER - TR) at most {RETRACE_TAKEN:g} PER, and TD "
                                          f"under PER (got TR = {w.tr:.6g} s, PER = {w.per:.6g} s)")
                # s = VT - V: the ramp enters as -a pulse, a sawtooth with the PULSE's own slope (V2 - V1) / TR,
                # so a crossing as it rises is the PULSE's to rounding, reset at the middle of its fall (TD + TR + PW
                # + TF / 2): a crossing as it falls, at TR + PW + TF (V2 - V) / (V2 - V1), moves by TF / 2 at most.
                # Against an exact computation of the literal PULSE (a fall of 5e-4 of the period), the voltage-mode
                # buck's vout is 2.2e-5 V off (the sawtooth over the whole period: 9.9e-5; reset at the fall's end:
                # 1.05e-4). A delayed ramp (TD > 0: a second phase) is periodic from t = 0, where SPICE holds V1
                # until TD: a run from rest differs over its first TD seconds only
                slope = (w.v2 - w.v1) / w.tr
                reset = w.tr + w.pw + w.tf / 2
                low = w.v1 - slope * (w.per - reset)
                ramp = Ramp(low=a * low, high=a * (low + slope * w.per), period=w.per,
                            delay=math.fmod(w.td + reset, w.per))
                # where the sawtooth leaves the PULSE: a falling crossing moved by up to TF / 2, and past V2 for PW +
                # TF / 2 (the PULSE's width and half its fall) and below V1 for the rest at V1 and half the fall,
                # where a control beyond V2 or V1 switches that the PULSE never crosses (a loop held at a duty of 1
                # by 2 mV: 13 mV of vout where there is none)
                rest = max(w.per - w.tr - w.pw - w.tf, 0.0)
                above, below = w.pw + w.tf / 2, rest + w.tf / 2
                if max(above, below) > RETRACE_SAID * w.per:
                    self.ramp_notes.append(
                        f"{src.title}'s ramp is taken as a sawtooth with its slope, reset at the middle of its fall "
                        f"(TF = {w.tf / w.per:.2g} of its period): in {switch.title}'s comparator a switching as the "
                        f"ramp falls moves by up to {w.tf / 2 / w.per:.2g} of the period, and a control beyond V2 by "
                        f"less than {abs(slope) * above:.2g} V (its slope times PW + TF/2) or beyond V1 by less than "
                        f"{abs(slope) * below:.2g} V (times its rest at V1 + TF/2) switches where the PULSE does not: "
                        f"the numbers move with them against ngspice's (said from {RETRACE_SAID:g} of the period)")
            elif isinstance(w, (Sin, Pwl)):
                raise self.error(src, f"{src.title}: a {type(w).__name__.upper()} in {switch.title}'s control is not "
                                      "compiled")
            else:
                d -= a * float(cast(float, w))
        return -row[:n], d, ramp

    def schedule_keys(self, period: float, drives: dict[str, dict[str, float] | None],
                      power: list[Element]) -> tuple[list[float], list[tuple[tuple[bool, ...], tuple[int, ...]]]]:
        """The instants in [0, T) where a switch or a power source changes, and the key of each interval:
        ((switch closed...), (source level index...))."""
        span = period if math.isfinite(period) else 1.0
        times = {0.0}
        waveforms: dict[str, tuple[Any, ...]] = {}     # ("switch", coefficients, vt, vh) or ("level", waveform)
        for name, coefficients in drives.items():
            vt, vh = self.threshold(next(s for s in self.switches if s.name == name))
            waveforms[name] = ("switch", coefficients, vt, vh)
        for s in power:
            waveforms[s.name] = ("level", s.waveform)
        events: list[tuple[int, Sequence[tuple[float, int]]]] = []
        for name, spec in waveforms.items():
            if spec[0] == "switch":
                events.append(self.switch_events(name, spec[1], spec[2], spec[3], period))
            else:
                events.append(self.level_events(spec[1], period, self.source(name) in self.edged))
        changes: tuple[int, Sequence[tuple[float, int]]] | Sequence[tuple[float, int]]   # an event, then its changes
        for changes in events:
            times.update(t for t, _ in changes[1])
        starts = sorted(t for t in times if 0.0 <= t < span * (1 - 1e-12))
        keys = []
        for t in starts:
            values = []
            for initial, changes in events:
                state = initial
                for when, value in changes:
                    if when <= t * (1 + 1e-15) + 1e-300:
                        state = value
                values.append(state)
            switches = tuple(bool(v) for v in values[:len(drives)])
            levels = tuple(int(v) for v in values[len(drives):])
            keys.append((switches, levels))
        return starts, keys

    def waveform_value(self, coefficients: dict[str, float], t: _Array) -> _Array:
        total = np.zeros_like(t)
        for name, c in coefficients.items():
            total += c * waveform_at(cast(Waveform, self.source(name).waveform), t)
        return total

    def corners(self, coefficients: dict[str, float], period: float) -> _Array:
        points: list[float] | _Array
        # the window's ends are corners too: a ramp still rising at 2 T (a sawtooth delayed by T/3 restarts at 4T/3)
        # had its last segment dropped with its crossing, and the duty 0.4 read 0.667
        points = [0.0, period, 2 * period]
        for name in coefficients:
            w = self.source(name).waveform
            if isinstance(w, Pulse):
                per = w.per if math.isfinite(w.per) else period
                for m in range(int(math.ceil(2 * period / per)) + 1):
                    base = w.td + m * per
                    points += [base, base + w.tr, base + w.tr + w.pw, base + w.tr + w.pw + w.tf]
            elif isinstance(w, Pwl):
                for m in range(int(math.ceil(2 * period / w.period)) + 1):
                    points += [m * w.period + t for t, _ in w.points]
            elif isinstance(w, Sin) and w.freq > 0:
                # a sine between the corners: pieces of at most 1/SINE_PIECES of its period, on each of which a
                # crossing of the sum (a line plus slow sines) is one sign change
                points += list(np.linspace(0.0, 2 * period, int(math.ceil(2 * period * w.freq * SINE_PIECES)) + 1))
        points = np.unique(np.array([p for p in points if 0.0 <= p <= 2 * period]))
        return points

    def sine_extrema(self, coefficients: dict[str, float], corners: _Array) -> _Array:
        """``corners`` with the control's extrema between them: a sine's peak inside a piece is a crossing pair
        that its ends, both below the threshold, do not show (a gate SIN(0 1 10k 0 0 2.8125) against VT = 0.999,
        closed 1.4 % of the period around its peak, mid-piece: both ends at 0.9988, the pulse lost, a buck's vout
        read 0 V "within ~0" where it is 2.58 V). Between corners the control is a line plus sines; its slope's
        sign changes are located by Brent's method."""
        sines = [(c, cast(Sin, self.source(name).waveform)) for name, c in coefficients.items()
                 if isinstance(self.source(name).waveform, Sin)]

        def sine_part(t: _Array) -> _Array:
            return sum((c * waveform_at(w, t) for c, w in sines), np.zeros_like(t))

        def sine_slope(t: float) -> float:
            return sum(c * w.va * 2 * math.pi * w.freq * math.cos(2 * math.pi * w.freq * t + math.radians(w.phase))
                       for c, w in sines)
        values = self.waveform_value(coefficients, corners)
        line = values - sine_part(corners)              # the PULSE and PWL terms: linear between the corners
        extra = []
        from scipy.optimize import brentq
        for t0, t1, a, b in zip(corners[:-1], corners[1:], line[:-1], line[1:]):
            slope = (b - a) / (t1 - t0)
            g0, g1 = slope + sine_slope(t0), slope + sine_slope(t1)
            if g0 * g1 < 0.0:
                extra.append(brentq(lambda t: slope + sine_slope(t), t0, t1, xtol=1e-15 * max(t1, 1e-300),
                                    rtol=1e-15))
        return np.unique(np.concatenate([corners, extra])) if extra else corners

    def switch_events(self, name: str, coefficients: dict[str, float], vt: float, vh: float,
                      period: float) -> tuple[bool, list[tuple[float, bool]]]:
        """(state at t = 0 on the periodic orbit, [(t in [0, T), closed)]) from the crossings of the control
        voltage with VT + VH (closing) and VT - VH (opening)."""
        switch = next(s for s in self.switches if s.name == name)
        if not math.isfinite(period):
            value = float(self.waveform_value(coefficients, np.array([0.0]))[0])
            if abs(value - vt) <= vh:
                names, unit = (("VT", "VH"), "V") if switch.kind == "S" else (("IT", "IH"), "A")
                raise self.error(switch, f"{switch.title}: its DC control {value:g} {unit} lies inside the hysteresis "
                                         f"band {names[0]} +- {names[1]} = {vt:g} +- {vh:g} {unit}: its state is not "
                                         "defined")
            return value > vt, []
        corners = self.corners(coefficients, period)
        smooth = any(isinstance(self.source(name).waveform, Sin) for name in coefficients)
        if smooth:
            corners = self.sine_extrema(coefficients, corners)
        values = self.waveform_value(coefficients, corners)
        changes = _crossings(corners, values, vt + vh, vt - vh, values[0] > vt,
                             (lambda t: float(self.waveform_value(coefficients, np.array([t]))[0])) if smooth else None)
        # the state at the start of the second period is the periodic one
        initial = next((s for t, s in reversed(changes) if t <= period * (1 + 1e-12)), values[0] > vt)
        inside = [(t - period, s) for t, s in changes if period * (1 - 1e-12) < t < 2 * period * (1 - 1e-12)]
        if not any(True for _ in changes):
            value = float(values[0])
            if abs(value - vt) <= vh:
                raise self.error(switch, f"{switch.title}: its control never leaves the hysteresis band")
        return initial, [(max(t, 0.0), s) for t, s in inside]

    def level_events(self, w: Pulse, period: float, edged: bool = False) -> tuple[int, list[tuple[float, int]]]:
        """(level at t = 0 on the periodic orbit, [(t in [0, T), level)]): a power PULSE holds v1 (level 0) or v2
        (level 1), changing at the middle of its edges; an edged one (:attr:`edged`) rises (level RISING) and falls
        (FALLING) between them over its edges."""
        per = w.per
        # an edge whose middle falls on the period's end (T/2 - e/2 + e + T/2 - e + e/2) is at 0, not at the
        # 1e-21 s that rounding leaves of it (a step of 1e-21 s at every period)
        snap: Callable[[float], float]
        snap = lambda t: 0.0 if min(t % per, per - t % per) <= 1e-12 * per else t % per      # noqa: E731
        marks = [(w.td + w.tr / 2, 1), (w.td + w.tr + w.pw + w.tf / 2, 0)]
        if edged:
            marks = [(w.td, RISING), (w.td + w.tr, 1), (w.td + w.tr + w.pw, FALLING), (w.td + w.tr + w.pw + w.tf, 0)]
            # a level that lasts nothing (a triangle's PW = 0) is no phase: the ramps meet
            marks = [(t, level) for (t, level), (after, _) in zip(marks, marks[1:] + [(w.td + per, RISING)])
                     if after - t > 1e-12 * per]
        one = sorted((snap(t), level) for t, level in marks)
        initial = one[-1][1]                        # the level the period ends with holds through t = 0
        inside = [(t + m * per, level) for m in range(int(round(period / per))) for t, level in one]
        return initial, sorted(inside)

    # --- one configuration ---------------------------------------------------------------------------------

    def network(self, switch_state: dict[str, bool], levels: dict[str, int]) -> tuple[_Network, list[str]]:
        """(the solved network, the port forms) of one configuration: every diode a current port, but those the
        network then cannot solve for (an inductor or another port fixes their current), which are voltage ports.

        The forms found are kept per circuit structure (:data:`_FORMS`): a sweep compiles the same netlist with
        new values at every point, and the search (a rank per trial) is the compile's largest cost. The kept forms
        are used only where this configuration's network is solvable with them (a controlled source's gain can
        make the rank depend on values); else the search runs again."""
        here = (tuple(switch_state.items()), tuple(levels.items()))
        forms: tuple[str, ...] | list[str]
        if here in self.solved:            # the switches' drives and the configurations ask for the same ones
            network, forms = self.solved[here]
            return network, list(forms)
        key = (self.nl.text, *here, tuple(s.name for s in self.shorts),
               tuple(d for d, rs in self.diode_rs.items() if rs), tuple(s for s, r in self.switch_ron.items() if r))
        kept = _FORMS.get(key)
        if kept is not None:
            network = _Network(self, switch_state, levels, list(kept))
            if network.nullity() == 0:
                self.solved[here] = (network.solve(checked=True), kept)
                return network, list(kept)
        forms = [CURRENT] * len(self.diodes)
        nullity = _Network(self, switch_state, levels, forms).nullity()
        for i in range(len(self.diodes)):
            if nullity == 0:
                break
            forms[i] = VOLTAGE
            trial = _Network(self, switch_state, levels, forms).nullity()
            if trial < nullity:
                nullity = trial
            else:
                forms[i] = CURRENT
        network = _Network(self, switch_state, levels, forms).solve()
        if len(_FORMS) >= MAX_KEPT_FORMS:
            _FORMS.clear()
        _FORMS[key] = tuple(forms)
        self.solved[here] = (network, tuple(forms))
        return network, forms

    def configuration(self, switch_state: dict[str, bool], levels: dict[str, int], slopes: tuple[float, ...] = (),
                      running: tuple[bool, ...] = ()) -> tuple[Configuration, list[str], _Maps, tuple[_Array, _Array]]:
        """(Configuration, port forms, signal maps, (E, F) of the SIN sources) of one configuration; ``slopes``: each
        ramp's slope in it (V/s or A/s); ``running``: each oscillator past its delay. An edged PULSE's level (its
        phase: a level, RISING or FALLING) is its ramp's, not the network's, whose input it is not."""
        solution, forms = self.network(switch_state, self.stepped(levels))
        config, signals, sinusoids = cast(_Lcs, self.lcs(solution, forms, switch_state, slopes, running,
                                                          tuple(levels.get(e.name, 0) for e in self.edged)))
        self.check_unique_ports(config, switch_state)
        return config, forms, signals, sinusoids

    def stepped(self, levels: dict[str, int]) -> dict[str, int]:
        """``levels`` as the network takes them: an edged PULSE's value is its ramp's state, whatever its phase."""
        edged = {e.name for e in self.edged}
        return {name: 0 if name in edged else level for name, level in levels.items()}

    def floating(self, switch_state: dict[str, bool], levels: dict[str, int]) -> tuple[_Array, _Array] | None:
        """The node potentials of this configuration that only its diodes tie to the rest of the circuit: shifts of
        the network's unknowns (every diode a current port) that satisfy every equation and change no capacitor's
        current and no inductor's voltage, so no state's derivative. A bridge rectifier's output while its four diodes
        block, a two-switch forward's winding between its clamp diodes at zero current: there the circuit sets no
        value to those nodes' potential (the LCP picks one of many; SPICE's comes from its leakages), and a conducting
        diode whose voltage a shift moves pins it. (what each signal does along them (S, m), what each diode's
        voltage does (k, m)), or None where there is none (a node behind an off diode and an inductor is set by the
        inductor's current and is not one). Not for a batch's points, nor a network beyond LARGE_NETWORK."""
        if not self.diodes or self.lead:
            return None
        network = _Network(self, switch_state, self.stepped(levels), [CURRENT] * len(self.diodes))
        if network.size == 0 or network.size > LARGE_NETWORK or network.nullity() == 0:
            return None
        _, sv, vt = np.linalg.svd(network.G)          # the null space at :meth:`_Network.nullity`'s tolerance
        shifts = vt[int(np.sum(sv > 1e-12 * max(np.abs(network.G).max(), 1.0))):].T
        moving = [np.eye(network.size)[network.branch_of[e.name]] for e in self.capacitors]
        for e in self.inductors:
            row = np.zeros(network.size)
            for node, sign in zip(e.nodes[:2], (1.0, -1.0)):
                if network.idx(node) is not None:
                    row[network.idx(node)] += sign
            moving.append(row)
        if moving:
            shifts = shifts @ _null(np.array(moving) @ shifts)
        if shifts.shape[1] == 0:
            return None
        along = copy.copy(network)             # the network's signal rows read along the shifts, not the inputs
        along.Z = shifts
        zero = np.zeros(shifts.shape[1])
        along.unit = lambda column=None: zero    # type: ignore[method-assign]  # states, diode currents: unmoved
        signals, ports = along.signal_rows(self.signal_names()), along.ports()
        for a in (signals, ports):
            a[np.abs(a) < 1e-9] = 0.0
        return (signals, ports) if signals.any() else None

    def lcs(self, solution: _Network, forms: Sequence[str], switch_state: dict[str, bool],
            slopes: tuple[float, ...] = (), running: tuple[bool, ...] = (),
            phases: tuple[int, ...] = ()) -> _Lcs | list[_Lcs]:
        """The configuration's LCS and signal maps from a solved network. A ramp (a PWL in the power circuit) is a
        state of its own, its value: its column of the network becomes a state's, and its slope its derivative. An
        edged PULSE (:attr:`edged`) is one too, at its edge's slope in phase RISING or FALLING (``phases``) and held
        on a level by r' = -gamma (r - level): zero on the waveform, and an r off it decays at gamma = LOOP_RATE / PER
        (as a loop of capacitors is held), so the periodic orbit pins it (a ramp alone repeats from any r). An
        oscillator (a delayed or damped SIN) is two, its value VO + VA s: its column scaled by VA becomes s's, and
        (s, c)' = [[-THETA, w], [-w, -THETA]] (s, c) once running (w = 2 pi FREQ), 0 before."""
        n, k = self.n, self.k
        dx = solution.derivatives()                       # (..., n, n + k + sources): ... a batch's points
        ports = solution.ports()                          # (..., k, n + k + sources)
        s = self.source_values(solution.levels)           # (..., sources)
        A, B, E = dx[..., :n], dx[..., n:n + k], _times(dx[..., n + k:], s)
        if self.islands and not self.lead:
            A, E = self.hold_islands(A, E)
        if self.flux_loops and not self.lead:
            A, E = self.hold_fluxes(A, E)
        C, D, F = ports[..., :n], ports[..., n:n + k], _times(ports[..., n + k:], s)
        if not self.diodes:                   # no diode: a pair that never holds (y = u + 1: u = 0)
            D, F = np.ones(self.lead + (1, 1)), np.ones(self.lead + (1,))
        shorted = self.shorted_diodes(switch_state, forms)
        if shorted:
            B, C, D, F = B.copy(), C.copy(), D.copy(), F.copy()
        for i in shorted:
            # an ideal diode across closed ideal switches (a body diode): its voltage is 0 whatever its current, so
            # any current would do (0 <= u, y = 0); the switch carries it all: a pair that never holds (y = u + 1)
            B[..., :, i], C[..., i, :], D[..., i, :], D[..., :, i], F[..., i] = 0.0, 0.0, 0.0, 0.0, 1.0
            D[..., i, i] = 1.0
        # a power PULSE's level is part of the configuration too (a rectifier of a square wave: two configurations)
        phase_of = dict(zip((e.name for e in self.edged), phases))
        name = ",".join([f"{sw}={'on' if on else 'off'}" for sw, on in switch_state.items()]
                        + [f"{src}={('v1', 'v2', 'rise', 'fall')[phase_of.get(src, level)]}"
                           for src, level in solution.levels.items()]) or "circuit"
        rows = solution.signal_rows(self.signal_names())
        columns, amplitudes = self.sinusoid_columns()
        E_sin, F_sin = dx[..., columns] * amplitudes, ports[..., columns] * amplitudes
        if not self.diodes:
            F_sin = np.zeros_like(F_sin)
        if shorted:
            F_sin = F_sin.copy()
            F_sin[..., shorted, :] = 0.0
        gates = self.gate_columns()
        static = s.copy()
        static[..., [c - n - k for c in gates]] = 0.0       # a gate's share is its waveform at each sample's time
        Sx = rows[..., :n]
        E_sin, F_sin = np.swapaxes(E_sin, -1, -2), np.swapaxes(F_sin, -1, -2)
        signals: _Maps = (Sx, rows[..., n:n + k], _times(rows[..., n + k:], static), rows[..., columns] * amplitudes,
                          rows[..., gates])
        if self.lead:                         # a batch (:meth:`rerun`): each point's configuration and maps
            return [(Configuration(A=A[p], B=B[p], C=C[p], D=D[p], E=E[p], F=F[p], name=name),
                     tuple(m[p].copy() for m in signals), (E_sin[p].copy(), F_sin[p].copy()))
                    for p in range(self.lead[0])]
        config = Configuration(A=A, B=B, C=C, D=D, E=E, F=F, name=name)
        extra: list[tuple[int | None, float]] = [(n + k + self.sources.index(x), 1.0)
                                                 for x in self.ramps + self.edged]
        for o in self.oscillators:
            extra += [(n + k + self.sources.index(o), cast(Sin, o.waveform).va), (None, 0.0)]
        if extra:
            r = len(extra)
            columns_of: Callable[[_Array], _Array]
            columns_of = lambda M: np.column_stack([M[:, c] * w if c is not None else np.zeros(M.shape[0])   # noqa: E731
                                                    for c, w in extra])
            block, rates = np.zeros((r, r)), np.zeros(r)
            rates[:len(self.ramps)] = slopes
            for i, (e, phase) in enumerate(zip(self.edged, phases), start=len(self.ramps)):
                p = cast(Pulse, e.waveform)
                if phase in (RISING, FALLING):
                    rates[i] = (p.v2 - p.v1) / p.tr if phase == RISING else (p.v1 - p.v2) / p.tf
                else:
                    block[i, i] = -LOOP_RATE / p.per
                    rates[i] = LOOP_RATE / p.per * (p.v2 if phase else p.v1)
            for j, (o, on) in enumerate(zip(self.oscillators, running)):
                i, w, damping = (len(self.ramps) + len(self.edged) + 2 * j, 2 * math.pi * cast(Sin, o.waveform).freq,
                                 cast(Sin, o.waveform).theta)
                if on:
                    block[i:i + 2, i:i + 2] = [[-damping, w], [-w, -damping]]
            C_extra = columns_of(ports)
            C_extra[shorted] = 0.0        # pairs that never hold (above)
            config = Configuration(A=np.block([[A, columns_of(dx)], [np.zeros((r, n)), block]]),
                                   B=np.vstack([config.B, np.zeros((r, k))]), C=np.hstack([config.C, C_extra]),
                                   D=config.D, E=np.concatenate([E, rates]), F=config.F, name=name)
            Sx = np.hstack([Sx, columns_of(rows)])
            E_sin = np.hstack([E_sin, np.zeros((E_sin.shape[0], r))])
        jump = self.jump(solution.K_w, s, n + len(extra))
        if jump is not None:
            config = replace(config, jump=jump)
        signals = (Sx.copy(), *(m.copy() for m in signals[1:]))
        return config, signals, (E_sin.copy(), F_sin.copy())

    def gate_waveforms(self) -> tuple[Waveform, ...]:
        return tuple(cast(Waveform, self.sources[c - self.n - self.k].waveform) for c in self.gate_columns())

    def gate_columns(self) -> list[int]:
        """The MNA input columns of the gate sources: a PULSE, PWL or SIN that reaches only switch controls (its value
        decides when switches close; in the power circuit a PULSE is a level of the configuration, a SIN an input)."""
        return [self.n + self.k + i for i, src in enumerate(self.sources)
                if isinstance(src.waveform, (Pulse, Pwl, Sin)) and not self.in_power_circuit(src)]

    def sinusoid_columns(self) -> tuple[list[int], _Array]:
        """(columns of the SIN sources among the MNA's input columns, their amplitudes VA)."""
        sines = [i for i, src in enumerate(self.sources) if isinstance(src.waveform, Sin) and src not in self.oscillators
                 and self.in_power_circuit(src)]
        return ([self.n + self.k + i for i in sines],
                np.array([cast(Sin, self.sources[i].waveform).va for i in sines], dtype=float))

    def joined(self, switch_state: dict[str, bool]) -> Callable[[str], str]:
        """The node a node is joined to by closed ideal switches (a representative of its class)."""
        parent: dict[str, str] = {}

        def root(node: str) -> str:
            while parent.get(node, node) != node:
                node = parent[node]
            return node

        for s in self.switches + self.shorts:
            if s.kind == "R" or (switch_state.get(s.name) and not self.switch_ron[s.name]):
                a, b = root(s.nodes[0]), root(s.nodes[1])
                if a != b:
                    parent[a] = b
        return root

    def shorted_diodes(self, switch_state: dict[str, bool], forms: Sequence[str]) -> list[int]:
        """The ideal diodes (no RS, current ports) whose two terminals closed ideal switches join."""
        root = self.joined(switch_state)
        return [i for i, (d, form) in enumerate(zip(self.diodes, forms))
                if form == CURRENT and not self.diode_rs[d.name] and root(d.nodes[0]) == root(d.nodes[1])]

    def check_unique_ports(self, config: Configuration, switch_state: dict[str, bool]) -> None:
        """Refuse two ideal diodes in parallel (the same two nodes, closed ideal switches joining nodes) or whose
        ports are the same; a diode reverse-biased by sources alone (y = F > 0 whatever x and u) never conducts
        (its u = 0 is unique) and passes."""
        if len(self.diodes) < 2:
            return
        assert config.F is not None                     # a Configuration fills in its F
        C, F = config.C, config.F
        if config.jump is not None:
            # the state is on the configuration's loops once it has jumped (x = P x + q): a diode a closed switch's
            # shorted capacitance ties to Vin (two phases' Coss, both switches closed) is blocked by Vin alone
            C, F = C @ config.jump.P, F + C @ config.jump.q
        C, F = self.on_loops(C, F)
        rows = np.hstack([C, config.D, F[:, None]])
        root = self.joined(switch_state)
        ends = [(root(d.nodes[0]), root(d.nodes[1])) for d in self.diodes]
        for i in range(len(self.diodes)):
            for j in range(i + 1, len(self.diodes)):
                a, b = rows[i], rows[j]
                scale = max(np.abs(a).max(), np.abs(b).max(), 1e-300)
                blocked = [np.abs(r[:-1]).max() <= 1e-12 * scale and r[-1] > 0 for r in (a, b)]
                if all(blocked):
                    continue
                d1, d2 = self.diodes[i], self.diodes[j]
                parallel = (ends[i] == ends[j] and ends[i][0] != ends[i][1] and not self.diode_rs[d1.name]
                            and not self.diode_rs[d2.name])
                same = (np.abs(a - b).max() <= 1e-12 * scale
                        and np.abs(config.D[i, j] - config.D[i, i]) <= 1e-12 * scale)
                if same and not parallel and config.same_columns(i, j):
                    # the same port twice over (:meth:`Configuration.twin_ports`: a two-switch forward's clamp
                    # diodes, one current, the winding's): the state is unique; blocked at zero current the node
                    # between them floats (its voltage the split the solver picks; SPICE's is set by leakages)
                    continue
                if parallel or same:
                    # joined through closed switches only in some configuration: name it (an interleaved boost's
                    # diodes meet at ground where both phases' switches are closed, which its gates reach)
                    own = (d1.nodes[0], d1.nodes[1]) == (d2.nodes[0], d2.nodes[1])
                    closed = sorted(name.upper() for name, on in switch_state.items() if on)
                    where = f" where {', '.join(closed)} {'is' if len(closed) == 1 else 'are'} closed" if (
                        closed and not own) else ""
                    raise self.error(d2, f"{d2.title} and {d1.title} are ideal diodes in parallel{where} (or in "
                                         "series with nothing between): the split of their current or voltage is not "
                                         "unique; put a resistance (RS in their .model) on one")

    def on_loops(self, C: _Array, F: _Array) -> tuple[_Array, _Array]:
        """(C, F) of the ports on the states the loops of capacitors allow (K x = b: :meth:`_Network.solve_loops`'s
        solution writes a node's voltage through the loop's capacitors, v(p) = (v(c1) + v(c2) + 2 Vdc)/3 for a
        split link, which is Vdc there): C on the free directions, F with the constraint's share. A diode across
        the link reads as reverse-biased by the source alone, as it is."""
        K_w = getattr(self, "loops", None)
        if K_w is None:
            return C, F
        size = C.shape[1]
        K = np.zeros((K_w.shape[0], size))
        K[:, :self.n] = K_w[:, :self.n]
        b = -K_w[:, self.n + self.k:] @ self.source_values({})
        pinv = np.linalg.pinv(K)
        free = np.eye(size) - pinv @ K                      # the projector onto K's null space
        return C @ free, F + C @ (pinv @ b)

    def source_values(self, levels: dict[str, int]) -> _Array:
        values: list[float | _Array] = []
        for s in self.sources:
            w = s.waveform
            if isinstance(w, Pulse) and s in self.edged:
                values.append(0.0)               # an edged PULSE's value is a state (:meth:`lcs`)
            elif isinstance(w, Pulse):
                values.append(w.v2 if levels.get(s.name, 0) else w.v1)
            elif isinstance(w, Pwl) and s in self.ramps:
                values.append(0.0)               # a ramp's value is a state (:meth:`lcs`)
            elif isinstance(w, Pwl):
                values.append(w.points[0][1])    # a gate's: its crossings are the schedule (:meth:`switch_events`)
            elif isinstance(w, Sin):
                values.append(w.vo)              # its sinusoid is an input of its own (:meth:`sinusoid_columns`)
            else:
                values.append(self.value(s))     # DC: a number, or a batch's P numbers
        if self.lead and values:
            return np.stack(np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in values)), axis=-1)
        return np.array(values, dtype=float)

    def signal_names(self) -> tuple[str, ...]:
        nodes = tuple(f"v({n})" for n in self.nodes)
        elements = tuple(f"i({e.name})" for e in self.nl.elements if e.kind not in "K")
        return nodes + elements

    def units(self) -> dict[str, str]:
        return {name: ("V" if name.startswith("v(") else "A") for name in self.signal_names()}

    def hold_islands(self, A: _Array, E: _Array) -> tuple[_Array, _Array]:
        """A and E with each island's charge q = sum(sign C v) held at its value where the run starts (q0, from the
        .ic or from rest): q' = -gamma (q - q0), which the circuit's own q' = 0 meets on its states; a start with
        another charge relaxes to q0 at gamma = LOOP_RATE / T instead of keeping an orbit of its own (a multiplier at
        1). The correction moves the island's potential as a whole: every loop's voltages stay tied."""
        A, E = A.copy(), E.copy()
        n_c = len(self.capacitors)
        capacitance = np.array([self.value(e) for e in self.capacitors])
        x0 = self.initial_state()
        gamma = LOOP_RATE / self.loop_time()
        for sign in self.islands:
            weight = sign * capacitance
            total = capacitance[sign != 0].sum()
            A[:n_c, :n_c] -= gamma * np.outer(sign, weight) / total
            E[:n_c] += gamma * sign * (weight @ x0[:n_c]) / total
        return A, E

    def hold_fluxes(self, A: _Array, E: _Array) -> tuple[_Array, _Array]:
        """A and E with each loop of inductors' flux phi = s^T M i held at its value where the run starts (phi0, from
        the IC= or from rest), as :meth:`hold_islands` holds a charge: phi' = -gamma (phi - phi0), which the circuit's
        own phi' = 0 meets on its states. Without it a current circulating in the loop never decays and every start
        has an orbit of its own: Newton had stopped at "1 - rho = 8.6e-14 amplifies" the rounding of two inductors in
        parallel."""
        A, E = A.copy(), E.copy()
        n_c = len(self.capacitors)
        M = np.asarray(self.mutual, dtype=float)
        i0 = self.initial_state()[n_c:]
        gamma = LOOP_RATE / self.loop_time()
        for sign in self.flux_loops:
            weight = M @ sign                               # phi = weight . i (M symmetric)
            total = float(sign @ weight)
            A[n_c:, n_c:] -= gamma * np.outer(sign, weight) / total
            E[n_c:] += gamma * sign * (weight @ i0) / total
        return A, E

    def invariants(self, state_names: tuple[str, ...]) -> tuple[Invariant, ...]:
        """What every configuration holds, as the summary reports it: each loop of capacitors' and cutset of
        inductors' constraint (sum of coefficient x state = value, its largest coefficient 1; from the sources), and
        each charge island's sum(sign C v) (from the .ic, or 0 from rest). A loop or cutset through a switch holds in
        its configurations only (a jump enters them) and is not listed."""
        out: list[Invariant] = []
        K_w = getattr(self, "loops", None)
        if K_w is not None:
            sources = self.source_values({})
            b = -K_w[:, self.n + self.k:] @ sources
            n_c = len(self.capacitors)
            for row, value in zip(K_w[:, :self.n], b):
                big = row[np.argmax(np.abs(row))]
                row = np.where(np.abs(row) > 1e-9 * abs(big), row / big, 0.0)      # the SVD's rounding is no term
                value = value / big
                if abs(value) < 1e-12 * max(np.abs(sources).max(initial=0.0), 1.0):
                    value = 0.0
                terms = [(coefficient, name) for coefficient, name in zip(row, state_names) if coefficient]
                kind = "loop" if np.abs(row[:n_c]).max(initial=0.0) > 0.0 else "cutset"
                out.append({"kind": kind, "constraint": _sum_text(terms), "value": float(value),
                            "unit": "V" if kind == "loop" else "A"})
        if self.islands:
            capacitance = np.array([self.value(e) for e in self.capacitors])
            x0 = self.initial_state()
            for sign in self.islands:
                terms = [(float(s_ * c_), name) for s_, c_, name in zip(sign, capacitance, state_names) if s_]
                weight, v = sign * capacitance, x0[:len(capacitance)]
                charge = float(weight @ v)
                if abs(charge) <= 1e-12 * float(np.abs(weight) @ np.abs(v)):      # rounding of a zero charge
                    charge = 0.0
                out.append({"kind": "charge", "constraint": _sum_text(terms), "value": charge, "unit": "C"})
        if self.flux_loops:
            n_c = len(self.capacitors)
            M = np.asarray(self.mutual, dtype=float)
            i0 = self.initial_state()[n_c:]
            for sign in self.flux_loops:
                weight = M @ sign
                terms = [(float(w), name) for w, name in zip(weight, state_names[n_c:]) if w]
                flux = float(weight @ i0)
                if abs(flux) <= 1e-12 * float(np.abs(weight) @ np.abs(i0)):        # rounding of a zero flux
                    flux = 0.0
                out.append({"kind": "flux", "constraint": _sum_text(terms), "value": flux, "unit": "Wb"})
        return tuple(out)

    def energy(self) -> tuple[_Array, _Array]:
        """(capacitances, inductance matrix) of the states (:attr:`Compiled.energy`)."""
        return (np.array([float(self.value(e)) for e in self.capacitors]), np.array(self.mutual, dtype=float))

    def moved(self, state_names: tuple[str, ...]) -> tuple[str, ...]:
        """A warning where the file's initial conditions (IC=, .ic) contradict a loop of capacitors or a cutset of
        inductors, which the run's start is moved onto (:meth:`consistent`); and where a comparator's sawtooth leaves
        its PULSE for more than RETRACE_SAID of its period (:meth:`state_law`)."""
        return tuple(dict.fromkeys(self.ramp_notes)) + self._moved_start(state_names)

    def _moved_start(self, state_names: tuple[str, ...]) -> tuple[str, ...]:
        if not self.nl.ic and all(e.ic is None for e in self.capacitors + self.inductors):
            return ()                                   # from rest: moved onto the constraints as SPICE's start is
        given = self.initial_state(self.nl)
        start = self.initial_state()
        if not given.size or np.abs(start - given).max() <= 1e-9 * max(np.abs(given).max(), np.abs(start).max(), 1e-300):
            return ()
        changed = np.flatnonzero(np.abs(start - given) > 1e-9 * max(np.abs(given).max(), np.abs(start).max()))
        held = "; ".join(f"{i['constraint']} = {i['value']:.6g} {i['unit']}" for i in self.invariants(state_names)
                         if i["kind"] != "charge")
        return (f"the initial conditions contradict what the circuit holds ({held}): the run starts from "
                + ", ".join(f"{state_names[i]} = {start[i]:.6g} (not {given[i]:.6g})" for i in changed)
                + ", the charges and fluxes redistributed as the circuit would at its start",)

    def loop_time(self) -> float:
        """The time over which a loop of capacitors is held to its constraint: the period, or the run."""
        period = self.period()
        assert self.nl.tran is not None                 # a netlist without .tran is refused (:meth:`__init__`)
        return period if math.isfinite(period) else self.nl.tran.tstop

    def consistent(self, x: _Array) -> _Array:
        """``x`` with its capacitors' voltages moved onto their loops' constraints as a closing loop moves charge
        (the smallest change in the capacitances' metric: x - C^-1 K^T (K C^-1 K^T)^-1 (K x - b)); x itself
        without a loop."""
        K_w = getattr(self, "loops", None)
        x = np.asarray(x, dtype=float)
        return x if K_w is None else cast(Jump, self.jump(K_w, self.source_values({}), x.size))(x)

    def jump(self, K_w: _Array | None, sources: _Array, size: int) -> Jump | None:
        """The state's jump entering a configuration whose closed switches make loops with capacitors (``K_w``: the
        loops' constraints from :meth:`_Network.solve_loops`, None without; :meth:`consistent`'s projection of a
        run's start onto the loops that hold always is the same): the capacitors' voltages projected
        onto K x = b in the capacitances' metric (charge conservation, :class:`~converters.problems.Jump`) on the
        ``size`` states (the ramps' and oscillators' among them, which do not jump)."""
        if K_w is None:
            return None
        n_c, n = len(self.capacitors), self.n
        K = K_w[:, :n]
        b = -K_w[:, self.n + self.k:] @ sources
        # the energy's metric: the capacitances, and the inductances with their mutual ones (flux conserved)
        metric = np.zeros((n, n))
        metric[:n_c, :n_c] = np.diag([self.value(e) for e in self.capacitors])
        # (the inductances only where a cutset holds their currents: a loop of capacitors leaves them, and a
        # coupling of 1 would make them singular)
        metric[n_c:, n_c:] = self.mutual if np.abs(K[:, n_c:]).max(initial=0.0) > 0.0 else np.eye(n - n_c)
        inverse = np.linalg.solve(metric, K.T)                                # W^-1 K^T
        gain = inverse @ np.linalg.inv(K @ inverse)                           # W^-1 K^T (K W^-1 K^T)^-1
        P, q, W = np.eye(size), np.zeros(size), np.zeros((size, size))
        P[:n, :n] -= gain @ K
        q[:n] = gain @ b
        W[:n, :n] = metric
        # rounding of the SVD's bases (1e-17 of a coefficient) is not a coupling: kept, a state that should not
        # move would drift by it at every step
        P[np.abs(P) < 1e-13] = 0.0
        return Jump(P=P, q=q, W=W)

    def initial_state(self, netlist: Netlist | None = None) -> _Array:
        """The states at t = 0: each element's IC=, or .ic v(node) across a capacitor, else 0 (UIC); of
        ``netlist``, this circuit with other values (:meth:`rerun`), where given."""
        nl = netlist or self.nl
        own = {e.name: e for e in nl.elements} if netlist is not None else None
        x = []
        for c in self.capacitors:
            c = own[c.name] if own else c
            if c.ic is not None:
                x.append(c.ic)
            else:
                a, b = c.nodes
                va = nl.ic.get(a, 0.0) if a != "0" else 0.0
                vb = nl.ic.get(b, 0.0) if b != "0" else 0.0
                x.append(va - vb)
        x += [(own[l.name] if own else l).ic or 0.0 for l in self.inductors]
        # a ramp holds its first value until its first time
        x += [cast(Pwl, r.waveform).points[0][1] for r in self.ramps]
        # an edged PULSE where its periodic orbit is at t = 0 (the level its schedule starts with: :meth:`level_events`)
        x += [float(waveform_at(w, np.array([w.per]))[0]) for w in (cast(Pulse, e.waveform) for e in self.edged)]
        for o in self.oscillators:                                  # VO + VA sin(PHASE) until TD (as ngspice's SIN)
            x += [math.sin(math.radians(cast(Sin, o.waveform).phase)),
                  math.cos(math.radians(cast(Sin, o.waveform).phase))]
        return self.consistent(np.array(x, dtype=float)) if netlist is None else np.array(x, dtype=float)


def _slope(w: Pwl, t: float) -> float:
    """The slope of a PWL on its segment from time t on (0 before its first point and after its last)."""
    for (t0, v0), (t1, v1) in zip(w.points, w.points[1:]):
        if t0 <= t < t1:
            return (v1 - v0) / (t1 - t0)
    return 0.0


def _once(w: Waveform | None) -> bool:
    """A waveform that does not repeat: a PWL without r=, a PULSE without PER (its level changes a few times, then
    holds)."""
    return (isinstance(w, Pwl) and w.repeat is None) or (isinstance(w, Pulse) and not math.isfinite(w.per)
                                                         and w.td + w.tr + w.pw + w.tf < math.inf)


def _reaches_ground(elements: Sequence[Element], node: str) -> bool:
    """Whether some chain of elements (their first two nodes: a switch's or a controlled source's output, never its
    control) joins ``node`` to ground, whatever the switches' states."""
    parent: dict[str, str] = {}

    def root(n: str) -> str:
        return _root(parent, n)
    for e in elements:
        if len(e.nodes) >= 2:
            parent[root(e.nodes[0])] = root(e.nodes[1])
    return root(node) == root("0")


def _crossings(corners: _Array, values: _Array, on: float, off: float, state: bool,
               exact: Callable[[float], float] | None = None) -> list[tuple[float, bool]]:
    """[(t, closed)] where a control (``values`` at ``corners``) starting in ``state`` rises above ``on`` (closing)
    or falls below ``off`` (opening): piecewise linear, located on its segments; with ``exact`` (the control as a
    function of t: a sine in it), located by Brent's method on the segment whose end has crossed."""
    changes: list[tuple[float, bool]] = []
    for (t0, v0), (t1, v1) in zip(zip(corners[:-1], values[:-1]), zip(corners[1:], values[1:])):
        target = off if state else on
        if (v1 < off) if state else (v1 > on):
            if exact is not None and (v0 - target) * (v1 - target) < 0:
                from scipy.optimize import brentq
                t = brentq(lambda s: exact(s) - target, t0, t1, xtol=1e-15 * max(t1, 1e-300), rtol=1e-15)
            else:
                t = t0 + (target - v0) / (v1 - v0) * (t1 - t0) if v1 != v0 else t1
            state = not state
            changes.append((float(t), state))
    return changes


#: A power PULSE run as steps whose edges take more than this fraction of its period is refused, more than EDGE_SAID of
#: its shorter level said (:meth:`_Compiler.check_steps`): one edge without a width, the other with one (its ramp
#: would have to jump).
STEP_EDGE_FRACTION = 1e-3
EDGE_SAID = 1e-2
#: A power PULSE whose edges both have a width and take more than this fraction of its shorter level is edged: its value
#: is a state of the LCS that follows its ramps (:meth:`_Compiler.lcs`). Shorter edges step between its levels at their
#: middle, which moves what they shape by about their share of the level (a voltage doubler's 10 ns edges on a 2 % pulse
#: of 10 us, 5 % of its 200 ns, read as steps, put its diode's peak current 3.3 % low and its source's rms 0.84 % high,
#: every estimate ~0; a +-10 V triangle through a half-wave rectifier read as a square wave gave twice its mean): below
#: 1e-2 that is below the 1 % pcsuite promises of a measurement, each stepped edge's rms share is in the estimate
#: (:func:`~converters.analysis.accuracy.edge_terms`) and its width in each mode fraction's (a three-stage ladder's 20
#: ns edges on its 10 us levels, against exact flows of the ramps: every value within three times its estimate). The
#: shipped bridge rectifier's 20 ps, resonant converter's T/10^4 and ladder's T/1000 edges step (the resonant
#: converter's built-in model takes the file's two configurations).
EDGE_RAMPED = 1e-2
#: A power PULSE's edge longer than this many of the circuit's fastest time constants is edged too
#: (:meth:`_Compiler.slow_edges`).
EDGE_TIME_CONSTANTS = 1.0
#: An edged PULSE's levels must hold for this fraction of its period: they pin its ramp on the periodic orbit, its
#: offset decaying by e^(-LOOP_RATE x this) a period (a triangle without levels repeats from any offset: use SIN).
EDGE_FLAT = 1e-2
#: An edged PULSE's phases beside its levels 0 (V1) and 1 (V2) (:meth:`_Compiler.level_events`).
RISING, FALLING = 2, 3


def _edged(w: Pulse) -> bool:
    """Whether a periodic power PULSE's edges are ramps of the LCS (:data:`EDGE_RAMPED`)."""
    return (math.isfinite(w.per) and min(w.tr, w.tf) > 0.0
            and max(w.tr, w.tf) > EDGE_RAMPED * max(min(w.pw, w.per - w.tr - w.pw - w.tf), 0.0))


def _edge_middles(w: Pulse) -> tuple[tuple[float, float], ...]:
    """A periodic PULSE's edges as (middle in [0, PER), width): where the power circuit steps between its levels."""
    return tuple((math.fmod(w.td + start + 0.5 * width, w.per) % w.per, width)
                 for start, width in ((0.0, w.tr), (w.tr + w.pw, w.tf)))


def waveform_at(w: Waveform, t: _Array) -> _Array:
    """A source's waveform at times t (DC, PULSE, SIN without delay or damping, or a PWL: repeated with r=0, else
    holding its last value)."""
    t = np.asarray(t, dtype=float)
    if isinstance(w, Pwl):
        times, values = np.array(w.points).T
        return cast(_Array, np.interp(np.mod(t, w.period), times, values))
    if isinstance(w, Sin):                      # a gate's sine (no delay or damping: those are refused in a gate)
        return w.vo + w.va * np.sin(2 * math.pi * w.freq * t + math.radians(w.phase))
    if not isinstance(w, Pulse):
        return np.full_like(t, float(w))
    per = w.per if math.isfinite(w.per) else math.inf
    local = t - w.td
    if math.isfinite(per):
        local = np.where(local >= 0, np.mod(local, per), local)
    out = np.full_like(t, w.v1)
    rise = (local >= 0) & (local < w.tr)
    out[rise] = w.v1 + (w.v2 - w.v1) * local[rise] / w.tr if w.tr > 0 else w.v2
    high = (local >= w.tr) & (local < w.tr + w.pw)
    out[high] = w.v2
    fall = (local >= w.tr + w.pw) & (local < w.tr + w.pw + w.tf)
    out[fall] = w.v2 + (w.v1 - w.v2) * (local[fall] - w.tr - w.pw) / w.tf if w.tf > 0 else w.v1
    return out


#: The longest retrace (a comparator's PULSE's width, fall and rest at V1: PER - TR) taken as a sawtooth reset at the
#: middle of its fall, as a fraction of the period: a switching as it falls moves by up to half of it, said with every
#: run (:data:`RETRACE_SAID`). An engineer's 200 kHz type II loop on PULSE(0 1 0 {T-20n} 10n 10n {T}) (4e-3 of T)
#: regulates to Vref - vc/A as ngspice does (its loop moves vc, not vout); a ramp resting for half its period is
#: refused (its sawtooth would not be the PULSE: a loop gain 4.9 dB high).
RETRACE_TAKEN = 1e-2

#: A comparator's ramp whose sawtooth leaves its PULSE for more than this fraction of its period (past V2 for its
#: width and half its fall, below V1 for its rest and half its fall: :meth:`_Compiler.state_law`) is said with every
#: run (against the literal PULSE, a fall of 1e-6 of the period moves the voltage-mode buck's period doubling by
#: 8e-7 V from pcsuite's; the shipped ramps' 1.5e-8 moves it by 8e-9 V).
RETRACE_SAID = 2e-8

#: A SIN in a switch's control is crossed on pieces of at most 1/SINE_PIECES of its period between the other
#: waveforms' corners (a sine-triangle modulator: the carrier's corners are far denser).
SINE_PIECES = 64

#: Resistances further apart than this ratio make the network's matrix singular in double precision (1 ohm beside
#: 1e13 ohm was refused as "no path to ground", 1 ohm beside 1e12 ohm runs): a refusal then says so.
RESISTANCE_SPREAD = 1e12


def _spread_hint(c: _Compiler) -> str:
    """'' or why a singular network may be the values' and not the topology's: the resistances span more than
    RESISTANCE_SPREAD."""
    resistors = [(float(e.value), e.name.upper()) for e in c.by_kind["R"] if e.value and e.value > 0.0]
    if len(resistors) < 2:
        return ""
    (low, small), (high, large) = min(resistors), max(resistors)
    if high <= RESISTANCE_SPREAD * low:
        return ""
    return (f"; or its values: the resistances span {high / low:.1e} ({small} {low:.3g} ohm beside {large} "
            f"{high:.3g} ohm), beyond the {RESISTANCE_SPREAD:.0e} double precision resolves in one network: bring the "
            "extremes closer (an open as 1e9 ohm, a short as 1e-3 ohm)")


#: A loop of capacitors holds its constraint at this rate over the period (:meth:`_Network.solve_loops`): a start off
#: it decays by e^-10 a period, and the rate is far below a step's (h = T/1000: 0.01).
LOOP_RATE = 10.0

#: The elements a loop of fixed voltages may hold, by branch kind, as a refusal names them.
LOOP_KINDS = (("V", "voltage sources"), ("C", "capacitors"), ("S", "closed switches"), ("R", "0 ohm resistors"),
              ("D", "conducting diodes"), ("E", "voltage-controlled voltage sources"),
              ("H", "current-controlled voltage sources"))

class _Network:
    """The resistive network of one configuration: MNA unknowns z = (node voltages, branch currents), each
    equation's right-hand side a linear function of (x, u, sources)."""

    #: The constraints (K_w w = 0, w = (x, u, sources)) of loops through closed switches (:meth:`solve_loops`).
    K_w: _Array | None = None
    #: The network solved: each unknown (row) as a linear function of (x, u, sources) (:meth:`solve`).
    Z: _Array

    def __init__(self, compiler: _Compiler, switch_state: dict[str, bool], levels: dict[str, int],
                 forms: Sequence[str]):
        self.c, self.levels, self.forms = compiler, levels, forms
        nodes = dict(compiler.node_index)
        branches: list[tuple[str, Element, str, str]] = []                 # (kind, element, a, b)
        c = compiler
        for e in c.by_kind["V"]:
            branches.append(("V", e, e.nodes[0], e.nodes[1]))
        for e in c.capacitors:
            branches.append(("C", e, e.nodes[0], e.nodes[1]))
        for e in c.switches:
            if switch_state.get(e.name) and not c.switch_ron[e.name]:
                branches.append(("S", e, e.nodes[0], e.nodes[1]))
        for e in c.shorts:
            branches.append(("R", e, e.nodes[0], e.nodes[1]))
        for e, form in zip(c.diodes, forms):
            anode = f"{e.name}#a" if c.diode_rs[e.name] else e.nodes[0]
            if form == VOLTAGE:
                branches.append(("D", e, anode, e.nodes[1]))
        for e in c.by_kind["E"] + c.by_kind["H"]:
            branches.append((e.kind, e, e.nodes[0], e.nodes[1]))
        self.nodes, self.branches = nodes, branches
        self.switch_state = switch_state
        size = len(nodes) + len(branches)
        self.size = size
        cols = c.n + c.k + len(c.sources)
        #: () for one circuit, (P,) for a batch of P circuits alike but for their values (:meth:`_Compiler.rerun`):
        #: G then holds each point's matrix; R (the inputs' columns) is the same for all
        self.lead = c.lead
        G = np.zeros(self.lead + (size, size))
        R = np.zeros((size, cols))
        idx: Callable[[str], int | None]
        idx = lambda node: None if node == "0" else nodes[node]          # noqa: E731
        self.idx = idx

        def conductance(a: str, b: str, g: float | _Array) -> None:
            for p, q, sign in ((a, a, 1), (b, b, 1), (a, b, -1), (b, a, -1)):
                if idx(p) is not None and idx(q) is not None:
                    G[..., idx(p), idx(q)] += sign * g

        def inject(a: str, b: str, column: int, scale: float = 1.0) -> None:
            """A current ``scale`` x column flowing from a through the element to b."""
            if idx(a) is not None:
                R[idx(a), column] -= scale
            if idx(b) is not None:
                R[idx(b), column] += scale

        for e in c.by_kind["R"]:
            if e.value:
                conductance(e.nodes[0], e.nodes[1], 1.0 / c.value(e))
        for e in c.switches:
            if switch_state.get(e.name) and c.switch_ron[e.name]:
                conductance(e.nodes[0], e.nodes[1], 1.0 / c.value(e, "RON"))
        for d in c.diodes:
            if c.diode_rs[d.name]:
                conductance(d.nodes[0], f"{d.name}#a", 1.0 / c.value(d, "RS"))
        for i, e in enumerate(c.inductors):
            inject(e.nodes[0], e.nodes[1], len(c.capacitors) + i)
        for j, (e, form) in enumerate(zip(c.diodes, forms)):
            if form == CURRENT:
                anode = f"{e.name}#a" if c.diode_rs[e.name] else e.nodes[0]
                inject(anode, e.nodes[1], c.n + j)
        for i, e in enumerate(c.sources):
            if e.kind == "I":
                inject(e.nodes[0], e.nodes[1], c.n + c.k + i)
        for e in c.by_kind["G"]:
            a, b, cp, cn = e.nodes
            for node, sign in ((a, 1.0), (b, -1.0)):
                if idx(node) is None:
                    continue
                for ctrl, s2 in ((cp, 1.0), (cn, -1.0)):
                    if idx(ctrl) is not None:
                        G[..., idx(node), idx(ctrl)] += sign * s2 * c.value(e)
        branch_of = {}
        for j, (kind, e, a, b) in enumerate(branches):
            row = len(nodes) + j
            branch_of[e.name] = row
            if idx(a) is not None:
                G[..., idx(a), row] += 1.0
                G[..., row, idx(a)] += 1.0
            if idx(b) is not None:
                G[..., idx(b), row] -= 1.0
                G[..., row, idx(b)] -= 1.0
            if kind == "V":
                R[row, c.n + c.k + [s.name for s in c.sources].index(e.name)] = 1.0
            elif kind == "C":
                R[row, c.capacitors.index(e)] = 1.0
            elif kind == "D":
                R[row, c.n + c.diodes.index(e)] = -1.0            # v_D = -u
            elif kind == "E":
                cp, cn = e.nodes[2], e.nodes[3]
                for ctrl, s2 in ((cp, 1.0), (cn, -1.0)):
                    if idx(ctrl) is not None:
                        G[..., row, idx(ctrl)] -= s2 * c.value(e)
        for e in c.by_kind["H"]:
            G[..., branch_of[e.name], branch_of[e.control[0]]] -= c.value(e)
        for e in c.by_kind["F"]:
            a, b = e.nodes
            col = branch_of[e.control[0]]
            if idx(a) is not None:
                G[..., idx(a), col] += c.value(e)
            if idx(b) is not None:
                G[..., idx(b), col] -= c.value(e)
        self.G, self.R, self.branch_of = G, R, branch_of

    def nullity(self) -> int | npt.NDArray[np.intp]:
        """The dimension of G's null space (per point of a batch)."""
        if self.size == 0:
            return np.zeros(self.lead, dtype=int) if self.lead else 0
        scale = np.maximum(np.abs(self.G).max(axis=(-2, -1)), 1.0)
        return self.size - cast(int | npt.NDArray[np.intp],             # matrix_rank's stub gives Any
                                interruptible(np.linalg.matrix_rank, self.G, tol=1e-12 * scale))

    def solve(self, checked: bool = False) -> _Network:
        """The network solved (``checked``: its nullity is known to be 0). Loops of capacitors and DC voltage
        sources (capacitors in series across another or across a source: a split DC link) are solved by
        :meth:`solve_loops`; any other dependent loop or cutset is refused naming its elements."""
        if not checked and self.nullity():
            if self.lead or not self.solve_loops():
                raise self.singular()
            return self
        self.Z = interruptible(np.linalg.solve, self.G, np.broadcast_to(self.R, self.lead + self.R.shape))
        return self

    def solve_loops(self) -> bool:
        """Solve a network whose only dependence is loops of capacitors, DC voltage sources, 0 ohm resistors and
        closed ideal switches, and cutsets of inductors and DC current sources (inductors in series, an inductor in
        series with a current source; False where it has another). A loop ties its capacitors' voltages, a cutset
        its inductors' currents (K x = b, K and b from the left null space of the MNA matrix), and what keeps them
        tied is the current circulating in the loop or the potential of the cutset's nodes: z = z0 + N j, z0 the
        least-squares solution and N the loop currents and node potentials (its null space), j such that
        d/dt (K x - b) = -gamma (K x - b). On the circuit's states (K x = b, where the run starts: the charges and
        fluxes redistributed as SPICE's operating point would) the term is zero and the dynamics are the
        circuit's; off them it decays at gamma = LOOP_RATE / T, so a start off the constraint is not a multiplier
        at 1 of the period map (Baumgarte's stabilisation of a constraint)."""
        c = self.c
        u, sv, vt = np.linalg.svd(self.G)
        scale = max(sv[0], 1.0)
        m = int(np.sum(sv <= 1e-12 * scale))
        N, L = vt[-m:].T, u[:, -m:]                     # loop currents and node potentials (right), the KVL/KCL (left)
        rows = len(self.nodes)
        # the null space is the loops' (branch rows alone) beside the cutsets' (node rows alone): split it so
        loops = N @ _null(N[:rows])
        cuts = N @ _null(N[rows:])
        # zero to rounding by construction, and so exactly: a loop current's rounding on the node rows, times the
        # large J of a big capacitor's loop (C = 1 F), read 1.4e-12 of the states in a PULSE gate's potential
        loops[:rows], cuts[rows:] = 0.0, 0.0
        if loops.shape[1] + cuts.shape[1] != m:
            return False
        allowed = {j for j, (kind, e, _, _) in enumerate(self.branches)
                   if kind in "CRS" or (kind == "V" and isinstance(e.waveform, float))}
        support = np.flatnonzero(np.abs(loops).max(axis=1, initial=0.0) > 1e-9)
        if any((r - rows) not in allowed for r in support):      # (a loop has no node rows: zeroed above)
            self.varying = [e for j, (kind, e, _, _) in enumerate(self.branches) if rows + j in support and (
                kind in "EH" or (kind == "V" and not isinstance(e.waveform, float)))]
            return False
        caps = [self.branch_of[e.name] for e in c.capacitors]
        if loops.shape[1] and (not caps or np.linalg.matrix_rank(loops[caps], tol=1e-9) < loops.shape[1]):
            return False                                # a loop of sources and shorts alone: no capacitor to give
        K_w = L.T @ self.R                              # (m, cols): K_w w = 0 on consistent inputs
        if np.linalg.matrix_rank(K_w, tol=1e-9 * max(np.abs(self.R).max(), 1e-300)) < m:
            return False                                # a node that floats: nothing ties it (no constraint)
        if np.linalg.matrix_rank(K_w[:, :c.n], tol=1e-9 * np.abs(K_w).max()) < m:
            return False                                # sources alone (a current source into a node, two sources
                                                        # in parallel): no state to give
        if np.abs(K_w[:, c.n:c.n + c.k]).max(initial=0.0) > 1e-9 * np.abs(K_w).max():
            return False                                # it holds a diode's quantity
        sources = K_w[:, c.n + c.k:]
        varying = [j for j, e in enumerate(c.sources) if not isinstance(e.waveform, float)]
        if varying and np.abs(sources[:, varying]).max() > 1e-9 * np.abs(K_w).max():
            # a loop or cutset through a source that varies: its states would follow the source's steps (an
            # impulsive current or voltage), which a DC source's constraint does not ask; named in the refusal
            self.varying = [c.sources[j] for j in varying
                            if np.abs(sources[:, j]).max() > 1e-9 * np.abs(K_w).max()]
            return False
        island = {node for node, i in self.nodes.items() if np.abs(cuts[i]).max(initial=0.0) > 1e-9}
        bordered = [e for e in c.switches
                    if not self.switch_state.get(e.name) and len({e.nodes[0], e.nodes[1]} & island) == 1]
        if cuts.shape[1] and self.interrupted(K_w):
            return False
        N = np.hstack([loops, cuts])
        M = K_w[:, :c.n] @ self.rates(N)
        if np.linalg.matrix_rank(M, tol=1e-9 * max(np.abs(M).max(), 1e-300)) < m:
            return False
        # the least-squares solution from the SVD above, its m null directions dropped: every equation off the loops'
        # and cutsets' own holds to rounding (numpy 2.4.6's lstsq, LAPACK gelsd, spread a split link's KVL residual
        # of 0.33 over every row: a closed ideal switch's node read 7e-4 of the link's capacitors' voltages)
        kept = sv.size - m
        Z0 = vt[:kept].T @ ((u[:, :kept].T @ self.R) / sv[:kept, None])
        gamma = LOOP_RATE / c.loop_time()
        J = np.linalg.solve(M, -gamma * K_w - K_w[:, :c.n] @ self.rates(Z0))
        Z = Z0 + N @ J
        # the least-squares solution and the SVD spread rounding (1e-17..1e-16 of a row) over coefficients a solve
        # leaves exactly 0: an ideal diode's D of 3e-16 made its held flow a 1e19 1/s mode. Below 1e-12 of its row's
        # largest, a coefficient is that noise.
        Z[np.abs(Z) < 1e-12 * np.abs(Z).max(axis=1, keepdims=True)] = 0.0
        self.Z = Z
        # a loop through a closed switch holds in this configuration only, and so does a cutset that an open switch
        # borders: entering it, the charges or fluxes jump onto it (:meth:`_Compiler.jump`); the others hold in every
        # configuration, where a run starts too (consistent)
        switch_rows = [rows + j for j, (kind, _, _, _) in enumerate(self.branches) if kind == "S"]
        through: list[_Array] | _Array
        through = [L[switch_rows]] if switch_rows else []
        for e in bordered:                              # a cutset bordered by an open switch: its KCL rows
            through.append(L[[self.nodes[n] for n in (e.nodes[0], e.nodes[1]) if n in island]])
        through = np.vstack(through) if through else np.zeros((0, m))
        if through.size and np.abs(through).max() > 1e-9:
            _, s_t, v_t = np.linalg.svd(through)
            static = v_t[int(np.sum(s_t > 1e-9)):].T              # combinations free of the switches
            self.K_w = K_w
            c.switch_loops = True
        else:
            static = np.eye(m)
        if static.shape[1]:
            c.loops = static.T @ K_w
        return True

    def rates(self, Z: _Array) -> _Array:
        """The states' derivatives (capacitors' dv/dt, inductors' di/dt) per column of network unknowns ``Z``."""
        c = self.c
        out = [Z[self.branch_of[e.name]] / c.value(e) for e in c.capacitors]
        if c.inductors:
            potential: Callable[[str], _Array]
            potential = lambda node: np.zeros(Z.shape[1]) if node == "0" else Z[self.nodes[node]]   # noqa: E731
            volts = np.stack([potential(e.nodes[0]) - potential(e.nodes[1]) for e in c.inductors])
            out += list(np.linalg.solve(c.mutual, volts))
        return np.stack(out)

    def interrupted(self, K_w: _Array) -> bool:
        """A cutset that fixes inductors' currents to 0 with no source in it, where one of them is coupled to no
        winding left free: its energy would have nowhere to go (an inductor whose only path a switch opens, one
        dangling from a node: SPICE's spike, not a jump to zero), refused. A coupled winding whose path opens (a
        forward converter's primary at turn-off) hands its flux to the windings left free, the leakage's energy
        lost (the jump's projection in the inductances' metric keeps every other winding's flux linkage); one left
        open (a sense winding) carries nothing, its voltage the others' mutual share."""
        c = self.c
        n_c = len(c.capacitors)
        K = K_w[:, n_c:c.n]
        if np.abs(K_w[:, c.n + c.k:]).max(initial=0.0) > 1e-9 * np.abs(K_w).max():
            return False
        rank = np.linalg.matrix_rank(K, tol=1e-9) if K.size else 0
        if not rank:
            return False
        fixed = []
        for i in range(K.shape[1]):
            unit = np.zeros(K.shape[1])
            unit[i] = 1.0
            if np.linalg.matrix_rank(np.vstack([K, unit]), tol=1e-9) == rank:
                fixed.append(i)
        free = [j for j in range(K.shape[1]) if j not in fixed]
        return any(not (np.abs(c.mutual[i, free]) > 0.0).any() for i in fixed)

    def singular(self) -> NetlistError:
        c = self.c
        _, s, vt = interruptible(np.linalg.svd, self.G)
        null = vt[-1]
        null = null / np.abs(null).max()
        where = ", ".join(f"{k}={'closed' if v else 'open'}" for k, v in self.switch_state.items())
        where = f" (with {where})" if where else ""
        spread = _spread_hint(c)
        members = [(kind, e) for j, (kind, e, a, b) in enumerate(self.branches) if abs(null[len(self.nodes) + j]) > 1e-6]
        loop = [e.name.upper() for _, e in members]
        nodes = [n for n, i in self.nodes.items() if abs(null[i]) > 1e-6 and "#" not in n]
        if loop:
            # the kinds the loop holds, not every kind a loop may hold (a 1 pF capacitor with a source was said to
            # loop through "0 ohm resistors" where there was none)
            kinds = [name for letter, name in LOOP_KINDS if any(kind == letter for kind, _ in members)]
            held = ", ".join(kinds[:-1]) + (" and " if len(kinds) > 1 else "") + kinds[-1]
            varying = [e for e in getattr(self, "varying", ()) if e.name.upper() in loop]
            if varying:
                names = ", ".join(f"{e.name.upper()} (" + ("controlled" if e.kind in "EH" else
                                                            type(e.waveform).__name__.upper()) + ")" for e in varying)
                return NetlistError(f"{c.path}: {', '.join(loop)} form a loop of {held}{where} closed by {names}, "
                                    "a source whose value varies: the loop's capacitor voltages are then set by it, "
                                    "not states of their own (pcsuite reduces such a loop where its sources are "
                                    "DC); put a resistance in the loop (a capacitor's ESR, the source's own)"
                                    f"{spread}")
            return NetlistError(f"{c.path}: {', '.join(loop)} form a loop of {held}{where}: their voltages are not "
                                f"independent{spread}")
        around = [e.name.upper() for e in c.nl.elements if set(e.nodes) & set(nodes)]
        if nodes and not _reaches_ground(c.nl.elements, nodes[0]):
            # no element of any kind, in any switch state, joins them to the rest: the switches and inductors the
            # message below names were not the cause (a resistor between two nodes of its own)
            return NetlistError(f"{c.path}: node{'s' if len(nodes) > 1 else ''} {', '.join(nodes)} ha"
                                f"{'ve' if len(nodes) > 1 else 's'} no path to ground through any element "
                                f"({', '.join(around)} connect only among them): a floating node; tie it to the circuit "
                                "(SPICE needs a path to ground too)")
        # a resistor at the nodes is a path: where it is there, its conductance is below what G's rank resolves
        # beside the network's largest (a 1 TOhm resistor to ground had been named among the open elements)
        weak = [(e.name.upper(), float(e.value)) for e in c.by_kind["R"] if e.value and set(e.nodes[:2]) & set(nodes)]
        opened = [name for name in around if name not in {name for name, _ in weak}]
        if weak:
            scale = max(float(np.abs(self.G).max()), 1.0)           # as nullity() takes it
            said = ", ".join(f"{name} ({value:.3g} ohm: {1.0 / value:.3g} S)" for name, value in weak)
            return NetlistError(f"{c.path}: node{'s' if len(nodes) > 1 else ''} {', '.join(nodes)} reach"
                                f"{'' if len(nodes) > 1 else 'es'} ground{where} only through {said}"
                                + (f" beside {', '.join(opened)}" if opened else "")
                                + f": a conductance at or below 1e-12 of the network's scale ({scale:.3g} S), where "
                                "pcsuite takes its matrix as singular; lower the resistance (an open as 1e9 ohm)"
                                f"{spread}")
        return NetlistError(f"{c.path}: node{'s' if len(nodes) > 1 else ''} {', '.join(nodes)} ha"
                            f"{'ve' if len(nodes) > 1 else 's'} no path to ground{where} but through open switches, "
                            f"inductors or current sources ({', '.join(around)}): a current interrupted with no path, "
                            f"or a node floating while a switch is open{spread}")

    def unit(self, column: int | None = None) -> _Array:
        """A row of the MNA's input columns (per point of a batch): 0, or 1 in ``column``."""
        row = np.zeros(self.lead + (self.R.shape[1],))
        if column is not None:
            row[..., column] = 1.0
        return row

    def voltage(self, node: str) -> _Array:
        i = self.idx(node)
        return self.unit() if i is None else self.Z[..., i, :]

    def branch(self, element: Element) -> _Array:
        return self.Z[..., self.branch_of[element.name], :]

    def derivatives(self) -> _Array:
        c = self.c
        rows = [self.branch(e) / _column(c.value(e)) for e in c.capacitors]
        if c.inductors:
            volts = np.stack([self.voltage(e.nodes[0]) - self.voltage(e.nodes[1]) for e in c.inductors], axis=-2)
            currents = cast(_Array, np.linalg.solve(c.mutual, volts))        # float64 (the stub says floating)
            rows += [currents[..., i, :] for i in range(len(c.inductors))]
        return np.stack(rows, axis=-2)

    def ports(self) -> _Array:
        c = self.c
        if not c.diodes:                      # no diode: a pair that never holds (y = u + 1)
            return self.unit()[..., None, :]
        rows = []
        for j, (e, form) in enumerate(zip(c.diodes, self.forms)):
            anode = f"{e.name}#a" if c.diode_rs[e.name] else e.nodes[0]
            if form == CURRENT:
                rows.append(self.voltage(e.nodes[1]) - self.voltage(anode))         # y = -v_D
            else:
                rows.append(self.branch(e))                                      # y = i_D
        out = np.stack(rows, axis=-2)
        # two node voltages' difference cancels their large coefficients and leaves their rounding: an ideal diode's
        # D of 2e-16 beside a flyback's sense winding (a cutset) made its held flow a 4.9e21 1/s mode and the default
        # step backward Euler. Below 1e-12 of its row's largest, a coefficient is that noise (as in Z's).
        out[np.abs(out) < 1e-12 * np.abs(out).max(axis=-1, keepdims=True)] = 0.0
        return out

    def current(self, e: Element) -> _Array:
        c = self.c
        if e.name in self.branch_of:
            return self.branch(e)
        if e.kind == "R":
            return (self.voltage(e.nodes[0]) - self.voltage(e.nodes[1])) / _column(c.value(e))
        if e.kind == "L":
            return self.unit(len(c.capacitors) + c.inductors.index(e))
        if e.kind == "D":
            return self.unit(c.n + c.diodes.index(e))
        if e.kind == "I":
            return self.unit(c.n + c.k + c.sources.index(e))
        if e.kind in "SW":
            if self.switch_state.get(e.name) and c.switch_ron[e.name]:
                return (self.voltage(e.nodes[0]) - self.voltage(e.nodes[1])) / _column(c.value(e, "RON"))
            return self.unit()
        if e.kind == "G":
            return _column(c.value(e)) * (self.voltage(e.nodes[2]) - self.voltage(e.nodes[3]))
        if e.kind == "F":
            return _column(c.value(e)) * self.Z[..., self.branch_of[e.control[0]], :]
        return self.unit()

    def signal_rows(self, names: tuple[str, ...]) -> _Array:
        rows = []
        elements = {f"i({e.name})": e for e in self.c.nl.elements}
        for name in names:
            if name.startswith("v("):
                rows.append(self.voltage(name[2:-1]))
            else:
                rows.append(self.current(elements[name]))
        return np.stack(rows, axis=-2)


def _times(M: _Array, v: _Array) -> _Array:
    """M v per point of a batch (``v`` one vector, or one per point); one circuit's M @ v."""
    return M @ v if v.ndim == 1 else np.matmul(M, v[..., None])[..., 0]


def _sum_text(terms: Sequence[tuple[float, str]]) -> str:
    """'v(c1) + v(c2)', '1e-06 v(c1) - 3e-06 v(c2)': a linear combination of states as text."""
    out = ""
    for coefficient, name in terms:
        sign = "-" if coefficient < 0 else "+"
        size = abs(coefficient)
        term = name if abs(size - 1.0) < 1e-12 else f"{size:.6g} {name}"
        out = (f"-{term}" if sign == "-" else term) if not out else f"{out} {sign} {term}"
    return out


def _null(A: _Array) -> _Array:
    """An orthonormal basis of the null space (columns) of A, rows of an orthonormal basis (singular values below
    1e-9 are its rounding)."""
    if A.shape[0] == 0:
        return np.eye(A.shape[1])
    _, sv, vt = np.linalg.svd(A)
    return vt[int(np.sum(sv > 1e-9)):].T


def _column(value: float | _Array) -> float | _Array:
    """A value that divides or scales rows: a number, or a batch's values as a column (one per point)."""
    return value[..., None] if isinstance(value, np.ndarray) else value


__all__ = ["compile_netlist", "compile_points", "Compiled", "CURRENT", "VOLTAGE"]
