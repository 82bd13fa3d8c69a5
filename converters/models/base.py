"""What every converter provides: parameters, per-configuration LCS, schedule, output and mode labels.

A converter is a stateless description; ``problem(params, t_end)`` builds the immutable
:class:`~converters.problems.LCSProblem`. Configuration 0 is switch ON, 1 is switch OFF (PWM converters).
"""
from __future__ import annotations

from abc import ABC, abstractmethod

import numpy as np

from ..errors import ParameterError
from ..problems import Configuration, LCSProblem, Schedule
from ..params import Param, resolve

ON, OFF = 0, 1


class Converter(ABC):
    name: str
    title: str
    parameters: tuple[Param, ...]
    state_names: tuple[str, ...]
    pair_names: tuple[str, ...]
    default_theta: float = 1.0

    def resolve(self, given: dict | None = None) -> dict:
        """Validated parameter values (defaults overlaid with ``given``)."""
        return resolve(self.parameters, dict(given or {}), self.name)

    def period(self, p: dict) -> float:
        return 1.0 / p["f_sw"]

    def default_h(self, p: dict) -> float:
        return self.period(p) / 1000.0

    @abstractmethod
    def configurations(self, p: dict) -> tuple[Configuration, ...]:
        """One Configuration per switch state, from validated parameters."""

    def schedule(self, p: dict) -> Schedule:
        return Schedule.pwm(self.period(p), p["D"], on=ON, off=OFF)

    def problem(self, p: dict, t_end: float, x0=None) -> LCSProblem:
        x0 = np.zeros(len(self.state_names)) if x0 is None else x0
        return LCSProblem(self.configurations(p), self.schedule(p), x0=x0, t_span=(0.0, t_end),
                          state_names=self.state_names, pair_names=self.pair_names,
                          metadata={"converter": self.name, **p})

    @abstractmethod
    def vout(self, x: np.ndarray, u: np.ndarray, config: np.ndarray, p: dict) -> np.ndarray:
        """Output voltage with its physical sign, shape (N,)."""

    @abstractmethod
    def output_node_current(self, x: np.ndarray, u: np.ndarray, config: np.ndarray) -> np.ndarray:
        """Current delivered to the output capacitor and load (A, magnitude); in steady state its
        mean equals |vout| / R (charge balance of the output capacitor)."""

    def switch(self, config: np.ndarray) -> np.ndarray:
        """Commanded switch state (1 = on) at each point."""
        return (np.asarray(config) == ON).astype(np.int8)

    def modes(self, active: np.ndarray, config: np.ndarray, x: np.ndarray) -> np.ndarray:
        """Conduction-mode label per point from the switch command and the complementarity state.

        One diode: ON with the diode blocking is CCM-ON, OFF with it conducting CCM-OFF; an active
        pair (u > 0, y = 0) marks the mode where the state is constrained: DCM in the OFF phase
        (inductor current held at zero), GDCM-ON in the ON phase.
        """
        on = self.switch(config).astype(bool)
        held = active[:, 0]
        labels = np.where(on, "CCM-ON", "CCM-OFF").astype(object)
        labels[~on & held] = self.off_held_label
        labels[on & held] = "GDCM-ON"
        return labels

    off_held_label = "DCM"


def check_h(h: float, period: float) -> float:
    if not 0.0 < h < period:
        raise ParameterError(f"h must be positive and below the switching period ({period:g} s); got {h:g}")
    return h
