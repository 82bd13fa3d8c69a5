"""Linear complementarity systems with a finite set of switch configurations.

    x' = A x + B u + E,   y = C x + D u + F,   0 <= u _|_ y >= 0,

with one (A, B, C, D, E, F) per switch configuration and a switching law saying which
configuration holds when (:mod:`converters.problems.schedule`, :mod:`converters.problems.switching`).
Problems are immutable; variants come from ``dataclasses.replace``.
Shapes: x has n entries, u and y have k (the same n and k in every configuration).

A configuration may carry a :class:`Jump`: closing a switch across a charged capacitance ties capacitor voltages
that were free, and an ideal switch moves the charge at once (an impulse of current: Acary, Bonnefon and
Brogliato 2011, sec. 2.5 and ch. 4, the circuit's counterpart of an impact). Entering the configuration, the state
is projected onto the loops' constraints by charge conservation, and the energy 1/2 C dv^2 of the redistribution is
lost (in the switch that closed; with a small on-resistance SPICE dissipates the same in it).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import TypeAlias

import numpy as np
import numpy.typing as npt

from ..errors import ParameterError
from ..validate import as_matrix, as_vector, parse_value
from .schedule import Schedule
from .switching import Comparators, Relay, StateSwitching

#: What decides which configuration holds when (an :class:`LCSProblem`'s ``switching``).
SwitchingLaw: TypeAlias = "Schedule | StateSwitching | Comparators | Relay"


@dataclass(frozen=True)
class Jump:
    """The state's jump entering a configuration whose loops of capacitors (through closed switches and DC
    sources) tie voltages: x+ = P x + q, the smallest change in the capacitances' metric W that meets the loops'
    K x = b (P = I - W^-1 K^T (K W^-1 K^T)^-1 K on the capacitors' voltages, identity on the other states): the
    charge each loop moves is conserved. P is a projection (P P = P, P q = 0): a state already on the loops does
    not move, so a method may apply it at every step of the configuration. The energy lost is
    1/2 (x+ - x)^T W (x+ - x): the loops' sources deliver b^T lambda and the capacitors store b^T lambda minus it.

    Shapes: P (n, n), q (n,), W (n, n) (W: the capacitances on the capacitors' voltages, 0 elsewhere)."""

    P: np.ndarray
    q: np.ndarray
    W: np.ndarray

    def __post_init__(self) -> None:
        P = as_matrix("jump P", self.P, (None, None))
        n = P.shape[0]
        q, W = as_vector("jump q", self.q, n), as_matrix("jump W", self.W, (n, n))
        for key, value in (("P", P), ("q", q), ("W", W)):
            value.setflags(write=False)
            object.__setattr__(self, key, value)

    def __call__(self, x: np.ndarray) -> np.ndarray:
        """The state after the jump from ``x`` (shape (n,) or (N, n))."""
        return np.asarray(x, dtype=float) @ self.P.T + self.q

    def loss(self, x: np.ndarray) -> np.ndarray:
        """The energy (J) the jump from ``x`` dissipates (per row of a (N, n) array)."""
        d = self(x) - np.asarray(x, dtype=float)
        return 0.5 * np.einsum("...i,ij,...j->...", d, self.W, d)

    def permuted(self, order: list[int]) -> "Jump":
        """The jump on states reordered (x_new = x[order])."""
        ix = np.ix_(order, order)
        return Jump(P=self.P[ix], q=self.q[order], W=self.W[ix])


@dataclass(frozen=True)
class Configuration:
    """One switch configuration: the matrices of x' = A x + B u + E, y = C x + D u + F.

    Shapes: A (n, n), B (n, k), C (k, n), D (k, k), E (n,), F (k,). E and F default to zero. ``jump``: the
    state's jump entering it (:class:`Jump`), or None.
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    E: np.ndarray | None = None
    F: np.ndarray | None = None
    name: str = ""
    jump: Jump | None = None

    def __post_init__(self) -> None:
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
        if self.jump is not None and (not isinstance(self.jump, Jump) or self.jump.P.shape != (n, n)):
            raise ParameterError(f"{label}jump must be a Jump on the n = {n} states or None; got {self.jump!r}")

    @property
    def n(self) -> int:
        return self.A.shape[0]

    @property
    def k(self) -> int:
        return self.B.shape[1]

    def same_columns(self, i: int, j: int) -> bool:
        """Pairs i and j act alike (equal columns of B and D: what u does to x and to every y), to 1e-12 of the
        larger: two diodes in series through a winding carry one current, the winding's."""
        columns = np.vstack([self.B, self.D])[:, [i, j]]
        scale = max(float(np.abs(columns).max()), 1e-300)
        return bool(np.abs(columns[:, 0] - columns[:, 1]).max() <= 1e-12 * scale)

    def twin_ports(self) -> dict[int, tuple[int, ...]]:
        """{pair: the other pairs with the same port}: equal columns (:meth:`same_columns`) and equal rows of C and
        D (what each y reads), to 1e-12 of the larger: the same port twice over (two diodes in series through a
        winding). The LCP's solution set then holds every split of u_i + u_j, and the state, which sees only the
        sum, is unique."""
        columns, rows = np.vstack([self.B, self.D]).T, np.hstack([self.C, self.D])   # (built once: k^2 pairs)

        def alike(a: np.ndarray, b: np.ndarray) -> bool:
            return bool(np.abs(a - b).max() <= 1e-12 * max(float(np.abs(a).max()), float(np.abs(b).max()), 1e-300))

        def same(i: int, j: int) -> bool:
            return alike(columns[i], columns[j]) and alike(rows[i], rows[j])
        return {i: tuple(j for j in range(self.k) if j != i and same(i, j)) for i in range(self.k)}


@dataclass(frozen=True)
class Sinusoids:
    """Sinusoidal inputs (AC sources) added to each configuration's E and F:

        E_c(t) = E_c + sum_j E[c, j] sin(omega_j t + phase_j),   F_c(t) likewise with F[c, j],

    shapes omega, phase (m,), E (configurations, m, n), F (configurations, m, k); omega in rad/s, phase in rad.
    Every omega_j T must be a whole multiple of 2 pi for the problem's period T (the inputs repeat with it)."""

    omega: np.ndarray
    phase: np.ndarray
    E: np.ndarray
    F: np.ndarray

    def __post_init__(self) -> None:
        omega, phase = (np.asarray(getattr(self, key), dtype=float).reshape(-1) for key in ("omega", "phase"))
        E, F = (np.asarray(getattr(self, key), dtype=float) for key in ("E", "F"))
        m = omega.size
        if phase.size != m or E.ndim != 3 or F.ndim != 3 or E.shape[1] != m or F.shape[1] != m \
                or E.shape[0] != F.shape[0]:
            raise ParameterError(f"sinusoids: omega and phase (m,), E (configurations, m, n) and F (configurations, m, "
                                 f"k) must agree; got {omega.shape}, {phase.shape}, {E.shape}, {F.shape}")
        if not (np.all(np.isfinite(omega)) and np.all(omega > 0) and np.all(np.isfinite(phase))
                and np.all(np.isfinite(E)) and np.all(np.isfinite(F))):
            raise ParameterError("sinusoids: omega must be positive, and every value finite")
        for key, value in (("omega", omega), ("phase", phase), ("E", E), ("F", F)):
            value.setflags(write=False)
            object.__setattr__(self, key, value)

    def values(self, t: npt.ArrayLike) -> np.ndarray:
        """sin(omega_j t + phase_j) at each time, shape (len(t), m) (t a scalar: (m,))."""
        t = np.asarray(t, dtype=float)
        return np.sin(np.multiply.outer(t, self.omega) + self.phase)


@dataclass(frozen=True)
class LCSProblem:
    """An LCS initial-value problem: configurations, the switching law, x0 and the time span (s).

    Only the mathematics: no step size, no solver. ``switching`` is a :class:`Schedule` (time-driven),
    a :class:`~converters.problems.switching.StateSwitching` (hysteresis or latch on a switching
    function of the state), a :class:`~converters.problems.switching.Comparators` (several of them) or a
    :class:`~converters.problems.switching.Relay` (the implicit relay).
    """

    configurations: tuple[Configuration, ...]
    switching: SwitchingLaw
    x0: np.ndarray
    t_span: tuple[float, float]
    state_names: tuple[str, ...] = ()
    pair_names: tuple[str, ...] = ()
    metadata: dict = field(default_factory=dict, compare=False)
    #: Sinusoidal inputs (AC sources) on top of each configuration's constant E and F, or None.
    inputs: Sinusoids | None = None
    #: Per configuration and pair, whether u is the device's current (else its voltage; the model's rule of which
    #: side of a pair conducts), or None: what a run reports of a pair it holds at zero current and voltage.
    pair_currents: tuple[tuple[bool, ...], ...] | None = field(default=None, compare=False)

    def __post_init__(self) -> None:
        configs = tuple(self.configurations)
        if not configs:
            raise ParameterError("configurations must hold at least one Configuration; got none")
        n, k = configs[0].n, configs[0].k
        for c in configs[1:]:
            if (c.n, c.k) != (n, k):
                raise ParameterError(f"every configuration must have the same n and k; configuration "
                                     f"{c.name!r} has n = {c.n}, k = {c.k}, the first n = {n}, k = {k}")
        if not isinstance(self.switching, (Schedule, StateSwitching, Comparators, Relay)):
            raise ParameterError(f"switching must be a Schedule, StateSwitching, Comparators or Relay; got "
                                 f"{self.switching!r}")
        bad = [c for c in self.switching.configs if not 0 <= c < len(configs)]
        if bad:
            raise ParameterError(f"switching configs must be indices in [0, {len(configs) - 1}]; got {bad[0]}")
        laws = self.switching.channels if isinstance(self.switching, Comparators) else (self.switching,)
        for function in (getattr(law, "function", None) for law in laws):
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
        if self.inputs is not None:
            if not isinstance(self.inputs, Sinusoids):
                raise ParameterError(f"inputs must be Sinusoids or None; got {self.inputs!r}")
            if self.inputs.E.shape[0] != len(configs) or self.inputs.E.shape[2] != n or self.inputs.F.shape[2] != k:
                raise ParameterError(f"inputs: E must be ({len(configs)}, m, {n}) and F ({len(configs)}, m, {k}); got "
                                     f"{self.inputs.E.shape} and {self.inputs.F.shape}")
            T = self.switching.period
            cycles = self.inputs.omega * T / (2 * np.pi)
            if not (np.isfinite(T) and np.all(np.abs(cycles - np.round(cycles)) <= 1e-9 * np.maximum(cycles, 1.0))):
                raise ParameterError(f"inputs: each sinusoid must repeat with the switching law's period T = {T:g} s "
                                     "(omega T a whole multiple of 2 pi)")
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
    def jumps(self) -> bool:
        """Whether a configuration's entry jumps the state (:class:`Jump`)."""
        return any(c.jump is not None for c in self.configurations)

    def configuration_at(self, index: int, t_e: float, t_f: float | None = None) -> Configuration:
        """Configuration ``index`` with its sinusoidal inputs evaluated: E at t_e, F at t_f (default t_e)."""
        c = self.configurations[index]
        if self.inputs is None:
            return c
        from dataclasses import replace
        t_f = t_e if t_f is None else t_f
        return replace(c, E=c.E + self.inputs.values(t_e) @ self.inputs.E[index],
                       F=c.F + self.inputs.values(t_f) @ self.inputs.F[index])

    @property
    def period(self) -> float:
        """The switching law's clock period T (s), inf when it has none: what stroboscopic maps step by."""
        return self.switching.period
