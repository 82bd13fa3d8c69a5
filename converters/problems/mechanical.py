"""Mechanical systems with dry friction and unilateral contacts: Lagrangian problems with set-valued laws.

    M q'' + C q' + K q = f(t) + sum_i w_i lambda_i + sum_j n_j Lambda_j,       x = (q, v), v = q'

* Friction contact i (a relay on a relative velocity): s_i = w_i . v - V_i (V_i: the belt's velocity).
  Slipping, lambda_i = -F_i(s_i) sign(s_i) with F_i(s) = N_i mu_i(s) >= 0; sticking (s_i held at 0),
  |lambda_i| <= F_i(0), the static friction. Popp's law: mu(s) = alpha / (1 + gamma |s|) + beta + eta s^2
  (Filippov; di Bernardo, Kowalczyk and Nordmark 2002). This is Filippov's convex combination of the two slip vector fields, written as
  Utkin's equivalent control: the stick force is what keeps s_i = 0.
* Unilateral contact j: gap g_j = n_j . q + c_j(t) >= 0 (c_j a given function of time, e.g. minus a cam's
  lift), Lambda_j >= 0, g_j Lambda_j = 0; an impact at g_j = 0 with g_j' < 0 follows Newton's law
  g_j'(+) = -e_j g_j'(-).

Only the mathematics: no step, no solver (:mod:`converters.methods` solve it). Functions of time are
picklable objects (workers rebuild nothing). Units are the model's (SI for the models shipped).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

from ..errors import ParameterError
from ..validate import as_matrix, as_vector, parse_value


@dataclass(frozen=True)
class PoppFriction:
    """F(s) = N (alpha / (1 + gamma |s|) + beta + eta s^2): Popp's measured characteristic, times the normal
    load N. Coulomb friction is alpha = eta = 0 (F = N beta at any speed)."""

    normal: float
    alpha: float = 0.3
    gamma: float = 1.42
    beta: float = 0.1
    eta: float = 0.01

    def __post_init__(self) -> None:
        for name in ("normal", "alpha", "gamma", "beta", "eta"):
            value = parse_value(f"friction {name}", getattr(self, name))
            if value < 0.0:
                raise ParameterError(f"friction {name} must be >= 0; got {value!r}")
            object.__setattr__(self, name, value)

    def magnitude(self, s: float | npt.NDArray[np.float64]) -> float | npt.NDArray[np.float64]:
        a = abs(s) if isinstance(s, float) else np.abs(s)
        return self.normal * (self.alpha / (1.0 + self.gamma * a) + self.beta + self.eta * a * a)

    def slope(self, s: float | npt.NDArray[np.float64]) -> float | npt.NDArray[np.float64]:
        """d F / d s (a sign-carrying derivative: F is even in s)."""
        a = np.abs(s)
        return self.normal * np.sign(s) * (-self.alpha * self.gamma / (1.0 + self.gamma * a) ** 2 + 2.0 * self.eta * a)

    def branch(self, a: float) -> float:
        """F on one side of s = 0 as a smooth function of a = sign * s (>= 0 on that side), continued past 0."""
        return self.normal * (self.alpha / (1.0 + self.gamma * a) + self.beta + self.eta * a * a)

    def branch_slope(self, a: float) -> float:
        """d branch / d a."""
        return self.normal * (-self.alpha * self.gamma / (1.0 + self.gamma * a) ** 2 + 2.0 * self.eta * a)

    @property
    def static(self) -> float:
        """The largest stick force, F(0) = N (alpha + beta)."""
        return self.normal * (self.alpha + self.beta)


@dataclass(frozen=True)
class FrictionContact:
    """A relay on s = direction . v - belt with the friction ``law``."""

    direction: np.ndarray
    law: PoppFriction
    belt: float = 0.0
    name: str = "friction"

    def __post_init__(self) -> None:
        d = as_vector(f"{self.name} direction", self.direction, None)
        d.setflags(write=False)
        object.__setattr__(self, "direction", d)
        object.__setattr__(self, "belt", parse_value(f"{self.name} belt velocity", self.belt))


@dataclass(frozen=True)
class ZeroOffset:
    """c(t) = 0."""

    def __call__(self, t: npt.ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        zero = np.zeros_like(np.asarray(t, dtype=float))
        return zero, zero, zero


@dataclass(frozen=True)
class UnilateralContact:
    """g = direction . q + offset(t) >= 0 with Newton restitution ``restitution`` in [0, 1]; ``offset(t)``
    returns (c, c', c'')."""

    direction: np.ndarray
    restitution: float
    offset: object = field(default_factory=ZeroOffset)
    name: str = "contact"

    def __post_init__(self) -> None:
        d = as_vector(f"{self.name} direction", self.direction, None)
        d.setflags(write=False)
        object.__setattr__(self, "direction", d)
        e = parse_value(f"{self.name} restitution", self.restitution)
        if not 0.0 <= e <= 1.0:
            raise ParameterError(f"restitution e must be in [0, 1]; got {e!r}")
        object.__setattr__(self, "restitution", e)


@dataclass(frozen=True)
class HarmonicForce:
    """f(t) = amplitude cos(omega t + phase) + constant, vectors of n entries."""

    amplitude: np.ndarray
    omega: float
    phase: float = 0.0
    constant: np.ndarray | None = None

    def __post_init__(self) -> None:
        amplitude = np.array(self.amplitude, dtype=float)
        amplitude.setflags(write=False)
        object.__setattr__(self, "amplitude", amplitude)
        object.__setattr__(self, "omega", parse_value("omega", self.omega))
        if self.constant is not None:
            constant = np.array(self.constant, dtype=float)
            constant.setflags(write=False)
            object.__setattr__(self, "constant", constant)

    def __call__(self, t: float) -> np.ndarray:
        out = self.amplitude * math.cos(self.omega * t + self.phase)
        return out if self.constant is None else out + self.constant

    def on_grid(self, t: np.ndarray) -> np.ndarray:
        """f at every time of ``t``, shape (len(t), n)."""
        out = np.multiply.outer(np.cos(self.omega * np.asarray(t, dtype=float) + self.phase), self.amplitude)
        return out if self.constant is None else out + self.constant


@dataclass(frozen=True)
class MechanicalProblem:
    """A Lagrangian initial-value problem with friction relays and unilateral contacts (module docstring).

    Parameters
    ----------
    mass, damping, stiffness : array_like, shape (n, n)
        M (symmetric positive definite), C, K.
    force : callable or None
        f(t) -> shape (n,); None: no external force.
    frictions, contacts : tuples of FrictionContact, UnilateralContact
    x0 : array_like, shape (2 n,)
        (q0, v0).
    t_span : (t0, t1)
    period : float
        The forcing's period (stroboscopic maps step by it); inf for an autonomous system.
    """

    mass: np.ndarray
    damping: np.ndarray
    stiffness: np.ndarray
    force: object
    frictions: tuple = ()
    contacts: tuple = ()
    x0: np.ndarray = None
    t_span: tuple = (0.0, 1.0)
    period: float = np.inf
    state_names: tuple = ()
    metadata: dict = field(default_factory=dict, compare=False)

    def __post_init__(self) -> None:
        M = as_matrix("mass", self.mass, (None, None))
        n = M.shape[0]
        if M.shape[1] != n or not np.allclose(M, M.T) or np.any(np.linalg.eigvalsh(0.5 * (M + M.T)) <= 0.0):
            raise ParameterError(f"mass must be a symmetric positive definite n x n matrix; got {M.tolist()}")
        C = as_matrix("damping", self.damping, (n, n))
        K = as_matrix("stiffness", self.stiffness, (n, n))
        for item in tuple(self.frictions) + tuple(self.contacts):
            if item.direction.shape != (n,):
                raise ParameterError(f"{item.name} direction must have n = {n} entries; got {item.direction.shape[0]}")
        x0 = as_vector("x0", np.zeros(2 * n) if self.x0 is None else self.x0, 2 * n)
        t0, t1 = parse_value("t_span[0]", self.t_span[0]), parse_value("t_span[1]", self.t_span[1])
        if not t1 > t0:
            raise ParameterError(f"t_span must satisfy t_end > t_start = {t0:g} s; got t_end = {t1:g}")
        period = float(self.period)
        if not (period > 0.0):
            raise ParameterError(f"period must be positive (inf: autonomous); got {period!r}")
        names = tuple(self.state_names) or tuple(f"q{i}" for i in range(n)) + tuple(f"v{i}" for i in range(n))
        if len(names) != 2 * n:
            raise ParameterError(f"state_names must have 2 n = {2 * n} entries; got {len(names)}")
        for key, value in (("mass", M), ("damping", C), ("stiffness", K), ("x0", x0)):
            value.setflags(write=False)
            object.__setattr__(self, key, value)
        object.__setattr__(self, "frictions", tuple(self.frictions))
        object.__setattr__(self, "contacts", tuple(self.contacts))
        object.__setattr__(self, "t_span", (t0, t1))
        object.__setattr__(self, "period", period)
        object.__setattr__(self, "state_names", names)

    @property
    def dof(self) -> int:
        """Degrees of freedom."""
        return self.mass.shape[0]

    @property
    def n(self) -> int:
        """State dimension, 2 dof: (q, v)."""
        return 2 * self.mass.shape[0]

    @property
    def pair_names(self) -> tuple[str, ...]:
        """The set-valued laws: friction contacts, then unilateral contacts."""
        return tuple(c.name for c in self.frictions) + tuple(c.name for c in self.contacts)

    #: What an event's ``config`` means for a friction contact (the state entered) and for a unilateral contact.
    config_names = ("stick", "slip+", "slip-", "closed", "open")

    def external(self, t: float) -> np.ndarray:
        return np.zeros(self.dof) if self.force is None else np.array(self.force(t), dtype=float)


__all__ = ["MechanicalProblem", "FrictionContact", "UnilateralContact", "PoppFriction", "HarmonicForce", "ZeroOffset"]
