"""Cuk converter (inverting), compiled from ``netlists/circuits/cuk.cir``: x = (i1, v1, i2, v2) with v1 on the
coupling capacitor C1 and v2 = |vo| on C2 (derived: docs/theory.md); parasitics (0 unless given) the inductors' DCR
rL1, rL2, the switch's Ron, the diode's Vf and Rd.

ON:  u = i_D, y = v1 (the switch grounds C1's input side; the diode stays off while v1 > 0).
OFF: u = -v_D, y = i_D = i1 + i2. The OFF pair held at y = 0 with i1 = -i2 != 0 is the
generalised DCM (GDCM-OFF); the ON pair held at v1 = 0 is GDCM-ON.
"""
from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ..params import Param, nonnegative, positive
from .analytic import InvertingRatios
from .base import Converter, power_balance
from .netlist import FromNetlist
from .pwm2 import STEPS

if TYPE_CHECKING:
    from ..trajectory import Samples, Trajectory


class Cuk(InvertingRatios, FromNetlist, Converter):
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
        nonnegative("Ron", None, "ohm", "switch on-resistance"),
        nonnegative("Vf", None, "V", "diode forward drop"),
        nonnegative("Rd", None, "ohm", "diode on-resistance"),
        *STEPS,
    )
    signal_names = ("vout", "switch", "i_in", "i_switch", "i_diode")
    signal_units = {"i_in": "A", "i_switch": "A", "i_diode": "A"}
    state_names = ("i1", "v1", "i2", "v2")
    netlist_file = "cuk.cir"
    netlist_states = ("i(l1)", "v(c1)", "i(l2)", "v(c2)")
    output_state = "v2"
    pair_names = ("diode",)
    closed_form = True
    off_held_label = "GDCM-OFF"

    @staticmethod
    def k_inductance(p: dict) -> float:
        """The closed forms' inductance: the effective Le = L1 L2 / (L1 + L2) (the relations are the buck-boost's)."""
        return p["L1"] * p["L2"] / (p["L1"] + p["L2"])

    #: The switch's and the diode's currents as the netlist names them (read on the compiled signal maps).
    element_signals = {"i_switch": "i(s1)", "i_diode": "i(d1)"}

    def signal(self, name: str, samples: Samples, p: dict) -> np.ndarray:
        if name == "i_in":
            return samples.x[:, 0]
        if name in self.element_signals:
            return self.netlist_signal(self.element_signals[name], samples, p)
        return super().signal(name, samples, p)

    def power(self, tr: Trajectory, p: dict, t0: float, t1: float) -> dict:
        """Input and output power, each parasitic's loss and the efficiency over [t0, t1] (W)."""
        square = lambda name: tr.rms(name, t0=t0, t1=t1) ** 2     # noqa: E731
        losses = {"rL1": lambda: p["rL1"] * square("i1"), "rL2": lambda: p["rL2"] * square("i2"),
                  "Ron": lambda: p["Ron"] * square("i_switch"),
                  "Vf": lambda: p["Vf"] * tr.mean("i_diode", t0=t0, t1=t1), "Rd": lambda: p["Rd"] * square("i_diode")}
        losses = {k: loss() for k, loss in losses.items() if p.get(k) is not None}     # the parts that are set
        p_in = p["Vin"] * tr.mean("i1", t0=t0, t1=t1)
        return power_balance(p_in, square("vout") / p["R"], losses)

    def output_node_current(self, samples: Samples) -> np.ndarray:
        return samples.x[:, 2]

    def vout(self, samples: Samples, p: dict) -> np.ndarray:
        return -samples.x[:, 3]

    @staticmethod
    def effective_inductance(p: dict) -> float:
        return p["L1"] * p["L2"] / (p["L1"] + p["L2"])
