"""Exact event-driven simulation of piecewise-linear LCS with any number of complementarity pairs (and,
through :mod:`.event_mechanical`, of mechanical problems with friction and impacts).

Between events the LCS is linear with constant inputs. A *mode* is a configuration and a held set J
of pairs (y_J = 0, u_J free to be positive; every other pair has u = 0 and y free to be positive).
On J the multipliers follow from keeping y_J at zero: with R, N orthonormal bases of the range and
the left null space of D_JJ,

    R^T (D_JJ u_J + C_J x + F_J) = 0        (pairs whose y depends on u: algebraic)
    N^T C_J (A x + B_J u_J + E) = 0         (pairs whose y is a function of the state: y' = 0)

solved for u_J = U x + u0 (least norm), so the flow is x' = (A + B_J U) x + E + B_J u0; the state
stays on N^T (C_J x + F_J) = 0 (the GDCM flow of one pair is the case J = {i}, D_ii = 0). In
augmented form x~ = [x; 1], x(t0 + tau) = expm(tau Z) x~, exact up to rounding.

A mode ends when a watched quantity crosses zero downwards: y_i of a free pair, u_i of a held pair,
and under a state-driven law (:class:`~converters.problems.switching.StateSwitching`) the distance
of the switching function to the level that ends the configuration (band - s, or s + band; a ramp
adds a term linear in time). Sign changes are looked for on samples at most ``sample_fraction`` T
apart (and 0.25 / ||Z|| apart); the crossing is located by Brent's method on the watched quantity's
Taylor polynomial (exact to rounding) to ``event_tol`` T. Time-driven configuration changes happen at
the schedule's instants; ramp resets are such instants too.

At every event the new mode is the solution of the mode-selection LCP, resolved lexicographically:
the held sets J are tried nearest to the pair that triggered the event first, and J is taken when,
along its flow, every watched quantity's first non-vanishing derivative (value, first, second, ...)
is positive. A state entering a configuration with y_K < 0 on pairs whose y is a function of the
state takes Moreau's impulse x+ = x + B_K lambda, 0 <= lambda _|_ C_K (x + B_K lambda) + F_K >= 0.

Jacobians (period maps, Floquet multipliers): the state-transition matrix of each segment is
expm(tau Z) restricted to x; at an event triggered by g(x, t) = 0 the saltation matrix
S = I + (f+ - f-) n^T / (n^T f- + dg/dt) (n the gradient of g) carries the change of vector field;
an impulse contributes I - B_K (C_K B_K)^-1 C_K.

Integrals over a run (means, RMS) use 8-point Gauss-Legendre quadrature on pieces no longer than the
sampling distance: exact to rounding for these exponential-polynomial pieces.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from ..errors import ParameterError, SimulationError
from ..problems import LCSProblem, Relay, Schedule, StateSwitching
from ..problems.mechanical import MechanicalProblem
from . import event_mechanical
from ..trajectory import Samples, Trajectory
from ..validate import check_positive, parse_value
from .base import Method, PeriodMap, RecordingPeriodMap

#: Largest number of complementarity pairs (the mode selection visits up to 2^k held sets).
MAX_PAIRS = 12


@dataclass(frozen=True)
class EventDriven(Method, key="event"):
    """The exact event-driven method for piecewise-linear LCS (module docstring).

    Parameters
    ----------
    event_tol : float
        Events are located to ``event_tol`` times the switching period (Brent's method on the exact
        flow). Default 1e-13.
    sample_fraction : float
        Watched quantities are sampled at most ``sample_fraction`` T apart when looking for sign
        changes (two crossings closer than that could be missed). Default 1/32.
    output_step : float or None
        Spacing of the output samples in s (events are always added); None: T/1000.
    max_events : int
        Refuse runs with more events than this (Zeno behaviour). Default 10^7.
    ode_rtol : float
        Mechanical (nonlinear) problems only: the relative tolerance of the DOP853 integration of each smooth
        phase (:mod:`.event_mechanical`; the LCS flows are exact). Default 1e-9 (event times within 1e-9 s of
        those at 1e-10 on the friction oscillator, measured).
    chatter_fraction : float
        Mechanical problems with impacts: a chattering sequence whose remaining accumulation time is below this
        fraction of the time scale (or whose bounces rise less than 1e-12 of the state) is completed in closed
        form, exactly for a constant relative acceleration. Default 1e-6.
    """

    counts = "segments"

    event_tol: float = 1e-13
    sample_fraction: float = 1.0 / 32.0
    output_step: float | None = None
    max_events: int = 10_000_000
    ode_rtol: float = 1e-9
    chatter_fraction: float = 1e-6
    step_option = "output_step"
    description = "exact event-driven: matrix exponentials per mode, events by root finding, any number of pairs"
    domains = ("lcs", "mechanical")

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
        for name, low, high in (("ode_rtol", 1e-14, 1e-3), ("chatter_fraction", 0.0, 1e-3)):
            value = parse_value(name, getattr(self, name))
            if not low <= value <= high:
                raise ParameterError(f"{name} must be in [{low:g}, {high:g}]; got {value!r}")
            object.__setattr__(self, name, value)

    @property
    def order(self) -> float:
        return math.inf

    def supports(self, problem) -> None:
        if isinstance(problem, MechanicalProblem):
            return
        if getattr(problem, "inputs", None) is not None:
            raise ParameterError("the event-driven method's exact flows take constant inputs per configuration; "
                                 "sinusoidal inputs (SIN sources): use --method lcp")
        if isinstance(problem.switching, Relay):
            raise ParameterError("the event-driven method follows a hysteresis or latched law (StateSwitching) "
                                 "exactly; the implicit relay is a time-stepping scheme: use --method lcp")
        if problem.k > MAX_PAIRS:
            raise ParameterError(f"the event-driven method selects modes among 2^k held sets: k must be <= "
                                 f"{MAX_PAIRS}; this problem has k = {problem.k}: use --method lcp")

    def solve(self, problem: LCSProblem, x0: np.ndarray) -> Trajectory:
        if isinstance(problem, MechanicalProblem):
            return event_mechanical.solve(problem, self, x0)
        solution = _Machine(problem, self).run(x0)[0]
        scale = _time_scale(problem)
        return solution.trajectory(self.output_step or scale / 1000.0)

    def period_map(self, problem: LCSProblem) -> PeriodMap:
        """The exact map over ``problem.t_span`` with its exact Jacobian (state-transition matrices and
        saltation matrices)."""
        self.supports(problem)
        if isinstance(problem, MechanicalProblem):
            return event_mechanical.period_map(problem, self)
        return EventPeriodMap(_Machine(problem, self))

    def return_map(self, problem: LCSProblem, config: int, crossings: int = 1) -> PeriodMap:
        """For autonomous state-switched problems: x (at a switching into ``config``) -> x at the
        ``crossings``-th next switching into ``config``, with its exact Jacobian; ``period`` of the map is
        the return time of its last call (a Poincare map: the section is the switching surface)."""
        self.supports(problem)
        if not isinstance(problem.switching, StateSwitching):
            raise ParameterError("a return map needs a state-driven switching law (StateSwitching)")
        return EventReturnMap(_Machine(problem, self), config, crossings)


def _time_scale(problem: LCSProblem) -> float:
    period = problem.switching.period
    return period if np.isfinite(period) else problem.t_span[1] - problem.t_span[0]


_GL_X, _GL_W = np.polynomial.legendre.leggauss(8)
_TAYLOR_TERMS = 26     # (0.25)^26 / 26! < 1e-30: the series is exact to rounding on a sampling step
_EXPONENTS = np.arange(_TAYLOR_TERMS)
_POWERS = 64           # sampling steps per batched product
_ZERO_RTOL = 1e-10     # a derivative counts as zero below this fraction of its own scale
_CROSS_RTOL = 1e-13    # a watched value counts as negative below -this fraction of its scale
#: Most substeps (each a quarter of the mode's fastest time constant at most) one crossing search may take: about
#: 5 s of work. A circuit far stiffer than its run (C = 1e-15 F in a 5 ms run: 2e10 substeps) is refused, not hung.
MAX_SUBSTEPS = 100_000_000
_ON_SET_RTOL = 1e-9    # a held pair's constraint N^T (C x + F) counts as met up to this (relative)


def expm(A: np.ndarray) -> np.ndarray:
    """scipy's matrix exponential (imported on first use: a run that needs no event method never pays it)."""
    from scipy.linalg import expm as scipy_expm
    return scipy_expm(A)


def _power_stack(S: np.ndarray, count: int) -> np.ndarray:
    """S^0 .. S^count, shape (count + 1, m, m), by doubling (log2(count) batched products)."""
    stack = np.eye(S.shape[0])[None].copy()
    top = S
    while stack.shape[0] <= count:
        stack = np.concatenate([stack, stack @ top])
        top = top @ top
    return stack[: count + 1]


class Flow:
    """The affine flow of one mode (configuration, held set J) in augmented form x~ = [x; 1].

    ``Z`` (n+1, n+1): x~' = Z x~. ``u_rows``, ``y_rows`` (k, n+1): u = u_rows x~, y = y_rows x~.
    ``watch_rows`` (k, n+1): y_i for free pairs, u_i for held ones (the mode ends when one falls
    through zero). ``constraint_rows``: N^T [C_J, F_J] (zero on the mode's state manifold);
    ``project``: the matrix taking a state onto that manifold along B_J. The sampling data (series,
    powers, quadrature maps) is built on first use.
    """

    def __init__(self, config_index: int, held: int, Z, u_rows, y_rows, constraint_rows, project, delta):
        self.config, self.held = config_index, held
        self.Z, self.u_rows, self.y_rows = Z, u_rows, y_rows
        k = u_rows.shape[0]
        held_pairs = np.array([(held >> i) & 1 for i in range(k)], dtype=bool)
        self.watch_rows = np.where(held_pairs[:, None], u_rows, y_rows)
        self.held_flags = held_pairs
        self.constraint_rows, self.project = constraint_rows, project
        self.constraint_scales = np.abs(constraint_rows).sum(axis=1)
        self.watches: dict = {}                  # _Watch per latch state (built by the machine that owns the flow)
        norm = float(np.abs(Z).sum(axis=1).max())
        self.delta = min(delta, 0.25 / norm) if norm > 0.0 else delta

    @property
    def n(self) -> int:
        return self.Z.shape[0] - 1

    def field(self, xt: np.ndarray) -> np.ndarray:
        """x' at x~."""
        return self.Z[:-1] @ xt

    def derivative_rows(self, rows: np.ndarray, order: int) -> tuple[np.ndarray, np.ndarray]:
        """Rows r Z^j (j = 0..order) of watched rows r, shape (order + 1, m, n+1), and their scales."""
        out, scales = [rows], [np.abs(rows).sum(axis=1)]
        absZ, abs_rows = np.abs(self.Z), np.abs(rows)
        for _ in range(order):
            out.append(out[-1] @ self.Z)
            abs_rows = abs_rows @ absZ
            scales.append(abs_rows.sum(axis=1))
        return np.array(out), np.array(scales)

    @cached_property
    def lexicographic_data(self):
        return self.derivative_rows(self.watch_rows, self.n + 1)

    def lexicographic_ok(self, xt: np.ndarray) -> bool:
        """Every watched quantity's first non-vanishing entry of (g, g', g'', ...) along the flow is
        positive (or all vanish)."""
        rows, scales = self.lexicographic_data
        values = (rows @ xt).T.tolist()                        # per quantity: g, g', g'', ...
        limits = ((_ZERO_RTOL * np.abs(xt).max()) * scales + 1e-300).T.tolist()
        for quantity, limit in zip(values, limits):            # plain floats: the first entry decides mostly
            for value, bound in zip(quantity, limit):
                if abs(value) > bound:
                    if value < 0.0:
                        return False
                    break
        return True

    @cached_property
    def taylor(self) -> np.ndarray:
        """Z^j / j!, j = 0.._TAYLOR_TERMS - 1: x~(s) = sum_j s^j (Z^j / j!) x~ for s <= delta."""
        n1 = self.Z.shape[0]
        taylor = np.empty((_TAYLOR_TERMS, n1, n1))
        taylor[0] = np.eye(n1)
        for j in range(1, _TAYLOR_TERMS):
            taylor[j] = taylor[j - 1] @ self.Z / j
        return taylor

    @cached_property
    def powers(self) -> np.ndarray:
        """expm(delta Z)^j, j = 0.._POWERS: the samples of a segment in one batched product."""
        return _power_stack(expm(self.delta * self.Z), _POWERS)

    @cached_property
    def node_maps(self) -> np.ndarray:
        """expm(s_k Z) at the Gauss-Legendre nodes s_k of [0, delta], shape (8, n+1, n+1)."""
        weights = (0.5 * (_GL_X + 1.0) * self.delta)[:, None] ** _EXPONENTS[None, :]
        return np.tensordot(weights, self.taylor, axes=([1], [0]))

    def propagate(self, xt: np.ndarray, s: float) -> np.ndarray:
        """x~ after s in [0, delta]."""
        return s ** _EXPONENTS @ (self.taylor @ xt)

    def advance(self, xt: np.ndarray, tau: float) -> np.ndarray:
        """x~ after any tau >= 0 (a rounding-negative tau counts as 0): whole sampling steps by powers of
        expm(delta Z), the rest by the series."""
        tau = max(tau, 0.0)
        whole = int(np.floor(tau / self.delta * (1.0 - 1e-12)))
        q = whole
        while q > 0:
            m = min(q, _POWERS)
            xt = self.powers[m] @ xt
            q -= m
        return self.propagate(xt, max(tau - whole * self.delta, 0.0))

    def transition(self, tau: float) -> np.ndarray:
        """The state-transition matrix over tau: d x(tau) / d x(0), shape (n, n)."""
        return expm(tau * self.Z)[:-1, :-1]

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


class _Watch:
    """What ends a segment: rows g = rows x~ + slopes (phase0 + tau), with the pair (or -1: the
    switching law) each row belongs to."""

    def __init__(self, flow: Flow, switch_row=None, switch_slope=0.0):
        rows, slopes, pairs = [flow.watch_rows], [np.zeros(flow.watch_rows.shape[0])], [np.arange(flow.watch_rows.shape[0])]
        if switch_row is not None:
            rows.append(switch_row[None, :])
            slopes.append(np.array([switch_slope]))
            pairs.append(np.array([-1]))
        self.rows = np.vstack(rows)
        self.rows_T = np.ascontiguousarray(self.rows.T)
        self.slopes = np.concatenate(slopes)
        self.timed = bool(np.any(self.slopes))
        self.pairs = np.concatenate(pairs)
        self.row_scales = np.abs(self.rows).sum(axis=1)


@dataclass
class Segment:
    t0: float
    t1: float
    flow: Flow
    xt0: np.ndarray     # augmented state [x; 1] at t0
    xt1: np.ndarray     # ... and at t1, before whatever happens there


class EventSolution:
    """The exact piecewise solution: segments (t0, t1, flow, start state) and the events between them.

    ``event_times``, ``event_kinds`` ('activate', 'release', 'impulse', 'switch'), ``event_pairs``
    (-1 for switching-law events), ``event_configs`` (the configuration in force after the event).
    """

    def __init__(self, problem, segments, times, kinds, pairs, configs, x_end, wall_s, options, end_config):
        self.problem, self.segments, self.options = problem, segments, options
        self.event_times, self.event_kinds, self.event_pairs, self.event_configs = times, kinds, pairs, configs
        self.x_end, self.wall_s, self.end_config = x_end, wall_s, end_config

    def _segments_in(self, t0: float, t1: float):
        for seg in self.segments:
            if seg.t1 > t0 and seg.t0 < t1:
                yield seg, max(seg.t0, t0), min(seg.t1, t1)

    def quadrature(self, t0: float | None = None, t1: float | None = None) -> tuple[Samples, np.ndarray]:
        """Gauss-Legendre nodes over [t0, t1] (default: the whole run) as Samples, and their weights.

        Pieces follow the segments (no node straddles an event), each at most the flow's sampling
        distance long, 8 nodes per piece."""
        t0 = self.problem.t_span[0] if t0 is None else t0
        t1 = self.problem.t_span[1] if t1 is None else t1
        ts, ws, xs, us, ys, cs, hs = [], [], [], [], [], [], []
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
            if not parts_x:
                continue
            nodes = parts_x[0] if len(parts_x) == 1 else np.vstack(parts_x)
            ts.extend(parts_t)
            ws.extend(parts_w)
            xs.append(nodes[:, :-1])
            us.append(nodes @ flow.u_rows.T)
            ys.append(nodes @ flow.y_rows.T)
            cs.append(np.full(nodes.shape[0], flow.config))
            hs.append(np.broadcast_to(flow.held_flags, (nodes.shape[0], flow.held_flags.size)))
        if not ts:
            raise ParameterError(f"quadrature interval [{t0:g}, {t1:g}] s lies outside the run")
        samples = Samples(np.concatenate(ts), np.vstack(xs), np.vstack(us), np.vstack(ys), np.concatenate(cs),
                          held=np.vstack(hs))
        return samples, np.concatenate(ws)

    def sample(self, times) -> Samples:
        """Exact states, pairs and configuration at the given times (a point on an event takes the
        segment arriving there)."""
        times = np.asarray(times, dtype=float)
        starts = np.array([s.t0 for s in self.segments])
        which = np.clip(np.searchsorted(starts, times, side="left") - 1, 0, len(self.segments) - 1)
        n, k = self.problem.n, self.problem.k
        x, u, y = np.empty((times.size, n)), np.empty((times.size, k)), np.empty((times.size, k))
        config = np.empty(times.size, dtype=np.int64)
        held = np.empty((times.size, k), dtype=bool)
        for i, s in enumerate(which):
            seg = self.segments[s]
            xt = seg.flow.advance(seg.xt0, times[i] - seg.t0)
            x[i], u[i], y[i] = xt[:n], seg.flow.u_rows @ xt, seg.flow.y_rows @ xt
            config[i], held[i] = seg.flow.config, seg.flow.held_flags
        return Samples(times, x, u, y, config, held=held)

    def event_list(self) -> list:
        """(time, kind, pair, config) of every event, in time order."""
        return list(zip(self.event_times, self.event_kinds, self.event_pairs, self.event_configs))

    def events_table(self, t: np.ndarray) -> dict:
        times = np.array(self.event_times, dtype=float)
        return {"time": times, "step": np.searchsorted(t, times) - 1, "pair": np.array(self.event_pairs, dtype=np.int64),
                "kind": np.array(self.event_kinds, dtype=object), "config": np.array(self.event_configs, dtype=np.int64)}

    def trajectory(self, output_step: float) -> Trajectory:
        """Samples on a uniform grid of ``output_step`` plus every segment boundary, as a Trajectory."""
        t0, t1 = self.problem.t_span
        grid = np.append(t0 + output_step * np.arange(int(np.floor((t1 - t0) / output_step * (1 + 1e-12))) + 1), t1)
        bounds = np.array([s.t1 for s in self.segments])
        t = np.unique(np.concatenate([grid[grid <= t1], bounds]))
        t = t[np.concatenate([[True], np.diff(t) > 1e-12 * output_step])]
        # A point at a segment's end takes the state the run recorded there; the others are propagated.
        n, k = self.problem.n, self.problem.k
        x, u, y = np.empty((t.size, n)), np.empty((t.size, k)), np.empty((t.size, k))
        config = np.empty(t.size, dtype=np.int64)
        which = np.minimum(np.searchsorted(bounds, t), bounds.size - 1)
        at_end = bounds[which] == t
        segs = [self.segments[i] for i in which[at_end]]
        ends = np.array([seg.xt1 for seg in segs]).reshape(-1, n + 1)
        x[at_end] = ends[:, :n]
        u[at_end] = np.einsum("skn,sn->sk", np.array([seg.flow.u_rows for seg in segs]).reshape(-1, k, n + 1), ends)
        y[at_end] = np.einsum("skn,sn->sk", np.array([seg.flow.y_rows for seg in segs]).reshape(-1, k, n + 1), ends)
        config[at_end] = [seg.flow.config for seg in segs]
        held = np.empty((t.size, k), dtype=bool)
        held[at_end] = np.array([seg.flow.held_flags for seg in segs]).reshape(-1, k)
        inside = ~at_end
        x[inside], u[inside], y[inside], config[inside], held[inside] = self._sample_sorted(t[inside], output_step)
        problem = self.problem
        return Trajectory(t=t, x=x, u=u, y=y, config=config, held=held, state_names=problem.state_names,
                          pair_names=problem.pair_names,
                          config_names=tuple(c.name or f"config{i}" for i, c in enumerate(problem.configurations)),
                          event_columns=self.events_table(t), method="event", steps=len(self.segments),
                          wall_s=self.wall_s, rule="exact", exact=self, period=problem.switching.period,
                          metadata=dict(problem.metadata, event_tol=self.options.event_tol, label="event"))

    def _sample_sorted(self, t: np.ndarray, step: float):
        """Sorted times on a grid of spacing ``step`` plus segment ends: per segment, offsets q step + r share a
        few remainders r; x = S^q expm(r Z) x0 with the powers S^q of S = expm(step Z) stacked once per flow."""
        n, k = self.problem.n, self.problem.k
        x, u, y = np.empty((t.size, n)), np.empty((t.size, k)), np.empty((t.size, k))
        config = np.empty(t.size, dtype=np.int64)
        held = np.empty((t.size, k), dtype=bool)
        starts = np.array([seg.t0 for seg in self.segments])
        which = np.clip(np.searchsorted(starts, t, side="left") - 1, 0, len(self.segments) - 1)
        powers: dict = {}
        longest: dict = {}                       # per flow, its longest segment: how many powers it needs
        for seg in self.segments:
            longest[id(seg.flow)] = max(longest.get(id(seg.flow), 0.0), seg.t1 - seg.t0)
        bounds = np.searchsorted(which, np.arange(len(self.segments) + 1))
        for s_index, seg in enumerate(self.segments):
            lo, hi = bounds[s_index], bounds[s_index + 1]
            if lo == hi:
                continue
            flow = seg.flow
            stack = powers.get(id(flow))
            if stack is None:
                count = min(_BLOCK, int(longest[id(flow)] / step) + 2)
                stack = powers[id(flow)] = _power_stack(expm(step * flow.Z), count)
            offsets = t[lo:hi] - seg.t0
            q = np.floor(offsets / step * (1 + 1e-12)).astype(np.int64)
            r = offsets - q * step
            r_key = np.round(r / step, 9)
            states = np.empty((hi - lo, n + 1))
            for key in np.unique(r_key):
                sel = np.flatnonzero(r_key == key)
                block_start = flow.advance(seg.xt0, r[sel[0]])
                qs = q[sel]
                blocks = int(qs.max()) // _BLOCK + 1
                for b in range(blocks):
                    in_block = sel[(qs // _BLOCK) == b]
                    if in_block.size:
                        states[in_block] = stack[q[in_block] - b * _BLOCK] @ block_start
                    if b + 1 < blocks:
                        block_start = stack[_BLOCK] @ block_start
            x[lo:hi] = states[:, :n]
            u[lo:hi] = states @ flow.u_rows.T
            y[lo:hi] = states @ flow.y_rows.T
            config[lo:hi] = flow.config
            held[lo:hi] = flow.held_flags
        return x, u, y, config, held


_BLOCK = 1024


def _held_sets_by_distance(k: int, reference: int) -> list[int]:
    """Every held set (bit mask) ordered by its distance from ``reference``, then by size."""
    masks = range(1 << k)
    return sorted(masks, key=lambda m: (bin(m ^ reference).count("1"), bin(m).count("1"), m))


class _Machine:
    """The flows of one problem (built on demand, reused for every run from a new initial state)."""

    def __init__(self, problem: LCSProblem, options: EventDriven):
        options.supports(problem)
        self.problem, self.options = problem, options
        self.scale = _time_scale(problem)
        self.flows: dict = {}
        self.orders: dict = {}
        law = problem.switching
        self.law = law if isinstance(law, StateSwitching) else None
        self.index2 = [i for i in range(problem.k)
                       if all(not np.any(c.D[i, :]) and not np.any(c.D[:, i]) for c in problem.configurations)]
        K = self.index2
        #: Per configuration: (C_K, F_K, B_K, row scales) of the pairs whose y is a function of the state.
        self.impulse_data = [(c.C[K], c.F[K], c.B[:, K], np.abs(c.C[K]).sum(axis=1) + np.abs(c.F[K]))
                             for c in problem.configurations]

    # --- modes --------------------------------------------------------------------------------------

    def flow(self, config: int, held: int) -> Flow:
        key = (config, held)
        flow = self.flows.get(key)
        if flow is None:
            flow = self.flows[key] = self._build_flow(config, held)
        return flow

    def _build_flow(self, index: int, held: int) -> Flow:
        c = self.problem.configurations[index]
        n, k = c.n, c.k
        J = [i for i in range(k) if (held >> i) & 1]
        xt_cols = n + 1
        u_rows = np.zeros((k, xt_cols))
        constraint_rows = np.zeros((0, xt_cols))
        project = None
        if J:
            DJJ, CJ, FJ, BJ = c.D[np.ix_(J, J)], c.C[J], c.F[J], c.B[:, J]
            U, S, _ = np.linalg.svd(DJJ)
            rank = int(np.sum(S > 1e-12 * max(S.max(initial=0.0), 1e-300))) if S.size else 0
            R, N = U[:, :rank], U[:, rank:]
            G = np.vstack([R.T @ DJJ, N.T @ CJ @ BJ])
            P = np.vstack([np.hstack([R.T @ CJ, (R.T @ FJ)[:, None]]),
                           np.hstack([N.T @ CJ @ c.A, (N.T @ CJ @ c.E)[:, None]])])
            u_rows[J] = -np.linalg.pinv(G) @ P
            if N.shape[1]:
                constraint_rows = np.hstack([N.T @ CJ, (N.T @ FJ)[:, None]])
                NCB = N.T @ CJ @ BJ
                project = (BJ, np.linalg.pinv(NCB))
        Z = np.zeros((xt_cols, xt_cols))
        Z[:n, :n], Z[:n, n] = c.A, c.E
        Z[:n] += c.B @ u_rows
        y_rows = np.hstack([c.C, c.F[:, None]]) + c.D @ u_rows
        delta = self.options.sample_fraction * self.scale
        return Flow(index, held, Z, u_rows, y_rows, constraint_rows, project, delta)

    def _on_set(self, flow: Flow, xt: np.ndarray, size: float, rate_field, slack: float) -> tuple[bool, np.ndarray]:
        """Is x~ on the flow's state manifold N^T (C_J x + F_J) = 0? Up to rounding, and at an event up to
        what the located time's error (``slack`` s, along the field before the event) allows. Returns
        (ok, x~ projected onto the manifold along B_J). ``size``: max |x~|."""
        rows = flow.constraint_rows
        if rows.shape[0] == 0:
            return True, xt
        r = rows @ xt
        tol = _ON_SET_RTOL * (flow.constraint_scales * size + 1e-300)
        if rate_field is not None:
            tol = tol + slack * np.abs(rows[:, :-1] @ rate_field)
        if (np.abs(r) > tol).any():
            return False, xt
        BJ, pinv = flow.project
        out = xt.copy()
        out[:-1] -= BJ @ (pinv @ r)
        return True, out

    def select(self, config: int, xt: np.ndarray, t: float, reference: int, rate_field=None) -> tuple[Flow, np.ndarray]:
        """The mode-selection LCP at (t, x): the held set nearest to ``reference`` whose flow keeps every
        watched quantity lexicographically non-negative; x~ projected onto its manifold. ``rate_field``:
        the vector field before an event (its location error may leave a held pair's y slightly off zero)."""
        k = self.problem.k
        order = self.orders.get(reference)
        if order is None:
            order = self.orders[reference] = _held_sets_by_distance(k, reference)
        slack = 4.0 * self.options.event_tol * self.scale
        size = np.abs(xt).max()
        for held in order:
            flow = self.flow(config, held)
            ok, projected = self._on_set(flow, xt, size, rate_field, slack)
            if ok and flow.lexicographic_ok(projected):
                return flow, projected
        name = self.problem.configurations[config].name
        raise SimulationError(f"the mode-selection LCP at t = {t:.9g} s in configuration {name!r} has no solution "
                              "(no set of held pairs keeps every pair complementary); the LCS is not well posed there")

    def enter(self, config: int, xt: np.ndarray, t: float, log) -> tuple[np.ndarray, np.ndarray | None]:
        """Moreau's impulse when configuration ``config`` is entered with y_K < 0 on the pairs K whose y is
        a function of the state: x+ = x + B_K lambda, 0 <= lambda _|_ C_K x+ + F_K >= 0. Returns x~+ and
        the jump's Jacobian d x+ / d x = I - B_J (C_J B_J)^-1 C_J on the pairs J that jumped (None: no jump)."""
        K = self.index2
        if not K:
            return xt, None
        c = self.problem.configurations[config]
        CK, FK, BK, row_scale = self.impulse_data[config]
        y = CK @ xt[:-1] + FK
        if np.all(y >= -_CROSS_RTOL * np.abs(xt).max() * row_scale):
            return xt, None
        M = CK @ BK
        from ..lcp import solve_lcp                 # imported here: a run that never needs it starts faster
        result = solve_lcp(M, y, method="lemke")
        if not result.solved:
            raise SimulationError(f"at t = {t:.9g} s configuration {c.name!r} starts with y = {y.tolist()} and no "
                                  f"impulse restores complementarity (C B = {M.tolist()}; the circuit forces a current "
                                  "into a blocking diode); check the model")
        lam = result.z
        xt = xt.copy()
        xt[:-1] += BK @ lam
        jumped = np.flatnonzero(lam > 0.0)
        for i in jumped:
            log(t, "impulse", K[i], config)
        if not jumped.size:
            return xt, None
        idx = [K[i] for i in jumped]
        Bs, Cs = c.B[:, idx], c.C[idx]
        return xt, np.eye(c.n) - Bs @ np.linalg.solve(Cs @ Bs, Cs)

    # --- switching law ------------------------------------------------------------------------------

    def switch_row(self, config: int, latched: bool):
        """(row, slope) of the switching law's watched quantity in ``config`` (None when it cannot switch)."""
        law = self.law
        if law is None or latched:
            return None, 0.0
        f = law.function
        low, slope = (f.ramp.low, f.ramp.slope) if f.ramp is not None else (0.0, 0.0)
        if config == law.below:      # ends when s = c x + d - ramp rises above +band: watch band - s
            return np.append(-f.c, law.band - f.d + low), slope
        return np.append(f.c, f.d - low + law.band), -slope       # ends when s falls below -band: s + band

    def law_config(self, xt: np.ndarray, config: int) -> int:
        """At a ramp reset: the configuration set by s against the band (inside the band it holds)."""
        law = self.law
        f = law.function
        s = float(f.c @ xt[:-1] + f.d - (f.ramp.low if f.ramp is not None else 0.0))
        if s < -law.band:
            return law.below
        if s > law.band:
            return law.above
        return config

    def edges(self, t0: float, t1: float):
        """(time, kind) of every time-driven instant in (t0, t1), then (t1, 'end'). kind: a configuration
        index (schedule), 'reset' (ramp reset)."""
        law = self.problem.switching
        out = []
        if isinstance(law, Schedule) and np.isfinite(law.period):
            T = law.period
            for m in range(int(np.floor(t0 / T)), int(np.ceil(t1 / T)) + 1):
                for start, config in zip(law.starts, law.configs):
                    t = m * T + start
                    if t0 < t < t1 and not (out and out[-1][1] == config):
                        out.append((t, config))
        elif isinstance(law, StateSwitching):
            out = [(t, "reset") for t in law.breakpoints(t0, t1)]
        out.append((t1, "end"))
        return out

    # --- crossings ----------------------------------------------------------------------------------

    def cross(self, flow: Flow, watch: _Watch, xt: np.ndarray, tau_max: float, phase0: float):
        """First downward zero crossing of a watched quantity in (0, tau_max]: (tau, row) or (None, None),
        and x~ at tau_max when there is none."""
        g_scale = watch.row_scales * np.abs(xt).max()
        if watch.timed:
            g_scale = g_scale + np.abs(watch.slopes) * self.scale
        threshold = -_CROSS_RTOL * g_scale
        if not (flow.delta > 0.0 and tau_max / flow.delta <= MAX_SUBSTEPS):
            from ..errors import ResourceError
            raise ResourceError(f"--method event: the stiffest mode's time constant is about {4.0 * flow.delta:.3g} s, "
                                f"so crossing {tau_max:.3g} s takes {tau_max / flow.delta if flow.delta > 0 else np.inf:.3g}"
                                f" substeps (at most {MAX_SUBSTEPS:.0e}): a run far longer than the circuit's fastest time "
                                "constant (a tiny C, L or R, or a long --t-end); use --method lcp, or a shorter --t-end")
        full = int(np.floor(tau_max / flow.delta * (1.0 - 1e-12)))
        tau, state = 0.0, xt
        while full > 0:
            m = min(full, _POWERS)
            states = flow.powers[1:m + 1] @ state
            values = states @ watch.rows_T
            if watch.timed:
                values += (phase0 + tau + flow.delta * np.arange(1, m + 1))[:, None] * watch.slopes[None, :]
            below = np.flatnonzero(values[:, 0] < threshold[0] if values.shape[1] == 1
                                   else (values < threshold).any(axis=1))
            if below.size:
                i = below[0]
                start = state if i == 0 else states[i - 1]
                return self._locate(flow, watch, start, tau + i * flow.delta, flow.delta, g_scale, phase0), None
            tau, state, full = tau + m * flow.delta, states[m - 1], full - m
        rest = tau_max - tau
        if rest > 0.0:
            end = flow.propagate(state, rest)
            values = watch.rows @ end + (phase0 + tau_max) * watch.slopes
            if np.any(values < threshold):
                return self._locate(flow, watch, state, tau, rest, g_scale, phase0), None
            state = end
        return (None, None), state

    def _locate(self, flow: Flow, watch: _Watch, xt_a, tau_a, width, g_scale, phase0):
        """The earliest crossing inside [tau_a, tau_a + width] (width <= delta): Brent's method on each
        watched quantity's Taylor polynomial, exact to rounding there. Returns (tau, row)."""
        V = flow.taylor @ xt_a                                   # x~(s) = sum_j s^j V_j
        coefficients = V @ watch.rows.T                          # (terms, rows)
        coefficients[0] += (phase0 + tau_a) * watch.slopes
        coefficients[1] += watch.slopes
        xtol = max(self.options.event_tol * self.scale, 1e-300)
        best, best_row = None, None
        for r in range(watch.rows.shape[0]):
            poly = coefficients[::-1, r].tolist()                # highest power first

            def g(s, poly=poly):
                value = 0.0
                for c in poly:   # Horner on Python floats: cheaper than any numpy call here
                    value = value * s + c
                return value

            threshold = _CROSS_RTOL * g_scale[r]
            if g(width) >= -threshold:
                continue
            # The bracket's left end may sit on a zero of g (the mode just began); move it to where g > 0.
            left, g_left = 0.0, poly[-1]
            if g_left <= threshold:
                probe, left = width, None
                for _ in range(60):
                    probe *= 0.5
                    if g(probe) > 0.0:
                        left = probe
                        break
                if left is None:                                 # leaves at once: an event at tau_a
                    return tau_a, r
            from scipy.optimize import brentq
            s = brentq(g, left, width, xtol=xtol, rtol=4 * np.finfo(float).eps, maxiter=200)
            if g(s) > threshold:
                # A loose tolerance may stop short of the zero; the mode selection must see the crossing
                # happen, so take the point past it (within 2 xtol, brentq's bound).
                s = min(s + 2.0 * xtol, width)
            if best is None or s < best:
                best, best_row = s, r
        if best is None:                                         # rounding: the sample said below, no root
            return tau_a + width, int(np.argmin(watch.rows @ flow.propagate(xt_a, width)))
        return tau_a + best, best_row

    # --- runs ---------------------------------------------------------------------------------------

    def run(self, x0, record: bool = True, jacobian: bool = False, stop_config: int | None = None,
            stop_count: int = 0):
        """Run over t_span from x0. ``jacobian``: also d x_end / d x0. ``stop_config``/``stop_count``: stop
        at the ``stop_count``-th switching into ``stop_config`` (a return map; the run may then end before
        t_span[1], which must be long enough). Returns (EventSolution, jacobian or None, stop time or None)."""
        start_clock = time.perf_counter()
        problem, options = self.problem, self.options
        n = problem.n
        t, t_end = problem.t_span
        xt = np.append(np.asarray(x0, dtype=float), 1.0)
        times, kinds, pairs, configs, segments = [], [], [], [], []
        jac = np.eye(n) if jacobian else None

        def log(time_, kind, pair, config_):
            times.append(time_), kinds.append(kind), pairs.append(pair), configs.append(config_)

        law = self.law
        config = problem.switching.initial_config(xt[:-1], t)
        latched = False
        ramp_period = law.period if law is not None else np.inf
        # The ramp's phase counts from t = 0 (ramp(t) = low + slope * (t mod T)), as in the stepper.
        phase_start = np.floor(t / ramp_period) * ramp_period if np.isfinite(ramp_period) else t
        xt, jump = self.enter(config, xt, t, log)
        if jac is not None and jump is not None:
            jac[:] = jump @ jac
        flow, xt = self.select(config, xt, t, 0)
        same_time_events, events, crossings = 0, 0, 0
        stop_time = None
        for edge_t, edge_kind in self.edges(t, t_end):
            while True:
                watch = flow.watches.get(latched)
                if watch is None:                        # the law's row depends on the configuration and the latch
                    watch = flow.watches[latched] = _Watch(flow, *self.switch_row(config, latched))
                phase0 = t - phase_start
                (tau, which), xt_end = self.cross(flow, watch, xt, edge_t - t, phase0)
                if tau is not None and t + tau >= edge_t - options.event_tol * self.scale:
                    tau = None                                   # a crossing on the edge itself: the edge handles it
                    xt_end = flow.advance(xt, edge_t - t)
                if tau is not None:
                    xt_end = flow.advance(xt, tau)
                t_next = edge_t if tau is None else t + tau
                if record and t_next > t:
                    segments.append(Segment(t, t_next, flow, xt, xt_end))
                if jac is not None:
                    jac[:] = flow.transition(t_next - t) @ jac
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
                pair = int(watch.pairs[which])
                grad = watch.rows[which, :n]
                dgdt = watch.slopes[which]
                f_before = flow.field(xt)
                if pair < 0:                                     # the switching law fires
                    config = law.above if config == law.below else law.below
                    latched = law.latch
                    log(t, "switch", -1, config)
                    if stop_config is not None and config == stop_config:
                        crossings += 1
                        if crossings >= stop_count:
                            if jac is not None:
                                denominator = grad @ f_before + dgdt
                                jac[:] = (np.eye(n) - np.outer(f_before, grad) / denominator) @ jac
                            stop_time = t
                            break
                    xt_in, jump = self.enter(config, xt, t, log)
                    new, xt_new = self.select(config, xt_in, t, flow.held, f_before)
                else:
                    jump = None
                    new, xt_new = self.select(config, xt, t, flow.held ^ (1 << pair), f_before)
                if jac is not None:
                    # Saltation through a jump x+ = Pi(x): S = DPi + (f+ - DPi f-) n^T / (n^T f- + dg/dt).
                    f_after = new.field(xt_new)
                    jump_jac = np.eye(n) if jump is None else jump
                    denominator = grad @ f_before + dgdt
                    if denominator != 0.0:
                        jac[:] = (jump_jac + np.outer(f_after - jump_jac @ f_before, grad) / denominator) @ jac
                    else:
                        jac[:] = jump_jac @ jac
                for i in range(problem.k):
                    was, now = (flow.held >> i) & 1, (new.held >> i) & 1
                    if was != now:
                        log(t, "activate" if now else "release", i, config)
                flow, xt = new, xt_new
            if stop_time is not None or edge_kind == "end":
                break
            if edge_kind == "reset":
                phase_start, latched = t, False
                new_config = self.law_config(xt, config)
                if new_config != config:
                    config = new_config
                    log(t, "switch", -1, config)
            else:
                config = edge_kind
            xt, jump = self.enter(config, xt, t, log)
            if jac is not None and jump is not None:
                jac[:] = jump @ jac
            new, xt = self.select(config, xt, t, flow.held)
            for i in range(problem.k):
                was, now = (flow.held >> i) & 1, (new.held >> i) & 1
                if was != now:
                    log(t, "activate" if now else "release", i, config)
            flow = new
        if stop_config is not None and stop_time is None:
            raise SimulationError(f"the return map found {crossings} of {stop_count} switchings into configuration "
                                  f"{stop_config} before t = {t_end:g} s; lengthen the problem's t_span")
        solution = EventSolution(problem, segments, times, kinds, pairs, configs, xt[:-1].copy(),
                                 time.perf_counter() - start_clock, options, config)
        return solution, jac, stop_time


class EventPeriodMap(RecordingPeriodMap):
    """The exact map over a problem's span, with its exact Jacobian; it keeps the events of its last run."""

    def __init__(self, machine: _Machine):
        super().__init__()
        self.machine = machine

    def _solve(self, x0, jacobian):
        solution, jac, _ = self.machine.run(x0, record=False, jacobian=jacobian)
        return solution, jac


class EventReturnMap(PeriodMap):
    """x -> x at the ``crossings``-th next switching into ``config`` (exact, with the exact Jacobian of
    the Poincare map). ``period`` holds the return time of the last evaluation."""

    def __init__(self, machine: _Machine, config: int, crossings: int):
        super().__init__()
        self.machine, self.config, self.crossings = machine, config, crossings
        self.period = math.nan

    def _run(self, x0, jacobian):
        self.evaluations += 1
        solution, jac, stop = self.machine.run(x0, record=False, jacobian=jacobian, stop_config=self.config,
                                               stop_count=self.crossings)
        self.period = stop - self.machine.problem.t_span[0]
        return solution.x_end, jac

    def end(self, x0):
        return self._run(x0, False)[0]

    def __call__(self, x0):
        return self._run(x0, True)
