"""Plots for comparisons: overlays of the last periods and the residual, as PNG bytes."""
from __future__ import annotations

import io

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
    """vout and the primary current of both simulators over the last periods, and their difference."""
    T = 1.0 / c.params["f_sw"]
    t_end = c.spice.time[-1]
    start = t_end - periods * T
    primary = c.metrics["current_signal"]
    t_l, t_s = c.lcp.trajectory.t, c.spice.time
    sel_l, sel_s = t_l >= start, t_s >= start
    fig, axes = plt.subplots(3, 1, figsize=(8, 7), sharex=True)
    scale = 1e6
    axes[0].plot((t_s[sel_s] - start) * scale, c.spice.signal(c.netlist.probes["vout"])[sel_s], label="ngspice", lw=2,
                 alpha=0.6)
    axes[0].plot((t_l[sel_l] - start) * scale, c.lcp.vout()[sel_l], "--", label="LCP", lw=1)
    axes[0].set_ylabel("vout (V)")
    axes[1].plot((t_s[sel_s] - start) * scale, c.spice.signal(c.netlist.probes[primary])[sel_s], label="ngspice",
                 lw=2, alpha=0.6)
    axes[1].plot((t_l[sel_l] - start) * scale, c.lcp.trajectory.state(primary)[sel_l], "--", label="LCP", lw=1)
    axes[1].set_ylabel(f"{primary} (A)")
    grid = np.linspace(start, t_end, periods * 2000 + 1)
    residual = (np.interp(grid, t_s, c.spice.signal(c.netlist.probes[primary]))
                - np.interp(grid, t_l, c.lcp.trajectory.state(primary)))
    axes[2].plot((grid - start) * scale, residual, lw=0.8)
    axes[2].set_ylabel(f"{primary}: ngspice - LCP (A)")
    axes[2].set_xlabel(f"time in the last {periods} periods (us)")
    for ax in axes[:2]:
        ax.legend(fontsize=8, loc="upper right")
    for ax in axes:
        ax.grid(alpha=0.3)
    fig.suptitle(f"{c.converter}: LCP time-stepper against ngspice", fontsize=10)
    return png(fig)
