"""The boost under sliding-mode control: the LCP stepper against the same controller in ngspice.

Metrics over a window at the end of the run (after the load step when there is one): mean vout
against Vref, switching frequency (switch closings per second) against Vin (v - Vin)/(2 band L v) at
the measured mean v, the two frequencies against each other, and the recovery time after a load
step (from the step until |v - Vref| <= 1 % Vref holds to the end).
"""
from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from converters.models.sliding import predicted_frequency, recovery_time, resolve_smc, simulate_smc
from netlists import SpiceOptions, build_smc_netlist

from .spice import run_spice

WINDOW_S = 2e-3
RECOVERY_TOL = 0.01


@dataclass
class SMCComparison:
    params: dict
    lcp: object                 # converters.models.sliding.SMCRun
    spice: object               # SpiceResult
    netlist: object
    metrics: dict

    def spice_arrays(self):
        r, nl = self.spice, self.netlist
        t = r.time
        v = r.signal(nl.probes["vout"])
        on = r.signal(nl.probes["sw"]) < 0.5 * v
        return t, r.signal(nl.probes["iL"]), v, on


def _closings(t, on):
    return t[np.flatnonzero(on[1:] & ~on[:-1]) + 1]


def _frequency(times, t0):
    times = times[times >= t0]
    return float((times.size - 1) / (times[-1] - times[0])) if times.size >= 2 else 0.0


def _mean(t, v, t0):
    sel = t >= t0
    return float(np.trapezoid(v[sel], t[sel]) / (t[sel][-1] - t[sel][0]))


def compare_smc(params: dict | None = None, t_end: float = 30e-3, h=None,
                spice_options: SpiceOptions | None = None) -> SMCComparison:
    """Run the hysteresis controller in both simulators from the same start and measure them."""
    p = resolve_smc(params)
    if "t_step" in p and p["t_step"] >= t_end - WINDOW_S:
        from converters.errors import ParameterError
        raise ParameterError(f"t_step must be before t_end - {WINDOW_S:g} s = {t_end - WINDOW_S:g} s so the "
                             f"recovery can be measured; got {p['t_step']:g}")
    lcp = simulate_smc(p, scheme="hysteresis", h=h, t_end=t_end)
    netlist = build_smc_netlist(p, t_end, spice_options)
    spice = run_spice(netlist)
    out = SMCComparison(p, lcp, spice, netlist, {})
    t0 = t_end - WINDOW_S
    ts, iL_s, v_s, on_s = out.spice_arrays()
    m = {"window_s": [t0, t_end], "vref_V": p["Vref"],
         "vout_mean_lcp_V": lcp.mean_vout(t0), "vout_mean_spice_V": _mean(ts, v_s, t0)}
    m["vout_ref_rel_lcp"] = abs(m["vout_mean_lcp_V"] / p["Vref"] - 1.0)
    m["vout_ref_rel_spice"] = abs(m["vout_mean_spice_V"] / p["Vref"] - 1.0)
    m["frequency_lcp_Hz"] = lcp.switching_frequency(t0)
    m["frequency_spice_Hz"] = _frequency(_closings(ts, on_s), t0)
    m["frequency_predicted_lcp_Hz"] = predicted_frequency(p, m["vout_mean_lcp_V"])
    m["frequency_predicted_spice_Hz"] = predicted_frequency(p, m["vout_mean_spice_V"])
    m["frequency_rel_lcp"] = abs(m["frequency_lcp_Hz"] / m["frequency_predicted_lcp_Hz"] - 1.0)
    m["frequency_rel_spice"] = abs(m["frequency_spice_Hz"] / m["frequency_predicted_spice_Hz"] - 1.0)
    m["frequency_lcp_vs_spice"] = abs(m["frequency_lcp_Hz"] / m["frequency_spice_Hz"] - 1.0)
    m["min_iL_lcp_A"] = float(lcp.x[lcp.t >= 0.5 * t_end, 0].min())
    m["held_steps_lcp"] = int(lcp.active[:, 0].sum())   # DCM never occurs under this control
    if "t_step" in p:
        m["t_step_s"] = p["t_step"]
        m["recovery_lcp_s"] = lcp.recovery_time(p["t_step"], RECOVERY_TOL)
        m["recovery_spice_s"] = recovery_time(ts, v_s, p["Vref"], p["t_step"], RECOVERY_TOL)
        m["recovery_lcp_vs_spice"] = abs(m["recovery_lcp_s"] / m["recovery_spice_s"] - 1.0)
        m["dip_lcp_V"] = float(p["Vref"] - lcp.vout[lcp.t >= p["t_step"]].min())
        m["dip_spice_V"] = float(p["Vref"] - v_s[ts >= p["t_step"]].min())
    m["lcp_wall_s"] = lcp.wall_s
    m["spice_wall_s"] = spice.wall_s
    m["lcp_steps"] = int(lcp.t.size - 1)
    m["spice_steps"] = spice.accepted_steps
    out.metrics = m
    return out


def implicit_metrics(params: dict | None = None, t_end: float = 30e-3, h=None) -> dict:
    """The chattering-free relay: lambda against Vin/v, its spread, and vout against Vref."""
    start = time.perf_counter()
    run = simulate_smc(params, scheme="implicit", h=h, t_end=t_end)
    s = run.summary(WINDOW_S)
    lam = 1.0 - run.switch[run.window(t_end - WINDOW_S)]
    reversals = int(np.sum(np.abs(np.diff(np.sign(np.diff(lam)))) > 0)) if lam.size > 2 else 0
    return {"vout_mean_V": s["vout_mean"], "vout_ref_rel": abs(s["vout_mean"] / run.params["Vref"] - 1.0),
            "lambda_mean": s["lambda_mean"], "vin_over_v": s["vin_over_v"],
            "lambda_minus_vin_over_v": abs(s["lambda_mean"] - s["vin_over_v"]),
            "lambda_spread": s["lambda_spread"], "lambda_saturated_steps": int(np.sum((lam <= 0) | (lam >= 1))),
            "lambda_direction_changes": reversals, "h_s": run.h, "steps": int(run.t.size - 1),
            "wall_s": time.perf_counter() - start, "recovery_s": s.get("recovery_time_s")}, run


def smc_plot(c: SMCComparison) -> bytes:
    from .plots import png, plt
    ts, iL_s, v_s, on_s = c.spice_arrays()
    lcp = c.lcp
    fig, axes = plt.subplots(3, 1, figsize=(8, 7))
    ax = axes[0]
    ax.plot(lcp.t * 1e3, lcp.vout, lw=1, label="LCP")
    ax.plot(ts * 1e3, v_s, lw=1, ls="--", label="ngspice")
    ax.axhline(c.params["Vref"], color="k", lw=0.5)
    ax.set_ylabel("vout (V)")
    ax.set_xlabel("t (ms)")
    ax.legend(fontsize=8)
    ax.set_title("boost under sliding-mode control: whole run", fontsize=9)
    t1 = lcp.t[-1]
    t0 = t1 - 5.0 / predicted_frequency(c.params)
    for ax, (y_l, y_s, label) in zip(axes[1:], ((lcp.x[:, 0], iL_s, "iL (A)"), (lcp.vout, v_s, "vout (V)"))):
        sl, ss = lcp.t >= t0, ts >= t0
        ax.plot(lcp.t[sl] * 1e6, y_l[sl], lw=1, label="LCP")
        ax.plot(ts[ss] * 1e6, y_s[ss], lw=1, ls="--", label="ngspice")
        ax.set_ylabel(label)
        ax.set_xlabel("t (us), last 5 switching periods")
        ax.grid(alpha=0.3)
    fig.tight_layout()
    return png(fig)
