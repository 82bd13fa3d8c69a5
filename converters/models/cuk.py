"""Cuk converter (inverting), ideal parts: x = (i1, v1, i2, v2) with v1 on the coupling capacitor C1
and v2 = |vo| on C2 (REFERENCE section 3).

ON:  u = i_D, y = v1 (the switch grounds C1's input side; the diode stays off while v1 > 0).
OFF: u = -v_D, y = i_D = i1 + i2. The OFF pair held at y = 0 with i1 = -i2 != 0 is the
generalised DCM (GDCM-OFF); the ON pair held at v1 = 0 is GDCM-ON.
"""
from __future__ import annotations

from ..problems import Configuration
from ..params import Param, nonnegative, positive
from .base import Converter, power_balance
from .pwm2 import STEPS


class Cuk(Converter):
    name = "cuk"
    title = "Cuk (inverting)"
    parameters = (
        nonnegative("Vin", 12.0, "V", "input voltage"),
        positive("L1", 100e-6, "H", "input inductance"),
        positive("C1", 10e-6, "F", "coupling capacitance"),
        positive("L2", 100e-6, "H", "output inductance"),
        positive("C2", 100e-6, "F", "output capacitance"),
        positive("R", 10.0, "ohm", "load resistance"),
        positive("f_sw", 100e3, "Hz", "switching frequency"),
        Param("D", 0.4, "", "duty ratio", low=0.0, high=1.0, low_open=False, high_open=False),
        nonnegative("rL1", None, "ohm", "input inductor DCR"),
        nonnegative("rL2", None, "ohm", "output inductor DCR"),
        *STEPS,
    )
    state_names = ("i1", "v1", "i2", "v2")
    output_state = "v2"
    pair_names = ("diode",)
    closed_form = True
    off_held_label = "GDCM-OFF"

    def configurations(self, p):
        Vin, L1, C1, L2, C2, R = (p[k] for k in ("Vin", "L1", "C1", "L2", "C2", "R"))
        d1, d2 = -p.get("rL1", 0.0) / L1, -p.get("rL2", 0.0) / L2      # the inductors' DCR, when given
        on = Configuration(
            A=[[d1, 0, 0, 0], [0, 0, -1 / C1, 0], [0, 1 / L2, d2, -1 / L2], [0, 0, 1 / C2, -1 / (R * C2)]],
            B=[[0], [1 / C1], [0], [0]], C=[[0, 1, 0, 0]], D=[[0]], E=[Vin / L1, 0, 0, 0], name="ON")
        off = Configuration(
            A=[[d1, -1 / L1, 0, 0], [1 / C1, 0, 0, 0], [0, 0, d2, -1 / L2], [0, 0, 1 / C2, -1 / (R * C2)]],
            B=[[1 / L1], [0], [1 / L2], [0]], C=[[1, 0, 1, 0]], D=[[0]], E=[Vin / L1, 0, 0, 0], name="OFF")
        return on, off

    def power(self, tr, p, t0: float, t1: float) -> dict:
        """Input and output power, the inductors' DCR losses and the efficiency over [t0, t1] (W)."""
        square = lambda name: tr.rms(name, t0=t0, t1=t1) ** 2     # noqa: E731
        losses = {k: p[k] * square(state) for k, state in (("rL1", "i1"), ("rL2", "i2")) if p.get(k) is not None}
        p_in = p["Vin"] * tr.mean("i1", t0=t0, t1=t1)
        p_out = square("vout") / p["R"]
        return power_balance(p_in, p_out, losses)

    def output_node_current(self, samples):
        return samples.x[:, 2]

    def vout(self, samples, p):
        return -samples.x[:, 3]

    @staticmethod
    def effective_inductance(p) -> float:
        return p["L1"] * p["L2"] / (p["L1"] + p["L2"])
