"""The voltage-mode controlled buck (Hamill, Deane and Jefferies 1992; Fossas and Olivar 1996): the
bifurcation benchmark of switching converters.

The buck LCS of :mod:`.pwm2` (ideal switch, ideal diode as a complementarity pair, so DCM can appear)
under a state-driven law: the control voltage vcon = A (vC - Vref) is compared with a sawtooth ramp
from VL to VU over each period T, and the switch is ON while vcon < ramp, i.e. below zero of the
switching function

    s(x, t) = A (vC - Vref) - ramp(t),    ramp(t) = VL + (VU - VL) (t mod T) / T.

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
from ..problems import LCSProblem, Ramp, StateSwitching, SwitchingFunction
from ..trajectory import Samples
from .base import OFF, ON, Model
from .buck import Buck

PARAMETERS = (
    positive("Vin", 24.0, "V", "input voltage (the classic bifurcation parameter, 20 to 36 V)"),
    positive("L", 20e-3, "H", "inductance"),
    positive("C", 47e-6, "F", "output capacitance"),
    positive("R", 22.0, "ohm", "load resistance"),
    positive("f_sw", 2.5e3, "Hz", "ramp (clock) frequency, 1/T"),
    positive("Vref", 11.3, "V", "reference voltage"),
    positive("A", 8.4, "", "amplifier gain of vcon = A (vC - Vref)"),
    Param("VL", 3.8, "V", "ramp low level", low=-np.inf, high=np.inf),
    Param("VU", 8.2, "V", "ramp high level (above VL)", low=-np.inf, high=np.inf),
    Param("latch", 0.0, "", "1: at most one switching per period (a latch), 0: none", low=0.0, high=1.0,
          low_open=False, high_open=False),
)


class BuckVoltageMode(Model):
    """The buck under voltage-mode PWM control (a ramp comparator), with its diode."""

    name = "buck"
    control = "voltage-mode"
    title = "buck, voltage-mode control (ramp comparator)"
    parameters = PARAMETERS
    state_names = ("iL", "vC")
    pair_names = ("diode",)
    signal_names = ("vout", "switch", "vcon", "ramp")

    def resolve(self, given: dict | None = None) -> dict:
        """Validated parameters; a ramp that does not rise, or a latch that is not 0 or 1, is refused."""
        p = super().resolve(given)
        if not p["VU"] > p["VL"]:
            raise ParameterError(f"VU (ramp high level) must be above VL = {p['VL']:g} V; got VU = {p['VU']:g} V")
        if p["latch"] not in (0.0, 1.0):
            raise ParameterError(f"latch must be 0 or 1; got {p['latch']!r}")
        return p

    def period(self, p: dict) -> float:
        return 1.0 / p["f_sw"]

    def configurations(self, p: dict):
        buck = Buck()
        return buck.configurations(buck.resolve({"Vin": p["Vin"], "L": p["L"], "C": p["C"], "R": p["R"],
                                                 "f_sw": p["f_sw"]}))

    def switching_law(self, p: dict, initial: int | None = None) -> StateSwitching:
        function = SwitchingFunction(c=[0.0, p["A"]], d=-p["A"] * p["Vref"],
                                     ramp=Ramp(p["VL"], p["VU"], self.period(p)))
        return StateSwitching(function, below=ON, above=OFF, latch=bool(p["latch"]), initial=initial)

    def problem(self, p: dict, t_end: float, x0=None, t_start: float = 0.0, initial: int | None = None) -> LCSProblem:
        """From x0 (default: at rest) over [t_start, t_end]."""
        x0 = np.zeros(2) if x0 is None else x0
        return LCSProblem(self.configurations(p), self.switching_law(p, initial), x0=x0, t_span=(t_start, t_end),
                          state_names=self.state_names, pair_names=self.pair_names,
                          metadata={"converter": self.key, **p})

    def signal(self, name: str, samples: Samples, p: dict) -> np.ndarray:
        if name == "vcon":
            return p["A"] * (samples.x[:, 1] - p["Vref"])
        if name == "ramp":
            return Ramp(p["VL"], p["VU"], self.period(p))(samples.t)
        return super().signal(name, samples, p)

    def vout(self, samples: Samples, p: dict) -> np.ndarray:
        return samples.x[:, 1]
