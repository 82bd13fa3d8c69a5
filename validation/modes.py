"""Conduction modes from waveforms, and their per-period sequences.

LCP trajectories carry their modes exactly (the complementarity state, see
``Converter.modes``). ngspice waveforms have none, so modes are read from the diode current and the
gate: a diode conducts when its current exceeds ``CURRENT_FRACTION`` of the peak diode current in the
window (0.1 %: far above the 1e-14 A saturation current, far below any real conduction current).
"""
from __future__ import annotations

import numpy as np

CURRENT_FRACTION = 1e-3
#: Runs shorter than this fraction of T are edge glitches (gate ramps, diode recovery), not modes.
MIN_RUN_FRACTION = 1e-2


def spice_modes(converter, spice, netlist, window_start: float) -> np.ndarray:
    """Mode label per ngspice time point (same labels as the LCP side)."""
    t = spice.time
    in_window = t >= window_start
    if converter.name == "prc":
        current = spice.signal(netlist.probes["iLf"])
        threshold = CURRENT_FRACTION * np.abs(current[in_window]).max()
        drive_positive = spice.vectors["drv"] > 0.0
        labels = np.where(drive_positive, "CCM-ON", "CCM-OFF").astype(object)
        labels[current <= threshold] = "DCM"
        return labels
    diode = spice.signal(netlist.probes["i_D"])
    threshold = CURRENT_FRACTION * np.abs(diode[in_window]).max()
    on = spice.vectors["gate"] >= 0.5
    conducting = diode > threshold
    labels = np.where(on, "CCM-ON", "CCM-OFF").astype(object)
    labels[on & conducting] = "GDCM-ON"
    labels[~on & ~conducting] = converter.off_held_label
    return labels


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
