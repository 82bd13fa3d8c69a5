"""The ngspice netlists of the built-in models. A converter's is its own circuit file (``netlists/circuits/NAME.cir``,
what the model compiles) written by :func:`~netlists.circuit.circuit_netlist`; a control's comparator, written here
with behavioural sources, drives the converter's gate in place of its PWM source (the voltage-mode buck). The
sliding-mode boost is its own circuit: its rectifier is a switch in antiphase (:func:`build_smc_netlist` says why).
Nothing typed by a user reaches the text: node and element names are constants here, and every value passes
:func:`_num` (a finite float, printed by us) before it is written. A parameter carrying netlist text
(``R=1\\n.control\\nshell ...``) is refused while it is parsed.

Near-ideal parts (docs/guide/ngspice.md): an ``SW`` switch (Ron 1 mOhm, Roff 1 MOhm) driven by a gate
pulse with edges of 1e-6 T, a diode ``D(IS=1e-14 N=0.001)``, zero-volt sense sources for the
inductor and diode currents. The diode model sets the accuracy floor (about 1 mV of forward drop).
"""
from __future__ import annotations

import re
from dataclasses import replace

from converters.circuits.netlist import Pulse, Pwl
from converters.errors import ParameterError
from converters.models import get_converter
from converters.validate import parse_value

from .circuit import circuit_netlist
from .options import Netlist, SpiceOptions, _num, diode_parameters, options_line


def build_netlist(converter: str, params: dict | None, t_end, options: SpiceOptions | None = None,
                  x0=None) -> Netlist:
    """The ngspice netlist of ``converter`` with validated ``params`` over [0, t_end]: the file the model compiles
    (``netlists/circuits/NAME.cir``) as :func:`converter_netlist` writes it, its gate the model's PWM at the options'
    edge (``edge_fraction`` of T, centred on D T and T, the instants the LCS switches at); a duty ratio of 0 or 1 is
    a DC gate.

    ``x0`` (the converter's state vector, default 0: from rest) becomes the inductor and capacitor
    initial conditions, so both simulators can start on the same periodic orbit.
    """
    conv = get_converter(converter)
    p = conv.resolve(params)
    options = options or SpiceOptions()
    gate = {}
    if "D" in conv.schedule_parameters:          # the model's PWM: on from t = 0 for D T, edges centred on D T and T
        D, T = p["D"], conv.period(p)
        edge = options.edge_fraction * T
        gate[GATE] = (float(D >= 1.0) if not 0.0 < D < 1.0 else
                      Pulse(1.0, 0.0, max(D * T - edge / 2, 0.0), edge, edge, max((1.0 - D) * T - edge, 0.0), T))
    return converter_netlist(conv, p, t_end, options, x0, waveforms=gate)


def converter_netlist(conv, p: dict, t_end, options: SpiceOptions, x0=None, waveforms: dict | None = None,
                      drives: dict | None = None) -> Netlist:
    """A built-in converter's own file at its parameters ``p`` as :func:`~netlists.circuit.circuit_netlist` writes it
    for ngspice (its ideal devices near-ideal, sense sources on the diodes and inductors), its probes also under the
    model's names (the states, ``vout``, ``switch``), with ``waveforms`` or ``drives`` in place of its sources (the
    PWM gate, or a control's comparator) and its load and input steps: the input a PWL from Vin to Vin_step and the
    load a conductance 1/R_step - 1/R switched in parallel by a PWL, each over the options' edge centred on t_step
    (breakpoints of ngspice's step control, where the LCS steps exactly)."""
    t_end = parse_value("t_end", t_end)
    if t_end <= 0:
        raise ParameterError(f"t_end must be positive (> 0 s); got {t_end!r}")
    x0 = [0.0] * len(conv.state_names) if x0 is None else list(x0)
    if len(x0) != len(conv.state_names):
        raise ParameterError(f"x0 must have {len(conv.state_names)} entries ({', '.join(conv.state_names)}); "
                             f"got {len(x0)}")
    state = {spice: parse_value(f"x0[{name}]", value) for name, spice, value in zip(conv.state_names,
                                                                                    conv.netlist_states, x0)}
    circuit = conv.circuit
    values = dict(conv.circuit_values(p))
    if "D" in conv.schedule_parameters:
        values["d"] = 0.5                         # (the file's PULSE is written for 0 < D < 1; it is replaced)
    waveforms, extra = dict(waveforms or {}), []
    if "t_step" in p:
        t, half = p["t_step"], options.edge_fraction * conv.period(p) / 2
        if "Vin_step" in p:
            waveforms[INPUT] = Pwl(((0.0, p["Vin"]), (t - half, p["Vin"]), (t + half, p["Vin_step"])))
        if "R_step" in p:
            out = output_node(circuit)
            extra = [f"Vstep step 0 PWL(0 0 {_num('t_step', t - half)} 0 {_num('t_step', t + half)} 1)",
                     f"Bstep {out} 0 I=V({out})*V(step)*({_num('1/R_step - 1/R', 1 / p['R_step'] - 1 / p['R'])})"]
    circuit_p = circuit.resolve(values)
    compiled = circuit.compiled(circuit_p)
    written = circuit_netlist(circuit, circuit_p, t_end, options, x0=[state[name] for name in compiled.state_names],
                              waveforms=waveforms, drives=drives, extra=tuple(extra))
    probes = dict(written.probes)
    for name, spice in zip(conv.state_names, conv.netlist_states):
        probes[name] = written.probes[spice]
    probes["vout"] = written.probes[circuit.output]
    return Netlist(written.text, conv.name, p, t_end, options, probes, written.pairs)


def output_node(circuit) -> str:
    """The node of a built-in file's output ``v(NODE)``, its load R1 between it and ground."""
    node = circuit.output[2:-1]
    if "," in node:
        raise ParameterError(f"{circuit.source}: a load step needs an output node against ground; the output is "
                             f"{circuit.output}")
    return node


#: The gate source of the built-in PWM converters' files (a duty of 0 or 1 writes it as DC) and their input source.
GATE, INPUT = "vg", "vin"


def build_smc_netlist(params: dict | None, t_end, options: SpiceOptions | None = None, x0=None,
                      rectifier: str = "switch") -> Netlist:
    """The boost under sliding-mode current control (``converters.models.sliding``) as an ngspice netlist.

    The controller is a behavioural source ctrl = Iref - iL driving an SW switch with VT = 0 and
    VH = band: ngspice's switch closes above VT + VH and opens below VT - VH, which is the hysteresis
    comparator of the LCP model. The PI integral is a 1 F capacitor charged by a current Vref - v; the
    load step a behavioural conductance 1/R + (1/R_step - 1/R) u(time - t_step). Every value is a
    validated number (``_num``).

    ``rectifier``: 'switch' (default) is a second SW switch driven in antiphase (switch-as-diode,
    docs/guide/ngspice.md), the ideal diode's behaviour while iL > 0, which this controller keeps
    (iL >= Iref - band). 'diode' uses the D(N = 0.001) diode: with comparator-driven switching ngspice
    then loses or gains energy at every switching event (its steady v moves by -2.4 % with gear,
    +1.8 % with MAXORD = 1, measured) because these events are not breakpoints of its integrator.
    """
    if rectifier not in ("switch", "diode"):
        raise ParameterError(f"rectifier must be 'switch' or 'diode'; got {rectifier!r}")
    from converters.models import get_model
    from converters.models.sliding import iref0, predicted_frequency
    p = get_model("boost", "smc").resolve(params)
    options = options or SpiceOptions(tmax_fraction=1.0 / 200.0)
    t_end = parse_value("t_end", t_end)
    if t_end <= 0:
        raise ParameterError(f"t_end must be positive (> 0 s); got {t_end!r}")
    iL0, v0 = (0.0, p["Vin"]) if x0 is None else (parse_value("x0[iL]", x0[0]), parse_value("x0[vC]", x0[1]))
    # TMAX: a fraction of the predicted switching period (tmax_fraction of 1/f).
    tmax = options.tmax_fraction / predicted_frequency(p)
    vref, i0 = _num("Vref", p["Vref"]), _num("Iref0", iref0(p))
    conductance = f"{_num('1/R', 1.0 / p['R'])}"
    if "t_step" in p:
        conductance += (f"+({_num('1/R_step - 1/R', 1.0 / p['R_step'] - 1.0 / p['R'])})"
                        f"*u(time-{_num('t_step', p['t_step'])})")
    initial = "ON" if iL0 < iref0(p) else "OFF"
    body = [f"Vin in 0 DC {_num('Vin', p['Vin'])}", "Vsl in in_s DC 0",
            f"L1 in_s sw {_num('L', p['L'])} IC={_num('iL0', iL0)}",
            f"S1 sw 0 ctrl 0 SWSMC {initial}", "Vsd sw da DC 0",
            "D1 da out DMOD" if rectifier == "diode" else f"S2 da out 0 ctrl SWSMC {'OFF' if initial == 'ON' else 'ON'}",
            f"C1 out 0 {_num('C', p['C'])} IC={_num('v0', v0)}",
            f"Bload out 0 I=V(out)*({conductance})",
            f"Bint 0 zi I={vref}-V(out)", "Cz zi 0 1 IC=0", "Rz zi 0 1e12",
            f"Bctrl ctrl 0 V=max({i0}+{_num('Kp', p['Kp'])}*({vref}-V(out))+{_num('Ki', p['Ki'])}*V(zi),0)-I(Vsl)",
            f".model SWSMC SW(VT=0 VH={_num('band', p['band'])} RON={_num('switch_ron', options.switch_ron)} "
            f"ROFF={_num('switch_roff', options.switch_roff)})",
            f".model DMOD D({diode_parameters(options)})"]
    lines = ["* pcsuite boost-smc", *body,
             options_line(options),
             f".tran {_num('tstep', tmax)} {_num('t_end', t_end)} 0 {_num('tmax', tmax)} UIC", ".end"]
    # The comparator's switch is closed where the switch node is pulled below half the output.
    probes = {"switch": ({"out": 0.5, "sw": -1.0}, 0.0), "iL": ("vsl#branch", 1.0), "vC": ("out", 1.0),
              "vout": ("out", 1.0), "i_D": ("vsd#branch", 1.0),
              "sw": ("sw", 1.0), "ctrl": ("ctrl", 1.0)}
    return Netlist("\n".join(lines) + "\n", "boost-smc", p, t_end, options, probes)


#: The voltage-mode comparator's gain (1/V) before its tanh saturation (:func:`build_voltage_mode_netlist`).
COMPARATOR_GAIN = 100.0
#: The comparator's output reaches the switch through an RC low-pass of time constant this fraction of T (its
#: resistance COMPARATOR_R): see :func:`build_voltage_mode_netlist`.
COMPARATOR_DELAY_FRACTION = 1e-5
COMPARATOR_R = 1e3


#: The voltage-mode sawtooth's fall time as a fraction of T (not the gate's edge: a comparator, not a PULSE, drives
#: this switch).
RAMP_FALL_FRACTION = 1e-4


def build_voltage_mode_netlist(params: dict | None, t_end, options: SpiceOptions | None = None,
                               x0=None) -> Netlist:
    """The buck under voltage-mode control (``converters.models.voltage_mode``) as an ngspice netlist: the buck's own
    file (:func:`converter_netlist`: its parasitics and steps as the open-loop buck's) with the comparator driving its
    gate in place of the PWM source.

    The sawtooth is a PULSE source rising from VL to VU over T - edge and falling back over the edge
    (edge = ``RAMP_FALL_FRACTION`` T); a behavioural source 1/2 + tanh(G (ramp - A (v_out - Vref))) / 2, G =
    ``COMPARATOR_GAIN``, a comparator's output saturating smoothly between 0 and 1 V, drives the gate (the switch's
    threshold 1/2) through an RC low-pass of time constant ``COMPARATOR_DELAY_FRACTION`` T, so the switch is
    closed while vcon = A (v_out - Vref) is below the ramp: the comparator of the LCS model, v_out the output node
    (behind the ESR where there is one, as the model senses it). Without the saturation ngspice stops with
    "timestep too small" in the first period where the loop takes over (the control voltage swings by tens of
    volts across the switch's threshold); with a hard clip (min/max), or G = 1 to 10, it still stopped so at the
    defaults (Vin = 24 V, t = 3.6 ms). G = 100 runs at 20, 24, 28 and 36 V and settles on the event method's
    period-2 orbit at 28 V; G = 1000 runs at 33 V too but finds period 6 at 28 V (measured). Without the low-pass,
    in the chaotic band (33 V) ngspice stopped at 0.18 s (trouble with the node driving the switch directly). With
    it (measured, 300 periods from rest against the event method's orbit): 1e-5 T runs 0.4 s at 33, 36 and 40 V,
    keeps period 2 at 28 V and at 31 V; 1e-4 T read the 31 V orbit as period 8. The comparator's switchings are not
    breakpoints of ngspice's step control: TMAX = T/1000 keeps their timing error small (``pcsuite bifurcation``
    uses it). There is no latch in the netlist: ``latch = 1`` is refused. Every value is a validated number
    (``_num``).
    """
    from converters.models import get_model
    model = get_model("buck", "voltage-mode")
    p = model.resolve(params)
    if p["latch"]:
        raise ParameterError("latch must be 0 for the ngspice netlist (its comparator drives the switch directly); "
                             f"got latch = {p['latch']:g}")
    options = options or SpiceOptions()
    buck = model.converter
    T = model.period(p)
    edge = RAMP_FALL_FRACTION * T
    gate = next(e for e in buck.circuit.netlist.elements if e.name == GATE).nodes[0]
    out = output_node(buck.circuit)
    drive = [f"Vramp ramp 0 PULSE({_num('VL', p['VL'])} {_num('VU', p['VU'])} 0 {_num('rise', T - edge)} "
             f"{_num('edge', edge)} 0 {_num('T', T)})",
             f"Bctrl craw 0 V=0.5+0.5*tanh({COMPARATOR_GAIN:g}*(V(ramp)-{_num('A', p['A'])}*(V({out})-"
             f"{_num('Vref', p['Vref'])})))",
             f"Rcf craw {gate} {_num('comparator R', COMPARATOR_R)}",
             f"Ccf {gate} 0 {_num('comparator C', COMPARATOR_DELAY_FRACTION * T / COMPARATOR_R)}"]
    written = converter_netlist(buck, model.plant(p), t_end, options, x0, drives={GATE: drive})
    _, rest = written.text.split("\n", 1)
    return replace(written, text=f"* pcsuite: {model.title}, on the built-in buck's circuit\n{rest}",
                   converter="buck-voltage-mode", params=p, probes={**written.probes, "ramp": ("ramp", 1.0)})


#: The clocked latch's clock pulse, as a fraction of T (its set input; the latch holds between pulses).
CLOCK_FRACTION = 1e-3


def _clocked_latch(gate: str, set_expression: str, reset_expression: str, T: float, clock_sets: bool = True,
                   limit: float | None = None) -> list:
    """A clocked SR latch in ngspice driving ``gate``: a switch with hysteresis (VT = 0, VH = 0.5: closed above
    0.5 V, open below -0.5 V, holding in between) on c = clock - reset connects 1 V to the gate. The clock is a
    pulse of CLOCK_FRACTION T at every period start (gated by ``set_expression``, 1 where the law may set the
    latch); ``reset_expression`` rises to 1 where the comparator resets it (a behavioural tanh of gain
    COMPARATOR_GAIN: the switch opens where it passes 1/2, the comparator's own threshold). At a clock edge with the
    reset high, c = 0: the latch holds off (a skipped period), as the LCS's clocked latch. ``clock_sets`` False:
    the mirror image (valley current mode): the clock resets the latch and the comparator, written as
    ``reset_expression`` rising to 1, sets it. ``limit``: a second pulse ``limit`` T into each period resets the
    latch too (a maximum duty ratio)."""
    width = CLOCK_FRACTION * T
    balance = "V(lset)-V(lrst)" if clock_sets else "V(lrst)-V(lset)"
    reset = f"0.5+0.5*tanh({reset_expression})"
    lines = []
    if limit is not None:
        lines = [f"Vlim llim 0 PULSE(0 1 {_num('limit', limit * T)} {_num('clock edge', width / 10)} "
                 f"{_num('clock edge', width / 10)} {_num('clock width', width)} {_num('T', T)})"]
        reset = f"max({reset},V(llim))"
    return lines + [
            f"Vclk clk 0 PULSE(0 1 0 {_num('clock edge', width / 10)} {_num('clock edge', width / 10)} "
            f"{_num('clock width', width)} {_num('T', T)})",
            f"Bset lset 0 V=V(clk)*({set_expression})",
            f"Brst lrst 0 V={reset}",
            f"Blc lcr 0 V={balance}",
            f"Rlc lcr lc {_num('latch R', COMPARATOR_R)}",
            f"Clc lc 0 {_num('latch C', COMPARATOR_DELAY_FRACTION * T / COMPARATOR_R)}",
            "Vone lone 0 DC 1",
            f"Slatch lone {gate} lc 0 LATCHMOD",
            f"Rlatch {gate} 0 1e6",
            ".model LATCHMOD SW(VT=0 VH=0.5 RON=1 ROFF=1e9)"]


def _compensator(model, p: dict, x0: list, out: str) -> tuple:
    """The compensator of a voltage loop (``converters.models.compensator``) in ngspice: each state a 1 F capacitor
    charged by a behavioural current (its row of xc' = Ac xc + Bc (Vref - v_out)), its output ``vc`` a behavioural
    voltage Cc xc + Dc (Vref - v_out). Returns (lines, {state name: node})."""
    from converters.models.compensator import Compensator
    comp = Compensator.of(p)
    Ac, Bc, Cc, Dc = comp.matrices()
    n, m = len(model.converter.state_names), len(Bc)
    if len(x0) != n + m:
        raise ParameterError(f"x0 must have {n + m} entries (the converter's states, then the compensator's); "
                             f"got {len(x0)}")
    error = f"({_num('Vref', p['Vref'])}-abs(V({out})))"
    nodes = [f"xc{i}" for i in range(m)]

    def combination(row, constant: str = "") -> str:
        terms = [f"{_num('compensator', float(a))}*V({node})" for a, node in zip(row, nodes) if a != 0.0]
        return "+".join(terms + ([constant] if constant else [])) or "0"

    lines = []
    for i in range(m):
        source = _num("Bc", float(Bc[i])) + "*" + error
        lines += [f"Bxc{i} 0 {nodes[i]} I={combination(Ac[i], source)}",
                  f"Cxc{i} {nodes[i]} 0 1 IC={_num(f'x0[{n + i}]', x0[n + i])}"]
    lines.append(f"Bvc vc 0 V={combination(Cc, _num('Dc', float(Dc)) + '*' + error)}")
    return lines, dict(zip(comp.states, nodes))


def _gated(model, p: dict, t_end, options: SpiceOptions | None, x0, drive_of) -> Netlist:
    """A two-state converter's own file (:func:`converter_netlist`: its parasitics and steps) with its gate driven
    by a clocked loop: ``drive_of(gate, T, edge, current)`` returns (the loop's lines, its probes), ``current`` the
    inductor's sense current as ngspice reads it, ``edge`` = ``RAMP_FALL_FRACTION`` T the fall of a PULSE sawtooth.
    ``x0``: the converter's states, then the controller's (from the loop's start when None)."""
    options = options or SpiceOptions()
    conv = model.converter
    T = model.period(p)
    n = len(conv.state_names)
    x0 = list(model.loop.x0(model, p) if x0 is None else x0)
    gate = next(e for e in conv.circuit.netlist.elements if e.name == GATE).nodes[0]
    sense, sign = converter_netlist(conv, model.plant(p), t_end, options, x0[:n]).probes["iL"]
    if not sense.endswith("#branch"):
        raise ParameterError(f"the inductor current of {conv.name} has no sense source in its netlist")
    current = f"({_num('sign', sign)}*I({sense[:-len('#branch')]}))"
    drive, probes = drive_of(gate, T, RAMP_FALL_FRACTION * T, current, x0)
    written = converter_netlist(conv, model.plant(p), t_end, options, x0[:n], drives={GATE: drive})
    _, rest = written.text.split("\n", 1)
    return replace(written, text=f"* pcsuite: {model.title}, on the built-in {conv.name}'s circuit\n{rest}",
                   converter=f"{conv.name}-{model.control}", params=p, probes={**written.probes, **probes})


def _sawtooth(name: str, node: str, start: float, end: float, T: float, edge: float) -> str:
    """A PULSE from ``start`` to ``end`` over T - edge, back over ``edge``, every T."""
    return (f"{name} {node} 0 PULSE({_num(name + ' start', start)} {_num(name + ' end', end)} 0 "
            f"{_num('rise', T - edge)} {_num('edge', edge)} 0 {_num('T', T)})")


def build_voltage_loop_netlist(params: dict | None, t_end, options: SpiceOptions | None = None, x0=None,
                               converter: str = "buck") -> Netlist:
    """A two-state converter under voltage-mode control with a compensator (``converters.models.compensator``) as an
    ngspice netlist (:func:`_gated`): the compensator (:func:`_compensator`), the carrier a sawtooth from VL to VU
    (from VU to VL for a leading edge), and the gate a clocked latch (:func:`_clocked_latch`) reset where the
    carrier passes vc (set there, and reset by the clock, for a leading edge)."""
    from converters.models import get_model
    model = get_model(converter, "voltage-loop")
    p = model.resolve(params)

    def drive_of(gate, T, edge, current, x0):
        lines, states = _compensator(model, p, x0, output_node(model.converter.circuit))
        start, end = (p["VU"], p["VL"]) if p["leading"] else (p["VL"], p["VU"])
        lines.append(_sawtooth("Vcarrier", "carrier", start, end, T, edge))
        comparator = "V(vc)-V(carrier)" if p["leading"] else "V(carrier)-V(vc)"
        lines += _clocked_latch(gate, "1", f"{COMPARATOR_GAIN:g}*({comparator})", T, clock_sets=not p["leading"])
        return lines, {"vc": ("vc", 1.0), "carrier": ("carrier", 1.0),
                       **{name: (node, 1.0) for name, node in states.items()}}
    return _gated(model, p, t_end, options, x0, drive_of)


def build_current_loop_netlist(params: dict | None, t_end, options: SpiceOptions | None = None, x0=None,
                               converter: str = "buck") -> Netlist:
    """Peak current mode under an outer voltage loop (``converters.models.current_mode.PeakCurrentLoop``) as an
    ngspice netlist (:func:`_gated`): the compensator (:func:`_compensator`) gives the command vc (read as amperes)
    less the compensation ramp (a sawtooth from 0 to ma (T - edge)); a clocked latch reset where the inductor's
    sense current passes it, and at Dmax T where Dmax < 1."""
    from converters.models import get_model
    model = get_model(converter, "current-loop")
    p = model.resolve(params)

    def drive_of(gate, T, edge, current, x0):
        lines, states = _compensator(model, p, x0, output_node(model.converter.circuit))
        lines += [_sawtooth("Vmramp", "mramp", 0.0, p["ma"] * (T - edge), T, edge), "Bic icmd 0 V=V(vc)-V(mramp)"]
        lines += _clocked_latch(gate, "1", f"{COMPARATOR_GAIN:g}*({current}-V(icmd))", T,
                                limit=p["Dmax"] if p["Dmax"] < 1.0 else None)
        return lines, {"vc": ("vc", 1.0), "icontrol": ("icmd", 1.0),
                       **{name: (node, 1.0) for name, node in states.items()}}
    return _gated(model, p, t_end, options, x0, drive_of)


def build_peak_current_netlist(params: dict | None, t_end, options: SpiceOptions | None = None, x0=None,
                               converter: str = "buck", valley: bool = False) -> Netlist:
    """A two-state converter under peak (or valley) current-mode control (``converters.models.current_mode``) as an
    ngspice netlist (:func:`_gated`): a clocked latch (:func:`_clocked_latch`) reset where the inductor current
    passes the command, a sawtooth falling from Iref to Iref - ma (T - edge), and at Dmax T where Dmax < 1; valley:
    the clock resets the latch, the current falling below Iv + ma t sets it."""
    from converters.models import get_model
    model = get_model(converter, "valley-current" if valley else "peak-current")
    p = model.resolve(params)

    def drive_of(gate, T, edge, current, x0):
        command, slope = (p["Iv"], p["ma"]) if valley else (p["Iref"], -p["ma"])
        comparator = f"V(icmd)-{current}" if valley else f"{current}-V(icmd)"
        limit = p["Dmax"] if not valley and p["Dmax"] < 1.0 else None
        lines = [_sawtooth("Vic", "icmd", command, command + slope * (T - edge), T, edge)]
        lines += _clocked_latch(gate, "1", f"{COMPARATOR_GAIN:g}*({comparator})", T, clock_sets=not valley,
                                limit=limit)
        return lines, {"icontrol": ("icmd", 1.0)}
    return _gated(model, p, t_end, options, x0, drive_of)


#: The netlist writer of each control (model, params, t_end, options, x0) -> Netlist; the implicit relay has none.
CONTROL_NETLISTS = {
    "pwm": lambda model, p, t_end, options, x0: build_netlist(model.name, p, t_end, options, x0=x0),
    "smc": lambda model, p, t_end, options, x0: build_smc_netlist(p, t_end, options, x0=x0),
    "voltage-mode": lambda model, p, t_end, options, x0: build_voltage_mode_netlist(p, t_end, options, x0=x0),
    "voltage-loop": lambda model, p, t_end, options, x0: build_voltage_loop_netlist(p, t_end, options, x0=x0,
                                                                                     converter=model.name),
    "peak-current": lambda model, p, t_end, options, x0: build_peak_current_netlist(p, t_end, options, x0=x0,
                                                                                     converter=model.name),
    "valley-current": lambda model, p, t_end, options, x0: build_peak_current_netlist(
        p, t_end, options, x0=x0, converter=model.name, valley=True),
    "current-loop": lambda model, p, t_end, options, x0: build_current_loop_netlist(p, t_end, options, x0=x0,
                                                                                     converter=model.name),
}


def model_netlist(model, params: dict, t_end, options: SpiceOptions | None = None, x0=None) -> Netlist:
    """The netlist of a model (a converter under its control, or a netlist file's circuit with the file's own
    ngspice settings where ``options`` is not given) with validated ``params``."""
    from converters.models.netlist import Circuit
    if isinstance(model, Circuit):
        from .circuit import circuit_netlist, file_spice_options
        return circuit_netlist(model, params, t_end, file_spice_options(model, options), x0=x0)
    writer = CONTROL_NETLISTS.get(model.control)
    if writer is None:
        raise ParameterError(f"no ngspice netlist for {model.key}: the implicit relay is a time-stepping scheme of "
                             "the LCP stepper only; use --control smc (the hysteresis comparator)")
    return writer(model, params, t_end, options, x0)


#: Periods the standalone netlists measure over (at the end of the run), and the run they make.
MEASURE_PERIODS = 10
STANDARD_PERIODS = 300


def _vector(probe) -> str | None:
    """An ngspice expression of a probe: a node voltage, a difference, or a source's branch current."""
    target, _ = probe
    if isinstance(target, tuple):                  # .meas takes a difference as an expression
        return f"par('v({target[0]})-v({target[1]})')"
    if target.endswith("#branch"):
        return f"i({target[:-len('#branch')]})"
    return f"v({target})"


def standalone(netlist: Netlist, period: float, state_names=(), window_periods: int = MEASURE_PERIODS,
               window: tuple | None = None, output: str = "vout") -> str:
    """The netlist as a file ngspice runs on its own (``ngspice -b FILE.cir``): ``.meas`` of vout's mean and
    peak-to-peak ripple and of each state's mean over the last ``window_periods`` periods, or over ``window``
    (t0, t1) in seconds for a model without a period (the sliding-mode boost: its summary's window); states
    with a negative probe sign are printed as the probe reads them: the comment says so. ``output``: the probe
    measured as vout (a netlist file's output, ``v(out)``); a state named as SPICE names it is measured as
    ``v_c1_mean`` (a .meas name is a word)."""
    t1 = netlist.t_end
    if window is None:
        t0 = max(0.0, t1 - window_periods * period)
        over = f"the last {window_periods} periods"
    else:
        t0, t1 = window
        over = "the summary's window"
    window = f"FROM={_num('t0', t0)} TO={_num('t1', t1)}"
    lines = [f"* ngspice -b this file: .meas over {over} [{t0:.6g}, {t1:.6g}] s",
             f"* parameters: {' '.join(f'{k}={v:g}' for k, v in netlist.params.items())}"]
    if output != "vout":
        lines.append(f"* vout_mean and vout_ripple measure {output}")
    measures = [f".meas tran vout_mean AVG {_vector(netlist.probes[output])} {window}",
                f".meas tran vout_ripple PP {_vector(netlist.probes[output])} {window}"]
    for name in state_names:
        probe = netlist.probes.get(name)
        if probe is None or isinstance(probe[0], tuple):
            continue
        sign = "" if probe[1] > 0 else f"  (pcsuite's {name} = -this)"
        if sign:
            lines.append(f"* {name}_mean is the probe {_vector(probe)}{sign}")
        word = re.sub(r"\W+", "_", name).strip("_")
        measures.append(f".meas tran {word}_mean AVG {_vector(probe)} {window}")
    body = netlist.text.rstrip("\n").split("\n")
    assert body[-1] == ".end"
    return "\n".join([body[0], *lines, *body[1:-1], *measures, ".end"]) + "\n"


def standard_netlist(converter: str) -> str:
    """The standard netlist of a converter (defaults, ``STANDARD_PERIODS`` periods from rest), as ``python -m
    netlists DIR`` writes it."""
    conv = get_converter(converter)
    p = conv.resolve({})
    T = conv.period(p)
    return standalone(build_netlist(conv.name, p, STANDARD_PERIODS * T), T, conv.state_names)
