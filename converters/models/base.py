"""What every model provides: parameters, the problem it builds, and its own laws for reading a run.

A model is a stateless description; ``problem(params, t_end)`` builds the immutable
:class:`~converters.problems.LCSProblem`, ``labels(params)`` binds its laws to the parameters for a
:class:`~converters.trajectory.Trajectory`: the named signals it adds (``vout``, ``switch``, ...), which
device of each complementarity pair conducts, and the conduction-mode rule. Analysis and validation
read runs only through these; nothing outside a model branches on its name.

Power converters (:class:`Converter`): configuration 0 is switch ON, 1 switch OFF (PWM). For each
configuration the model says whether u of each pair is its device's current (a diode carrying
u = i_D, y = -v_D) or its voltage (u = -v_D, y = i_D): ``pair_currents``. A device conducts where its
current carries the pair.
"""
from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt

from ..errors import ParameterError, SignalError
from ..problems import Configuration, LCSProblem, Schedule
from ..params import Param, resolve
from ..trajectory import Samples

if TYPE_CHECKING:
    from ..trajectory import Trajectory

ON, OFF = 0, 1


@dataclass(frozen=True)
class BoundLabels:
    """Any model's signals bound to one parameter set (converters: :class:`Labels`; mechanics too)."""

    model: object
    params: dict

    @property
    def signal_names(self) -> tuple[str, ...]:
        return self.model.signal_names

    def signal(self, name: str, samples: Samples) -> np.ndarray:
        return self.model.signal(name, samples, self.params)

    def waveform_measures(self, name: str, t0: float, t1: float) -> tuple[float, float, float, float] | None:
        """(mean, rms, min, max) over [t0, t1] of a signal that is a source's waveform alone, exactly; None for any
        other (read on the run): the model's, where it has them."""
        measures = getattr(self.model, "waveform_measures", None)
        return None if measures is None else measures(name, self.params, t0, t1)


@dataclass(frozen=True)
class Labels(BoundLabels):
    """A model's laws bound to one parameter set (what a Trajectory reads its signals and modes with)."""

    def conducting(self, samples: Samples) -> np.ndarray:
        return self.model.conducting(samples)

    def modes(self, conducting: np.ndarray, switch: np.ndarray, x: np.ndarray) -> np.ndarray:
        return self.model.modes(conducting, switch, x)


@dataclass(frozen=True)
class SteppedLabels(Labels):
    """The laws of a run with a load or input step: a point after t_step is read with the circuit after the step
    (vout through the ESR, the capacitor's current and the input current depend on R and Vin); a point at t_step
    ends the step before it and belongs to the circuit before."""

    def signal(self, name: str, samples: Samples) -> np.ndarray:
        after = np.asarray(samples.t) > self.params["t_step"]
        if not after.any():
            return super().signal(name, samples)
        stepped = self.model.signal(name, samples, self.model.stepped(self.params))
        return stepped if after.all() else np.where(after, stepped, super().signal(name, samples))


class Model(ABC):
    """A parametrised family of problems with its own signals and mode rules."""

    name: str
    title: str
    parameters: tuple[Param, ...]
    state_names: tuple[str, ...]
    pair_names: tuple[str, ...]
    #: The command line's --control for this model (``pwm``: open-loop PWM).
    control: str = "pwm"
    #: Signals the model adds to a run, beside its states.
    signal_names: tuple[str, ...] = ("vout", "switch")
    #: Every mode label the model's rule can produce.
    mode_labels: tuple[str, ...] = ("CCM-ON", "CCM-OFF", "DCM", "GDCM-ON")
    #: True when the model states its CCM/DCM closed forms (:class:`.analytic.SmallRipple`).
    closed_form: bool = False
    #: The state that carries the output voltage (what a bifurcation diagram shows by default).
    output_state: str = "vC"

    #: The parameters of a load or input step, where a model has them (a run in phases: :meth:`step_times`).
    STEP_PARAMETERS = ("t_step", "R_step", "Vin_step")

    def resolve(self, given: dict | None = None) -> dict:
        """Validated parameter values (defaults overlaid with ``given``)."""
        return resolve(self.parameters, dict(given or {}), self.key)

    def parameter_name(self, name: str) -> str:
        """A parameter's name as the model keys it (a netlist's are case-insensitive, as SPICE's)."""
        return name

    @property
    def key(self) -> str:
        return self.name if self.control == Model.control else f"{self.name} --control {self.control}"

    @abstractmethod
    def problem(self, p: dict, t_end: float, x0: npt.NDArray[np.float64] | None = None,
                t_start: float = 0.0, initial: int | None = None) -> LCSProblem:
        """The problem over [t_start, t_end] from x0 (default: the model's start, e.g. at rest);
        ``initial``: the configuration in force at t_start where the switching law keeps a memory."""

    def labels(self, p: dict) -> Labels:
        return Labels(self, p)

    @abstractmethod
    def period(self, p: dict) -> float:
        """The switching period T (s): the schedule's, or the predicted one of a state-driven law."""

    def default_h(self, p: dict) -> float:
        return self.period(p) / 1000.0

    def configurations(self, p: dict) -> tuple:
        """The circuit's configurations at ``p`` (those of its problem over one period, or an instant)."""
        return self.problem(p, self.period(p) if self.periodic(p) else 1e-9).configurations

    def fastest_rate(self, p: dict) -> float:
        """The largest |lambda| (1/s) of the circuit's configurations at ``p``
        (:func:`~converters.methods.theta.fastest_rate`)."""
        from ..methods.theta import fastest_rate
        return fastest_rate(self.configurations(p))

    def default_theta(self, p: dict, h: float) -> float:
        """The stepper's theta for steps of ``h`` s at ``p``: 0.5 where the step resolves every time constant of
        the circuit's configurations, 1 where one is shorter (:func:`~converters.methods.theta.default_theta`): the
        same rule for a named converter and its netlist."""
        from ..methods.theta import default_theta
        return default_theta(self.configurations(p), h)

    def periodic(self, p: dict) -> bool:
        """True when the problem's switching law has a fixed period (stroboscopic steady states)."""
        return True

    def step_times(self, p: dict) -> list[float]:
        """Instants where the model's circuit changes (load or input steps): a run is split there."""
        return []

    def prepare(self, points: list[dict]) -> None:
        """Get ready for problems at many parameter sets (a sweep's chunk): a model compiled from a netlist
        compiles them together (:meth:`Circuit.prepare`); the others have nothing to do."""

    def phase_options(self, p: dict, t: float) -> dict:
        """Keyword arguments of ``problem`` for the phase that starts at time t."""
        return {}

    def signal(self, name: str, samples: Samples, p: dict) -> np.ndarray:
        if name == "vout":
            return self.vout(samples, p)
        if name == "switch":
            return self.switch(samples)
        raise SignalError(f"signal must be one of {', '.join(self.signal_names)}; got {name!r}")

    @abstractmethod
    def vout(self, samples: Samples, p: dict) -> np.ndarray:
        """Output voltage with its physical sign, shape (N,)."""

    def switch(self, samples: Samples) -> np.ndarray:
        """Commanded switch state (1 = on) at each point; under a relay its blend z in [0, 1]."""
        if samples.relay is not None:
            return samples.relay
        return (np.asarray(samples.config) == ON).astype(np.int8)

    #: Per configuration, per pair: True where u is the device's current (u = i_D), False where u is
    #: its voltage (u = -v_D, y = i_D).
    pair_currents: tuple[tuple[bool, ...], ...] = ((True,), (False,))

    def conducting(self, samples: Samples) -> np.ndarray:
        """Per point and pair: the pair's device conducts: held where u is its current, free where u is its
        voltage (held: the method's own mode where it knows it, else u > y)."""
        currents = np.asarray(self.pair_currents, dtype=bool)[np.asarray(samples.config)]
        held = samples.held if samples.held is not None else samples.u > samples.y
        return held == currents

    def modes(self, conducting: np.ndarray, switch: np.ndarray, x: np.ndarray) -> np.ndarray:
        """One diode: ON with the diode blocking is CCM-ON, OFF with it conducting CCM-OFF; the pair held
        where the state is constrained: DCM (or the model's ``off_held_label``) in the OFF phase (the
        inductor current held at zero), GDCM-ON in the ON phase (the diode conducting with the switch)."""
        on = np.asarray(switch) >= 0.5
        conducts = conducting[:, 0]
        labels = np.where(on, "CCM-ON", "CCM-OFF").astype(object)
        labels[~on & ~conducts] = self.off_held_label
        labels[on & conducts] = "GDCM-ON"
        return labels

    #: Periods the summary measures over (at most; a shorter run: all of it).
    SUMMARY_PERIODS = 10

    def summary_from(self, p: dict, t_start: float, t_end: float) -> float:
        """Where what a run's summary and plot read begins (s): its window and the window before it (the
        accuracy check's transient); a run stored at an output spacing keeps every step from here on."""
        if not self.periodic(p):
            return t_start
        return max(t_start, t_end - 2 * self.SUMMARY_PERIODS * self.period(p))

    def summary(self, tr: Trajectory, p: dict) -> dict:
        """The model's measures of a run for its JSON summary, over its last min(10, all) periods
        (``window_periods``): the mean output, every signal's mean, RMS, min, max and ripple
        (``measurements``), the power balance where the model has one (``power``), and the mode fractions of
        the last period."""
        span = (tr.t[-1] - tr.t[0]) / self.period(p)
        window = float(min(self.SUMMARY_PERIODS, max(1, int(np.floor(span + 1e-9)))))
        t1 = tr.t[-1]
        t0 = t1 - window * self.period(p)
        out = {"vout_mean": tr.mean("vout", t0=t0, t1=t1), "window_periods": window,
               "mode_fractions": tr.mode_fractions(1)}
        out["measurements"] = tr.measurement_rows(t0=t0, t1=t1)
        out.update(jump_losses(tr, t0, t1))
        if hasattr(self, "power"):
            power = self.window_power(tr, p, t0, t1)
            if np.isfinite(power["input_W"]):          # an ngspice run of a two-state converter: not measured
                out["power"] = power
        return out

    def window_power(self, tr: Trajectory, p: dict, t0: float, t1: float) -> dict:
        """The power summary over [t0, t1] (a model with a step measures each side with its own circuit)."""
        return self.power(tr, p, t0, t1)

    off_held_label = "DCM"
    #: The mode whose end is the diode's turn-off in a period (None: not compared).
    turn_off_label: str | None = "CCM-OFF"
    #: Defaults of ``pcsuite compare``: start on the periodic orbit or from rest, periods run, window read.
    compare_defaults = {"start": "steady", "periods": 30, "window": 10}


class Converter(Model):
    """A PWM power converter: one Configuration per switch state and a PWM schedule."""

    @abstractmethod
    def configurations(self, p: dict) -> tuple[Configuration, ...]:
        """One Configuration per switch state, from validated parameters."""

    def period(self, p: dict) -> float:
        return 1.0 / p["f_sw"]

    def schedule(self, p: dict) -> Schedule:
        return Schedule.pwm(self.period(p), p["D"], on=ON, off=OFF)

    def problem(self, p: dict, t_end: float, x0: npt.NDArray[np.float64] | None = None,
                t_start: float = 0.0, initial: int | None = None,
                after_step: bool = False) -> LCSProblem:
        """From x0 (default: at rest) over [t_start, t_end]; ``initial`` is the schedule's business;
        ``after_step``: the circuit after the load or input step (``R_step``, ``Vin_step``)."""
        x0 = np.zeros(len(self.state_names)) if x0 is None else x0
        circuit = self.stepped(p) if after_step else p
        return LCSProblem(self.configurations(circuit), self.schedule(p), x0=x0, t_span=(t_start, t_end),
                          state_names=self.state_names, pair_names=self.pair_names,
                          metadata={"converter": self.name, **p}, pair_currents=self.pair_currents)

    # --- load and input steps (open loop) -------------------------------------------------------------------

    def resolve(self, given: dict | None = None) -> dict:
        return self.check_steps(super().resolve(given))

    @staticmethod
    def check_steps(p: dict) -> dict:
        """``p``, or the error of a step without its instant or an instant without a step."""
        if "t_step" in p and not ({"R_step", "Vin_step"} & set(p)):
            raise ParameterError("t_step needs R_step (a load step) or Vin_step (an input step), or both")
        if ({"R_step", "Vin_step"} & set(p)) and "t_step" not in p:
            raise ParameterError("R_step and Vin_step need t_step (the instant of the step)")
        return p

    @staticmethod
    def stepped(p: dict) -> dict:
        """The parameters after the step."""
        return {**p, "R": p.get("R_step", p["R"]), "Vin": p.get("Vin_step", p["Vin"])}

    def step_times(self, p: dict) -> list[float]:
        return [p["t_step"]] if "t_step" in p else []

    def phase_options(self, p: dict, t: float) -> dict:
        return {"after_step": bool(t >= p["t_step"])} if "t_step" in p else {}

    def labels(self, p: dict) -> Labels:
        return SteppedLabels(self, p) if "t_step" in p else Labels(self, p)

    def summary_from(self, p: dict, t_start: float, t_end: float) -> float:
        start = super().summary_from(p, t_start, t_end)        # the step response reads every period after it
        return max(t_start, min(start, p["t_step"] - self.SUMMARY_PERIODS * self.period(p))) if "t_step" in p else start

    def window_power(self, tr: Trajectory, p: dict, t0: float, t1: float) -> dict:
        """:meth:`power` over [t0, t1] with the circuit in force: a window across the step is the energy-weighted
        sum of its two parts (each measured with its own R and Vin)."""
        if "t_step" not in p or t1 <= p["t_step"]:
            return self.power(tr, p, t0, t1)
        after = self.stepped(p)
        if t0 >= p["t_step"]:
            return self.power(tr, after, t0, t1)
        parts = ((self.power(tr, p, t0, p["t_step"]), p["t_step"] - t0),
                 (self.power(tr, after, p["t_step"], t1), t1 - p["t_step"]))
        energy = lambda key: sum(part[key] * span for part, span in parts) / (t1 - t0)      # noqa: E731
        losses = {k: sum(part["losses_W"][k] * span for part, span in parts) / (t1 - t0) for k in parts[0][0]["losses_W"]}
        return power_balance(energy("input_W"), energy("output_W"), losses)

    def summary(self, tr: Trajectory, p: dict) -> dict:
        out = super().summary(tr, p)
        if "t_step" in p and tr.t[0] < p["t_step"] < tr.t[-1]:
            out["step"] = step_response(tr, p["t_step"], self.period(p), tr.metadata.get("step_target"))
        return out

    @abstractmethod
    def output_node_current(self, samples: Samples) -> np.ndarray:
        """Current delivered to the output capacitor and load (A, magnitude); in steady state its
        mean equals |vout| / R (charge balance of the output capacitor)."""


#: The settling band of a step response: the final value +- this fraction of the step (an input step), or of
#: the final value when the step barely moves it (a load step on an open-loop converter in CCM).
SETTLING_BAND = 0.02
LOAD_BAND = 1e-3
#: Periods the per-period mean must stay inside the band, at the end of the run, for the response to count as
#: settled: a ringing response that has just crossed into the band may leave it again.
SETTLED_PERIODS = 10


def power_balance(p_in: float, p_out: float, losses: dict) -> dict:
    """The power summary of a run: input, output, each loss, the efficiency and the balance
    (p_in - p_out - losses) / p_in (zero on a periodic orbit)."""
    total = sum(losses.values())
    return {"input_W": p_in, "output_W": p_out, "losses_W": losses, "total_loss_W": total,
            "efficiency": p_out / p_in if p_in > 0 else float("nan"),
            "balance": (p_in - p_out - total) / p_in if p_in > 0 else float("nan")}


def step_response(tr: Trajectory, t_step: float, T: float, target: float | None = None) -> dict:
    """vout's response to a step at t_step, read on its per-period means (the switching ripple averaged out).

    Parameters
    ----------
    tr : Trajectory
        The run, labelled (it has ``vout``).
    t_step, T : float
        The step's instant and the switching period (s).
    target : float, optional
        The final value the step leads to: the periodic steady-state mean of vout of the circuit after the step
        (V; what :func:`converters.run.run_converter` computes). Without it the final value is the mean of the
        run's last 10 periods, exact only when the run has settled.

    Returns
    -------
    dict
        ``vout_before`` (mean of the 10 periods before the step), ``vout_final`` (the target, or the last 10
        periods' mean: ``final_from`` says which), ``vout_end`` (the last 10 periods' mean), ``deviation_V``
        (largest |mean - final| after the step), ``band_V`` (the settling band: 2 % of the step, or 0.1 % of the
        final value for a step that barely moves vout), ``settling_time_s`` (from the step to the end of the last
        period whose mean lies outside the band), ``settled`` (the means have stayed inside the band for the last
        ``SETTLED_PERIODS`` periods of the run), and, when the step moves vout by more than 0.1 % of the final
        value, how far the means go past the final value in the step's direction: ``overshoot_V`` (V),
        ``overshoot_percent`` (% of the final value) and ``overshoot_of_step`` (a fraction of the step, the
        control textbook's measure).
    """
    first = int(np.ceil((t_step - tr.t[0]) / T - 1e-9))
    count = int(np.floor((tr.t[-1] - tr.t[0]) / T + 1e-9))
    read_from = max(0, first - 10)                  # the 10 periods before the step, and every one after it
    means = np.array([tr.mean("vout", t0=tr.t[0] + j * T, t1=tr.t[0] + (j + 1) * T) for j in range(read_from, count)])
    before = float(np.mean(means[:first - read_from])) if first > 0 else float("nan")
    after = means[first - read_from:]
    end = float(np.mean(after[-10:])) if len(after) else float("nan")
    final = end if target is None else float(target)
    change = final - before
    # an input step moves vout: the band is a fraction of that move; a load step on an open-loop converter in CCM
    # barely does: the band is then a fraction of the final value
    moved = abs(change) > LOAD_BAND * abs(final)
    band = SETTLING_BAND * abs(change) if moved else LOAD_BAND * abs(final)
    outside = np.flatnonzero(np.abs(after - final) > band)
    inside_at_end = len(after) - (outside[-1] + 1 if len(outside) else 0)      # periods inside the band at the end
    past = float(max(((after - final) * np.sign(change)).max(), 0.0)) if len(after) and change != 0 else 0.0
    out = {"t_step_s": t_step, "vout_before": before, "vout_final": final,
           "final_from": "run end" if target is None else "steady state after the step", "vout_end": end,
           "deviation_V": float(np.abs(after - final).max()) if len(after) else float("nan"),
           "band_V": float(band),
           "settling_time_s": float(tr.t[0] + T * (first + (outside[-1] + 1 if len(outside) else 0)) - t_step),
           "settled": bool(inside_at_end >= SETTLED_PERIODS)}
    if moved:         # a step that barely moves vout has no direction to overshoot in: its deviation says it all
        out.update(overshoot_V=past, overshoot_percent=100.0 * past / abs(final) if final else float("nan"),
                   overshoot_of_step=past / abs(change))
    return out


def check_h(h: float, period: float) -> float:
    if not 0.0 < h < period:
        raise ParameterError(f"h must be positive and below the switching period ({period:g} s); got {h:g}")
    return h


def jump_losses(tr: Trajectory, t0: float, t1: float) -> dict:
    """{"losses": {"redistribution_W", "redistribution_J", "jumps"}} of a run whose switches close across charged
    capacitances (:meth:`~converters.trajectory.Trajectory.jump_losses` over [t0, t1): the energy of the jumps and
    its mean power); {} for a run without."""
    if not getattr(tr.problem, "jumps", False):
        return {}
    jumps, energy = tr.jump_losses(t0=t0, t1=t1)
    return {"losses": {"redistribution_W": energy / (t1 - t0), "redistribution_J": energy, "jumps": jumps}}
