"""The typed result of a simulation, convertible to pandas."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pandas as pd


@dataclass(frozen=True)
class Trajectory:
    """Time series of an LCS simulation. SI units throughout (s, A, V).

    Attributes
    ----------
    t : ndarray, shape (N,)
        Time points (the uniform grid plus every schedule switching instant).
    x : ndarray, shape (N, n)
        States; columns named by ``state_names``.
    u, y : ndarray, shape (N, k)
        Complementarity pairs (0 <= u _|_ y >= 0); row 0 holds the consistent initial pair.
    config : ndarray of int, shape (N,)
        Configuration of the step that arrived at each point (row 0: of the first step).
    events : pandas.DataFrame (property)
        Columns ``time`` (sub-step estimate from the step's own LCP data), ``step``, ``pair`` and
        ``kind`` (``activate``: u becomes positive; ``release``: u returns to zero). Built on first
        access from ``event_columns`` (a dict of equal-length arrays, or a DataFrame): a pandas table
        costs more than a short run itself.
    wall_s : float
        Seconds spent building the step matrices and stepping.
    """

    t: np.ndarray
    x: np.ndarray
    u: np.ndarray
    y: np.ndarray
    config: np.ndarray
    state_names: tuple[str, ...]
    pair_names: tuple[str, ...]
    config_names: tuple[str, ...]
    event_columns: object
    method: str
    steps: int
    wall_s: float
    general_solves: int = 0
    metadata: dict = field(default_factory=dict, compare=False)

    @property
    def events(self) -> pd.DataFrame:
        frame = self.__dict__.get("_events_frame")
        if frame is None:
            columns = self.event_columns
            frame = columns if isinstance(columns, pd.DataFrame) else pd.DataFrame(columns)
            object.__setattr__(self, "_events_frame", frame)
        return frame

    @property
    def active(self) -> np.ndarray:
        """Complementarity mode flags, shape (N, k): True where u > y (u carries the pair)."""
        return self.u > self.y

    def state(self, name: str) -> np.ndarray:
        try:
            return self.x[:, self.state_names.index(name)]
        except ValueError:
            raise KeyError(f"state must be one of {', '.join(self.state_names)}; got {name!r}") from None

    def to_pandas(self) -> pd.DataFrame:
        """Columns: time, one per state, u_<pair>, y_<pair>, config (name), one per pair ``active_<pair>``."""
        data = {"time": self.t}
        for i, name in enumerate(self.state_names):
            data[name] = self.x[:, i]
        active = self.active
        for i, name in enumerate(self.pair_names):
            data[f"u_{name}"] = self.u[:, i]
            data[f"y_{name}"] = self.y[:, i]
            data[f"active_{name}"] = active[:, i]
        data["config"] = pd.Categorical.from_codes(self.config, categories=list(self.config_names))
        return pd.DataFrame(data)
