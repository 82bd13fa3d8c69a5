"""The two blocks on a belt (stick-slip): the section where block 1 starts to stick, against the belt velocity, and a
regime decided by a test that can fail (a cycle of the section, or a positive largest Lyapunov exponent).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from converters.analysis.bifurcation import (
    detect_period,
    lyapunov_interval,
    section_diagram,
)
from converters.errors import SimulationError
from converters.methods import EventDriven
from converters.models.mechanics import get_mechanical
from converters.models.path import ParameterPath


def two_block_diagram(params: dict | None, name: str, values, *, transient: float = 60.0, record: float = 60.0,
                      workers: int | None = None, progress: bool = False):
    """The two-block system on the section where block 1 starts to stick (the event method), against ``name``."""
    model = get_mechanical("stick-slip")
    p = model.resolve(params)
    path = ParameterPath(model, p, name)
    return section_diagram(path, EventDriven(), values, model.problem(p, 1.0).x0, kind="stick", pair=0,
                           transient=transient, record=record, unit=model.time_scale(p), workers=workers,
                           progress=progress)


def lyapunov_of_flow(model_name: str, params: dict | None, *, span_units: float = 1.0, transient: int = 60,
                     blocks: int = 20, block: int = 25, x0=None) -> tuple[float, float]:
    """The largest Lyapunov exponent of an autonomous model's flow per time unit, with the half-width of its 95 %
    interval: the event method's exact map over ``span_units`` time units iterated with its Jacobians from x0 (the
    model's start by default), ``blocks`` batches of ``block`` maps after ``transient``
    (:func:`converters.analysis.bifurcation.lyapunov_interval`)."""
    model = get_mechanical(model_name)
    p = model.resolve(params)
    unit = model.time_scale(p)
    period_map = EventDriven().period_map(model.problem(p, span_units * unit))
    start = model.problem(p, 1.0).x0 if x0 is None else x0
    exponent, half, _ = lyapunov_interval(period_map, start, transient, blocks, block)
    return exponent / span_units, half / span_units


def two_block_regime(params: dict | None, *, transient: float = 500.0, record: float = 500.0, tol: float = 1e-9,
                     blocks: int = 20, block: int = 25) -> dict:
    """The two-block system's regime at one belt velocity, by two tests that can fail: (1) the states where block 1
    starts to stick, after ``transient`` time units over ``record`` more, close into a cycle of k section points to
    ``tol`` (:func:`converters.analysis.bifurcation.detect_period`), the closing shown by the largest difference
    over the record's first and last k points (a transient still decaying has the first well above the last);
    (2) the largest Lyapunov exponent per time unit with its 95 % interval, from the run's end. Regime: "periodic"
    when a cycle closes (a periodic orbit of a flow has exponent 0: the interval must contain it or lie below);
    "chaotic" when none does and the interval lies above 0; otherwise "undetermined"."""
    p = get_mechanical("stick-slip").resolve(params)
    (row,) = two_block_diagram(p, "V", [p["V"]], transient=transient, record=record, workers=1)
    if row.error:
        raise SimulationError(f"the two-block run at V = {p['V']:g} m/s failed: {row.error}")
    points = row.states[:, [0, 1, 3]]                                   # v1 = V there: x1, x2, v2
    k = detect_period(points, tol) if len(points) >= 4 else 0
    exponent, half = lyapunov_of_flow("stick-slip", p, transient=0, blocks=blocks, block=block, x0=row.states[-1])
    closing = None
    if k:
        gaps = np.abs(points[k:] - points[:-k]).max(axis=1)
        closing = (float(gaps[:k].max()), float(gaps[-k:].max()))
    regime = ("periodic" if k and exponent - half <= 0.0 else "chaotic" if not k and exponent - half > 0.0
              else "undetermined")
    return {"V": p["V"], "sections": len(points), "period": k, "closing": closing, "lyapunov": exponent,
            "half_width": half, "regime": regime}


@dataclass(frozen=True)
class _TwoBlockRegime:
    """:func:`two_block_regime` at one belt velocity (picklable, for a process pool)."""

    params: dict

    def __call__(self, V: float) -> dict:
        return two_block_regime({**self.params, "V": V})



def two_block_regimes(params: dict | None, velocities, workers: int | None = None) -> list[dict]:
    """:func:`two_block_regime` at each belt velocity (m/s), in the parallel backend's pool."""
    from converters.parallel import parallel_map
    return parallel_map(_TwoBlockRegime(dict(params or {})), [float(V) for V in velocities], workers=workers)
