"""Generalised discontinuous conduction (GDCM) from the matrices of a configuration, and the exact
conduction-mode prediction of a PWM converter (Batlle, Fossas, Merillas and Miralles 2005).

For one complementarity pair (k = 1) with D = 0 and C B > 0 in a configuration (A, B, C, E, F):

    GDCM set        C x + F = 0   and   C (A x + E) <= 0
    multiplier      u = -C (A x + E) / (C B) >= 0
    reduced flow    x' = P (A x + E),  P = I - B C / (C B)   (C P = 0: C x + F stays 0; dimension n - 1)
    exit            C (A x + E) > 0

The closed-form boundaries Kcrit(D) (:mod:`converters.models.analytic`) assume small ripple. The exact
prediction here needs no such assumption: the CCM orbit (every pair at u = 0) is computed exactly
with matrix exponentials, and the converter is in CCM if and only if that orbit keeps y = C x + F >= 0
in every configuration; where y would go negative, the pair must hold instead (DCM, or GDCM-ON in the
switch-on configuration).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt
from scipy.linalg import expm

from ..errors import ParameterError
from ..problems import Configuration, LCSProblem

if TYPE_CHECKING:
    from ..models.base import Model


@dataclass(frozen=True)
class GDCMCondition:
    """The GDCM condition of one single-pair configuration (see the module docstring)."""

    name: str
    possible: bool
    reason: str
    CB: float
    P: np.ndarray          # projector onto ker C along B, shape (n, n)
    A_red: np.ndarray      # P A
    E_red: np.ndarray      # P E
    config: Configuration

    def on_set(self, x: npt.ArrayLike) -> np.ndarray:
        """C x + F at each state (rows of x): zero on the GDCM set."""
        c = self.config
        return np.atleast_2d(x) @ c.C[0] + c.F[0]

    def drift(self, x: npt.ArrayLike) -> np.ndarray:
        """C (A x + E): non-positive while the GDCM persists; positive means exit."""
        c = self.config
        return (np.atleast_2d(x) @ c.A.T + c.E) @ c.C[0]

    def multiplier(self, x: npt.ArrayLike) -> np.ndarray:
        """u = -C (A x + E) / (C B), the pair's multiplier on the GDCM set."""
        return -self.drift(x) / self.CB

    def reduced_rhs(self, x: npt.ArrayLike) -> np.ndarray:
        return np.atleast_2d(x) @ self.A_red.T + self.E_red

    @property
    def reduced_dimension(self) -> int:
        return int(np.linalg.matrix_rank(self.P))


def gdcm_condition(config: Configuration) -> GDCMCondition:
    """The GDCM condition of a configuration with one complementarity pair."""
    n, k = config.n, config.k
    if k != 1:
        raise ParameterError(f"the single-pair GDCM condition needs k = 1; configuration {config.name!r} has "
                             f"k = {k} (report its mode combinations instead)")
    CB = float(config.C[0] @ config.B[:, 0])
    P = np.eye(n)
    possible, reason = True, "C x + F = 0 and C (A x + E) <= 0"
    if config.D[0, 0] != 0.0:
        possible, reason = False, f"D = {config.D[0, 0]:.3g} > 0: the pair does not constrain the state"
    elif CB <= 0.0:
        possible, reason = False, f"C B = {CB:.3g} <= 0: no non-negative multiplier holds y at 0"
    else:
        P = np.eye(n) - np.outer(config.B[:, 0], config.C[0]) / CB
    return GDCMCondition(config.name, possible, reason, CB, P, P @ config.A, P @ config.E, config)


@dataclass(frozen=True)
class CCMOrbit:
    """The exact CCM orbit of a periodically switched LCS (every pair at u = 0) and its y-margin."""

    x0: np.ndarray                 # state at the start of the period
    t: np.ndarray                  # sample times over one period
    x: np.ndarray                  # states at the samples, shape (S, n)
    y: np.ndarray                  # C x + F of the configuration holding at each sample, shape (S, k)
    config: np.ndarray             # configuration index per sample
    min_y: dict                    # configuration name -> min over its phase of min_i y_i

    def admissible(self, rtol: float = 0.0) -> bool:
        scale = max(1e-300, float(np.abs(self.y).max()))
        return all(v >= -rtol * scale for v in self.min_y.values())


def _augmented(config: Configuration, tau: float) -> np.ndarray:
    n = config.n
    aug = np.zeros((n + 1, n + 1))
    aug[:n, :n], aug[:n, n] = config.A, config.E
    return expm(aug * tau)


def ccm_orbit(problem: LCSProblem, samples_per_phase: int = 100) -> CCMOrbit:
    """Exact periodic orbit with every pair at u = 0 (matrix exponentials; no small-ripple assumption)."""
    from ..validate import check_integer
    check_integer("samples_per_phase", samples_per_phase, 1, 100_000)      # 1e9 had hung (0: a division by 0)
    schedule = problem.switching
    if not np.isfinite(schedule.period):
        raise ParameterError("ccm_orbit needs a periodic schedule; got a constant one")
    T, n = schedule.period, problem.n
    starts = list(schedule.starts) + [T]
    phases = [(problem.configurations[c], c, b - a) for c, a, b in zip(schedule.configs, starts[:-1], starts[1:])]
    total = np.eye(n + 1)
    steps = []
    for config, _, tau in phases:
        step = _augmented(config, tau / samples_per_phase)
        steps.append(step)
        total = np.linalg.matrix_power(step, samples_per_phase) @ total
    lhs = np.eye(n) - total[:n, :n]
    if abs(np.linalg.det(lhs)) < 1e-14:
        raise ParameterError("the CCM period map has a unit eigenvalue: no unique CCM orbit (undamped circuit)")
    x0 = np.linalg.solve(lhs, total[:n, n])
    min_y: dict[str, float]
    ts, xs, ys, cs, min_y = [], [], [], [], {}
    state, t0 = np.append(x0, 1.0), 0.0
    for (config, index, tau), step in zip(phases, steps):
        block = np.empty((samples_per_phase + 1, n + 1))
        block[0] = state
        for s in range(samples_per_phase):
            block[s + 1] = step @ block[s]
        xb = block[:, :n]
        yb = xb @ config.C.T + config.F
        ts.append(t0 + tau * np.arange(samples_per_phase + 1) / samples_per_phase)
        xs.append(xb), ys.append(yb), cs.append(np.full(samples_per_phase + 1, index))
        name = config.name or f"config{index}"
        min_y[name] = min(min_y.get(name, np.inf), float(yb.min()))
        state, t0 = block[-1], t0 + tau
    return CCMOrbit(x0, np.concatenate(ts), np.vstack(xs), np.vstack(ys), np.concatenate(cs), min_y)


def exact_mode(converter: Model, params: dict) -> dict:
    """Predicted conduction mode of a PWM converter from its matrices: CCM when the exact CCM orbit keeps
    every y >= 0; otherwise the pair holds in each configuration where y would go negative."""
    p = converter.resolve(params)
    problem = converter.problem(p, converter.period(p))
    orbit = ccm_orbit(problem)
    scale = float(np.abs(orbit.y).max()) or 1.0
    violated = [name for name, v in orbit.min_y.items() if v < -1e-12 * scale]
    labels = {"ON": "GDCM-ON", "OFF": converter.off_held_label}
    mode = "CCM" if not violated else "+".join(labels.get(name, f"held-{name}") for name in violated)
    return {"mode": mode, "min_y": orbit.min_y, "y_scale": scale}


def describe(converter: Model, params: dict) -> list[dict]:
    """Per configuration: the GDCM condition in words and numbers (for reports and `pcsuite gdcm`)."""
    p = converter.resolve(params)
    out = []
    for config in converter.configurations(p):
        if config.k != 1:
            out.append({"configuration": config.name, "possible": None,
                        "condition": f"k = {config.k} pairs: mode combinations are reported instead"})
            continue
        g = gdcm_condition(config)
        row = {"configuration": config.name, "possible": g.possible, "condition": g.reason, "CB": g.CB}
        if g.possible:
            row["reduced_dimension"] = g.reduced_dimension
            row["C"] = config.C[0].tolist()
            row["F"] = float(config.F[0])
        out.append(row)
    return out
