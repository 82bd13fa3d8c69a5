"""Maps with closed-form bifurcations, dressed as a problem family and a method, for the continuation and
brute-force engines: the engines see only ``problem.switching.period``, ``t_span``, ``Method.period_map``
(with its events) and ``Method.solve``.

* logistic   x -> p x (1 - x): period doubling at p = 3 and 1 + sqrt(6); period-2 orbit
             ((p + 1) +- sqrt((p - 3)(p + 1))) / (2 p); Lyapunov exponent ln 2 at p = 4.
* fold       x -> p + x - x^2: fixed points +-sqrt(p), a fold at p = 0 (multipliers 1 -+ 2 sqrt(p)).
* delayed    (x, y) -> (y, p y (1 - x)): fixed point 1 - 1/p, multipliers of modulus sqrt(p - 1): a
             Neimark-Sacker bifurcation at p = 2.
* tent       x -> p + a x (x < 0), p + b x (x >= 0), a = 0.5, b = -1.5: the fixed point p / (1 - a) < 0 for
             p < 0 and p / (1 - b) > 0 for p > 0 crosses the border x = 0 at p = 0, where its multiplier jumps
             from a to b, across -1 (a border collision that destabilises it, not a smooth period doubling).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from converters.methods.base import Method, PeriodMap
from converters.problems import Configuration, LCSProblem, Schedule
from converters.trajectory import Trajectory

#: Slopes of the tent map: left of the border a, right of it b.
TENT_A, TENT_B = 0.5, -1.5


def step(kind: str, p: float, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """One application of the map and its Jacobian."""
    if kind == "logistic":
        return np.array([p * x[0] * (1 - x[0])]), np.array([[p * (1 - 2 * x[0])]])
    if kind == "fold":
        return np.array([p + x[0] - x[0] ** 2]), np.array([[1 - 2 * x[0]]])
    if kind == "delayed":
        return np.array([x[1], p * x[1] * (1 - x[0])]), np.array([[0.0, 1.0], [-p * x[1], p * (1 - x[0])]])
    if kind == "tent":
        slope = TENT_A if x[0] < 0 else TENT_B
        return np.array([p + slope * x[0]]), np.array([[slope]])
    raise ValueError(kind)


DIMENSION = {"logistic": 1, "fold": 1, "delayed": 2, "tent": 1}


@dataclass(frozen=True)
class MapFamily:
    """value -> a problem whose metadata carries the map and the parameter (period 1 per application)."""

    kind: str

    def __call__(self, value: float) -> LCSProblem:
        n = DIMENSION[self.kind]
        config = Configuration(A=np.zeros((n, n)), B=np.zeros((n, 1)), C=np.zeros((1, n)), D=np.eye(1))
        return LCSProblem((config, config), Schedule(period=1.0, starts=(0.0,), configs=(0,)), np.zeros(n), (0.0, 1.0),
                          metadata={"kind": self.kind, "p": float(value)})


class _Map(PeriodMap):
    def __init__(self, kind, p, applications):
        super().__init__()
        self.kind, self.p, self.applications = kind, p, applications

    def __call__(self, x0):
        self.evaluations += 1
        x, jac = np.array(x0, dtype=float), np.eye(len(x0))
        for _ in range(self.applications):
            x, J = step(self.kind, self.p, x)
            jac = J @ jac
        return x, jac

    def events(self, x0):
        """The tent map's 'switching': which side of the border each application starts on."""
        x, out = np.array(x0, dtype=float), []
        for m in range(self.applications):
            if self.kind == "tent":
                out.append((float(m), "switch", -1, int(x[0] >= 0)))
            x = step(self.kind, self.p, x)[0]
        return out


@dataclass(frozen=True)
class MapMethod(Method):
    """Applies the problem's map once per unit of time."""

    @property
    def order(self) -> float:
        return float("inf")

    def period_map(self, problem):
        t0, t1 = problem.t_span
        return _Map(problem.metadata["kind"], problem.metadata["p"], int(round(t1 - t0)))

    def solve(self, problem, x0):
        t0, t1 = problem.t_span
        count = int(round(t1 - t0))
        xs = [np.array(x0, dtype=float)]
        for _ in range(count):
            xs.append(step(problem.metadata["kind"], problem.metadata["p"], xs[-1])[0])
        return Trajectory(t=t0 + np.arange(count + 1, dtype=float), x=np.array(xs),
                          state_names=problem.state_names, period=1.0)
