"""The built-in converters' matrices derived by hand (Kirchhoff's laws per switch state, each port chosen as the
diode's current where the network leaves it free and as its voltage where an inductor fixes it), the independent
oracle of the circuits the models compile from their netlists (netlists/circuits/*.cir): :data:`HAND` holds each
converter as a model whose configurations are these, everything else the library's."""
from __future__ import annotations


from converters.models import CONVERTERS
from converters.problems import Configuration


def pwm2(p, topology):
    """Buck, boost, buck-boost: x = (iL, vC); ON u = i_D, OFF u = -v_D; each parasitic only when given."""
    Vin, L, C, R = p["Vin"], p["L"], p["C"], p["R"]
    rL, Ron, Vf, Rd, rC = (p.get(k, 0.0) for k in ("rL", "Ron", "Vf", "Rd", "rC"))
    a, b = R / (R + rC), R * rC / (R + rC)
    G = 1.0 / ((R + rC) * C)
    # OFF: the diode carries iL into the output (buck-boost: into |vo|), the switch is open.
    off_E = {"buck": -Vf / L, "boost": (Vin - Vf) / L, "buck-boost": -Vf / L}[topology]
    off = Configuration(A=[[-(rL + Rd + b) / L, -a / L], [G * R, -G]], B=[[1.0 / L], [0.0]],
                        C=[[1.0, 0.0]], D=[[0.0]], E=[off_E, 0.0], F=[0.0], name="OFF")
    if topology == "buck":
        # ON: the inductor still feeds the output; the diode only sees the switch node.
        on = Configuration(A=[[-(rL + Ron + b) / L, -a / L], [G * R, -G]], B=[[Ron / L], [0.0]],
                           C=[[-Ron, 0.0]], D=[[Ron + Rd]], E=[Vin / L, 0.0], F=[Vin + Vf], name="ON")
    else:
        # ON: the inductor is across the source; the diode current (if any) feeds the output.
        F_on = Vf if topology == "boost" else Vin + Vf
        on = Configuration(A=[[-(rL + Ron) / L, 0.0], [0.0, -G]], B=[[Ron / L], [G * R]],
                           C=[[-Ron, a]], D=[[Ron + Rd + b]], E=[Vin / L, 0.0], F=[F_on], name="ON")
    return on, off


def cuk(p):
    """x = (i1, v1, i2, v2); ON u = i_D, y = v1; OFF u = -v_D, y = i_D = i1 + i2. With parasitics (each only when given): the inductors' DCR rL1, rL2;
    the switch's Ron, through which i_S = i1 + i2 - i_D flows in ON (so y = v1 - Ron i_S + Vf + Rd u); the
    diode's Vf and Rd, across which v_n2 = -u + Vf + Rd (i1 + i2) in OFF."""
    Vin, L1, C1, L2, C2, R = (p[k] for k in ("Vin", "L1", "C1", "L2", "C2", "R"))
    rL1, rL2, Ron, Vf, Rd = (p.get(k, 0.0) for k in ("rL1", "rL2", "Ron", "Vf", "Rd"))
    on = Configuration(
        A=[[-(rL1 + Ron) / L1, 0, -Ron / L1, 0], [0, 0, -1 / C1, 0],
           [-Ron / L2, 1 / L2, -(rL2 + Ron) / L2, -1 / L2], [0, 0, 1 / C2, -1 / (R * C2)]],
        B=[[Ron / L1], [1 / C1], [Ron / L2], [0]], C=[[-Ron, 1, -Ron, 0]], D=[[Ron + Rd]],
        E=[Vin / L1, 0, 0, 0], F=[Vf], name="ON")
    off = Configuration(
        A=[[-(rL1 + Rd) / L1, -1 / L1, -Rd / L1, 0], [1 / C1, 0, 0, 0],
           [-Rd / L2, 0, -(rL2 + Rd) / L2, -1 / L2], [0, 0, 1 / C2, -1 / (R * C2)]],
        B=[[1 / L1], [0], [1 / L2], [0]], C=[[1, 0, 1, 0]], D=[[0]],
        E=[(Vin - Vf) / L1, 0, -Vf / L2, 0], name="OFF")
    return on, off



def prc(p):
    """x = (ir, vr, iLf, vo); u = (i_D1, i_D3, -v_D2, -v_D4), a transformer of ratio n between tank and bridge."""
    Lr, Cr, Lf, Cf, R, n, Vin = (p[k] for k in ("Lr", "Cr", "Lf", "Cf", "R", "n", "Vin"))
    A = [[0, -1 / Lr, 0, 0], [1 / Cr, 0, 0, 0], [0, 0, 0, -1 / Lf], [0, 0, 1 / Cf, -1 / (R * Cf)]]
    B = [[0, 0, 0, 0], [-1 / (n * Cr), 1 / (n * Cr), 0, 0], [0, 0, 1 / Lf, 1 / Lf], [0, 0, 0, 0]]
    C = [[0, -1 / n, 0, 0], [0, 1 / n, 0, 0], [0, 0, 1, 0], [0, 0, 1, 0]]
    D = [[0, 0, 1, 0], [0, 0, 0, 1], [-1, 0, 0, 0], [0, -1, 0, 0]]
    return tuple(Configuration(A=A, B=B, C=C, D=D, E=[sign * Vin / Lr, 0, 0, 0], name=name)
                 for sign, name in ((1.0, "drive+"), (-1.0, "drive-")))



def _hand(converter, configurations):
    """``converter`` (a library model) with its configurations from the hand derivation, its ports the hand's."""
    cls = type(converter)
    currents = ((True, True, False, False),) * 2 if converter.name == "prc" else ((True,), (False,))
    oracle = type(f"Hand{cls.__name__}", (cls,), {"configurations": lambda self, p: configurations(p),
                                                 "pair_currents": currents})
    return oracle()


HAND = {"buck": _hand(CONVERTERS["buck"], lambda p: pwm2(p, "buck")),
        "boost": _hand(CONVERTERS["boost"], lambda p: pwm2(p, "boost")),
        "buck-boost": _hand(CONVERTERS["buck-boost"], lambda p: pwm2(p, "buck-boost")),
        "cuk": _hand(CONVERTERS["cuk"], cuk), "prc": _hand(CONVERTERS["prc"], prc)}
