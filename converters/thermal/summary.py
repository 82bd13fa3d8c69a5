"""A steady-state run's device losses and junction temperatures: what ``simulate --steady --thermal`` adds to the
JSON summary."""
from __future__ import annotations

import math
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
    out = thermal_of_run(model, p, tr, setup, t1 - T, t1)
    out["accuracy"] = _losses_estimate(model, p, tr, setup, out)
    if "warning" in out["accuracy"]:
        out["warning"] = out["accuracy"].pop("warning")
    return out


def _losses_estimate(model: Any, p: dict, tr: Trajectory, setup: ThermalSetup, summary: dict[str, Any]) -> dict:
    """How far the devices' losses may be from the exact periodic ones at the same junction temperatures: the
    run's last period against the method's periodic orbit (a transient not settled) plus the discretization, the
    orbit's losses at h against those at 2h (the orbits the run's own accuracy check found,
    :func:`converters.analysis.accuracy.orbit_runs`): for an error C h^p that difference is (2^p - 1) times the
    error at h, so it bounds it for any order p >= 1 (a loss read at an edge or through a diode's event inside a
    step converges more slowly than the stepper's order: Richardson by the order gave half the error the exact
    method shows on the shipped example). Where an interval between switchings spans fewer than 4 steps (2 at
    2h: a dead time of one step is one step at h and at 2h, and their difference does not show its error: 1e-8
    against 6e-5 on the shipped example at h = T/200), the orbit at h against one at h / 2^m where that interval
    spans 2 steps or more, and twice their difference (for p >= 1 the error at h is at most twice it). The event
    method's orbit has no discretization. Where the stepper's difference at h and 2h cannot be trusted (a resonance
    the step damps, a mode shorter than a step: :func:`~converters.analysis.accuracy.second_resolution`), the exact
    method's orbit at the same junction temperatures stands for the exact losses. Per device in W, and in
    all relative to the devices' total (their absolute errors summed: none cancels another); a warning beyond
    the default target."""
    from ..analysis.accuracy import DEFAULT_RTOL, orbit_runs, second_resolution
    from ..methods.base import ErrorKind
    method = tr.algorithm
    if method is None or method.error_kind is ErrorKind.MODEL:
        return {"checked": False, "reason": "the method's error is its model's, not a step's"}
    runs = orbit_runs(model, p, method, tr)
    if isinstance(runs, str):
        return {"checked": False, "reason": runs, "warning": f"the devices' losses' error could not be estimated: "
                                                             f"{runs}"}
    fine, coarse = runs.fine, runs.coarse
    T = model.period(p)
    pair, bound = (fine, coarse), 1.0
    step = getattr(method, "h", None)
    reference = second_resolution(model, p, method, tr, runs)[1] if coarse is not None else None
    if isinstance(reference, str):
        reference = None
    shortest = _shortest_interval(fine, T) if coarse is not None and step else np.inf
    if step and shortest < 4.0 * step and reference is None:     # h / 2^m: the shortest interval 2 steps or more
        halved = orbit_runs(model, p, method.coarsened(0.5 ** max(1, math.ceil(math.log2(2.0 * step / shortest)))),
                            tr, observe=False)
        if isinstance(halved, str):
            return {"checked": False, "reason": halved, "warning": f"the devices' losses' error could not be "
                                                                   f"estimated: {halved}"}
        pair, bound = (halved.fine, halved.coarse), 2.0      # the error at h: twice the difference from h/2 (p >= 1)
    descriptions = {d: m.description for d, m in setup.devices.items()}
    tj = {d: v["tj_C"] for d, v in summary["devices"].items()}

    def totals(run: Trajectory) -> dict[str, float]:
        read = waveforms(model, p, run, descriptions, 0.0, T)       # the orbit's one period
        return {d: w.total_W(tj[d]) for d, w in read.items()}
    orbit = totals(fine)
    exact = dict(orbit)
    if reference is not None:
        # where the step's difference cannot be trusted (a resonance it damps, a mode shorter than a step): the
        # exact orbit's losses at the same junction temperatures
        exact = totals(reference)
    elif pair[1] is not None:     # the error at h bounded by the difference to 2h (or twice that of h/2 to h)
        finer, coarser = (orbit, totals(pair[1])) if pair[0] is fine else (totals(pair[0]), orbit)
        exact = {d: orbit[d] + bound * (finer[d] - coarser[d]) for d in orbit}
    reported = {d: v["total_W"] for d, v in summary["devices"].items()}
    errors = {d: abs(reported[d] - exact[d]) for d in reported}
    scale = max(sum(reported.values()), 1e-300)
    out: dict[str, Any] = {"checked": True, "target": DEFAULT_RTOL,
                           **({"estimated_by": "the exact (event) method's orbit"} if reference is not None else {}),
                           "losses_error_estimate": sum(errors.values()) / scale,
                           "transient": sum(abs(reported[d] - orbit[d]) for d in reported) / scale,
                           "discretization": sum(abs(orbit[d] - exact[d]) for d in reported) / scale,
                           "device_error_W": errors}
    power = summary["power"]
    if power["input_W"] > 0:      # efficiency = out / (in + losses): the losses' error moves it by eta dL / in
        out["efficiency_error_estimate"] = power["efficiency"] * sum(errors.values()) / power["input_W"]
    if out["losses_error_estimate"] > DEFAULT_RTOL:
        out["warning"] = (f"the devices' losses may be {out['losses_error_estimate']:.1e} off (more than "
                          f"{DEFAULT_RTOL:g} of their total): use --rtol 1e-4 (or a smaller --h)")
    return out


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


def _shortest_interval(orbit: Trajectory, T: float) -> float:
    """The shortest time between two switchings of a one-period run on the orbit (its configuration's changes, the
    period's wrap counted; T where it switches less than twice)."""
    if orbit.config is None:
        return T
    times = orbit.t[np.flatnonzero(np.diff(orbit.config) != 0)]
    if times.size < 2:
        return T
    return float(np.diff(np.concatenate([times, [times[0] + T]])).min())


def thermal_of_transient(model: Any, p: dict, tr: Trajectory, setup: ThermalSetup,
                         start: dict[str, float] | None = None) -> Any:
    """The junction and heatsink temperatures along a run of a periodic netlist, period by period
    (:func:`.network.thermal_cosimulation`): each period's losses read at the junctions' temperatures at its
    start, the network stepped over it; from ``start`` (default: a cold start at the ambient). A
    :class:`.network.ThermalTransient` at the periods' bounds."""
    from .network import thermal_cosimulation
    T = model.period(p)
    t0 = float(tr.t[0])
    count = int(np.floor((float(tr.t[-1]) - t0) / T * (1.0 + 1e-9)))
    if count < 1:
        span = float(tr.t[-1]) - t0
        raise ParameterError(f"a thermal co-simulation reads whole periods: the run spans {span:.3g} s, less than "
                             f"one period ({T:.3g} s)")
    descriptions = {d: m.description for d, m in setup.devices.items()}
    elements = [e for e in model.netlist.elements if e.name.lower() in setup.devices]
    windows = []
    for k in range(count):
        a, b = t0 + k * T, t0 + (k + 1) * T
        windows.append((a, b, waveforms(model, p, tr, descriptions, a, b,
                                        Window(model, p, tr, a, b, device_signals(elements)))))
    return thermal_cosimulation(setup, windows, start)


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
