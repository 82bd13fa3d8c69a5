"""Report sections: each runs one study and returns its HTML, data files and metrics."""
from __future__ import annotations

import html
from functools import partial

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import pandas as pd  # noqa: E402

from converters.lcp.problems import problem_set  # noqa: E402

from .defaults import K_RANGES  # noqa: E402
from .core_checks import convergence_table, core_waveforms, observed_orders  # noqa: E402
from .peer import METHODS, PEER_TOL, peer_directory, peer_table, solver_table  # noqa: E402
from .report import Section, csv_bytes, esc, figure_png, has_quick_form, runs_alone, table_html, url  # noqa: E402


def _pivot(rows: pd.DataFrame) -> pd.DataFrame:
    """problem x method grid of 'status / err / iterations / time'."""
    rows = rows.copy()
    rows["cell"] = [f"{r.status} | {r.err:.1e} | {r.iterations} | {r.time_s * 1e3:.2f} ms"
                    for r in rows.itertuples()]
    return rows.pivot(index=["problem", "k"], columns="method", values="cell")[list(METHODS)].reset_index()


def lcp_project_section() -> Section:
    cases = problem_set()
    rows = pd.DataFrame(solver_table([(c.name, c.M, c.q) for c in cases], tol=1e-10))
    expected = {c.name: ("solved" if c.solvable else "no_solution") for c in cases}
    families = {c.name: c.family for c in cases}
    lemke_ok = all(r.status == expected[r.problem] for r in rows.itertuples() if r.method == "lemke")
    grid = _pivot(rows)
    grid.insert(1, "family", grid["problem"].map(families))
    text = (f"<p>{len(cases)} problems generated in code (seeded): random P-matrices (symmetric PD, "
            "non-symmetric PD, triangular non-PD), PSD with many solutions, degenerate, Murty's exponential "
            "family, and two with no solution. Each cell: status | err = ||z - max(0, z - w)|| / ||q|| | "
            "iterations | time; tol = 1e-10; closed-form fast paths off so every algorithm runs.</p>"
            + table_html(grid) +
            "<p>PGS converges only for symmetric positive definite M (its failures on the non-symmetric "
            "rows are expected); enumeration refuses k &gt; 12; Murty is finite on P-matrices only.</p>")
    return Section("LCP solvers: project problem set", text, {"lcp_project.csv": csv_bytes(rows)},
                   ok=lemke_ok, metrics={"problems": len(cases)})


def lcp_peer_section() -> Section:
    directory = peer_directory()
    rows = pd.DataFrame(peer_table(directory))
    grid = _pivot(rows)
    unexplained = rows[rows["differs"] & (rows["explanation"] == "")]
    enum_refused = (rows["method"] == "enum") & (rows["k"] > 12)
    must_solve = rows[rows["method"].isin(["lemke", "enum"]) & (rows["siconos"] == "solves") & ~enum_refused]
    solved_where_siconos_solves = bool((must_solve["status"] == "solved").all())
    diffs = rows[rows["differs"]][["problem", "method", "siconos", "status", "err", "explanation"]]
    text = (f"<p>The 20 problems of Siconos' LCP test collection, read from <code>{html.escape(str(directory))}"
            f"</code>; tol = {PEER_TOL:g} as in Siconos. Each cell: status | err | iterations | time.</p>"
            + table_html(grid) +
            "<h3>Differences from Siconos' expected-failure list, explained</h3>"
            + table_html(diffs, "status"))
    return Section("LCP solvers: Siconos peer collection", text, {"lcp_peer.csv": csv_bytes(rows)},
                   ok=solved_where_siconos_solves and unexplained.empty,
                   metrics={"differences": len(diffs), "unexplained": len(unexplained)})


def core_section() -> Section:
    table = convergence_table()
    orders = observed_orders(table)
    fig, ax = plt.subplots(figsize=(6.5, 4))
    for (case, theta), group in table.groupby(["case", "theta"], sort=False):
        ax.loglog(group["h"], group["error"], "o-", label=f"{case}, theta = {theta:g}")
    ax.set_xlabel("step h (s)")
    ax.set_ylabel("max |vC error| (V)")
    ax.legend(fontsize=7)
    ax.grid(True, which="both", alpha=0.3)
    conv_png = figure_png(fig)
    waves = core_waveforms()
    fig, axes = plt.subplots(len(waves), 1, figsize=(7, 5), sharex=True)
    for ax, (title, tr) in zip(axes, waves.items()):
        ax.plot(tr.t * 1e3, tr.x[:, 0], label="vC (V)")
        ax.plot(tr.t * 1e3, tr.x[:, 1] * 1e3, label="iL (mA)")
        ax.set_title(title, fontsize=9)
        ax.legend(fontsize=7)
    axes[-1].set_xlabel("time (ms)")
    wave_png = figure_png(fig)
    lc_be, lc_tr = orders["observed_order"].iloc[0], orders["observed_order"].iloc[1]
    bridge_be = orders["observed_order"].iloc[2]
    ok = abs(lc_be - 1.0) <= 0.15 and abs(lc_tr - 2.0) <= 0.2 and bridge_be >= 0.8
    text = ("<p>Error against closed forms (the free LC tank; the diode bridge, which with ideal diodes is a "
            "parallel RLC) as h shrinks. Targets: order 1.0 +- 0.15 (theta = 1) and 2.0 +- 0.2 "
            "(theta = 0.5) without switching; order >= 0.8 on the bridge.</p>"
            + table_html(orders) + '<img src="core_convergence.png" alt="convergence">'
            + '<img src="core_waveforms.png" alt="waveforms">' + table_html(table))
    return Section("LCS time-stepping: convergence on the Siconos circuits", text,
                   {"core_convergence.png": conv_png, "core_waveforms.png": wave_png,
                    "core_convergence.csv": csv_bytes(table)}, ok=ok,
                   metrics={"orders": orders.to_dict(orient="records")})


def converter_section() -> Section:
    from converters.models import analytic
    from converters.run import run_converter

    from .defaults import OPERATING_POINTS, THRESHOLDS
    TOLERANCE = THRESHOLDS["closed_form"]
    rows = []
    for name, params, mode in OPERATING_POINTS:
        run = run_converter(name, params, steady=True)
        p = run.metadata["params"]
        expected = analytic.conversion_ratio(p, name) * p["Vin"]
        vout = run.mean("vout", periods=10)
        fractions = run.mode_fractions()
        rows.append({"converter": name, "parameters": " ".join(f"{k}={v}" for k, v in params.items()) or "defaults",
                     "K": analytic.k_factor(p, name), "Kcrit": analytic.k_crit(p["D"], name),
                     "predicted": analytic.predicted_mode(p, name), "vout_mean_V": vout, "closed_form_V": expected,
                     "rel_error": vout / expected - 1.0, "tolerance": TOLERANCE[mode],
                     "modes_last_period": ", ".join(f"{k} {v:.3f}" for k, v in fractions.items()),
                     "steady_after_periods": run.metadata["steady_periods"], "wall_s": run.wall_s,
                     "result": "pass" if abs(vout / expected - 1.0) <= TOLERANCE[mode] else "fail"})
    table = pd.DataFrame(rows)
    text = ("<p>Periodic steady state (Newton shooting on the stepper's period map with its exact Jacobian; "
            "backward Euler, h = T/1000) against the small-ripple closed forms (Erickson and Maksimovic, Fundamentals of Power Electronics, ch. 5): CCM "
            "ratio to 0.05 %, DCM formula to 1 %.</p>" + table_html(table, "result", good=("pass",)))
    return Section("Converter library: steady state against closed forms", text,
                   {"converters_steady_state.csv": csv_bytes(table)}, ok=bool((table["result"] == "pass").all()))


def gdcm_map_section(name: str) -> Section:
    """One converter's 30 x 30 D-K map: closed form and exact prediction, LCP and ngspice detection."""
    from .gdcm import BOUNDARY_BAND, D_RANGE, K_RANGES, dk_map, disagreements, map_plot, map_summary
    frame = dk_map(name, 30, 30, spice=True, spice_workers=1, progress=False)
    summary = map_summary(frame)
    spice_ok = summary["spice_agreement"] >= 0.98
    ok = summary["far_disagreements"] == 0 and spice_ok and summary["lcp_errors"] == 0
    table = pd.DataFrame([summary])
    table["result"] = "pass" if ok else "fail"
    slug = name.replace("-", "_")
    text = (f"<p>D in [{D_RANGE[0]}, {D_RANGE[1]}] (30 values) by K = 2 L / (R T) in [{K_RANGES[name][0]:g}, "
            f"{K_RANGES[name][1]:g}] (30 log-spaced values, set by the load R at the default inductances). "
            "<i>predicted</i>: closed form Kcrit(D) (small ripple); <i>exact</i>: the CCM orbit computed with "
            "matrix exponentials keeps the diode's y >= 0 or not (no ripple approximation); <i>lcp</i>: "
            "the complementarity state of the time-stepper's periodic orbit (h = T/1000); <i>spice</i>: "
            "ngspice diode current above 0.1 % of its peak, runs under 0.05 % of T merged. Acceptance: no "
            f"LCP/closed-form disagreement farther than {BOUNDARY_BAND:.0%} (relative, in K) from the "
            "boundary; ngspice agrees with the LCP at 98 % of the points or more.</p>"
            + table_html(table, "result", good=("pass",))
            + f"<img src='{url(f'gdcm_map_{slug}.png')}' alt='D-K map {esc(name)}'>"
            + "<p>Disagreements (LCP against the closed form, or ngspice against the LCP):</p>"
            + table_html(disagreements(frame)))
    files = {f"gdcm_map_{slug}.png": map_plot(frame),
             f"gdcm_map_{slug}.csv": csv_bytes(frame.drop(columns=["x0"], errors="ignore"))}
    return Section(f"Conduction modes: {name} D-K map", text, files, ok=ok, metrics=summary)




def control_section() -> Section:
    """The compensated buck's loop: a type III designed for fs/10 and 60 degrees on the exact control-to-output,
    the loop gain before (the plant) and after (exact), a sinusoid injected at a few frequencies beside it."""
    import numpy as np

    from converters.analysis.smallsignal import (FrequencyResponse, SmallSignalModel, design_compensator, frequencies,
                                                 injection_response, loop_gain)
    from converters.models import get_model

    from .plots import bode_figure
    model = get_model("buck", "voltage-loop")
    p = model.resolve({})
    design = design_compensator(model.converter, model.plant(p), crossover_hz=1e4, phase_margin_deg=60.0,
                                vref=p["Vref"], carrier=(p["VL"], p["VU"]))
    closed = {**design.compensator.as_dict()}
    response, found = loop_gain(model, closed)
    plant = SmallSignalModel(model.converter, {**model.plant(p), "D": design.duty}, input="D")
    f = frequencies(plant.T)
    before = FrequencyResponse(f, plant.response(f) / (p["VU"] - p["VL"]), "D", "vout", "loop gain", plant.T,
                               plant.orbit.multipliers)
    small = SmallSignalModel(model, closed, input="control", outputs=("sensed",))
    f_used, injected = injection_response(small, [300.0, 3e3, 1e4, 3e4], "sensed")
    injected_T = -injected / (1 + injected)
    exact_T = -small.response(f_used, "sensed") / (1 + small.response(f_used, "sensed"))
    check = pd.DataFrame({"f_Hz": f_used, "exact_dB": 20 * np.log10(np.abs(exact_T)),
                          "injected_dB": 20 * np.log10(np.abs(injected_T)),
                          "difference_dB": 20 * np.log10(np.abs(injected_T / exact_T)),
                          "difference_deg": np.degrees(np.angle(injected_T / exact_T))})
    rows = pd.DataFrame([
        {"quantity": "crossover (Hz)", "designed": 1e4, "measured (exact loop gain)": found.crossover_hz,
         "tolerance": "5 %", "result": "pass" if abs(found.crossover_hz / 1e4 - 1) <= 0.05 else "fail"},
        {"quantity": "phase margin (deg)", "designed": 60.0, "measured (exact loop gain)": found.phase_margin_deg,
         "tolerance": "3 deg", "result": "pass" if abs(found.phase_margin_deg - 60.0) <= 3.0 else "fail"}])
    agrees = bool((check["difference_dB"].abs() < 1e-2).all() and (check["difference_deg"].abs() < 0.1).all())
    values = ", ".join(f"{k} = {v:.6g} {'rad/s' if k == 'wi' else 'Hz'}" for k, v in design.compensator.as_dict().items()
                       if v)
    text = (f"<p>The default buck (12 V to 5 V, 100 uH, 100 uF, 10 ohm, 100 kHz) under <code>--control voltage-loop"
            f"</code>: a {design.compensator.kind} compensator designed by the k-factor method (Venable 1983) on the "
            f"exact control-to-output response at D = {design.duty:.6g} for a crossover of 10 kHz and 60 degrees "
            f"({values}). Measured on the closed loop's exact loop gain (Middlebrook's injection on the "
            "small-signal model about the periodic orbit):</p>" + table_html(rows, "result", good=("pass",))
            + f'<img src="{url("loop_gain.png")}" alt="loop gain before and after the compensator">'
            + "<p>The loop gain by a sinusoid injected at the comparator (each frequency simulated to its periodic "
              "steady state by the event method, its fundamental read) beside the exact one:</p>"
            + table_html(check))
    files = {"loop_gain.png": bode_figure(response, None, found, before=before),
             "loop_design.csv": csv_bytes(rows), "loop_check.csv": csv_bytes(check)}
    return Section("Control: a type III loop designed and measured", text, files,
                   ok=bool((rows["result"] == "pass").all()) and agrees,
                   metrics={"crossover_hz": found.crossover_hz, "phase_margin_deg": found.phase_margin_deg})


#: Report sections that are not scenes, per suite (the scenes come from validation/scenes/*.toml).
EXTRA_SECTIONS = {
    "default": [("LCP solvers: project problem set", lcp_project_section),
                ("LCP solvers: Siconos peer collection", lcp_peer_section),
                ("LCS time-stepping: convergence on the Siconos circuits", core_section),
                ("Converter library: steady state against closed forms", converter_section),
                ("Control: a type III loop designed and measured", control_section)],
}
GDCM_MAPS = [(f"Conduction modes: {name} D-K map", partial(gdcm_map_section, name)) for name in K_RANGES]
EXTRA_SECTIONS["default"] += GDCM_MAPS
EXTRA_SECTIONS["lcp"] = EXTRA_SECTIONS["default"][:2]
EXTRA_SECTIONS["gdcm"] = GDCM_MAPS


# --- the speed-accuracy trade-off and the stability map (pcsuite bench) ---------------------------------

TRADEOFF_TEXT = (
    "<p>Every method against the exact event-driven solution (exact flows per mode, root-found events, "
    "Newton on the exact period map), each run starting on the exact periodic orbit and covering the same "
    "{periods} periods. Errors are relative: mean vout, RMS of the (first) inductor current, and the "
    "timing of the diode events of the last period in units of T; the accuracy axis is the larger of the "
    "first two. Wall time is each method's own run (LCP: <code>simulate()</code> with its matrices; event: "
    "run plus exact quadrature; smoothing: the solve; ngspice: load plus <code>.tran</code>, timed in its "
    "worker). Acceptance per case: at the accuracy of ngspice's default (<code>.tran</code> TMAX = T/100, "
    "RELTOL 1e-3, trap) the fastest LCP run at least as accurate is 100 times faster or more, and the "
    "fastest event run below 1e-8 takes less time than that ngspice run.</p>")


def _sweep_size(sweep: dict) -> int:
    """Runs per case of a trade-off sweep (validation.tradeoff.FULL or QUICK), ngspice included."""
    return (len(sweep["thetas"]) * len(sweep["lcp_steps"]) + len(sweep["event_tols"]) + len(sweep["smooth"])
            + len(sweep["spice"]))


def tradeoff_form(runs: pd.DataFrame, meta: dict) -> str:
    """What a trade-off measurement covered, for the reader: its form (quick or full size) and its size."""
    from .tradeoff import CASES, FULL, PERIODS
    cases = list(dict.fromkeys(runs["case"]))
    per_case = int(runs.groupby("case").size().max()) if len(runs) else 0
    size = (f"{len(runs)} runs, {per_case} settings for each of {len(cases)} of the {len(CASES)} cases "
            f"({', '.join(cases)}), {meta.get('periods', 'an unknown number of')} periods each"
            + (", without ngspice" if meta.get("spice") is False else ""))
    full = (f"{len(CASES)} cases x {_sweep_size(FULL)} settings = {len(CASES) * _sweep_size(FULL)} runs of {PERIODS} "
            "periods")
    if meta.get("quick"):
        return (f"Quick form: {size}. <code>make bench</code> measures the full size ({full}) and the next report "
                "shows it.")
    return f"Full size: {size}."


def _default_trade_html(trade: pd.DataFrame) -> str:
    """The stepper's default theta at each step measured against the other theta at the same step."""
    if trade.empty:
        return ("<p>The stepper's default theta at each step: not in these runs (measured before the runs said "
                "which theta the default picks; the next <code>make bench</code> or report measures it).</p>")
    gains = trade["error_gain"].dropna() if "error_gain" in trade else pd.Series(dtype=float)
    costs = trade["time_cost"].dropna() if "time_cost" in trade else pd.Series(dtype=float)
    summary = (f"; at each step it is {gains.min():.3g} to {gains.max():.3g} times as accurate as the other theta at "
               f"the same step, in {costs.min():.2f} to {costs.max():.2f} times its time" if len(gains) and len(costs)
               else "")
    picked = ", ".join(f"theta {theta:g} at {count}" for theta, count in
                       trade["default_theta"].value_counts().sort_index().items())
    return ("<p>The stepper's default: theta 0.5 (second order) where the step resolves every time constant of the "
            "circuit's configurations, backward Euler (L-stable) where one is shorter, which the trapezoidal rule "
            "would ring on (a stiff node read 1.36 MV from a 10 V source). Here it picked " + picked + " of the "
            "steps" + summary + ".</p>" + table_html(trade))


def tradeoff_section(files: dict, meta: dict, source: str) -> Section:
    """The trade-off tables and Pareto plot from the files of :func:`validation.bench.collect_tradeoff`."""
    from .bench import read_csv
    from .tradeoff import default_trade, pareto_front
    runs = read_csv(files["tradeoff.csv"])
    accept = read_csv(files["tradeoff_acceptance.csv"])
    refs = read_csv(files["tradeoff_references.csv"])
    stiffness = read_csv(files["stiffness.csv"])
    front = pd.concat([pareto_front(g) for _, g in runs.groupby("case", sort=False)])
    columns = ["case", "family", "setting", "wall_s", "error", "err_mean_vout", "err_rms_iL", "err_event_T"]
    failed = runs[runs["failure"].astype(object).fillna("").astype(str) != ""]
    if meta.get("quick"):
        # the report's quick form judges what a loaded machine cannot change: an LCP run as accurate as ngspice's
        # default and an event run below 1e-8 exist; their speed-ups are measured here and judged by make bench
        found = [c for c in ("lcp_setting", "event_setting") if c in accept]
        ok = bool(len(accept)) and len(found) == 2 and bool(accept[found].notna().all().all())
        verdict = ("<p>Verdict of this quick form: accuracy only (per case an LCP run at least as accurate as "
                   "ngspice's default, and an event run below 1e-8); the speed-ups below are measured on this "
                   "machine under its load, and <code>make bench</code> checks them (LCP at least 100x ngspice's "
                   "default, the event method faster than it).</p>")
    else:
        ok = bool(len(accept)) and bool((accept["result"] == "pass").all())
        verdict = ""
    text = (f"<p>{source} {tradeoff_form(runs, meta)}</p>" + verdict
            + TRADEOFF_TEXT.format(periods=meta.get("periods", "the same"))
            + table_html(accept, "result", good=("pass",))
            + "<img src='tradeoff.png' alt='Pareto plot: error against wall time per case and method'>"
            + "<p>The exact references:</p>" + table_html(refs)
            + _default_trade_html(default_trade(runs))
            + "<p>Pareto front per case (runs no other run beats in both time and error):</p>"
            + table_html(front[[c for c in columns if c in front]])
            + f"<p>Failed runs: {len(failed)} of {len(runs)}" + (":" if len(failed) else ".") + "</p>"
            + (table_html(failed[["case", "family", "setting", "failure"]]) if len(failed) else "")
            + "<p>Smoothing (DCM buck, Radau, solver_rtol 1e-6): the largest Jacobian eigenvalue times T grows as "
              "1/eps, and with it the solver's work.</p>" + table_html(stiffness)
            + "<p>Every run: <a href='tradeoff.csv'>tradeoff.csv</a>; per case: "
              "<a href='tradeoff_acceptance.csv'>tradeoff_acceptance.csv</a>.</p>")
    trade = default_trade(runs)
    metrics = {"runs": len(runs), "failed_runs": len(failed), "acceptance": accept.to_dict(orient="records"),
               "default_trade": trade.to_dict(orient="records"),
               "date": meta.get("date", ""), "quick": bool(meta.get("quick")), "periods": meta.get("periods"),
               "cases": runs["case"].nunique()}
    return Section("Speed-accuracy trade-off", text, dict(files), ok=ok, metrics=metrics)


STABILITY_TEXT = (
    "<p>The buck converter (Vin 12 V, L 10 uH, C 100 uF, R 10 ohm, 100 kHz, D 0.4) pushed one parameter "
    "at a time to an extreme, every method run from rest for 10 periods (2 for h = 1e-6 T) in its own "
    "process with a 60 s limit. Checks: NaN or inf; divergence (stored energy above 10 times what was "
    "supplied); energy created (the scheme's own discrete energy balance, (E_end - E_0) - (E_in - E_load), "
    "above 1e-3 of the energy scale: ideal switches and diodes are lossless, a scheme may dissipate but "
    "must not create); failure to finish; errors (ngspice failures are counted here). Ill-posed requests "
    "are refused before any run with one line naming the parameter.</p>")

STABILITY_NOTE = (
    "<p>LCP theta = 0.5 imposes complementarity at the step end while its energy identity is taken at "
    "the mid-step state: a diode that switches inside a step does the work h x_mid' Q B lambda_k+1 "
    "(checked step by step to 1e-18 J). At h = T/2 this creates energy above the threshold; it falls as "
    "h^2 (see the residuals of the smaller steps in stability.csv). Backward Euler only dissipates.</p>")


def stability_section(files: dict, meta: dict, source: str) -> Section:
    """The stability map from the files of :func:`validation.bench.collect_stability`."""
    from .bench import read_csv
    table = read_csv(files["stability.csv"])
    counts = read_csv(files["stability_summary.csv"])
    refused = read_csv(files["ill_posed.csv"])
    lcp = table[table["method"].str.startswith("LCP")]
    lcp_finite = int((lcp["verdict"] == "NaN/inf").sum()) == 0 and int((lcp["status"] != "ok").sum()) == 0
    all_refused = bool(refused["refused"].astype(str).eq("True").all())
    ok = lcp_finite and all_refused
    flagged = table[table["verdict"] != "ok"]
    columns = ["vary", "value", "h", "method", "verdict", "energy_residual", "points", "wall_s", "error"]
    text = (f"<p>{source} The whole map: {len(table)} runs.</p>" + STABILITY_TEXT + table_html(counts)
            + f"<p>Runs not ok: {len(flagged)} of {len(table)}" + (":" if len(flagged) else ".") + "</p>"
            + (table_html(flagged[columns]) if len(flagged) else "") + STABILITY_NOTE
            + "<p>Ill-posed requests:</p>" + table_html(refused)
            + "<p>Every run: <a href='stability.csv'>stability.csv</a>.</p>")
    metrics = {"runs": len(table), "lcp_nan_inf": int((lcp["verdict"] == "NaN/inf").sum()),
               "ill_posed_refused": int(refused["refused"].astype(str).eq("True").sum()),
               "errors": int((table["verdict"] == "error").sum()), "date": meta.get("date", "")}
    return Section("Numerical stability at the extremes", text, dict(files), ok=ok, metrics=metrics)


def saved_bench_section(part: str) -> Section | None:
    """The newest saved ``pcsuite bench`` results of one part as a section, or None when there are none."""
    from .bench import DEFAULT_OUT, read_bench
    saved = read_bench(DEFAULT_OUT, part)
    if saved is None:
        return None
    files, meta = saved
    source = (f"Saved by pcsuite bench on {html.escape(str(meta.get('date', 'an unknown date')))} "
              f"(<code>{html.escape(str(DEFAULT_OUT))}</code>).")
    build = tradeoff_section if part == "tradeoff" else stability_section
    return build(files, meta, source)


def live_bench_section(part: str) -> Section:
    """The part measured now: the trade-off in its quick form, the stability map whole (98 runs of 10 periods from
    rest, each in its own process: about half a minute)."""
    from .bench import collect_stability, collect_tradeoff
    if part == "tradeoff":
        files, meta = collect_tradeoff(quick=True, progress=False)
    else:
        files, meta = collect_stability(progress=False)
    source = f"Measured for this report in {meta['wall_s']:.0f} s."
    return (tradeoff_section if part == "tradeoff" else stability_section)(files, meta, source)


def default_bench_section(part: str) -> Section:
    """The default report's section of one part, always measured: the trade-off from a full-size ``make bench``
    saved in reports/bench when there is one, else measured now in its quick form; the stability map measured now."""
    if part == "tradeoff":
        from .bench import DEFAULT_OUT, full_size, read_bench
        saved = read_bench(DEFAULT_OUT, part)
        if saved is not None and full_size(saved[1]):
            return saved_bench_section(part)
    return live_bench_section(part)


# The bifurcation study: alone in its suite it may use every core for its diagram; in the default suite the
# suite's own pool keeps them busy.
from .bifurcation import SECTION_TITLE as _BIFURCATION_TITLE, bifurcation_section  # noqa: E402

EXTRA_SECTIONS["bifurcation"] = [(_BIFURCATION_TITLE, partial(bifurcation_section, workers=None))]


def _mechanics(name: str, **options):
    """A section of the mechanical module (imported when the section runs)."""
    from . import mechanics
    return getattr(mechanics, name)(**options)


EXTRA_SECTIONS["mechanics"] = [
    ("Mechanics: the dry-friction oscillator's sliding bifurcations", partial(_mechanics, "sliding_section")),
    ("Mechanics: the degenerate switching-sliding bifurcation", partial(_mechanics, "degenerate_section")),
    ("Mechanics: the friction oscillator's domain of attraction", partial(_mechanics, "basins_section")),
    ("Mechanics: event-driven against Moreau-Jean and the closed forms", partial(_mechanics, "agreement_section")),
    ("Mechanics: the cam-follower's impact phases", partial(_mechanics, "cam_section")),
    ("Mechanics: past the end of complete chattering",
     has_quick_form(partial(_mechanics, "chattering_windows_section"))),
    ("Mechanics: continuation of periodic orbits and the corner-impact bifurcation",
     partial(_mechanics, "cam_continuation_section")),
    ("Mechanics: two blocks on a belt", has_quick_form(partial(_mechanics, "two_block_section")))]
EXTRA_SECTIONS["default"] += [(_BIFURCATION_TITLE, partial(bifurcation_section, workers=1))]
EXTRA_SECTIONS["default"] += [("Speed-accuracy trade-off", runs_alone(partial(default_bench_section, "tradeoff"))),
                              ("Numerical stability at the extremes", partial(default_bench_section, "stability"))]

from .thermal import TITLE as _THERMAL_TITLE, thermal_section  # noqa: E402

EXTRA_SECTIONS["default"] += [(_THERMAL_TITLE, thermal_section)]
EXTRA_SECTIONS["thermal"] = [(_THERMAL_TITLE, thermal_section)]
EXTRA_SECTIONS["bench"] = [("Speed-accuracy trade-off", runs_alone(partial(live_bench_section, "tradeoff"))),
                           ("Numerical stability at the extremes", partial(live_bench_section, "stability"))]
