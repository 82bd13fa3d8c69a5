"""A netlist as the plant of a control: what a loop senses and drives, read off the compiled circuit.

A control (:mod:`.control`) closes its loop around a converter through what the converter states about itself:
the configurations its switch selects (ON, OFF), the output as an affine function of the state
(:meth:`NetlistPlant.output_row`), its signals and its conducting devices. A built-in converter states them by
hand; a netlist (:class:`~.netlist.Circuit`) states them through its compile: its PWM gate drives two
configurations, told apart by the first switch (the netlist's order; ``switch`` is that switch's state in every
model of a netlist), and its output row is the compiled signal map of the file's output where it reads the state
alone, the same in both configurations. So ``--control voltage-mode`` takes ``netlists/circuits/buck.cir`` and
gives the built-in closed loop's orbit (tests/models/test_control_on_netlists.py).

The loop replaces the netlist's gate; the circuit's own parameters keep their SPICE names (case-insensitive), the
loop's its own. A netlist whose gate selects more than two configurations, or two that the first switch does not
tell apart, is refused in one line naming what it has.
"""
from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np
import numpy.typing as npt

from ..errors import ParameterError
from ..problems import Configuration, Schedule
from ..trajectory import Samples
from .base import ON, Converter
from .netlist import Circuit


class NetlistPlant(Converter):
    """A :class:`Circuit` seen as a converter with one driven switch (module docstring)."""

    #: A plant the loops that sense only the output and drive only the switch can close around.
    drives_one_switch = True

    def __init__(self, circuit: Circuit):
        self.circuit = circuit
        self.name, self.title = circuit.name, circuit.title
        # the loop's PWM replaces the gate: the duty ratio the file's gate reads is not the plant's
        self.parameters = tuple(q for q in circuit.parameters if q.name != "d")
        self.state_names = circuit.state_names
        self.pair_names = circuit.pair_names
        self.signal_names = circuit.signal_names
        self.signal_units = circuit.signal_units
        self.output_state = circuit.output_state
        self.mode_labels = ()
        self.off_held_label, self.turn_off_label = "off", None
        compiled = circuit.compiled(circuit.resolve({}))
        self.order = self._driven(compiled)
        self.pair_currents = tuple(compiled.pair_currents[i] for i in self.order)

    def _driven(self, compiled: Any) -> tuple[int, int]:
        """The compiled configurations (ON, OFF): the gate's two, ON with the first switch closed."""
        where = f"{self.name}: a control drives one switch between two configurations"
        if not compiled.switch_names:
            raise ParameterError(f"{where}; this netlist has no switch")
        configs = sorted(set(compiled.law.configs)) if isinstance(compiled.law, Schedule) else []
        if len(configs) != 2:
            raise ParameterError(f"{where}; its gates select {len(configs) or 'no'} configurations on a schedule"
                                 f"{'' if configs else ' (a state-driven law of its own)'}")
        first = [compiled.closed[i][0] for i in configs]
        if first[0] == first[1]:
            raise ParameterError(f"{where}; its two configurations do not differ in {compiled.switch_names[0].upper()}"
                                 ", the switch the loop drives")
        on, off = (configs[0], configs[1]) if first[0] else (configs[1], configs[0])
        return on, off

    def __reduce__(self) -> tuple[Any, ...]:
        return (NetlistPlant, (self.circuit,))

    def parameter_name(self, name: str) -> str:
        return self.circuit.parameter_name(name)

    def _values(self, p: dict[str, Any]) -> dict[str, Any]:
        """The circuit's resolved parameters at the plant's ``p`` (a loop's own in ``p`` are not the circuit's)."""
        names = {q.name for q in self.parameters}
        return self.circuit.resolve({k: v for k, v in p.items() if v is not None and k in names})

    def configurations(self, p: dict[str, Any]) -> tuple[Configuration, ...]:
        compiled = self.circuit.compiled(self._values(p))
        return tuple(replace(compiled.configurations[i], name=name) for i, name in zip(self.order, ("ON", "OFF")))

    def period(self, p: dict[str, Any]) -> float:
        return self.circuit.period(self._values(p))

    def _circuit_samples(self, samples: Samples) -> Samples:
        """The samples with each configuration index the compiled circuit's (the loop numbers them ON, OFF)."""
        return replace(samples, config=np.asarray(self.order)[np.asarray(samples.config, dtype=np.int64)])

    def signal(self, name: str, samples: Samples, p: dict[str, Any]) -> npt.NDArray[np.float64]:
        if name == "switch":
            return self.switch(samples)
        return np.asarray(self.circuit.signal(name, self._circuit_samples(samples), self._values(p)), dtype=float)

    def vout(self, samples: Samples, p: dict[str, Any]) -> npt.NDArray[np.float64]:
        return self.signal("vout", samples, p)

    def output_row(self, p: dict[str, Any]) -> tuple[npt.NDArray[np.float64], float] | None:
        """The file's output as c . x + d where it is one: its signal map reads the state alone (no pair, no SIN
        source, no gate) and is the same in the ON and OFF configurations; else None (a loop sensing it is
        refused)."""
        compiled = self.circuit.compiled(self._values(p))
        output = self.circuit.output
        if output not in compiled.signal_names:
            return None
        Sx, Su, s0, Ssin, Sgate = compiled.signal_rows(compiled.signal_names.index(output))
        on, off = self.order
        if any(np.any(m[[on, off]]) for m in (Su, Ssin, Sgate)):
            return None
        if not (np.array_equal(Sx[on], Sx[off]) and s0[on] == s0[off]):
            return None
        return np.array(Sx[on], dtype=float), float(s0[on])

    def modes(self, conducting: npt.NDArray[np.bool_], switch: npt.NDArray[Any],
              x: npt.NDArray[np.float64]) -> npt.NDArray[Any]:
        """A netlist's mode names (:meth:`Circuit.mode_labels`): its closed switches and conducting diodes."""
        compiled = self.circuit.compiled(self.circuit.resolve({}))
        switches = [s.upper() for s in compiled.switch_names]
        diodes = [d.upper() for d in compiled.pair_names] if compiled.pair_names != ("none",) else []
        closed = {state: [s for s, on in zip(switches, compiled.closed[self.order[state]]) if on] for state in (0, 1)}
        out = np.empty(len(switch), dtype=object)
        for i, (command, row) in enumerate(zip(np.asarray(switch), np.asarray(conducting, dtype=bool))):
            names = closed[ON if command >= 0.5 else 1 - ON] + [d for d, on in zip(diodes, row) if on]
            out[i] = "+".join(names) or "off"
        return out

    def output_node_current(self, samples: Samples) -> npt.NDArray[np.float64]:
        raise ParameterError(f"{self.name}: a netlist names no output node current; read its element currents "
                             "(i(NAME)) instead")

    def power(self, tr: Any, p: dict[str, Any], t0: float, t1: float) -> dict[str, float]:
        """Not stated for a netlist (its energy balance is the accuracy check's): NaN, left out of summaries."""
        return {"input_W": float("nan")}
