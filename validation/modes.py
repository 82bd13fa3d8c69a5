"""Per-period sequences of conduction modes (of any labelled trajectory: LCP, event, ngspice).

Modes themselves come from the model's rule (``Trajectory.modes``); for ngspice the devices'
conduction is read from their currents (:func:`validation.spice.spice_trajectory`).
"""
from __future__ import annotations

import numpy as np

#: Runs shorter than this fraction of T are edge glitches (gate ramps, diode recovery), not modes.
MIN_RUN_FRACTION = 1e-2


def period_sequences(t: np.ndarray, labels: np.ndarray, period: float, first: int, count: int) -> list[tuple]:
    """For periods first..first+count-1: the sequence of modes, runs shorter than 1 % of T dropped."""
    out = []
    for m in range(first, first + count):
        lo, hi = m * period, (m + 1) * period
        idx = np.flatnonzero((t >= lo - 1e-12 * period) & (t < hi - 1e-12 * period))
        if idx.size == 0:
            out.append(())
            continue
        times, labs = t[idx], labels[idx]
        change = np.flatnonzero(labs[1:] != labs[:-1]) + 1
        starts = np.concatenate([[0], change])
        ends = np.concatenate([change, [labs.size]])
        runs = []
        for s, e in zip(starts, ends):
            end_time = times[e] if e < labs.size else hi
            duration = end_time - times[s]
            if duration >= MIN_RUN_FRACTION * period:
                if not runs or runs[-1] != labs[s]:
                    runs.append(str(labs[s]))
        out.append(tuple(runs))
    return out
