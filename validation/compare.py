"""The LCP time-stepper against ngspice on the same circuit, started on the same periodic orbit.

Data flow: the LCP side finds the periodic steady state x* (shooting) and simulates ``periods``
periods from it; the netlist gets x* as initial conditions and ngspice simulates the same span.
Metrics are taken over the last ``window`` periods, each simulator on its own time points where
possible (means, ripple, mode runs, turn-off instants) and on a common fine grid only for the
pointwise errors, with a guard band of 1 % of T around every switching edge and diode event so
that edge timing is measured by the timing metric, not smeared into the amplitude errors.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from converters.errors import ParameterError
from converters.models import get_converter
from converters.run import ConverterRun, run_converter
from netlists import SpiceOptions, build_netlist

from .modes import period_sequences, spice_modes
from .spice import SpiceResult, run_spice

THRESHOLDS = {"vout_mean_rel": 1e-2, "mode_agreement": 1.0, "turn_off_error_T": 2e-2}
EDGE_GUARD_T = 1e-2
THERMAL_VOLTAGE = 0.025852


@dataclass
class Comparison:
    converter: str
    params: dict
    lcp: ConverterRun
    spice: SpiceResult
    netlist: object
    window_start: float
    metrics: dict = field(default_factory=dict)
    checks: dict = field(default_factory=dict)

    @property
    def passed(self) -> bool:
        return all(self.checks.values())

    def to_dict(self) -> dict:
        return {"converter": self.converter, "params": self.params, "metrics": self.metrics,
                "thresholds": THRESHOLDS, "checks": self.checks, "passed": self.passed,
                "ngspice": self.spice.ngspice_version, "spice_options": self.spice.options}


def compare(converter: str, params: dict | None = None, *, periods: int | None = None, window: int | None = None,
            h=None, theta=None, spice_options: SpiceOptions | None = None, start: str | None = None) -> Comparison:
    """Run both simulators on the same circuit and measure their agreement.

    ``start``: 'steady' (default for PWM converters: both start on the LCP's periodic orbit, 30
    periods, metrics over the last 10) or 'rest' (default for the PRC, whose ideal tank keeps a
    ~1e-4 V cycle-to-cycle jitter: the Siconos scene, 2 ms from rest, metrics over the last 1 ms).
    """
    conv = get_converter(converter)
    p = conv.resolve(params)
    T = conv.period(p)
    start = start or ("rest" if conv.name == "prc" else "steady")
    if start not in ("steady", "rest"):
        raise ParameterError(f"start must be 'steady' or 'rest'; got {start!r}")
    if conv.name == "prc":
        periods, window = periods or 110, window or 55
    periods, window = periods or 30, window or 10
    if not 1 <= window <= periods:
        raise ParameterError(f"window must be in [1, periods = {periods}]; got {window}")
    x_star = (run_converter(conv, p, h=h, theta=theta, steady=True).trajectory.x[0] if start == "steady"
              else np.zeros(len(conv.state_names)))
    lcp = run_converter(conv, p, h=h, theta=theta, periods=periods, x0=x_star)
    netlist = build_netlist(conv.name, p, periods * T, spice_options, x0=x_star)
    spice = run_spice(netlist)
    result = Comparison(conv.name, p, lcp, spice, netlist, window_start=(periods - window) * T)
    _metrics(result, conv, T, periods, window)
    return result


def _metrics(c: Comparison, conv, T, periods, window):
    lcp, spice, nl = c.lcp, c.spice, c.netlist
    t_l, t_s = lcp.trajectory.t, spice.time
    w_l, w_s = t_l >= c.window_start - 1e-12 * T, t_s >= c.window_start - 1e-12 * T
    vout_l, vout_s = lcp.vout(), spice.signal(nl.probes["vout"])
    mean_l = lcp.mean(vout_l, window)
    mean_s = float(np.trapezoid(vout_s[w_s], t_s[w_s]) / (t_s[w_s][-1] - t_s[w_s][0]))
    m = c.metrics
    m["vout_mean_lcp_V"], m["vout_mean_spice_V"] = mean_l, mean_s
    m["vout_mean_abs_error_V"] = abs(mean_s - mean_l)
    m["vout_mean_rel_error"] = abs(mean_s - mean_l) / max(abs(mean_l), 1e-12)
    ripple_l = float(np.ptp(vout_l[w_l]))
    m["vout_ripple_lcp_V"], m["vout_ripple_spice_V"] = ripple_l, float(np.ptp(vout_s[w_s]))
    m["vout_ripple_error_V"] = abs(m["vout_ripple_spice_V"] - ripple_l)

    labels_l = lcp.modes()
    labels_s = spice_modes(conv, spice, nl, c.window_start)
    first = periods - window
    seq_l = period_sequences(t_l, labels_l, T, first, window)
    seq_s = period_sequences(t_s, labels_s, T, first, window)
    agree = [a == b for a, b in zip(seq_l, seq_s)]
    m["mode_sequence_lcp"] = " > ".join(seq_l[-1])
    m["mode_sequence_spice"] = " > ".join(seq_s[-1])
    m["mode_agreement"] = float(np.mean(agree))

    edges = _edges(conv, c.params, T, c.window_start, periods * T)
    off_l, off_s = _turn_offs(lcp, labels_l, T, first, window), _spice_turn_offs(spice, nl, labels_s, T, first,
                                                                                 window, conv)
    pairs = [(a, b) for a, b in zip(off_l, off_s) if a is not None and b is not None]
    m["turn_off_error_T"] = max((abs(a - b) / T for a, b in pairs), default=float("nan"))
    events = [x for x in off_l + off_s if x is not None]

    grid = np.linspace(c.window_start, periods * T, window * 2000 + 1)
    guard = np.zeros(grid.shape, dtype=bool)
    for e in np.concatenate([edges, np.array(events, dtype=float)]):
        guard |= np.abs(grid - e) < EDGE_GUARD_T * T
    primary = conv.state_names[0]
    cur_l = np.interp(grid, t_l, lcp.trajectory.state(primary))
    cur_s = np.interp(grid, t_s, spice.signal(nl.probes[primary]))
    ripple_i = float(np.ptp(cur_l))
    m["current_signal"] = primary
    m["current_rms_error_over_ripple"] = float(np.sqrt(np.mean((cur_l - cur_s)[~guard] ** 2)) / max(ripple_i, 1e-12))
    m["current_max_error_outside_edges_A"] = float(np.abs(cur_l - cur_s)[~guard].max())
    m["vout_max_error_outside_edges_V"] = float(np.abs(np.interp(grid, t_l, vout_l) -
                                                       np.interp(grid, t_s, vout_s))[~guard].max())
    m["lcp_wall_s"], m["spice_wall_s"] = lcp.wall_s, spice.wall_s
    m["runtime_ratio_spice_over_lcp"] = spice.wall_s / max(lcp.wall_s, 1e-9)
    m["lcp_steps"], m["spice_accepted_steps"] = lcp.trajectory.steps, spice.accepted_steps
    m["diode_drop_floor_V"] = _diode_drop(spice, nl, c.window_start)
    c.checks = {"vout_mean_rel": m["vout_mean_rel_error"] <= THRESHOLDS["vout_mean_rel"],
                "mode_agreement": m["mode_agreement"] >= THRESHOLDS["mode_agreement"],
                "turn_off_error_T": (math.isnan(m["turn_off_error_T"])
                                     or m["turn_off_error_T"] <= THRESHOLDS["turn_off_error_T"])}


def _edges(conv, p, T, start, end):
    fraction = 0.5 if conv.name == "prc" else p["D"]
    k = np.arange(math.floor(start / T), math.ceil(end / T) + 1)
    return np.concatenate([k * T, (k + fraction) * T])


def _turn_offs(lcp, labels, T, first, count):
    """Per period: end of the diode's CCM-OFF conduction (sub-step estimate from the LCP events)."""
    t = lcp.trajectory.t
    events = lcp.trajectory.events
    activate = events[events["kind"] == "activate"]
    out = []
    for m in range(first, first + count):
        idx = np.flatnonzero((t > m * T) & (t <= (m + 1) * T + 1e-12 * T) & (labels == "CCM-OFF"))
        if idx.size == 0:
            out.append(None)
            continue
        last = idx[-1]
        hit = activate[activate["step"] == last]
        out.append(float(hit["time"].iloc[0]) if len(hit) else float(t[last]))
    return out


def _spice_turn_offs(spice, nl, labels, T, first, count, conv):
    if conv.name == "prc":
        return [None] * count
    t = spice.time
    out = []
    for m in range(first, first + count):
        idx = np.flatnonzero((t > m * T) & (t <= (m + 1) * T + 0.01 * T) & (labels == "CCM-OFF"))
        if idx.size == 0 or idx[-1] + 1 >= t.size:
            out.append(None)
            continue
        j = idx[-1]
        diode = spice.signal(nl.probes["i_D"])
        threshold = 1e-3 * np.abs(diode[t >= m * T]).max()
        a, b = diode[j] - threshold, diode[j + 1] - threshold
        frac = a / (a - b) if a > 0 >= b else 0.0
        out.append(float(t[j] + frac * (t[j + 1] - t[j])))
    return out


def _diode_drop(spice, nl, start):
    """Forward drop of the SPICE diode model at its mean conduction current: the accuracy floor."""
    if "i_D" not in nl.probes:
        return float("nan")
    current = spice.signal(nl.probes["i_D"])[spice.time >= start]
    conducting = current[current > 1e-3 * max(current.max(), 1e-30)]
    if conducting.size == 0:
        return 0.0
    o = nl.options
    return float(o.diode_n * THERMAL_VOLTAGE * np.log1p(conducting.mean() / o.diode_is))
