"""Voltage-mode control with a compensator: the error amplifier's transfer function (an integrator, PI, type II or
type III) drives a trailing-edge PWM, its states appended to the converter's.

The error e = Vref - vout passes through

    Gc(s) = wi / s  (1 + s/wz1) (1 + s/wz2) / ((1 + s/wp1) (1 + s/wp2))

(type III; type II without the second zero and pole, -p fz2=0 -p fp2=0; PI: wi (1 + s/wz1) / s; I: wi / s), and its
output vc is
compared with a carrier rising from VL to VU over each period: the switch turns on at the clock and off where the
carrier reaches vc (a clocked latch: trailing-edge modulation, duty ratio (vc - VL) / (VU - VL)); with -p leading=1
the carrier falls from VU to VL, the clock turns the switch off and the carrier meeting vc turns it on (leading
edge, the same duty ratio). The compensator
is realised as an integrator and one first-order section per zero-pole pair, z' = wp (y - z), y+ = (wp/wz) y +
(1 - wp/wz) z: every state is a voltage of the amplifier's scale (a companion form's would span wp^2/wi), so the
event method's exact flows and Newton's tolerance see them alike. The design by the k-factor method (Venable 1983)
from the exact control-to-output response is :func:`converters.analysis.smallsignal.design_compensator`.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
import numpy.typing as npt

from ..errors import ParameterError
from ..params import Param, positive
from ..problems import Configuration, Ramp, StateSwitching, SwitchingFunction
from ..trajectory import Samples
from .base import OFF, ON, Converter
from .control import Control, Controlled


def _hz(name: str, default: float, doc: str) -> Param:
    return Param(name, default, "Hz", f"{doc}; 0: none", low=0.0, low_open=False)


#: The defaults: the type III that `pcsuite bode buck --control voltage-loop --design fc=10k,pm=60` designs for the
#: default buck (12 V to 5 V, 100 uH, 100 uF, 10 ohm, 100 kHz): crossover 9.62 kHz, phase margin 60.0 degrees.
PARAMETERS = (
    positive("Vref", 5.0, "V", "output voltage reference"),
    Param("VL", 0.0, "V", "carrier low level", low=-np.inf, high=np.inf),
    Param("VU", 1.0, "V", "carrier high level (above VL)", low=-np.inf, high=np.inf),
    positive("wi", 3716.39, "rad/s", "the compensator's integrator gain (Gc = wi/s at low frequency)"),
    _hz("fz1", 1358.07, "first zero (PI, type II, type III)"),
    _hz("fz2", 1358.07, "second zero (type III)"),
    _hz("fp1", 73633.7, "first pole (type II, type III)"),
    _hz("fp2", 73633.7, "second pole (type III)"),
    Param("leading", 0.0, "", "1: leading-edge modulation (the clock turns the switch off, a carrier falling from VU "
                              "to VL meets vc and turns it on); 0: trailing edge", low=0.0, high=1.0, low_open=False,
          high_open=False),
)


@dataclass(frozen=True)
class Compensator:
    """wi / s times one lead-lag (1 + s/wz) / (1 + s/wp) per (zero, pole) pair, and a PI's zero without a pole."""

    wi: float
    zeros: tuple = ()
    poles: tuple = ()

    def __post_init__(self) -> None:
        if len(self.zeros) not in (len(self.poles), len(self.poles) + 1) or (len(self.zeros) > len(self.poles)
                                                                              and self.poles):
            raise ParameterError(f"a compensator has as many zeros as poles (type II, III) or one zero and no pole "
                                 f"(PI); got zeros {list(self.zeros)} Hz and poles {list(self.poles)} Hz")

    @classmethod
    def of(cls, p: dict) -> "Compensator":
        zeros = tuple(p[k] for k in ("fz1", "fz2") if p.get(k))          # 0 (or unset): none
        poles = tuple(p[k] for k in ("fp1", "fp2") if p.get(k))
        return cls(p["wi"], zeros, poles)

    @property
    def kind(self) -> str:
        return {(0, 0): "I", (1, 0): "PI", (1, 1): "type II", (2, 2): "type III"}.get(
            (len(self.zeros), len(self.poles)), f"{len(self.zeros)} zeros, {len(self.poles)} poles")

    @property
    def states(self) -> tuple[str, ...]:
        return ("x_int",) + tuple(f"x_lead{i + 1}" for i in range(len(self.poles)))

    def matrices(self) -> tuple:
        """(Ac, Bc, Cc, Dc): xc' = Ac xc + Bc e, vc = Cc xc + Dc e."""
        m = 1 + len(self.poles)
        Ac, Bc = np.zeros((m, m)), np.zeros(m)
        Bc[0] = self.wi
        row = np.eye(m)[0]                         # y: the integrator's output, then each section's
        for i, (fz, fp) in enumerate(zip(self.zeros, self.poles), start=1):
            wz, wp = 2 * math.pi * fz, 2 * math.pi * fp
            Ac[i] = wp * (row - np.eye(m)[i])
            row = (wp / wz) * row + (1 - wp / wz) * np.eye(m)[i]
        direct = self.wi / (2 * math.pi * self.zeros[0]) if len(self.zeros) > len(self.poles) else 0.0
        return Ac, Bc, row, direct

    def transfer(self, f: npt.ArrayLike) -> np.ndarray:
        """Gc at frequencies f (Hz)."""
        s = 2j * math.pi * np.asarray(f, dtype=float)
        out = self.wi / s
        for fz in self.zeros:
            out = out * (1 + s / (2 * math.pi * fz))
        for fp in self.poles:
            out = out / (1 + s / (2 * math.pi * fp))
        return out

    def components(self, ri: float) -> dict:
        """The op-amp circuit that realises Gc (ohm and farad), for an input resistor ``ri``: the amplifier inverting,
        its non-inverting input at Vref, so that vc - Vref = (Zf/Zi) (Vref - vout) for an ideal amplifier. Zi: Ri from
        vout to the inverting input, beside Rc + Cc in series (type III's second zero and pole); Zf: Ca + Rz in series
        (the integrator and the first zero), beside Cb (the first pole), from the inverting input to the output.
        Then wi = 1/(Ri (Ca + Cb)), wz1 = 1/(Rz Ca), wp1 = (Ca + Cb)/(Rz Ca Cb), wz2 = 1/((Ri + Rc) Cc) and
        wp2 = 1/(Rc Cc) (H. D. Venable's type II and III amplifiers); a PI has no Cb, an integrator Ca alone.
        ``netlists/circuits/voltage-loop-buck.cir`` writes these expressions in its ``.param`` lines."""
        if not ri > 0.0:
            raise ParameterError(f"ri (the compensator's input resistor) must be above 0 ohm; got {ri!r}")
        for fz, fp in zip(self.zeros, self.poles):
            if not fp > fz:
                raise ParameterError(f"an op-amp type II or III places each pole above its zero; got a zero at {fz:g} "
                                     f"Hz and a pole at {fp:g} Hz")
        total = 1.0 / (self.wi * ri)                                  # Ca + Cb
        out = {"Ri": ri, "Ca": total}
        if self.zeros:
            wz1 = 2 * math.pi * self.zeros[0]
            if self.poles:
                out["Cb"] = total * self.zeros[0] / self.poles[0]
                out["Ca"] = total - out["Cb"]
            out["Rz"] = 1.0 / (wz1 * out["Ca"])
        if len(self.poles) == 2:
            wz2, wp2 = 2 * math.pi * self.zeros[1], 2 * math.pi * self.poles[1]
            out["Cc"] = (1.0 / wz2 - 1.0 / wp2) / ri
            out["Rc"] = 1.0 / (wp2 * out["Cc"])
        return out

    def as_dict(self) -> dict:
        """The control's parameters: wi, fz1, fz2, fp1, fp2 (0: a zero or pole it does not have)."""
        zeros, poles = list(self.zeros) + [0.0] * (2 - len(self.zeros)), list(self.poles) + [0.0] * (2 - len(self.poles))
        return {"wi": self.wi, "fz1": zeros[0], "fz2": zeros[1], "fp1": poles[0], "fp2": poles[1]}


def _with_compensator(c: Configuration, sensed: np.ndarray, offset: float, vref: float,
                      comp: Compensator) -> Configuration:
    """The configuration with the compensator's states appended: xc' = Ac xc + Bc (Vref - vout), vout = sensed . x +
    offset."""
    Ac, Bc, _, _ = comp.matrices()
    n, m = c.n, Ac.shape[0]
    A = np.zeros((n + m, n + m))
    A[:n, :n], A[n:, n:] = c.A, Ac
    A[n:, :n] = -np.outer(Bc, sensed)
    E = np.concatenate([np.asarray(c.E, dtype=float), Bc * (vref - offset)])
    return replace(c, A=A, B=np.vstack([c.B, np.zeros((m, c.k))]), C=np.hstack([c.C, np.zeros((c.k, m))]), E=E)


def ccm_duty(converter: Converter, vout: float, vin: float) -> float | None:
    """The duty ratio that gives |vout| from vin in CCM by the converter's closed form (None without one)."""
    closed = getattr(converter, "ccm_duty", None)
    return closed(abs(vout) / vin) if closed is not None and vin > 0 else None


class CompensatedLoop:
    """What a compensator on Vref - vout (:class:`Compensator`, its parameters ``wi``, ``fz1``, ...) adds to a
    control: its states, appended to the circuit's (a voltage loop's, or a current-mode controller's outer loop)."""

    def check(self, model: Controlled, p: dict) -> None:
        Compensator.of(p)
        self.sensed(model, p)

    def controller_states(self, p: dict) -> tuple[str, ...]:
        return Compensator.of(p).states

    def augment(self, configurations: tuple, p: dict, model: Controlled) -> tuple:
        c, d = self.sensed(model, p)
        comp = Compensator.of(p)
        return tuple(_with_compensator(config, c, d, p["Vref"], comp) for config in configurations)


class VoltageLoop(CompensatedLoop, Control):
    """Trailing-edge PWM of a compensator's output (module docstring)."""

    key = "voltage-loop"
    title = "voltage-mode control with a compensator (I, PI, type II or III)"
    parameters = PARAMETERS
    #: The two-state converters, with an inductance that keeps the default load in CCM.
    plants = {"buck": {"L": 100e-6}, "boost": {"L": 100e-6}, "buck-boost": {"L": 100e-6}}
    signal_names = ("vc", "carrier")
    signal_units = {"vc": "V", "carrier": "V"}

    def check(self, model: Controlled, p: dict) -> None:
        if not p["VU"] > p["VL"]:
            raise ParameterError(f"VU (carrier high level) must be above VL = {p['VL']:g} V; got VU = {p['VU']:g} V")
        if p["leading"] not in (0.0, 1.0):
            raise ParameterError(f"leading must be 0 (trailing edge) or 1 (leading edge); got {p['leading']!r}")
        super().check(model, p)

    def x0(self, model: Controlled, p: dict) -> np.ndarray:
        """The start of a run when none is given: the output capacitor at Vref, the inductor current 0, and the
        compensator's states at the carrier's level of the duty ratio that gives Vref in CCM (the converter's
        closed form where it has one, else 1/2). From rest the compensator would sit at the carrier's foot: no
        switching, and a period map whose integrator has its multiplier at 1, where Newton cannot start."""
        converter = model.converter
        duty = ccm_duty(converter, p["Vref"], p["Vin"]) or 0.5
        x = np.zeros(len(converter.state_names))
        x[converter.state_names.index(converter.output_state)] = p["Vref"]
        return np.concatenate([x, np.full(len(Compensator.of(p).states), p["VL"] + duty * (p["VU"] - p["VL"]))])

    def law(self, model: Controlled, p: dict, initial: int | None = None,
            circuit: dict | None = None) -> StateSwitching:
        """Trailing edge: s = carrier - vc, ON below zero, vc = Cc xc + Dc (Vref - vout), the carrier VL + (VU - VL)
        (t mod T) / T (entering s = c x + d - ramp as a falling ramp -VL .. -VU). Leading edge: s = vc - carrier,
        the carrier falling from VU to VL, OFF below zero (the clock turns the switch off, the crossing on)."""
        sensed, offset = self.sensed(model, p if circuit is None else circuit)
        _, _, Cc, Dc = Compensator.of(p).matrices()
        c = np.concatenate([Dc * np.asarray(sensed, dtype=float), -Cc])
        d = -Dc * (p["Vref"] - offset)
        T = model.period(p)
        if p["leading"]:
            function = SwitchingFunction(c=-c, d=-d - p["VU"], ramp=Ramp(0.0, -(p["VU"] - p["VL"]), T))
            return StateSwitching(function, below=OFF, above=ON, latch=True, clocked=True, initial=initial)
        function = SwitchingFunction(c=c, d=d, ramp=Ramp(-p["VL"], -p["VU"], T))
        return StateSwitching(function, below=ON, above=OFF, latch=True, clocked=True, initial=initial)

    def signal(self, name: str, samples: Samples, p: dict, model: Controlled,
               circuit: dict | None = None) -> np.ndarray:
        """``vc``: the compensator's output (V); ``carrier``: the PWM carrier (V)."""
        t = np.asarray(samples.t, dtype=float)
        if name == "carrier":
            rising = np.mod(t, model.period(p)) / model.period(p)
            return p["VL"] + (p["VU"] - p["VL"]) * (1.0 - rising if p["leading"] else rising)
        _, _, Cc, Dc = Compensator.of(p).matrices()
        n = len(model.converter.state_names)
        vout = np.abs(model.vout(samples, p if circuit is None else circuit))
        return np.asarray(samples.x)[:, n:] @ Cc + Dc * (p["Vref"] - vout)
