"""Conduction modes of a labelled trajectory: mode intervals and the detected mode class.

Mode labels come from the model's rule (``Trajectory.modes``): a pair held in the switch-off
configuration is DCM (Cuk: GDCM-OFF), in the switch-on one GDCM-ON. The class of a period is 'CCM'
when no held label occurs, else the held labels joined by '+'.
"""
from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from ..trajectory import Trajectory

#: Mode labels in which a held pair constrains the state.
HELD = ("DCM", "GDCM-OFF", "GDCM-ON")


def mode_intervals(t: np.ndarray, labels: np.ndarray, t0: float, t1: float, period: float,
                   min_run_fraction: float = 0.0) -> list[dict]:
    """Runs of equal labels within [t0, t1]: mode, start and end (s, from t0) and fraction of T.

    ``labels[j]`` holds on [t[j], t[j+1]); ``labels`` may have one entry fewer than ``t`` (for LCP
    trajectories pass ``labels[1:]``: each point carries the label of the step that ends there). Runs shorter than ``min_run_fraction`` T are
    merged into their neighbours (edge glitches of a continuous simulator).
    """
    t, labels = np.asarray(t, dtype=float), np.asarray(labels).astype(str)
    ends = np.append(t[1:], t[-1]) if labels.size == t.size else t[1:]
    starts = t[:labels.size]
    keep = (ends > t0) & (starts < t1)
    starts, ends, labels = np.clip(starts[keep], t0, t1), np.clip(ends[keep], t0, t1), labels[keep]
    if labels.size == 0:
        return []
    first = np.concatenate([[0], np.flatnonzero(labels[1:] != labels[:-1]) + 1])
    last = np.append(first[1:] - 1, labels.size - 1)
    runs = [[labels[a], starts[a], ends[b]] for a, b in zip(first, last)]
    if min_run_fraction > 0.0:
        merged: list[list] = []
        for lab, a, b in runs:
            if b - a < min_run_fraction * period and merged:
                merged[-1][2] = b
            elif merged and merged[-1][0] == lab:
                merged[-1][2] = b
            else:
                merged.append([lab, a, b])
        if len(merged) > 1 and merged[0][2] - merged[0][1] < min_run_fraction * period:
            merged[1][1] = merged[0][1]  # a glitch at the window start belongs to the run after it
            merged.pop(0)
        runs = merged
    return [{"mode": str(lab), "start": float(a - t0), "end": float(b - t0), "fraction": float((b - a) / period)}
            for lab, a, b in runs if b > a]


def mode_class(intervals: list[dict]) -> str:
    """'CCM' when no held mode occurs in the intervals, else the held modes present joined by '+'."""
    held = sorted({iv["mode"] for iv in intervals if iv["mode"] in HELD}, key=HELD.index)
    return "+".join(held) if held else "CCM"


def held_fraction(intervals: list[dict], periods: float) -> float:
    return float(sum(iv["fraction"] for iv in intervals if iv["mode"] in HELD) / periods)


def mode_sequence(intervals: list[dict]) -> str:
    """The modes the intervals pass through, in order and joined by ' > ' (one period's: a run that wraps around
    the period's end is one)."""
    labels = [iv["mode"] for iv in intervals]
    sequence = [label for i, label in enumerate(labels) if i == 0 or label != labels[i - 1]]
    if len(sequence) > 1 and sequence[0] == sequence[-1]:
        sequence.pop()
    return " > ".join(sequence)


def period_modes(model: object, intervals: list[dict]) -> tuple[str, float]:
    """What a sweep stores of one period's modes: (mode, held fraction of T). A built-in converter's mode class
    ('CCM', 'DCM', ...; :func:`mode_class`) and the fraction its pairs are held; a netlist's modes name its closed
    switches and conducting diodes, not a class, so its mode is their sequence over the period ('S1 > D1 > off')
    and the fraction is that of 'off', where nothing conducts (a buck's DCM). A netlist's every mode had read
    'CCM', held 0, in deep DCM: none of its labels is a class's."""
    if getattr(model, "off_held_label", None) == "off":
        return mode_sequence(intervals), float(sum(iv["fraction"] for iv in intervals if iv["mode"] == "off"))
    return mode_class(intervals), held_fraction(intervals, 1.0)


def orbit_intervals(orbit: Trajectory) -> list[dict]:
    """Mode intervals over one period of a labelled orbit Trajectory (each point carries the label of the
    step that ends there)."""
    t = orbit.t
    return mode_intervals(t, np.asarray(orbit.modes())[1:], t[0], t[-1], t[-1] - t[0])
