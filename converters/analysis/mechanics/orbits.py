"""The event method's exact maps of a mechanical model along one of its parameters, and the settings the studies
continue them with.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from converters.analysis.bifurcation import detect_period
from converters.analysis.continuation import check_path
from converters.errors import ParameterError
from converters.methods import EventDriven
from converters.models.path import ParameterPath

#: Continuation settings for the event method's maps (accurate to its ODE tolerance, 1e-9): Newton to 1e-8
#: (scaled), bifurcations bracketed to 1e-7, d F / d p by a forward difference of relative step 1e-5.
CONTINUATION = {"tol": 1e-8, "locate_tol": 1e-7, "fd_step": 1e-5}


def mechanical_path(model, params: dict, name: str, start: float, stop: float) -> ParameterPath:
    spec = {p.name: p for p in model.parameters}
    if name not in spec:
        raise ParameterError(f"--param must name a parameter of {model.key} ({', '.join(spec)}); got {name!r}")
    p = spec[name]
    check_path(name, start, stop, p.low, p.high, p.low_open, p.high_open)
    return ParameterPath(model, model.resolve(params), name)


def orbit_period(path, value: float, x0, *, warm_up: int = 300, record: int = 48, max_period: int = 8) -> tuple[int, np.ndarray]:
    """(period in forcing periods (0: none up to max_period), a state on the attractor) at ``value``: the event
    method's stroboscopic map iterated from x0."""
    problem = path(value)
    one = EventDriven().period_map(replace(problem, t_span=(problem.t_span[0], problem.t_span[0] + problem.period)))
    x = np.array(x0, dtype=float)
    for _ in range(warm_up):
        x = one.end(x)
    samples = []
    for _ in range(record):
        samples.append(x)
        x = one.end(x)
    period = detect_period(np.array(samples), 1e-6)
    return (period if period <= max_period else 0), x
