"""The affine flow of one mode of an LCS, exact: x~(t0 + tau) = expm(tau Z) x~ in augmented form x~ = [x; 1], its
Taylor polynomial (for locating crossings), its powers (for sampling), and what ends it (:class:`_Watch`)."""
from __future__ import annotations

import math
from functools import cached_property

import numpy as np
import numpy.typing as npt

from ...problems import LCSProblem

FloatArray = npt.NDArray[np.float64]


def _time_scale(problem: LCSProblem) -> float:
    period = problem.switching.period
    return period if np.isfinite(period) else problem.t_span[1] - problem.t_span[0]


_GL_X, _GL_W = np.polynomial.legendre.leggauss(8)
_TAYLOR_TERMS = 26     # (0.25)^26 / 26! < 1e-30: the series is exact to rounding on a sampling step
#: The largest |Z| (1/s) whose series terms Z^j / j! stay finite in double precision (j < _TAYLOR_TERMS): about
#: 1e13 / s, a time constant of 1e-13 s (1 mohm with 100 fF). Faster flows are refused by name, not run on NaN.
MAX_SERIES_NORM = math.exp((math.log(1e300) + math.lgamma(_TAYLOR_TERMS)) / (_TAYLOR_TERMS - 1))
_EXPONENTS = np.arange(_TAYLOR_TERMS)
_POWERS = 64           # sampling steps per batched product
#: A quadrature piece spans at most this over the flow's norm |Z| (row sums): 8-point Gauss-Legendre's error on
#: e^{sZ} over a piece L is about L^17 |Z|^16 (8!)^4 / (17 (16!)^3) ~ 1e-18 L at L |Z| = 2, rounding; a sampling
#: step (a quarter over the norm) would take eight times the nodes, and a snubber's 100 ps beside a 10 us period
#: ran a machine out of memory.
_PIECE_NORM = 2.0
_ZERO_RTOL = 1e-10     # a derivative counts as zero below this fraction of its own scale
_CROSS_RTOL = 1e-13    # a watched value counts as negative below -this fraction of its scale
#: Most substeps (each a quarter of the mode's fastest time constant at most) one crossing search may take: 1 to 3 s
#: of work (0.1 to 0.3 us each), which a steady state's Newton repeats a few times a period. A circuit far stiffer
#: than its run (C = 1e-15 F in a 5 ms run: 2e10 substeps) is refused, not hung; so is one whose fastest time
#: constant is 1e7 times shorter than its switching period (a 1 mohm, 1 nF probe on a 100 kHz buck: 8e7 substeps
#: a period, 12 s each, had run past 300 s).
MAX_SUBSTEPS = 10_000_000
#: A search whose stretch holds more than this many times MAX_SUBSTEPS is refused before it starts (a crossing
#: could end it early, but not that early).
HOPELESS = 100
_ON_SET_RTOL = 1e-9    # a held pair's constraint N^T (C x + F) counts as met up to this (relative)


def expm(A: FloatArray) -> FloatArray:
    """scipy's matrix exponential (imported on first use: a run that needs no event method never pays it)."""
    from scipy.linalg import expm as scipy_expm
    exponential: FloatArray = scipy_expm(A)           # scipy's functions are untyped
    return exponential


#: A flow of more states than this marches one sampling step per product until it has marched
#: :data:`MARCH_BEFORE_STACK` steps, then stacks S^0..S^64 and takes 64 steps per batched product (smaller flows stack
#: at once). Stacking costs 127 products of (n+1)-square matrices, 7 ms at n = 48: a flow entered once (a 48-diode
#: ladder enters some 150 modes a period, each for a few steps) never repays it (its 20 periods: 29 s stacking, 14 s
#: marching).
STACK_STATES = 12
MARCH_BEFORE_STACK = 4096


def _march(S: FloatArray, state: FloatArray, count: int) -> FloatArray:
    """S^1 state .. S^count state, shape (count, m): one product per step."""
    out = np.empty((count, state.size))
    for j in range(count):
        state = S @ state
        out[j] = state
    return out


def _power_stack(S: FloatArray, count: int) -> FloatArray:
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

    def __init__(self, config_index: int, held: int, Z: FloatArray, u_rows: FloatArray, y_rows: FloatArray,
                 constraint_rows: FloatArray, project: tuple[FloatArray, FloatArray] | None, delta: float) -> None:
        self.config, self.held = config_index, held
        self.Z, self.u_rows, self.y_rows = Z, u_rows, y_rows
        k = u_rows.shape[0]
        held_pairs = np.array([(held >> i) & 1 for i in range(k)], dtype=bool)
        self.watch_rows = np.where(held_pairs[:, None], u_rows, y_rows)
        self.held_flags = held_pairs
        self.constraint_rows, self.project = constraint_rows, project
        self.constraint_scales = np.abs(constraint_rows).sum(axis=1)
        #: _Watch per law state (bits, latched), built by the machine that owns the flow
        self.watches: dict[tuple[int, int], _Watch] = {}
        self.norm = norm = float(np.abs(Z).sum(axis=1).max())      # |Z|, 1/s
        self.delta = min(delta, 0.25 / norm) if norm > 0.0 else delta
        #: Sampling steps per quadrature piece (:data:`_PIECE_NORM`; at most a batched product's).
        self.piece_steps = max(1, min(_POWERS, int(_PIECE_NORM / (norm * self.delta)))) if norm > 0.0 else _POWERS
        self.piece = self.piece_steps * self.delta
        self.marched = 0                         # sampling steps marched without the stack (STACK_STATES)

    @property
    def n(self) -> int:
        size: int = self.Z.shape[0]                        # numpy types a shape's entries Any
        return size - 1

    def field(self, xt: FloatArray) -> FloatArray:
        """x' at x~."""
        return self.Z[:-1] @ xt

    @cached_property
    def unit_field(self) -> tuple[FloatArray, FloatArray, FloatArray]:
        """(Z / |Z|, |Z / |Z||, |watch rows|): the watched quantities' derivatives in the time unit 1 / |Z| (|Z| the
        largest row sum; their signs are the derivatives'), which keeps a 48-state ladder's 50th (|Z| ~ 1e7 / s)
        finite."""
        norm = float(np.abs(self.Z).sum(axis=1).max())
        Z = self.Z / norm if norm > 0.0 else self.Z
        return Z, np.abs(Z), np.abs(self.watch_rows)

    def lexicographic_ok(self, xt: FloatArray, small_positive: bool = False) -> bool:
        """Every watched quantity's first non-vanishing entry of (g, g', g'', ..., its (n+1)th derivative) along
        the flow is positive (or all vanish). An entry vanishes below :data:`_ZERO_RTOL` of its scale (|row|
        |Z|^j 1 max |x~|). ``small_positive``: a positive g counts as positive however small (the flow then
        crosses it as any other). The derivatives come one order at a time, Z^j x~ for the quantities still
        undecided: no (n+2) k (n+1) table per mode (1 MB each at k = 48)."""
        Z, absZ, abs_rows = self.unit_field
        rows, size = self.watch_rows, _ZERO_RTOL * np.abs(xt).max()
        undecided = np.arange(rows.shape[0])
        d, s = xt, np.ones(xt.size)
        for order in range(self.n + 2):
            values = rows[undecided] @ d
            decided = np.abs(values) > size * (abs_rows[undecided] @ s) + 1e-300
            if small_positive and order == 0:
                decided |= values > 0.0
            if (values[decided] < 0.0).any():
                return False
            undecided = undecided[~decided]
            if not undecided.size:
                return True
            d, s = Z @ d, absZ @ s
        return True

    @cached_property
    def taylor(self) -> FloatArray:
        """Z^j / j!, j = 0.._TAYLOR_TERMS - 1: x~(s) = sum_j s^j (Z^j / j!) x~ for s <= delta."""
        n1 = self.Z.shape[0]
        taylor = np.empty((_TAYLOR_TERMS, n1, n1))
        taylor[0] = np.eye(n1)
        for j in range(1, _TAYLOR_TERMS):
            taylor[j] = taylor[j - 1] @ self.Z / j
        return taylor

    @cached_property
    def step_map(self) -> FloatArray:
        """expm(delta Z): one sampling step."""
        return expm(self.delta * self.Z)

    @cached_property
    def powers(self) -> FloatArray:
        """expm(delta Z)^j, j = 0.._POWERS: the samples of a segment in one batched product."""
        return _power_stack(self.step_map, _POWERS)

    @cached_property
    def piece_map(self) -> FloatArray:
        """expm(piece Z): one quadrature piece."""
        return self.powers[self.piece_steps] if "powers" in self.__dict__ else expm(self.piece * self.Z)

    @cached_property
    def piece_powers(self) -> FloatArray:
        """expm(piece Z)^j, j = 0.._POWERS: the starts of a segment's quadrature pieces in one batched product."""
        return _power_stack(self.piece_map, _POWERS)

    def stacked(self, steps: int) -> bool:
        """Take the next ``steps`` sampling steps from the stacked powers (else march them: STACK_STATES)?"""
        if "powers" in self.__dict__ or self.Z.shape[0] <= STACK_STATES or self.marched >= MARCH_BEFORE_STACK:
            return True
        self.marched += steps
        return False

    def steps(self, xt: FloatArray, count: int) -> FloatArray:
        """x~ after 1..count sampling steps (count <= _POWERS), shape (count, n+1)."""
        return self.powers[1:count + 1] @ xt if self.stacked(count) else _march(self.step_map, xt, count)

    @cached_property
    def node_maps(self) -> FloatArray:
        """expm(s_k Z) at the Gauss-Legendre nodes s_k of [0, piece], shape (8, n+1, n+1)."""
        return np.stack([expm(s * self.Z) for s in 0.5 * (_GL_X + 1.0) * self.piece])

    def series(self, xt: FloatArray) -> FloatArray:
        """Z^j x~ / j!, j = 0.._TAYLOR_TERMS - 1, shape (terms, n+1): x~(s) = sum_j s^j (these)_j for s <= delta.
        From the stored :attr:`taylor` for small flows; one product per term for larger ones (the table is 26
        (n+1)^2: 0.5 MB a mode at n = 48, for a product saved)."""
        if self.Z.shape[0] <= STACK_STATES:
            return self.taylor @ xt
        out = np.empty((_TAYLOR_TERMS, xt.size))
        out[0] = xt
        for j in range(1, _TAYLOR_TERMS):
            out[j] = self.Z @ out[j - 1] / j
        return out

    def propagate(self, xt: FloatArray, s: float) -> FloatArray:
        """x~ after s in [0, delta]."""
        return s ** _EXPONENTS @ self.series(xt)

    def advance(self, xt: FloatArray, tau: float) -> FloatArray:
        """x~ after any tau >= 0 (a rounding-negative tau counts as 0): whole sampling steps by powers of
        expm(delta Z), the rest by the series."""
        tau = max(tau, 0.0)
        whole = int(np.floor(tau / self.delta * (1.0 - 1e-12)))
        q = whole
        while q > 0:
            m = min(q, _POWERS)
            xt = self.powers[m] @ xt if self.stacked(m) else _march(self.step_map, xt, m)[-1]
            q -= m
        return self.propagate(xt, max(tau - whole * self.delta, 0.0))

    def transition(self, tau: float) -> FloatArray:
        """The state-transition matrix over tau: d x(tau) / d x(0), shape (n, n)."""
        return expm(tau * self.Z)[:-1, :-1]

    def sample_states(self, xt: FloatArray, count: int, pieces: bool = False) -> FloatArray:
        """x~ at 0, delta, ..., count delta (``pieces``: 0, piece, ...): shape (count + 1, n+1)."""
        if not self.stacked(count * (self.piece_steps if pieces else 1)):
            return np.vstack([xt, _march(self.piece_map if pieces else self.step_map, xt, count)])
        powers = self.piece_powers if pieces else self.powers
        if count <= _POWERS:
            return powers[:count + 1] @ xt
        blocks, state = [], xt
        while count >= 0:
            m = min(count, _POWERS)
            block = powers[:m + 1] @ state
            blocks.append(block[:-1] if count > m else block)
            state, count = block[-1], count - m if count > m else -1
        return np.vstack(blocks)


class _Watch:
    """What ends a segment: rows g = rows x~ + slopes (phase0 + tau), with the pair each row belongs to (or
    -1 - j: channel j of the switching law) and, in ``channels``, the law's channel of each row (``m``, one past
    the last channel, for a pair: its phase is never read, its slope is 0)."""

    def __init__(self, flow: Flow, switch_rows: FloatArray | None = None, switch_slopes: FloatArray | None = None,
                 channels: npt.NDArray[np.int64] | None = None, m: int = 1) -> None:
        count = flow.watch_rows.shape[0]
        rows, slopes, pairs, owners = [flow.watch_rows], [np.zeros(count)], [np.arange(count)], [np.full(count, m)]
        if switch_rows is not None:
            rows.append(np.atleast_2d(switch_rows))
            slopes.append(np.asarray(switch_slopes, dtype=float))
            pairs.append(-1 - np.asarray(channels))
            owners.append(np.asarray(channels))
        self.rows = np.vstack(rows)
        self.rows_T = np.ascontiguousarray(self.rows.T)
        self.slopes = np.concatenate(slopes)
        self.timed = bool(np.any(self.slopes))
        self.pairs = np.concatenate(pairs)
        self.channels = np.concatenate(owners)
        self.row_scales = np.abs(self.rows).sum(axis=1)


