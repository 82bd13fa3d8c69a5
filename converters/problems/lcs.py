"""Linear complementarity systems with a finite set of switch configurations.

    x' = A x + B u + E,   y = C x + D u + F,   0 <= u _|_ y >= 0,

with one (A, B, C, D, E, F) per switch configuration and a switching law saying which
configuration holds when (:mod:`converters.problems.schedule`, :mod:`converters.problems.switching`).
Problems are immutable; variants come from ``dataclasses.replace``.
Shapes: x has n entries, u and y have k (the same n and k in every configuration).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import ParameterError
from ..validate import as_matrix, as_vector, parse_value
from .schedule import Schedule
from .switching import Relay, StateSwitching


@dataclass(frozen=True)
class Configuration:
    """One switch configuration: the matrices of x' = A x + B u + E, y = C x + D u + F.

    Shapes: A (n, n), B (n, k), C (k, n), D (k, k), E (n,), F (k,). E and F default to zero.
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    E: np.ndarray | None = None
    F: np.ndarray | None = None
    name: str = ""

    def __post_init__(self):
        label = f"configuration {self.name!r}: " if self.name else ""
        A = as_matrix(label + "A", self.A, (None, None))
        n = A.shape[0]
        if A.shape[1] != n:
            raise ParameterError(f"{label}A must be square (n x n); got shape {A.shape[0]}x{A.shape[1]}")
        B = as_matrix(label + "B", self.B, (n, None))
        k = B.shape[1]
        if k < 1:
            raise ParameterError(f"{label}B must have at least one column (k >= 1); got shape {n}x0")
        C = as_matrix(label + "C", self.C, (k, n))
        D = as_matrix(label + "D", self.D, (k, k))
        E = np.zeros(n) if self.E is None else as_vector(label + "E", self.E, n)
        F = np.zeros(k) if self.F is None else as_vector(label + "F", self.F, k)
        for key, value in zip("ABCDEF", (A, B, C, D, E, F)):
            value.setflags(write=False)
            object.__setattr__(self, key, value)

    @property
    def n(self) -> int:
        return self.A.shape[0]

    @property
    def k(self) -> int:
        return self.B.shape[1]


@dataclass(frozen=True)
class LCSProblem:
    """An LCS initial-value problem: configurations, the switching law, x0 and the time span (s).

    Only the mathematics: no step size, no solver. ``switching`` is a :class:`Schedule` (time-driven),
    a :class:`~converters.problems.switching.StateSwitching` (hysteresis or latch on a switching
    function of the state) or a :class:`~converters.problems.switching.Relay` (the implicit relay).
    """

    configurations: tuple[Configuration, ...]
    switching: Schedule | StateSwitching | Relay
    x0: np.ndarray
    t_span: tuple[float, float]
    state_names: tuple[str, ...] = ()
    pair_names: tuple[str, ...] = ()
    metadata: dict = field(default_factory=dict, compare=False)

    def __post_init__(self):
        configs = tuple(self.configurations)
        if not configs:
            raise ParameterError("configurations must hold at least one Configuration; got none")
        n, k = configs[0].n, configs[0].k
        for c in configs[1:]:
            if (c.n, c.k) != (n, k):
                raise ParameterError(f"every configuration must have the same n and k; configuration "
                                     f"{c.name!r} has n = {c.n}, k = {c.k}, the first n = {n}, k = {k}")
        if not isinstance(self.switching, (Schedule, StateSwitching, Relay)):
            raise ParameterError(f"switching must be a Schedule, StateSwitching or Relay; got {self.switching!r}")
        bad = [c for c in self.switching.configs if not 0 <= c < len(configs)]
        if bad:
            raise ParameterError(f"switching configs must be indices in [0, {len(configs) - 1}]; got {bad[0]}")
        function = getattr(self.switching, "function", None)
        if function is not None and function.n != n:
            raise ParameterError(f"the switching function must have one coefficient per state (n = {n}); "
                                 f"got {function.n}")
        x0 = as_vector("x0", self.x0, n)
        x0.setflags(write=False)
        if isinstance(self.t_span, (str, bytes)) or not hasattr(self.t_span, "__len__") or len(self.t_span) != 2:
            raise ParameterError(f"t_span must be (t_start, t_end) in s; got {self.t_span!r}")   # "01", (0, 1, 2)
        t0, t1 = (parse_value("t_span[0]", self.t_span[0]), parse_value("t_span[1]", self.t_span[1]))
        if not t1 > t0:
            raise ParameterError(f"t_span must satisfy t_end > t_start = {t0:g} s; got t_end = {t1:g}")
        states = tuple(self.state_names) or tuple(f"x{i}" for i in range(n))
        pairs = tuple(self.pair_names) or tuple(f"pair{i}" for i in range(k))
        if len(states) != n or len(pairs) != k:
            raise ParameterError(f"state_names must have n = {n} and pair_names k = {k} entries; "
                                 f"got {len(states)} and {len(pairs)}")
        object.__setattr__(self, "configurations", configs)
        object.__setattr__(self, "x0", x0)
        object.__setattr__(self, "t_span", (t0, t1))
        object.__setattr__(self, "state_names", states)
        object.__setattr__(self, "pair_names", pairs)

    @property
    def n(self) -> int:
        return self.configurations[0].n

    @property
    def k(self) -> int:
        return self.configurations[0].k

    @property
    def period(self) -> float:
        """The switching law's clock period T (s), inf when it has none: what stroboscopic maps step by."""
        return self.switching.period
