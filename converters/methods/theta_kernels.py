"""Compiled hot loop of the theta stepper (numba, cached on disk): the per-step LCS update.

Everything here works on plain arrays; the problem/method objects stay in Python.

One complementarity pair (k = 1): each step is one of two affine maps of its start state x, chosen by the
sign of the step LCP's q, itself affine in x (:func:`branch_maps` builds them once per matrix set):

    q = CPhi x + q0                           (CPhi = C Phi, q0 = C Gamma + F)
    q >= 0: u = 0,       x+ = Phi_b[0] x + Gamma_b[0]    (the pair free: Phi, Gamma)
    q < 0:  u = -q / M,  x+ = Phi_b[1] x + Gamma_b[1]    (held: Phi - H CPhi / M, Gamma - H q0 / M)

and y = q + M u. The serial loop (:func:`run_steps`), the batched steady states
(:mod:`converters.sweeps.batch`) and the exact Jacobian (:func:`step_jacobian`: the held step's derivative is
Phi_b[1], the free step's Phi_b[0]) all read these maps; x+ no longer waits on the division
for u, so a step's dependency chain is one affine map.
"""
from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import numpy.typing as npt
from numba import njit, types
from numba.cpython.unsafe.tuple import tuple_setitem
from numba.extending import overload

from ..compiled import (EVENTS_FULL, FORBIDDEN, NEEDS_GENERAL_SOLVER, NO_SOLUTION,  # noqa: F401 (the callers')
                        OK, PIVOTS_PER_PAIR)
from ..lcp import state as LCP_STATE
from ..lcp.kernels import masks_by_size, solve_augmented, solve_small_lcp
from ..lcp.murty import sizes as pivoting_sizes
from ..lcp.murty import solve_warm
from ..lcp.result import max_abs_matrix

#: The kernels' arrays: float64; index arrays of any integer width (the ahead-of-time module's are int32, numba's
#: JIT compiles a version for each); the int64 arrays the callers allocate.
Floats = npt.NDArray[np.float64]
Indices = npt.NDArray[np.integer[Any]]
Ints = npt.NDArray[np.int64]
#: The one-pair loop's ``state``: n zeros (the state in registers) or None (in x).
Registers = tuple[float, ...] | None

# _size, _get and _put are numba's keys for the overloads after them: their bodies never run, and their values are
# those of the implementation numba picks for the argument types (Any here). numba checks an overload's parameters,
# annotations included, against those of the implementation it returns: the lambdas of _size_impl and _get_impl
# take no annotations, so neither do they; _put_impl and its two functions share one (Any: numba's types in the
# overload, the values in its implementations).


def _size(state: Registers, x: Floats) -> Any:
    """n: the length of the register tuple (a compile-time constant) or the width of x."""


# numba matches an overload's parameters, annotations included, against those of the lambdas it returns, which cannot
# carry annotations: these two stay bare
@overload(_size)
def _size_impl(state, x) -> Callable[..., int]:  # type: ignore[no-untyped-def]
    if isinstance(state, types.UniTuple):
        return lambda state, x: len(state)
    return lambda state, x: x.shape[1]


def _get(current: Registers, x: Floats, j: int, l: int) -> Any:
    """Component l of the state of row j: from the registers, or from x."""


@overload(_get)
def _get_impl(current, x, j, l) -> Callable[..., float]:  # type: ignore[no-untyped-def]
    if isinstance(current, types.UniTuple):
        return lambda current, x, j, l: current[l]
    return lambda current, x, j, l: x[j, l]


def _put(state: Registers, x: Floats, j: int, i: int, value: float) -> Any:
    """Component i of the state of row j set to value, in x and (when it is a tuple) in the returned state."""


@overload(_put)
def _put_impl(state: Any, x: Any, j: Any, i: Any, value: Any) -> Callable[..., Registers]:
    if isinstance(state, types.UniTuple):
        def into_registers(state: Any, x: Any, j: Any, i: Any, value: Any) -> tuple[float, ...]:
            x[j, i] = value
            return tuple_setitem(state, i, value)  # type: ignore[call-arg]  # numba's stub lists its typing context
        return into_registers

    def into_rows(state: Any, x: Any, j: Any, i: Any, value: Any) -> Any:
        x[j, i] = value
        return state
    return into_rows


@njit(cache=True)
def branch_maps(Phi: Floats, Gamma: Floats, H: Floats, C: Floats, F: Floats, M: Floats, Phi_b: Floats,
                Gamma_b: Floats, CPhi: Floats, q0: Floats) -> None:
    """The step as affine maps of its start state (module docstring), for every matrix set s, in place:
    CPhi = C Phi (k, n) and q0 = C Gamma + F (k): the step LCP's q = CPhi x + q0; Phi_b[s, 0] = Phi,
    Gamma_b[s, 0] = Gamma: every pair free; for one pair with M > 0, Phi_b[s, 1] = Phi - H CPhi / M and
    Gamma_b[s, 1] = Gamma - H q0 / M: the pair held (u = -q / M). Otherwise (k > 1, or M <= 0 where a
    held pair has no solution) Phi_b[s, 1], Gamma_b[s, 1] repeat the free branch and are never used."""
    sets, n, k = Phi.shape[0], Phi.shape[1], H.shape[2]
    for s in range(sets):
        for i in range(k):
            acc = F[s, i]
            for r in range(n):
                acc += C[s, i, r] * Gamma[s, r]
            q0[s, i] = acc
            for l in range(n):          # CPhi[s, i, l] = sum_r C[s, i, r] Phi[s, r, l], r in order: along rows of Phi
                CPhi[s, i, l] = 0.0
            for r in range(n):
                f = C[s, i, r]
                for l in range(n):
                    CPhi[s, i, l] += f * Phi[s, r, l]
        held = k == 1 and M[s, 0, 0] > 0.0
        for i in range(n):
            Gamma_b[s, 0, i] = Gamma[s, i]
            Gamma_b[s, 1, i] = Gamma[s, i] - H[s, i, 0] * q0[s, 0] / M[s, 0, 0] if held else Gamma[s, i]
            for l in range(n):
                Phi_b[s, 0, i, l] = Phi[s, i, l]
                Phi_b[s, 1, i, l] = Phi[s, i, l] - H[s, i, 0] * CPhi[s, 0, l] / M[s, 0, 0] if held else Phi[s, i, l]


@njit(cache=True)
def run_steps(which: Indices, Phi: Floats, Gamma: Floats, H: Floats, C: Floats, F: Floats, M: Floats, Phi_b: Floats,
              Gamma_b: Floats, CPhi: Floats, q0: Floats, x: Floats, u: Floats, y: Floats, start: int, inline: bool,
              period: int, state: Registers) -> tuple[int, int]:
    """Advance x, u, y from row ``start`` to the end; step j uses the matrix set ``which[j]``.

    Returns (status, j): OK when every step is done, NEEDS_GENERAL_SOLVER at the first step j
    whose LCP the compiled solvers do not solve (singular, or degenerate beyond them: the caller solves it
    and resumes at j + 1), NO_SOLUTION when a scalar LCP provably has none. ``inline``: k <= MAX_INLINE_K,
    solved by :func:`solve_small_lcp`; otherwise by principal pivoting (:func:`converters.lcp.murty.solve_warm`,
    at most PIVOTS_PER_PAIR k flips a step). Each step starts from a guess of its active set: the pairs that
    conducted at the same step a period earlier when ``period`` (steps in a period of a plan that repeats one;
    0: none) reaches back into the run, otherwise the last step's. A run near its periodic orbit repeats its
    pattern, where the last step's set is wrong at each switching: a 16-stage multiplier's graded steps
    (T/10, 42 a period, a diode switching at nearly every one) took 1.6 flips a step from the last step's set and
    0.003 from the last period's. One pair: :func:`run_scalar` (``state`` from
    :func:`converters.compiled.register_state`).
    """
    n = x.shape[1]
    k = u.shape[1]
    if k == 1:
        return run_scalar(which, Phi_b, Gamma_b, CPhi, q0, M, x, u, y, start, state)
    xf = np.empty(n)
    q = np.empty(k)
    z = np.empty(k)
    work = np.empty((k, k + 1))
    order = masks_by_size(k) if inline else np.empty(0, dtype=np.int64)
    active = np.empty(k, dtype=np.bool_)
    nonzero = np.empty(k, dtype=np.int64)
    sets = M.shape[0]
    m_bigs = np.empty(sets)                  # max|M| of each set, for the pivoting's check of its answer
    # Phi and C by columns: x_free and q as sums of columns, the inner loop along a row of PhiT (contiguous,
    # vectorised: a 32 x 32 product 160 ns against 480 as dot products of rows), each entry's terms added in the
    # same order as :func:`_lcp_step`'s dot products
    PhiT, CT = np.empty((sets, n, n)), np.empty((sets, n, k))
    for s in range(sets):
        m_bigs[s] = max_abs_matrix(M[s])
        for i in range(n):
            for l in range(n):
                PhiT[s, l, i] = Phi[s, i, l]
        for i in range(k):
            for l in range(n):
                CT[s, l, i] = C[s, i, l]
    floats, ints = pivoting_sizes(k)
    fw, iw, st = np.empty(floats), np.empty(ints, dtype=np.int64), np.empty(LCP_STATE.ST_SIZE, dtype=np.int64)
    for i in range(k):
        active[i] = u[start, i] > 0.0
    mask = 0
    for j in range(start, which.shape[0]):
        s = which[j]
        back = j + 1 - period
        if period > 0 and back >= 0:
            if inline:
                mask = 0
                for i in range(k):
                    if u[back, i] > 0.0:
                        mask |= 1 << i
            else:
                for i in range(k):
                    active[i] = u[back, i] > 0.0
        for i in range(n):
            xf[i] = Gamma[s, i]
        for l in range(n):
            f = x[j, l]
            for i in range(n):
                xf[i] += PhiT[s, l, i] * f
        for i in range(k):
            q[i] = F[s, i]
        for l in range(n):
            f = xf[l]
            for i in range(k):
                q[i] += CT[s, l, i] * f
        if inline:
            mask = solve_small_lcp(M[s], q, k, z, mask, order, work)
            if mask < 0:
                return NEEDS_GENERAL_SOLVER, j
        elif solve_warm(M[s], q, z, active, fw, iw, st, PIVOTS_PER_PAIR * k, m_bigs[s]) < 0:
            return NEEDS_GENERAL_SOLVER, j
        # few pairs conduct at once (a rectifier's, a multiplier's diodes): the products with z over its nonzero
        # entries only, the same sums in the same order
        m = 0
        for l in range(k):
            if z[l] != 0.0:
                nonzero[m] = l
                m += 1
        for i in range(n):
            acc = xf[i]
            for r in range(m):
                acc += H[s, i, nonzero[r]] * z[nonzero[r]]
            x[j + 1, i] = acc
        for i in range(k):
            acc = q[i]
            for r in range(m):
                acc += M[s, i, nonzero[r]] * z[nonzero[r]]
            y[j + 1, i] = acc
            u[j + 1, i] = z[i]
    return OK, which.shape[0]


@njit(cache=True)
def run_scalar(which: Indices, Phi_b: Floats, Gamma_b: Floats, CPhi: Floats, q0: Floats, M: Floats, x: Floats,
               u: Floats, y: Floats, start: int, state: Registers) -> tuple[int, int]:
    """k = 1: the step as the affine map of its branch (module docstring): q = CPhi x + q0; q >= 0 frees the
    pair (u = 0), q < 0 holds it (u = -q / M > 0) or, when M <= 0, has no solution (NO_SOLUTION at that step).
    ``state``: n zeros to carry the state in registers, or None to read it from x
    (:func:`converters.compiled.register_state`).
    The one loop of the one-pair stepper: the serial runs and the batched steady states call it."""
    n = _size(state, x)
    current = state
    for i in range(n):
        current = _put(current, x, start, i, x[start, i])
    for j in range(start, which.shape[0]):
        s = which[j]
        q = q0[s, 0]
        for l in range(n):
            q += CPhi[s, 0, l] * _get(current, x, j, l)
        m = M[s, 0, 0]
        if q >= 0.0:
            branch = 0
            z = 0.0
        elif m > 0.0:
            branch = 1
            z = -q / m
        else:
            return NO_SOLUTION, j
        following = state
        for i in range(n):
            acc = Gamma_b[s, branch, i]
            for l in range(n):
                acc += Phi_b[s, branch, i, l] * _get(current, x, j, l)
            following = _put(following, x, j + 1, i, acc)
        u[j + 1, 0] = z
        y[j + 1, 0] = q + m * z
        current = following
    return OK, which.shape[0]


@njit(cache=True)
def theta_matrices(A: Floats, B: Floats, C: Floats, D: Floats, E: Floats, F: Floats, dt: float, theta: float,
                   Phi: Floats, Gamma: Floats, H: Floats, M: Floats, W: Floats) -> bool:
    """One-step matrices of one configuration over dt (the formulas of :mod:`.discretize`), in place:
    W = (I - dt theta A)^-1, Phi = W (I + dt (1 - theta) A), Gamma = dt W E, H = dt W B, M = D + C H.
    Returns False when I - dt theta A is singular. Every plan's matrices come from here
    (:func:`set_matrices`). Gamma is W's product with dt E (not a column of the elimination): a set that
    differs from another only in E, F gets it from that one's W (:func:`set_matrices`), to the same bits."""
    n, k = A.shape[0], B.shape[1]
    cols = 2 * n + k
    a = np.empty((n, n + cols))
    for i in range(n):
        for j in range(n):
            a[i, j] = -dt * theta * A[i, j]
            a[i, n + j] = dt * (1.0 - theta) * A[i, j]            # I + dt (1 - theta) A
            a[i, 2 * n + k + j] = 0.0                              # I (for W)
        a[i, i] += 1.0
        a[i, n + i] += 1.0
        a[i, 2 * n + k + i] = 1.0
        for l in range(k):
            a[i, 2 * n + l] = dt * B[i, l]
    if not solve_augmented(a, n, cols):
        return False
    for i in range(n):
        for j in range(n):
            Phi[i, j] = a[i, n + j]
            W[i, j] = a[i, 2 * n + k + j]
        for l in range(k):
            H[i, l] = a[i, 2 * n + l]
    _gamma(W, E, dt, Gamma)
    for i in range(k):                 # M[i, l] = D[i, l] + sum_j C[i, j] H[j, l], j in order: along rows of H
        for l in range(k):
            M[i, l] = D[i, l]
        for j in range(n):
            f = C[i, j]
            for l in range(k):
                M[i, l] += f * H[j, l]
    return True


@njit(cache=True, inline="always")
def _gamma(W: Floats, E: Floats, dt: float, Gamma: Floats) -> None:
    """Gamma = W (dt E)."""
    n = W.shape[0]
    for i in range(n):
        acc = 0.0
        for l in range(n):
            acc += W[i, l] * (dt * E[l])
        Gamma[i] = acc


@njit(cache=True)
def set_matrices(A: Floats, B: Floats, C: Floats, D: Floats, E: Floats, F: Floats, dts: Floats, theta: float,
                 leader: Indices, Phi: Floats, Gamma: Floats, H: Floats, M: Floats, Phi_b: Floats, Gamma_b: Floats,
                 CPhi: Floats, q0: Floats) -> bool:
    """Every matrix set s (configuration matrices A[s]..F[s], step dts[s]) in place: :func:`theta_matrices` and
    :func:`branch_maps`. ``leader[s]`` <= s: the first set with the same A, B, C, D and step (s itself when
    none): a set that differs from its leader only in E, F (a source's levels and ramps, a sinusoidal input's
    value at each step) copies its Phi, H, M and takes Gamma from its W, without an elimination of its own.
    Returns False when some I - dt theta A is singular."""
    sets, n = A.shape[0], A.shape[1]
    slot = np.empty(sets, dtype=np.int64)
    leaders = 0
    for s in range(sets):
        if leader[s] == s:
            slot[s] = leaders
            leaders += 1
    W = np.empty((leaders, n, n))
    for s in range(sets):
        first = leader[s]
        if first == s:
            if not theta_matrices(A[s], B[s], C[s], D[s], E[s], F[s], dts[s], theta, Phi[s], Gamma[s], H[s], M[s],
                                  W[slot[s]]):
                return False
        else:
            Phi[s] = Phi[first]
            H[s] = H[first]
            M[s] = M[first]
            _gamma(W[slot[first]], E[s], dts[s], Gamma[s])
    branch_maps(Phi, Gamma, H, C, F, M, Phi_b, Gamma_b, CPhi, q0)
    return True


@njit(cache=True)
def _lcp_step(Phi: Floats, Gamma: Floats, H: Floats, C: Floats, F: Floats, M: Floats, x_from: Floats, x_to: Floats,
              u_to: Floats, y_to: Floats, mask: int, order: Ints, work: Floats, xf: Floats, q: Floats,
              z: Floats) -> int:
    """One theta step from x_from with given matrices: x_free, the step LCP, x_to, u_to, y_to.
    Returns the new active-set mask (or -1 when the inline solver finds no basis)."""
    n, k = H.shape[0], H.shape[1]
    for i in range(n):
        acc = Gamma[i]
        for l in range(n):
            acc += Phi[i, l] * x_from[l]
        xf[i] = acc
    for i in range(k):
        acc = F[i]
        for l in range(n):
            acc += C[i, l] * xf[l]
        q[i] = acc
    mask = solve_small_lcp(M, q, k, z, mask, order, work)
    if mask < 0:
        return -1
    for i in range(n):
        acc = xf[i]
        for l in range(k):
            acc += H[i, l] * z[l]
        x_to[i] = acc
    for i in range(k):
        acc = q[i]
        for l in range(k):
            acc += M[i, l] * z[l]
        y_to[i] = acc
        u_to[i] = z[i]
    return mask


@njit(cache=True, inline="always")
def _uniform_step(Phi: Floats, Gamma: Floats, H: Floats, C: Floats, F: Floats, M: Floats, s: int, x: Floats,
                  u: Floats, y: Floats, j: int, mask: int, order: Ints, work: Floats, xf: Floats, q: Floats,
                  z: Floats) -> int:
    """Step j -> j + 1 with the stacked uniform-step matrices of set s (no slicing: indices only); k = 1 in
    closed form. Returns the active-set mask, or -1 (no solution the inline solver finds).

    run_steps keeps its own loops (and run_scalar for k = 1): built on this function it measured
    57 ns/step against 12.7 on the half-wave rectifier (benchmarks/step_cost.py)."""
    n, k = x.shape[1], u.shape[1]
    for i in range(n):
        acc = Gamma[s, i]
        for l in range(n):
            acc += Phi[s, i, l] * x[j, l]
        xf[i] = acc
    if k == 1:
        qq = F[s, 0]
        for l in range(n):
            qq += C[s, 0, l] * xf[l]
        m = M[s, 0, 0]
        zz = 0.0
        if qq < 0.0:
            if m <= 0.0:
                return -1
            zz = -qq / m
        for i in range(n):
            x[j + 1, i] = xf[i] + H[s, i, 0] * zz
        u[j + 1, 0] = zz
        y[j + 1, 0] = qq + m * zz
        return 1 if zz > 0.0 else 0
    for i in range(k):
        acc = F[s, i]
        for l in range(n):
            acc += C[s, i, l] * xf[l]
        q[i] = acc
    mask = solve_small_lcp(M[s], q, k, z, mask, order, work)
    if mask < 0:
        return -1
    for i in range(n):
        acc = xf[i]
        for l in range(k):
            acc += H[s, i, l] * z[l]
        x[j + 1, i] = acc
    for i in range(k):
        acc = q[i]
        for l in range(k):
            acc += M[s, i, l] * z[l]
        y[j + 1, i] = acc
        u[j + 1, i] = z[i]
    return mask


@njit(cache=True, inline="always")
def _surface(c: Floats, d: float, x: Floats, phase: float, low: float, slope: float) -> float:
    """s = c . x + d - ramp at the given phase of the ramp period (no ramp: slope = low = 0)."""
    acc = d - low - slope * phase
    for i in range(c.shape[0]):
        acc += c[i] * x[i]
    return acc


@njit(cache=True, inline="always")
def _log_switch(ev_time: Floats, ev_config: Ints, ev_step: Ints, count: int, time: float, config: int, j: int) -> int:
    ev_time[count] = time
    ev_config[count] = config
    ev_step[count] = j
    return count + 1


@njit(cache=True)
def run_state_switched(A: Floats, B: Floats, C: Floats, D: Floats, E: Floats, F: Floats, Phi: Floats, Gamma: Floats,
                       H: Floats, M: Floats, t: Floats, h: float, theta: float, c: Floats, d: Floats, low: Floats,
                       slope: Floats, ramp_period: Floats, delay: Floats, band: Floats, latch: Ints, clocked: Ints,
                       limit: Floats, table: Ints, x: Floats, u: Floats, y: Floats, config: Ints, start: int,
                       state: Ints, ev_time: Floats, ev_config: Ints, ev_step: Ints) -> tuple[int, int]:
    """The theta stepper under state-driven laws (:class:`StateSwitching`, :class:`Comparators`): m channels,
    channel ch with s_ch = c[ch] . x + d[ch] - ramp_ch, its state bit ch of ``bits`` (0: below, 1: above), the
    configuration ``table[bits]``.

    Step j runs in the configuration in force; when its end point carries a channel's s through the level that
    ends that channel's state (+band for below, -band for above), the crossing is placed by linear interpolation
    of s over the step and the step is redone from there in the new configuration; the earliest of the channels'
    crossings goes first, and each channel switches at most once per step. A channel's ramp resets (at
    delay + m period) are grid points: there its latch opens and its state is set by s against the band (a switch
    event when it changes; not at the run's start, where the law's initial states hold); a ``clocked`` latch only
    leaves below inside a period (its clock alone sets it); at the phase ``limit`` T of each period (a grid point;
    limit < 0: none) a channel still below switches above and latches. ``state`` = [bits, latched bits, event
    count] carries the law's memory across calls. Stacks A..F and the uniform-step matrices Phi..M are indexed by
    configuration.

    Returns (status, j): OK, NEEDS_GENERAL_SOLVER (an LCP the inline solver cannot take), EVENTS_FULL (the event
    buffers are full at step j: grow them and resume at j) or FORBIDDEN (the channels' states ``state[0]`` have no
    configuration, ``table`` -1 there: from ``ev_time[state[2]]`` on).
    """
    n, k = x.shape[1], u.shape[1]
    m = c.shape[0]
    order = masks_by_size(k)
    work = np.empty((k, k + 1))
    xf, q, z = np.empty(n), np.empty(k), np.empty(k)
    Phi_s, Gamma_s, H_s, M_s, W_s = np.empty((n, n)), np.empty(n), np.empty((n, k)), np.empty((k, k)), np.empty((n, n))
    xs, xm, um, ym = np.empty(n), np.empty(n), np.empty(k), np.empty(k)
    phase0 = np.zeros(m)
    bits, latched, count = state[0], state[1], state[2]
    mask = 0
    for j in range(start, t.shape[0] - 1):
        t0, t1 = t[j], t[j + 1]
        dt = t1 - t0
        if count + 3 * m > ev_time.shape[0]:     # room for each channel's reset, limit and crossing in this step
            state[0], state[1], state[2] = bits, latched, count
            return EVENTS_FULL, j
        for ch in range(m):
            phase0[ch] = 0.0
            if ramp_period[ch] == np.inf:
                continue
            T = ramp_period[ch]
            since = t0 - delay[ch]
            phase = since - np.floor(since / T + 1e-9) * T
            bit = (bits >> ch) & 1
            if phase < 1e-9 * T:                 # a ramp reset (s jumps): the latch opens, s decides
                phase = 0.0
                if j > 0:                        # at the run's start the law's initial states hold
                    latched &= ~(1 << ch)
                    s_reset = _surface(c[ch], d[ch], x[j], 0.0, low[ch], slope[ch])
                    new = 0 if s_reset < -band[ch] else 1 if s_reset > band[ch] else bit
                    if new != bit:
                        bits ^= 1 << ch
                        bit = new
                        count = _log_switch(ev_time, ev_config, ev_step, count, t0, table[bits], j)
            if limit[ch] >= 0.0 and abs(phase - limit[ch] * T) < 1e-9 * T and j > 0:
                latched |= 1 << ch               # the period's limit: leave below and latch
                if bit == 0:
                    bits |= 1 << ch
                    count = _log_switch(ev_time, ev_config, ev_step, count, t0, table[bits], j)
            phase0[ch] = phase
        current = table[bits]
        if current < 0:                          # a combination of states with no configuration: where, unlogged
            ev_time[count] = t0
            state[0], state[1], state[2] = bits, latched, count
            return FORBIDDEN, j
        uniform = abs(dt - h) <= 1e-9 * h
        if uniform:
            mask = _uniform_step(Phi, Gamma, H, C, F, M, current, x, u, y, j, mask, order, work, xf, q, z)
        else:
            theta_matrices(A[current], B[current], C[current], D[current], E[current], F[current], dt, theta,
                           Phi_s, Gamma_s, H_s, M_s, W_s)
            mask = _lcp_step(Phi_s, Gamma_s, H_s, C[current], F[current], M_s, x[j], x[j + 1], u[j + 1], y[j + 1],
                             mask, order, work, xf, q, z)
        if mask < 0:
            state[0], state[1], state[2] = bits, latched, count
            return NEEDS_GENERAL_SOLVER, j
        for i in range(n):
            xs[i] = x[j, i]
        ts = t0                                  # the piece [ts, t1] from xs was just stepped into x[j + 1]
        switched = 0                             # the channels that switched in this step
        for _ in range(m):
            first, best = -1, 2.0
            for ch in range(m):
                bit = (bits >> ch) & 1
                if (switched >> ch) & 1 or (latched >> ch) & 1 or (clocked[ch] != 0 and bit == 1):
                    continue
                s0 = _surface(c[ch], d[ch], xs, phase0[ch] + (ts - t0), low[ch], slope[ch])
                s1 = _surface(c[ch], d[ch], x[j + 1], phase0[ch] + dt, low[ch], slope[ch])
                level = band[ch] if bit == 0 else -band[ch]
                if (s1 > level) if bit == 0 else (s1 < level):
                    frac = 0.0
                    if (s0 - level) * (s1 - level) < 0.0:
                        frac = (level - s0) / (s1 - s0)
                    frac = min(max(frac, 0.0), 1.0)
                    if frac < best:
                        first, best = ch, frac
            if first < 0:
                break
            piece = t1 - ts
            dt1 = best * piece
            if dt1 > 1e-12 * dt:
                theta_matrices(A[current], B[current], C[current], D[current], E[current], F[current], dt1,
                               theta, Phi_s, Gamma_s, H_s, M_s, W_s)
                mask = _lcp_step(Phi_s, Gamma_s, H_s, C[current], F[current], M_s, xs, xm, um, ym, mask,
                                 order, work, xf, q, z)
                if mask < 0:
                    state[0], state[1], state[2] = bits, latched, count
                    return NEEDS_GENERAL_SOLVER, j
                for i in range(n):
                    xs[i] = xm[i]
            ts += dt1
            bits ^= 1 << first
            switched |= 1 << first
            if latch[first] != 0:
                latched |= 1 << first
            current = table[bits]
            if current < 0:
                ev_time[count] = ts
                state[0], state[1], state[2] = bits, latched, count
                return FORBIDDEN, j
            count = _log_switch(ev_time, ev_config, ev_step, count, ts, current, j)
            if t1 - ts > 1e-12 * dt:
                theta_matrices(A[current], B[current], C[current], D[current], E[current], F[current], t1 - ts,
                               theta, Phi_s, Gamma_s, H_s, M_s, W_s)
                mask = _lcp_step(Phi_s, Gamma_s, H_s, C[current], F[current], M_s, xs, x[j + 1], u[j + 1],
                                 y[j + 1], mask, order, work, xf, q, z)
                if mask < 0:
                    state[0], state[1], state[2] = bits, latched, count
                    return NEEDS_GENERAL_SOLVER, j
            else:
                for i in range(n):
                    x[j + 1, i] = xs[i]
                break
        config[j + 1] = current
    state[0], state[1], state[2] = bits, latched, count
    return OK, t.shape[0] - 1


@njit(cache=True)
def run_relay(A: Floats, B: Floats, C: Floats, D: Floats, E: Floats, F: Floats, low: int, high: int, t: Floats,
              h: float, theta: float, c: Floats, d: float, x: Floats, u: Floats, y: Floats, blend: Floats,
              start: int) -> tuple[int, int]:
    """The theta stepper under the implicit relay (:class:`Relay`): configuration ``low`` blended
    towards ``high`` by z in [0, 1], with f_high - f_low frozen at the step start and -s(x_end) in
    N_[0,1](z). Each step is one LCP of size k + 2: the pairs of ``low`` and the relay written as
    0 <= z _|_ s + mu >= 0, 0 <= mu _|_ 1 - z >= 0 (Acary and Brogliato 2008).

    Returns (status, j) like :func:`run_steps`."""
    n, k = x.shape[1], u.shape[1]
    K = k + 2
    order = masks_by_size(K)
    work = np.empty((K, K + 1))
    Phi, Gamma, H, M, W = np.empty((n, n)), np.empty(n), np.empty((n, k)), np.empty((k, k)), np.empty((n, n))
    Mb, qb, zb = np.zeros((K, K)), np.empty(K), np.empty(K)
    xf, g, b = np.empty(n), np.empty(n), np.empty(n)
    dt_built = -1.0
    mask = 0
    for j in range(start, t.shape[0] - 1):
        dt = t[j + 1] - t[j]
        if dt != dt_built:
            theta_matrices(A[low], B[low], C[low], D[low], E[low], F[low], dt, theta, Phi, Gamma, H, M, W)
            dt_built = dt
        for i in range(n):
            acc = E[high, i] - E[low, i]
            for l in range(n):
                acc += (A[high, i, l] - A[low, i, l]) * x[j, l]
            b[i] = acc
        for i in range(n):
            acc = 0.0
            for l in range(n):
                acc += W[i, l] * b[l]
            g[i] = dt * acc                                   # dt W (f_high - f_low)(x_j)
            acc = Gamma[i]
            for l in range(n):
                acc += Phi[i, l] * x[j, l]
            xf[i] = acc
        for i in range(K):
            for l in range(K):
                Mb[i, l] = 0.0
        for i in range(k):
            acc = F[low, i]
            cg = 0.0
            for l in range(n):
                acc += C[low, i, l] * xf[l]
                cg += C[low, i, l] * g[l]
            qb[i] = acc
            Mb[i, k] = cg
            for l in range(k):
                Mb[i, l] = M[i, l]
        acc, cg = d, 0.0
        for l in range(n):
            acc += c[l] * xf[l]
            cg += c[l] * g[l]
        qb[k] = acc
        Mb[k, k] = cg
        Mb[k, k + 1] = 1.0
        for l in range(k):
            ch = 0.0
            for i in range(n):
                ch += c[i] * H[i, l]
            Mb[k, l] = ch
        qb[k + 1] = 1.0
        Mb[k + 1, k] = -1.0
        mask = solve_small_lcp(Mb, qb, K, zb, mask, order, work)
        if mask < 0:
            return NEEDS_GENERAL_SOLVER, j
        zr = min(max(zb[k], 0.0), 1.0)
        for i in range(n):
            acc = xf[i] + g[i] * zr
            for l in range(k):
                acc += H[i, l] * zb[l]
            x[j + 1, i] = acc
        for i in range(k):
            acc = qb[i] + Mb[i, k] * zr
            for l in range(k):
                acc += M[i, l] * zb[l]
            y[j + 1, i] = acc
            u[j + 1, i] = zb[i]
        blend[j + 1] = zr  # type: ignore[assignment]  # numpy's stubs read an element of zb as Any: zr is a float
    return OK, t.shape[0] - 1


@njit(cache=True)
def _left_multiply(left: Floats, right: Floats, work: Floats) -> None:
    """right <- left right (n x n; ``work`` n x n scratch; left may be right)."""
    n = right.shape[0]
    for r in range(n):
        for col in range(n):
            acc = 0.0
            for l in range(n):
                acc += left[r, l] * right[l, col]
            work[r, col] = acc
    for r in range(n):
        for col in range(n):
            right[r, col] = work[r, col]


@njit(cache=True)
def step_jacobian(which: Indices, u: Floats, Phi_b: Floats, H: Floats, CPhi: Floats, M: Floats,
                  jac: Floats) -> None:
    """d x_N / d x_0 of a run of the scheduled stepper, in place of ``jac`` (n x n, identity on entry).

    Each step is x_{j+1} = x_free + H z with x_free = Phi x_j + Gamma and, on the step's active set
    J = {i: z_i > 0}, z_J = -M_JJ^-1 (C_J x_free + F_J): so d x_{j+1} / d x_j = Phi - H_J M_JJ^-1 (C Phi)_J
    (exact wherever the active sets stay the same under a small change of x_0). One pair: the step's own
    affine map, Phi_b[s, 1] when held, Phi_b[s, 0] = Phi when free (:func:`branch_maps`); a run of L steps
    with the same map multiplies by its L-th power, formed by repeated squaring (a period of 1000 steps in
    four such runs takes some 40 matrix products instead of 1000)."""
    n, k = jac.shape[0], u.shape[1]
    new = np.empty((n, n))
    if k == 1:
        power = np.empty((n, n))
        steps = which.shape[0]
        j = 0
        while j < steps:
            s = which[j]
            held = u[j + 1, 0] > 0.0
            length = 1
            while j + length < steps and which[j + length] == s and (u[j + length + 1, 0] > 0.0) == held:
                length += 1
            j += length
            branch = 1 if held else 0
            for r in range(n):
                for col in range(n):
                    power[r, col] = Phi_b[s, branch, r, col]
            while True:
                if length & 1:                                   # jac <- power jac
                    _left_multiply(power, jac, new)
                length >>= 1
                if length == 0:
                    break
                _left_multiply(power, power, new)                # power <- power^2
        return
    S = np.empty((n, n))
    a = np.empty((k, k + n))
    act = np.empty(k, dtype=np.int64)
    for j in range(which.shape[0]):
        s = which[j]
        m = 0
        for i in range(k):
            if u[j + 1, i] > 0.0:
                act[m] = i
                m += 1
        for r in range(n):
            for col in range(n):
                S[r, col] = Phi_b[s, 0, r, col]
        if m > 0:
            for r in range(m):
                for col in range(m):
                    a[r, col] = M[s, act[r], act[col]]
                for col in range(n):
                    a[r, m + col] = CPhi[s, act[r], col]
            if solve_augmented(a, m, n):
                for r in range(n):
                    for col in range(n):
                        acc = 0.0
                        for l in range(m):
                            acc += H[s, r, act[l]] * a[l, m + col]
                        S[r, col] -= acc
        _left_multiply(S, jac, new)
