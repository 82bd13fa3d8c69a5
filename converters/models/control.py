"""Controls compose with converters: a :class:`Control` is a switching law (and the controller states it adds) that
closes a loop around a :class:`~.base.Converter`; ``control.on(converter)`` is the closed-loop model
(:class:`Controlled`).

The converter keeps what is the circuit's: its configurations (compiled from its netlist), its parameters and
parasitics, its load and input steps, its output voltage, element signals, losses and mode rules. The control
says what is the loop's: the law that replaces the converter's PWM schedule, the parameters it adds (and the duty
ratio it takes over), the controller states appended to the circuit's, its signals, the period of its clock or
the one it predicts, and, where it has one, its own summary. A control names the converters it closes a loop
around (``plants``), each with the plant's defaults of the circuit it is published with.

A law reads the converter through what the converter states about itself: its output as an affine function of
the state (:meth:`~.pwm2.PWMTwoState.output_row`), so a loop sensing vout is exact with the capacitor's ESR where
vout is a function of the state alone (the buck), and refused where it is not.
"""
from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt

from ..errors import ParameterError
from ..params import Param
from ..problems import LCSProblem
from ..trajectory import Samples
from .base import Converter, Labels, Model, SteppedLabels

if TYPE_CHECKING:
    from ..problems import Schedule
    from ..problems.lcs import SwitchingLaw
    from ..trajectory import Trajectory


class Control(ABC):
    """A closed-loop switching law, applicable to the converters named in ``plants``."""

    #: The command line's ``--control``.
    key: str
    #: What the loop is, after the converter's title ("voltage-mode control (ramp comparator)").
    title: str
    #: The controller's own parameters.
    parameters: tuple[Param, ...] = ()
    #: Per converter name: the plant's defaults where the loop is published with other values than the converter's
    #: (a number: the default; a Param: the parameter, where the loop narrows its range).
    plants: dict[str, dict] = {}
    #: The converter's parameters the loop sets itself (the duty ratio): not the user's.
    sets: tuple[str, ...] = ("D",)
    #: The converter's parameters the closed loop keeps (None: all but ``sets``).
    keeps: tuple[str, ...] | None = None
    #: The signals the loop adds.
    signal_names: tuple[str, ...] = ()
    signal_units: dict = {}
    #: The loop reads only the output (:meth:`sensed`) and drives only the switch: it closes around any plant that
    #: states them (a netlist's, :class:`~.plant.NetlistPlant`), not only the converters of ``plants``.
    output_only: bool = False

    def applies_to(self, converter: Converter) -> bool:
        return converter.name in self.plants or (self.output_only and getattr(converter, "drives_one_switch", False))

    def on(self, converter: Converter) -> Converter:
        """The model of ``converter`` under this control."""
        if not self.applies_to(converter):
            raise ParameterError(f"--control {self.key} is available for {', '.join(self.plants)} only; "
                                 f"got {converter.name!r}")
        return Controlled(converter, self)

    def check(self, model: "Controlled", p: dict) -> None:
        """Refuse parameter values the loop cannot run with (one line naming them)."""

    @abstractmethod
    def law(self, model: "Controlled", p: dict, initial: int | None = None,
            circuit: dict | None = None) -> SwitchingLaw:
        """The switching law (:mod:`converters.problems.switching`) at parameters ``p`` (the controller's design
        values) sensing the circuit in force (``circuit``: ``p``, or after a load or input step); ``initial``: the
        configuration in force at the start where the law keeps a memory."""

    def augment(self, configurations: tuple, p: dict, model: "Controlled") -> tuple:
        """The converter's configurations with the controller's states appended (none by default)."""
        return configurations

    def sensed(self, model: "Controlled", circuit: dict) -> tuple:
        """The output voltage the loop senses as (c, d), |vout| = c . x + d over the converter's state; refused
        where vout is not a function of the state."""
        row = model.converter.output_row(model.plant(circuit))
        if row is None and "rC" not in circuit:
            raise ParameterError(f"--control {self.key} senses the output, which on {model.name} depends on more than "
                                 "the circuit's state (a diode's current through an ESR, a source) or differs between "
                                 "the switch's configurations; sense a capacitor's voltage behind no resistance")
        if row is None:
            raise ParameterError(f"--control {self.key} senses vout, which on {model.name} with rC > 0 depends on the "
                                 f"diode's current as well as the state; give rC = 0 (got rC = {circuit.get('rC'):g})")
        return row

    def controller_states(self, p: dict) -> tuple[str, ...]:
        """The names of the controller's states appended to the converter's at ``p`` (an integrator)."""
        return ()

    def x0(self, model: "Controlled", p: dict) -> np.ndarray:
        """The start of a run when none is given: at rest."""
        return np.zeros(len(model.converter.state_names) + len(self.controller_states(p)))

    def period(self, model: "Controlled", p: dict) -> float:
        """The clock's period (s); a law without a clock: the one it predicts."""
        return model.converter.period(p)

    def periodic(self, p: dict) -> bool:
        return True

    def default_h(self, model: "Controlled", p: dict) -> float:
        return model.period(p) / 1000.0

    def max_h(self, model: "Controlled", p: dict) -> float:
        return model.period(p)

    def signal(self, name: str, samples: Samples, p: dict, model: "Controlled", circuit: dict | None = None) -> np.ndarray:
        """A signal of ``signal_names`` at the controller's design values ``p``, sensing the circuit in force
        (``circuit``: ``p``, or after a load or input step)."""
        raise NotImplementedError(name)

    def summary(self, model: "Controlled", tr: Trajectory, p: dict, *options: Any) -> dict | None:
        """The loop's own summary of a run, or None: the converter's (every measurement over the last periods)."""
        return None

    def window_start(self, model: "Controlled", p: dict, t_start: float, t_end: float,
                     window_s: float | None = None) -> float:
        """Where the summary's window begins (s): the last ``SUMMARY_PERIODS`` periods (at most the run)."""
        return max(t_start, t_end - model.SUMMARY_PERIODS * model.period(p))

    def summary_from(self, model: "Controlled", p: dict, t_start: float, t_end: float) -> float | None:
        """Where the loop's own summary reads from, or None: the converter's rule."""
        return None


class OpenLoop(Control):
    """Open-loop PWM at the duty ratio D: the converter as it is."""

    key = "pwm"
    title = "open-loop PWM"
    sets = ()

    def applies_to(self, converter: Converter) -> bool:
        return True

    def on(self, converter: Converter) -> Converter:
        return converter

    def law(self, model: Controlled, p: dict, initial: int | None = None,
            circuit: dict | None = None) -> Schedule:
        return model.schedule(p)


@dataclass(frozen=True)
class ControlledLabels(SteppedLabels):
    """A closed loop's laws with a load or input step: the circuit's signals are read with the circuit in force,
    the controller's with its design values sensing the circuit in force (a step changes the plant, not the
    controller)."""

    def signal(self, name: str, samples: Samples) -> np.ndarray:
        model, p = self.model, self.params
        if name not in model.loop.signal_names:
            return super().signal(name, samples)
        before = model.loop.signal(name, samples, p, model, p)
        after = np.asarray(samples.t) > p["t_step"]
        if not after.any():
            return before
        return np.where(after, model.loop.signal(name, samples, p, model, model.stepped(p)), before)


class Controlled(Converter):
    """A converter under a control (module docstring): the circuit's knowledge from ``converter``, the loop's from
    ``loop``. A registered loop pickles by name (a sweep's workers take the registry's), another as its plant and
    its loop."""

    def __init__(self, converter: Converter, loop: Control) -> None:
        self.converter, self.loop = converter, loop
        self.name, self.control = converter.name, loop.key
        self.title = f"{converter.title.split(' (')[0]}, {loop.title}"
        defaults = loop.plants.get(converter.name, {})
        keeps = loop.keeps
        plant = tuple(defaults[q.name] if isinstance(defaults.get(q.name), Param)
                      else replace(q, default=defaults.get(q.name, q.default)) for q in converter.parameters
                      if q.name not in loop.sets and (keeps is None or q.name in keeps))
        self.parameters = plant + tuple(loop.parameters)
        self.state_names = tuple(converter.state_names)
        self.pair_names = converter.pair_names
        self.signal_names = tuple(converter.signal_names) + tuple(loop.signal_names)
        self.signal_units = {**getattr(converter, "signal_units", {}), **loop.signal_units}
        for attribute in ("mode_labels", "output_state", "off_held_label", "turn_off_label", "pair_currents"):
            setattr(self, attribute, getattr(converter, attribute))
        self.closed_form = False             # the closed forms are the open-loop converter's at a given D

    def __reduce__(self) -> tuple[Any, ...]:
        if REGISTERED.get((self.name, self.control)) is self:      # a sweep's worker gets the registry's own object
            return (registered, (self.name, self.control))
        return (Controlled, (self.converter, self.loop))            # a netlist's loop: its plant pickles itself

    def parameter_name(self, name: str) -> str:
        """The plant's parameters as it names them (a netlist's case-insensitively), the loop's as the loop does."""
        if any(q.name == name for q in self.parameters):
            return name
        plant = self.converter.parameter_name(name)
        return plant if any(q.name == plant for q in self.parameters) else name

    def plant(self, p: dict) -> dict:
        """The converter's parameters of ``p`` (what its configurations and signals read)."""
        names = {q.name for q in self.converter.parameters}
        return {k: v for k, v in p.items() if k in names}

    def resolve(self, given: dict | None = None) -> dict:
        """Validated parameters: the loop's refusals first (they name its own rules), then the converter's."""
        p = Model.resolve(self, {self.parameter_name(k): v for k, v in dict(given or {}).items()})
        self.loop.check(self, p)
        return self.check_steps(p)

    def period(self, p: dict) -> float:
        return self.loop.period(self, p)

    def periodic(self, p: dict) -> bool:
        return self.loop.periodic(p)

    def default_h(self, p: dict) -> float:
        return self.loop.default_h(self, p)

    def max_h(self, p: dict) -> float:
        return self.loop.max_h(self, p)

    def configurations(self, p: dict) -> tuple:
        return self.loop.augment(self.converter.configurations(self.plant(p)), p, self)

    def schedule(self, p: dict) -> Schedule:
        raise ParameterError(f"{self.key} has no PWM schedule: its switching law is the loop's")

    def problem(self, p: dict, t_end: float, x0: npt.NDArray[np.float64] | None = None, t_start: float = 0.0,
                initial: int | None = None, after_step: bool = False) -> LCSProblem:
        """From x0 (default: the loop's start) over [t_start, t_end]; ``initial``: the switch state at t_start
        (a law with a memory); ``after_step``: the circuit after the load or input step, under the same
        controller."""
        x0 = self.loop.x0(self, p) if x0 is None else x0
        circuit = self.stepped(p) if after_step else p
        return LCSProblem(self.configurations(circuit), self.loop.law(self, p, initial, circuit), x0=x0,
                          t_span=(t_start, t_end), state_names=self.state_names + self.loop.controller_states(p),
                          pair_names=self.pair_names,
                          metadata={"converter": self.key, **p})

    def labels(self, p: dict) -> Labels:
        return ControlledLabels(self, p) if "t_step" in p else Labels(self, p)

    def signal(self, name: str, samples: Samples, p: dict) -> np.ndarray:
        if name in self.loop.signal_names:
            return self.loop.signal(name, samples, p, self, p)
        if name == "switch":
            return self.switch(samples)
        return self.converter.signal(name, samples, self.plant(p))

    def vout(self, samples: Samples, p: dict) -> np.ndarray:
        return self.converter.vout(samples, self.plant(p))

    def modes(self, conducting: np.ndarray, switch: np.ndarray, x: np.ndarray) -> np.ndarray:
        return self.converter.modes(conducting, switch, x)

    def output_node_current(self, samples: Samples) -> np.ndarray:
        return self.converter.output_node_current(samples)

    def power(self, tr: Trajectory, p: dict, t0: float, t1: float) -> dict:
        return self.converter.power(tr, self.plant(p), t0, t1)

    def window_start(self, p: dict, t_start: float, t_end: float, window_s: float | None = None) -> float:
        """Where the summary's window begins (s): the loop's rule (a law without a clock has its own window)."""
        return self.loop.window_start(self, p, t_start, t_end, window_s)

    def summary_from(self, p: dict, t_start: float, t_end: float) -> float:
        start = self.loop.summary_from(self, p, t_start, t_end)
        return super().summary_from(p, t_start, t_end) if start is None else start

    def summary(self, tr: Trajectory, p: dict, *options: Any) -> dict:
        """The loop's own summary where it has one (``options``: its own, the sliding mode's window), else the
        converter's."""
        own = self.loop.summary(self, tr, p, *options)
        return super().summary(tr, p) if own is None else own


#: The closed loops of the registry (:data:`converters.models.MODELS`, which fills this in as it builds them), by
#: (converter, control): here, below the registry, so that a loop pickles by name without importing it.
REGISTERED: dict[tuple[str, str], Controlled] = {}


def registered(name: str, control: str) -> Controlled:
    """The registry's closed loop (unpickling imports converters.models, whose package fills REGISTERED first)."""
    return REGISTERED[(name, control)]


__all__ = ["Control", "Controlled", "OpenLoop"]
