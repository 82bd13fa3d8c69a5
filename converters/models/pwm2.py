"""The three two-state PWM converters (buck, boost, buck-boost) share one parametrised model.

The circuit is its netlist (``netlists/circuits/buck.cir``, ``boost.cir``, ``buck-boost.cir``), compiled into the
LCS (:class:`~.netlist.FromNetlist`). State x = (iL, vC): inductor current (A) and output-capacitor voltage
magnitude (V). One diode, whose port the compiler chooses as one would by hand:
ON:  u = i_D,  y = -v_D (reverse voltage across the ideal diode)
OFF: u = -v_D, y = i_D = iL (the diode is in series with the inductor)
Optional parasitics (0 in the netlist unless given): rL inductor DCR, Ron switch on-resistance, Vf and Rd diode
forward drop and resistance, rC capacitor ESR. The ESR enters through the output node: vout = a vC + b (i_in - Io) with
a = R/(R + rC), b = R rC/(R + rC), where i_in is the current delivered to the output (iL for the buck, i_D
otherwise) and Io a current the load draws beside R (the netlist's Iload, 0 unless set): what :meth:`PWMTwoState.vout` and :meth:`PWMTwoState.output_row` read. The element signals (switch,
diode, capacitor, input) are the netlist's own (:attr:`PWMTwoState.element_signals`)."""
from __future__ import annotations

from typing import TYPE_CHECKING, cast

import numpy as np
import numpy.typing as npt

from ..params import Param, nonnegative, positive
from .base import ON, Converter, power_balance
from .netlist import FromNetlist

if TYPE_CHECKING:
    from ..trajectory import Samples, Trajectory

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
#: A current the load draws beside R (the netlist's Iload: the output impedance's small-signal input).
LOAD = (Param("Io", None, "A", "load current drawn from the output beside R", low=-np.inf, low_open=False),)
#: An open-loop step: the load R -> R_step and/or the input Vin -> Vin_step at t_step.
STEPS = (
    positive("t_step", None, "s", "instant of a load or input step (with R_step and/or Vin_step)"),
    positive("R_step", None, "ohm", "load resistance after t_step"),
    nonnegative("Vin_step", None, "V", "input voltage after t_step"),
)


#: The element signals every two-state converter adds (A and V; device voltages anode-cathode and drain-source).
ELEMENT_SIGNALS = ("i_in", "i_switch", "v_switch", "i_diode", "v_diode", "i_cap")


class PWMTwoState(FromNetlist, Converter):
    """Shared model; subclasses set ``topology`` to 'buck', 'boost' or 'buck-boost' and their netlist."""

    topology: str
    parameters = COMMON + PARASITICS + LOAD + STEPS
    state_names = ("iL", "vC")
    pair_names = ("diode",)
    netlist_states = ("i(l1)", "v(c1)")
    signal_names = ("vout", "switch") + ELEMENT_SIGNALS
    signal_units = {"i_in": "A", "i_switch": "A", "v_switch": "V", "i_diode": "A", "v_diode": "V", "i_cap": "A"}

    #: Each element signal as the netlist names it (devices' voltages anode-cathode and drain-source; the input
    #: current the one the source delivers, the capacitor's the one charging it): set per topology.
    element_signals: dict

    def signal(self, name: str, samples: Samples, p: dict) -> np.ndarray:
        if name in ELEMENT_SIGNALS:
            return self.netlist_signal(self.element_signals[name], samples, p)
        return super().signal(name, samples, p)

    def elements(self, samples: Samples, p: dict) -> dict:
        """Input, switch, diode and capacitor currents and the switch's and diode's voltages: the netlist's own
        signals (:attr:`element_signals`, read on the compiled signal maps: exact with every parasitic, in every
        mode). An ngspice run has no pair variables: its element signals are NaN (not measured), and summaries leave
        them out."""
        return {name: self.netlist_signal(spice, samples, p) for name, spice in self.element_signals.items()}

    def power(self, tr: Trajectory, p: dict, t0: float, t1: float) -> dict:
        """Input and output power, each element's loss and the efficiency over [t0, t1] (W), by the run's own
        quadrature (exact pieces for the event method). On a periodic orbit input = output + losses."""
        rL, Ron, Vf, Rd, rC = (p.get(k, 0.0) for k in ("rL", "Ron", "Vf", "Rd", "rC"))
        mean = lambda name: tr.mean(name, t0=t0, t1=t1)          # noqa: E731
        square = lambda name: tr.rms(name, t0=t0, t1=t1) ** 2     # noqa: E731
        losses = {"rL": lambda: rL * square("iL"), "Ron": lambda: Ron * square("i_switch"),
                  "Vf": lambda: Vf * mean("i_diode"), "Rd": lambda: Rd * square("i_diode"),
                  "rC": lambda: rC * square("i_cap")}
        losses = {k: loss() for k, loss in losses.items() if p.get(k) is not None}     # the parts that are set
        p_in = p["Vin"] * mean("i_in")
        p_out = square("vout") / p["R"] + (p["Io"] * abs(mean("vout")) if p.get("Io") else 0.0)
        return power_balance(p_in, p_out, losses)

    def output_node_current(self, samples: Samples) -> np.ndarray:
        """Current delivered to the output node (A): iL for the buck, the diode current otherwise."""
        if self.topology == "buck":
            return samples.x[:, 0]
        on = np.asarray(samples.config) == ON
        u = cast("npt.NDArray[np.float64]", samples.u)         # the diode's current: a run with its pairs
        return np.where(on, u[:, 0], samples.x[:, 0])

    def output_row(self, p: dict) -> tuple[npt.NDArray[np.float64], float] | None:
        """|vout| as an affine function of the state, (c, d) with |vout| = c . x + d, where it is one: the buck's
        a vC + b iL (its ESR carries the inductor current); the others' vC without ESR. None where vout also
        depends on the diode's current (a boost or buck-boost with ESR): a loop sensing vout is then refused."""
        R, rC = p["R"], p.get("rC", 0.0)
        a, b = R / (R + rC), R * rC / (R + rC)
        if self.topology == "buck":
            return np.array([b, a]), -b * p.get("Io", 0.0)
        return (np.array([0.0, 1.0]), 0.0) if not rC else None

    def vout(self, samples: Samples, p: dict) -> np.ndarray:
        R, rC = p["R"], p.get("rC", 0.0)
        a, b = R / (R + rC), R * rC / (R + rC)
        magnitude = a * samples.x[:, 1]
        if rC:       # the capacitor's current through its ESR: what reaches the output node less what the loads draw
            magnitude = magnitude + b * (self.output_node_current(samples) - p.get("Io", 0.0))
        return -magnitude if self.topology == "buck-boost" else magnitude
