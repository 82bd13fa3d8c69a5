"""A user's netlist as ngspice runs it: the same circuit, its ideal devices mapped to near-ideal models.

The file is read and flattened by :mod:`converters.circuits.netlist` (every value a number, ``.control``
refused), and written back element by element with numbers formatted here only, so nothing of the file's
text reaches ngspice but what the reader understood. What changes: a switch model without ``RON`` (or with ``RON=0``) gets the
near-ideal ``RON``/``ROFF`` of :class:`~netlists.options.SpiceOptions`, a diode model without ``IS``/``N`` the
near-ideal ``IS``/``N``, a 0 ohm resistor's two nodes one, each diode and inductor a 0 V sense source (its current is a probe), the
``.tran`` pcsuite's span, the ``.options`` pcsuite's (by default the file's TMAX as a fraction of its period and
its RELTOL, ABSTOL and METHOD: :func:`file_spice_options`), and the initial conditions the run's start (``IC=`` on every
capacitor and inductor, with ``UIC``). Element names keep their letter; a subcircuit's elements and nodes
keep their flattened names with ``.`` written as ``_``.
"""
from __future__ import annotations

import math
import re

from converters.circuits.netlist import Pulse, Pwl, Sin
from converters.errors import ParameterError

from .options import Netlist, SpiceOptions, _num, options_line


def _name(flat: str) -> str:
    return flat.replace(".", "_").replace("#", "_")


def _node(flat: str) -> str:
    return "0" if flat == "0" else _name(flat)


def _shorts(netlist, prefer=()) -> dict:
    """Each node a 0 ohm resistor joins to others, mapped to the one of its class the written netlist keeps: ground
    where it is one, else a node of ``prefer`` (the file's output), else the one with the most other elements (not
    the inner node of a parasitic), else the first. A 0 V source in its place would be exact too, but one in series
    with a capacitor stopped ngspice ("timestep too small" on a DCM boost's diode at RELTOL 1e-5, where the merged
    nodes run)."""
    zero = [e for e in netlist.elements if e.kind == "R" and e.value == 0]
    if not zero:
        return {}
    degree = {n: 0 for n in netlist.nodes}
    for e in netlist.elements:
        if not (e.kind == "R" and e.value == 0):
            for n in e.nodes:
                degree[n] = degree.get(n, 0) + 1
    order = {n: i for i, n in enumerate(netlist.nodes)}
    rank = lambda n: (n == "0", n in prefer, degree.get(n, 0), -order.get(n, 0))      # noqa: E731
    classes = {n: {n} for e in zero for n in e.nodes}
    for e in zero:
        a, b = classes[e.nodes[0]], classes[e.nodes[1]]
        if a is not b:
            a |= b
            for n in b:
                classes[n] = a
    return {n: max(c, key=rank) for n, c in classes.items() if max(c, key=rank) != n}


def file_spice_options(circuit, options: SpiceOptions | None = None) -> SpiceOptions:
    """``options`` where given, else ngspice's settings from the file itself: its ``.options`` RELTOL, ABSTOL and
    METHOD, and its ``.tran`` TMAX as a fraction of its period at its own parameters (a ladder of capacitors
    whose charge transfers last a few RS C asks for finer steps than the default T/200); the defaults for what
    it does not state."""
    if options is not None:
        return options
    given = dict(circuit.netlist.spice_options)
    tmax, p = circuit.netlist.tran.tmax, circuit.resolve({})
    if tmax is not None and circuit.periodic(p):
        given["tmax_fraction"] = min(tmax / circuit.period(p), 0.5)
    return SpiceOptions(**given)


def circuit_netlist(circuit, p: dict, t_end: float, options: SpiceOptions | None = None, x0=None,
                    diode_currents: bool = True, waveforms: dict | None = None, drives: dict | None = None,
                    extra: tuple = ()) -> Netlist:
    """The ngspice netlist of ``circuit`` (a :class:`converters.models.netlist.Circuit`) at parameters ``p`` over
    [0, t_end], started from ``x0`` (the circuit's state vector; default its own initial state). Without
    ``diode_currents`` the diodes have no sense source (their currents, and the modes, are not measured): in a
    capacitor-diode ladder or a capacitor-input bridge the 0 V sources in series with near-ideal diodes stop
    ngspice ("timestep too small" at the commutations), which runs the ladder without them. ``waveforms``:
    sources written with another waveform than the file's ({name: a number (DC) or a Pulse}: a built-in
    converter's gate at the options' edge, or DC at a duty of 0 or 1). ``drives``: sources written as other lines
    ({name: lines}, a control's comparator in place of a gate; the lines are the caller's, every value in them
    formatted by :func:`~netlists.options._num`); ``extra``: lines added after the elements (a load step). The probes: every state, node voltage and sensed current under its SPICE name, the file's output (a
    difference of two nodes where it names one), and ``switch``: the first switch's control against its threshold,
    or in a circuit without switches the first PULSE source at the middle of its levels (on at its first level,
    as the compiled configuration 0)."""
    from converters.circuits.netlist import read_netlist
    options = options or SpiceOptions()
    netlist = read_netlist(circuit.netlist.text, overrides=p, name=circuit.source)
    compiled = circuit.compiled(p)
    T = compiled.period if math.isfinite(compiled.period) else t_end
    x = compiled.x0 if x0 is None else list(x0)
    if len(x) != len(compiled.state_names):
        raise ParameterError(f"x0 must have {len(compiled.state_names)} entries ({', '.join(compiled.state_names)}); "
                             f"got {len(x)}")
    ic = dict(zip(compiled.state_names, (_num(f"x0[{n}]", v) for n, v in zip(compiled.state_names, x))))
    # PySpice stops a run at any line ngspice prints with "error" in it, and ngspice echoes the title ("Circuit:
    # ..."): a title such as "one error amplifier" failed every comparison
    lines = [f"* pcsuite: {re.sub('(?i)error', 'err', circuit.title)}"]
    probes, pairs = {}, []
    shorts = _shorts(netlist, prefer={part.strip() for part in circuit.output[2:-1].split(",")})
    node_of = lambda flat: _node(shorts.get(flat, flat))          # noqa: E731
    for e in netlist.elements:
        n = [node_of(node) for node in e.nodes]
        name = e.kind + _name(e.name)[1:] if _name(e.name)[0].upper() == e.kind else e.kind + "_" + _name(e.name)
        if e.kind == "R" and e.value == 0:        # its nodes are merged (ngspice would make it 1 mohm)
            continue
        if e.kind == "R":
            lines.append(f"{name} {n[0]} {n[1]} {_num(e.name, e.value)}")
        elif e.kind == "C":
            lines.append(f"{name} {n[0]} {n[1]} {_num(e.name, e.value)} IC={ic[f'v({e.name})']}")
            probes[f"v({e.name})"] = ((n[1], -1.0) if n[0] == "0" else (n[0], 1.0) if n[1] == "0"
                                      else ((n[0], n[1]), 1.0))
        elif e.kind == "L":
            sense = f"vsense_{_name(e.name)}"
            inner = f"sense_{_name(e.name)}"          # never a node name that starts with a digit ("0_...")
            lines += [f"{sense} {n[0]} {inner} DC 0",
                      f"{name} {inner} {n[1]} {_num(e.name, e.value)} IC={ic[f'i({e.name})']}"]
            probes[f"i({e.name})"] = (f"{sense}#branch", 1.0)
        elif e.kind == "K":
            a, b = (f"L{_name(c)[1:]}" if _name(c)[0].upper() == "L" else "L_" + _name(c) for c in e.control)
            lines.append(f"{name} {a} {b} {_num(e.name, e.value)}")
        elif e.name in (drives or {}):
            lines += list(drives[e.name])
        elif e.kind in "VI":
            waveform = (waveforms or {}).get(e.name, e.waveform)
            lines.append(f"{name} {n[0]} {n[1]} {_waveform(e.name, waveform)}")
            if e.kind == "V":
                probes[f"i({e.name})"] = (f"{name.lower()}#branch", 1.0)
        elif e.kind in "EG":
            lines.append(f"{name} {n[0]} {n[1]} {n[2]} {n[3]} {_num(e.name, e.value)}")
        elif e.kind in "FH":
            lines.append(f"{name} {n[0]} {n[1]} {_source(e.control[0])} {_num(e.name, e.value)}")
        elif e.kind == "D":
            sense = f"vsense_{_name(e.name)}"
            inner = f"sense_{_name(e.name)}"
            if diode_currents:
                lines += [f"{sense} {n[0]} {inner} DC 0", f"{name} {inner} {n[1]} {_name(e.model)}"]
                probes[f"i({e.name})"] = (f"{sense}#branch", 1.0)
            else:
                lines.append(f"{name} {n[0]} {n[1]} {_name(e.model)}")
            pairs.append(f"i({e.name})")
        elif e.kind == "S":                # no sense source: in series with a switch it stalled ngspice (a Cuk)
            lines.append(f"{name} {n[0]} {n[1]} {n[2]} {n[3]} {_name(e.model)}")
        elif e.kind == "W":            # an S switch on an H transducer of its current (1 V/A): ngspice's own W
            control = f"wctl_{_name(e.name)}"   # stalled at the first diode it turned off (a hysteretic buck)
            lines += [f"H_{_name(e.name)} {control} 0 {_source(e.control[0])} 1",
                      f"S_{_name(e.name)} {n[0]} {n[1]} {control} 0 {_name(e.model)}"]
    for state in compiled.state_names:    # a ramp's, an edged PULSE's or an oscillator's states read on copies of
        kind, _, rest = state.partition("(")     # their sources
        if kind in ("pwl", "pulse", "sin", "cos"):
            e = next(e for e in netlist.elements if e.name == rest[:-1])
            w = (waveforms or {}).get(e.name, e.waveform)
            if kind in ("sin", "cos"):     # e^(-THETA t') sin (and cos: the phase 90 degrees on) of the damped rotation
                w = Sin(0.0, 1.0, w.freq, w.td, w.theta, w.phase + (90.0 if kind == "cos" else 0.0))
            copy = f"{kind}_{_name(e.name)}"
            lines.append(f"V{copy} {copy} 0 {_waveform(e.name, w)}")
            probes[state] = (copy, 1.0)
    lines += list(extra)
    for model in netlist.models.values():
        lines.append(_model(model, options))
    for node in netlist.nodes:
        if node != "0":
            if node_of(node) != "0":          # a node shorted to ground has no vector
                probes.setdefault(f"v({node})", (node_of(node), 1.0))
    switches = [e for e in netlist.elements if e.kind in "SW"]
    if switches:
        s = switches[0]
        model = netlist.models[s.model]
        if s.kind == "S":
            probes["switch"] = ({node_of(s.nodes[2]): 1.0, **({node_of(s.nodes[3]): -1.0} if s.nodes[3] != "0" else {})},
                                model.params.get("VT", 0.0))
        else:
            probes["switch"] = ({f"wctl_{_name(s.name)}": 1.0}, model.params.get("IT", 0.0))
    else:
        pulse = next((e for e in netlist.elements if e.kind == "V" and isinstance(e.waveform, Pulse)), None)
        if pulse is not None:
            w, (a, b) = pulse.waveform, (node_of(node) for node in pulse.nodes)
            sign = 1.0 if w.v1 > w.v2 else -1.0
            probes["switch"] = ({a: sign, **({b: -sign} if b != "0" else {})}, sign * (w.v1 + w.v2) / 2)
    if circuit.output not in probes and "," in circuit.output:
        a, b = (part.strip() for part in circuit.output[2:-1].split(",", 1))
        probes[circuit.output] = ((node_of(a), node_of(b)), 1.0) if b != "0" else (node_of(a), 1.0)
    # a period's fraction (TMAX = T/200 by default), or without a period the file's own .tran step
    tran = netlist.tran
    tmax = options.tmax_fraction * T if math.isfinite(compiled.period) else min(tran.tmax or tran.tstep,
                                                                                 options.tmax_fraction * t_end / 10)
    # RSHUNT: every node a 1e12 ohm path to ground (a bridge's output floats while its diodes block)
    lines += [options_line(options, " RSHUNT=1e12"),
              f".tran {_num('tstep', tmax)} {_num('t_end', t_end)} 0 {_num('tmax', tmax)} UIC", ".end"]
    return Netlist("\n".join(lines) + "\n", circuit.name, dict(p), t_end, options, probes, tuple(pairs) or ("none",))


def _waveform(name: str, w) -> str:
    if isinstance(w, Pulse):
        values = [w.v1, w.v2, w.td, w.tr, w.tf, w.pw, w.per]
        if not math.isfinite(w.per):
            values = values[:-1] if math.isfinite(w.pw) else values[:-2]
        return "PULSE(" + " ".join(_num(f"{name} PULSE", v) for v in values) + ")"
    if isinstance(w, Sin):
        return "SIN(" + " ".join(_num(f"{name} SIN", v) for v in (w.vo, w.va, w.freq, w.td, w.theta, w.phase)) + ")"
    if isinstance(w, Pwl):
        return ("PWL(" + " ".join(_num(f"{name} PWL", v) for point in w.points for v in point) + ")"
                + (" r=0" if w.repeat is not None else ""))
    return f"DC {_num(name, float(w))}"


def _source(control: str) -> str:
    """The name a controlling V source is written under (the element's own, its letter V kept)."""
    return "V" + _name(control)[1:] if _name(control)[0].upper() == "V" else "V_" + _name(control)


def _model(model, options: SpiceOptions) -> str:
    params = dict(model.params)
    if model.kind in ("SW", "CSW"):
        if not params.get("RON"):              # RON = 0 is the ideal switch: ngspice's is near-ideal
            params["RON"] = options.switch_ron
        params.setdefault("ROFF", options.switch_roff)
        if model.kind == "CSW":            # the W switch's S equivalent reads its current as 1 V/A
            params["VT"], params["VH"] = params.pop("IT", 0.0), params.pop("IH", 0.0)
        params.setdefault("VT", 0.0)
        params.setdefault("VH", 0.0)
    elif model.kind == "D":
        if "IS" not in params and "N" not in params:
            params.update(IS=options.diode_is, N=options.diode_n, **({"CJO": options.diode_cjo}
                                                                     if options.diode_cjo else {}))
    text = " ".join(f"{key}={_num(f'.model {model.name} {key}', value)}" for key, value in params.items())
    return f".model {_name(model.name)} {'SW' if model.kind == 'CSW' else model.kind}({text})"


__all__ = ["circuit_netlist"]
