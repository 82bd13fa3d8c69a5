"""A circuit from its netlist as a model like the built-in ones: parameters, problems, signals and modes.

``Circuit.from_netlist(path)`` reads the file once; every ``.param`` and every element value (R, L, C, the
couplings, the sources' DC values, the controlled sources' gains) is a parameter (``-p R1=5``, ``-p vin=48``,
names case-insensitive as in SPICE). ``problem(p, t_end)`` compiles the netlist with those values
(:mod:`converters.circuits.compile`, cached per parameter set) into an :class:`~converters.problems.LCSProblem`. The signals are
every node voltage and branch current under its SPICE name (``v(out)``, ``i(l1)``, ``i(d1)``), ``vout`` the
output the file names (its first ``.meas`` vector, else ``v(out)``) and ``switch`` the first switch's state; the
mode of a point is the set of conducting diodes and closed switches (``S1+D2``; ``off`` when none).
"""
from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from functools import lru_cache
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt

from ..circuits.compile import EDGE_TIME_CONSTANTS, Compiled, compile_netlist, compile_points, waveform_at
from ..circuits.netlist import Netlist, NetlistError, Pulse, check_overrides, read_netlist, with_values
from ..errors import ParameterError, SignalError
from ..params import Param
from ..problems import Configuration, LCSProblem, Sinusoids
from ..trajectory import Samples
from ..validate import quoted
from .base import Labels, Model, jump_losses

if TYPE_CHECKING:
    from ..trajectory import Trajectory

#: Units of the element values by letter.
UNITS = {"R": "ohm", "L": "H", "C": "F", "V": "V", "I": "A", "K": "", "E": "", "G": "S", "F": "", "H": "ohm"}


@dataclass(frozen=True)
class CircuitLabels(Labels):
    """A circuit's laws bound to one parameter set: signals from the compiled maps, modes from the conducting
    diodes and the closed switches."""

    def mode_labels_of(self, samples: Samples) -> np.ndarray:
        return self.model.mode_labels(samples, self.params)


class Circuit(Model):
    """A netlist as a model (module docstring)."""

    control = "pwm"

    def __init__(self, netlist: Netlist, source: str) -> None:
        self.netlist = netlist
        self.source = source
        self.name = Path(source).name if "\n" not in source else "netlist"
        self.title = netlist.title or self.name
        self.parameters = self._parameters()
        compiled = self.compiled(self.resolve({}))
        self.state_names = compiled.state_names
        self.pair_names = compiled.pair_names
        self.output = self._output(compiled)
        # the output and each .meas vector that is a difference of node voltages (v(a,b)) are signals too
        extra = tuple(v for v in dict.fromkeys([self.output, *netlist.outputs]) if v not in compiled.signal_names
                      and (v == self.output or _difference(v, compiled.signal_names)))
        self.signal_names = ("vout", "switch") + compiled.signal_names + extra
        for name in (self.output, *extra):
            compiled.units.setdefault(name, "A" if name.startswith("i(") else "V")
        # vout is the file's output: a current where its .meas reads one (an inverter's load current)
        self.signal_units = {"vout": compiled.units[self.output], "switch": "1", **compiled.units}
        self.output_state = next((s for s in compiled.state_names if s.startswith("v(")), compiled.state_names[0])

    @classmethod
    def from_netlist(cls, path: str | Path, text: str | None = None) -> "Circuit":
        """The model of the netlist at ``path`` (or of ``text``, ``path`` naming it in messages)."""
        netlist = read_netlist(text if text is not None else Path(path), name=str(path) if text is not None else None)
        return cls(netlist, str(path))

    @property
    def key(self) -> str:
        return self.name

    def __reduce__(self) -> tuple[Any, ...]:  # picklable for worker processes: rebuilt from the file's text
        return (_rebuild, (self.netlist.text, self.source))

    # --- parameters ------------------------------------------------------------------------------------------

    def _parameters(self) -> tuple:
        out = []
        for name, value in self.netlist.params.items():
            if name not in self.netlist.derived:
                out.append(Param(name, value, "", ".param", low=-math.inf, low_open=False))
        for e in self.netlist.elements:
            if e.name in self.netlist.expressions:       # follows the .param its value names
                continue
            if e.kind in "RLC":                  # a resistor may be 0 ohm (a short)
                out.append(Param(e.name, e.value, UNITS[e.kind], f"{e.title} (line {e.line})", low=0.0,
                                 low_open=e.kind != "R"))
            elif e.kind == "K":
                out.append(Param(e.name, e.value, "", f"{e.title} (line {e.line})", low=-1.0, high=1.0,
                                 high_open=False))
            elif e.kind in "VI" and not isinstance(e.waveform, Pulse) and isinstance(e.waveform, float):
                out.append(Param(e.name, e.waveform, UNITS[e.kind], f"{e.title} (line {e.line})", low=-math.inf,
                                 low_open=False))
            elif e.kind in "EGFH":
                out.append(Param(e.name, e.value, UNITS[e.kind], f"{e.title} (line {e.line})", low=-math.inf,
                                 low_open=False))
        names = [q.name for q in out]
        twice = next((n for n in names if names.count(n) > 1), None)
        # a source with a waveform is not a parameter, but its name keys its value as one (the waveform is refused
        # a -p): a .param of its name would set it
        twice = twice or next((n for n in self.netlist.params if n not in self.netlist.derived and any(
            e.name == n and e.kind in "VI" and not isinstance(e.waveform, float) for e in self.netlist.elements)),
            None)
        if twice is not None:          # -p NAME would be ambiguous: SPICE names are case-insensitive
            element = next(e for e in self.netlist.elements if e.name == twice)
            raise NetlistError(f"{self.netlist.where(twice)}: .param {twice} and {element.title} (line {element.line}) "
                               "share a name, and pcsuite sets a value by its name (-p, or the .param itself) without "
                               "telling them apart; rename one")
        return tuple(out)

    def resolve(self, given: dict | None = None) -> dict:
        lowered = {}
        for key, value in dict(given or {}).items():
            name = str(key).lower()
            if name in lowered:
                raise ParameterError(f"-p {key} is given twice")
            lowered[name] = value
        check_overrides(self.netlist, dict(given or {}), self.parameters)
        return super().resolve(lowered)

    def parameter_name(self, name: str) -> str:
        return str(name).lower()

    def compiled(self, p: dict) -> Compiled:
        return _compile(self.netlist.text, self.source, tuple(sorted(p.items())))

    def prepare(self, points: list[dict]) -> None:
        """Compile the circuit at many resolved parameter sets together (:func:`compile_points`: one stamp and
        solve for the sets that change values only), kept for :meth:`compiled` to take; a set the batch cannot
        take (or that fails) is left to its own compile, which gives its result or its error."""
        keys = [(self.netlist.text, self.source, tuple(sorted(p.items()))) for p in points]
        keys = [key for key in dict.fromkeys(keys) if key not in _PREPARED]
        netlists, kept, first = [], [], None
        for key in keys:
            given = dict(key[2])
            netlist = None
            if first is not None:          # a point that changes element values alone is the first's, rebound
                if given.keys() == first[0].keys():
                    netlist = with_values(first[1], {k: v for k, v in given.items() if first[0][k] != v})
            try:
                netlist = netlist or read_netlist(key[0], overrides=given, name=key[1])
            except NetlistError:
                continue
            first = first or (given, netlist)
            netlists.append(netlist)
            kept.append(key)
        if len(_PREPARED) + len(kept) > COMPILED_KEPT:
            _PREPARED.clear()
        for key, compiled in zip(kept, compile_points(netlists)):
            if compiled is not None:
                _PREPARED[key] = compiled

    # --- the problem -----------------------------------------------------------------------------------------

    def problem(self, p: dict, t_end: float, x0: npt.NDArray[np.float64] | None = None, t_start: float = 0.0,
                initial: int | None = None) -> LCSProblem:
        c = self.compiled(p)
        x0 = c.x0 if x0 is None else x0
        inputs = Sinusoids(*c.inputs) if c.inputs is not None else None
        # the law in force at t_start: a run is split at step_times (converters.run does), as a built-in's at t_step
        return LCSProblem(c.configurations, c.law_at(t_start), x0=x0, t_span=(t_start, t_end),
                          state_names=c.state_names, pair_names=c.pair_names, metadata={"circuit": self.name, **p},
                          inputs=inputs, pair_currents=tuple(tuple(bool(b) for b in row) for row in c.pair_currents))

    def step_times(self, p: dict) -> list[float]:
        """The instants where a switch driven by a source that does not repeat changes (a load step's switch)."""
        return [t for t, _ in self.compiled(p).phases]

    def period(self, p: dict) -> float:
        return self.compiled(p).period

    def periodic(self, p: dict) -> bool:
        return math.isfinite(self.period(p))

    def default_h(self, p: dict) -> float:
        tran = self.netlist.tran
        if self.periodic(p):
            # T/1000, or the file's own step (a fraction of its period) where it is finer, as a whole number of steps
            # a period and a multiple of 4: a SIN source needs whole steps at h, and the accuracy check's orbits at
            # 2h and 4h too (a 60 Hz rectifier's .tran 10u was refused: T/1666.7)
            # (its period at the file's own parameters, where they have one: a gate at -p VT=0.5 switches where
            # the file's VT = 1.5 left it none, and the fraction had been 0, a ZeroDivisionError)
            own = self.period(self.resolve({}))
            fraction = min(1e-3, tran.tstep / (own if math.isfinite(own) else self.period(p)))
            return self.period(p) / (4 * math.ceil(0.25 / fraction - 1e-9))
        return min(tran.tmax or tran.tstep, tran.tstop / 5000.0)     # the file's step, at most a 5,000th of its run

    def max_h(self, p: dict) -> float:
        return self.netlist.tran.tstop / 20.0

    def default_duration(self, p: dict) -> float:
        """The run the file states: its .tran TSTOP."""
        return self.netlist.tran.tstop

    def time_scale(self, p: dict) -> float:
        return self.default_h(p) * 1000.0

    #: A circuit without a period is summarised over the last tenth of its run.
    WINDOW_FRACTION = 0.1

    def summary(self, tr: Trajectory, p: dict) -> dict:
        """The model's summary (:meth:`Model.summary`); without a period, over the last tenth of the run
        (``window_s``); with what the circuit holds fixed (``invariants``: its loops of capacitors, cutsets of
        inductors and charge islands), where it has any."""
        compiled = self.compiled(p)
        held = {"invariants": [dict(i) for i in compiled.invariants]} if compiled.invariants else {}
        notes = list(compiled.notes) + self._edge_warnings(p)
        if notes:
            held["warnings"] = notes
        t1 = float(tr.t[-1])
        if self.periodic(p):
            out = super().summary(tr, p)
            t0 = t1 - out["window_periods"] * self.period(p)
        else:
            t0 = t1 - self.WINDOW_FRACTION * (t1 - float(tr.t[0]))
            out = {"vout_mean": tr.mean("vout", t0=t0, t1=t1), "window_s": [t0, t1],
                   "mode_fractions": tr.mode_fractions(None, t0=t0, t1=t1),
                   "measurements": tr.measurement_rows(t0=t0, t1=t1), **jump_losses(tr, t0, t1)}
        floating = self.floating_warning(tr, p, ["vout", *self.netlist.outputs], t0, t1)
        if floating:
            held["warnings"] = [*held.get("warnings", []), floating]
        impulses = _impulse_warning(out, compiled)
        if impulses:
            held["warnings"] = [*held.get("warnings", []), impulses]
        return {**out, **held}

    def _edge_warnings(self, p: dict) -> list[str]:
        """Why the power PULSEs' step semantics cannot be trusted here: an edge run as a step (its other edge has no
        width, so it is no ramp of the LCS: :meth:`~converters.circuits.compile._Compiler.slow_edges`) longer than
        the circuit's fastest time constant (a 10 V square wave with 1 us edges through 10 ohm into 10 nF: the step
        drives 1 A through the resistor, the ramp 0.1 A; the values the mode sets near an edge are a step's, up to
        edge / tau times a ramp's, where no estimate sees it)."""
        edges = self.compiled(p).power_edges
        if not edges:
            return []
        rate = self.fastest_rate(p)
        out = []
        for title, _, middles in edges:
            edge = max(width for _, width in middles)
            if edge * rate > EDGE_TIME_CONSTANTS:
                out.append(f"{title}: its edges ({edge:.3g} s) are run as steps at their middle, and the circuit's "
                           f"fastest time constant ({1.0 / rate:.3g} s) is shorter: the currents that mode carries "
                           f"near an edge are a step's, up to {edge * rate:.2g} times the ramp's, which no estimate "
                           "sees; give both edges a width (they are then ramps), or a resistance that slows the mode")
        return out

    def floating_mask(self, names: Sequence[str], samples: Samples, p: dict) -> np.ndarray:
        """Where each signal of ``names`` is not set by the circuit (bool, (points, names)): in a configuration with
        node potentials only diodes tie to the rest (:meth:`~converters.circuits.compile._Compiler.floating`), where
        the diodes that conduct pin no shift of them that moves the signal."""
        c = self.compiled(p)
        out = np.zeros((len(samples.t), len(names)), dtype=bool)
        if not any(f is not None for f in c.floating) or samples.u is None or samples.config is None:
            return out                                  # (an ngspice run's: its leakages set it)
        weights = [_weights(self.output if name == "vout" else name, c.signal_names) for name in names]
        rows = np.array([np.zeros(len(c.signal_names)) if w is None else w for w in weights])
        # a diode pins the potentials where it carries current; one held at zero current (the event method's mode
        # may hold a blocked diode at u = y = 0) pins them on one side only, and they are not set there
        conducting = _carrying(c, samples)
        config, k = np.asarray(samples.config, dtype=np.int64), conducting.shape[1]
        if k + int(config.max(initial=0)).bit_length() < 63:     # one integer per (configuration, conducting diodes)
            codes = (config << k) | (conducting.astype(np.int64) @ (np.int64(1) << np.arange(k, dtype=np.int64)))
        else:
            codes = np.unique(np.column_stack([config, conducting]), axis=0, return_inverse=True)[1].ravel()
        _, first, inverse = np.unique(codes, return_index=True, return_inverse=True)
        for j, at in enumerate(first):
            floating = c.floating[config[at]]
            if floating is not None:
                out[inverse.ravel() == j] = (np.abs(rows @ floating[0] @ _pinned(floating[1], conducting[at]))
                                             > 1e-9).any(axis=1)
        return out

    def floating_shares(self, tr: Trajectory, p: dict, names: Sequence[str], t0: float, t1: float) -> dict[str, float]:
        """{name: the fraction of [t0, t1] it is not set by the circuit} for the signals of ``names`` that are not
        (:meth:`floating_mask`; "vout" as the file's output)."""
        if not any(f is not None for f in self.compiled(p).floating):
            return {}
        names = list(dict.fromkeys(names))
        masks: dict[int, np.ndarray] = {}            # the integral reads each name's column at the same samples

        def column(samples: Samples, i: int) -> np.ndarray:
            if id(samples) not in masks:
                masks[id(samples)] = self.floating_mask(names, samples, p)
            return masks[id(samples)][:, i]
        points = tr.integration_points(t0, t1)
        shares = {name: tr.integral(lambda s, i=i: column(s, i), t0, t1, points) / (t1 - t0)
                  for i, name in enumerate(names)}
        return {name: share for name, share in shares.items() if share > 0}

    def floating_text(self, p: dict, shares: dict[str, float]) -> str:
        """What :meth:`floating_shares` found, in one line: how long, which nodes float and which diodes alone would
        tie them, and what to do."""
        c = self.compiled(p)
        named = {self.output if name == "vout" else name: share for name, share in shares.items()}
        # per configuration, the shift that moves the named signals most (S^T w): the nodes and diodes it moves
        # are the floating group behind them, not every group the circuit has
        moved_nodes, moved_diodes = np.zeros(len(c.signal_names), bool), np.zeros(len(c.pair_names), bool)
        for signals, ports in (f for f in c.floating if f is not None):
            for name in named:
                w = _weights(name, c.signal_names)
                d = signals.T @ w if w is not None else np.zeros(signals.shape[1])
                if np.abs(d).max(initial=0.0) > 1e-9:
                    d = d / np.linalg.norm(d)
                    moved_nodes |= np.abs(signals @ d) > 1e-9
                    moved_diodes |= np.abs(ports @ d) > 1e-9
        nodes = [n[2:-1] for i, n in enumerate(c.signal_names) if n.startswith("v(") and moved_nodes[i]]
        diodes = [d.upper() for i, d in enumerate(c.pair_names) if moved_diodes[i]]
        floats = ", ".join(f"{name} ({100 * share:.3g} % of the time)" for name, share in named.items())
        across = f" (v({nodes[0]},{nodes[1]}))" if len(nodes) > 1 else ""
        return (f"{floats} {'is' if len(named) == 1 else 'are'} not set by the circuit: while "
                f"{_and(diodes)} block, node{'s' if len(nodes) > 1 else ''} {', '.join(nodes)} float "
                "(nothing else ties them to the rest), and pcsuite's value there is one of many the LCP could pick "
                f"(SPICE's comes from its leakages); measure a voltage across the floating nodes{across}, or tie "
                "them to a reference with a resistor")

    def floating_warning(self, tr: Trajectory, p: dict, names: Sequence[str], t0: float, t1: float) -> str | None:
        """:meth:`floating_text` of the signals of ``names`` not set over part of [t0, t1]; None where all are."""
        shares = self.floating_shares(tr, p, names, t0, t1)
        return self.floating_text(p, shares) if shares else None

    def summary_from(self, p: dict, t_start: float, t_end: float) -> float:
        if self.periodic(p):
            return super().summary_from(p, t_start, t_end)
        return t_end - 2 * self.WINDOW_FRACTION * (t_end - t_start)

    # --- signals and modes -----------------------------------------------------------------------------------

    def labels(self, p: dict) -> CircuitLabels:
        return CircuitLabels(self, p)

    def _output(self, compiled: Compiled) -> str:
        """The file's output: the first vector a .meas names (v(NODE), v(A,B) or i(ELEMENT)), else v(out), else the
        first node's voltage that no voltage source holds to ground (else the first node's)."""
        for vector in self.netlist.outputs:
            if vector in compiled.signal_names or _difference(vector, compiled.signal_names):
                return vector
        if "v(out)" in compiled.signal_names:
            return "v(out)"
        nodes = [s for s in compiled.signal_names if s.startswith("v(")]
        # not a node a voltage source holds to ground (a DC link, a gate): no output (a half-bridge's link,
        # v(p) = 200 V, had been compared with ngspice's and passed)
        held, grown = {"0"}, True
        while grown:                        # sources stacked on sources (a link of two 100 V halves) hold too
            grown = False
            for e in self.netlist.elements:
                if e.kind == "V" and (e.nodes[0] in held) != (e.nodes[1] in held):
                    held |= {e.nodes[0], e.nodes[1]}
                    grown = True
        held = {f"v({n})" for n in held}
        return next((name for name in nodes if name not in held), nodes[0])

    def signal(self, name: str, samples: Samples, p: dict) -> np.ndarray:
        if name == "vout":
            return self.signal(self.output, samples, p)
        if name == "switch":
            return self.switch_state(samples, p)
        if name in ("v(0)", "v(gnd)"):
            return np.zeros(len(samples.t))
        c = self.compiled(p)
        pair = _difference(name, c.signal_names)
        if pair:
            return self.signal(pair[0], samples, p) - self.signal(pair[1], samples, p)
        try:
            row = c.signal_names.index(name)
        except ValueError:
            raise SignalError(f"signal must be one of vout, switch, {', '.join(c.signal_names)}; got {name!r}") from None
        config = np.asarray(samples.config, dtype=np.int64)
        # each configuration's row of each map, stacked by configuration: one gather and one product per point
        Sx, Su, s0, Ssin, Sgate = c.signal_rows(row)
        x = np.asarray(samples.x)
        out = np.einsum("ij,ij->i", x, Sx[config]) + s0[config]
        if samples.u is not None:
            out += np.einsum("ij,ij->i", np.asarray(samples.u), Su[config])
        t = np.asarray(samples.t, dtype=float)
        if c.inputs is not None and Ssin.any():          # the SIN sources' share at each point's time
            omega, phase = c.inputs[0], c.inputs[1]
            out += np.einsum("ij,ij->i", np.sin(np.multiply.outer(t, omega) + phase), Ssin[config])
        if c.gates and Sgate.any():                      # a gate's node voltage follows its waveform
            gate_values = np.column_stack([waveform_at(w, t) for w in c.gates])
            out += np.einsum("ij,ij->i", gate_values, Sgate[config])
        return out

    #: Points a period of a SIN gate is read at, between the other gates' corners, for a signal of waveforms alone.
    WAVEFORM_POINTS = 4096

    def waveform_measures(self, name: str, p: dict, t0: float, t1: float) -> tuple[float, float, float, float] | None:
        """(mean, rms, min, max) over [t0, t1] of a signal that is its gate sources' waveforms alone, with the same
        weights in every configuration (a gate's node voltage), from the waveforms themselves: exact on a PULSE's
        or PWL's corners, whose kinks fall inside the run's steps or quadrature pieces (a 10 ns ramp's gate read
        its mean 0.20025 for the PULSE's 0.2, 1.2e-3 off with no estimate); None for any other signal."""
        c = self.compiled(p)
        if not c.gates or name not in c.signal_names or not t1 > t0:
            return None
        Sx, Su, s0, Ssin, Sgate = c.signal_rows(c.signal_names.index(name))
        if Sx.any() or Su.any() or s0.any() or Ssin.any() or not Sgate.any() or (Sgate != Sgate[0]).any():
            return None
        weights = Sgate[0]
        corners = [np.array([t0, t1])]
        for w, weight in zip(c.gates, weights):
            if weight == 0.0:
                continue
            if isinstance(w, Pulse) and math.isfinite(w.per):
                first = math.floor((t0 - w.td) / w.per)
                starts = w.td + w.per * np.arange(first, math.ceil((t1 - w.td) / w.per) + 1)
                corners.append((starts[:, None] + np.array([0.0, w.tr, w.tr + w.pw, w.tr + w.pw + w.tf])).ravel())
            else:                       # a PWL's corners repeat with its period; a SIN is read densely
                period = getattr(w, "period", None)
                if not period or not math.isfinite(period):
                    return None
                points = [float(tt) for tt, _ in getattr(w, "points", ())] or \
                    list(np.linspace(0.0, period, self.WAVEFORM_POINTS, endpoint=False))
                first = math.floor(t0 / period)
                starts = period * np.arange(first, math.ceil(t1 / period) + 1)
                corners.append((starts[:, None] + np.array(points)[None, :]).ravel())
        t = np.unique(np.concatenate(corners))
        t = t[(t >= t0) & (t <= t1)]
        v = np.column_stack([waveform_at(w, t) for w in c.gates]) @ weights
        # the waveform is linear between its corners (a SIN's points close enough): the trapezoid and the exact
        # square of a line, the extremes at the corners
        dt = np.diff(t)
        a, b = v[:-1], v[1:]
        span = t1 - t0
        mean = float(dt @ (0.5 * (a + b))) / span
        rms = math.sqrt(max(float(dt @ ((a * a + a * b + b * b) / 3.0)) / span, 0.0))
        return mean, rms, float(v.min()), float(v.max())

    def signal_table(self, samples: Samples, p: dict, names: Sequence[str] | None = None) -> np.ndarray:
        """The signals ``names`` of the compiled circuit (default: every one, its ``signal_names``' order) at each
        point, (points, signals): one product per configuration the points are in, where :meth:`signal` reads one
        signal (losses and power balances read many at the same points)."""
        c = self.compiled(p)
        try:
            Sx, Su, s0, Ssin, Sgate = c.signal_stack(None if names is None else tuple(names))
        except ValueError as error:
            raise SignalError(str(error)) from None
        config = np.asarray(samples.config, dtype=np.int64)
        x, t = np.asarray(samples.x, dtype=float), np.asarray(samples.t, dtype=float)
        u = None if samples.u is None else np.asarray(samples.u, dtype=float)
        sines = np.sin(np.multiply.outer(t, c.inputs[0]) + c.inputs[1]) if c.inputs is not None and Ssin.any() else None
        gates = np.column_stack([waveform_at(w, t) for w in c.gates]) if c.gates and Sgate.any() else None
        from ..circuits.kernels import signal_rows          # the states' and pairs' share: one compiled pass
        out = np.empty((t.size, s0.shape[1]))
        signal_rows(np.ascontiguousarray(x), np.zeros((t.size, 0)) if u is None else np.ascontiguousarray(u),
                    np.ascontiguousarray(config), np.ascontiguousarray(Sx), np.ascontiguousarray(Su),
                    np.ascontiguousarray(s0), out)
        for values, maps in ((sines, Ssin), (gates, Sgate)):      # the waveforms' share, per configuration
            if values is None:
                continue
            for k in np.unique(config):
                at = config == k
                out[at] += values[at] @ maps[k].T
        return out

    def storage_power(self, samples: Samples, p: dict) -> np.ndarray:
        """The power the capacitors and inductors absorb at each point, sum of v i (W): d/dt of their stored
        energy between jumps (:func:`converters.analysis.accuracy.energy_balance`)."""
        c = self.compiled(p)
        out = np.zeros(len(samples.t))
        for name in c.state_names:
            kind, element = name[0], name[2:-1]
            if kind not in "vi" or not name.endswith(")"):
                continue                                    # a ramp's or an oscillator's state
            if kind == "v":
                out += samples.x[:, c.state_names.index(name)] * self.signal(f"i({element})", samples, p)
            else:
                a, b = next(e.nodes[:2] for e in self.netlist.elements if e.name == element)
                out += samples.x[:, c.state_names.index(name)] * (self.signal(f"v({a})", samples, p)
                                                                   - self.signal(f"v({b})", samples, p))
        return out

    def source_power(self, samples: Samples, p: dict) -> np.ndarray:
        """The power the independent sources (V, I) exchange at each point, sum of |v i| (W): the scale of the
        energy balance."""
        c = self.compiled(p)
        out = np.zeros(len(samples.t))
        for e in self.netlist.elements:
            if e.kind in "VI" and f"i({e.name})" in c.signal_names:
                a, b = e.nodes[:2]
                out += np.abs((self.signal(f"v({a})", samples, p) - self.signal(f"v({b})", samples, p))
                              * self.signal(f"i({e.name})", samples, p))
        return out

    def stored_energy(self, x: np.ndarray, p: dict) -> float | None:
        """1/2 C v^2 + 1/2 i^T L i at the states ``x`` (J); None where the weights are not known."""
        c = self.compiled(p)
        if not c.energy:
            return None
        capacitance, inductance = c.energy
        n_c, n_l = capacitance.size, inductance.shape[0]
        v, i = np.asarray(x[:n_c], float), np.asarray(x[n_c:n_c + n_l], float)
        return float(0.5 * capacitance @ (v * v) + 0.5 * i @ inductance @ i)

    def unit_scales(self, samples: Samples, p: dict) -> dict[str, float] | None:
        """{"V": the largest voltage, "A": the largest current among ``samples``' states and pair variables, "S":
        the circuit's largest conductance: of its signal maps (a current signal's weight on a capacitor's voltage:
        1/R), a period over an inductance, a capacitance over a period; 0 where none}: what a relative error of
        each unit is taken on (:func:`converters.analysis.accuracy.circuit_floor`)."""
        c = self.compiled(p)
        x = np.abs(np.asarray(samples.x, dtype=float))
        currents = np.array([name.startswith("i(") for name in c.state_names])
        volts = float(x[:, ~currents].max(initial=0.0)) if x.size else 0.0
        amps = float(x[:, currents].max(initial=0.0)) if x.size else 0.0
        if samples.u is not None and samples.y is not None and samples.config is not None and c.pair_names != ("none",):
            forms = np.asarray(c.pair_currents, dtype=bool)[np.asarray(samples.config, dtype=np.int64)]
            u, y = np.abs(np.asarray(samples.u, dtype=float)), np.abs(np.asarray(samples.y, dtype=float))
            amps = max(amps, float(np.where(forms, u, y).max(initial=0.0)))
            volts = max(volts, float(np.where(forms, y, u).max(initial=0.0)))
        if "_conductance" not in c.__dict__:
            rows = [i for i, name in enumerate(c.signal_names) if c.units.get(name) == "A"]
            columns = np.flatnonzero(~currents)
            conductance = max((float(np.abs(maps[0][np.ix_(rows, columns)]).max(initial=0.0))
                               for maps in c.signal_maps), default=0.0)
            if c.energy and np.isfinite(c.period) and c.period > 0.0:
                # the current a period's voltage drives through an inductor (T / L) or into a capacitor (C / T): a
                # path the diodes block has currents of rounding whose scale is no resistor's (0.1 S beside 1 S)
                capacitance, inductance = c.energy
                diagonal = np.abs(np.diag(inductance)) if np.size(inductance) else np.zeros(0)
                conductance = max(conductance, float((c.period / diagonal[diagonal > 0.0]).max(initial=0.0)),
                                  float(np.abs(capacitance).max(initial=0.0)) / c.period)
            c.__dict__["_conductance"] = conductance
        return {"V": volts, "A": amps, "S": c.__dict__["_conductance"]}

    def vout(self, samples: Samples, p: dict) -> np.ndarray:
        return self.signal("vout", samples, p)

    def switch_state(self, samples: Samples, p: dict) -> np.ndarray:
        c = self.compiled(p)
        if not c.switch_names:
            return np.zeros(len(samples.t), dtype=np.int8)
        closed = np.array([cl[0] for cl in c.closed], dtype=np.int8)
        return closed[np.asarray(samples.config, dtype=np.int64)]

    def conducting(self, samples: Samples, p: dict | None = None) -> np.ndarray:
        c = self.compiled(p if p is not None else self.resolve({}))
        currents = np.asarray(c.pair_currents, dtype=bool)[np.asarray(samples.config, dtype=np.int64)]
        if samples.held is not None:                  # the event method's own modes
            return samples.held == currents
        # a diode conducts where its current exceeds its reverse voltage (u > y where u is its current, y > u where u
        # is its voltage: the model's rule) and rounding: a pair at u = y = 0 (a bridge's output floating while every
        # diode blocks) carries nothing, whichever variable u is. The stepper had read a bridge's D3 at 1e-16 A as
        # conducting, "D3 0.148" where it is off (0.415 exact).
        return np.where(currents, samples.u > samples.y, samples.y > samples.u) & _carrying(c, samples)

    def mode_labels(self, samples: Samples, p: dict) -> np.ndarray:
        c = self.compiled(p)
        conducting = self.conducting(samples, p) if c.pair_names != ("none",) else np.zeros((len(samples.t), 0), bool)
        config = np.asarray(samples.config, dtype=np.int64)
        names: dict[tuple[np.int64, ...], str] = {}
        out = np.empty(len(samples.t), dtype=object)
        diodes = [d.upper() for d in c.pair_names] if c.pair_names != ("none",) else []
        switches = [s.upper() for s in c.switch_names]
        keys = np.concatenate([config[:, None], conducting.astype(np.int64)], axis=1)
        for i, key in enumerate(map(tuple, keys)):
            label = names.get(key)
            if label is None:
                closed = [s for s, on in zip(switches, c.closed[key[0]]) if on]
                label = "+".join(closed + [d for d, on in zip(diodes, key[1:]) if on]) or "off"
                names[key] = label
            out[i] = label
        return out

    off_held_label = "off"
    turn_off_label = None


def _impulse_warning(summary: dict, compiled) -> str:
    """'' or what a run whose state jumps cannot say. A switch closing across a charged capacitance moves its charge
    in an instant, a current impulse that no sample holds, so the means (and rms) of the currents through the loop
    that jumps leave it out (a buck with 3 nF across its diode read i(vin) -1.0085 A where it is -1.0365 A, i(cd)
    -0.0288 A where a capacitor's mean current is 0 on an orbit); a switch opening an inductor's path hands its flux
    on in an instant, a voltage impulse across the cutset that the means of those voltages leave out."""
    losses = summary.get("losses", {})
    if not losses.get("redistribution_J", 0.0) > 0.0:
        return ""
    moved = set()
    for configuration in compiled.configurations:
        if configuration.jump is not None:
            P = configuration.jump.P
            for i, name in enumerate(compiled.state_names):
                if np.any(P[i] != np.eye(len(P))[i]):
                    moved.add("charge" if name.startswith("v(") else "flux")
    said = []
    if "charge" in moved:
        said.append("the means and rms of the currents through the capacitors, sources and switches of the loops "
                    "that jump leave out each jump's impulse of charge")
    if "flux" in moved:
        said.append("the means of the voltages across the inductors, switches and diodes of the cutsets that jump "
                    "leave out each jump's impulse of flux")
    return (f"the state jumps {losses['jumps']} times in the window ({' and '.join(sorted(moved))} redistributed in "
            f"an instant: {losses['redistribution_W']:.4g} W lost): " + "; ".join(said) + " (a switch's RON makes "
            "the impulse a pulse the run can read)")


#: A pair's current counts where it exceeds this fraction of its sample's largest pair variable (V or A): rounding
#: leaves 1e-16 A in a diode that a 325 V bridge holds at u = y = 0.
CARRYING = 1e-9


def _carrying(c, samples: Samples) -> np.ndarray:
    """Per point and pair: the pair carries a current above rounding, :data:`CARRYING` of the larger of the point's
    largest pair variable and the circuit's (its sources' terms in the pairs: a blocked diode's 12 V), so a
    window's label does not depend on the rows asked for, and a point where every pair is at rounding (1e-28 as a
    switch opens on a path the diodes block) reads nothing as conducting."""
    forms = np.asarray(c.pair_currents, dtype=bool)[np.asarray(samples.config, dtype=np.int64)]
    u, y = np.asarray(samples.u, dtype=float), np.asarray(samples.y, dtype=float)
    current = np.where(forms, u, y)
    sources = max([float(np.abs(k.F).max(initial=0.0)) for k in c.configurations]
                  + ([float(np.abs(c.inputs[3]).max(initial=0.0))] if c.inputs is not None else []))
    scale = np.maximum(np.maximum(np.abs(u).max(axis=1, initial=0.0), np.abs(y).max(axis=1, initial=0.0)), sources)
    # a pair behind an impedance D_ii (its current's own term: ohms where u is its current, siemens where u is its
    # voltage) is solved to rounding of the current that scale drives through it, not of the scale itself in
    # amperes: a peak detector's diode fed through 1 Gohm carries 9 pA where 1e-9 of its 10 V source is 10 nA, and
    # had read "off 1.000000" where it conducts half the period; the mixed scale stays a bound (a pair whose
    # current no impedance of its own sets, D_ii = 0: a diode in series with an inductor)
    if "_pair_diagonals" not in c.__dict__:          # (per configuration, once: measures read many sample blocks)
        c.__dict__["_pair_diagonals"] = np.array([np.diag(k.D) if np.size(k.D) else np.zeros(forms.shape[1])
                                                  for k in c.configurations])
    d = c.__dict__["_pair_diagonals"][np.asarray(samples.config, dtype=np.int64)]
    with np.errstate(divide="ignore"):
        conductance = np.where(forms, np.where(d > 0.0, 1.0 / np.where(d > 0.0, d, 1.0), np.inf), d)
    conductance = np.where(conductance > 0.0, conductance, np.inf)
    # (an infinite conductance drives the scale itself: 0 * inf at a point whose pairs and sources are all 0 had
    # printed numpy's "invalid value encountered in multiply" to the user)
    driven = np.minimum(scale[:, None] * np.where(np.isinf(conductance), 1.0, conductance), scale[:, None])
    own = np.abs(current).max(axis=1, initial=0.0)
    return current > CARRYING * np.maximum(driven, own[:, None])


def _weights(name: str, names: tuple[str, ...]) -> np.ndarray | None:
    """Signal ``name`` as weights of the compiled signals ``names`` (a node pair's voltage: +1 and -1; ground: 0);
    None for one that is not a combination of them ("switch")."""
    if name in names:
        return np.eye(len(names))[names.index(name)]
    if name in ("v(0)", "v(gnd)"):
        return np.zeros(len(names))
    pair = _difference(name, names)
    if pair is None:
        return None
    a, b = (_weights(v, names) for v in pair)
    return None if a is None or b is None else a - b


def _pinned(ports: np.ndarray, conducting: np.ndarray) -> np.ndarray:
    """The floating shifts (columns) that the conducting diodes' voltages, held at 0, leave free."""
    if not conducting.any():
        return np.eye(ports.shape[1])
    from scipy.linalg import null_space
    return null_space(ports[conducting], rcond=1e-9)


def _and(names: list[str]) -> str:
    """'D1', 'D1 and D2', 'D1, D2 and D3'."""
    return names[0] if len(names) == 1 else f"{', '.join(names[:-1])} and {names[-1]}"


def _difference(name: str, names: tuple[str, ...]) -> tuple[str, ...] | None:
    """("v(a)", "v(b)") for "v(a,b)" when both are node voltages of the circuit (ground: 0)."""
    if not (name.startswith("v(") and name.endswith(")") and "," in name):
        return None
    a, b = (part.strip() for part in name[2:-1].split(",", 1))
    pair = tuple(f"v({node})" for node in (a, b))
    if all(v in names or v == "v(0)" for v in pair):
        return pair
    return None


#: Compiled parameter sets kept per process: more than a sweep chunk's points (ModelSweep.chunk_hint), so that a
#: point's row reads the compile its problem made.
COMPILED_KEPT = 1024


#: Compiles made together ahead of their use (:meth:`Circuit.prepare`), each taken once by :func:`_compile`.
_PREPARED: dict = {}


@lru_cache(maxsize=COMPILED_KEPT)
def _compile(text: str, source: str, values: tuple) -> Compiled:
    prepared = _PREPARED.pop((text, source, values), None)
    if prepared is not None:
        return prepared
    netlist = read_netlist(text, overrides=dict(values), name=source)
    return compile_netlist(netlist)


class FromNetlist:
    """A built-in converter compiled from its netlist (``netlists/circuits/NETLIST_FILE``), the one statement of its
    circuit: its configurations are the compiled LCS's with the states put in the model's order
    (``netlist_states``: each state's SPICE name), each pair's port form the compiler's. The model keeps what the
    netlist does not say: its closed forms, its named signals, its losses and its mode names."""

    netlist_file: str
    netlist_states: tuple
    #: The model's name of each configuration (the compiled ones are named by the switches' states).
    configuration_names: tuple = ("ON", "OFF")
    #: Parameters of the model's own schedule (its PWM: :meth:`Converter.schedule`), not passed to the circuit: the
    #: configurations do not depend on them, and the file's gate is written for 0 < D < 1 where the model takes
    #: D = 0 and 1 too.
    schedule_parameters: frozenset = frozenset({"D"})

    def configurations(self, p: dict) -> tuple:
        return _builtin_configurations(self.netlist_file, tuple(self.netlist_states), tuple(self.configuration_names),
                                       self.circuit_values(p))

    def prepare(self, points: list[dict]) -> None:
        """The circuit compiled at every point's values together (:meth:`Circuit.prepare`)."""
        circuit = self.circuit
        resolved = []
        for p in points:
            try:
                resolved.append(_resolved(self.netlist_file, self.circuit_values(p)))
            except ParameterError:
                continue
        circuit.prepare(resolved)

    def netlist_signal(self, name: str, samples: Samples, p: dict) -> np.ndarray:
        """A signal of the model's netlist by its SPICE name (``i(d1)``, ``v(in,sw)``) at the model's parameters
        ``p``: the compiled configuration's signal map, the model's states put in the
        compiled order. NaN on a run without pair variables (ngspice's: no complementarity variables to read)."""
        if samples.u is None:
            return np.full(len(samples.t), np.nan)
        circuit = self.circuit
        values = _resolved(self.netlist_file, self.circuit_values(p))
        compiled = circuit.compiled(values)
        order = [self.netlist_states.index(state) for state in compiled.state_names]
        return circuit.signal(name, replace(samples, x=np.asarray(samples.x)[:, order]), values)

    @property
    def circuit(self) -> Circuit:
        """The netlist the model compiles, as a :class:`Circuit`."""
        return builtin(self.netlist_file)

    def circuit_values(self, p: dict) -> tuple:
        """The circuit's parameter values of the model's ``p`` (names lower-cased as SPICE's, sorted)."""
        skip = NOT_CIRCUIT | self.schedule_parameters
        return tuple(sorted((k.lower(), float(v)) for k, v in p.items() if v is not None and k not in skip))

    @property
    def pair_currents(self) -> tuple:
        """Per configuration, per pair: u is the diode's current (the compiler's port form at the defaults: a
        parameter changes values, never which quantity a port carries)."""
        return self.circuit.compiled(self.circuit.resolve({})).pair_currents


#: A model's parameters that are not the circuit's (the instants and values of a step: a run in phases).
NOT_CIRCUIT = frozenset({"t_step", "R_step", "Vin_step"})


@lru_cache(maxsize=None)
def builtin(name: str) -> Circuit:
    """The Circuit of a built-in netlist, ``netlists/circuits/NAME`` (package data beside the ``netlists`` package;
    read by path so the model library does not import it)."""
    path = Path(__file__).resolve().parents[2] / "netlists" / "circuits" / name
    return Circuit.from_netlist(path)


@lru_cache(maxsize=COMPILED_KEPT)
def _resolved(name: str, values: tuple) -> dict:
    """A built-in netlist's resolved parameters at the model's circuit values (read-only: shared by the callers)."""
    return builtin(name).resolve(dict(values))


@lru_cache(maxsize=COMPILED_KEPT)
def _builtin_configurations(name: str, states: tuple, names: tuple, values: tuple) -> tuple:
    compiled = builtin(name).compiled(_resolved(name, values))
    order = [compiled.state_names.index(s) for s in states]
    return tuple(_permuted(c, order, label) for c, label in zip(compiled.configurations, names, strict=True))


def _permuted(c: Configuration, order: list[int], name: str) -> Configuration:
    """A configuration with its states in ``order`` (x_model = x_compiled[order]), named ``name``."""
    A, B, C, E = np.asarray(c.A), np.asarray(c.B), np.asarray(c.C), np.asarray(c.E)
    return Configuration(A=A[np.ix_(order, order)], B=B[order], C=C[:, order], D=c.D, E=E[order], F=c.F, name=name,
                         jump=None if c.jump is None else c.jump.permuted(order))


def _rebuild(text: str, source: str) -> Circuit:
    return Circuit(read_netlist(text, name=source), source)


def load(path: str | Path) -> Circuit:
    """The Circuit of a netlist file, read once per process while the file is unchanged (its path, size and
    modification time)."""
    path = Path(path)
    try:
        stat = path.stat()
    except OSError:
        raise NetlistError(f"{quoted(path)}: no such file") from None
    return _load(str(path.resolve()), stat.st_size, stat.st_mtime_ns, str(path))


@lru_cache(maxsize=16)
def _load(resolved: str, size: int, mtime: int, given: str) -> Circuit:
    return Circuit.from_netlist(given)


def is_netlist(name: object) -> bool:
    """A CONVERTER argument that names a netlist file (``.cir``, ``.sp``, ``.net``, ``.spice``)."""
    return isinstance(name, (str, Path)) and str(name).lower().endswith((".cir", ".sp", ".net", ".spice", ".ckt"))


__all__ = ["Circuit", "is_netlist", "NetlistError"]
