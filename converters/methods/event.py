"""Exact event-driven simulation of single-pair piecewise-linear LCS: the accuracy reference.

Between events the LCS is linear with constant inputs, x' = Ab x + eb, where (Ab, eb) depend on the
switch configuration (A, B, C, D, E, F) and on the mode of the complementarity pair (k = 1):

    free            u = 0                     Ab = A,            eb = E             watched: y = C x + F
    held, D > 0     u = -(C x + F) / D        Ab = A - B C / D,  eb = E - B F / D   watched: u
    held, D = 0     u = -C (A x + E) / (C B)  Ab = P A,          eb = P E           watched: u
                    (C B > 0; P = I - B C / (C B) keeps y = C x + F at 0: the GDCM flow)

so x(t0 + tau) = expm(tau Z) [x0; 1] with Z = [[Ab, eb], [0, 0]], exact up to rounding. A mode ends
when its watched quantity crosses zero downwards: sign changes are looked for on samples at most
``sample_fraction`` T apart (and 0.25 / ||Z|| apart), then the crossing is located by Brent's method
on the exact flow to ``event_tol`` T. Configuration changes happen at the schedule's known instants.
At every event the new mode is the solution of the mode-selection LCP, resolved lexicographically:
free if the first non-zero entry of (y, y', y'', ...) along the free flow is positive (or all vanish),
else held if that of (u, u', ...) along the held flow is. A configuration entered with y < 0 and D = 0
makes the state jump, x+ = x + B lambda with lambda = -(C x + F) / (C B) (Moreau's impulse: the LCP
0 <= lambda _|_ C (x + B lambda) + F >= 0).

Integrals over a run (means, RMS) use 8-point Gauss-Legendre quadrature on pieces no longer than the
sampling distance: exact to rounding for these exponential-polynomial pieces.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np
import pandas as pd
from scipy.linalg import expm
from scipy.optimize import brentq

from ..errors import ParameterError, SimulationError
from ..validate import check_positive, parse_value
from ..problems import Configuration, LCSProblem
from ..trajectory import Trajectory


@dataclass(frozen=True)
class EventDriven:
    """The exact event-driven method (:mod:`converters.methods.event`) for LCS with one complementarity pair.

    Parameters
    ----------
    event_tol : float
        Events (zero crossings of the watched complementarity variable) are located to
        ``event_tol`` times the switching period (Brent's method on the exact flow). Default 1e-13.
    sample_fraction : float
        The watched variable is sampled at most ``sample_fraction`` T apart when looking for sign
        changes (two crossings closer than that could be missed). Default 1/32.
    output_step : float or None
        Spacing of the output samples in s (events are always added); None: T/1000.
    max_events : int
        Refuse runs with more events than this (Zeno behaviour). Default 10^7.
    """

    event_tol: float = 1e-13
    sample_fraction: float = 1.0 / 32.0
    output_step: float | None = None
    max_events: int = 10_000_000

    def __post_init__(self):
        tol = parse_value("event_tol", self.event_tol)
        if not 0.0 < tol <= 1e-2:
            raise ParameterError(f"event_tol must be in (0, 1e-2] (fraction of the period); got {tol!r}")
        object.__setattr__(self, "event_tol", tol)
        frac = parse_value("sample_fraction", self.sample_fraction)
        if not 0.0 < frac <= 1.0:
            raise ParameterError(f"sample_fraction must be in (0, 1]; got {frac!r}")
        object.__setattr__(self, "sample_fraction", frac)
        if self.output_step is not None:
            object.__setattr__(self, "output_step", check_positive("output_step", self.output_step, "s"))
        if not (isinstance(self.max_events, (int, np.integer)) and self.max_events >= 1):
            raise ParameterError(f"max_events must be an integer >= 1; got {self.max_events!r}")

    @property
    def name(self) -> str:
        return "event"


_GL_X, _GL_W = np.polynomial.legendre.leggauss(8)
_TAYLOR_TERMS = 26     # (0.25)^26 / 26! < 1e-30: the series is exact to rounding on a sampling step
_EXPONENTS = np.arange(_TAYLOR_TERMS)
_POWERS = 64           # sampling steps per batched product
_ZERO_RTOL = 1e-10      # a derivative counts as zero below this fraction of its own scale
_CROSS_RTOL = 1e-13     # a watched value counts as negative below -this fraction of its scale


@dataclass(frozen=True)
class Flow:
    """The affine flow of one (configuration, pair mode), in augmented form x~ = [x; 1].

    Z (n+1, n+1): x~' = Z x~. ``u_row``, ``y_row``, ``watch_row`` (n+1,): u = u_row . x~, y = y_row . x~,
    and the mode ends when watch_row . x~ crosses zero downwards. ``delta``: sampling distance (s);
    ``step`` = expm(delta Z).
    """

    config: int
    held: bool
    Z: np.ndarray
    u_row: np.ndarray
    y_row: np.ndarray
    watch_row: np.ndarray
    delta: float
    step: np.ndarray
    taylor: np.ndarray      # Z^j / j!, j = 0.._TAYLOR_TERMS - 1: x~(s) = sum_j s^j (Z^j / j!) x~ for s <= delta
    powers: np.ndarray      # step^j, j = 0.._POWERS: the samples of a segment in one batched product
    node_maps: np.ndarray     # expm(s_k Z) at the Gauss-Legendre nodes s_k of [0, delta], shape (8, n+1, n+1)
    watch_derivatives: np.ndarray  # rows watch Z^j, j = 0..n+1: the watched quantity's derivatives
    derivative_scales: np.ndarray  # rows |watch| |Z|^j 1

    def taylor_vectors(self, xt: np.ndarray) -> np.ndarray:
        """V with x~(s) = (s^0, s^1, ...) @ V for 0 <= s <= delta (the series converges: delta ||Z|| <= 0.25)."""
        return self.taylor @ xt

    def sample_states(self, xt: np.ndarray, count: int) -> np.ndarray:
        """x~ at 0, delta, ..., count delta: shape (count + 1, n+1)."""
        if count <= _POWERS:
            return self.powers[:count + 1] @ xt
        blocks, state = [], xt
        while count >= 0:
            m = min(count, _POWERS)
            block = self.powers[:m + 1] @ state
            blocks.append(block[:-1] if count > m else block)
            state, count = block[-1], count - m if count > m else -1
        return np.vstack(blocks)

    def propagate(self, xt: np.ndarray, s: float) -> np.ndarray:
        """x~ after s in [0, delta]."""
        return s ** _EXPONENTS @ (self.taylor @ xt)

    def advance(self, xt: np.ndarray, tau: float) -> np.ndarray:
        """x~ after any tau >= 0: whole sampling steps by powers of expm(delta Z), the rest by the series."""
        q = int(np.floor(tau / self.delta * (1.0 - 1e-12)))
        while q > 0:
            m = min(q, _POWERS)
            xt = self.powers[m] @ xt
            q -= m
        rest = tau - np.floor(tau / self.delta * (1.0 - 1e-12)) * self.delta
        return self.propagate(xt, max(rest, 0.0))

    def derivatives(self, xt: np.ndarray, order: int) -> tuple[np.ndarray, np.ndarray]:
        """(values, scales) of the watched quantity and its first ``order`` time derivatives at x~.

        The scale of each derivative uses max |x~| for every entry: a variable near zero (the
        inductor current at a DCM event) must not be its own yardstick."""
        return self.watch_derivatives[:order + 1] @ xt, self.derivative_scales[:order + 1] * np.abs(xt).max()

    def lexicographic_sign(self, xt: np.ndarray) -> int:
        """Sign of the first non-zero entry of (g, g', g'', ...) along this flow; 0 if all vanish."""
        values, scales = self.derivatives(xt, xt.size)
        for v, s in zip(values, scales):
            if abs(v) > _ZERO_RTOL * s + 1e-300:
                return 1 if v > 0 else -1
        return 0


def _flow(config: Configuration, index: int, held: bool, period_scale: float, sample_fraction: float) -> Flow | None:
    """The flow of ``config`` with the pair free or held; None when the pair cannot be held (C B <= 0, D = 0)."""
    n = config.n
    A, b, c, d, E, f = config.A, config.B[:, 0], config.C[0], float(config.D[0, 0]), config.E, float(config.F[0])
    y_row = np.append(c, f)
    if not held:
        u_row = np.zeros(n + 1)
        Ab, eb, watch = A, E, y_row
        y_out = y_row
    elif d > 0.0:
        u_row = -np.append(c, f) / d
        Ab, eb = A + np.outer(b, u_row[:n]), E + b * u_row[n]
        watch, y_out = u_row, np.zeros(n + 1)
    else:
        cb = float(c @ b)
        if d < 0.0 or cb <= 0.0:
            return None
        u_row = -np.append(c @ A, c @ E) / cb
        Ab, eb = A + np.outer(b, u_row[:n]), E + b * u_row[n]
        watch, y_out = u_row, y_row
    Z = np.zeros((n + 1, n + 1))
    Z[:n, :n], Z[:n, n] = Ab, eb
    norm = float(np.abs(Z).sum(axis=1).max())
    delta = sample_fraction * period_scale
    if norm > 0.0:
        delta = min(delta, 0.25 / norm)
    taylor = np.empty((_TAYLOR_TERMS, n + 1, n + 1))
    taylor[0] = np.eye(n + 1)
    for j in range(1, _TAYLOR_TERMS):
        taylor[j] = taylor[j - 1] @ Z / j
    step = expm(delta * Z)
    node_weights = (0.5 * (_GL_X + 1.0) * delta)[:, None] ** _EXPONENTS[None, :]
    node_maps = np.tensordot(node_weights, taylor, axes=([1], [0]))
    rows, scales = [watch], [np.abs(watch).sum()]
    absZ, abs_row = np.abs(Z), np.abs(watch)
    for _ in range(n + 1):
        rows.append(rows[-1] @ Z)
        abs_row = abs_row @ absZ
        scales.append(abs_row.sum())
    return Flow(index, held, Z, u_row, y_out, watch, delta, step, taylor, _power_stack(step, _POWERS),
                node_maps, np.array(rows), np.array(scales))


@dataclass
class Segment:
    t0: float
    t1: float
    flow: Flow
    xt0: np.ndarray     # augmented state [x; 1] at t0


@dataclass
class EventSolution:
    """The exact piecewise solution: segments (t0, t1, flow, start state) and the events between them.

    ``events``: time, kind ('activate', 'release', 'impulse'), configuration. ``wall_s``: seconds spent.
    """

    problem: LCSProblem
    segments: list
    event_times: list
    event_kinds: list
    x_end: np.ndarray
    wall_s: float
    options: EventDriven

    @property
    def events(self) -> pd.DataFrame:
        return pd.DataFrame({"time": np.array(self.event_times, dtype=float), "pair": 0,
                             "kind": np.array(self.event_kinds, dtype=object)})

    def _segments_in(self, t0: float, t1: float):
        for seg in self.segments:
            if seg.t1 > t0 and seg.t0 < t1:
                yield seg, max(seg.t0, t0), min(seg.t1, t1)

    def quadrature(self, t0: float | None = None, t1: float | None = None):
        """Gauss-Legendre nodes over [t0, t1] (default: the whole run): (t, weights, x, u, config).

        Pieces follow the segments (no node straddles an event), each at most the flow's sampling
        distance long, 8 nodes per piece."""
        t0 = self.problem.t_span[0] if t0 is None else t0
        t1 = self.problem.t_span[1] if t1 is None else t1
        ts, ws, xs, us, cs = [], [], [], [], []
        half = 0.5 * (_GL_X + 1.0)
        for seg, a, b in self._segments_in(t0, t1):
            flow, length = seg.flow, b - a
            if length <= 0.0:
                continue
            # Whole pieces of the sampling step delta: their starts S^q x~ in batched products, their
            # nodes by the precomputed node maps; then the rest of the segment by the series.
            full = int(np.floor(length / flow.delta * (1.0 - 1e-12)))
            xt = seg.xt0 if a == seg.t0 else flow.advance(seg.xt0, a - seg.t0)
            starts = flow.sample_states(xt, full)                              # (full + 1, n+1)
            rest = length - full * flow.delta
            parts_t, parts_w, parts_x = [], [], []
            if full:
                parts_x.append(np.tensordot(starts[:full], flow.node_maps, axes=([1], [2])).reshape(-1, starts.shape[1]))
                parts_t.append((a + flow.delta * np.arange(full)[:, None] + flow.delta * half[None, :]).ravel())
                parts_w.append(np.tile(0.5 * flow.delta * _GL_W, full))
            if rest > 1e-15 * length:
                offsets = rest * half
                parts_x.append((offsets[:, None] ** _EXPONENTS[None, :]) @ (flow.taylor @ starts[full]))
                parts_t.append(a + full * flow.delta + offsets)
                parts_w.append(0.5 * rest * _GL_W)
            nodes = parts_x[0] if len(parts_x) == 1 else np.vstack(parts_x)
            ts.extend(parts_t)
            ws.extend(parts_w)
            xs.append(nodes[:, :-1])
            us.append(nodes @ flow.u_row)
            cs.append(np.full(nodes.shape[0], flow.config))
        if not ts:
            raise ParameterError(f"quadrature interval [{t0:g}, {t1:g}] s lies outside the run")
        return (np.concatenate(ts), np.concatenate(ws), np.vstack(xs), np.concatenate(us)[:, None],
                np.concatenate(cs))

    def sample(self, times) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Exact (x, u, y, config) at the given times (a point on an event takes the segment arriving there)."""
        times = np.asarray(times, dtype=float)
        starts = np.array([s.t0 for s in self.segments])
        which = np.clip(np.searchsorted(starts, times, side="left") - 1, 0, len(self.segments) - 1)
        n = self.problem.n
        x, u, y = np.empty((times.size, n)), np.empty((times.size, 1)), np.empty((times.size, 1))
        config = np.empty(times.size, dtype=np.int64)
        for s in np.unique(which):
            seg = self.segments[s]
            idx = np.flatnonzero(which == s)
            for i in idx:
                xt = expm((times[i] - seg.t0) * seg.flow.Z) @ seg.xt0
                x[i], u[i, 0], y[i, 0] = xt[:n], seg.flow.u_row @ xt, seg.flow.y_row @ xt
            config[idx] = seg.flow.config
        return x, u, y, config

    def trajectory(self, output_step: float) -> Trajectory:
        """Samples on a uniform grid of ``output_step`` plus every segment boundary, as a Trajectory."""
        t0, t1 = self.problem.t_span
        grid = np.append(t0 + output_step * np.arange(int(np.floor((t1 - t0) / output_step * (1 + 1e-12))) + 1), t1)
        bounds = np.array([s.t1 for s in self.segments])
        t = np.unique(np.concatenate([grid[grid <= t1], bounds]))
        t = t[np.concatenate([[True], np.diff(t) > 1e-12 * output_step])]
        x, u, y, config = self._sample_sorted(t, output_step)
        problem = self.problem
        events = self.events
        events = events[events["kind"] != "impulse"].assign(step=np.searchsorted(t, events["time"]) - 1)
        return Trajectory(t=t, x=x, u=u, y=y, config=config, state_names=problem.state_names,
                          pair_names=problem.pair_names,
                          config_names=tuple(c.name or f"config{i}" for i, c in enumerate(problem.configurations)),
                          event_columns=events[["time", "step", "pair", "kind"]].reset_index(drop=True),
                          method="event", steps=len(self.segments), wall_s=self.wall_s,
                          metadata=dict(problem.metadata, event_tol=self.options.event_tol))

    def _sample_sorted(self, t: np.ndarray, step: float):
        """Sorted times on a grid of spacing ``step`` plus segment ends: per segment, offsets q step + r share a
        few remainders r; x = S^q expm(r Z) x0 with the powers S^q of S = expm(step Z) stacked once per flow."""
        n = self.problem.n
        x, u, y = np.empty((t.size, n)), np.empty((t.size, 1)), np.empty((t.size, 1))
        config = np.empty(t.size, dtype=np.int64)
        starts = np.array([seg.t0 for seg in self.segments])
        which = np.clip(np.searchsorted(starts, t, side="left") - 1, 0, len(self.segments) - 1)
        powers: dict = {}
        bounds = np.searchsorted(which, np.arange(len(self.segments) + 1))
        for s_index, seg in enumerate(self.segments):
            lo, hi = bounds[s_index], bounds[s_index + 1]
            if lo == hi:
                continue
            flow = seg.flow
            stack = powers.get(id(flow))
            if stack is None:
                stack = powers[id(flow)] = _power_stack(expm(step * flow.Z), _BLOCK)
            offsets = t[lo:hi] - seg.t0
            q = np.floor(offsets / step * (1 + 1e-12)).astype(np.int64)
            r = offsets - q * step
            r_key = np.round(r / step, 9)
            states = np.empty((hi - lo, n + 1))
            for key in np.unique(r_key):
                sel = np.flatnonzero(r_key == key)
                base = expm(r[sel[0]] * flow.Z) @ seg.xt0
                block_start, block = base, 0
                qs = q[sel]
                for b in range(int(qs.max()) // _BLOCK + 1):
                    in_block = sel[(qs // _BLOCK) == b]
                    if in_block.size:
                        states[in_block] = stack[q[in_block] - b * _BLOCK] @ block_start
                    block_start = stack[_BLOCK] @ block_start
            x[lo:hi] = states[:, :n]
            u[lo:hi, 0] = states @ flow.u_row
            y[lo:hi, 0] = states @ flow.y_row
            config[lo:hi] = flow.config
        return x, u, y, config


_BLOCK = 1024


def _power_stack(S: np.ndarray, count: int) -> np.ndarray:
    """S^0 .. S^count, shape (count + 1, m, m), by doubling (log2(count) batched products)."""
    stack = np.eye(S.shape[0])[None].copy()
    top = S
    while stack.shape[0] <= count:
        stack = np.concatenate([stack, stack @ top])
        top = top @ top
    return stack[: count + 1]


class _Machine:
    """The flows of one problem (built once; reused for every run from a new initial state)."""

    def __init__(self, problem: LCSProblem, options: EventDriven):
        if problem.k != 1:
            raise ParameterError(f"the event-driven method handles one complementarity pair (k = 1); this problem has "
                                 f"k = {problem.k}: use the LCP time-stepper (--method lcp)")
        self.problem, self.options = problem, options
        schedule = problem.schedule
        t0, t1 = problem.t_span
        self.scale = schedule.period if np.isfinite(schedule.period) else (t1 - t0)
        self.flows = {}
        for i, config in enumerate(problem.configurations):
            for held in (False, True):
                self.flows[(i, held)] = _flow(config, i, held, self.scale, options.sample_fraction)

    def edges(self, t0: float, t1: float):
        """(time, configuration) of every schedule instant in (t0, t1), then (t1, None)."""
        schedule = self.problem.schedule
        if not np.isfinite(schedule.period):
            return [(t1, None)]
        T = schedule.period
        first, last = int(np.floor(t0 / T)), int(np.ceil(t1 / T))
        out = []
        for m in range(first, last + 1):
            for start, config in zip(schedule.starts, schedule.configs):
                t = m * T + start
                if t0 < t < t1 and not (out and out[-1][1] == config):
                    out.append((t, config))
        out.append((t1, None))
        return out

    def config_at(self, t: float) -> int:
        return int(self.problem.schedule.config_at(np.array([t]))[0])

    def enter(self, config: int, xt: np.ndarray, t: float, kinds: list, times: list) -> np.ndarray:
        """Apply Moreau's impulse when the configuration is entered with y < 0 and D = 0."""
        c = self.problem.configurations[config]
        y = c.C[0] @ xt[:-1] + c.F[0]
        scale = (np.abs(c.C[0]).sum() + abs(c.F[0])) * np.abs(xt).max()
        if c.D[0, 0] > 0.0 or y >= -_CROSS_RTOL * scale:
            return xt
        cb = float(c.C[0] @ c.B[:, 0])
        if cb <= 0.0:
            raise SimulationError(f"at t = {t:.9g} s configuration {c.name!r} starts with y = {y:.4g} < 0 and C B = "
                                  f"{cb:.3g} <= 0: no impulse restores complementarity (the circuit forces a current "
                                  "into a blocking diode); check the model")
        xt = xt.copy()
        xt[:-1] += c.B[:, 0] * (-y / cb)
        times.append(t)
        kinds.append("impulse")
        return xt

    def select(self, config: int, xt: np.ndarray, t: float) -> Flow:
        """The mode-selection LCP at (t, x), resolved lexicographically (module docstring)."""
        free = self.flows[(config, False)]
        if free.lexicographic_sign(xt) >= 0:
            return free
        held = self.flows[(config, True)]
        if held is not None and held.lexicographic_sign(xt) >= 0:
            return held
        name = self.problem.configurations[config].name
        raise SimulationError(f"the mode-selection LCP at t = {t:.9g} s in configuration {name!r} has no solution "
                              "(the pair can be neither free nor held); the LCS is not well posed there")

    def cross(self, flow: Flow, xt: np.ndarray, tau_max: float):
        """First downward zero crossing of the watched quantity in (0, tau_max]: (tau or None, x~ at tau_max).

        The samples of whole sampling steps come from one batched product with the powers of
        expm(delta Z); the last, partial step from the series."""
        w = flow.watch_row
        g_scale = np.abs(w).sum() * np.abs(xt).max()
        threshold = -_CROSS_RTOL * g_scale
        full = int(np.floor(tau_max / flow.delta * (1.0 - 1e-12)))
        tau, state = 0.0, xt
        while full > 0:
            m = min(full, _POWERS)
            states = flow.powers[1:m + 1] @ state
            below = np.flatnonzero(states @ w < threshold)
            if below.size:
                i = below[0]
                start = state if i == 0 else states[i - 1]
                return self._locate(flow, start, tau + i * flow.delta, flow.delta, g_scale), None
            tau, state, full = tau + m * flow.delta, states[m - 1], full - m
        rest = tau_max - tau
        if rest > 0.0:
            end = flow.propagate(state, rest)
            if w @ end < threshold:
                return self._locate(flow, state, tau, rest, g_scale), None
            state = end
        return (None, None), state

    def _locate(self, flow: Flow, xt_a: np.ndarray, tau_a: float, width: float, g_scale: float):
        """The crossing inside [tau_a, tau_a + width] (width <= delta): Brent's method on the watched
        quantity's Taylor polynomial, exact to rounding there. Returns (tau, x~ at tau)."""
        V = flow.taylor @ xt_a
        coefficients = (V @ flow.watch_row)[::-1].tolist()    # highest power first

        def g(s):
            value = 0.0
            for c in coefficients:   # Horner on Python floats: cheaper than any numpy call here
                value = value * s + c
            return value

        # The bracket's left end may sit on a zero of g (the mode just began); move it to a point where g > 0.
        left, g_left = 0.0, coefficients[-1]
        if g_left <= _CROSS_RTOL * g_scale:
            probe, left = width, None
            for _ in range(60):
                probe *= 0.5
                value = g(probe)
                if value > 0.0:
                    left, g_left = probe, value
                    break
            if left is None:  # leaves at once: an event at tau_a
                return tau_a, xt_a
        xtol = max(self.options.event_tol * self.scale, 1e-300)
        s = brentq(g, left, width, xtol=xtol, rtol=4 * np.finfo(float).eps, maxiter=200)
        if g(s) > _CROSS_RTOL * g_scale:
            # A loose tolerance may stop short of the zero; the mode selection must see the crossing
            # happen, so take the point past it (within 2 xtol, brentq's bound).
            s = min(s + 2.0 * xtol, width)
        return tau_a + s, s ** _EXPONENTS @ V

    def run(self, x0, record: bool = True) -> EventSolution:
        start_clock = time.perf_counter()
        problem, options = self.problem, self.options
        t, t_end = problem.t_span
        xt = np.append(np.asarray(x0, dtype=float), 1.0)
        times, kinds, segments = [], [], []
        config = self.config_at(t)
        xt = self.enter(config, xt, t, kinds, times)
        flow = self.select(config, xt, t)
        same_time_events, events = 0, 0
        for edge_t, edge_config in self.edges(t, t_end):
            while True:
                (tau, xt_event), xt_end = self.cross(flow, xt, edge_t - t)
                if tau is not None and t + tau >= edge_t - options.event_tol * self.scale:
                    tau = None   # a crossing on the edge itself: the edge handles it
                    xt_end = flow.advance(xt, edge_t - t)
                elif tau is not None:
                    xt_end = xt_event
                t_next = edge_t if tau is None else t + tau
                if record and t_next > t:
                    segments.append(Segment(t, t_next, flow, xt))
                if tau is None:
                    t, xt = edge_t, xt_end
                    break
                same_time_events = same_time_events + 1 if tau == 0.0 else 0
                events += 1
                if same_time_events > 8 or events > options.max_events:
                    raise SimulationError(f"{'repeated events at one instant' if same_time_events > 8 else 'too many events'}"
                                          f" near t = {t + tau:.9g} s (Zeno behaviour or a degenerate LCS); "
                                          f"max_events = {options.max_events}")
                t, xt = t + tau, xt_end
                new = self.select(config, xt, t)
                if new.held and not flow.held:
                    xt = self._project(config, xt)
                if new is not flow:
                    times.append(t)
                    kinds.append("activate" if new.held else "release")
                flow = new
            if edge_config is None:
                break
            config = edge_config
            xt = self.enter(config, xt, t, kinds, times)
            flow = self.select(config, xt, t)
        return EventSolution(problem, segments, times, kinds, xt[:-1].copy(), time.perf_counter() - start_clock, options)

    def _project(self, config: int, xt: np.ndarray) -> np.ndarray:
        """Put the state exactly on y = 0 when a D = 0 pair becomes held (removes the root finder's residue)."""
        c = self.problem.configurations[config]
        if c.D[0, 0] != 0.0:
            return xt
        cb = float(c.C[0] @ c.B[:, 0])
        xt = xt.copy()
        xt[:-1] -= c.B[:, 0] * ((c.C[0] @ xt[:-1] + c.F[0]) / cb)
        return xt


def simulate_event(problem: LCSProblem, options: EventDriven | None = None, *, x0=None) -> EventSolution:
    """Run the event-driven method over ``problem.t_span`` from ``x0`` (default ``problem.x0``)."""
    options = options or EventDriven()
    return _Machine(problem, options).run(problem.x0 if x0 is None else _check_x0(x0, problem.n))


def _check_x0(x0, n):
    x = np.asarray(x0, dtype=float)
    if x.shape != (n,) or not np.all(np.isfinite(x)):
        raise ParameterError(f"x0 must be {n} finite numbers; got {x0!r}")
    return x


@dataclass(frozen=True)
class EventOrbit:
    """The exact periodic orbit: its initial state, one period of the solution, shooting statistics."""

    x0: np.ndarray
    solution: EventSolution
    residual: float
    iterations: int
    converged: bool
    wall_s: float = field(default=0.0)


def event_orbit(problem: LCSProblem, x_guess, options: EventDriven | None = None, tol: float = 1e-13,
                max_iter: int = 30) -> EventOrbit:
    """Newton shooting on the exact one-period map (``problem.t_span`` must be one period)."""
    from ..analysis.periodic import newton_fixed_point
    start = time.perf_counter()
    options = options or EventDriven()
    machine = _Machine(problem, options)
    result = newton_fixed_point(lambda x: machine.run(x, record=False).x_end, _check_x0(x_guess, problem.n),
                                tol=tol, max_iter=max_iter)
    solution = machine.run(result.x)
    return EventOrbit(result.x, solution, result.residual, result.iterations, result.converged,
                      time.perf_counter() - start)
