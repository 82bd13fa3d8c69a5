"""The measures a sweep row holds on demand, beside its standard ones: any signal's statistic over the measured
period (``v(out).ripple``, ``iL.rms``, ``vout.max``), the power balance (``efficiency``, ``input_W``, ``output_W``,
``total_loss_W``) and each element's loss (``losses.Ron``). Each is read on the same one-period run as the
standard measures, by the run's own rule (exact quadrature for the event method), so every backend gives the same
value; each has a unit (the Parquet dataset's metadata, the plots' axes). ``fraction.MODE`` is the fraction of the
period spent in a mode (``fraction.DCM``, ``fraction.CCM-ON``; a netlist's ``fraction.S1``: 0 where the point never
enters it)."""
from __future__ import annotations

from collections.abc import Iterable
from typing import TYPE_CHECKING

import numpy as np

from ..errors import ParameterError

if TYPE_CHECKING:
    from ..models import Model
    from ..trajectory import Trajectory

#: A signal's statistics over the measured period.
STATISTICS = ("mean", "rms", "min", "max", "ripple")
#: The power balance's measures and their units.
POWERS = {"efficiency": "1", "input_W": "W", "output_W": "W", "total_loss_W": "W"}


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
        if name.startswith("fraction.") and name[len("fraction."):].strip():
            out[name] = "1"
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
                                 f"{', '.join(POWERS)}, losses.NAME, fraction.MODE")
        out[name] = signal_unit(units, signal)
    return out


def metric_value(model: Model, p: dict, run: Trajectory, name: str) -> float:
    """The metric on a one-period run (labelled with the model's laws)."""
    t0, t1 = run.t[0], run.t[-1]
    if name.startswith("fraction."):
        return float(run.mode_fractions(None, t0=t0, t1=t1).get(name[len("fraction."):], 0.0))
    if name in POWERS or name.startswith("losses."):
        power = model.window_power(run, p, t0, t1)
        return float(power["losses_W"].get(name[len("losses."):], np.nan) if name.startswith("losses.")
                     else power[name])
    signal, _, statistic = name.rpartition(".")
    if statistic in ("mean", "rms", "ripple"):
        return float(getattr(run, statistic)(signal, t0=t0, t1=t1))
    values = np.asarray(run.signal(signal, run.rows_between(t0, t1)), dtype=float)
    return float(values.min() if statistic == "min" else values.max())


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
