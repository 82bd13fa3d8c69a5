"""The three two-state PWM converters (buck, boost, buck-boost) share one parametrised model.

State x = (iL, vC): inductor current (A) and output-capacitor voltage magnitude (V). One diode:
ON:  u = i_D,  y = -v_D (reverse voltage across the ideal diode)
OFF: u = -v_D, y = i_D = iL (the diode is in series with the inductor)
Optional parasitics (modelled only when given): rL inductor DCR, Ron switch on-resistance, Vf and
Rd diode forward drop and resistance, rC capacitor ESR. The ESR enters through the output node:
vout = a vC + b i_in with a = R/(R + rC), b = R rC/(R + rC), and C vC' = (R i_in - vC)/(R + rC),
where i_in is the current delivered to the output (iL for the buck, i_D otherwise). With every
parasitic zero the matrices are exactly those of REFERENCE section 3.
"""
from __future__ import annotations

import numpy as np

from ..problems import Configuration
from ..params import Param, nonnegative, positive
from .base import ON, Converter

COMMON = (
    nonnegative("Vin", 12.0, "V", "input voltage"),
    positive("L", 10e-6, "H", "inductance"),
    positive("C", 100e-6, "F", "output capacitance"),
    positive("R", 10.0, "ohm", "load resistance"),
    positive("f_sw", 100e3, "Hz", "switching frequency"),
    Param("D", 0.4, "", "duty ratio", low=0.0, high=1.0, low_open=False, high_open=False),
)
PARASITICS = (
    nonnegative("rL", None, "ohm", "inductor DCR"),
    nonnegative("Ron", None, "ohm", "switch on-resistance"),
    nonnegative("Vf", None, "V", "diode forward drop"),
    nonnegative("Rd", None, "ohm", "diode on-resistance"),
    nonnegative("rC", None, "ohm", "capacitor ESR"),
)


class PWMTwoState(Converter):
    """Shared model; subclasses set ``topology`` to 'buck', 'boost' or 'buck-boost'."""

    topology: str
    parameters = COMMON + PARASITICS
    state_names = ("iL", "vC")
    pair_names = ("diode",)
    closed_form = True

    def configurations(self, p):
        Vin, L, C, R = p["Vin"], p["L"], p["C"], p["R"]
        rL, Ron, Vf, Rd, rC = (p.get(k, 0.0) for k in ("rL", "Ron", "Vf", "Rd", "rC"))
        a, b = R / (R + rC), R * rC / (R + rC)
        G = 1.0 / ((R + rC) * C)
        # OFF: the diode carries iL into the output (buck-boost: into |vo|), the switch is open.
        off_E = {"buck": -Vf / L, "boost": (Vin - Vf) / L, "buck-boost": -Vf / L}[self.topology]
        off = Configuration(A=[[-(rL + Rd + b) / L, -a / L], [G * R, -G]], B=[[1.0 / L], [0.0]],
                            C=[[1.0, 0.0]], D=[[0.0]], E=[off_E, 0.0], F=[0.0], name="OFF")
        if self.topology == "buck":
            # ON: the inductor still feeds the output; the diode only sees the switch node.
            on = Configuration(A=[[-(rL + Ron + b) / L, -a / L], [G * R, -G]], B=[[Ron / L], [0.0]],
                               C=[[-Ron, 0.0]], D=[[Ron + Rd]], E=[Vin / L, 0.0], F=[Vin + Vf], name="ON")
        else:
            # ON: the inductor is across the source; the diode current (if any) feeds the output.
            F_on = Vf if self.topology == "boost" else Vin + Vf
            on = Configuration(A=[[-(rL + Ron) / L, 0.0], [0.0, -G]], B=[[Ron / L], [G * R]],
                               C=[[-Ron, a]], D=[[Ron + Rd + b]], E=[Vin / L, 0.0], F=[F_on], name="ON")
        return on, off

    def output_node_current(self, samples):
        """Current delivered to the output node (A): iL for the buck, the diode current otherwise."""
        if self.topology == "buck":
            return samples.x[:, 0]
        on = np.asarray(samples.config) == ON
        return np.where(on, samples.u[:, 0], samples.x[:, 0])

    def vout(self, samples, p):
        R, rC = p["R"], p.get("rC", 0.0)
        a, b = R / (R + rC), R * rC / (R + rC)
        magnitude = a * samples.x[:, 1]
        if rC:
            magnitude = magnitude + b * self.output_node_current(samples)
        return -magnitude if self.topology == "buck-boost" else magnitude
