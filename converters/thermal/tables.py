"""Loss tables: values on a grid read by multilinear interpolation and linear extrapolation.

PLECS reads the tables of a thermal description so (its manual: "PLECS uses a linear interpolation technique";
outside the table the same lines are extended), and so does pcsuite: a turn-on or turn-off energy over the blocked
voltage, the commutated current and the junction temperature, an on-state voltage over the current and the
temperature. An axis of one point is constant along it (a datasheet taken at one temperature). Switching energies
and on-state voltages extrapolated below zero are read as zero: neither is negative in a device.
"""
from __future__ import annotations

import bisect
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from ..errors import ParameterError


@dataclass(frozen=True, eq=False)
class Table:
    """``values[i0, i1, ...]`` at (axes[0][i0], axes[1][i1], ...); ``names`` and ``units`` name the axes in messages."""

    names: tuple[str, ...]
    units: tuple[str, ...]
    axes: tuple[npt.NDArray[np.float64], ...]
    values: npt.NDArray[np.float64]
    what: str = "table"

    def __post_init__(self) -> None:
        if len(self.axes) != len(self.names) or self.values.ndim != len(self.axes):
            raise ParameterError(f"{self.what}: {self.values.ndim} dimensions of values for {len(self.axes)} axes")
        for name, unit, axis, size in zip(self.names, self.units, self.axes, self.values.shape):
            check_axis(f"{self.what}: the {name} axis", axis, unit)
            if axis.size != size:
                raise ParameterError(f"{self.what}: the {name} axis has {axis.size} points and the values {size} "
                                     f"along it")
        if not np.all(np.isfinite(self.values)):
            raise ParameterError(f"{self.what}: the values must be finite numbers")

    def __call__(self, *point: float) -> float:
        """The value at ``point`` (one coordinate per axis, in the axes' units)."""
        return float(self.at(*point))

    def at(self, *point: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """The values at points given axis by axis as arrays (broadcast together)."""
        coords = np.broadcast_arrays(*(np.asarray(x, dtype=float) for x in point))
        return self.blend(self.slices(*coords[:-1]), coords[-1])

    @property
    def by_last(self) -> npt.NDArray[np.float64]:
        """The values with the last axis first (a corner's values over the temperatures are one take), kept."""
        by_last = self.__dict__.get("_by_last")
        if by_last is None:
            by_last = self.__dict__["_by_last"] = np.ascontiguousarray(np.moveaxis(self.values, -1, 0))
        return by_last

    def slices(self, *point: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """The values at points given on every axis but the last, at each point of the last (a temperature):
        shape (its size, the points'). :meth:`blend` then reads them at any value of the last axis, so a table
        read at fixed currents and voltages over many temperatures interpolates those once."""
        coords = [np.asarray(x, dtype=float) for x in point]
        if len(coords) > 1:
            coords = list(np.broadcast_arrays(*coords))
        shape = coords[0].shape if coords else ()
        cells = self.__dict__.get("_cells")
        if cells is None:          # per axis: its inner points (a cell index is one search) and its cells' widths
            cells = self.__dict__["_cells"] = [(axis[1:-1], np.diff(axis)) for axis in self.axes[:-1]]
        by_last = self.by_last
        total: Any = 0.0
        corners: list[tuple[Any, Any]] = [((slice(None),), 1.0)]
        for axis, (inner, widths), x in zip(self.axes[:-1], cells, coords):
            if axis.size == 1:                          # constant along it
                corners = [(index + (0,), weight) for index, weight in corners]
                continue
            j = np.searchsorted(inner, x)               # the cell; outside the axis its end cell's line
            w = (x - axis[j]) / widths[j]
            corners = [c for index, weight in corners
                       for c in ((index + (j,), weight * (1.0 - w)), (index + (j + 1,), weight * w))]
        for index, weight in corners:                   # multilinear: the 2^d corners of each point's cell
            total = total + weight * by_last[index]
        return np.broadcast_to(total, (self.axes[-1].size, *shape)) if np.ndim(total) < 1 + len(shape) else total

    def blend(self, slices: npt.NDArray[np.float64], last: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """:meth:`slices` read at ``last`` on the last axis (linear, extrapolated as the others; below zero: zero)."""
        axis, x = self.axes[-1], np.asarray(last, dtype=float)
        if axis.size == 1:
            return np.maximum(slices[0], 0.0)
        j = np.clip(np.searchsorted(axis, x) - 1, 0, axis.size - 2)
        w = (x - axis[j]) / (axis[j + 1] - axis[j])
        if j.ndim == 0:
            return np.maximum((1.0 - w) * slices[int(j)] + w * slices[int(j) + 1], 0.0)
        rows = np.arange(slices.shape[1]) if slices.ndim > 1 else ()
        return np.maximum((1.0 - w) * slices[j, rows] + w * slices[j + 1, rows], 0.0)


    def weighted_sum(self, slices: npt.NDArray[np.float64],
                     weights: npt.NDArray[np.float64]) -> Callable[[float], float]:
        """``last -> weights @ blend(slices, last)``, read as the temperature is iterated (:meth:`summed`)."""
        return self.summed(slices @ weights, bool(np.all(slices >= 0.0)),
                           lambda last: float(self.blend(slices, last) @ weights))

    def summed(self, sums: npt.NDArray[np.float64], nonnegative: bool,
               elsewhere: Callable[[float], float]) -> Callable[[float], float]:
        """``last -> weights @ blend(slices, last)`` from ``sums`` (the slices' weighted sums, one per point of the
        last axis): within the last axis' range and with no slice below zero (``nonnegative``: a blend of two
        values >= 0 is >= 0, so the clip at zero never acts) a blend of two sums instead of every point's;
        elsewhere ``elsewhere(last)``, the points' blend."""
        low, high, grid = float(self.axes[-1][0]), float(self.axes[-1][-1]), self.axes[-1].tolist()

        def at(last: float) -> float:
            if nonnegative and low <= last <= high:
                if len(grid) == 1:
                    return float(sums[0])
                j = min(max(bisect.bisect_left(grid, last) - 1, 0), len(grid) - 2)
                w = (last - grid[j]) / (grid[j + 1] - grid[j])
                return float((1.0 - w) * sums[j] + w * sums[j + 1])
            return elsewhere(last)
        return at


def check_axis(what: str, axis: npt.NDArray[np.float64], unit: str) -> None:
    """An axis: at least one finite point, strictly increasing."""
    if axis.ndim != 1 or axis.size == 0:
        raise ParameterError(f"{what} must hold at least one value ({unit})")
    if not np.all(np.isfinite(axis)):
        raise ParameterError(f"{what} must hold finite numbers ({unit}); got {axis.tolist()}")
    if axis.size > 1 and not np.all(np.diff(axis) > 0):
        raise ParameterError(f"{what} must increase strictly ({unit}); got {axis.tolist()}")


def energy_table(what: str, voltage: npt.ArrayLike, current: npt.ArrayLike, temperature: npt.ArrayLike,
                 energy: npt.ArrayLike) -> Table:
    """A switching energy (J) over the blocked voltage (V), the commutated current (A) and the junction temperature
    (degC): ``energy[temperature][voltage][current]``, the nesting of a PLECS description. Refused: a negative
    energy; a single voltage column other than 0 V (linear interpolation could not scale the energy with the
    blocked voltage: add the 0 V column, E = 0 there, as vendors' files have it)."""
    v, i, t = (np.asarray(a, dtype=float).ravel() for a in (voltage, current, temperature))
    e = np.asarray(energy, dtype=float)
    if e.shape != (t.size, v.size, i.size):
        raise ParameterError(f"{what}: the energies must be {t.size} x {v.size} x {i.size} (temperature x voltage x "
                             f"current, one per point of the axes); got the shape {e.shape}")
    if np.any(e < 0):
        raise ParameterError(f"{what}: a switching energy must be >= 0 J; got {float(e.min()):g} J")
    if v.size == 1 and v[0] != 0.0:
        raise ParameterError(f"{what}: one voltage column ({v[0]:g} V) cannot scale the energy with the blocked "
                             "voltage; add a 0 V column (0 J) or a second voltage")
    return Table(("voltage", "current", "temperature"), ("V", "A", "degC"), (v, i, t), np.transpose(e, (1, 2, 0)),
                 what)


def on_state_table(what: str, current: npt.ArrayLike, temperature: npt.ArrayLike,
                   voltage: npt.ArrayLike) -> Table:
    """An on-state voltage (V) over the current (A) and the junction temperature (degC): ``voltage[temperature]
    [current]``. Refused: a negative drop, or one that falls as the current rises (a datasheet's curve never does:
    a column in the wrong order)."""
    i, t = (np.asarray(a, dtype=float).ravel() for a in (current, temperature))
    v = np.asarray(voltage, dtype=float)
    if i.size and i[0] < 0:
        raise ParameterError(f"{what}: the current axis must start at >= 0 A (the reverse quadrant is not read); got "
                             f"{i[0]:g} A")
    if v.shape != (t.size, i.size):
        raise ParameterError(f"{what}: the on-state voltages must be {t.size} x {i.size} (temperature x current); got "
                             f"the shape {v.shape}")
    if np.any(v < 0):
        raise ParameterError(f"{what}: an on-state voltage must be >= 0 V at a current >= 0; got {float(v.min()):g} V")
    if i.size > 1 and np.any(np.diff(v, axis=1) < 0):
        raise ParameterError(f"{what}: the on-state voltage must not fall as the current rises (at each temperature)")
    return Table(("current", "temperature"), ("A", "degC"), (i, t), v.T.copy(), what)
