"""A steady-state run's device losses and junction temperatures: what ``simulate --steady --thermal`` adds to the
JSON summary."""
from __future__ import annotations

from typing import Any

import numpy as np

from ..errors import ParameterError
from ..trajectory import Trajectory
from .losses import Window, device_signals, waveforms
from .network import ThermalSetup


def thermal_summary(model: Any, p: dict, tr: Trajectory, setup: ThermalSetup) -> dict[str, Any]:
    """Each device's losses by kind over the orbit's last period at its steady junction temperature (losses and
    temperatures iterated to a fixed point: :meth:`ThermalSetup.steady`), the case and heatsink temperatures, and
    the power balance with the devices' losses. The switches and diodes are ideal in the circuit, as in PLECS: the
    tables' losses are not in its currents, so the source delivers the circuit's input plus the devices' losses.
    ``balance_W`` is what is left of input = output + the circuit's resistive losses + the devices' losses: the
    circuit's own balance over the period (its discretization), the devices' losses adding to both sides."""
    if "orbit" not in tr.metadata:
        raise ParameterError("--thermal reads the losses of the periodic steady state: run with --steady")
    if not hasattr(model, "netlist"):
        raise ParameterError("--thermal applies to a netlist's switches and diodes (FILE.cir)")
    T = model.period(p)
    t1 = float(tr.t[-1])
    return thermal_of_run(model, p, tr, setup, t1 - T, t1)


def thermal_of_run(model: Any, p: dict, tr: Trajectory, setup: ThermalSetup, t0: float, t1: float) -> dict[str, Any]:
    """:func:`thermal_summary` over [t0, t1] of ``tr`` (a period of the steady state), unchecked."""
    elements = [e for e in model.netlist.elements if e.kind in "VIR" or e.name.lower() in setup.devices]
    window = Window(model, p, tr, t0, t1, device_signals(elements))
    read = waveforms(model, p, tr, {d: m.description for d, m in setup.devices.items()}, t0, t1, window)
    steady = setup.steady(lambda tj: {d: w.losses(tj[d]) for d, w in read.items()},
                          lambda tj: {d: w.total_W(tj[d]) for d, w in read.items()})
    devices = {d: {**steady.losses[d].summary(), "name": setup.devices[d].description.name,
                   "case_C": steady.case[d]} for d in setup.devices}
    losses = sum(v["total_W"] for v in devices.values())
    source, load, resistive = _circuit_power(model, p, tr, window)
    total_in = source + losses
    return {"ambient_C": setup.ambient, "devices": devices, "heatsinks_C": steady.heatsink,
            "iterations": steady.iterations, "tj_moved_K": steady.moved,
            "power": {"input_W": total_in, "output_W": load, "circuit_losses_W": resistive,
                      "device_losses_W": losses, "efficiency": load / total_in if total_in > 0 else float("nan"),
                      "balance_W": total_in - load - resistive - losses},
            "time_scales": "junction temperatures from the period's average losses (the thermal time constants are "
                           "far longer than the switching period)"}


def _circuit_power(model: Any, p: dict, tr: Trajectory, window: Window) -> tuple[float, float, float]:
    """(what the sources deliver, what the load takes, what the other resistors dissipate) over the window (W), by
    the run's own rule (:meth:`Trajectory.integral`): the load the resistors from the output node to ground (NaN
    without one)."""
    read = window.read

    def power(e: Any, sign: float) -> Any:
        a, b = e.nodes[:2]
        return lambda s: sign * (read(f"v({a})", s) - read(f"v({b})", s)) * read(f"i({e.name})", s)
    output = getattr(model, "output", "")
    node = output[2:-1] if output.startswith("v(") and "," not in output else None
    source = load = resistive = 0.0
    has_load = False
    for e in model.netlist.elements:
        if e.kind in "VI":
            if not np.any(read(f"i({e.name})", window.rows)):       # a gate's drive: it delivers nothing
                continue
            source += window.mean(power(e, -1.0))
        elif e.kind == "R":
            dissipated = window.mean(power(e, 1.0))
            if node is not None and set(e.nodes[:2]) == {node, "0"}:
                load, has_load = load + dissipated, True
            else:
                resistive += dissipated
    return source, (load if has_load else float("nan")), resistive
