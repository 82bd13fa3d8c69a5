"""A run's picture: its waveforms over the last periods and the mode timeline (``Trajectory.plot``).

Units on every axis (A for currents i*, V for voltages v*, time in the unit that suits the window), the
operating point in the title, no offset notation on the axes. matplotlib is imported on first use.
"""
from __future__ import annotations

from collections.abc import Iterable
from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt

if TYPE_CHECKING:
    from matplotlib.figure import Figure

PERIODS = 3
#: A run with a load or input step is drawn from this many periods before the step to its end.
STEP_PERIODS_BEFORE = 10


def time_unit(span: float) -> tuple[float, str]:
    for scale, unit in ((1e9, "ns"), (1e6, "us"), (1e3, "ms")):
        if span * scale < 5000:
            return scale, unit
    return 1.0, "s"


def eng(value: float) -> str:
    """A value as a SPICE user writes it: 22u, 250k, 0.25."""
    if value == 0 or 1e-3 <= abs(value) < 1e3:
        return f"{value:.4g}"
    for exponent, suffix in ((9, "G"), (6, "meg"), (3, "k"), (-3, "m"), (-6, "u"), (-9, "n"), (-12, "p")):
        if abs(value) >= 10.0 ** exponent:
            return f"{value / 10.0 ** exponent:.4g}{suffix}"
    return f"{value:.3g}"


# ``tr`` is a Trajectory: typed Any, as converters.trajectory imports this module (the layering keeps it below).
def held_pairs(tr: Any, rows: npt.NDArray[np.integer[Any]]) -> np.ndarray:
    """Per row, the names of the complementarity pairs that hold (u carries the pair), joined by '+'; 'none'."""
    active = np.asarray(tr.active[rows], dtype=bool)
    names = np.asarray(tr.pair_names, dtype=object)
    return np.array(["+".join(names[row]) or "none" for row in active])


def plot(tr: Any, periods: float | None = None, signals: Iterable[str] | None = None,
         title: str | None = None) -> Figure:
    """A matplotlib Figure: one panel per signal (default: the states and vout) over the last ``periods``
    switching periods (default 3; the whole run without a period; a run with a load or input step from
    STEP_PERIODS_BEFORE periods before it to the end, the step marked), then the mode timeline."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    step = ((tr.metadata or {}).get("params") or {}).get("t_step")
    stepped = periods is None and step is not None and tr.t[0] < step < tr.t[-1] and np.isfinite(tr.period)
    if periods is None:
        periods = PERIODS if np.isfinite(tr.period) else None
    t0, t1 = tr.window(periods) if periods else (tr.t[0], tr.t[-1])
    if stepped:                   # a load or input step: the periods before it, the response, the end
        t0 = max(tr.t[0], step - STEP_PERIODS_BEFORE * tr.period)
    rows = tr.rows_between(t0, t1)
    t = tr.t[rows]
    names = list(signals) if signals is not None else (
        list(tr.state_names) + (["vout"] if "vout" in tr.signal_names and "vout" not in tr.state_names else []))
    scale, unit = time_unit(t1 - t0)
    # the mode timeline: the model's conduction modes, or for a bare LCS the pairs that hold (u > y) at each step
    has_modes = tr.labels is not None or "mode" in tr.measured or tr.u is not None
    fig, axes = plt.subplots(len(names) + int(has_modes), 1, figsize=(8, 1.7 * len(names) + 1.6), sharex=True,
                             gridspec_kw={"height_ratios": [3] * len(names) + ([1] if has_modes else [])})
    axes = np.atleast_1d(axes)
    for ax, name in zip(axes, names):
        ax.plot((t - t0) * scale, tr.signal(name, rows), lw=1)
        if stepped:
            ax.axvline((step - t0) * scale, color="C3", lw=0.8, ls="--")
        quantity = "A" if name.startswith("i") else "V" if name.startswith("v") else ""
        ax.set_ylabel(f"{name} ({quantity})" if quantity else name)
        ax.ticklabel_format(axis="y", useOffset=False)
        ax.grid(alpha=0.3)
    if has_modes:
        ax = axes[-1]
        modes = (np.asarray(tr.modes(rows)).astype(str) if tr.labels is not None or "mode" in tr.measured
                 else held_pairs(tr, rows))
        labels = sorted(set(modes))
        colours = plt.cm.tab10(np.arange(len(labels)))
        step_modes = modes[1:]                                        # each step by its end point's mode
        change = np.flatnonzero(step_modes[1:] != step_modes[:-1]) + 1
        starts, ends = np.concatenate([[0], change]), np.concatenate([change, [step_modes.size]])
        for a, b in zip(starts, ends):                                # one band per run of a mode
            k = labels.index(step_modes[a])
            ax.axvspan((t[a] - t0) * scale, (t[b] - t0) * scale, color=colours[k], lw=0)
        for k, label in enumerate(labels):
            ax.plot([], [], color=colours[k], lw=6, label=label)
        ax.set_yticks([])
        ax.set_ylabel("mode" if tr.labels is not None or "mode" in tr.measured else "held pairs")
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, frameon=False)
    axes[-1].set_xlabel(f"time from {t0 * scale:.6g} {unit} ({unit})")
    if not has_modes:
        axes[-1].ticklabel_format(axis="x", useOffset=False)
    if title is None:
        meta = tr.metadata or {}
        params = meta.get("params") or {}
        point = ", ".join(f"{k} = {eng(v)}" for k, v in params.items() if isinstance(v, (int, float)))
        title = f"{meta.get('model') or 'LCS'} ({tr.method}){': ' + point if point else ''}"
    fig.suptitle(title, fontsize=9)
    fig.tight_layout()
    return fig


__all__ = ["plot"]
