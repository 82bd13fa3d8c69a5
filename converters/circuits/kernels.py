"""A compiled loop of the netlist models' signals (:meth:`converters.models.netlist.NetlistModel.signal_table`):
a run's rows read through each configuration's signal maps in one pass, where numpy takes a pass per configuration
and map (the losses of a sweep's points read a period's rows at each)."""
from __future__ import annotations

from typing import TYPE_CHECKING

from numba import njit

if TYPE_CHECKING:
    import numpy as np
    import numpy.typing as npt

    FloatArray = npt.NDArray[np.float64]
    IntArray = npt.NDArray[np.int64]


@njit(cache=True)
def signal_rows(x: FloatArray, u: FloatArray, config: IntArray, Sx: FloatArray, Su: FloatArray, s0: FloatArray,
                out: FloatArray) -> None:
    """``out[r, k]`` = signal k at row r: ``Sx[c, k] . x[r] + Su[c, k] . u[r] + s0[c, k]``, c the row's
    configuration (the signal maps of :meth:`Compiled.signal_stack`, without SIN or gate terms)."""
    for r in range(x.shape[0]):
        c = config[r]
        for k in range(s0.shape[1]):
            value = s0[c, k]
            for j in range(x.shape[1]):
                value += Sx[c, k, j] * x[r, j]
            for j in range(u.shape[1]):
                value += Su[c, k, j] * u[r, j]
            out[r, k] = value
