"""Netlist generation. Nothing typed by a user reaches the text: node and element names are constants
here, and every value passes :func:`_num` (a finite float, printed by us) before it is written. A
parameter carrying netlist text (``R=1\\n.control\\nshell ...``) is refused while it is parsed.

Near-ideal parts (REFERENCE section 7): an ``SW`` switch (Ron 1 mOhm, Roff 1 MOhm) driven by a gate
pulse with edges of 1e-4 T, a diode ``D(IS=1e-14 N=0.001)``, zero-volt sense sources for the
inductor and diode currents. The diode model sets the accuracy floor (about 1 mV of forward drop).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

from converters.errors import ParameterError
from converters.models import get_converter
from converters.validate import parse_value


#: ngspice's default ABSTOL in A.
NGSPICE_ABSTOL = 1e-12


@dataclass(frozen=True)
class SpiceOptions:
    """Transient settings. ``tmax`` defaults to T/200; ``method`` is 'trap' or 'gear'."""

    tmax_fraction: float = 1.0 / 200.0
    reltol: float = 1e-3
    method: str = "gear"
    diode_n: float = 0.001
    diode_is: float = 1e-14
    switch_ron: float = 1e-3
    switch_roff: float = 1e6
    # The gate's edge: ngspice's SW switch changes state at the first time point past its threshold, and where its
    # time points fall inside the edge shifts with the rounding of t from period to period: at 1e-4 T a 48 V ->
    # 12 V buck's switch-on moved by up to ~36 ps, its steady mean wandering between levels 34 ppm apart for
    # thousands of periods (RELTOL and TMAX changed nothing); at 1e-6 T it settles in 90 periods.
    edge_fraction: float = 1e-6
    # ngspice's own ABSTOL (then not written); the power-electronics tolerances (CONVERGENCE_FALLBACK) loosen it.
    abstol: float = NGSPICE_ABSTOL
    # The diodes' junction capacitance CJO in F (0: none, the near-ideal default).
    diode_cjo: float = 0.0

    def __post_init__(self):
        for name in ("tmax_fraction", "reltol", "diode_n", "diode_is", "switch_ron", "switch_roff", "edge_fraction",
                     "abstol", "diode_cjo"):
            value = parse_value(name, getattr(self, name))
            if value < 0 or (value == 0 and name != "diode_cjo"):
                raise ParameterError(f"{name} must be {'non-negative' if name == 'diode_cjo' else 'positive'}; "
                                     f"got {value!r}")
            object.__setattr__(self, name, value)
        if self.method not in ("trap", "gear"):
            raise ParameterError(f"method must be one of trap, gear; got {self.method!r}")


@dataclass(frozen=True)
class Netlist:
    text: str
    converter: str
    params: dict
    t_end: float
    options: SpiceOptions
    # state name -> (vector, sign) or ((vector_a, vector_b), sign) difference, see validation.spice;
    # "switch" -> ({vector: coefficient}, threshold): the switch is on where the combination >= threshold
    probes: dict = field(default_factory=dict)
    #: Probe names of each complementarity pair's device current, in the model's pair order.
    pairs: tuple = ("i_D",)


def _num(name: str, value) -> str:
    """The only way a value enters a netlist: a finite float, formatted here."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        value = parse_value(name, value)
    value = float(value)
    if not math.isfinite(value):
        raise ParameterError(f"{name} must be a finite number for the netlist; got {value!r}")
    return f"{value:.12g}"


def _gate(T: float, D: float, options: SpiceOptions) -> str:
    if D <= 0.0:
        return "Vg gate 0 DC 0"
    if D >= 1.0:
        return "Vg gate 0 DC 1"
    # On from t = 0, as the LCP's period starts: an initial state taken at the start of that period (x0, the
    # periodic orbit) is then consistent with the switch's state. A gate that rose at t = 0 turned the switch on
    # while ngspice's first steps, under UIC, were still settling the conducting diode: 20 kA flowed backwards
    # through it for 1 ns and took 0.1-0.2 V off the boost's capacitor at every start. Each period: off at
    # D T, on at T (both crossings edge / 2 later), on for D T.
    edge = options.edge_fraction * T
    off = max(T - D * T - edge, edge)
    return (f"Vg gate 0 PULSE(1 0 {_num('D T', D * T)} {_num('edge', edge)} {_num('edge', edge)} {_num('off', off)} "
            f"{_num('T', T)})")


def _models(options: SpiceOptions) -> list[str]:
    return [f".model SWMOD SW(VT=0.5 VH=0 RON={_num('switch_ron', options.switch_ron)} "
            f"ROFF={_num('switch_roff', options.switch_roff)})",
            f".model DMOD D({diode_parameters(options)})"]


def diode_parameters(options: SpiceOptions) -> str:
    """The near-ideal diode's ``.model`` parameters: IS, N, and CJO where the options give one."""
    text = f"IS={_num('diode_is', options.diode_is)} N={_num('diode_n', options.diode_n)}"
    return text + (f" CJO={_num('diode_cjo', options.diode_cjo)}" if options.diode_cjo else "")


def options_line(options: SpiceOptions, extra: str = "") -> str:
    """The ``.options`` line every pcsuite netlist carries."""
    abstol = f" ABSTOL={_num('abstol', options.abstol)}" if options.abstol != NGSPICE_ABSTOL else ""
    return f".options RELTOL={_num('reltol', options.reltol)}{abstol} METHOD={options.method} ITL4=100{extra}"


def _diode(anode: str, cathode: str, p: dict) -> list[str]:
    """Sense source, the diode, then the optional forward drop Vf and resistance Rd in series."""
    lines = [f"Vsd {anode} da DC 0"]
    node = "da"
    if p.get("Vf"):
        lines.append(f"Vfwd {node} db DC {_num('Vf', p['Vf'])}")   # potential falls by Vf along the diode
        node = "db"
    if p.get("Rd"):
        lines.append(f"Rd {node} dc {_num('Rd', p['Rd'])}")
        node = "dc"
    lines.append(f"D1 {node} {cathode} DMOD")
    return lines


def _inductor(a: str, b: str, p: dict, name="L1", value_key="L", sense="Vsl", dcr_key="rL", ic=0.0) -> list[str]:
    lines = [f"{sense} {a} {a}_s DC 0"]
    node = f"{a}_s"
    if p.get(dcr_key):
        lines.append(f"R{name} {node} {a}_r {_num(dcr_key, p[dcr_key])}")
        node = f"{a}_r"
    lines.append(f"{name} {node} {b} {_num(value_key, p[value_key])} IC={_num(name + ' initial current', ic)}")
    return lines


def _plate(a: str, p: dict, esr_key="rC") -> str:
    """The node of the capacitor's own plate on side ``a`` (:func:`_capacitor`): behind its ESR when it has one,
    where the capacitor voltage is read (the terminal ``a`` is the output, ESR drop included)."""
    return f"{a}_esr" if p.get(esr_key) else a


def _capacitor(a: str, b: str, p: dict, name="C1", value_key="C", esr_key="rC", ic=0.0) -> list[str]:
    ic_text = _num(name + " initial voltage", ic)
    if p.get(esr_key):
        return [f"R{name} {a} {a}_esr {_num(esr_key, p[esr_key])}",
                f"{name} {a}_esr {b} {_num(value_key, p[value_key])} IC={ic_text}"]
    return [f"{name} {a} {b} {_num(value_key, p[value_key])} IC={ic_text}"]


def build_netlist(converter: str, params: dict | None, t_end, options: SpiceOptions | None = None,
                  x0=None) -> Netlist:
    """The ngspice netlist of ``converter`` with validated ``params`` over [0, t_end].

    ``x0`` (the converter's state vector, default 0: from rest) becomes the inductor and capacitor
    initial conditions, so both simulators can start on the same periodic orbit.
    """
    conv = get_converter(converter)
    p = conv.resolve(params)
    options = options or SpiceOptions()
    t_end = parse_value("t_end", t_end)
    if t_end <= 0:
        raise ParameterError(f"t_end must be positive (> 0 s); got {t_end!r}")
    T = conv.period(p)
    if p.get("Ron"):
        options = SpiceOptions(**{**options.__dict__, "switch_ron": p["Ron"]})
    x0 = [0.0] * len(conv.state_names) if x0 is None else list(x0)
    if len(x0) != len(conv.state_names):
        raise ParameterError(f"x0 must have {len(conv.state_names)} entries ({', '.join(conv.state_names)}); "
                             f"got {len(x0)}")
    ic = {name: parse_value(f"x0[{name}]", value) for name, value in zip(conv.state_names, x0)}
    body, probes = _BODIES[conv.name](p, T, options, ic)
    probes.setdefault("switch", ({"gate": 1.0}, 0.5))
    tmax = options.tmax_fraction * T
    lines = [f"* pcsuite {conv.name}", *body, *_models(options),
             options_line(options),
             f".tran {_num('tstep', tmax)} {_num('t_end', t_end)} 0 {_num('tmax', tmax)} UIC", ".end"]
    pairs = tuple(f"i_{name}" if f"i_{name}" in probes else "i_D" for name in conv.pair_names)
    return Netlist("\n".join(lines) + "\n", conv.name, p, t_end, options, probes, pairs)


def _buck(p, T, o, ic):
    body = [f"Vin in 0 DC {_num('Vin', p['Vin'])}", _gate(T, p["D"], o), "S1 in sw gate 0 SWMOD",
            *_diode("0", "sw", p), *_inductor("sw", "out", p, ic=ic["iL"]), *_capacitor("out", "0", p, ic=ic["vC"]),
            f"R1 out 0 {_num('R', p['R'])}"]
    return body, {"iL": ("vsl#branch", 1.0), "vC": (_plate("out", p), 1.0), "vout": ("out", 1.0),
                  "i_D": ("vsd#branch", 1.0)}


def _boost(p, T, o, ic):
    body = [f"Vin in 0 DC {_num('Vin', p['Vin'])}", _gate(T, p["D"], o), *_inductor("in", "sw", p, ic=ic["iL"]),
            "S1 sw 0 gate 0 SWMOD", *_diode("sw", "out", p), *_capacitor("out", "0", p, ic=ic["vC"]),
            f"R1 out 0 {_num('R', p['R'])}"]
    return body, {"iL": ("vsl#branch", 1.0), "vC": (_plate("out", p), 1.0), "vout": ("out", 1.0),
                  "i_D": ("vsd#branch", 1.0)}


def _buck_boost(p, T, o, ic):
    body = [f"Vin in 0 DC {_num('Vin', p['Vin'])}", _gate(T, p["D"], o), "S1 in sw gate 0 SWMOD",
            *_inductor("sw", "0", p, ic=ic["iL"]), *_diode("out", "sw", p),
            *_capacitor("out", "0", p, ic=0.0 - ic["vC"]), f"R1 out 0 {_num('R', p['R'])}"]
    # the output is negative: the capacitor's plate on the output side carries -vC
    return body, {"iL": ("vsl#branch", 1.0), "vC": (_plate("out", p), -1.0), "vout": ("out", 1.0),
                  "i_D": ("vsd#branch", 1.0)}


def _cuk(p, T, o, ic):
    body = [f"Vin in 0 DC {_num('Vin', p['Vin'])}", _gate(T, p["D"], o),
            *_inductor("in", "n1", p, name="L1", value_key="L1", sense="Vsl1", dcr_key="rL1", ic=ic["i1"]),
            "S1 n1 0 gate 0 SWMOD", *_capacitor("n1", "n2", p, name="C1", value_key="C1", ic=ic["v1"]),
            *_diode("n2", "0", p),
            *_inductor("out", "n2", p, name="L2", value_key="L2", sense="Vsl2", dcr_key="rL2", ic=ic["i2"]),
            *_capacitor("0", "out", p, name="C2", value_key="C2", ic=ic["v2"]), f"R1 out 0 {_num('R', p['R'])}"]
    return body, {"i1": ("vsl1#branch", 1.0), "v1": (("n1", "n2"), 1.0), "i2": ("vsl2#branch", 1.0),
                  "v2": ("out", -1.0), "vout": ("out", 1.0), "i_D": ("vsd#branch", 1.0)}


#: The PRC's square-wave source's edge as a fraction of T: a voltage source switching the resonant tank, not a
#: gate; at 1e-6 T ngspice stopped (timestep too small on a bridge diode).
DRIVE_EDGE_FRACTION = 1e-4


def _prc(p, T, o, ic):
    if p["n"] != 1.0:
        raise ParameterError(f"n (transformer ratio) must be 1 for the ngspice netlist; got {p['n']!r}")
    edge = DRIVE_EDGE_FRACTION * T
    vin = _num("Vin", p["Vin"])
    drive = (f"Vdr drv 0 PULSE({vin} -{vin} {_num('half', T / 2 - edge / 2)} {_num('edge', edge)} "
             f"{_num('edge', edge)} {_num('width', T / 2 - edge)} {_num('T', T)})")
    # Bridge: top tank node a, bottom 0; D1 a->p, D3 0->p, D2 n->a, D4 n->0 (p, n: rectifier output).
    body = [drive, *_inductor("drv", "a", p, name="Lr", value_key="Lr", sense="Vslr", ic=ic["ir"]),
            *_capacitor("a", "0", p, name="Cr", value_key="Cr", ic=ic["vr"]),
            # Each diode behind a zero-volt sense source (its current is a probe).
            "Vsd1 a d1 DC 0", "D1 d1 p DMOD", "Vsd3 0 d3 DC 0", "D3 d3 p DMOD",
            "Vsd2 nn d2 DC 0", "D2 d2 a DMOD", "Vsd4 nn d4 DC 0", "D4 d4 0 DMOD",
            *_inductor("p", "out", p, name="Lf", value_key="Lf", sense="Vslf", ic=ic["iLf"]),
            *_capacitor("out", "nn", p, name="Cf", value_key="Cf", ic=ic["vo"]), f"R1 out nn {_num('R', p['R'])}",
            "Rgnd nn 0 1e9"]
    return body, {"switch": ({"drv": 1.0}, 0.0), "ir": ("vslr#branch", 1.0), "vr": ("a", 1.0), "iLf": ("vslf#branch", 1.0),
                  "vo": (("out", "nn"), 1.0), "vout": (("out", "nn"), 1.0),
                  **{f"i_D{i}": (f"vsd{i}#branch", 1.0) for i in range(1, 5)}}


_BODIES = {"buck": _buck, "boost": _boost, "buck-boost": _buck_boost, "cuk": _cuk, "prc": _prc}


def build_smc_netlist(params: dict | None, t_end, options: SpiceOptions | None = None, x0=None,
                      rectifier: str = "switch") -> Netlist:
    """The boost under sliding-mode current control (``converters.models.sliding``) as an ngspice netlist.

    The controller is a behavioural source ctrl = Iref - iL driving an SW switch with VT = 0 and
    VH = band: ngspice's switch closes above VT + VH and opens below VT - VH, which is the hysteresis
    comparator of the LCP model. The PI integral is a 1 F capacitor charged by a current Vref - v; the
    load step a behavioural conductance 1/R + (1/R_step - 1/R) u(time - t_step). Every value is a
    validated number (``_num``).

    ``rectifier``: 'switch' (default) is a second SW switch driven in antiphase (switch-as-diode,
    REFERENCE section 7), the ideal diode's behaviour while iL > 0, which this controller keeps
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
    """The buck under voltage-mode control (``converters.models.voltage_mode``) as an ngspice netlist.

    The sawtooth is a PULSE source rising from VL to VU over T - edge and falling back over the edge
    (edge = ``RAMP_FALL_FRACTION`` T, what the measurements below were made with); a behavioural source ctrl = tanh(G (ramp - A (v_out - Vref))), G =
    ``COMPARATOR_GAIN``, a comparator's output saturating smoothly at +-1 V, drives an SW switch with VT = 0
    and no hysteresis through an RC low-pass of time constant ``COMPARATOR_DELAY_FRACTION`` T, so the switch is
    closed while vcon = A (v_out - Vref) is below the ramp: the comparator of the LCS model. Without the
    saturation ngspice stops with "timestep too small" in the first period where the loop takes over (the
    control voltage swings by tens of volts across the switch's threshold); with a hard clip at +-1 V
    (min/max), or G = 1 to 10, it still stopped so at the defaults (Vin = 24 V, t = 3.6 ms). G = 100 runs at 20,
    24, 28 and 36 V and settles on the event method's period-2 orbit at 28 V; G = 1000 runs at 33 V too but finds
    period 6 at 28 V (measured). Without the low-pass, in the chaotic band (33 V) ngspice stopped at 0.18 s
    (trouble with node ctrl, the source driving the switch directly). With it (measured, 300 periods from rest
    against the event method's orbit): 1e-5 T runs 0.4 s at 33, 36 and 40 V, keeps period 2 at 28 V (1.8e-5,
    2.7e-5 without) and at 31 V (1.7e-5); 1e-4 T read the 31 V orbit as period 8; 1e-6 T was 3e-5 and 5.5e-5.
    The diode is
    the D(N = 0.001) model (it may block: DCM). The comparator's switchings are not breakpoints of
    ngspice's step control: TMAX = T/1000 keeps their timing error small (``pcsuite bifurcation`` uses it).
    There is no latch in the netlist: ``latch = 1`` is refused. Every value is a validated number (``_num``).
    """
    from converters.models import get_model
    p = get_model("buck", "voltage-mode").resolve(params)
    if p["latch"]:
        raise ParameterError("latch must be 0 for the ngspice netlist (its comparator drives the switch directly); "
                             f"got latch = {p['latch']:g}")
    options = options or SpiceOptions()
    t_end = parse_value("t_end", t_end)
    if t_end <= 0:
        raise ParameterError(f"t_end must be positive (> 0 s); got {t_end!r}")
    iL0, v0 = (0.0, 0.0) if x0 is None else (parse_value("x0[iL]", x0[0]), parse_value("x0[vC]", x0[1]))
    T = 1.0 / p["f_sw"]
    edge = RAMP_FALL_FRACTION * T
    tmax = options.tmax_fraction * T
    body = [f"Vin in 0 DC {_num('Vin', p['Vin'])}",
            f"Vramp ramp 0 PULSE({_num('VL', p['VL'])} {_num('VU', p['VU'])} 0 {_num('rise', T - edge)} "
            f"{_num('edge', edge)} 0 {_num('T', T)})",
            f"Bctrl craw 0 V=tanh({COMPARATOR_GAIN:g}*(V(ramp)-{_num('A', p['A'])}*(V(out)-{_num('Vref', p['Vref'])})))",
            f"Rcf craw ctrl {_num('comparator R', COMPARATOR_R)}",
            f"Ccf ctrl 0 {_num('comparator C', COMPARATOR_DELAY_FRACTION * T / COMPARATOR_R)}",
            "S1 in sw ctrl 0 SWVM", *_diode("0", "sw", p), *_inductor("sw", "out", p, ic=iL0),
            *_capacitor("out", "0", p, ic=v0), f"R1 out 0 {_num('R', p['R'])}",
            f".model SWVM SW(VT=0 VH=0 RON={_num('switch_ron', options.switch_ron)} "
            f"ROFF={_num('switch_roff', options.switch_roff)})",
            f".model DMOD D({diode_parameters(options)})"]
    lines = ["* pcsuite buck voltage-mode", *body,
             options_line(options),
             f".tran {_num('tstep', tmax)} {_num('t_end', t_end)} 0 {_num('tmax', tmax)} UIC", ".end"]
    probes = {"switch": ({"ctrl": 1.0}, 0.0), "iL": ("vsl#branch", 1.0), "vC": ("out", 1.0), "vout": ("out", 1.0),
              "i_D": ("vsd#branch", 1.0), "ramp": ("ramp", 1.0)}
    return Netlist("\n".join(lines) + "\n", "buck-voltage-mode", p, t_end, options, probes)


def model_netlist(model, params: dict, t_end, options: SpiceOptions | None = None, x0=None) -> Netlist:
    """The netlist of a model (a converter under its control) with validated ``params``."""
    if model.control == "pwm":
        return build_netlist(model.name, params, t_end, options, x0=x0)
    if model.control == "smc":
        return build_smc_netlist(params, t_end, options, x0=x0)
    if model.control == "voltage-mode":
        return build_voltage_mode_netlist(params, t_end, options, x0=x0)
    raise ParameterError(f"no ngspice netlist for {model.key}: the implicit relay is a time-stepping scheme of "
                         "the LCP stepper only; use --control smc (the hysteresis comparator)")


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
               window: tuple | None = None) -> str:
    """The netlist as a file ngspice runs on its own (``ngspice -b FILE.cir``): ``.meas`` of vout's mean and
    peak-to-peak ripple and of each state's mean over the last ``window_periods`` periods, or over ``window``
    (t0, t1) in seconds for a model without a period (the sliding-mode boost: its summary's window); states
    with a negative probe sign are printed as the probe reads them: the comment says so."""
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
    measures = [f".meas tran vout_mean AVG {_vector(netlist.probes['vout'])} {window}",
                f".meas tran vout_ripple PP {_vector(netlist.probes['vout'])} {window}"]
    for name in state_names:
        probe = netlist.probes.get(name)
        if probe is None or isinstance(probe[0], tuple):
            continue
        sign = "" if probe[1] > 0 else f"  (pcsuite's {name} = -this)"
        if sign:
            lines.append(f"* {name}_mean is the probe {_vector(probe)}{sign}")
        measures.append(f".meas tran {name}_mean AVG {_vector(probe)} {window}")
    body = netlist.text.rstrip("\n").split("\n")
    assert body[-1] == ".end"
    return "\n".join([body[0], *lines, *body[1:-1], *measures, ".end"]) + "\n"


def standard_netlist(converter: str) -> str:
    """The standard netlist of a converter (defaults, ``STANDARD_PERIODS`` periods from rest), as shipped in
    ``netlists/<converter>.cir``."""
    conv = get_converter(converter)
    p = conv.resolve({})
    T = conv.period(p)
    return standalone(build_netlist(conv.name, p, STANDARD_PERIODS * T), T, conv.state_names)
