"""Voltage-mode control with a ramp comparator (Hamill, Deane and Jefferies 1992; Fossas and Olivar 1996): on the
buck, the bifurcation benchmark of switching converters.

A control (:mod:`.control`) around the converter's own circuit (the buck LCS of :mod:`.pwm2`: ideal switch, ideal
diode as a complementarity pair, so DCM can appear; its parasitics, load and input steps as the open-loop
converter's): the control voltage vcon = A (vout - Vref) is compared with a sawtooth ramp from VL to VU over each
period T, and the switch is ON while vcon < ramp, i.e. below zero of the switching function

    s(x, t) = A (vout(x) - Vref) - ramp(t),    ramp(t) = VL + (VU - VL) (t mod T) / T,

vout(x) the converter's output as a function of the state (vC, or a vC + b iL through the buck's ESR).
At every period start the ramp falls back to VL and s jumps up (the switch turns OFF if it was ON);
within the period the rising ramp crosses vcon once, turning the switch ON: the period-1 orbit switches
once per period, OFF then ON. ``latch = 1`` adds the usual one-switching-per-period latch (after its
switching the switch holds until the period ends); without it a second crossing inside the period
switches again. The switching instants depend on the state: the stepper places them inside its step, the
event method exactly, with the ramp's slope in the saltation matrices of the period map.
"""
from __future__ import annotations

import numpy as np

from ..errors import ParameterError
from ..params import Param, positive
from ..problems import Ramp, StateSwitching, SwitchingFunction
from ..trajectory import Samples
from .base import OFF, ON
from .control import Control, Controlled

PARAMETERS = (
    positive("Vref", 11.3, "V", "reference voltage"),
    positive("A", 8.4, "", "amplifier gain of vcon = A (vout - Vref)"),
    Param("VL", 3.8, "V", "ramp low level", low=-np.inf, high=np.inf),
    Param("VU", 8.2, "V", "ramp high level (above VL)", low=-np.inf, high=np.inf),
    Param("latch", 0.0, "", "1: at most one switching per period (a latch), 0: none", low=0.0, high=1.0,
          low_open=False, high_open=False),
)


class VoltageMode(Control):
    """A ramp comparator on the amplified output error (module docstring)."""

    key = "voltage-mode"
    title = "voltage-mode control (ramp comparator)"
    parameters = PARAMETERS
    #: Hamill, Deane and Jefferies' buck (Vin the classic bifurcation parameter, 20 to 36 V).
    plants = {"buck": {"Vin": positive("Vin", 24.0, "V", "input voltage (the classic bifurcation parameter, 20 to 36 V)"),
                       "L": 20e-3, "C": 47e-6, "R": 22.0, "f_sw": 2.5e3}}
    signal_names = ("vcon", "ramp")
    signal_units = {"vcon": "V", "ramp": "V"}
    output_only = True

    def check(self, model: Controlled, p: dict) -> None:
        """A ramp that does not rise, or a latch that is not 0 or 1, is refused."""
        if not p["VU"] > p["VL"]:
            raise ParameterError(f"VU (ramp high level) must be above VL = {p['VL']:g} V; got VU = {p['VU']:g} V")
        if p["latch"] not in (0.0, 1.0):
            raise ParameterError(f"latch must be 0 or 1; got {p['latch']!r}")
        self.sensed(model, p)

    def ramp(self, model: Controlled, p: dict) -> Ramp:
        return Ramp(p["VL"], p["VU"], model.period(p))

    def law(self, model: Controlled, p: dict, initial: int | None = None,
            circuit: dict | None = None) -> StateSwitching:
        c, d = self.sensed(model, p if circuit is None else circuit)
        function = SwitchingFunction(c=p["A"] * c, d=p["A"] * (d - p["Vref"]), ramp=self.ramp(model, p))
        return StateSwitching(function, below=ON, above=OFF, latch=bool(p["latch"]), initial=initial)

    def signal(self, name: str, samples: Samples, p: dict, model: Controlled,
               circuit: dict | None = None) -> np.ndarray:
        if name == "vcon":
            return p["A"] * (np.abs(model.vout(samples, p if circuit is None else circuit)) - p["Vref"])
        return self.ramp(model, p)(samples.t)
