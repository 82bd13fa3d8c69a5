"""The measures a sweep row holds on demand, beside its standard ones: any signal's statistic over the measured
period (``v(out).ripple``, ``iL.rms``, ``vout.max``), the power balance (``efficiency``, ``input_W``, ``output_W``,
``total_loss_W``) and each element's loss (``losses.Ron``); with a thermal setup (a netlist's ``*pcsuite thermal FILE``: devices' losses
from their descriptions, :mod:`converters.thermal`), ``thermal.efficiency``, ``thermal.losses_W``, ``tj.NAME``
and ``tj.max`` (junction temperatures, degC), ``loss.NAME`` (a device's losses, W). Each is read on the same one-period run as the
standard measures, by the run's own rule (exact quadrature for the event method), so every backend gives the same
value; each has a unit (the Parquet dataset's metadata, the plots' axes). ``fraction.MODE`` is the fraction of the
period spent in a mode the model names (``fraction.DCM``, ``fraction.CCM-ON``; a netlist's ``fraction.S1``,
``fraction.off``: 0 where the point never enters it); another name is refused."""
from __future__ import annotations

from collections.abc import Iterable
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import ParameterError

if TYPE_CHECKING:
    from ..models import Model
    from ..trajectory import Trajectory

#: A signal's statistics over the measured period.
STATISTICS = ("mean", "rms", "min", "max", "ripple")
#: The power balance's measures and their units.
POWERS = {"efficiency": "1", "input_W": "W", "output_W": "W", "total_loss_W": "W"}
#: With a thermal setup: the balance with the devices' losses, and per device (tj.NAME, loss.NAME).
THERMAL = {"thermal.efficiency": "1", "thermal.losses_W": "W", "tj.max": "degC"}


def check_metrics(model: Model, p: dict, names: Iterable[str]) -> dict:
    """{metric: unit} of metrics the model can give at ``p``; anything else is refused in one line naming the valid
    forms. The power balance's and the losses' names are read off one period of the stepper from the model's start
    (what its ``power`` reports at these parameters: the parasitics that are set)."""
    from ..trajectory import signal_unit
    units = dict(getattr(model, "signal_units", {}) or {})
    out, power = {}, None
    for name in names:
        if not isinstance(name, str) or not name.strip():
            raise ParameterError(f"a metric must be a name (SIGNAL.STAT, efficiency, losses.NAME); got {name!r}")
        if name.startswith("fraction."):
            _check_mode(model, name)
            out[name] = "1"
            continue
        if name in THERMAL or name.startswith(("tj.", "loss.")):
            setup = _thermal_setup(model)
            device = name.partition(".")[2]
            if name not in THERMAL and device not in setup.devices:
                raise ParameterError(f"metric {name!r}: the thermal setup's devices are {', '.join(setup.devices)}")
            out[name] = THERMAL.get(name, "degC" if name.startswith("tj.") else "W")
            continue
        if name in POWERS or name.startswith("losses."):
            if not hasattr(model, "power"):
                raise ParameterError(f"metric {name!r}: {model.key} has no power balance (the built-in converters "
                                     "have one); its signals' statistics are SIGNAL.STAT")
            power = power or _probe_power(model, p)
            if name.startswith("losses.") and name[len("losses."):] not in power["losses_W"]:
                raise ParameterError(f"metric {name!r}: the losses of {model.key} here are "
                                     f"{', '.join('losses.' + k for k in power['losses_W']) or 'none (ideal parts)'}")
            out[name] = POWERS.get(name, "W")
            continue
        signal, dot, statistic = name.rpartition(".")
        names_here = _signal_names(model, p)
        if not dot or statistic not in STATISTICS or signal not in names_here:
            raise ParameterError(f"metric {name!r}: a sweep's metrics are SIGNAL.STAT with STAT one of "
                                 f"{', '.join(STATISTICS)} and SIGNAL one of {', '.join(names_here)}; or "
                                 f"{', '.join(POWERS)}, losses.NAME, fraction.MODE, tj.NAME, loss.NAME, "
                                 "thermal.efficiency")
        out[name] = signal_unit(units, signal)
    return out


def metric_value(model: Model, p: dict, run: Trajectory, name: str) -> float:
    """The metric on a one-period run (labelled with the model's laws)."""
    t0, t1 = run.t[0], run.t[-1]
    if name.startswith("fraction."):
        return float(run.mode_fractions(None, t0=t0, t1=t1).get(name[len("fraction."):], 0.0))
    if name in THERMAL or name.startswith(("tj.", "loss.")):
        thermal = run.__dict__.setdefault("_thermal", {})       # one summary per run, whatever it is asked
        if "summary" not in thermal:
            from ..thermal.summary import thermal_of_run
            thermal["summary"] = thermal_of_run(model, p, run, _thermal_setup(model), float(t0), float(t1))
        summary = thermal["summary"]
        if name == "thermal.efficiency":
            return float(summary["power"]["efficiency"])
        if name == "thermal.losses_W":
            return float(summary["power"]["device_losses_W"])
        if name == "tj.max":
            return float(max(d["tj_C"] for d in summary["devices"].values()))
        device = summary["devices"][name.partition(".")[2]]
        return float(device["tj_C"] if name.startswith("tj.") else device["total_W"])
    if name in POWERS or name.startswith("losses."):
        power = model.window_power(run, p, t0, t1)
        return float(power["losses_W"].get(name[len("losses."):], np.nan) if name.startswith("losses.")
                     else power[name])
    signal, _, statistic = name.rpartition(".")
    if statistic in ("mean", "rms", "ripple"):
        return float(getattr(run, statistic)(signal, t0=t0, t1=t1))
    values = np.asarray(run.signal(signal, run.rows_between(t0, t1)), dtype=float)
    return float(values.min() if statistic == "min" else values.max())


def _check_mode(model: Model, name: str) -> None:
    """Refuse ``fraction.MODE`` for a mode the model never names (``fraction.DCM`` on a netlist, whose modes name its
    conducting elements, had read 0.0 at every point of a buck in DCM). A netlist's modes are its closed switches,
    then its conducting diodes, in the file's order, joined by '+', or 'off'."""
    mode = name[len("fraction."):]
    circuit: Any = model
    while circuit is not None and not hasattr(circuit, "netlist"):      # a netlist's plant, or a loop around one
        circuit = getattr(circuit, "circuit", None) or getattr(circuit, "converter", None)
    if circuit is None or getattr(model, "off_held_label", None) != "off":       # a built-in converter's classes
        labels = tuple(label for label in dict.fromkeys([*(getattr(model, "mode_labels", ()) or ()),
                                                         getattr(model, "off_held_label", None)]) if label)
        if mode not in labels:
            raise ParameterError(f"metric {name!r}: the modes of {model.key} are "
                                 f"{', '.join('fraction.' + label for label in labels)}")
        return
    compiled = circuit.compiled(circuit.resolve({}))
    switches = [s.upper() for s in compiled.switch_names]
    diodes = [d.upper() for d in compiled.pair_names] if compiled.pair_names != ("none",) else []
    parts = mode.split("+")
    canonical = "+".join([s for s in switches if s in parts] + [d for d in diodes if d in parts])
    if mode == "off" or (canonical == mode and len(set(parts)) == len(parts)):
        return
    names = ", ".join(switches + diodes) or "none"
    hint = f"; in their order: fraction.{canonical}" if set(parts) <= set(switches + diodes) and canonical else ""
    raise ParameterError(f"metric {name!r}: a netlist's modes are its closed switches and conducting diodes "
                         f"({names}) joined by '+' (switches first, in the file's order), or 'off' where nothing "
                         f"conducts{hint}")


def _thermal_setup(model: Model):  # -> ThermalSetup
    """The thermal setup a netlist names (``*pcsuite thermal FILE``), or a one-line refusal."""
    from ..thermal.network import declared_setup, read_setup
    declared = declared_setup(model.netlist.text, model.source) if hasattr(model, "netlist") else None
    if declared is None:
        raise ParameterError(f"the thermal metrics (tj.NAME, loss.NAME, thermal.efficiency) need a netlist that names "
                             f"its thermal setup ('*pcsuite thermal FILE'); {model.key} names none")
    return read_setup(declared)


def _signal_names(model: Model, p: dict) -> list[str]:
    labels = model.labels(p)
    states = list(getattr(model, "state_names", ()) or model.problem(p, model.period(p)).state_names)
    return states + [s for s in labels.signal_names if s not in states and s != "mode"]


def _probe_power(model: Model, p: dict) -> dict:
    """The power balance of one period from the model's start (the stepper at T/200): which losses it reports."""
    from dataclasses import replace

    from ..methods import Theta
    from ..simulate import simulate
    T = model.period(p)
    run = replace(simulate(model.problem(p, T), Theta(h=T / 200)), labels=model.labels(p))
    return model.window_power(run, p, run.t[0], run.t[-1])
