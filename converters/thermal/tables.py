"""Loss tables: values on a grid read by multilinear interpolation and linear extrapolation.

PLECS reads the tables of a thermal description so (its manual: "PLECS uses a linear interpolation technique";
outside the table the same lines are extended), and so does pcsuite: a turn-on or turn-off energy over the blocked
voltage, the commutated current and the junction temperature, an on-state voltage over the current and the
temperature. An axis of one point is constant along it (a datasheet taken at one temperature). Switching energies
and on-state voltages extrapolated below zero are read as zero: neither is negative in a device.
"""
from __future__ import annotations

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

    def slices(self, *point: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """The values at points given on every axis but the last, at each point of the last (a temperature):
        shape (its size, the points'). :meth:`blend` then reads them at any value of the last axis, so a table
        read at fixed currents and voltages over many temperatures interpolates those once."""
        coords = np.broadcast_arrays(*(np.asarray(x, dtype=float) for x in point))
        shape = coords[0].shape if coords else ()
        lower, upper, weights = [], [], []
        for axis, x in zip(self.axes[:-1], coords):
            if axis.size == 1:                          # constant along it
                j, w = np.zeros(x.shape, dtype=int), np.zeros(x.shape)
            else:
                j = np.clip(np.searchsorted(axis, x) - 1, 0, axis.size - 2)
                w = (x - axis[j]) / (axis[j + 1] - axis[j])      # outside the axis: its end segment's line
            lower.append(j)
            upper.append(np.minimum(j + 1, axis.size - 1))
            weights.append(w)
        by_last = self.__dict__.get("_by_last")
        if by_last is None:                             # the last axis first: a corner's values are one take
            by_last = self.__dict__["_by_last"] = np.ascontiguousarray(np.moveaxis(self.values, -1, 0))
        total = np.zeros((self.axes[-1].size, *shape))
        for corner in range(2 ** len(lower)):           # multilinear: the 2^d corners of each point's cell
            index: list[Any] = [slice(None)]
            weight: Any = 1.0
            for d in range(len(lower)):
                up = (corner >> d) & 1
                index.append(upper[d] if up else lower[d])
                weight = weight * (weights[d] if up else 1.0 - weights[d])
            total += weight * by_last[tuple(index)]
        return total

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
