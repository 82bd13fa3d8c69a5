"""What a mechanical model provides: named parameters, the problem it builds, and how its runs read.

A mechanical model builds a :class:`~converters.problems.mechanical.MechanicalProblem` from validated
parameters; every method that takes mechanical problems (the event method, Moreau-Jean) solves it, and the
analysis (periodic orbits, continuation, brute-force diagrams) works on it unchanged. Its labels name the
signals a run adds (relative velocities, friction and contact forces, gaps) and the mode of each point
(``stick``, ``slip+``, ``slip-`` per friction contact; ``contact``, ``flight`` per unilateral contact).
"""
from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt

from ...params import Param, resolve
from ...problems.mechanical import MechanicalProblem
from ...trajectory import Samples
from ..base import BoundLabels

if TYPE_CHECKING:
    from ...trajectory import Trajectory

_STATE_LABELS = {0: "stick", 1: "slip+", 2: "slip-", 3: "contact", 4: "flight"}


@dataclass(frozen=True)
class MechanicalLabels(BoundLabels):
    """A mechanical model's reading of a run: signals from the pairs (u: forces, y: velocities and gaps)."""

    def mode_labels_of(self, samples: Samples) -> np.ndarray:
        """Per point: each set-valued law's state, joined with '+' when there are several (``stick+slip-``)."""
        m = len(self.model.friction_names)
        k = m + len(self.model.contact_names)
        codes = np.asarray(samples.config, dtype=np.int64)
        states = (codes[:, None] // (5 ** np.arange(k))[None, :]) % 5
        names = np.vectorize(_STATE_LABELS.get, otypes=[object])(states)
        return names[:, 0] if k == 1 else np.array(["+".join(row) for row in names], dtype=object)


class MechanicalModel(ABC):
    """A parametrised family of mechanical problems."""

    name: str
    title: str
    parameters: tuple[Param, ...]
    state_names: tuple[str, ...]
    friction_names: tuple[str, ...] = ()
    contact_names: tuple[str, ...] = ()
    #: The bifurcation parameter a diagram sweeps by default, and the state it draws.
    sweep: str = ""
    output_state: str = ""
    #: What its brute-force diagram shows: ``stroboscopic`` (the state at each forcing period), ``section`` (a
    #: state where friction pair 0 starts to stick), ``impacts`` (the phase of each impact), or "" (none).
    diagram: str = ""
    #: True where periodic orbits and their sliding bifurcations can be followed (a forced Filippov system).
    sliding: bool = False

    def resolve(self, given: dict | None = None) -> dict:
        return resolve(self.parameters, dict(given or {}), self.name)

    @property
    def key(self) -> str:
        return self.name

    @abstractmethod
    def problem(self, p: dict, t_end: float, x0: npt.NDArray[np.float64] | None = None,
                t_start: float = 0.0) -> MechanicalProblem:
        """The problem over [t_start, t_end] from x0 (default: the model's start state)."""

    @abstractmethod
    def period(self, p: dict) -> float:
        """The forcing period (s), inf for an autonomous system."""

    def periodic(self, p: dict) -> bool:
        return bool(np.isfinite(self.period(p)))

    def time_scale(self, p: dict) -> float:
        """A natural time unit: the forcing period, or the model's own for an autonomous system."""
        return self.period(p)

    def default_h(self, p: dict) -> float:
        """The Moreau-Jean step: 1/2000 of the time scale."""
        return self.time_scale(p) / 2000.0

    @property
    def signal_names(self) -> tuple[str, ...]:
        return tuple(f"v_rel_{n}" for n in self.friction_names) + tuple(f"friction_{n}" for n in self.friction_names) \
            + tuple(f"gap_{n}" for n in self.contact_names) + tuple(f"force_{n}" for n in self.contact_names)

    def signal(self, name: str, samples: Samples, p: dict) -> np.ndarray:
        m = len(self.friction_names)
        for i, pair in enumerate(self.friction_names):
            if name == f"v_rel_{pair}":
                return samples.y[:, i]
            if name == f"friction_{pair}":
                return samples.u[:, i]
        for j, pair in enumerate(self.contact_names):
            if name == f"gap_{pair}":
                return samples.y[:, m + j]
            if name == f"force_{pair}":
                return samples.u[:, m + j]
        raise KeyError(f"signal must be one of {', '.join(self.signal_names)}; got {name!r}")

    def labels(self, p: dict) -> MechanicalLabels:
        return MechanicalLabels(self, p)

    def summary(self, tr: Trajectory, p: dict) -> dict:
        """Counts of the run's events by kind, and the time spent in each mode over the last time scale."""
        events = tr.events
        counts = events["kind"].value_counts().to_dict() if len(events) else {}
        t1 = tr.t[-1]
        t0 = max(tr.t[0], t1 - self.time_scale(p))
        return {"events": {str(k): int(v) for k, v in counts.items()},
                "mode_fractions": _fractions_at_events(tr, t0, t1)}


def _fractions_at_events(tr: Trajectory, t0: float, t1: float) -> dict[str, float]:
    """The time in each mode over [t0, t1], the mode before each event held up to its time: on the output grid
    alone each step is counted by its end point's mode, and a sample at an event carries the mode after it (the
    friction oscillator's slip+ read 0.130 for 0.1274194, one output sample, 2 %; a stick of 0.0095632 read
    0.010)."""
    import numpy as np
    fractions = tr.mode_fractions(None, t0=t0, t1=t1)
    table = tr.event_table()
    if table is None or not len(table["time"]):
        return fractions
    rows = tr.rows_between(t0, t1)
    t = tr.t[rows]
    labels = np.asarray(tr.modes(rows)).astype(str)
    seconds = {label: share * (t[-1] - t[0]) for label, share in fractions.items()}
    for when in np.asarray(table["time"], dtype=float):
        # the step (t[k-1], t[k]] ending at the event (a sample there carries the mode after it) or holding it
        k = int(np.searchsorted(t, when * (1 - 1e-15), side="left"))
        if not 0 < k < t.size or not t[k - 1] < when <= t[k] * (1 + 1e-15) or labels[k] == labels[k - 1]:
            continue
        moved = min(when, t[k]) - t[k - 1]                       # the part before the event: the earlier mode's
        seconds[labels[k]] -= moved
        seconds[labels[k - 1]] = seconds.get(labels[k - 1], 0.0) + moved
    total = t[-1] - t[0]
    return {label: float(value / total) for label, value in sorted(seconds.items())}
