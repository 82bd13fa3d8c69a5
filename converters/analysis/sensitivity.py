"""Exact sensitivities of a steady state: d(metric)/d(parameter) on the periodic orbit, with no extra simulation.

On the orbit x* = P(x*, p) of the period map P, the implicit function theorem gives dx*/dp = (I - J)^-1 dP/dp
(J = dP/dx, the monodromy matrix with its saltation matrices). The mean of an output y = r x + r0 over the period
then moves by the mean of r dx(t) + (dr x + dr0) along the orbit, dx(t) the linearised flow started at dx*/dp. That
is the exact small-signal model at zero frequency (:class:`~converters.analysis.smallsignal.SmallSignalModel`,
whose periodic solution at w = 0 is that IFT solve): per parameter one matrix exponential per segment and one
linear solve, for sources and the duty ratio (which enter affinely) and for element values (an inductance, a
capacitance, a load: they change the modes' matrices, whose derivatives are read by a five-point difference of the
compiled matrices, error of order 1e-12; the flows and events stay exact). The event method's orbit is the one
differentiated; the stepper's orbit converges to it as h -> 0.

The normalised sensitivity S = (p / m) dm/dp is the percentage change of the metric per percent of the parameter
(S = 1: proportional; a parameter at 0, such as an ideal part's resistance, has S = 0 and its derivative stands).
"""
from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass
from typing import TYPE_CHECKING, cast

import numpy as np

from ..errors import ParameterError, ResourceError, SignalError, SimulationError
from .smallsignal import SmallSignalModel, _mean_output, quantity_unit

if TYPE_CHECKING:
    from ..models.base import Model

#: The statistics of a signal that have exact sensitivities here (a metric is SIGNAL or SIGNAL.mean).
STATISTICS = ("mean",)


@dataclass(frozen=True)
class Sensitivity:
    """d(metric)/d(parameter) at the steady state, and the normalised (p/m) dm/dp."""

    parameter: str
    value: float
    unit: str
    derivative: float                   # metric unit per parameter unit

    def normalised(self, metric_value: float) -> float:
        return self.value * self.derivative / metric_value if metric_value != 0.0 else math.nan


@dataclass(frozen=True)
class Sensitivities:
    """Every parameter's sensitivity of one metric at one steady state, and the parameters not taken (with why)."""

    metric: str
    signal: str
    metric_value: float
    metric_unit: str
    rows: tuple                         # Sensitivity, ranked by |normalised| then |derivative|
    skipped: dict                       # parameter -> why it has no sensitivity here
    multipliers: np.ndarray             # the orbit's Floquet multipliers (its stability)
    orbit_warning: str = ""             # the orbit's own (PeriodicOrbit.warning: a remote orbit)
    border: str = ""                    # where the orbit lies at a border of its modes (SmallSignalModel.border)

    def as_dict(self) -> dict:
        return {"metric": self.metric, "value": self.metric_value, "unit": self.metric_unit,
                "sensitivities": [{"parameter": s.parameter, "value": s.value, "unit": s.unit,
                                   "derivative": s.derivative, "normalised": s.normalised(self.metric_value)}
                                  for s in self.rows],
                "skipped": dict(self.skipped),
                "spectral_radius": float(np.abs(self.multipliers).max(initial=0.0)),
                **({"border": self.border} if self.border else {})}


def parse_metric(text: str) -> tuple[str, str]:
    """(signal, statistic) of a metric written SIGNAL or SIGNAL.STATISTIC (vout, v(out).mean, iL.mean)."""
    signal, dot, statistic = text.rpartition(".")
    if not dot or statistic not in _KNOWN:
        signal, statistic = text, "mean"
    if statistic not in STATISTICS:
        raise ParameterError(f"metric {text!r}: exact sensitivities are taken of a signal's mean here "
                             f"({', '.join('SIGNAL.' + s for s in STATISTICS)}, or SIGNAL alone); got the {statistic}")
    if not signal:
        raise ParameterError(f"metric must name a signal (vout, a state, v(NODE), i(ELEMENT)); got {text!r}")
    return signal, statistic


#: Statistics a metric's suffix may name (those without exact sensitivities are refused by name).
_KNOWN = ("mean", "rms", "min", "max", "ripple")


def sensitivities(model: Model | str, params: dict | None = None, *, metric: str = "vout",
                  parameters: Iterable[str] | None = None, tol: float = 1e-10) -> Sensitivities:
    """The exact sensitivities of ``metric`` (a signal's mean over the period of the steady state) to each of
    ``parameters`` (default: every parameter with a value that keeps the period: element values, sources, the duty
    ratio, a reference...). A parameter named explicitly that cannot be taken raises; by default it is listed in
    ``skipped`` with the reason."""
    if isinstance(model, str):
        from ..models import get_model
        model = get_model(model)
    signal, statistic = parse_metric(metric)
    p = model.resolve(params)
    explicit = parameters is not None
    if parameters is not None:
        names = []
        for name in parameters:
            key = model.parameter_name(name)
            if key not in {q.name for q in model.parameters}:
                raise ParameterError(f"parameter must be one of {', '.join(q.name for q in model.parameters)}; "
                                     f"got {name!r}")
            names.append(key)
    else:
        names = [q.name for q in model.parameters if isinstance(p.get(q.name), (int, float))
                 and not isinstance(p.get(q.name), bool)]
    units = {q.name: q.unit for q in model.parameters}
    base, rows, skipped = None, [], {}
    for name in names:
        try:
            small = SmallSignalModel(model, p, input=name, outputs=(signal,), tol=tol,
                                     orbit=None if base is None else base.orbit)
        except (SignalError, ResourceError):    # the metric's signal (wrong for every parameter), or a limit
            raise
        except ParameterError as error:
            if explicit:
                raise
            skipped[name] = str(error)
            continue
        base = base or small
        derivative = float(np.real(small.response([0.0], signal)[0]))
        rows.append(Sensitivity(name, float(p[name]), units.get(name, ""), derivative))
    if base is None:
        reasons = set(skipped.values())
        raise SimulationError(f"no parameter of {model.key} has a sensitivity here: " +
                              (reasons.pop() if len(reasons) == 1       # one reason for all (the law): said once
                               else "; ".join(f"{k}: {v}" for k, v in skipped.items())))
    value = _mean_output(base, signal)
    ranked = sorted(rows, key=lambda s: (-abs(s.normalised(value)) if math.isfinite(s.normalised(value)) else 0.0,
                                         -abs(s.derivative)))
    return Sensitivities(metric, signal, value, quantity_unit(model, p, signal), tuple(ranked), skipped,
                         base.orbit.multipliers, base.orbit.warning, base.border())



def finite_difference(model: Model | str, params: dict | None, metric: str, parameter: str, relative: float = 1e-4,
                      tol: float = 1e-12) -> float:
    """The same derivative by brute force: the steady state (Newton shooting to ``tol``) at the parameter moved by
    +-h and +-2h (h = ``relative`` times its value, or its distance to its range's nearer end where smaller), a
    five-point central difference; a three-point one-sided one where the range ends. Four orbits per parameter: the
    check of :func:`sensitivities`, not its method."""
    from .smallsignal import STENCILS, move_scale, steady_mean
    if isinstance(model, str):
        from ..models import get_model
        model = get_model(model)
    signal, _ = parse_metric(metric)
    p = model.resolve(params)
    key = model.parameter_name(parameter)
    value = float(p[key])
    h = relative * move_scale(next(q for q in model.parameters if q.name == key), value)
    given = {k: v for k, v in p.items() if v is not None}

    def at(k: int) -> float | None:
        try:
            return steady_mean(model, {**given, key: value + k * h}, signal, tol)
        except ResourceError:
            raise
        except ParameterError:
            return None
    for offsets, weights, denominator in STENCILS:
        values = [at(k) for k in offsets]
        if all(v is not None for v in values):
            found = cast("list[float]", values)          # every one (all() does not narrow the list's type)
            return sum(w * v for w, v in zip(weights, found)) / (denominator * h)
    raise ParameterError(f"{parameter} = {value!r} cannot be moved by +-{2 * h:g} inside its range")
