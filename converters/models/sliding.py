"""Sliding-mode (indirect current) control of the boost converter (Sira-Ramirez 1987; Utkin 1992).

A control (:mod:`.control`) around the boost's own circuit (the LCS of :mod:`.pwm2`: ideal switch, ideal diode as
a complementarity pair) with a switching law on the sliding variable

    sigma = iL - Iref,   Iref = Iref0 + Kp (Vref - vC) + Ki z,   z' = Vref - vC,   Iref0 = Vref^2 / (R Vin)

(the integrator state z is added only when Ki > 0; Iref0 uses the nominal R). sigma is affine in the
state, so both laws of :mod:`converters.problems.switching` apply as they are:

* ``smc`` (hysteresis): ON (configuration 0) when sigma falls below -band, OFF when it rises above
  +band: a :class:`StateSwitching`. The stepper locates each switching inside its step; the event
  method exactly. Switching frequency f = Vin (v - Vin) / (2 band L v).
* ``smc-implicit`` (chattering-free): the :class:`Relay` between OFF (z = 0) and ON (z = 1) on sigma,
  imposed at each step's end: one LCP of size 3 per step; z settles at 1 - Vin / v.

Sliding exists only for Vref > Vin (the equivalent control 1 - Vin / v must lie in (0, 1)).
A load step (R -> R_step at t_step) splits the run in two phases; the switch state carries over, and the
controller keeps its design values (Iref0 at the nominal R).
"""
from __future__ import annotations

from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np

from ..errors import ParameterError
from ..params import nonnegative, positive
from ..problems import Configuration, Relay, StateSwitching, SwitchingFunction
from ..trajectory import Samples
from .base import OFF, ON
from .control import Control, Controlled

if TYPE_CHECKING:
    from ..trajectory import Trajectory

PARAMETERS = (
    positive("Vref", 20.0, "V", "output voltage reference (must exceed Vin)"),
    positive("band", 0.05, "A", "hysteresis half-band on the current error"),
    nonnegative("Kp", 0.0, "A/V", "outer PI loop: proportional gain"),
    nonnegative("Ki", 0.0, "A/(V s)", "outer PI loop: integral gain"),
)


def iref0(p: dict) -> float:
    return p["Vref"] ** 2 / (p["R"] * p["Vin"])


def predicted_frequency(p: dict, v: float | None = None) -> float:
    """f = Vin (v - Vin) / (2 band L v) (the hysteresis band's switching frequency), at v = Vref unless given."""
    v = p["Vref"] if v is None else v
    return p["Vin"] * (v - p["Vin"]) / (2.0 * p["band"] * p["L"] * v)


class SlidingMode(Control):
    """Sliding-mode current control: the hysteresis comparator (``smc``) or the implicit relay."""

    parameters = PARAMETERS
    plants = {"boost": {"Vin": positive("Vin", 10.0, "V", "input voltage"), "L": 1e-3, "C": 100e-6, "R": 40.0}}
    keeps = ("Vin", "L", "C", "R", "t_step", "R_step")
    sets = ("D", "f_sw")
    signal_names = ("iref",)
    signal_units = {"iref": "A"}

    def __init__(self, implicit: bool = False):
        self.implicit = implicit
        self.key = "smc-implicit" if implicit else "smc"
        self.title = ("sliding-mode current control, implicit relay" if implicit
                      else "sliding-mode current control, hysteresis")

    def controller_states(self, p: dict) -> tuple:
        return ("z",) if p["Ki"] > 0.0 else ()

    def check(self, model: Controlled, p: dict) -> None:
        """A request where sliding cannot exist is refused."""
        if p["Vref"] <= p["Vin"]:
            raise ParameterError(f"Vref must be above Vin = {p['Vin']:g} V for a boost under sliding-mode control "
                                 f"(sliding on i = Iref needs the equivalent control 1 - Vin/v in (0, 1)); "
                                 f"got Vref = {p['Vref']:g} V")
        if ("t_step" in p) != ("R_step" in p):
            raise ParameterError("t_step and R_step go together (the load steps from R to R_step at t_step); "
                                 f"got only {'t_step' if 't_step' in p else 'R_step'}")

    def period(self, model: Controlled, p: dict) -> float:
        """The predicted switching period 1/f at v = Vref (the law itself has no clock)."""
        return 1.0 / predicted_frequency(p)

    def periodic(self, p: dict) -> bool:
        return False

    def default_h(self, model: Controlled, p: dict) -> float:
        """Hysteresis: 1/500 of the shorter of t_on = 2 band L / Vin, t_off = 2 band L / (Vref - Vin).
        Implicit: 1 us bounded by 1/200 of sqrt(L C) (no switching to resolve)."""
        if self.implicit:
            return min(1e-6, np.sqrt(p["L"] * p["C"]) / 200.0)
        t_on = 2.0 * p["band"] * p["L"] / p["Vin"]
        t_off = 2.0 * p["band"] * p["L"] / (p["Vref"] - p["Vin"])
        return min(t_on, t_off) / 500.0

    def max_h(self, model: Controlled, p: dict) -> float:
        """Largest step accepted: 1/20 of the shorter switching interval (hysteresis), 200 default steps
        (implicit)."""
        return self.default_h(model, p) * (200.0 if self.implicit else 25.0)

    def augment(self, configurations: tuple, p: dict, model: Controlled) -> tuple:
        """With Ki > 0 the PI integral z' = Vref - vout as a third state."""
        if p["Ki"] <= 0.0:
            return configurations
        c, _ = self.sensed(model, p)
        return tuple(_with_integrator(config, c[:config.n], p["Vref"]) for config in configurations)

    def x0(self, model: Controlled, p: dict) -> np.ndarray:
        """iL = 0, vC = Vin: the state a boost reaches at power-up through its diode (z = 0)."""
        return np.array([0.0, p["Vin"]] + [0.0] * (p["Ki"] > 0.0))

    def sliding_function(self, model: Controlled, p: dict, circuit: dict | None = None) -> SwitchingFunction:
        """sigma = iL - Iref0 - Kp (Vref - vout) - Ki z, affine in the state (vout sensed on the circuit in
        force; Iref0 at the design values)."""
        c, d = self.sensed(model, p if circuit is None else circuit)
        n = len(model.converter.state_names)
        row = np.zeros(n)
        row[0] = 1.0
        row = row + p["Kp"] * c[:n]
        if p["Ki"] > 0.0:
            row = np.append(row, -p["Ki"])
        return SwitchingFunction(c=list(row), d=-(iref0(p) + p["Kp"] * (p["Vref"] - d)))

    def law(self, model: Controlled, p: dict, initial: int | None = None,
            circuit: dict | None = None) -> Relay | StateSwitching:
        function = self.sliding_function(model, p, circuit)
        return (Relay(function, low=OFF, high=ON) if self.implicit
                else StateSwitching(function, below=ON, above=OFF, band=p["band"], initial=initial))

    def signal(self, name: str, samples: Samples, p: dict, model: Controlled,
               circuit: dict | None = None) -> np.ndarray:
        x = samples.x
        integral = p["Ki"] * x[:, 2] if x.shape[1] > 2 else 0.0
        sensed = np.abs(model.vout(samples, p if circuit is None else circuit))
        return iref0(p) + p["Kp"] * (p["Vref"] - sensed) + integral

    def window_start(self, model: Controlled, p: dict, t_start: float, t_end: float,
                     window_s: float | None = None) -> float:
        """Where the summary's window begins: ``window_s`` (default min(a quarter of the run, 2 ms)) before the
        end, and not before a load step (standalone netlists measure over the same window)."""
        t0 = t_end - (window_s or min(0.25 * (t_end - t_start), 2e-3))
        if "t_step" in p and p["t_step"] < t_end:
            t0 = max(t0, p["t_step"])
        return t0

    def summary_from(self, model: Controlled, p: dict, t_start: float, t_end: float) -> float:
        """The window, the window before it (the accuracy check's transient), and from the load step on (the
        recovery time)."""
        window = t_end - self.window_start(model, p, t_start, t_end)
        start = t_end - 2 * window
        return max(t_start, min(start, p["t_step"]) if "t_step" in p else start)

    def summary(self, model: Controlled, tr: Trajectory, p: dict, window_s: float | None = None) -> dict:
        """Measures over the last ``window_s`` (default min(T_end / 4, 2 ms), after the load step): mean vout
        against Vref, every state's and signal's mean, RMS, min, max and ripple (``measurements``); hysteresis: the
        switching frequency against the prediction at the measured v; implicit: the blend z against 1 - Vin / v
        and its spread; with a load step the recovery time."""
        t_end = tr.t[-1]
        t0 = self.window_start(model, p, tr.t[0], t_end, window_s)
        out = {"vout_mean": tr.mean("vout", t0=t0), "vref": p["Vref"], "window_s": [t0, t_end],
               "measurements": tr.measurement_rows(t0=t0, t1=t_end)}
        if self.implicit:
            lam = 1.0 - tr.signal("switch", tr.rows_between(t0, t_end))
            out.update(lambda_mean=float(lam.mean()), lambda_spread=float(lam.max() - lam.min()),
                       vin_over_v=p["Vin"] / out["vout_mean"])
        else:
            out["switching_frequency_Hz"] = switching_frequency(tr, t0)
            out["predicted_frequency_Hz"] = predicted_frequency(p, out["vout_mean"])
        if "t_step" in p:
            out["recovery_time_s"] = recovery_time(tr.t, tr.signal("vout"), p["Vref"], p["t_step"])
        return out


def switching_frequency(tr: Trajectory, t0: float, t1: float | None = None, config: int = ON) -> float:
    """Switchings into ``config`` (default: the switch closing) per second between the first and the last
    one in [t0, t1]: from the trajectory's switching events (located inside the step, or exactly), or, for
    a measured run without events (ngspice), where its switch signal rises through 1/2."""
    t1 = tr.t[-1] if t1 is None else t1
    events = tr.events
    if "config" in events and (events["kind"] == "switch").any():
        times = events.loc[(events["kind"] == "switch") & (events["config"] == config), "time"].to_numpy()
    else:
        on = tr.signal("switch") >= 0.5
        if config != ON:
            on = ~on
        times = tr.t[np.flatnonzero(on[1:] & ~on[:-1]) + 1]
    times = times[(times >= t0) & (times <= t1)]
    return float((times.size - 1) / (times[-1] - times[0])) if times.size >= 2 else 0.0


def _with_integrator(c: Configuration, sensed: np.ndarray, vref: float) -> Configuration:
    """The configuration with z' = Vref - vout appended, vout = sensed . x (the circuit's state)."""
    n = c.n
    A = np.zeros((n + 1, n + 1))
    A[:n, :n] = c.A
    A[n, :n] = -np.asarray(sensed)
    return replace(c, A=A, B=np.vstack([c.B, np.zeros((1, c.k))]), C=np.hstack([c.C, np.zeros((c.k, 1))]),
                   E=np.append(c.E, vref))


def recovery_time(t: np.ndarray, v: np.ndarray, vref: float, t_event: float, tol: float = 0.01) -> float:
    """Time after t_event from which |v - vref| <= tol vref to the end (inf if never; 0 if never left)."""
    after = t >= t_event
    outside = np.flatnonzero(after & (np.abs(v - vref) > tol * vref))
    if outside.size == 0:
        return 0.0
    last = outside[-1]
    return float(t[last + 1] - t_event) if last + 1 < t.size else float("inf")
