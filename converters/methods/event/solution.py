"""The event method's exact piecewise solution: its segments, events, integrals (Gauss-Legendre on each
exponential-polynomial piece) and samples on any grid."""
from __future__ import annotations

from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt

from ...errors import ParameterError
from ...limits import check_memory
from ...trajectory import Samples, Trajectory
from .core import PiecewiseSolution
from .flow import _EXPONENTS, _GL_W, _GL_X, FloatArray, Flow, _power_stack, expm

if TYPE_CHECKING:
    from ...problems import LCSProblem
    from . import EventDriven

#: One quadrature piece being gathered: its nodes' times and weights, x~ at the nodes, the flow, and the held flags
#: its segment reports (:meth:`EventSolution.held_flags`).
_Part = tuple[FloatArray, FloatArray, FloatArray, Flow, npt.NDArray[np.bool_]]

#: A held pair whose current and voltage stay below this fraction of its segment's largest pair variable at the
#: segment's start, middle and end carries nothing (:meth:`EventSolution.held_flags`).
IDLE = 1e-12

_BLOCK = 1024
#: Gauss-Legendre pieces a measure reads at a time (8 nodes each): a one-state circuit's block peaks at ~30 MB.
QUADRATURE_BLOCK = 1 << 14
#: Bytes of the flows' power stacks :meth:`EventSolution._sample_sorted` keeps at once (a 48-diode ladder's 1,200
#: modes at 38 MB each held 4 GB); past it they are dropped and rebuilt when a flow returns.
STACKS_HELD = 1 << 27


@dataclass
class Segment:
    t0: float
    t1: float
    flow: Flow
    xt0: np.ndarray     # augmented state [x; 1] at t0
    xt1: np.ndarray     # ... and at t1, before whatever happens there


class EventSolution(PiecewiseSolution):
    """The exact piecewise solution of an LCS: segments (t0, t1, flow, start state) and the events between them
    (:class:`.core.PiecewiseSolution`; kinds 'activate', 'release', 'impulse', 'switch'); ``end_config`` the
    configuration in force at the end."""

    problem: LCSProblem
    segments: list[Segment]

    def __init__(self, problem: LCSProblem, segments: list[Segment], events: Iterable[tuple[float, str, int, int]],
                 x_end: FloatArray, wall_s: float, options: EventDriven, end_config: int,
                 jumps: tuple[tuple[float, float], ...] = ()) -> None:
        super().__init__(problem, segments, events, x_end, wall_s, options)
        self.end_config = end_config
        #: ((time, energy lost), ...) of the state's jumps (:meth:`._Machine.enter`)
        self.jumps = jumps

    def held_flags(self, seg: Segment) -> npt.NDArray[np.bool_]:
        """The held flags a segment reports: its flow's, except for a pair at its corner throughout the segment
        (u = y = 0 at its start, middle and end: it carries nothing, whichever side the machine holds it on), which
        reads as not conducting (held where u is the device's voltage, free where u is its current). A two-switch
        forward's clamp diodes, free at zero current once the core has reset, had read "D3+D1+D2" where D2 alone
        conducts. Computed once per segment."""
        cache: dict[int, npt.NDArray[np.bool_]] = self.__dict__.setdefault("_held_flags", {})
        key = id(seg)
        if key not in cache:
            flags = seg.flow.held_flags
            currents = self.problem.pair_currents
            if currents is not None and flags.size:
                flow = seg.flow
                states = np.array([seg.xt0, flow.advance(seg.xt0, 0.5 * (seg.t1 - seg.t0)), seg.xt1])
                u, y = np.abs(states @ flow.u_rows.T), np.abs(states @ flow.y_rows.T)
                scale = max(float(u.max(initial=0.0)), float(y.max(initial=0.0)))
                idle = ((u <= IDLE * scale) & (y <= IDLE * scale)).all(axis=0)
                if idle.any():
                    flags = np.where(idle, ~np.asarray(currents[flow.config], dtype=bool), flags)
            cache[key] = flags
        return cache[key]

    def _segments_in(self, t0: float, t1: float) -> Iterator[tuple[Segment, float, float]]:
        for seg in self.segments:
            if seg.t1 > t0 and seg.t0 < t1:
                yield seg, max(seg.t0, t0), min(seg.t1, t1)

    def quadrature_pieces(self, t0: float, t1: float) -> int:
        """Gauss-Legendre pieces over [t0, t1] (8 nodes each): what :meth:`quadrature` would hold."""
        return sum(int((b - a) / seg.flow.piece) + 1 for seg, a, b in self._segments_in(t0, t1) if b > a)

    def quadrature_blocks(self, t0: float | None = None, t1: float | None = None,
                          pieces: int = QUADRATURE_BLOCK) -> Iterator[tuple[Samples, FloatArray]]:
        """Gauss-Legendre nodes over [t0, t1] (default: the whole run) as (Samples, weights), in blocks of about
        ``pieces`` pieces: a sum over the blocks is the integral, and no more than a block's nodes are held.

        Pieces follow the segments (no node straddles an event), each at most the flow's quadrature piece long
        (:data:`.flow._PIECE_NORM`), 8 nodes per piece."""
        t0 = self.problem.t_span[0] if t0 is None else t0
        t1 = self.problem.t_span[1] if t1 is None else t1
        parts: list[_Part] = []                    # (t, w, x~ nodes, flow) of the block being gathered
        held_pieces, half, any_part = 0, 0.5 * (_GL_X + 1.0), False
        for seg, a, b in self._segments_in(t0, t1):
            flow, length, flags = seg.flow, b - a, self.held_flags(seg)
            if length <= 0.0:
                continue
            # Whole pieces: their starts in batched products (a block's worth at a time), their nodes by the
            # node maps; then the rest of the segment by the series.
            full = int(np.floor(length / flow.piece * (1.0 - 1e-12)))
            xt = seg.xt0 if a == seg.t0 else flow.advance(seg.xt0, a - seg.t0)
            done = 0
            while done < full:
                m = min(full - done, max(pieces - held_pieces, 1))
                starts = flow.sample_states(xt, m, pieces=True)                # (m + 1, n+1)
                nodes = np.tensordot(starts[:m], flow.node_maps, axes=([1], [2])).reshape(-1, starts.shape[1])
                times = (a + flow.piece * (done + np.arange(m))[:, None] + flow.piece * half[None, :]).ravel()
                parts.append((times, np.tile(0.5 * flow.piece * _GL_W, m), nodes, flow, flags))
                xt, done, held_pieces = starts[m], done + m, held_pieces + m
                if held_pieces >= pieces:
                    yield self._block(parts)
                    parts, held_pieces, any_part = [], 0, True
            rest = length - full * flow.piece
            if rest > 1e-15 * length:
                offsets = rest * half
                parts.append((a + full * flow.piece + offsets, 0.5 * rest * _GL_W,
                              (offsets[:, None] ** _EXPONENTS[None, :]) @ flow.series(xt), flow, flags))
                held_pieces += 1
        if parts:
            yield self._block(parts)
        elif not any_part:
            raise ParameterError(f"quadrature interval [{t0:g}, {t1:g}] s lies outside the run")

    @staticmethod
    def _block(parts: list[_Part]) -> tuple[Samples, FloatArray]:
        xs = [nodes for _, _, nodes, _, _ in parts]
        samples = Samples(np.concatenate([t for t, _, _, _, _ in parts]), np.vstack([x[:, :-1] for x in xs]),
                          np.vstack([x @ f.u_rows.T for x, (_, _, _, f, _) in zip(xs, parts)]),
                          np.vstack([x @ f.y_rows.T for x, (_, _, _, f, _) in zip(xs, parts)]),
                          np.concatenate([np.full(x.shape[0], f.config) for x, (_, _, _, f, _) in zip(xs, parts)]),
                          held=np.vstack([np.broadcast_to(flags, (x.shape[0], flags.size))
                                          for x, (_, _, _, _, flags) in zip(xs, parts)]))
        return samples, np.concatenate([w for _, w, _, _, _ in parts])

    def quadrature(self, t0: float | None = None, t1: float | None = None) -> tuple[Samples, FloatArray]:
        """Every Gauss-Legendre node over [t0, t1] at once (:meth:`quadrature_blocks`), after a check that they fit
        the memory limit."""
        a = self.problem.t_span[0] if t0 is None else t0
        b = self.problem.t_span[1] if t1 is None else t1
        n, k = self.problem.n, self.problem.k
        check_memory(f"the event method's quadrature over [{a:.6g}, {b:.6g}] s",
                     8 * self.quadrature_pieces(a, b) * (8 * (n + 2 * k + 3) + k),
                     "--method lcp (its samples are its steps), or a shorter window")
        blocks = list(self.quadrature_blocks(a, b, pieces=2**62))
        return blocks[0]

    def sample(self, times: npt.ArrayLike) -> Samples:
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
            config[i], held[i] = seg.flow.config, self.held_flags(seg)
        return Samples(times, x, u, y, config, held=held)

    def trajectory(self, output_step: float) -> Trajectory:
        """Samples on a uniform grid of ``output_step`` plus every segment boundary, as a Trajectory."""
        bounds = np.array([s.t1 for s in self.segments])
        t = self.output_times(output_step)
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
        held[at_end] = np.array([self.held_flags(seg) for seg in segs]).reshape(-1, k)
        inside = ~at_end
        x[inside], u[inside], y[inside], config[inside], held[inside] = self._sample_sorted(t[inside], output_step)
        t, x, u, y, config, held = self._after_boundaries(t, x, u, y, config, held)
        problem = self.problem
        return Trajectory(t=t, x=x, u=u, y=y, config=config, held=held, state_names=problem.state_names,
                          pair_names=problem.pair_names,
                          config_names=tuple(c.name or f"config{i}" for i, c in enumerate(problem.configurations)),
                          event_columns=self.events_table(t), method="event", steps=len(self.segments),
                          wall_s=self.wall_s, rule="exact", exact=self, period=problem.switching.period, jumps=self.jumps,
                          metadata=dict(problem.metadata, event_tol=self.options.event_tol, label="event"))

    def _after_boundaries(self, t: FloatArray, x: FloatArray, u: FloatArray, y: FloatArray,
                          config: npt.NDArray[np.int64], held: npt.NDArray[np.bool_]
                          ) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, npt.NDArray[np.int64],
                                     npt.NDArray[np.bool_]]:
        """The samples with a second one at each boundary where the state jumps (a charge or flux redistributed) or
        the configuration or the held set changes (an output with a feedthrough, a capacitor's ESR carrying a switched
        current, a diode's current as it takes a capacitor's: each steps there): the sample on a boundary holds the
        value before it, and the next one on the grid had been the first after it (an inductor cutset's peak read
        1.4 % low, at a sample 0.001 T after its jump; a diode's peak as it turned on behind a 100 ns node, 0.54 %)."""
        n = self.problem.n
        rows = []
        for before, seg in zip(self.segments, self.segments[1:]):
            if seg.flow.config == before.flow.config and np.array_equal(seg.xt0, before.xt1) \
                    and np.array_equal(self.held_flags(seg), self.held_flags(before)):
                continue
            xt = seg.xt0
            rows.append((seg.t0, xt[:n], seg.flow.u_rows @ xt, seg.flow.y_rows @ xt, seg.flow.config,
                         self.held_flags(seg)))
        if not rows:
            return t, x, u, y, config, held
        at = np.searchsorted(t, np.array([r[0] for r in rows]), side="right")
        return (np.insert(t, at, [r[0] for r in rows]), np.insert(x, at, np.array([r[1] for r in rows]), axis=0),
                np.insert(u, at, np.array([r[2] for r in rows]), axis=0),
                np.insert(y, at, np.array([r[3] for r in rows]), axis=0),
                np.insert(config, at, [r[4] for r in rows]),
                np.insert(held, at, np.array([r[5] for r in rows]), axis=0))

    def _sample_sorted(self, t: FloatArray, step: float) -> tuple[FloatArray, FloatArray, FloatArray,
                                                                   npt.NDArray[np.int64], npt.NDArray[np.bool_]]:
        """Sorted times on a grid of spacing ``step`` plus segment ends: per segment, offsets q step + r share a
        few remainders r; x = S^q expm(r Z) x0 with the powers S^q of S = expm(step Z) stacked once per flow."""
        n, k = self.problem.n, self.problem.k
        x, u, y = np.empty((t.size, n)), np.empty((t.size, k)), np.empty((t.size, k))
        config = np.empty(t.size, dtype=np.int64)
        held = np.empty((t.size, k), dtype=bool)
        starts = np.array([seg.t0 for seg in self.segments])
        which = np.clip(np.searchsorted(starts, t, side="left") - 1, 0, len(self.segments) - 1)
        powers: dict[int, FloatArray] = {}
        longest: dict[int, float] = {}           # per flow, its longest segment: how many powers it needs
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
                if sum(p.nbytes for p in powers.values()) > STACKS_HELD:
                    powers.clear()
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
            held[lo:hi] = self.held_flags(seg)
        return x, u, y, config, held


