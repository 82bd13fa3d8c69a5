"""Plots for comparisons: overlays of the last periods and the residual, as PNG bytes."""
from __future__ import annotations

import io
import math

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def png(fig) -> bytes:
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=100, bbox_inches="tight")
    plt.close(fig)
    return buffer.getvalue()


def comparison_plot(c, periods: int = 3) -> bytes:
    """vout and every inductor current of both simulators over the last periods, and the primary current's
    difference; legends beside the panels, off the traces; the operating point in the title."""
    from converters.plotting import eng, time_unit
    T, span = c.lcp.period, "periods"
    if not math.isfinite(T):             # a circuit that switches itself: its cycles; a transient: the whole run
        cycle = c.metrics.get("cycle_lcp_s")
        T, span = (cycle, "cycles") if cycle else ((c.spice.t[-1] - c.spice.t[0]) / periods, "thirds of the run")
    t_end = c.spice.t[-1]
    start = t_end - periods * T
    primary = c.metrics["current_signal"]
    currents = [name for name in c.lcp.state_names if name.startswith("i")]
    t_l, t_s = c.lcp.t, c.spice.t
    sel_l, sel_s = t_l >= start, t_s >= start
    panels = ["vout", *currents]
    fig, axes = plt.subplots(len(panels) + 1, 1, figsize=(9, 2.0 * (len(panels) + 1) + 0.6), sharex=True)
    scale, unit = time_unit(periods * T)
    for ax, name in zip(axes, panels):
        spice = c.spice.signal(name) if name == "vout" else c.spice.state(name)
        lcp = c.lcp.signal(name) if name == "vout" else c.lcp.state(name)
        ax.plot((t_s[sel_s] - start) * scale, spice[sel_s], label="ngspice", lw=2, alpha=0.6)
        ax.plot((t_l[sel_l] - start) * scale, lcp[sel_l], "--", label="LCP", lw=1)
        ax.set_ylabel(f"{name} ({'V' if name.startswith('v') else 'A'})")
        ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)
    grid = np.linspace(start, t_end, periods * 2000 + 1)
    residual = np.interp(grid, t_s, c.spice.state(primary)) - np.interp(grid, t_l, c.lcp.state(primary))
    axes[-1].plot((grid - start) * scale, residual, lw=0.8)
    axes[-1].set_ylabel(f"{primary}: ngspice - LCP (A)")
    axes[-1].set_xlabel(f"time in the last {periods} {span} ({unit})")
    for ax in axes:
        ax.grid(alpha=0.3)
        ax.ticklabel_format(axis="y", useOffset=False)
    point = ", ".join(f"{k} = {eng(v)}" for k, v in c.params.items() if isinstance(v, (int, float)))
    fig.suptitle(f"{c.converter}: LCP time-stepper against ngspice\n{point}", fontsize=9)
    fig.tight_layout()
    return png(fig)


MODE_COLOURS = {"CCM-ON": "#4c72b0", "CCM-OFF": "#55a868", "DCM": "#c44e52", "GDCM-OFF": "#8172b2",
                "GDCM-ON": "#ccb974"}


def mode_timeline_plot(t_lcp, modes_lcp, t_spice, modes_spice, period: float, title: str, periods: int = 3) -> bytes:
    """Mode of each simulator over the last periods, as coloured bars."""
    end = min(t_lcp[-1], t_spice[-1])
    start = end - periods * period
    fig, ax = plt.subplots(figsize=(8, 1.8))
    for row, (t, labels, name) in enumerate(((t_lcp, modes_lcp, "LCP"), (t_spice, modes_spice, "ngspice"))):
        sel = np.flatnonzero(t >= start)
        times, labs = t[sel], np.asarray(labels)[sel].astype(str)
        # Each point carries the label of the step that ended there: a run spans from the point
        # before its first label to its last point.
        change = np.flatnonzero(labs[1:] != labs[:-1]) + 1
        bounds = np.concatenate([[0], change, [labs.size - 1]])
        for a, b in zip(bounds[:-1], bounds[1:]):
            left = times[max(a - 1, 0)]
            ax.barh(row, (times[b] - left) * 1e6 if b > a else 0.0, left=(left - start) * 1e6, height=0.6,
                    color=MODE_COLOURS.get(labs[a], "#999999"), linewidth=0)
    ax.set_yticks([0, 1], ["LCP", "ngspice"])
    ax.set_xlabel(f"time in the last {periods} periods (us)")
    handles = [plt.Rectangle((0, 0), 1, 1, color=c) for c in MODE_COLOURS.values()]
    ax.legend(handles, MODE_COLOURS.keys(), fontsize=7, ncol=5, loc="upper center", bbox_to_anchor=(0.5, -0.55))
    ax.set_title(f"{title}: conduction modes", fontsize=9)
    return png(fig)


def bode_figure(response, check=None, margins=None, fmt: str = "png", before=None) -> bytes:
    """Magnitude (dB) and phase (degrees) of a frequency response against frequency (Hz, log axis), the brute-force
    injection's points over it where given, a loop gain's crossover and margins, and ``before`` (the plant's loop
    gain Fm Gvd before a compensator) dashed; PNG or SVG bytes."""
    fig, (top, bottom) = plt.subplots(2, 1, sharex=True, figsize=(8, 6.5))
    f = response.frequency_hz
    top.semilogx(f, response.magnitude_db, color="C0",
                 label="loop gain with the compensator (exact)" if before is not None else "exact small-signal model")
    bottom.semilogx(f, response.phase_deg, color="C0")
    if before is not None:
        top.semilogx(before.frequency_hz, before.magnitude_db, color="C2", ls="--", label="plant Fm Gvd (exact)")
        bottom.semilogx(before.frequency_hz, before.phase_deg, color="C2", ls="--")
    if check is not None:
        f_check, values = check
        phase = np.degrees(np.angle(values))
        # the check's phases on the exact curve's branch (the exact curve is unwrapped along the frequencies)
        reference = np.interp(f_check, f, response.phase_deg)
        phase = phase + 360.0 * np.round((reference - phase) / 360.0)
        top.semilogx(f_check, 20 * np.log10(np.abs(values)), "o", color="C1", mfc="none",
                     label="sinusoid injected (brute force)")
        bottom.semilogx(f_check, phase, "o", color="C1", mfc="none")
    fs = 1.0 / response.period
    for ax in (top, bottom):
        ax.axvline(fs / 2, color="grey", lw=0.8, ls=":")
        ax.grid(True, which="both", lw=0.3)
        ax.ticklabel_format(axis="y", useOffset=False, style="plain")
    top.text(fs / 2, top.get_ylim()[1], " fs/2", va="top", fontsize=8, color="grey")
    if margins is not None and math.isfinite(margins.crossover_hz):
        top.axhline(0.0, color="grey", lw=0.8)
        bottom.axhline(-180.0, color="grey", lw=0.8)
        for ax in (top, bottom):
            ax.axvline(margins.crossover_hz, color="C3", lw=0.8, ls="--")
        bottom.set_title(f"crossover {margins.crossover_hz:.4g} Hz, phase margin {margins.phase_margin_deg:.3g} deg"
                         + (f", gain margin {margins.gain_margin_db:.3g} dB" if math.isfinite(margins.gain_margin_db)
                            else ""), fontsize=9)
    unit = f" ({response.output_unit}/{response.input_unit})" if response.output_unit and response.input_unit else ""
    what = "loop gain T" if response.kind == "loop gain" else f"{response.output} / {response.input}"
    top.set_ylabel(f"|{what}| (dB{', ' + unit.strip(' ()') if unit else ''})")
    bottom.set_ylabel("phase (deg)")
    bottom.set_xlabel("frequency (Hz)")
    top.legend(fontsize=8, loc="lower left")
    fig.tight_layout()
    buffer = io.BytesIO()
    fig.savefig(buffer, format=fmt, dpi=110)
    plt.close(fig)
    return buffer.getvalue()


def tornado_figure(found, title: str, fmt: str = "png") -> bytes:
    """A tornado chart: each parameter's normalised sensitivity (p/m) dm/dp of a steady-state mean as a horizontal
    bar, the largest on top, its value printed at the bar's end; PNG or SVG bytes."""
    rows = [r for r in found.rows if math.isfinite(r.normalised(found.metric_value))][::-1]
    values = np.array([r.normalised(found.metric_value) for r in rows])
    fig, ax = plt.subplots(figsize=(7.5, 1.2 + 0.38 * max(len(rows), 1)))
    ax.barh(range(len(rows)), values, color=np.where(values >= 0, "C0", "C3"))
    ax.set_yticks(range(len(rows)), [f"{r.parameter} = {r.value:.4g}{' ' + r.unit if r.unit else ''}" for r in rows])
    ax.axvline(0.0, color="black", lw=0.8)
    span = max(np.abs(values).max(initial=0.0), 1e-300)
    for i, v in enumerate(values):
        ax.text(v + (0.02 if v >= 0 else -0.02) * span, i, f"{v:.3g}", va="center", ha="left" if v >= 0 else "right",
                fontsize=8)
    ax.set_xlim(-1.25 * span if (values < 0).any() else 0.0, 1.25 * span if (values > 0).any() else 0.0)
    ax.ticklabel_format(axis="x", useOffset=False, style="plain")
    ax.set_xlabel(f"normalised sensitivity (p/m) dm/dp of mean({found.signal}) = {found.metric_value:.6g} "
                  f"{found.metric_unit} (% per %)")
    ax.set_title(f"{title}: exact steady-state sensitivities", fontsize=10)
    ax.grid(True, axis="x", lw=0.3)
    fig.tight_layout()
    buffer = io.BytesIO()
    fig.savefig(buffer, format=fmt, dpi=110)
    plt.close(fig)
    return buffer.getvalue()
