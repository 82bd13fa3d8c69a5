"""The event method's engine for one problem: the modes' flows (built on demand), the mode-selection LCP at an
event, Moreau's impulse entering a configuration, the switching law, the location of crossings, and the run from
one event to the next."""
from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, cast

import numpy as np
import numpy.typing as npt

from ...errors import SimulationError
from ...limits import check_in_use
from ...problems import Comparators, LCSProblem, Schedule, StateSwitching
from ...problems.switching import initial_bits, law_channels
from .core import EnginePeriodMap
from .flow import (_CROSS_RTOL, _ON_SET_RTOL, _POWERS, _ZERO_RTOL, HOPELESS, MAX_SERIES_NORM, MAX_SUBSTEPS, FloatArray,
                   Flow, _time_scale, _Watch)
from .solution import EventSolution, Segment
from .timeline import Crossing, Edge, FlowSpan, TimelineEntry

if TYPE_CHECKING:
    from ...problems.lcs import Configuration
    from ...trajectory import Trajectory
    from . import EventDriven

#: Where a run records an event: (time, kind, pair, configuration after it).
EventLog = Callable[[float, str, int, int], None]
#: A time-driven instant: (time, kind, channel), kind a configuration index, "reset", "limit" or "end".
EdgeEntry = tuple[float, int | str, int]


def _held_sets_by_distance(k: int, reference: int) -> list[int]:
    """Every held set (bit mask) ordered by its distance from ``reference``, then by size."""
    masks = range(1 << k)
    return sorted(masks, key=lambda m: (bin(m ^ reference).count("1"), bin(m).count("1"), m))


def _neighbours(k: int, held: int) -> list[int]:
    """The held sets one pair away from ``held``."""
    return [held ^ (1 << i) for i in range(k)]


#: The mode-selection LCP's step over the configuration's fastest rate (:meth:`_Machine.lcp_held`): small enough
#: that each further derivative of the watched quantities weighs 1e3 times less than the one before it (the
#: rational complementarity problem's ordering), large enough that three of them stay above rounding.
SELECT_STEP = 1e-3
#: When the LCP's held set at :data:`SELECT_STEP` and its neighbours fail the exact test, the LCP is solved again
#: at steps this much shorter, up to this many times: an input that moves faster than the configuration's rates
#: (a clock's 10 ps edge beside a 10 ohm, 100 nF ladder) makes the step look past the instant's ordering, and the
#: rational complementarity problem's solution is the mode only for sigma = 1/h large enough (Heemels, Schumacher
#: and Weiland 2000), a bound not known in advance. Four refinements reach 1e-15 of the fastest time constant.
SELECT_REFINEMENTS = 4
SELECT_REFINE = 1e-3
#: Up to this many pairs, a held set is also sought among all 2^k (nearest to the reference first) when the LCP's
#: candidate and its neighbours fail the exact test (a degenerate LCP: several pairs at zero to three derivatives).
ENUMERATE_PAIRS = 12


#: How often (in segments) the engine looks at the memory it holds against the limit (/proc: ~10 us a look).
MEMORY_LOOK = 4096

@dataclass(eq=False)
class _Run:
    """One event-driven run as it advances (:meth:`_Machine.run`): where it is (t, the augmented state, the mode and
    configuration, the law's channel bits and latches, each ramp's phase start), what it has recorded (segments, the
    event log, the timeline), the period map's Jacobian so far, and its counters."""

    t: float
    xt: FloatArray
    config: int
    bits: int                                    # bit j: channel j above
    phase_start: FloatArray
    jac: FloatArray | None
    record: bool
    timeline: list[TimelineEntry] | None
    flow: Flow | None = None
    latched: int = 0                             # bit j: channel j latched
    segments: list[Segment] = field(default_factory=list)
    times: list[float] = field(default_factory=list)
    kinds: list[str] = field(default_factory=list)
    pairs: list[int] = field(default_factory=list)
    configs: list[int] = field(default_factory=list)
    same_time_events: int = 0
    events: int = 0
    crossings: int = 0
    looks: int = 0
    stop_time: float | None = None

    def log(self, time_: float, kind: str, pair: int, config: int) -> None:
        self.times.append(time_)
        self.kinds.append(kind)
        self.pairs.append(pair)
        self.configs.append(config)

    def apply(self, jump: FloatArray | None) -> None:
        """Carry the Jacobian through a state jump (a configuration entered across a charged capacitance)."""
        if self.jac is not None and jump is not None:
            self.jac[:] = jump @ self.jac


def _off_manifold(flow: Flow, S: FloatArray) -> bool:
    """Whether a saltation ``S`` maps perturbations off ``flow``'s state manifold (its held pairs' state constraints,
    N^T C_J x + N^T F_J = 0), where every perturbed run is once it holds them: beyond 1e-9 of the rows' scale."""
    rows = flow.constraint_rows[:, :-1]
    if not rows.size:
        return False
    return bool(np.abs(rows @ S).max() > 1e-9 * max(float(np.abs(rows).max()), 1e-300))


class _Machine:
    """The flows of one problem (built on demand, reused for every run from a new initial state)."""

    def __init__(self, problem: LCSProblem, options: EventDriven) -> None:
        options.supports(problem)
        self.problem, self.options = problem, options
        self.scale = _time_scale(problem)
        self.flows: dict[tuple[int, int], Flow] = {}
        self.orders: dict[int, list[int]] = {}
        #: per configuration: the mode-selection LCP's matrices (the LU factors of I - h A and their pivots, W, h)
        self.select_data: dict[tuple[int, int], tuple[tuple[FloatArray, npt.NDArray[np.int32]], FloatArray, float]] = {}
        law = problem.switching
        self.law = law if isinstance(law, (StateSwitching, Comparators)) else None
        #: The law's channels (one per comparator) and the configuration of each combination of their states.
        self.channels, self.table = law_channels(self.law) if self.law is not None else ((), ())
        #: The last run's jumps: ((time, energy lost), ...) (:meth:`enter`)
        self.jumps: list[tuple[float, float]] = []
        #: Per configuration: the pairs whose y is a function of the state there (no D row or column: a diode in
        #: series with an inductor once the switch across it opens, though the closed switch gave it a D), and
        #: their (C_K, F_K, B_K, row scales).
        self.index2 = [[i for i in range(problem.k) if not np.any(c.D[i, :]) and not np.any(c.D[:, i])]
                       for c in problem.configurations]
        # (a Configuration's E and F are typed optional for their defaults; once it is built they are arrays)
        self.impulse_data = [(c.C[K], cast(FloatArray, c.F)[K], c.B[:, K],
                              np.abs(c.C[K]).sum(axis=1) + np.abs(cast(FloatArray, c.F)[K]))
                             for c, K in zip(problem.configurations, self.index2)]

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
            DJJ, CJ, FJ, BJ = c.D[np.ix_(J, J)], c.C[J], cast(FloatArray, c.F)[J], c.B[:, J]
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
        y_rows = np.hstack([c.C, cast(FloatArray, c.F)[:, None]]) + c.D @ u_rows
        delta = self.options.sample_fraction * self.scale
        return Flow(index, held, Z, u_rows, y_rows, constraint_rows, project, delta)

    def _on_set(self, flow: Flow, xt: np.ndarray, size: float, rate_field: FloatArray | None,
                slack: float) -> tuple[bool, np.ndarray]:
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
        BJ, pinv = cast("tuple[FloatArray, FloatArray]", flow.project)      # set where there are constraint rows
        out = xt.copy()
        out[:-1] -= BJ @ (pinv @ r)
        return True, out

    def select(self, config: int, xt: np.ndarray, t: float, reference: int,
               rate_field: FloatArray | None = None) -> tuple[Flow, np.ndarray]:
        """The mode at (t, x): a held set whose flow keeps every watched quantity lexicographically non-negative,
        x~ projected onto its manifold. Tried in turn: ``reference`` (the held set before the event with the pair
        that crossed flipped), the mode-selection LCP's candidate (:meth:`lcp_held`) and the sets one pair from
        it, then the same at its shorter steps (:data:`SELECT_REFINEMENTS`); then, for at most
        :data:`ENUMERATE_PAIRS` pairs, every set nearest ``reference`` first. ``rate_field``:
        the vector field before an event (its location error may leave a held pair's y slightly off zero)."""
        k = self.problem.k
        slack = 4.0 * self.options.event_tol * self.scale
        size = np.abs(xt).max()
        tried: set[int] = set()

        def valid(held: int, small_positive: bool = False) -> tuple[Flow, np.ndarray] | None:
            if held in tried and not small_positive:
                return None
            tried.add(held)
            flow = self.flow(config, held)
            ok, projected = self._on_set(flow, xt, size, rate_field, slack)
            return (flow, projected) if ok and flow.lexicographic_ok(projected, small_positive) else None

        found = valid(reference)
        if found is not None:
            return found
        candidate = self.lcp_held(config, xt)
        for held in [candidate, *_neighbours(k, candidate)]:
            found = valid(held)
            if found is not None:
                return found
        for refinement in range(1, SELECT_REFINEMENTS + 1):
            finer = self.lcp_held(config, xt, refinement)
            for held in [finer, *_neighbours(k, finer)]:        # (a set already tried is not tried again)
                found = valid(held)
                if found is not None:
                    return found
        if k <= ENUMERATE_PAIRS:
            order = self.orders.get(reference)
            if order is None:
                order = self.orders[reference] = _held_sets_by_distance(k, reference)
            for held in order:
                found = valid(held)
                if found is not None:
                    return found
        # Currents or voltages positive but below the zero band (1e-7 A in a 48-diode ladder at no load, falling):
        # the LCP's mode holds at this instant, and its flow crosses them as any other.
        for held in (candidate, reference):
            found = valid(held, small_positive=True)
            if found is not None:
                return found
        name = self.problem.configurations[config].name
        if k <= ENUMERATE_PAIRS:
            raise SimulationError(f"the mode-selection LCP at t = {t:.9g} s in configuration {name!r} has no solution "
                                  "(every set of held pairs leaves a pair non-complementary); the LCS is not well "
                                  "posed there")
        # past ENUMERATE_PAIRS only the LCP's candidate and its neighbours are tried: not finding the mode among them
        # says nothing of the circuit (a 16-stage Dickson pump with 10 ohm in every diode, unique at every instant)
        raise SimulationError(f"the event method did not find the mode at t = {t:.9g} s in configuration {name!r}: "
                              f"with {k} pairs it tries the mode-selection LCP's held sets (at its step and shorter "
                              f"ones) and the sets one pair from them, and enumerates every set only up to "
                              f"{ENUMERATE_PAIRS} pairs; use --method lcp")

    def lcp_held(self, config: int, xt: np.ndarray, refinement: int = 0) -> int:
        """The held set (bit mask) of the backward-Euler LCP over a step h = :data:`SELECT_STEP` over the
        configuration's fastest rate (times :data:`SELECT_REFINE` ** ``refinement``):
        0 <= u _|_ (D + C (I - hA)^-1 h B) u + C (I - hA)^-1 (x + h E) + F >= 0. It is
        the rational complementarity problem at sigma = 1/h, whose solution for large sigma gives the mode the LCS
        leaves x in, the watched quantities' derivatives ordered lexicographically (Heemels, Schumacher and Weiland,
        "Linear complementarity systems", SIAM J. Appl. Math. 60 (2000); for passive networks the backward-Euler
        LCP's consistency: Camlibel, Heemels and Schumacher, IEEE Trans. Circuits Syst. I 49 (2002)). One k-by-k LCP
        (Lemke) instead of 2^k flows; the exact test in :meth:`select` still decides."""
        import scipy.linalg
        data = self.select_data.get((config, refinement))
        if data is None:
            c = self.problem.configurations[config]
            # The fastest rate: A's, and where a pair has a resistance (D_ii > 0) the rate its conduction adds,
            # |C||B| over D_ii (a 48-diode ladder's RS C chain: |h C B| reached D at h = 1e-3 / |A| and the LCP
            # chose another mode than D's own).
            coupling = (np.abs(c.C) @ np.abs(c.B)).sum(axis=1)
            d = np.diag(c.D)
            resistive = d > 0.0
            rate = max(float(np.abs(c.A).sum(axis=1).max(initial=0.0)), 1.0 / self.scale,
                       float((coupling[resistive] / d[resistive]).max(initial=0.0)))
            h = SELECT_STEP * SELECT_REFINE ** refinement / rate
            lu = scipy.linalg.lu_factor(np.eye(c.n) - h * c.A)
            W = c.D + c.C @ scipy.linalg.lu_solve(lu, h * c.B)
            data = self.select_data[config, refinement] = (lu, W, h)
        lu, W, h = data
        c = self.problem.configurations[config]
        q = c.C @ scipy.linalg.lu_solve(lu, xt[:-1] + h * cast(FloatArray, c.E)) + c.F
        from ...lcp import solve_lcp                 # imported here: a run that never needs it starts faster
        result = solve_lcp(W, q, method="lemke")
        if not result.solved:
            return 0
        z = result.z
        held = 0
        for i in np.flatnonzero(z > 1e-12 * max(float(np.abs(z).max()), 1e-300)):
            held |= 1 << int(i)
        return held

    def enter(self, config: int, xt: np.ndarray, t: float, log: EventLog) -> tuple[np.ndarray, np.ndarray | None]:
        """The state's jumps when configuration ``config`` is entered: first the charges its closed switches
        redistribute (:class:`~converters.problems.Jump`: x+ = P x + q, Jacobian P), then Moreau's impulse where
        y_K < 0 on the pairs K whose y is a function of the state: x+ = x + B_K lambda,
        0 <= lambda _|_ C_K x+ + F_K >= 0. Returns x~+ and the jumps' Jacobian d x+ / d x (the impulse's
        I - B_J (C_J B_J)^-1 C_J on the pairs J that jumped; None: no jump)."""
        c = self.problem.configurations[config]
        if c.jump is not None:
            x = xt[:-1]
            moved = c.jump(x)
            if np.abs(moved - x).max() > _CROSS_RTOL * max(np.abs(x).max(), np.abs(moved).max()):
                log(t, "jump", -1, config)
                self.jumps.append((t, float(c.jump.loss(x))))
            xt = np.append(moved, 1.0)
            xt, impulse = self._impulse(c, config, xt, t, log)
            return xt, c.jump.P if impulse is None else impulse @ c.jump.P
        return self._impulse(c, config, xt, t, log)

    def _impulse(self, c: Configuration, config: int, xt: np.ndarray, t: float,
                 log: EventLog) -> tuple[np.ndarray, np.ndarray | None]:
        K = self.index2[config]
        if not K:
            return xt, None
        CK, FK, BK, row_scale = self.impulse_data[config]
        y = CK @ xt[:-1] + FK
        if np.all(y >= -_CROSS_RTOL * np.abs(xt).max() * row_scale):
            return xt, None
        M = CK @ BK
        from ...lcp import solve_lcp                 # imported here: a run that never needs it starts faster
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

    def law_rows(self, bits: int,
                 latched: int) -> tuple[FloatArray | None, FloatArray | None, npt.NDArray[np.int64] | None]:
        """(rows, slopes, channels) of the quantities whose zero ends the channels' states ``bits`` (bit j: channel
        j above), the latched channels (``latched`` bits) and a clocked channel above (only its clock sets it) left
        out: channel j below ends when s_j = c x + d - ramp rises above +band (watch band - s_j), above when it falls
        below -band (watch s_j + band)."""
        rows: list[FloatArray] = []
        slopes: list[float] = []
        channels: list[int] = []
        for j, channel in enumerate(self.channels):
            above = (bits >> j) & 1
            if (latched >> j) & 1 or (channel.clocked and above):
                continue
            f = channel.function
            low, slope = (f.ramp.low, f.ramp.slope) if f.ramp is not None else (0.0, 0.0)
            if above:
                rows.append(np.append(f.c, f.d - low + channel.band))
                slopes.append(-slope)
            else:
                rows.append(np.append(-f.c, channel.band - f.d + low))
                slopes.append(slope)
            channels.append(j)
        if not rows:
            return None, None, None
        return np.array(rows), np.array(slopes), np.array(channels, dtype=int)

    def switch_row(self, config: int, latched: int) -> tuple[FloatArray | None, float]:
        """(row, slope) of a one-comparator law's watched quantity in ``config`` (None when it cannot switch)."""
        if self.law is None:
            return None, 0.0
        rows, slopes, _ = self.law_rows(int(config == self.table[1]), int(bool(latched)))
        return (rows[0], cast(FloatArray, slopes)[0]) if rows is not None else (None, 0.0)    # both, or neither

    def config_of(self, bits: int, t: float) -> int:
        """The configuration of the channels' states ``bits`` (a SimulationError where the law has none)."""
        config = self.table[bits]
        return config if config >= 0 else cast(Comparators, self.law).config(bits, t)     # only theirs hold -1

    def reset_bits(self, xt: np.ndarray, bits: int, j: int) -> int:
        """At channel j's ramp reset: its state set by s_j against its band (inside the band it holds)."""
        channel = self.channels[j]
        f = channel.function
        s = float(f.c @ xt[:-1] + f.d - (f.ramp.low if f.ramp is not None else 0.0))
        if s < -channel.band:
            return bits & ~(1 << j)
        if s > channel.band:
            return bits | (1 << j)
        return bits

    def edges(self, t0: float, t1: float) -> list[EdgeEntry]:
        """(time, kind, channel) of every time-driven instant in (t0, t1), then (t1, 'end', -1). kind: a
        configuration index (schedule), 'reset' (channel's ramp reset), 'limit' (a latched channel's limit: a
        maximum duty ratio)."""
        law = self.problem.switching
        out: list[EdgeEntry] = []
        if isinstance(law, Schedule) and np.isfinite(law.period):
            T = law.period
            for m in range(int(np.floor(t0 / T)), int(np.ceil(t1 / T)) + 1):
                for start, config in zip(law.starts, law.configs):
                    t = m * T + start
                    if t0 < t < t1 and not (out and out[-1][1] == config):
                        out.append((t, config, -1))
        elif self.law is not None:
            out = sorted([(t, "reset", j) for j, c in enumerate(self.channels) for t in c.resets(t0, t1)]
                         + [(t, "limit", j) for j, c in enumerate(self.channels) for t in c.limits(t0, t1)])
        out.append((t1, "end", -1))
        return out

    # --- crossings ----------------------------------------------------------------------------------

    def cross(self, flow: Flow, watch: _Watch, xt: np.ndarray, tau_max: float,
              phase0: FloatArray | float) -> tuple[tuple[float, int] | tuple[None, None], FloatArray | None]:
        """First downward zero crossing of a watched quantity in (0, tau_max]: (tau, row) or (None, None),
        and x~ at tau_max when there is none. ``phase0``: each row's ramp phase at the segment's start (a scalar
        or one per row)."""
        size = np.abs(xt).max()
        g_scale = watch.row_scales * size
        if watch.timed:
            g_scale = g_scale + np.abs(watch.slopes) * self.scale
        def too_long() -> Exception:
            from ...errors import ResourceError
            return ResourceError(f"--method event: the stiffest mode's time constant is about "
                                 f"{4.0 * flow.delta:.3g} s, so crossing {tau_max:.3g} s takes "
                                 f"{tau_max / flow.delta if flow.delta > 0 else np.inf:.3g} substeps (at most "
                                 f"{MAX_SUBSTEPS:.0e}): a run or a switching period far longer than the circuit's "
                                 "fastest time constant (a tiny C, L or R, or a long --t-end); use --method lcp, or a "
                                 "shorter --t-end")
        # a search whose whole stretch is beyond reach is refused at once; one that may end at a crossing early (an
        # autonomous circuit's stretch is its run) once it has taken MAX_SUBSTEPS without meeting one
        if not (flow.delta > 0.0 and tau_max / flow.delta <= HOPELESS * MAX_SUBSTEPS):
            raise too_long()
        if flow.norm > MAX_SERIES_NORM:                      # a flow too fast for its series (Z^j / j! overflows)
            from ...errors import ResourceError
            raise ResourceError(f"--method event: the stiffest mode's time constant is about {4.0 * flow.delta:.3g} s, "
                                f"shorter than the exact flows represent in double precision (about "
                                f"{1.0 / MAX_SERIES_NORM:.1g} s: a tiny C, L or R); use --method lcp")
        offsets = self._dip_offsets(flow, watch, xt, g_scale)
        base = -_CROSS_RTOL * g_scale
        threshold = offsets + base
        full = int(np.floor(tau_max / flow.delta * (1.0 - 1e-12)))
        tau, state, allowed = 0.0, xt, MAX_SUBSTEPS
        while full > 0:
            if allowed <= 0:
                raise too_long()
            m = min(full, _POWERS)
            allowed -= m
            states = flow.steps(state, m)
            values = states @ watch.rows_T
            if watch.timed:
                values += (phase0 + (tau + flow.delta * np.arange(1, m + 1))[:, None]) * watch.slopes
            below = np.flatnonzero(values[:, 0] < threshold[0] if values.shape[1] == 1
                                   else (values < threshold).any(axis=1))
            if below.size:
                i = below[0]
                start = state if i == 0 else states[i - 1]
                return self._locate(flow, watch, start, tau + i * flow.delta, flow.delta, g_scale, phase0,
                                    offsets), None
            tau, state, full = tau + m * flow.delta, states[m - 1], full - m
            if offsets.any():            # a dip is looked for over the first _POWERS steps: past them, plain zero
                offsets, threshold = np.zeros_like(offsets), base
        rest = tau_max - tau
        if rest > 0.0:
            end = flow.propagate(state, rest)
            values = watch.rows @ end + (phase0 + tau_max) * watch.slopes
            if np.any(values < threshold):
                return self._locate(flow, watch, state, tau, rest, g_scale, phase0, offsets), None
            state = end
        return (None, None), state

    def _dip_offsets(self, flow: Flow, watch: _Watch, xt: FloatArray, g_scale: FloatArray) -> FloatArray:
        """Where each watched row crosses at the segment's start: 0, or for a pair's quantity that starts at or below
        zero inside the mode selection's zero band (which took it as zero and let its flow's derivatives decide) and
        dips further before it rises within the first _POWERS steps, that dip's bottom. Crossed at once, such a
        row is flipped, the selection keeps the mode, and the run repeats the instant (a Newton iterate of a no-load
        48-diode ladder: a held diode's current at -5.8e-8 A, falling at 21 A/s, rising again at 4e9 A/s^2 from
        -8.6e-8 A; the band 9.2e-8 A)."""
        k = self.problem.k
        band = _ZERO_RTOL * g_scale[:k]
        start = watch.rows[:k] @ xt
        offsets = np.zeros(watch.rows.shape[0])
        dipping = np.flatnonzero((start < _CROSS_RTOL * g_scale[:k]) & (start >= -band))
        if dipping.size:         # at zero or below it: those falling (a pair just flipped rises from zero)
            dipping = dipping[(start[dipping] < -_CROSS_RTOL * g_scale[dipping])
                              | (watch.rows[dipping, :-1] @ flow.field(xt) < 0.0)]
        if dipping.size:
            s = np.linspace(0.0, flow.delta, 65)                            # the first step finely, then steps
            coefficients = flow.series(xt) @ watch.rows[dipping].T          # (terms, rows): g(s) = sum_j s^j c_j
            g = np.vstack([np.vander(s, coefficients.shape[0], increasing=True) @ coefficients,
                           flow.steps(xt, _POWERS) @ watch.rows[dipping].T])
            low = g.min(axis=0)
            rises = (g[-1] > low + _CROSS_RTOL * g_scale[dipping]) & (low >= -2.0 * band[dipping])
            offsets[dipping] = np.where(rises, np.minimum(low, start[dipping]), 0.0)
        return offsets

    def _locate(self, flow: Flow, watch: _Watch, xt_a: FloatArray, tau_a: float, width: float, g_scale: FloatArray,
                phase0: FloatArray | float, offsets: FloatArray) -> tuple[float, int]:
        """The earliest crossing inside [tau_a, tau_a + width] (width <= delta): Brent's method on each
        watched quantity's Taylor polynomial, exact to rounding there; a row crosses its ``offsets`` entry (0, or
        where the segment started it below zero inside the zero band and it dips before it rises, the dip's
        bottom). Returns (tau, row)."""
        V = flow.series(xt_a)                                   # x~(s) = sum_j s^j V_j
        coefficients = V @ watch.rows.T                          # (terms, rows)
        coefficients[0] += (phase0 + tau_a) * watch.slopes - offsets
        coefficients[1] += watch.slopes
        xtol = max(self.options.event_tol * self.scale, 1e-300)
        best, best_row = None, None
        for r in range(watch.rows.shape[0]):
            poly = coefficients[::-1, r].tolist()                # highest power first

            def g(s: float, poly: list[float] = poly) -> float:
                value = 0.0
                for c in poly:   # Horner on Python floats: cheaper than any numpy call here
                    value = value * s + c
                return value

            threshold = _CROSS_RTOL * g_scale[r]
            if g(width) >= -threshold:
                continue
            # The bracket's left end may sit on a zero of g (the mode just began); move it to where g > 0.
            left: float | None
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
            return tau_a + width, int(np.argmin(watch.rows @ flow.propagate(xt_a, width) - offsets))
        return tau_a + best, cast(int, best_row)                  # found with best

    # --- runs ---------------------------------------------------------------------------------------

    def run(self, x0: npt.ArrayLike, record: bool = True, jacobian: bool = False, stop_config: int | None = None,
            stop_count: int = 0,
            timeline: list[TimelineEntry] | None = None) -> tuple[EventSolution, FloatArray | None, float | None]:
        """Run over t_span from x0. ``jacobian``: also d x_end / d x0. ``stop_config``/``stop_count``: stop
        at the ``stop_count``-th switching into ``stop_config`` (a return map; the run may then end before
        t_span[1], which must be long enough). ``timeline``: a list that receives, in time order, what a
        linearisation about the run needs (:meth:`timeline`). Returns (EventSolution, jacobian or None, stop time
        or None).

        The run goes from edge to edge of the time-driven law (:meth:`edges`); between two it flows in its mode and
        stops at each crossing of a watched row (:meth:`_to_crossing_or`, :meth:`_cross_into`), and at the edge
        enters what the edge says (:meth:`_at_edge`)."""
        start_clock = time.perf_counter()
        problem = self.problem
        t_end = problem.t_span[1]
        run = self._start(x0, record, jacobian, timeline)
        for edge_t, edge_kind, channel in self.edges(run.t, t_end):
            while not self._to_crossing_or(run, edge_t, stop_config, stop_count):
                pass
            if run.stop_time is not None or edge_kind == "end":
                break
            self._at_edge(run, edge_kind, channel)
        if stop_config is not None and run.stop_time is None:
            raise SimulationError(f"the return map found {run.crossings} of {stop_count} switchings into configuration "
                                  f"{stop_config} before t = {t_end:g} s; lengthen the problem's t_span")
        solution = EventSolution(problem, run.segments, zip(run.times, run.kinds, run.pairs, run.configs),
                                 run.xt[:-1].copy(), time.perf_counter() - start_clock, self.options, run.config,
                                 tuple(self.jumps))
        return solution, run.jac, run.stop_time

    def _start(self, x0: npt.ArrayLike, record: bool, jacobian: bool,
               timeline: list[TimelineEntry] | None) -> _Run:
        """The run at t_span[0]: the law's configuration and channel states there, its ramps' phases, the state
        after entering the configuration (a jump where it closes across a charged capacitance) and its mode."""
        problem, law = self.problem, self.law
        t = problem.t_span[0]
        xt = np.append(np.asarray(x0, dtype=float), 1.0)
        self.jumps = []
        config = problem.switching.initial_config(xt[:-1], t)
        # Each channel's ramp phase counts from its delay (ramp(t) = low + slope ((t - delay) mod T)), as in the
        # stepper; the last entry is the pairs' rows' (their slope is 0).
        phase_start = np.full(len(self.channels) + 1, t)
        for j, law_channel in enumerate(self.channels):
            ramp = law_channel.function.ramp
            if ramp is not None:
                phase_start[j] = t - float(ramp.phase(t))
        run = _Run(t=t, xt=xt, config=config, bits=initial_bits(law, xt[:-1], t) if law is not None else 0,
                   phase_start=phase_start, jac=np.eye(problem.n) if jacobian else None, record=record,
                   timeline=timeline)
        run.xt, jump = self.enter(config, run.xt, t, run.log)
        run.apply(jump)
        run.flow, run.xt = self.select(config, run.xt, t, 0)
        return run

    def _to_crossing_or(self, run: _Run, edge_t: float, stop_config: int | None, stop_count: int) -> bool:
        """Flow from ``run``'s state to the first crossing of a watched row before ``edge_t`` and take it, or to
        ``edge_t``: True when the run reached the edge or stopped (a return map's crossing), False after a
        crossing."""
        options = self.options
        run.looks += 1
        if run.looks % MEMORY_LOOK == 0:
            check_in_use(f"--method event at t = {run.t:.6g} s ({run.events:,} events, {len(run.segments):,} "
                         "segments)", "--method lcp (its memory is known before the run), or a shorter --t-end")
        flow, t, xt = cast(Flow, run.flow), run.t, run.xt
        watch = flow.watches.get((run.bits, run.latched))
        if watch is None:                        # the law's rows depend on its channels' states and latches
            watch = flow.watches[run.bits, run.latched] = _Watch(flow, *self.law_rows(run.bits, run.latched),
                                                                 m=len(self.channels))
        phase0 = t - run.phase_start[watch.channels] if watch.timed else 0.0
        (tau, which), xt_end = self.cross(flow, watch, xt, edge_t - t, phase0)
        if tau is not None and t + tau >= edge_t - options.event_tol * self.scale:
            tau = None                                   # a crossing on the edge itself: the edge handles it
            xt_end = flow.advance(xt, edge_t - t)
        if tau is not None:
            xt_end = flow.advance(xt, tau)
        xt_end = cast(FloatArray, xt_end)       # cross gives x~ at the edge when nothing crosses before it
        t_next = edge_t if tau is None else t + tau
        if run.record and t_next > t:
            run.segments.append(Segment(t, t_next, flow, xt, xt_end))
        if run.timeline is not None and t_next > t:
            run.timeline.append(FlowSpan(t, t_next, flow, xt))
        if run.jac is not None:
            run.jac[:] = flow.transition(t_next - t) @ run.jac
        if tau is None:
            run.t, run.xt = edge_t, xt_end
            return True
        run.same_time_events = run.same_time_events + 1 if tau == 0.0 else 0
        run.events += 1
        if run.same_time_events > 8 or run.events > options.max_events:
            raise SimulationError(f"{'repeated events at one instant' if run.same_time_events > 8 else 'too many events'}"
                                  f" near t = {t + tau:.9g} s (Zeno behaviour or a degenerate LCS); "
                                  f"max_events = {options.max_events}")
        run.t, run.xt = t + tau, xt_end
        return self._cross_into(run, watch, cast(int, which), stop_config, stop_count)

    def _cross_into(self, run: _Run, watch: _Watch, which: int, stop_config: int | None, stop_count: int) -> bool:
        """At a crossing of ``watch``'s row ``which``: a law's channel switches (its configuration entered) or a
        pair is held or freed; the mode after it, the saltation of the Jacobian, the log. True when a return map
        stops here."""
        n, t, xt = self.problem.n, run.t, run.xt
        flow = cast(Flow, run.flow)
        pair = int(watch.pairs[which])
        grad = watch.rows[which, :n]
        dgdt = watch.slopes[which]
        f_before = flow.field(xt)
        latched_before = run.latched
        if pair < 0:                                     # channel -1 - pair of the law switches
            j = -1 - pair
            run.bits ^= 1 << j
            run.latched |= int(self.channels[j].latch) << j
            run.config = self.config_of(run.bits, t)
            run.log(t, "switch", -1, run.config)
            if stop_config is not None and run.config == stop_config:
                run.crossings += 1
                if run.crossings >= stop_count:
                    if run.jac is not None:
                        denominator = grad @ f_before + dgdt
                        run.jac[:] = (np.eye(n) - np.outer(f_before, grad) / denominator) @ run.jac
                    run.stop_time = t
                    return True
            xt_in, jump = self.enter(run.config, xt, t, run.log)
            new, xt_new = self.select(run.config, xt_in, t, flow.held, f_before)
        else:
            jump = None
            new, xt_new = self.select(run.config, xt, t, flow.held ^ self._crossed(watch, xt, pair), f_before)
        if run.timeline is not None:
            run.timeline.append(Crossing(t, watch.rows[which].copy(), dgdt, f_before, new.field(xt_new),
                                         np.eye(n) if jump is None else jump, pair, flow, latched_before,
                                         xt, run.config, new, xt_new))
        if run.jac is not None:
            # Saltation through a jump x+ = Pi(x): S = DPi + (f+ - DPi f-) n^T / (n^T f- + dg/dt).
            f_after = new.field(xt_new)
            jump_jac = np.eye(n) if jump is None else jump
            denominator = grad @ f_before + dgdt
            S = jump_jac + np.outer(f_after - jump_jac @ f_before, grad) / denominator if denominator != 0.0 \
                else jump_jac
            if jump is None and pair >= 0 and bin(flow.held ^ new.held).count("1") > 1 and _off_manifold(new, S):
                S = self._saltations(run.config, flow, new, xt, pair)
            run.jac[:] = S @ run.jac
        self._log_pairs(run, flow, new)
        run.flow, run.xt = new, xt_new
        return False

    def _saltations(self, config: int, before: Flow, after: Flow, xt: FloatArray, pair: int) -> FloatArray:
        """The saltation through several pairs held or freed at one instant: one per pair, in the order they crossed
        (a pair a few nV past zero crossed that long before, at its rate), each from the flow with the pairs before
        it changed to the flow with it changed too, on its own watched row; a pair whose watched quantity is not
        falling through zero (rising again from a few nV below it, where a Newton iterate started it) has no instant
        to shift and changes the flow alone. Taken where the crossing row's saltation alone maps perturbations off the
        new flow's state manifold (:func:`_off_manifold`): a Dickson pump's two diodes, turning on together as their
        phase's edge rises, had left the Jacobian a multiplier at 1 (its capacitors' voltages summed where the diode
        ties them), and Newton stopped."""
        n = self.problem.n
        changed = before.held ^ after.held
        flipped = [i for i in range(self.problem.k) if (changed >> i) & 1]
        rows = before.watch_rows[flipped]
        rates, values = rows[:, :n] @ before.field(xt), rows @ xt
        # (earliest first: the time since each crossed, value / rate; the crossing row's 0; the others' first)
        since = np.where(rates < 0.0, values / np.where(rates < 0.0, rates, 1.0), np.inf)
        if pair in flipped:
            since[flipped.index(pair)] = 0.0
        order = [flipped[i] for i in np.argsort(-since, kind="stable")]
        S, held, flow_a = np.eye(n), before.held, before
        for i, j in enumerate(order):
            held ^= 1 << j
            flow_b = after if i == len(order) - 1 else self.flow(config, held)
            f_a, f_b = flow_a.field(xt), flow_b.field(xt)
            grad = flow_a.watch_rows[j, :n]
            denominator = grad @ f_a
            if denominator < 0.0 or (j == pair and denominator != 0.0):
                S = (np.eye(n) + np.outer(f_b - f_a, grad) / denominator) @ S
            flow_a = flow_b
        return S

    def _crossed(self, watch: _Watch, xt: FloatArray, pair: int) -> int:
        """The pairs (bit mask) a crossing of ``pair`` flips: it and every pair whose watched quantity is already
        below the crossing threshold at this instant. They all cross now; taken one per event, each would end a
        zero-length segment (a Newton iterate of a no-load 48-diode ladder starts a period with every other diode a
        few nV forward: 24 crossings at one instant, and a saltation through each)."""
        k = self.problem.k
        values = watch.rows[:k] @ xt
        # (a pair that dips inside the zero band counts too: taken with the others, the selection decides it)
        below = values < -_CROSS_RTOL * watch.row_scales[:k] * np.abs(xt).max()
        flipped = 1 << pair
        for i in np.flatnonzero(below):
            flipped |= 1 << int(i)
        return flipped

    def _at_edge(self, run: _Run, edge_kind: str | int, channel: int) -> None:
        """At a time-driven instant: a ramp's reset (the channel's phase restarts, its latch clears, its state
        re-read), a period's limit (the channel leaves below and latches) or a schedule's edge (the configuration
        it enters); then the configuration entered and its mode."""
        n, t = self.problem.n, run.t
        flow = cast(Flow, run.flow)
        if edge_kind == "reset":
            run.phase_start[channel] = t
            run.latched &= ~(1 << channel)
            new_bits = self.reset_bits(run.xt, run.bits, channel)
            if new_bits != run.bits:
                run.bits, run.config = new_bits, self.config_of(new_bits, t)
                run.log(t, "switch", -1, run.config)
        elif edge_kind == "limit":                       # the period's limit: leave below and latch
            run.latched |= 1 << channel
            if not (run.bits >> channel) & 1:
                run.bits |= 1 << channel
                run.config = self.config_of(run.bits, t)
                run.log(t, "switch", -1, run.config)
        else:
            run.config = cast(int, edge_kind)            # a schedule's edge: the configuration it enters
        xt_before = run.xt
        run.xt, jump = self.enter(run.config, run.xt, t, run.log)
        run.apply(jump)
        new, run.xt = self.select(run.config, run.xt, t, flow.held)
        if run.timeline is not None:
            run.timeline.append(Edge(t, edge_kind, run.config, np.eye(n) if jump is None else jump, xt_before, flow,
                                     new, run.xt))
        self._log_pairs(run, flow, new)
        run.flow = new

    def _log_pairs(self, run: _Run, before: Flow, after: Flow) -> None:
        """Log each pair held or freed between two modes at the run's instant."""
        for i in range(self.problem.k):
            was, now = (before.held >> i) & 1, (after.held >> i) & 1
            if was != now:
                run.log(run.t, "activate" if now else "release", i, run.config)

    def timeline(self, x0: npt.ArrayLike) -> list[TimelineEntry]:
        """The run from x0 over the span as typed records in time order (:mod:`.timeline`): a :class:`FlowSpan` per
        segment, a :class:`Crossing` per state event, an :class:`Edge` per time-driven instant: what a
        linearisation about the run reads (:mod:`converters.analysis.smallsignal`)."""
        entries: list[TimelineEntry] = []
        self.run(x0, record=False, timeline=entries)
        return entries

    def period_run(self, x0: FloatArray, jacobian: bool) -> tuple[EventSolution, FloatArray | None]:
        """(solution, Jacobian or None) of one span from x0, unrecorded (:class:`.core.EnginePeriodMap`)."""
        solution, jac, _ = self.run(x0, record=False, jacobian=jacobian)
        return solution, jac




# --- the engine's entry points (converters.methods.event.ENGINES) ----------------------------------------------

def supports(problem: LCSProblem, options: EventDriven) -> None:
    from ...errors import ParameterError
    from ...problems import Relay
    if getattr(problem, "inputs", None) is not None:
        raise ParameterError("the event-driven method's exact flows take constant inputs per configuration; "
                             "sinusoidal inputs (SIN sources): use --method lcp")
    if isinstance(problem.switching, Relay):
        raise ParameterError("the event-driven method follows a hysteresis or latched law (StateSwitching) "
                             "exactly; the implicit relay is a time-stepping scheme: use --method lcp")


def solve(problem: LCSProblem, options: EventDriven, x0: FloatArray) -> Trajectory:
    solution = _Machine(problem, options).run(x0)[0]
    return solution.trajectory(options.output_step or _time_scale(problem) / 1000.0)


class EventPeriodMap(EnginePeriodMap):
    """The exact map over an LCS's span, with its exact Jacobian; it keeps the events of its last run."""


def period_map(problem: LCSProblem, options: EventDriven) -> EventPeriodMap:
    return EventPeriodMap(_Machine(problem, options))
