"""Moreau-Jean time-stepping of mechanical problems: one small LCP per step (Siconos' MoreauJeanOSI).

With the theta-method on the smooth part and impulses P over the step,

    (M + h theta C + h^2 theta^2 K) v+ = M v - h K q - h^2 theta (1 - theta) K v - h (1 - theta) C v
                                         + h (theta f(t+) + (1 - theta) f(t)) + H^T P
    q+ = q + h (theta v+ + (1 - theta) v)

so v+ = v_free + W H^T P. The impulses obey the set-valued laws at velocity level:

* friction i, a relay: P_i in [-h F_i, h F_i] with -s_i(+) in the normal cone there (s_i(+) = w_i . v+ - V_i);
  F_i is the law's magnitude at the step's starting velocity (the static value while stuck);
* unilateral contact j, active when its gap predicted half a step ahead along the free motion (to second order:
  the relative acceleration the step's free velocity gives included) is <= 0: Newton's impact law
  0 <= U_j(+) + e_j U_j <= ... _|_ P_j >= 0, U = n_j . v + c_j'(t).

Both at once are one LCP of size c + 2 m (a relay is an LCP of twice its size, Acary and Brogliato 2008:
[[D, I], [-I, 0]], [q + D lb; ub - lb]), solved by the compiled small-LCP kernel of :mod:`converters.lcp`
inside a compiled step loop (:mod:`.moreau_kernels`). The declared order is 1 (impulsive events inside a step); sticking is exact
(the relay holds s = 0 to rounding), impacts happen at the step ends (penetration O(h)).
"""
from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any, cast

import numpy as np
import numpy.typing as npt

from ..errors import ParameterError, SimulationError
from ..compiled import MAX_INLINE_K
from ..problems.mechanical import MechanicalProblem
from ..trajectory import Trajectory
from .base import Method, check_step_and_theta
from .event.mechanical import CLOSED, OPEN, SLIP_NEG, SLIP_POS, STICK

MAX_STEPS = 50_000_000


@dataclass(frozen=True)
class MoreauJean(Method, key="moreau"):
    """Moreau-Jean time-stepping of mechanical problems (module docstring).

    Parameters
    ----------
    h : float
        Step (s); each span is cut into whole steps of at most h (a whole number per forcing period).
    theta : float
        In [0.5, 1] (0.5: Siconos' example; 1: backward Euler on the smooth part).
    """

    h: float
    theta: float = 0.5
    step_option = "h"
    description = "Moreau-Jean time-stepper for mechanical problems: one LCP per step (friction relays, impacts)"
    domains = ("mechanical",)

    def __post_init__(self) -> None:
        check_step_and_theta(self)

    @property
    def order(self) -> float:
        return 1.0

    def supports(self, problem: object) -> None:
        if not isinstance(problem, MechanicalProblem):
            raise ParameterError("the Moreau-Jean method takes mechanical problems (MechanicalProblem); for a linear "
                                 "complementarity system use the LCP stepper (--method lcp)")
        k = len(problem.contacts) + 2 * len(problem.frictions)
        if k > MAX_INLINE_K:
            raise ParameterError(f"the Moreau-Jean step LCP has size c + 2 m = {k}; at most {MAX_INLINE_K} are solved "
                                 "inline")

    def grid(self, problem: MechanicalProblem) -> np.ndarray:
        t0, t1 = problem.t_span
        span = t1 - t0
        T = problem.period
        periods = span / T if np.isfinite(T) else 0.0
        if np.isfinite(T) and periods >= 1.0 and abs(periods - round(periods)) <= 1e-9 * periods:
            count = int(round(periods)) * int(np.ceil(T / self.h * (1.0 - 1e-12)))
        else:
            count = int(np.ceil(span / self.h * (1.0 - 1e-12)))
        if count > MAX_STEPS:
            raise ParameterError(f"h gives {count} steps over t_span; h must be >= {span / MAX_STEPS:.3g} s; got {self.h:g}")
        grid: np.ndarray = t0 + span * np.arange(count + 1) / count
        return grid

    def solve(self, problem: MechanicalProblem, x0: np.ndarray) -> Trajectory:
        clock = time.perf_counter()
        t = self.grid(problem)
        n, m, c = problem.dof, len(problem.frictions), len(problem.contacts)
        N = t.size - 1
        h = t[1] - t[0]
        q, v = np.empty((N + 1, n)), np.empty((N + 1, n))
        q[0], v[0] = x0[:n], x0[n:]
        impulse = np.zeros((N + 1, m + c))
        status = np.zeros((N + 1, m + c), dtype=np.int64)
        f = (np.array([problem.external(tt) for tt in t]) if not hasattr(problem.force, "on_grid")
             else problem.force.on_grid(t)) if problem.force is not None else np.zeros((N + 1, n))
        f = np.ascontiguousarray(f.reshape(N + 1, n))
        c0, c1 = np.zeros((N + 1, c)), np.zeros((N + 1, c))
        for j, contact in enumerate(problem.contacts):
            values = contact.offset(t)
            c0[:, j], c1[:, j] = values[0], values[1]
        WT = np.array([fr.direction for fr in problem.frictions]).reshape(m, n)
        V = np.array([fr.belt for fr in problem.frictions], dtype=float)
        popp = np.array([[fr.law.normal, fr.law.alpha, fr.law.gamma, fr.law.beta, fr.law.eta]
                         for fr in problem.frictions]).reshape(m, 5)
        WN = np.array([ct.direction for ct in problem.contacts]).reshape(c, n)
        e = np.array([ct.restitution for ct in problem.contacts], dtype=float)
        M = np.ascontiguousarray(problem.mass)
        W = np.linalg.inv(M + h * self.theta * problem.damping + h * h * self.theta ** 2 * problem.stiffness)
        s0 = WT @ v[0] - V
        status[0, :m] = np.where(np.abs(s0) <= 1e-12, STICK, np.where(s0 > 0, SLIP_POS, SLIP_NEG))
        gap0 = WN @ q[0] + c0[0] if c else np.zeros(0)
        status[0, m:] = np.where(np.abs(gap0) <= 1e-12 * (1.0 + np.abs(q[0]).max()), CLOSED, OPEN)
        from .moreau_kernels import run_moreau      # numba: imported when a mechanical run needs it
        failed = run_moreau(q, v, impulse, status, h, self.theta, M, W, np.ascontiguousarray(problem.stiffness),
                            np.ascontiguousarray(problem.damping), f, WT, V, popp, WN, c0, c1, e, 0)
        if failed >= 0:
            raise SimulationError(f"the Moreau-Jean step LCP at t = {t[failed]:.6g} s has no solution the inline "
                                  "solver finds; try a smaller h")
        x = np.hstack([q, v])
        gaps = q @ WN.T + c0
        slips = v @ WT.T - V
        rates = v @ WN.T + c1
        events = _events(t, status, slips, rates, m, c)
        code = (status * (5 ** np.arange(m + c))[None, :]).sum(axis=1)
        held = (status == STICK) | (status == CLOSED)
        return Trajectory(t=t, x=x, u=impulse / h, y=np.hstack([slips, gaps]), config=code, held=held,
                          state_names=problem.state_names, pair_names=problem.pair_names, event_columns=events,
                          method=self.key, steps=N, wall_s=time.perf_counter() - clock, rule="linear",
                          period=problem.period, metadata=dict(problem.metadata, h=h, theta=self.theta, label=self.label))

    @property
    def label(self) -> str:
        return f"moreau-jean(theta {self.theta:g})"


def _events(t: npt.NDArray[np.float64], status: npt.NDArray[np.int64], slips: npt.NDArray[np.float64],
            rates: npt.NDArray[np.float64], m: int, c: int) -> dict[str, npt.NDArray[Any]]:
    """Events from the step statuses: a friction contact entering stick (``stick``), leaving it (``slip``), or
    changing slip direction without sticking (``cross``, at the interpolated zero of s); a contact closing while
    it approaches (``impact``: its gap's rate before the step below -1e-3 of the largest rate) or opening
    (``detach``). Times are step ends, crossings interpolated."""
    times: list[float] = []
    kinds: list[str] = []
    pairs: list[int] = []
    configs: list[int] = []
    steps: list[np.integer[Any]] = []                 # rows from np.flatnonzero: numpy's integers
    for i in range(m):
        st = status[:, i].copy()
        # A crossing inside a step shows as one step held at s = 0 between opposite slips (the relay clips the
        # velocity to zero for that step): at this step's resolution it is a crossing.
        single = np.flatnonzero((st[1:-1] == STICK) & (st[:-2] != STICK) & (st[2:] != STICK) & (st[:-2] != st[2:])) + 1
        st[single] = st[single + 1]
        change = np.flatnonzero(st[1:] != st[:-1]) + 1
        for k in change:
            before, after = st[k - 1], st[k]
            if after == STICK:
                kind, time_ = "stick", t[k]
            elif before == STICK:
                kind, time_ = "slip", t[k - 1]
            else:
                a, b = slips[k - 1, i], slips[k + 1 if k + 1 < len(t) else k, i]
                span = t[cast(int, min(k + 1, len(t) - 1))] - t[k - 1]
                time_ = t[k - 1] + span * (a / (a - b) if a != b else 0.5)
                kind = "cross"
            times.append(time_)
            kinds.append(kind)
            pairs.append(i)
            configs.append(int(after))
            steps.append(k - 1)
    for j in range(c):
        st = status[:, m + j]
        # Moreau-Jean with e > 0 bounces a contact pressed by an accelerating surface in micro-steps (active, then
        # inactive for a step): closures slower than 1e-3 of the largest gap rate are those, not impacts.
        threshold = 1e-3 * np.abs(rates[:, j]).max()
        change = np.flatnonzero(st[1:] != st[:-1]) + 1
        for k in change:
            closing = st[k] == CLOSED
            if closing and rates[k - 1, j] >= -threshold:
                continue                                  # a resting contact's flicker, not an impact
            times.append(t[k])
            kinds.append("impact" if closing else "detach")
            pairs.append(m + j)
            configs.append(int(st[k]))
            steps.append(k - 1)
    order = np.argsort(times, kind="stable")
    return {"time": np.array(times)[order], "step": np.array(steps, dtype=np.int64)[order],
            "pair": np.array(pairs, dtype=np.int64)[order], "kind": np.array(kinds, dtype=object)[order],
            "config": np.array(configs, dtype=np.int64)[order]}


__all__ = ["MoreauJean"]
