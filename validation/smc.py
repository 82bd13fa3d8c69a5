"""The boost under sliding-mode control: the LCP stepper against the same controller in ngspice.

Metrics over a window at the end of the run (after the load step when there is one): mean vout
against Vref, switching frequency (switch closings per second) against Vin (v - Vin)/(2 band L v) at
the measured mean v, the two frequencies against each other, and the recovery time after a load
step (from the step until |v - Vref| <= 1 % Vref holds to the end). Thresholds: data/defaults.toml.
"""
from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from converters.errors import ParameterError
from converters.models import get_model
from converters.models.sliding import predicted_frequency, recovery_time, switching_frequency
from converters.run import run_converter
from converters.validate import parse_value
from netlists import SpiceOptions, build_smc_netlist

from .defaults import passes
from .spice import run_spice, spice_trajectory

WINDOW_S = 2e-3
RECOVERY_TOL = 0.01


@dataclass
class SMCComparison:
    params: dict
    lcp: object                 # Trajectory (LCP stepper)
    spice: object               # Trajectory (ngspice)
    netlist: object
    metrics: dict


def compare_smc(params: dict | None = None, t_end: float = 30e-3, h=None,
                spice_options: SpiceOptions | None = None) -> SMCComparison:
    """Run the hysteresis controller in both simulators from the same start and measure them."""
    model = get_model("boost", "smc")
    p = model.resolve(params)
    t_end = parse_value("t_end", t_end, "s")
    if not 2 * WINDOW_S <= t_end:
        raise ParameterError(f"t_end must be at least {2 * WINDOW_S:g} s (twice the {WINDOW_S:g} s window measured at "
                             f"the end of the run); got {t_end:g}")
    if "t_step" in p and p["t_step"] >= t_end - WINDOW_S:
        raise ParameterError(f"t_step must be before t_end - {WINDOW_S:g} s = {t_end - WINDOW_S:g} s so the "
                             f"recovery can be measured; got {p['t_step']:g}")
    lcp = run_converter(model, p, h=h, t_end=t_end)
    netlist = build_smc_netlist(p, t_end, spice_options)
    spice = spice_trajectory(model, p, netlist, run_spice(netlist))
    t0 = t_end - WINDOW_S
    m = {"window_s": [t0, t_end], "vref_V": p["Vref"],
         "vout_mean_lcp_V": lcp.mean("vout", t0=t0), "vout_mean_spice_V": spice.mean("vout", t0=t0)}
    m["vout_ref_rel_lcp"] = abs(m["vout_mean_lcp_V"] / p["Vref"] - 1.0)
    m["vout_ref_rel_spice"] = abs(m["vout_mean_spice_V"] / p["Vref"] - 1.0)
    m["frequency_lcp_Hz"] = switching_frequency(lcp, t0)
    m["frequency_spice_Hz"] = switching_frequency(spice, t0)
    m["frequency_predicted_lcp_Hz"] = predicted_frequency(p, m["vout_mean_lcp_V"])
    m["frequency_predicted_spice_Hz"] = predicted_frequency(p, m["vout_mean_spice_V"])
    m["frequency_rel_lcp"] = abs(m["frequency_lcp_Hz"] / m["frequency_predicted_lcp_Hz"] - 1.0)
    m["frequency_rel_spice"] = abs(m["frequency_spice_Hz"] / m["frequency_predicted_spice_Hz"] - 1.0)
    m["frequency_lcp_vs_spice"] = abs(m["frequency_lcp_Hz"] / m["frequency_spice_Hz"] - 1.0)
    m["min_iL_lcp_A"] = float(lcp.state("iL")[lcp.t >= 0.5 * t_end].min())
    m["held_steps_lcp"] = int(lcp.active[:, 0].sum())   # DCM never occurs under this control
    if "t_step" in p:
        v_l, v_s = lcp.signal("vout"), spice.signal("vout")
        m["t_step_s"] = p["t_step"]
        m["recovery_lcp_s"] = recovery_time(lcp.t, v_l, p["Vref"], p["t_step"], RECOVERY_TOL)
        m["recovery_spice_s"] = recovery_time(spice.t, v_s, p["Vref"], p["t_step"], RECOVERY_TOL)
        m["recovery_lcp_vs_spice"] = abs(m["recovery_lcp_s"] / m["recovery_spice_s"] - 1.0)
        m["dip_lcp_V"] = float(p["Vref"] - v_l[lcp.t >= p["t_step"]].min())
        m["dip_spice_V"] = float(p["Vref"] - v_s[spice.t >= p["t_step"]].min())
    m["lcp_wall_s"] = lcp.wall_s
    m["spice_wall_s"] = spice.wall_s
    m["lcp_steps"] = int(lcp.steps)
    m["spice_steps"] = int(spice.steps)
    return SMCComparison(p, lcp, spice, netlist, m)


def smc_checks(metrics: dict, thresholds: dict, params: dict, t_end: float) -> list[tuple]:
    """(check, value, threshold, pass) of a sliding-mode comparison."""
    m, th = metrics, thresholds

    def row(name, value, label=None):
        return (label or name, value, th[name], passes(name, value, th[name]))

    rows = [row("vout_ref_rel", m["vout_ref_rel_lcp"], "vout_ref_rel (LCP)"),
            row("vout_ref_rel", m["vout_ref_rel_spice"], "vout_ref_rel (ngspice)"),
            row("frequency_rel", m["frequency_rel_lcp"], "frequency_rel (LCP)"),
            row("frequency_rel", m["frequency_rel_spice"], "frequency_rel (ngspice)"),
            row("frequency_agreement", m["frequency_lcp_vs_spice"])]
    if "recovery_lcp_s" in m:
        rows += [("recovered within 1 % (LCP)", m["recovery_lcp_s"], t_end - params["t_step"],
                  bool(np.isfinite(m["recovery_lcp_s"]))),
                 ("recovered within 1 % (ngspice)", m["recovery_spice_s"], t_end - params["t_step"],
                  bool(np.isfinite(m["recovery_spice_s"]))),
                 row("recovery_agreement", m["recovery_lcp_vs_spice"])]
    return rows


def implicit_checks(metrics: dict, thresholds: dict) -> list[tuple]:
    """(check, value, threshold, pass) of the implicit relay's run."""
    th = thresholds
    return [("vout_ref_rel", metrics["vout_ref_rel"], th["vout_ref_rel"],
             passes("vout_ref_rel", metrics["vout_ref_rel"], th["vout_ref_rel"])),
            ("|lambda - Vin/v|", metrics["lambda_minus_vin_over_v"], th["lambda_settle"],
             passes("lambda_settle", metrics["lambda_minus_vin_over_v"], th["lambda_settle"])),
            ("lambda spread (no chatter)", metrics["lambda_spread"], th["lambda_settle"],
             passes("lambda_settle", metrics["lambda_spread"], th["lambda_settle"]))]


def implicit_metrics(params: dict | None = None, t_end: float = 30e-3, h=None) -> tuple[dict, object]:
    """The chattering-free relay: lambda against Vin/v, its spread, and vout against Vref."""
    start = time.perf_counter()
    model = get_model("boost", "smc-implicit")
    run = run_converter(model, params, h=h, t_end=t_end)
    p = run.metadata["params"]
    s = model.summary(run, p, WINDOW_S)
    lam = 1.0 - run.signal("switch")[run.t >= t_end - WINDOW_S]
    reversals = int(np.sum(np.abs(np.diff(np.sign(np.diff(lam)))) > 0)) if lam.size > 2 else 0
    return {"vout_mean_V": s["vout_mean"], "vout_ref_rel": abs(s["vout_mean"] / p["Vref"] - 1.0),
            "lambda_mean": s["lambda_mean"], "vin_over_v": s["vin_over_v"],
            "lambda_minus_vin_over_v": abs(s["lambda_mean"] - s["vin_over_v"]),
            "lambda_spread": s["lambda_spread"], "lambda_saturated_steps": int(np.sum((lam <= 0) | (lam >= 1))),
            "lambda_direction_changes": reversals, "h_s": run.metadata["method_options"]["h"],
            "steps": int(run.steps), "wall_s": time.perf_counter() - start,
            "recovery_s": s.get("recovery_time_s")}, run


def smc_plot(c: SMCComparison) -> bytes:
    from .plots import png, plt
    lcp, spice = c.lcp, c.spice
    fig, axes = plt.subplots(3, 1, figsize=(8, 7))
    ax = axes[0]
    ax.plot(lcp.t * 1e3, lcp.signal("vout"), lw=1, label="LCP")
    ax.plot(spice.t * 1e3, spice.signal("vout"), lw=1, ls="--", label="ngspice")
    ax.axhline(c.params["Vref"], color="k", lw=0.5)
    ax.set_ylabel("vout (V)")
    ax.set_xlabel("t (ms)")
    ax.legend(fontsize=8)
    ax.set_title("boost under sliding-mode control: whole run", fontsize=9)
    t1 = lcp.t[-1]
    t0 = t1 - 5.0 / predicted_frequency(c.params)
    for ax, name, label in zip(axes[1:], ("iL", "vout"), ("iL (A)", "vout (V)")):
        sl, ss = lcp.t >= t0, spice.t >= t0
        ax.plot(lcp.t[sl] * 1e6, lcp.signal(name)[sl], lw=1, label="LCP")
        ax.plot(spice.t[ss] * 1e6, spice.signal(name)[ss], lw=1, ls="--", label="ngspice")
        ax.set_ylabel(label)
        ax.set_xlabel("t (us), last 5 switching periods")
        ax.grid(alpha=0.3)
    fig.tight_layout()
    return png(fig)
