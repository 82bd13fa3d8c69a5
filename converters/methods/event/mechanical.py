"""The event-driven method on mechanical problems (:class:`~converters.problems.mechanical.MechanicalProblem`):
smooth phases integrated by scipy's DOP853, events located on its dense output, modes chosen at each event.

A *mode* says, per friction contact, stick (s_i held at 0) or slip in a direction, and per unilateral
contact, closed (g_j held at 0) or open. Inside a mode the flow is smooth: with H the rows of the held
contacts and G = H M^-1 H^T,

    v' = P (f(t) - K q - C v - sum_slip sigma_i F_i(s_i) w_i) - M^-1 H^T G^-1 c''(t),   P = M^-1 - M^-1 H^T G^-1 H M^-1

and the held contacts' forces follow from keeping their velocity (stick) or their gap's acceleration
(closed) at zero. A mode ends when a watched quantity falls through zero: sigma_i s_i of a slipping
contact, F_i(0) - |lambda_i| of a sticking one, the gap g_j of an open contact, Lambda_j of a closed one.
Two crossings inside one integrator step (a near-tangency, or a stick force that exceeds the static
limit only briefly while the trivial stick flow lets the integrator take long steps) are not lost: every
local minimum of a watched quantity is an event too, and a value found below zero there is traced back
to its zero on the dense output.

At an event the new mode is the first consistent one (each contact's previous state first; at a zero of
s_i, stick before slip): a stick force within +-F_i(0), a slip that moves in its direction, a closed
contact that pushes, an open one that separates. An impact applies Newton's law g'(+) = -e g'(-); when
the chattering sequence that follows would end within ``chatter_fraction`` of the time scale (for a
constant relative acceleration a, after 2 g'(+) / (|a| (1 - e))), it is completed in closed form and the
contact closes.

Jacobians (period maps, Floquet multipliers): the variational equations Phi' = J Phi with the mode's
analytic J, and at each event the saltation matrix S = R + (f+ - R f-) n^T / (n^T f- + dh/dt) (R the
event's jump map: the identity, or Newton's impact map; n the gradient of the event function h). Entering
stick, f+ has no component across the surface: S is the sliding projector. Runs through a completed
chattering sequence have no exact Jacobian (the period map then says so and uses finite differences).
"""
from __future__ import annotations

import itertools
import time
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, cast

import numpy as np
import numpy.typing as npt

from ...errors import ParameterError, SimulationError
from ...problems.mechanical import MechanicalProblem
from ...trajectory import Samples, Trajectory
from ..base import FiniteDifferenceMap, PeriodMap
from .core import EnginePeriodMap, PiecewiseSolution

if TYPE_CHECKING:
    from . import EventDriven

STICK, SLIP_POS, SLIP_NEG, CLOSED, OPEN = 0, 1, 2, 3, 4
_SIGN = {SLIP_POS: 1.0, SLIP_NEG: -1.0}

FloatArray = npt.NDArray[np.float64]
#: A watched quantity as a function of (t, y) (y: the integrator's state, x first): an event function of solve_ivp.
EventFunction = Callable[[float, FloatArray], float]
#: An event of a mode: (function, kind, index, direction) (:meth:`MechanicalMachine._events`).
Watched = tuple[EventFunction, str, int, int]
#: A run's events: (time, kind, pair, config) (:class:`.core.Event`).
EventRecord = tuple[float, str, int, int]
#: What an event leaves: (t, x, the mode's states, the Jacobian or None, whether a chattering sequence completed).
EventOutcome = tuple[float, FloatArray, tuple[int, ...], FloatArray | None, bool]


def time_scale(problem: MechanicalProblem) -> float:
    return problem.period if np.isfinite(problem.period) else problem.t_span[1] - problem.t_span[0]


class _Mode:
    """Everything about one mode that does not depend on the state (built once, reused)."""

    def __init__(self, dyn: "_Dynamics", states: tuple[int, ...]) -> None:
        self.states = states
        m = dyn.m
        self.stick = [i for i in range(m) if states[i] == STICK]
        self.slip = [(i, _SIGN[states[i]]) for i in range(m) if states[i] in _SIGN]
        self.closed = [j for j in range(dyn.c) if states[m + j] == CLOSED]
        self.open = [j for j in range(dyn.c) if states[m + j] == OPEN]
        H = np.vstack([dyn.WT[self.stick], dyn.WN[self.closed]]) if (self.stick or self.closed) else np.zeros((0, dyn.n))
        self.H = H
        self.HM = H @ dyn.Minv
        if H.shape[0]:
            G = H @ dyn.Minv @ H.T
            try:
                self.Ginv = np.linalg.inv(G)
            except np.linalg.LinAlgError:
                raise SimulationError(f"the held contacts of mode {states} are dependent (G = H M^-1 H^T is singular); "
                                      "the mechanical model over-constrains its degrees of freedom") from None
            self.P = dyn.Minv - dyn.Minv @ H.T @ self.Ginv @ H @ dyn.Minv
            self.R = dyn.Minv @ H.T @ self.Ginv                     # v' gains -R [0; c''] from closed contacts
        else:
            self.Ginv = np.zeros((0, 0))
            self.P = dyn.Minv
            self.R = np.zeros((dyn.n, 0))
        self.code = sum(s * 5 ** i for i, s in enumerate(states))


class _Dynamics:
    """The problem's matrices and laws, with each mode's vector field, forces and Jacobian."""

    def __init__(self, problem: MechanicalProblem) -> None:
        self.problem = problem
        self.n, self.m, self.c = problem.dof, len(problem.frictions), len(problem.contacts)
        self.Minv = np.linalg.inv(problem.mass)
        self.K, self.C = problem.stiffness, problem.damping
        self.WT: FloatArray = np.array([f.direction for f in problem.frictions]).reshape(self.m, self.n)
        self.V: FloatArray = np.array([f.belt for f in problem.frictions])
        self.laws = [f.law for f in problem.frictions]
        self.static = np.array([law.static for law in self.laws])
        self.WN = np.array([c.direction for c in problem.contacts]).reshape(self.c, self.n)
        self.e = np.array([c.restitution for c in problem.contacts])
        self.offsets = [c.offset for c in problem.contacts]
        self.modes: dict[tuple[int, ...], _Mode] = {}

    def mode(self, states: tuple[int, ...]) -> _Mode:
        mode = self.modes.get(states)
        if mode is None:
            mode = self.modes[states] = _Mode(self, states)
        return mode

    # --- values at a state -----------------------------------------------------------------------------

    def offset(self, j: int, t: float) -> tuple[float, float, float]:
        c0, c1, c2 = self.offsets[j](t)
        return float(c0), float(c1), float(c2)

    def base(self, mode: _Mode, t: float, q: FloatArray, v: FloatArray) -> FloatArray:
        out = self.problem.external(t) - self.K @ q - self.C @ v
        for i, sigma in mode.slip:
            # The law's smooth continuation across s = 0 (F depends on |s| = sigma s in this mode): the
            # integrator's stages may probe just past the zero that ends the mode.
            w = self.WT[i]
            out -= (sigma * self.laws[i].branch(sigma * (float(w @ v) - self.V[i]))) * w
        return out

    def held_forces(self, mode: _Mode, t: float, base: FloatArray) -> FloatArray:
        """Forces of the held contacts (sticks first, then closed contacts) that keep them held."""
        if not mode.H.shape[0]:
            return np.zeros(0)
        rhs = mode.HM @ base
        for k, j in enumerate(mode.closed):
            rhs[len(mode.stick) + k] += self.offset(j, t)[2]
        return -mode.Ginv @ rhs

    def field(self, mode: _Mode, t: float, x: FloatArray) -> FloatArray:
        n = self.n
        out = np.empty(2 * n)
        out[:n] = x[n:]
        out[n:] = mode.P @ self.base(mode, t, x[:n], x[n:])
        if mode.closed:
            extra = np.zeros(len(mode.stick) + len(mode.closed))
            for k, j in enumerate(mode.closed):
                extra[len(mode.stick) + k] = self.offset(j, t)[2]
            out[n:] -= mode.R @ extra
        return out

    def jacobian(self, mode: _Mode, t: float, x: FloatArray) -> FloatArray:
        """d field / d x (analytic): [[0, I], [-P K, P (-C - sum_slip sigma_i F_i'(s_i) w_i w_i^T)]]."""
        n = self.n
        v = x[n:]
        dv = -self.C.copy()
        for i, sigma in mode.slip:
            s = sigma * (float(self.WT[i] @ v) - self.V[i])
            dv -= self.laws[i].branch_slope(s) * np.outer(self.WT[i], self.WT[i])      # sigma^2 = 1
        J = np.zeros((2 * n, 2 * n))
        J[:n, n:] = np.eye(n)
        J[n:, :n] = -mode.P @ self.K
        J[n:, n:] = mode.P @ dv
        return J

    def contact_forces(self, mode: _Mode, t: float, x: FloatArray) -> tuple[FloatArray, FloatArray]:
        """(lambda_T (m,), Lambda_N (c,)) in the mode."""
        n = self.n
        q, v = x[:n], x[n:]
        base = self.base(mode, t, q, v)
        held = self.held_forces(mode, t, base)
        lam_t, lam_n = np.zeros(self.m), np.zeros(self.c)
        for i, sigma in mode.slip:
            lam_t[i] = -sigma * self.laws[i].branch(sigma * (float(self.WT[i] @ v) - self.V[i]))
        lam_t[mode.stick] = held[:len(mode.stick)]
        lam_n[mode.closed] = held[len(mode.stick):]
        return lam_t, lam_n

    def slips(self, x: FloatArray) -> FloatArray:
        return self.WT @ x[self.n:] - self.V

    def gaps(self, t: float, x: FloatArray) -> tuple[FloatArray, FloatArray]:
        q, v = x[:self.n], x[self.n:]
        g, dg = np.empty(self.c), np.empty(self.c)
        for j in range(self.c):
            c0, c1, _ = self.offset(j, t)
            g[j], dg[j] = self.WN[j] @ q + c0, self.WN[j] @ v + c1
        return g, dg


@dataclass
class _Segment:
    t0: float
    t1: float
    mode: _Mode
    solution: Callable[[float], FloatArray] | None      # scipy OdeSolution (x part first); None: zero length
    x0: np.ndarray
    x1: np.ndarray


class MechanicalSolution(PiecewiseSolution):
    """The piecewise solution of a mechanical problem: segments with their dense outputs, and the events between
    them (:class:`.core.PiecewiseSolution`); ``chattered``: a chattering sequence was completed in closed form."""

    problem: MechanicalProblem
    segments: list[_Segment]

    def __init__(self, problem: MechanicalProblem, segments: list[_Segment], events: Iterable[EventRecord],
                 x_end: FloatArray, wall_s: float, options: EventDriven, chattered: bool) -> None:
        super().__init__(problem, segments, events, x_end, wall_s, options)
        self.chattered = chattered

    def sample(self, times: npt.ArrayLike) -> Samples:
        dyn = _Dynamics(self.problem)
        times = np.asarray(times, dtype=float)
        starts = np.array([s.t0 for s in self.segments])
        which = np.clip(np.searchsorted(starts, times, side="right") - 1, 0, len(self.segments) - 1)
        n2, k = self.problem.n, dyn.m + dyn.c
        x, u, y = np.empty((times.size, n2)), np.empty((times.size, k)), np.empty((times.size, k))
        config, held = np.empty(times.size, dtype=np.int64), np.empty((times.size, k), dtype=bool)
        for i, s_index in enumerate(which):
            seg = self.segments[s_index]
            t = min(max(times[i], seg.t0), seg.t1)
            if t >= seg.t1:
                xi = seg.x1
            elif seg.solution is None or t <= seg.t0:
                xi = seg.x0
            else:
                xi = seg.solution(t)[:n2]
            x[i] = xi
            lam_t, lam_n = dyn.contact_forces(seg.mode, t, xi)
            g, _ = dyn.gaps(t, xi)
            u[i] = np.concatenate([lam_t, lam_n])
            y[i] = np.concatenate([dyn.slips(xi), g])
            config[i] = seg.mode.code
            held[i] = [s in (STICK, CLOSED) for s in seg.mode.states]
        return Samples(times, x, u, y, config, held=held)

    def trajectory(self, output_step: float, method_key: str = "event") -> Trajectory:
        t = self.output_times(output_step)
        samples = self.sample(t)
        problem = self.problem
        return Trajectory(t=t, x=samples.x, u=samples.u, y=samples.y, config=samples.config, held=samples.held,
                          state_names=problem.state_names, pair_names=problem.pair_names,
                          event_columns=self.events_table(t), method=method_key, steps=len(self.segments),
                          wall_s=self.wall_s, rule="linear", period=problem.period,
                          metadata=dict(problem.metadata, label="event", chattering=self.chattered))


class MechanicalMachine:
    """Runs of one mechanical problem (the dynamics built once)."""

    def __init__(self, problem: MechanicalProblem, options: EventDriven) -> None:
        self.problem, self.options = problem, options
        self.dyn = _Dynamics(problem)
        self.scale = time_scale(problem)

    # --- mode selection -------------------------------------------------------------------------------

    def _consistent(self, states: tuple[int, ...], t: float, x: FloatArray, zero_friction: Sequence[int],
                    zero_contacts: Sequence[int]) -> bool:
        dyn = self.dyn
        mode = dyn.mode(states)
        lam_t, lam_n = dyn.contact_forces(mode, t, x)
        acc = dyn.field(mode, t, x)[dyn.n:]
        scale_f = 1e-9 * (1.0 + np.abs(dyn.static).max(initial=0.0))
        for i in zero_friction:
            if states[i] == STICK:
                if abs(lam_t[i]) > dyn.static[i] + scale_f:
                    return False
            elif _SIGN[states[i]] * (dyn.WT[i] @ acc) < -1e-9 * (1.0 + np.abs(acc).max()):
                return False
        for j in zero_contacts:
            if states[dyn.m + j] == CLOSED:
                # A contact force is rounding next to the forces it balances (a spring's, say): judge it on their scale.
                forces = np.abs(dyn.base(mode, t, x[:dyn.n], x[dyn.n:])).max()
                if lam_n[j] < -1e-9 * (1.0 + abs(lam_n[j]) + forces):
                    return False
            else:
                _, c1, c2 = dyn.offset(j, t)
                rate = dyn.WN[j] @ x[dyn.n:] + c1
                if rate < -1e-9 or (abs(rate) <= 1e-9 and dyn.WN[j] @ acc + c2 < -1e-9 * (1.0 + np.abs(acc).max())):
                    return False
        return True

    def select(self, t: float, x: FloatArray, previous: tuple[int, ...], zero_friction: Sequence[int],
               zero_contacts: Sequence[int], friction_order: Sequence[int] = (STICK, SLIP_POS, SLIP_NEG),
               contact_order: Sequence[int] | None = None) -> tuple[int, ...]:
        """The first consistent mode: contacts not at zero keep their state; a friction contact at zero tries
        ``friction_order`` (stick first where a velocity has just reached zero), a unilateral contact at zero
        ``contact_order`` (default: its previous state first)."""
        dyn = self.dyn
        options = []
        for i in range(dyn.m):
            options.append(list(friction_order) if i in zero_friction else [previous[i]])
        for j in range(dyn.c):
            if j in zero_contacts:
                options.append(list(dict.fromkeys(contact_order or [previous[dyn.m + j], CLOSED, OPEN])))
            else:
                options.append([previous[dyn.m + j]])
        for states in itertools.product(*options):
            if self._consistent(tuple(states), t, x, zero_friction, zero_contacts):
                return tuple(states)
        raise SimulationError(f"no consistent mode at t = {t:.9g} s (stick forces beyond static friction in every "
                              "combination, or a contact that can neither push nor separate); the model is not well posed there")

    # --- one segment -----------------------------------------------------------------------------------

    def _events(self, mode: _Mode, t0: float, x0: FloatArray) -> list[Watched]:
        """Event functions of the mode: (function, kind, index, direction). A watched quantity that starts the
        segment at zero is never mistaken for a crossing there: leaving at a speed it is watched as
        value / (t - t0) (positive at the start, the same later zeros); leaving tangentially as value - eps, armed
        once it has left zero by more than rounding (:meth:`_fresh`)."""
        dyn = self.dyn
        out: list[Watched] = []
        n = dyn.n
        start_field = dyn.field(mode, t0, x0)
        # functions of (t, y) with each loop's values bound as defaults (which leaves mypy their parameters only)
        value: Callable[..., float]
        rate: Callable[..., float]
        margin: Any                           # entries of the held forces, which numpy's stubs type as arrays
        force: Any
        for i, sigma in mode.slip:
            w, V = dyn.WT[i], dyn.V[i]
            value = lambda t, y, w=w, V=V, s=sigma: s * (w @ y[n:2 * n] - V)       # noqa: E731
            rate = lambda t, y, w=w, s=sigma, mode=mode: s * (w @ dyn.field(mode, t, y[:2 * n])[n:])  # noqa: E731
            out.append((self._fresh(value, rate, t0, x0, start_field, mode), "zero", i, -1))
            out.append((rate, "extremum", i, 1))
        for i in mode.stick:
            position = mode.stick.index(i)
            margin = (lambda t, y, i=i, p=position, mode=mode: dyn.static[i] - abs(                 # noqa: E731
                dyn.held_forces(mode, t, dyn.base(mode, t, y[:n], y[n:2 * n]))[p]))
            out.append((margin, "break", i, -1))
            out.append((self._rate(margin, mode), "break-extremum", i, 1))
        for j in mode.open:
            value = lambda t, y, j=j: dyn.WN[j] @ y[:n] + dyn.offset(j, t)[0]         # noqa: E731
            rate = lambda t, y, j=j: dyn.WN[j] @ y[n:2 * n] + dyn.offset(j, t)[1]       # noqa: E731
            out.append((self._fresh(value, rate, t0, x0, start_field, mode), "impact", dyn.m + j, -1))
            out.append((rate, "gap-extremum", dyn.m + j, 1))
        for j in mode.closed:
            position = len(mode.stick) + mode.closed.index(j)
            force = (lambda t, y, p=position, mode=mode:                                                    # noqa: E731
                     dyn.held_forces(mode, t, dyn.base(mode, t, y[:n], y[n:2 * n]))[p])
            out.append((self._fresh(force, self._rate(force, mode), t0, x0, start_field, mode), "detach", dyn.m + j, -1))
            out.append((self._rate(force, mode), "detach-extremum", dyn.m + j, 1))
        return out

    def _rate(self, function: EventFunction, mode: _Mode) -> EventFunction:
        """d function / dt along the mode's flow (a central difference): its zeros are the extrema a held
        contact's margin may dip below zero between two integrator steps."""
        dyn, delta = self.dyn, 1e-7 * self.scale
        n2 = 2 * dyn.n

        def rate(t: float, y: FloatArray) -> float:
            x = y[:n2]
            f = dyn.field(mode, t, x)
            return (function(t + delta, x + delta * f) - function(t - delta, x - delta * f)) / (2.0 * delta)
        return rate

    def _fresh(self, value: EventFunction, rate: EventFunction, t0: float, x0: FloatArray, start_field: FloatArray,
               mode: _Mode) -> EventFunction:
        """``value`` itself, or value / (t - t0)^p when it starts at zero (see :meth:`_events`)."""
        scale = 1e-12 * (1.0 + np.abs(x0).max())
        if abs(value(t0, x0)) > scale:
            return value
        first = rate(t0, x0)
        if first > scale:
            tiny = 1e-300

            # leaving at a speed: value / (t - t0) starts at that speed
            def watched(t: float, y: FloatArray) -> float:
                if t <= t0:
                    return first
                return value(t, y) / max(t - t0, tiny)
            return watched
        # A tangential start (a stick that breaks, a contact whose force reached zero): the value grows as a
        # power of (t - t0) that stays below its own rounding for a while, so its sign is noise there. Watch
        # value - eps: armed once the value has genuinely left zero, it fires at most eps early on the way back.
        eps: float = 64.0 * scale

        def armed(t: float, y: FloatArray) -> float:
            return value(t, y) - eps
        return armed

    def _integrate(self, mode: _Mode, t0: float, t1: float, x0: FloatArray,
                   phi: FloatArray | None) -> tuple[Any, list[Watched], tuple[float, int] | None]:
        # (scipy's OdeResult, the mode's events, (time, index into them) of the one that ends the phase, or None)
        from scipy.integrate import solve_ivp
        dyn, opts = self.dyn, self.options
        n2 = 2 * dyn.n
        if phi is None:
            def fun(t: float, y: FloatArray) -> FloatArray:
                return dyn.field(mode, t, y)
            y0 = x0
        else:
            def fun(t: float, y: FloatArray) -> FloatArray:
                x = y[:n2]
                return np.concatenate([dyn.field(mode, t, x), (dyn.jacobian(mode, t, x) @ y[n2:].reshape(n2, n2)).ravel()])
            y0 = np.concatenate([x0, phi.ravel()])
        watched = self._events(mode, t0, x0)
        functions: list[EventFunction] = []
        for function, kind, index, direction in watched:
            cast(Any, function).terminal = not kind.endswith("extremum")      # what solve_ivp reads of an event
            cast(Any, function).direction = direction
            functions.append(function)
        scale = 1.0 + np.abs(x0).max()
        # The integrator sees the state's dynamics only: a friction contact's watched quantities follow them (and
        # the extremum events catch two crossings inside a step), so a quarter of the time scale is step enough.
        # An open contact's gap also holds c(t), which it never sees (a cam's profile): there the steps are capped
        # at the sampling fraction, and at an eighth of the predicted flight after an impact.
        max_step = 0.25 * self.scale
        if mode.open:
            max_step = opts.sample_fraction * self.scale
            for j in mode.open:
                g0, rate0 = dyn.WN[j] @ x0[:dyn.n] + dyn.offset(j, t0)[0], dyn.WN[j] @ x0[dyn.n:2 * dyn.n] + dyn.offset(j, t0)[1]
                acc0 = dyn.WN[j] @ dyn.field(mode, t0, x0[:2 * dyn.n])[dyn.n:] + dyn.offset(j, t0)[2]
                if abs(g0) <= 1e-9 * scale and rate0 > 0.0 and acc0 < 0.0:
                    max_step = min(max_step, 0.25 * rate0 / -acc0)          # flight 2 u / |a|: eight steps
        result = solve_ivp(fun, (t0, t1), y0, method="DOP853", rtol=opts.ode_rtol, atol=opts.ode_rtol * 1e-2 * scale,
                           max_step=max_step, events=functions, dense_output=True)
        if result.status == -1:
            raise SimulationError(f"the integration failed at t = {result.t[-1]:.9g} s: {result.message}")
        # The first terminal event, or an earlier extremum where the watched value is found below zero (two
        # crossings inside one step: the first one is then traced back on the dense output).
        fired = None
        if mode.open:
            fired = self._scan_gaps(mode, watched, result, t0)
        for k, times in enumerate(result.t_events):
            kind = watched[k][1]
            for t_event in times:
                if kind.endswith("extremum") and (t_event - t0 <= 1e-14 * self.scale
                                                  or not self._below(kind, watched[k], mode, t_event, result)):
                    continue
                if fired is None or t_event < fired[0]:
                    fired = (float(t_event), k)
        return result, watched, fired

    def _scan_gaps(self, mode: _Mode, watched: list[Watched], result: Any, t0: float) -> tuple[float, int] | None:
        """An open gap sampled on each step's dense output (8 points a step): the first sample below zero is
        an impact the step ends did not see. Returns (time, watched index) of the first such crossing, or None."""
        from scipy.optimize import brentq
        indices = [k for k, entry in enumerate(watched) if entry[1] == "impact"]
        steps = result.t
        if len(steps) < 2 or not indices:
            return None
        grid = np.unique(np.concatenate([np.linspace(a, b, 9) for a, b in zip(steps[:-1], steps[1:])]))
        grid = grid[grid > t0 + 1e-14 * self.scale]
        if not grid.size:
            return None
        states = result.sol(grid)
        first = None
        for k in indices:
            function = watched[k][0]
            values = np.array([function(tt, states[:, i]) for i, tt in enumerate(grid)])
            negative = np.flatnonzero(values < 0.0)
            if not negative.size:
                continue
            right = negative[0]
            left_t = grid[right - 1] if right > 0 else t0
            if function(left_t, result.sol(left_t)) < 0.0:
                continue
            t_zero = brentq(lambda tt: function(tt, result.sol(tt)), left_t, grid[right], xtol=1e-15 * self.scale,
                            rtol=4 * np.finfo(float).eps)
            if first is None or t_zero < first[0]:
                first = (float(t_zero), k)
        return first

    def _below(self, kind: str, watched_entry: Watched, mode: _Mode, t: float, result: Any) -> bool:
        """Is the watched quantity of an extremum event below zero there (a crossing missed inside a step)?"""
        y = result.sol(t)
        return self._watched_value(kind, watched_entry[2], mode)(t, y) < 0.0

    def _watched_value(self, kind: str, index: int, mode: _Mode) -> EventFunction:
        """The quantity whose extremum an ``*-extremum`` event watches, as a function of (t, y)."""
        dyn = self.dyn
        n = dyn.n
        if kind == "extremum":
            sigma = _SIGN[mode.states[index]]
            return lambda t, y: sigma * (dyn.WT[index] @ y[n:2 * n] - dyn.V[index])
        if kind == "gap-extremum":
            j = index - dyn.m
            return lambda t, y: dyn.WN[j] @ y[:n] + dyn.offset(j, t)[0]
        if kind == "break-extremum":
            position = mode.stick.index(index)
            return lambda t, y: dyn.static[index] - abs(dyn.held_forces(mode, t, dyn.base(mode, t, y[:n], y[n:2 * n]))[position])
        position = len(mode.stick) + mode.closed.index(index - dyn.m)
        return lambda t, y: dyn.held_forces(mode, t, dyn.base(mode, t, y[:n], y[n:2 * n]))[position]

    # --- runs --------------------------------------------------------------------------------------------

    def period_run(self, x0: FloatArray, jacobian: bool) -> tuple[MechanicalSolution, FloatArray | None]:
        """(solution, Jacobian or None) of one span from x0, unrecorded (:class:`.core.EnginePeriodMap`)."""
        solution, phi = self.run(x0, record=False, jacobian=jacobian)
        if jacobian and (solution.chattered or phi is None):
            raise SimulationError("this run went through a completed chattering sequence, which has no exact Jacobian; "
                                  "use the finite-difference period map")
        return solution, phi

    def run(self, x0: npt.ArrayLike, record: bool = True,
            jacobian: bool = False) -> tuple[MechanicalSolution, FloatArray | None]:
        """Run over t_span from x0: (MechanicalSolution, d x_end / d x0 or None)."""
        clock = time.perf_counter()
        dyn, opts = self.dyn, self.options
        problem = self.problem
        n2 = 2 * dyn.n
        t, t_end = problem.t_span
        x = np.array(x0, dtype=float)
        phi = np.eye(n2) if jacobian else None
        events: list[EventRecord] = []
        segments: list[_Segment] = []
        chattered = False
        zero_f = [i for i in range(dyn.m) if abs(dyn.slips(x)[i]) <= 1e-12 * (1.0 + abs(dyn.V[i]))]
        g, dg = dyn.gaps(t, x)
        zero_c = [j for j in range(dyn.c) if abs(g[j]) <= 1e-12 and abs(dg[j]) <= 1e-12]
        if any(g < -1e-9 * (1.0 + np.abs(x).max())):
            raise ParameterError(f"x0 must keep every gap >= 0 (the contacts are unilateral); got gaps {g.tolist()}")
        start = tuple([STICK if i in zero_f else (SLIP_POS if dyn.slips(x)[i] > 0 else SLIP_NEG) for i in range(dyn.m)]
                      + [CLOSED if j in zero_c else OPEN for j in range(dyn.c)])
        states = self.select(t, x, start, zero_f, zero_c) if (zero_f or zero_c) else start
        same_time, count = 0, 0
        while t < t_end:
            mode = dyn.mode(states)
            result, watched, fired = self._integrate(mode, t, t_end, x, phi)
            if fired is None:
                t_next, y_next = t_end, result.y[:, -1]
            else:
                t_next = fired[0]
                y_next = result.sol(t_next)
            if record:
                segments.append(_Segment(t, t_next, mode, result.sol if t_next > t else None, x.copy(), y_next[:n2].copy()))
            x = y_next[:n2].copy()
            if phi is not None:
                phi = y_next[n2:].reshape(n2, n2).copy()
            same_time = same_time + 1 if t_next - t <= 1e-13 * self.scale else 0
            t = t_next
            if fired is None:
                break
            count += 1
            if same_time > 20 or count > opts.max_events:
                raise SimulationError(f"{'repeated events at one instant' if same_time > 20 else 'too many events'} near "
                                      f"t = {t:.9g} s (Zeno behaviour, or a degenerate mode); max_events = {opts.max_events}")
            _, kind, index, _ = watched[fired[1]]
            t, x, states, phi, chattered_now = self._handle(kind, index, t, x, mode, phi, result, events, segments, record)
            chattered = chattered or chattered_now

        solution = MechanicalSolution(problem, segments, events, x, time.perf_counter() - clock, opts, chattered)
        return solution, phi

    def _handle(self, kind: str, index: int, t: float, x: FloatArray, mode: _Mode, phi: FloatArray | None,
                result: Any, events: list[EventRecord], segments: list[_Segment], record: bool) -> EventOutcome:
        """The event at (t, x): the jump, the saltation, the new mode. Returns (t, x, states, phi, chattered)."""
        dyn = self.dyn
        n, m = dyn.n, dyn.m
        states = list(mode.states)
        f_before = dyn.field(mode, t, x)
        if kind.endswith("extremum"):                       # a crossing inside the last step: go back to it
            t, x, phi = self._back_to_zero(result, self._watched_value(kind, index, mode), t, segments, record, phi)
            kind = {"extremum": "zero", "gap-extremum": "impact", "break-extremum": "break",
                    "detach-extremum": "detach"}[kind]
            f_before = dyn.field(mode, t, x)
        if kind == "zero":                                  # a slipping velocity reached zero: stick, or cross
            i = index
            w = dyn.WT[i]
            x = x.copy()
            x[n:] -= dyn.Minv @ w * ((w @ x[n:] - dyn.V[i]) / (w @ dyn.Minv @ w))   # exactly on s_i = 0
            new = self.select(t, x, mode.states, [i], [])
            config = new[i]
            label = "stick" if config == STICK else ("touch" if config == mode.states[i] else "cross")
            events.append((t, label, i, config))
            grad = np.concatenate([np.zeros(n), w])
            phi = self._saltation(phi, dyn.mode(new), t, x, f_before, grad, 0.0)
            return t, x, new, phi, False
        if kind == "break":                                 # a stick force reached the static limit
            i = index
            w = dyn.WT[i]
            x = x.copy()
            x[n:] -= dyn.Minv @ w * ((w @ x[n:] - dyn.V[i]) / (w @ dyn.Minv @ w))   # leave from exactly s_i = 0
            lam = dyn.contact_forces(mode, t, x)[0][i]
            states[i] = SLIP_NEG if lam > 0 else SLIP_POS
            new = tuple(states)
            if not self._consistent(new, t, x, [i], []):
                new = self.select(t, x, mode.states, [i], [], friction_order=(SLIP_POS, SLIP_NEG))
            events.append((t, "slip", i, new[i]))
            grad, dhdt = self._gradient(lambda tt, y: dyn.static[i] - abs(dyn.contact_forces(mode, tt, y)[0][i]), t, x)
            phi = self._saltation(phi, dyn.mode(new), t, x, f_before, grad, dhdt)
            return t, x, new, phi, False
        if kind == "detach":
            j = index - m
            x = self._onto_contact(j, t, x)           # the held gap drifts by rounding: start the flight on it
            states[m + j] = OPEN
            new = tuple(states)
            events.append((t, "detach", index, OPEN))
            grad, dhdt = self._gradient(lambda tt, y: dyn.contact_forces(mode, tt, y)[1][j], t, x)
            phi = self._saltation(phi, dyn.mode(new), t, x, f_before, grad, dhdt)
            return t, x, new, phi, False
        if kind == "impact":
            return self._impact(index - m, t, x, mode, phi, f_before, events)
        raise AssertionError(kind)

    def _impact(self, j: int, t: float, x: FloatArray, mode: _Mode, phi: FloatArray | None, f_before: FloatArray,
                events: list[EventRecord]) -> EventOutcome:
        """Newton's law at contact j; a chattering sequence about to accumulate is completed in closed form."""
        dyn, opts = self.dyn, self.options
        n, m = dyn.n, dyn.m
        w = dyn.WN[j]
        c0, c1, c2 = dyn.offset(j, t)
        rate = w @ x[n:] + c1
        mass = w @ dyn.Minv @ w
        e = dyn.e[j]
        if rate >= -1e-9 * (1.0 + np.abs(x[n:]).max()):
            # Reached at a speed of rounding size (a contact whose force touched zero and returns): no impact, the
            # contact closes if it can push, with its state put on the constraint.
            x_on = self._onto_contact(j, t, x)
            new = self.select(t, x_on, mode.states, [], [j], contact_order=(CLOSED, OPEN))
            events.append((t, "contact", m + j, new[m + j]))
            return t, x_on, new, (None if phi is None else phi), False
        x_after = x.copy()
        x_after[n:] -= dyn.Minv @ w * ((1.0 + e) * rate / mass)
        events.append((t, "impact", m + j, OPEN))
        separating = -e * rate
        states = list(mode.states)
        # Relative acceleration in free flight right after: if the contact pulls back, the bounces accumulate
        # after 2 u / (|a| (1 - e)) for a constant a.
        acc = w @ dyn.field(dyn.mode(tuple(states)), t, x_after)[n:] + c2
        chattered = False
        if acc < 0.0 and e < 1.0:
            remaining = 2.0 * separating / (-acc * (1.0 - e))
            # Complete it once what remains is short, or once a bounce rises less than the state's resolution (the
            # gap's rounding: below it the next impacts cannot be located).
            height = separating * separating / (-2.0 * acc)
            if remaining <= opts.chatter_fraction * self.scale or height <= 1e-12 * (1.0 + np.abs(x[:n]).max()):
                t = t + remaining
                x_after = x_after.copy()
                x_after[:n] += x_after[n:] * remaining                # the other coordinates drift on (first order)
                x_after = self._onto_contact(j, t, x_after)      # on the contact at the accumulation time, moving with it
                states[m + j] = CLOSED
                new = tuple(states)
                if not self._consistent(new, t, x_after, [], [j]):
                    states[m + j] = OPEN
                    new = tuple(states)
                events.append((t, "chatter", m + j, new[m + j]))
                return t, x_after, new, None, True
        if phi is not None:
            # Newton's impact map: v+ = v - (1 + e) M^-1 w (w . v + c'(t)) / (w M^-1 w): saltation through the jump.
            R = np.eye(2 * n)
            R[n:, n:] -= (1.0 + e) * np.outer(dyn.Minv @ w, w) / mass
            f_after = dyn.field(dyn.mode(tuple(states)), t, x_after)
            grad = np.concatenate([w, np.zeros(n)])
            denominator = grad @ f_before + c1
            extra = np.zeros(2 * n)
            extra[n:] = -(1.0 + e) * dyn.Minv @ w * c2 / mass        # d(jump)/dt through c'(t)
            phi = (R + np.outer(f_after - R @ f_before - extra, grad) / denominator) @ phi
        return t, x_after, tuple(states), phi, chattered

    def _onto_contact(self, j: int, t: float, x: FloatArray) -> FloatArray:
        """x moved along M^-1 n_j onto g_j = 0 and g_j' = 0 (a closed contact's state, its rounding drift removed)."""
        dyn = self.dyn
        n, w = dyn.n, dyn.WN[j]
        c0, c1, _ = dyn.offset(j, t)
        mass = w @ dyn.Minv @ w
        x = x.copy()
        x[:n] -= dyn.Minv @ w * ((w @ x[:n] + c0) / mass)
        x[n:] -= dyn.Minv @ w * ((w @ x[n:] + c1) / mass)
        return x

    def _back_to_zero(self, result: Any, function: EventFunction, t_ext: float, segments: list[_Segment],
                      record: bool, phi: FloatArray | None) -> tuple[float, FloatArray, FloatArray | None]:
        """The zero of ``function(t, y)`` (positive at the segment's start, negative at t_ext) on the dense output:
        (t, x, phi) there, the last recorded segment cut to it."""
        from scipy.optimize import brentq
        grid = np.linspace(result.t[0], t_ext, 65)
        values = [function(tt, result.sol(tt)) for tt in grid]
        positive = next((k for k, v in enumerate(values) if v > 0.0), None)
        if positive is None:                     # never above zero: the segment left the surface only by rounding
            t_zero = grid[0]
        else:
            right = next((k for k in range(positive + 1, len(values)) if values[k] <= 0.0), len(values) - 1)
            t_zero = brentq(lambda tt: function(tt, result.sol(tt)), grid[right - 1], grid[right],
                            xtol=1e-15 * self.scale, rtol=4 * np.finfo(float).eps)
        y = result.sol(t_zero)
        n2 = 2 * self.dyn.n
        if record and segments:
            last = segments[-1]
            segments[-1] = _Segment(last.t0, t_zero, last.mode, last.solution, last.x0, y[:n2].copy())
        return t_zero, y[:n2].copy(), (y[n2:].reshape(n2, n2).copy() if phi is not None else None)

    def _gradient(self, function: EventFunction, t: float, x: FloatArray) -> tuple[FloatArray, float]:
        """(d h / d x, d h / d t) by central differences."""
        grad = np.empty(x.size)
        for k in range(x.size):
            dx = 1e-7 * (1.0 + abs(x[k]))
            e = np.zeros(x.size)
            e[k] = dx
            grad[k] = (function(t, x + e) - function(t, x - e)) / (2.0 * dx)
        dt = 1e-7 * self.scale
        return grad, (function(t + dt, x) - function(t - dt, x)) / (2.0 * dt)

    def _saltation(self, phi: FloatArray | None, new_mode: _Mode, t: float, x: FloatArray, f_before: FloatArray,
                   grad: FloatArray, dhdt: float) -> FloatArray | None:
        if phi is None:
            return None
        f_after = self.dyn.field(new_mode, t, x)
        denominator = grad @ f_before + dhdt
        if denominator == 0.0:
            return phi
        return (np.eye(x.size) + np.outer(f_after - f_before, grad) / denominator) @ phi


class MechanicalPeriodMap(EnginePeriodMap):
    """x(t0) -> x(t1) over a mechanical problem's span with the Jacobian of the variational equations and
    saltation matrices (an impact's: Newton's law differentiated, its time through the gap's rate); it keeps the
    events of its last run. A run through a completed chattering sequence (closed form: the accumulation erases
    the approach, so no saltation matrix holds it) has its Jacobian by forward differences instead;
    ``jacobian_kind`` says which the last Jacobian was."""

    jacobian_kind = "exact"
    machine: MechanicalMachine

    def _solve(self, x0: FloatArray, jacobian: bool) -> tuple[MechanicalSolution, FloatArray | None]:
        solution, phi = self.machine.run(x0, record=False, jacobian=jacobian)
        self.jacobian_kind = "exact"
        if jacobian and (solution.chattered or phi is None):
            phi = FiniteDifferenceMap(lambda x: self.machine.run(x, record=False)[0].x_end)(x0)[1]
            self.jacobian_kind = "finite differences"
        return solution, phi


def period_map(problem: MechanicalProblem, options: EventDriven) -> PeriodMap:
    return MechanicalPeriodMap(MechanicalMachine(problem, options))


def sliding_boundary(problem: MechanicalProblem, states: tuple[int, ...], i: int, sigma: float, t: float,
                     x: npt.ArrayLike) -> tuple[float, float]:
    """(margin, curvature) of friction contact ``i`` at a state (t, x) on its surface s_i = 0, the other contacts
    in ``states`` (a mode's states, one per contact).

    margin = |lambda_i| / F_i(0) - 1 of the force that would hold the contact stuck there: negative inside the
    sliding region, zero on its boundary, where the slip field of direction ``sigma`` (+1 or -1) is tangent to the
    surface. curvature = -sigma s_i'' along that slip field: positive where its fold is invisible (its orbit
    through the fold stays on the other side, so an orbit that crosses the surface just outside the sliding
    region comes back to it), zero at a cubic tangency (the degeneracy of a switching-sliding point). s_i'' is
    w_i . d/dt (v') along the slip field: its Jacobian times the field, and the explicit time derivative by a
    central difference (1e-6 of the time scale: the forcing is smooth)."""
    dyn = _Dynamics(problem)
    x = np.asarray(x, dtype=float)
    held = list(states)
    held[i] = STICK
    lam_t, _ = dyn.contact_forces(dyn.mode(tuple(held)), t, x)
    margin = abs(lam_t[i]) / dyn.static[i] - 1.0
    held[i] = SLIP_POS if sigma > 0 else SLIP_NEG
    mode = dyn.mode(tuple(held))
    n = dyn.n
    field = dyn.field(mode, t, x)
    dt = 1e-6 * time_scale(problem)
    explicit = (dyn.field(mode, t + dt, x) - dyn.field(mode, t - dt, x))[n:] / (2.0 * dt)
    jerk = (dyn.jacobian(mode, t, x) @ field)[n:] + explicit
    return float(margin), float(-np.sign(sigma) * (dyn.WT[i] @ jerk))


def supports(problem: MechanicalProblem, options: EventDriven) -> None:
    """Every mechanical problem (its own checks ran when it was built)."""


def solve(problem: MechanicalProblem, options: EventDriven, x0: FloatArray) -> Trajectory:
    solution = MechanicalMachine(problem, options).run(x0)[0]
    step = options.output_step or time_scale(problem) / 200.0
    return solution.trajectory(step)


__all__ = ["MechanicalMachine", "MechanicalSolution", "MechanicalPeriodMap", "supports", "solve", "period_map",
           "STICK", "SLIP_POS", "SLIP_NEG", "CLOSED", "OPEN", "time_scale", "sliding_boundary"]
