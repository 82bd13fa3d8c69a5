"""What a linearisation about an event-method run reads (:mod:`converters.analysis.smallsignal`): the run's
segments and events as typed records, in time order (:meth:`.machine._Machine.timeline`).

``x~`` is the extended state of a flow (the circuit's state with its constant inputs appended: x~' = Z x~); a
``flow`` is the mode the machine integrates (its ``config``, ``held`` pairs, ``Z``, ``field(x~)``, ``watch_rows``).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Union

import numpy as np
import numpy.typing as npt

Vector = npt.NDArray[np.float64]
Matrix = npt.NDArray[np.float64]


@dataclass(frozen=True)
class FlowSpan:
    """One segment: the flow from t0 to t1 starting at x~(t0)."""

    t0: float
    t1: float
    flow: Any
    xt0: Vector


@dataclass(frozen=True)
class Crossing:
    """A state event: a guard (a pair's, or the switching law's when ``pair`` < 0) crosses zero at ``t``.

    ``row`` is the guard's row over x~, ``dgdt`` its explicit time slope (a ramp's); the fields f before and after
    the event, the state's ``jump`` (x+ = jump x- where the configuration entered redistributes charge; the identity
    otherwise), the flows and x~ on both sides, what the law had latched before, and the configuration after."""

    t: float
    row: Vector
    dgdt: float
    f_before: Vector
    f_after: Vector
    jump: Matrix
    pair: int
    flow_before: Any
    latched_before: int
    xt_before: Vector
    config: int
    flow_after: Any
    xt_after: Vector


@dataclass(frozen=True)
class Edge:
    """A time-driven instant: a schedule's edge (``kind`` the configuration entered), a clock's ``reset`` or a
    period's ``limit``; the state's ``jump``, the flows and x~ on both sides."""

    t: float
    kind: int | str
    config: int
    jump: Matrix
    xt_before: Vector
    flow_before: Any
    flow_after: Any
    xt_after: Vector


#: A run's timeline entry.
TimelineEntry = Union[FlowSpan, Crossing, Edge]
