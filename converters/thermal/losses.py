"""A device's losses over a window of a netlist's run, from its description's tables.

As PLECS computes them with ideal switches: the circuit runs as it is; each device's losses are read from its
tables at the run's currents and voltages and at a given junction temperature.

* conduction: the mean over the window of v_on(|i|, Tj) |i| while the device conducts (a switch while closed, its
  channel conducting either way with the same drop; a diode while its current is positive), integrated by the
  run's own rule (the exact method's quadrature on its exact pieces);
* turn-on and turn-off: at each of the device's switching edges in the window, E_on(V blocked before the edge,
  I conducted after it, Tj) and E_off(V blocked after it, I conducted before it, Tj) (a diode's turn-off energy is
  its reverse recovery), summed and divided by the window's length. The values before and after an edge are the
  circuit's at the edge's instant in the configuration it ends and in the one it begins
  (:meth:`converters.trajectory.Trajectory.edges`).
"""
from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from ..errors import ParameterError
from ..trajectory import Samples, Trajectory
from .description import DeviceDescription
from .tables import Table

#: A diode conducts where its current exceeds this fraction of its largest in the window (an ideal diode's current
#: is zero to rounding when it blocks).
CONDUCTING = 1e-9


@dataclass(frozen=True)
class DeviceLosses:
    """One device's losses over a window (W) at the junction temperature ``tj`` (degC)."""

    name: str
    kind: str
    tj: float
    conduction_W: float
    turn_on_W: float
    turn_off_W: float
    turn_ons: int
    turn_offs: int

    @property
    def total_W(self) -> float:
        return self.conduction_W + self.turn_on_W + self.turn_off_W

    def summary(self) -> dict[str, Any]:
        off = "recovery_W" if self.kind == "Diode" else "turn_off_W"
        return {"kind": self.kind, "tj_C": self.tj, "conduction_W": self.conduction_W, "turn_on_W": self.turn_on_W,
                off: self.turn_off_W, "total_W": self.total_W, "turn_ons": self.turn_ons, "turn_offs": self.turn_offs}


def device_losses(model: Any, p: dict, tr: Trajectory, descriptions: Mapping[str, DeviceDescription],
                  tj: Mapping[str, float], t0: float, t1: float) -> dict[str, DeviceLosses]:
    """Each described device's losses over [t0, t1] of ``tr`` (a run of the netlist ``model`` at ``p``), its
    tables read at ``tj[name]`` (degC). ``descriptions`` maps element names (``s1``, ``d1``) to descriptions."""
    compiled = model.compiled(p)
    elements = {e.name.lower(): e for e in model.netlist.elements}
    rows = tr.rows_between(t0, t1)
    _, before, after = tr.edges(rows)
    span = t1 - t0
    out = {}
    for name, description in descriptions.items():
        element = elements.get(name.lower())
        if element is None or element.kind not in "SD":
            raise ParameterError(f"a thermal description names {name!r}, which is no switch (S) or diode (D) of "
                                 f"the circuit ({', '.join(n for n, e in elements.items() if e.kind in 'SD')})")
        if description.kind == "Diode" and element.kind != "D" or description.kind != "Diode" and element.kind != "S":
            raise ParameterError(f"{name}: a {description.kind} description on a {'diode' if element.kind == 'D' else 'switch'}")
        temperature = float(tj[name])
        a, b = element.nodes[:2]

        def current(s: Samples, element_name: str = name) -> npt.NDArray[np.float64]:
            return np.asarray(model.signal(f"i({element_name.lower()})", s, p), dtype=float)

        def blocked(s: Samples, a: str = a, b: str = b, diode: bool = element.kind == "D") -> npt.NDArray[np.float64]:
            v = np.asarray(model.signal(f"v({a})", s, p) - model.signal(f"v({b})", s, p), dtype=float)
            return np.abs(v)                      # a diode blocks v(cathode) - v(anode), a switch either polarity

        if element.kind == "S":
            k = compiled.switch_names.index(element.name.lower())
            closed_by = np.array([c[k] for c in compiled.closed], dtype=bool)

            def conducting(s: Samples) -> npt.NDArray[np.bool_]:
                return closed_by[np.asarray(s.config, dtype=int)]
        else:
            peak = float(np.max(np.abs(current(tr.samples(rows))), initial=0.0))

            def conducting(s: Samples) -> npt.NDArray[np.bool_]:
                return current(s) > CONDUCTING * peak

        conduction = 0.0
        if description.conduction is not None:
            table = description.conduction

            def power(i: npt.NDArray[np.float64], on: npt.NDArray[np.bool_]) -> npt.NDArray[np.float64]:
                return np.where(on, table.at(np.abs(i), temperature) * np.abs(i), 0.0)
            conduction = _mean(tr, rows, lambda s: power(current(s), conducting(s)), power, current, conducting,
                               t0, t1)
        was, now = conducting(before), conducting(after)
        ons, offs = np.flatnonzero(~was & now), np.flatnonzero(was & ~now)
        on_energy = _energies(description.turn_on, blocked(before)[ons], np.abs(current(after))[ons], temperature)
        off_energy = _energies(description.turn_off, blocked(after)[offs], np.abs(current(before))[offs],
                               temperature)
        out[name] = DeviceLosses(name, description.kind, temperature, conduction, on_energy / span,
                                 off_energy / span, int(ons.size), int(offs.size))
    return out


def _mean(tr: Trajectory, rows: npt.NDArray[np.int_], of_samples: Any, power: Any, current: Any, conducting: Any,
          t0: float, t1: float) -> float:
    """The mean over [t0, t1] of a power that is a function of the device's current: by the exact method's
    quadrature, or, on a run read linearly between its points, by Simpson's rule on each step's current (linear
    there): exact for a drop linear in the current, as the run's own RMS is (its (a^2 + a b + b^2) / 3)."""
    if tr.rule == "exact":
        return tr.integral(of_samples, t0, t1) / (t1 - t0)
    samples = tr.samples(rows)
    i, on = current(samples), conducting(samples)
    a, a_on = i[:-1].copy(), on[:-1].copy()
    edges, _, after = tr.edges(rows)
    a[edges], a_on[edges] = current(after), conducting(after)      # a step that starts at an edge: its own side
    dt = np.diff(samples.t)
    b = i[1:]
    if tr.rule == "end":
        return float(dt @ power(b, on[1:])) / float(samples.t[-1] - samples.t[0])
    simpson = power(a, a_on) + 4.0 * power(0.5 * (a + b), a_on) + power(b, a_on)
    return float(dt @ simpson) / 6.0 / float(samples.t[-1] - samples.t[0])


def _energies(table: Table | None, voltage: npt.NDArray[np.float64], current: npt.NDArray[np.float64],
              temperature: float) -> float:
    if table is None:
        return 0.0
    return float(table.at(voltage, current, temperature).sum())
