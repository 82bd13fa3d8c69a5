"""Compiled loops of the losses over a window of a stepped run (:class:`converters.thermal.losses.Window`).

A sweep reads each point's losses from a period of about a thousand steps: the conduction's Simpson nodes and the
on-state table at each of them are a few multiply-adds per row, which numpy spreads over some hundred array
operations per point (as long as the point's own run). Here they are one pass (and the signals at the rows one
more: :func:`converters.circuits.kernels.signal_rows`).
The numpy forms in :mod:`converters.thermal.losses` stay the reference (and the path of exact runs, and of
signals that follow a SIN or gate waveform); a test holds the two together to rounding.
"""
from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numba import njit

if TYPE_CHECKING:
    import numpy.typing as npt

    FloatArray = npt.NDArray[np.float64]
    IntArray = npt.NDArray[np.int64]
    BoolArray = npt.NDArray[np.bool_]


@njit(cache=True, inline="always")
def _cell(axis: FloatArray, size: int, x: float) -> tuple[int, int, float]:
    """(lower, upper, weight of the upper) of x's cell on an axis of ``size`` points: the end cells' lines
    outside it, and an axis of one point constant (:meth:`Table.slices`)."""
    if size == 1:
        return 0, 0, 0.0
    j = 0
    while j < size - 2 and axis[j + 1] < x:
        j += 1
    return j, j + 1, (x - axis[j]) / (axis[j + 1] - axis[j])


@njit(cache=True)
def energy_sums(voltage: FloatArray, current: FloatArray, axis_v: FloatArray, axis_i: FloatArray,
                by_last: FloatArray, sums: FloatArray) -> float:
    """``sums[k]`` = the sum over the points (voltage[p], current[p]) of a switching-energy table's bilinear
    value at its k-th temperature (``by_last[k, v, i]``); returns the least value read (>= 0: the clip at zero
    never acts)."""
    low = np.inf
    for k in range(by_last.shape[0]):
        sums[k] = 0.0
    for p in range(voltage.size):
        v0, v1, wv = _cell(axis_v, axis_v.size, voltage[p])
        i0, i1, wi = _cell(axis_i, axis_i.size, current[p])
        for k in range(by_last.shape[0]):
            e = ((1.0 - wv) * ((1.0 - wi) * by_last[k, v0, i0] + wi * by_last[k, v0, i1])
                 + wv * ((1.0 - wi) * by_last[k, v1, i0] + wi * by_last[k, v1, i1]))
            if e < low:
                low = e
            sums[k] += e
    return low


@njit(cache=True)
def conduction_sums(t: FloatArray, current: FloatArray, config: IntArray, current_starts: FloatArray,
                    config_starts: IntArray, edges: IntArray, diode: BoolArray, threshold: FloatArray,
                    closed: BoolArray, axes: FloatArray, sizes: IntArray, values: FloatArray,
                    temperatures: IntArray, sums: FloatArray, lowest: FloatArray) -> None:
    """Per device d (a column of ``current``): ``sums[d, k]`` = the mean over the window of |i| v_on(|i|) at the
    table's k-th temperature by Simpson's rule on each step while the device conducts at the step's start (a
    diode while its current exceeds ``threshold[d]``, a switch while ``closed[configuration, d]``); a step that
    starts at an edge read from the edge's own side (row e of ``current_starts`` for the step from row
    ``edges[e]``), as :meth:`Window.quadrature` and :meth:`Table.weighted_sum` compute it. ``lowest[d]``: the least
    table value read at any node (>= 0: the clip at zero never acts). Each step is cut where its current crosses
    a kink of |i| v_on(|i|) (zero, a table point either way), as :meth:`Window.quadrature` cuts it: Simpson is
    exact on each piece. The device's table: ``axes[d, :sizes[d]]`` (A) and ``values[d, :temperatures[d],
    :sizes[d]]`` (V)."""
    span = t[-1] - t[0]
    n = t.size
    cuts = np.empty(2 * axes.shape[1] + 1)
    for d in range(current.shape[1]):
        size, count = sizes[d], temperatures[d]
        axis, table = axes[d], values[d]
        for k in range(count):
            sums[d, k] = 0.0
        low = np.inf
        e = 0
        for r in range(n - 1):
            a, c = current[r, d], config[r]
            while e < edges.size and edges[e] < r:
                e += 1
            if e < edges.size and edges[e] == r:
                a, c = current_starts[e, d], config_starts[e]
            on = a > threshold[d] if diode[d] else closed[c, d]
            b = current[r + 1, d]
            step = (t[r + 1] - t[r]) / span / 6.0 if on else 0.0
            # the step cut where the current crosses a kink of |i| v_on(|i|): 0 and the table's points either way
            count_cuts = 0
            if a != b:
                for j in range(-1, size):
                    for sign in (1.0, -1.0):
                        if j < 0 and sign < 0:
                            continue
                        kink = 0.0 if j < 0 else sign * axis[j]
                        if j >= 0 and axis[j] <= 0.0:
                            continue
                        s = (kink - a) / (b - a)
                        if 0.0 < s < 1.0:
                            cuts[count_cuts] = s
                            count_cuts += 1
            cuts[:count_cuts].sort()
            start = 0.0
            for piece in range(count_cuts + 1):
                end = cuts[piece] if piece < count_cuts else 1.0
                for node in range(3):
                    f = start if node == 0 else (0.5 * (start + end) if node == 1 else end)
                    i = abs(a + f * (b - a))
                    lower, upper, w = _cell(axis, size, i)
                    weight = step * (end - start) * (4.0 if node == 1 else 1.0)
                    for k in range(count):
                        v = (1.0 - w) * table[k, lower] + w * table[k, upper]
                        if v < low:
                            low = v
                        sums[d, k] += weight * i * v
                start = end
        lowest[d] = low
