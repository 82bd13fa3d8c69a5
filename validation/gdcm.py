"""Conduction-mode cross-check: closed-form and exact prediction, LCP and ngspice detection.

``gdcm_check`` is one operating point (``pcsuite gdcm``); ``dk_map`` is a D-K grid per converter
(load R sets K = 2 L / (R T) at the converter's default inductances).

Detection: LCP modes come from the complementarity state of the stepper's periodic orbit (exact up
to the step h). ngspice modes come from the diode current: conducting above 0.1 % of its peak in the
window (``validation.modes.CURRENT_FRACTION``); runs shorter than 0.05 % of T are edge glitches
(the gate edges, 0.01 % of T, leave glitches of 0.005 % of T) and are merged into their neighbours. Both simulators start on the LCP
orbit; ngspice runs ``SPICE_PERIODS`` periods and the last ``WINDOW_PERIODS`` are read, with RELTOL
1e-4 (``SPICE_OPTIONS``): at the default 1e-3 its step control places the diode turn-off up to 0.4 % of
T late, which hides held intervals shorter than that (seen at Cuk points within 2 % of the boundary).
"""
from __future__ import annotations

import time

import numpy as np
import pandas as pd

from converters.analysis import gdcm
from converters.analysis.modes import HELD, held_fraction, mode_class, mode_intervals, orbit_intervals
from converters.errors import ParameterError
from converters.models import analytic, get_converter
from converters.run import steady_orbit
from converters.parallel import parallel_map
from netlists import SpiceOptions, build_netlist

from .defaults import BOUNDARY_BAND, D_RANGE, K_RANGES  # noqa: F401 (re-exported for the report and tests)
from .spice import SpiceError, close_spice_worker, run_spice, spice_trajectory

SPICE_PERIODS = 8
WINDOW_PERIODS = 2
SPICE_MIN_RUN = 5e-4
SPICE_OPTIONS = SpiceOptions(reltol=1e-4)


def predicted_label(converter, p: dict) -> str:
    """The closed-form prediction in the detection vocabulary: 'CCM' or the converter's held-OFF label."""
    return converter.off_held_label if analytic.predicted_mode(p, converter.name) == "DCM" else "CCM"


def spice_intervals(converter, netlist, result, periods_window: int = WINDOW_PERIODS) -> list[dict]:
    T = converter.period(netlist.params)
    start = netlist.t_end - periods_window * T
    run = spice_trajectory(converter, netlist.params, netlist, result, start)
    return mode_intervals(run.t, run.modes(), start, netlist.t_end, T, SPICE_MIN_RUN)


def gdcm_check(name: str, params: dict | None = None, *, h=None) -> dict:
    """Predicted mode against the modes detected in both simulators at one operating point."""
    from converters.models.netlist import is_netlist
    if is_netlist(name):
        return circuit_check(name, params, h=h)
    conv = get_converter(name)
    p = conv.resolve(params)
    T = conv.period(p)
    orbit = steady_orbit(conv, p, h=h)
    out = {"converter": conv.name, "params": p, "period_s": T}
    if not analytic.has_closed_form(conv.name):
        return {**out, **_combinations(conv, p, orbit)}
    exact = gdcm.exact_mode(conv, p)
    # The prediction is the exact one (the CCM orbit from the matrices: no ripple approximation, and it sees
    # GDCM-ON, which the small-ripple closed form cannot); the closed form is reported beside it.
    out["predicted"] = exact["mode"]
    out["prediction"] = {"K": analytic.k_factor(p, conv.name), "Kcrit": analytic.k_crit(p["D"], conv.name),
                         "closed_form": predicted_label(conv, p), "exact_matrix": exact["mode"],
                         "exact_min_y": exact["min_y"], "conditions": gdcm.describe(conv, p)}
    lcp_iv = orbit_intervals(orbit)
    spice_iv, note = _spice_run(conv, p, orbit.x[0])
    if note:
        out["spice_note"] = note
    out["lcp"] = mode_class(lcp_iv)
    out["spice"] = mode_class(spice_iv)
    out["intervals"] = {"lcp": lcp_iv, "spice": spice_iv, "lcp_periods": 1, "spice_periods": WINDOW_PERIODS}
    out["held_fraction"] = {"lcp": held_fraction(lcp_iv, 1), "spice": held_fraction(spice_iv, WINDOW_PERIODS)}
    _judge(out, conv, p, orbit)
    if "GDCM" in out["lcp"]:
        out["gdcm_constraint"] = _constraint_residuals(conv, p, orbit)
    return out


def _judge(out: dict, conv, p: dict, orbit) -> None:
    """The verdict, to what each side resolves (:func:`judge_held`): the LCP's held fraction is a whole number of
    its steps, ngspice's runs shorter than SPICE_MIN_RUN are its glitches. Near the DCM boundary (a buck at R =
    3.327 ohm, held 3.7e-5 of T) the LCP had printed 0.0010 and ngspice CCM, and the verdict DISAGREE said nothing
    of why."""
    exact = exact_held(conv, p)
    T = out["period_s"]
    resolution = {"lcp": float(np.diff(orbit.t).max()) / T, "spice": SPICE_MIN_RUN}
    out["held_fraction"]["exact"] = exact
    out["resolution"] = resolution
    out["agree"], out["notes"] = judge_held(out["predicted"], exact, {
        side: (out[side], out["held_fraction"][side], resolution[side]) for side in ("lcp", "spice")})


def exact_held(conv, p: dict) -> float:
    """The fraction of the period the exact orbit (the event method's) holds every device off."""
    return held_fraction(orbit_intervals(steady_orbit(conv, p, method="event")), 1)


def judge_held(predicted: str, exact: float, sides: dict) -> tuple[bool, list[str]]:
    """Whether each side's conduction class agrees with the exact prediction to what the side resolves, and the
    notes that say why. ``sides`` maps a side's name to (its class, its held fraction of T, its resolution as a
    fraction of T). A side whose class differs from the prediction while its held fraction is within its resolution
    of the exact one agrees to what it can see, and a note says so; otherwise the disagreement names the side and
    the fractions. The one rule of the gdcm command and the report's scenes."""
    notes, differ = [], []
    for side, (label, held, resolution) in sides.items():
        if label == predicted:
            continue
        apart = abs(held - exact)
        if apart <= resolution * (1 + 1e-9):
            notes.append(f"{side} reads {label} where the exact orbit is {predicted} (held {exact:.2g} of T): within "
                         f"what it resolves ({resolution:.2g} of T)")
        else:
            differ.append(f"{side} reads {label}, held {held:.4g} of T, where the exact orbit is {predicted}, held "
                          f"{exact:.4g} of T ({apart:.2g} apart; it resolves {resolution:.2g})")
    return not differ, notes + differ


def _constraint_residuals(conv, p, orbit) -> dict:
    """Per held mode of the orbit (DCM, GDCM-OFF, GDCM-ON): over its points, max |C x + F| (A / V) of the
    configuration it occurs in, the largest exit drift C (A x + E) and the smallest multiplier."""
    labels = np.asarray(orbit.modes()).astype(str)
    configurations = conv.configurations(p)
    out = {}
    for label in HELD:
        points = np.flatnonzero(labels == label)
        if points.size == 0:
            continue
        for index in np.unique(orbit.config[points]):
            cond = gdcm.gdcm_condition(configurations[index])
            xs = orbit.x[points[orbit.config[points] == index]]
            out[label] = {"configuration": cond.name, "max_abs_Cx_plus_F": float(np.abs(cond.on_set(xs)).max()),
                          "max_drift": float(cond.drift(xs).max()), "min_multiplier": float(cond.multiplier(xs).min())}
    return out


def _combinations(conv, p, orbit) -> dict:
    """Several pairs (the PRC's bridge): which devices conduct, as fractions of the period, in both
    simulators, named by the model's own mode labels (``D2+D3``, ``DCM``: as the waveform file's ``mode``
    column); no closed-form prediction."""
    T = conv.period(p)
    lcp = orbit.mode_fractions(periods=None)
    netlist = build_netlist(conv.name, p, SPICE_PERIODS * T, SPICE_OPTIONS, x0=orbit.x[0])
    start = netlist.t_end - WINDOW_PERIODS * T
    run = spice_trajectory(conv, p, netlist, run_spice(netlist), start)
    spice = run.mode_fractions(periods=None, t0=start)
    keys = sorted(set(lcp) | set(spice))
    diff = max(abs(lcp.get(k, 0.0) - spice.get(k, 0.0)) for k in keys)
    return {"predicted": f"n/a ({len(conv.pair_names)} pairs: combinations of conducting devices)", "lcp": lcp, "spice": spice,
            "max_fraction_difference": diff, "agree": set(k for k, v in lcp.items() if v > 0.01) ==
            set(k for k, v in spice.items() if v > 0.01)}


def conduction_class(tr, t0: float, t1: float) -> str:
    """A netlist's conduction class over [t0, t1] from its modes: CCM where some device always conducts; where
    nothing does (mode 'off') for more than 1 % of the time, DCM when every inductor current is zero there
    (below CURRENT_FRACTION, 0.1 %, of its peak: ngspice's near-ideal diode leaves 5e-6 of the peak in a DCM
    buck) and GDCM when one is held non-zero (inductor currents circulating with the diodes blocked and the
    switches open: the Cuk's i1 = -i2)."""
    from .spice import CURRENT_FRACTION
    rows = tr.rows_between(t0, t1)
    off = np.asarray(tr.modes(rows)).astype(str) == "off"
    if tr.mode_fractions(None, t0=t0, t1=t1).get("off", 0.0) <= 0.01:
        return "CCM"
    currents = [name for name in tr.state_names if name.startswith("i(")]
    held = [np.abs(np.asarray(tr.state(name))[rows][off]).max()
            > CURRENT_FRACTION * np.abs(np.asarray(tr.state(name))[rows]).max() for name in currents]
    return "GDCM" if any(held) else "DCM"


def circuit_check(path, params: dict | None = None, *, h=None) -> dict:
    """``pcsuite gdcm FILE.cir``: a netlist has no closed-form prediction; its conduction class
    (:func:`conduction_class`) and its modes' fractions of the period on the stepper's periodic orbit against
    ngspice's on the same file (started on that orbit, SPICE_PERIODS periods, the last WINDOW_PERIODS read)."""
    from dataclasses import replace

    from converters.models import get_model
    from converters.analysis.periodic import ANALYSIS_REMEDY
    from converters.run import make_method, steady_state
    from converters.simulate import simulate
    from netlists.circuit import circuit_netlist, file_spice_options

    from .spice import circuit_trajectory, run_spice_retrying
    circuit = get_model(path)
    p = circuit.resolve(params)
    if not circuit.periodic(p):
        raise ParameterError(f"gdcm needs a periodic circuit; {circuit.name} has no period (its sources are DC or "
                             "it switches itself)")
    T = circuit.period(p)
    method = make_method(circuit, p, "lcp", h)
    orbit = steady_state(circuit, p, method, tol=1e-9, remedy=ANALYSIS_REMEDY)
    lcp = replace(simulate(circuit.problem(p, T, x0=orbit.x0), method), labels=circuit.labels(p))
    span = SPICE_PERIODS * T
    netlist, run, notes = run_spice_retrying(lambda o: circuit_netlist(circuit, p, span, o, x0=orbit.x0),
                                             file_spice_options(circuit))
    start = span - WINDOW_PERIODS * T
    spice = circuit_trajectory(circuit, p, netlist, run, start)
    fractions = {"lcp": lcp.mode_fractions(None, t0=0.0, t1=T), "spice": spice.mode_fractions(None, t0=start, t1=span)}
    keys = sorted(set(fractions["lcp"]) | set(fractions["spice"]))
    conduction = {"lcp": conduction_class(lcp, 0.0, T), "spice": conduction_class(spice, start, span)}
    held = [{k for k, v in f.items() if v > 0.01} for f in fractions.values()]
    return {"converter": circuit.name, "params": p, "period_s": T,
            "predicted": "n/a (a netlist: no closed form; its conduction class in each simulator)",
            "lcp": fractions["lcp"], "spice": fractions["spice"], "conduction": conduction,
            "max_fraction_difference": max(abs(fractions["lcp"].get(k, 0.0) - fractions["spice"].get(k, 0.0))
                                           for k in keys),
            "notes": notes, "agree": held[0] == held[1] and conduction["lcp"] == conduction["spice"]}


# --- D-K maps -----------------------------------------------------------------------------------------

def dk_grid(name: str, n_d: int = 30, n_k: int = 30) -> pd.DataFrame:
    """Operating points: D linear over D_RANGE, K log-spaced over K_RANGES; K set by the load R."""
    conv = get_converter(name)
    if conv.name not in K_RANGES:
        raise ParameterError(f"converter must be one of {', '.join(K_RANGES)} for a D-K map; got {name!r}")
    if n_d < 2 or n_k < 2:
        raise ParameterError(f"the grid needs at least 2 x 2 points; got {n_d} x {n_k}")
    base = conv.resolve({})
    inductance = analytic.k_factor(base, conv.name) * base["R"] / (2.0 * base["f_sw"])   # L (Cuk: L1 L2 / (L1 + L2))
    rows = []
    for D in np.linspace(*D_RANGE, n_d):
        for K in np.geomspace(*K_RANGES[conv.name], n_k):
            R = 2.0 * inductance * base["f_sw"] / K
            kc = analytic.k_crit(D, conv.name)
            rows.append({"converter": conv.name, "D": float(D), "K": float(K), "R": float(R), "Kcrit": kc,
                         "distance": float(K / kc - 1.0)})
    return pd.DataFrame(rows)


def _lcp_point(row: dict) -> dict:
    conv = get_converter(row["converter"])
    p = conv.resolve({"D": row["D"], "R": row["R"]})
    out = {"predicted": predicted_label(conv, p)}
    try:
        out["exact"] = gdcm.exact_mode(conv, p)["mode"]
        orbit = steady_orbit(conv, p)
        iv = orbit_intervals(orbit)
        out.update(lcp=mode_class(iv), lcp_held=held_fraction(iv, 1), converged=orbit.metadata["orbit"]["converged"],
                   x0=orbit.x[0].tolist())
    except Exception as exc:  # one failed point is recorded, the map goes on
        out.update(lcp="error", lcp_error=str(exc))
    return out


def _spice_point(row: dict) -> dict:
    conv = get_converter(row["converter"])
    p = conv.resolve({"D": row["D"], "R": row["R"]})
    try:
        iv, note = _spice_run(conv, p, row["x0"])
        return {"spice": mode_class(iv), "spice_held": held_fraction(iv, WINDOW_PERIODS), "spice_note": note}
    except Exception as exc:  # ngspice failures are counted and shown, never fatal
        return {"spice": "error", "spice_error": str(exc).splitlines()[0][:200]}


def _spice_run(conv, p, x0):
    """ngspice at RELTOL 1e-4; when it stops ("timestep too small"), once more at its default 1e-3."""
    T = conv.period(p)
    try:
        netlist = build_netlist(conv.name, p, SPICE_PERIODS * T, SPICE_OPTIONS, x0=x0)
        return spice_intervals(conv, netlist, run_spice(netlist)), ""
    except SpiceError as exc:
        netlist = build_netlist(conv.name, p, SPICE_PERIODS * T, x0=x0)
        note = f"RELTOL 1e-4 failed ({str(exc).splitlines()[0][:120]}); RELTOL 1e-3 used"
        return spice_intervals(conv, netlist, run_spice(netlist)), note


def _pool_map(point, rows: list[dict], workers: int, progress: bool, label: str) -> list[dict]:
    """``point`` (_lcp_point or _spice_point) at every row on the pool; ngspice's workers shut down after."""
    finalize = close_spice_worker if point is _spice_point else None
    return parallel_map(point, rows, workers=workers, chunk=30, progress=progress, label=label, finalize=finalize)


def dk_map(name: str, n_d: int = 30, n_k: int = 30, *, spice: bool = True, workers: int = 1,
           spice_workers: int = 2, progress: bool = True) -> pd.DataFrame:
    """The D-K map: closed-form and exact predictions, LCP-detected and (optionally) ngspice-detected modes."""
    grid = dk_grid(name, n_d, n_k)
    rows = grid.to_dict("records")
    start = time.perf_counter()
    _lcp_point(rows[0])  # load the compiled kernels once, before the workers fork
    lcp = _pool_map(_lcp_point, rows, workers, progress, f"{name} LCP map")
    frame = pd.concat([grid, pd.DataFrame(lcp)], axis=1)
    lcp_wall = time.perf_counter() - start
    spice_wall = float("nan")
    if spice:
        start = time.perf_counter()
        spice_rows = frame.to_dict("records")
        frame = pd.concat([frame, pd.DataFrame(_pool_map(_spice_point, spice_rows, spice_workers, progress,
                                                         f"{name} ngspice map"))], axis=1)
        spice_wall = time.perf_counter() - start
    frame.attrs.update(lcp_wall_s=lcp_wall, spice_wall_s=spice_wall)
    return frame


def map_summary(frame: pd.DataFrame) -> dict:
    """Agreement counts of one map (the acceptance numbers)."""
    far = frame["distance"].abs() > BOUNDARY_BAND
    lcp_vs_pred = frame["lcp"] == frame["predicted"]
    out = {"converter": frame["converter"].iloc[0], "points": int(len(frame)),
           "far_points": int(far.sum()), "far_disagreements": int((far & ~lcp_vs_pred).sum()),
           "near_disagreements": int((~far & ~lcp_vs_pred).sum()),
           "lcp_vs_exact_disagreements": int((frame["lcp"] != frame["exact"]).sum()),
           "lcp_errors": int((frame["lcp"] == "error").sum()),
           "not_converged": int((~frame["converged"].fillna(False).astype(bool)).sum()),
           "lcp_wall_s": frame.attrs.get("lcp_wall_s", float("nan"))}
    if "spice_note" in frame:
        out["spice_retried"] = int(frame["spice_note"].fillna("").astype(bool).sum())
    if "spice" in frame:
        agree = frame["spice"] == frame["lcp"]
        out.update(spice_agreement=float(agree.mean()), spice_disagreements=int((~agree).sum()),
                   spice_errors=int((frame["spice"] == "error").sum()),
                   spice_wall_s=frame.attrs.get("spice_wall_s", float("nan")))
    return out


def disagreements(frame: pd.DataFrame) -> pd.DataFrame:
    """Rows where the LCP differs from the closed form, or ngspice from the LCP."""
    bad = frame["lcp"] != frame["predicted"]
    if "spice" in frame:
        bad |= frame["spice"] != frame["lcp"]
    cols = [c for c in ("D", "K", "Kcrit", "distance", "R", "predicted", "exact", "lcp", "lcp_held", "spice",
                        "spice_held", "spice_note", "spice_error") if c in frame]
    return frame.loc[bad, cols]


def map_plot(frame: pd.DataFrame) -> bytes:
    from .plots import png, plt
    name = frame["converter"].iloc[0]
    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    held = frame["lcp"].isin(HELD)
    ax.scatter(frame.loc[~held, "D"], frame.loc[~held, "K"], s=9, c="#4c72b0", label="LCP: CCM")
    ax.scatter(frame.loc[held, "D"], frame.loc[held, "K"], s=9, c="#c44e52",
               label=f"LCP: {get_converter(name).off_held_label}")
    if "spice" in frame:
        off = frame["spice"] != frame["lcp"]
        ax.scatter(frame.loc[off, "D"], frame.loc[off, "K"], s=60, facecolors="none", edgecolors="k",
                   label="ngspice differs")
    off_pred = frame["lcp"] != frame["predicted"]
    ax.scatter(frame.loc[off_pred, "D"], frame.loc[off_pred, "K"], s=40, marker="x", c="#dd8452",
               label="LCP differs from closed form")
    d = np.linspace(frame["D"].min(), frame["D"].max(), 200)
    ax.plot(d, [analytic.k_crit(v, name) for v in d], "k-", lw=1, label="Kcrit(D) (closed form)")
    ax.set_yscale("log")
    ax.set_xlabel("D")
    ax.set_ylabel("K = 2 L / (R T)")
    ax.set_title(f"{name}: conduction mode over D and K", fontsize=10)
    ax.legend(fontsize=7, loc="lower left")
    ax.grid(alpha=0.3, which="both")
    return png(fig)
