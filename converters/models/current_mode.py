"""Peak and valley current-mode control. Peak: a clock turns the switch on at every period start, the inductor
current reaching the control current minus a compensation ramp turns it off (Ridley 1991, "A new, continuous-time
model for current-mode control"; Deane and Hamill 1990 for its period doubling). Valley: the clock turns it off,
the current falling to the command plus the ramp turns it on (the mirror image: unstable without compensation
below D = 1/2).

A control (:mod:`.control`) around a two-state converter's circuit (its parasitics, load and input steps). With the
command Iref (A) and the compensation ramp's slope ma (A/s) the switching function is

    s(x, t) = iL - (Iref - ma (t mod T)),

the switch ON below zero; latched (one switching per period): after the turn-off it stays off until the clock,
and at the clock it turns on where iL is below Iref (a period whose current starts above the command is skipped).
A period in which the current never reaches the command keeps the switch on throughout (duty ratio 1). Without
compensation the period-1 orbit of the CCM buck loses stability near D = 0.5, where the off-slope m2 meets the
on-slope m1 (an inductor-current perturbation is multiplied by -m2/m1 each period); a ramp of half the off-slope
keeps it stable to any duty ratio. Exact in the event method (the crossings and saltation matrices with the
ramp's slope), located inside the step in the stepper.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..params import Param, nonnegative, positive
from ..problems import Ramp, StateSwitching, SwitchingFunction
from ..trajectory import Samples
from .base import OFF, ON
from .compensator import PARAMETERS as VOLTAGE_LOOP, CompensatedLoop, Compensator, ccm_duty
from .control import Control, Controlled

#: The maximum duty ratio: the switch turns off at Dmax T where the current has not reached the command (1: none).
DMAX = Param("Dmax", 1.0, "", "maximum duty ratio (the switch turns off at Dmax T at the latest; 1: no limit)",
             low=0.0, high=1.0, low_open=True, high_open=False)
PARAMETERS = (
    positive("Iref", 0.5, "A", "peak current command (the inductor current that turns the switch off)"),
    nonnegative("ma", 0.0, "A/s", "slope compensation: the command falls by ma per second of each period"),
    DMAX,
)


def _limit(p: dict) -> float | None:
    return p["Dmax"] if p.get("Dmax", 1.0) < 1.0 else None


class PeakCurrent(Control):
    """A clocked turn-on and a turn-off on the inductor current (module docstring)."""

    key = "peak-current"
    title = "peak current-mode control"
    parameters = PARAMETERS
    #: The two-state converters, with an inductance that keeps the default load in CCM (100 uH) and, for the boost
    #: and buck-boost, a load their default command can drive (40 ohm: at 10 ohm the boost's input current without
    #: switching, Vin/R = 1.2 A, is above the 0.5 A command and every period is skipped).
    plants = {"buck": {"L": 100e-6}, "boost": {"L": 100e-6, "R": 40.0}, "buck-boost": {"L": 100e-6, "R": 40.0}}
    signal_names = ("icontrol",)
    signal_units = {"icontrol": "A"}

    def law(self, model: Controlled, p: dict, initial: int | None = None,
            circuit: dict | None = None) -> StateSwitching:
        c = np.zeros(len(model.converter.state_names))
        c[model.converter.state_names.index("iL")] = 1.0
        T = model.period(p)
        # s = iL - Iref + ma (t mod T): the law's ramp (subtracted) falls from 0 to -ma T over each period
        function = SwitchingFunction(c=c, d=-p["Iref"], ramp=Ramp(0.0, -p["ma"] * T, T))
        return StateSwitching(function, below=ON, above=OFF, latch=True, clocked=True, initial=initial, limit=_limit(p))

    def x0(self, model: Controlled, p: dict) -> np.ndarray:
        """The start of a run when none is given: the capacitor discharged, the inductor current half the command
        (from rest a boost's current may not reach a command above Vin T / L in the first period: the switch then
        stays on, and the period map has a multiplier at 1 there, which Newton shooting cannot start from)."""
        x0 = np.zeros(len(model.converter.state_names))
        x0[model.converter.state_names.index("iL")] = 0.5 * p["Iref"]
        return x0

    def signal(self, name: str, samples: Samples, p: dict, model: Controlled,
               circuit: dict | None = None) -> np.ndarray:
        """``icontrol``: the command with its compensation ramp, Iref - ma (t mod T) (A)."""
        return p["Iref"] - p["ma"] * np.mod(np.asarray(samples.t, dtype=float), model.period(p))


VALLEY_PARAMETERS = (
    positive("Iv", 0.5, "A", "valley current command (the inductor current that turns the switch on; the default "
                             "buck's orbit is stable above D = 1/2 without compensation: Iv > 0.45 A)"),
    nonnegative("ma", 0.0, "A/s", "slope compensation: the command rises by ma per second of each period"),
)


class ValleyCurrent(PeakCurrent):
    """A clocked turn-off and a turn-on where the inductor current falls to Iv + ma (t mod T): s = Iv + ma (t mod
    T) - iL, the switch OFF below zero, the clocked latch's one switching per period to ON."""

    key = "valley-current"
    title = "valley current-mode control"
    parameters = VALLEY_PARAMETERS

    def law(self, model: Controlled, p: dict, initial: int | None = None,
            circuit: dict | None = None) -> StateSwitching:
        c = np.zeros(len(model.converter.state_names))
        c[model.converter.state_names.index("iL")] = -1.0
        T = model.period(p)
        function = SwitchingFunction(c=c, d=p["Iv"], ramp=Ramp(0.0, -p["ma"] * T, T))
        return StateSwitching(function, below=OFF, above=ON, latch=True, clocked=True, initial=initial)

    def x0(self, model: Controlled, p: dict) -> np.ndarray:
        """The capacitor discharged, the inductor current twice the command (the clock's turn-off then the
        comparator's turn-on within the first period)."""
        x0 = np.zeros(len(model.converter.state_names))
        x0[model.converter.state_names.index("iL")] = 2.0 * p["Iv"]
        return x0

    def signal(self, name: str, samples: Samples, p: dict, model: Controlled,
               circuit: dict | None = None) -> np.ndarray:
        """``icontrol``: the command with its compensation ramp, Iv + ma (t mod T) (A)."""
        return p["Iv"] + p["ma"] * np.mod(np.asarray(samples.t, dtype=float), model.period(p))


def _loop_parameters() -> tuple[Param, ...]:
    kept = {q.name: q for q in VOLTAGE_LOOP}
    return (kept["Vref"],
            nonnegative("ma", 0.0, "A/s", "slope compensation: the command falls by ma per second of each period"),
            DMAX,
            replace(kept["wi"], default=2.0e4), replace(kept["fz1"], default=2.0e3), replace(kept["fz2"], default=0.0),
            replace(kept["fp1"], default=0.0), replace(kept["fp2"], default=0.0))


class PeakCurrentLoop(CompensatedLoop, PeakCurrent):
    """Peak current mode under an outer voltage loop: the command is a compensator's output (I, PI, type II or III
    on Vref - vout, as :class:`~.compensator.VoltageLoop`'s, read as amperes: a current sense of 1 V/A), s = iL -
    vc + ma (t mod T), the clocked latch of peak current mode."""

    key = "current-loop"
    title = "peak current-mode control under an outer voltage loop"

    # a property where Control has a class attribute: read alike, but mypy refuses the override
    @property
    def parameters(self) -> tuple[Param, ...]:  # type: ignore[override]
        return _loop_parameters()

    def x0(self, model: Controlled, p: dict) -> np.ndarray:
        """The output capacitor at Vref, the inductor current 0, the compensator's states (the command) at the
        inductor current the load needs at Vref in CCM: Vref / R for a buck, the input current P / Vin for a
        boost, input and output current for a buck-boost (the converter's ``ccm_ratio`` tells which: its output
        current over (1 - D) where it is not the buck's D)."""
        converter = model.converter
        x = np.zeros(len(converter.state_names))
        x[converter.state_names.index(converter.output_state)] = p["Vref"]
        current = p["Vref"] / p["R"]
        ratio = getattr(converter, "ccm_ratio", None)
        duty = ccm_duty(converter, p["Vref"], p["Vin"])
        if duty is not None and abs(ratio(0.5) - 0.5) > 1e-12:       # not a buck: the inductor carries Iout/(1 - D)
            current = current / (1 - duty)
        return np.concatenate([x, np.full(len(Compensator.of(p).states), current)])

    def law(self, model: Controlled, p: dict, initial: int | None = None,
            circuit: dict | None = None) -> StateSwitching:
        sensed, offset = self.sensed(model, p if circuit is None else circuit)
        _, _, Cc, Dc = Compensator.of(p).matrices()
        n = len(model.converter.state_names)
        c = np.zeros(n)
        c[model.converter.state_names.index("iL")] = 1.0
        c = np.concatenate([c + Dc * np.asarray(sensed, dtype=float), -Cc])
        T = model.period(p)
        function = SwitchingFunction(c=c, d=-Dc * (p["Vref"] - offset), ramp=Ramp(0.0, -p["ma"] * T, T))
        return StateSwitching(function, below=ON, above=OFF, latch=True, clocked=True, initial=initial, limit=_limit(p))

    def signal(self, name: str, samples: Samples, p: dict, model: Controlled,
               circuit: dict | None = None) -> np.ndarray:
        """``icontrol``: the compensator's command less the compensation ramp (A)."""
        _, _, Cc, Dc = Compensator.of(p).matrices()
        n = len(model.converter.state_names)
        vout = np.abs(model.vout(samples, p if circuit is None else circuit))
        command = np.asarray(samples.x)[:, n:] @ Cc + Dc * (p["Vref"] - vout)
        return command - p["ma"] * np.mod(np.asarray(samples.t, dtype=float), model.period(p))
