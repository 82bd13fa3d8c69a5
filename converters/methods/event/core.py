"""The event method's core, shared by its engines (one per problem type, as Siconos has one integrator per
dynamical-system type: :mod:`.machine` for LCS, exact flows; :mod:`.mechanical` for mechanical problems with
friction and impacts, DOP853 between events): the piecewise solution an engine's run returns (segments, the events
between them, samples on an output grid, the event table) and the period map over an engine's runs.

An engine is a class built from (problem, options) whose ``period_run(x0, jacobian)`` returns (solution, the
Jacobian of the span's end state or None) and whose ``run(x0)`` returns the recorded solution first."""
from __future__ import annotations

from collections.abc import Iterable, Sequence
from typing import TYPE_CHECKING, Any, NamedTuple, Protocol

import numpy as np
import numpy.typing as npt

from ..base import RecordingPeriodMap

if TYPE_CHECKING:
    from ...problems import LCSProblem
    from ...problems.mechanical import MechanicalProblem
    from . import EventDriven


class Event(NamedTuple):
    """One event of a run: its ``time`` (s), ``kind`` (``activate``, ``release``, ``impulse``, ``switch``, ``jump``,
    and the mechanical ``stick``, ``slip``, ...), the ``pair`` (-1 for a switching-law event) and ``config`` (the
    configuration or mode code in force after it). A tuple: (time, kind, pair, config) unpacks as before."""

    time: float
    kind: str
    pair: int
    config: int


class Span(Protocol):
    """What the core reads of an engine's segment: where it starts and ends (s)."""

    t0: float
    t1: float


class PiecewiseSolution:
    """An engine's run: ``segments`` (each with t0 and t1), ``events`` (:class:`Event` records in time order),
    ``x_end``."""

    def __init__(self, problem: LCSProblem | MechanicalProblem, segments: Sequence[Span],
                 events: Iterable[tuple[float, str, int, int]], x_end: npt.NDArray[np.float64], wall_s: float,
                 options: EventDriven) -> None:
        self.problem, self.segments = problem, segments
        self.events = [Event(*event) for event in events]
        self.x_end, self.wall_s, self.options = x_end, wall_s, options

    def event_list(self) -> list[Event]:
        """(time, kind, pair, config) of every event, in time order."""
        return list(self.events)

    # each field of the events on its own, in time order
    event_times = property(lambda self: [e[0] for e in self.events])
    event_kinds = property(lambda self: [e[1] for e in self.events])
    event_pairs = property(lambda self: [e[2] for e in self.events])
    event_configs = property(lambda self: [e[3] for e in self.events])

    def events_table(self, t: np.ndarray) -> dict[str, npt.NDArray[Any]]:
        """The events as a Trajectory's event columns; ``step``: the last sample of ``t`` before each."""
        times = np.array([e[0] for e in self.events], dtype=float)
        return {"time": times, "step": np.searchsorted(t, times) - 1,
                "pair": np.array([e[2] for e in self.events], dtype=np.int64),
                "kind": np.array([e[1] for e in self.events], dtype=object),
                "config": np.array([e[3] for e in self.events], dtype=np.int64)}

    def output_times(self, output_step: float) -> np.ndarray:
        """A uniform grid of ``output_step`` over the span, every segment's end and the span's end, points closer
        than 1e-12 of the step merged."""
        t0, t1 = self.problem.t_span
        grid = t0 + output_step * np.arange(int(np.floor((t1 - t0) / output_step * (1 + 1e-12))) + 1)
        t = np.unique(np.concatenate([grid[grid <= t1], [s.t1 for s in self.segments], [t1]]))
        merged: npt.NDArray[np.float64] = t[np.concatenate([[True], np.diff(t) > 1e-12 * output_step])]
        return merged


class Engine(Protocol):
    """What the period map asks of an engine (module docstring)."""

    def period_run(self, x0: npt.NDArray[np.float64],
                   jacobian: bool) -> tuple[PiecewiseSolution, npt.NDArray[np.float64] | None]: ...


class EnginePeriodMap(RecordingPeriodMap):
    """x(t0) -> x(t1) over the problem's span by an engine's runs, with the engine's Jacobian (state-transition
    and saltation matrices); it keeps the events of its last run."""

    def __init__(self, engine: Engine) -> None:
        super().__init__()
        self.machine = engine

    def _solve(self, x0: npt.NDArray[np.float64],
               jacobian: bool) -> tuple[PiecewiseSolution, npt.NDArray[np.float64] | None]:
        return self.machine.period_run(x0, jacobian)
