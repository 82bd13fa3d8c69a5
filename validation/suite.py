"""Run the scenes of a suite (in parallel across processes, with a progress bar) and turn each into
a report section. A failing scene becomes a failed section with its reason; it never aborts the run.
"""
from __future__ import annotations

import math
import time
import traceback
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path

import numpy as np
import pandas as pd

from converters.models import analytic, get_converter
from converters.parallel import parallel_map
from netlists import SpiceOptions

from .compare import compare
from .defaults import passes
from .io import parquet_bytes
from .plots import comparison_plot, mode_timeline_plot
from .report import Section, esc, run_section, table_html, url
from .scenes import Scene, scenes_of
from .spice import close_spice_worker


@dataclass
class SceneResult:
    scene: Scene
    ok: bool
    reason: str = ""
    checks: list = field(default_factory=list)       # (check, value, threshold, pass)
    metrics: dict = field(default_factory=dict)
    gdcm: dict = field(default_factory=dict)
    files: dict = field(default_factory=dict)
    wall_s: float = 0.0
    accuracy: dict = field(default_factory=dict)     # the LCP side's, when the scene asks for an rtol
    notes: list = field(default_factory=list)        # what a reader must know (ngspice not settled, ...)


def run_scene(scene: Scene) -> SceneResult:
    start = time.perf_counter()
    try:
        result = _run_scene(scene)
    except Exception as exc:  # reported as the scene's failure, never fatal to the suite
        reason = "".join(traceback.format_exception_only(type(exc), exc)).strip()
        return SceneResult(scene, ok=False, reason=reason, wall_s=time.perf_counter() - start)
    result.wall_s = time.perf_counter() - start
    return result


def _run_scene(scene: Scene) -> SceneResult:
    """The scene's study (:data:`SCENE_RUNNERS`, by its control; a PWM converter's comparison otherwise)."""
    return SCENE_RUNNERS.get(scene.control, _run_pwm_scene)(scene)


def _scene_classes(conv, p: dict, c) -> dict:
    """A scene's conduction classes, each side's from its own intervals over the window with runs shorter than
    what the scene resolves (MIN_RUN_FRACTION of T, and the LCP's step where coarser) merged into their
    neighbours, and judged against the exact prediction by the gdcm command's rule
    (:func:`validation.gdcm.judge_held`). Classes and judgement take one resolution: a held interval shorter than
    what the classes see, judged at a finer one, is a disagreement neither side can show (a buck at R = 3.35 ohm,
    held 2.6e-3 of T)."""
    from converters.analysis.modes import held_fraction, mode_class, mode_intervals

    from .gdcm import exact_held, judge_held
    from .modes import MIN_RUN_FRACTION
    T = conv.period(p)
    t0, t1 = c.window_start, float(c.lcp.t[-1])
    periods = (t1 - t0) / T
    resolution = {"lcp": max(float(np.diff(c.lcp.t).max()) / T, MIN_RUN_FRACTION), "spice": MIN_RUN_FRACTION}
    # each LCP point carries the label of the step that ends there; ngspice's label holds from its point on
    intervals = {"lcp": mode_intervals(c.lcp.t, np.asarray(c.lcp.modes())[1:], t0, t1, T, MIN_RUN_FRACTION),
                 "spice": mode_intervals(c.spice.t, np.asarray(c.spice.modes()), t0, t1, T, MIN_RUN_FRACTION)}
    # the held class by the model's own label: DCM, or GDCM where the held pair keeps i1 = -i2 != 0 (Cuk)
    held = "GDCM" if conv.off_held_label.startswith("GDCM") else "DCM"
    # the exact prediction (from the matrices), as the gdcm command's: the small-ripple closed form had said CCM
    # at a buck's R = 3.327 ohm, DCM for 3.7e-5 of T, where gdcm said DISAGREE
    from converters.analysis.gdcm import exact_mode
    gdcm = {"K": analytic.k_factor(p, conv.name), "Kcrit": analytic.k_crit(p["D"], conv.name),
            "closed_form": held if analytic.predicted_mode(p, conv.name) == "DCM" else "CCM",
            "predicted": "CCM" if exact_mode(conv, p)["mode"] == "CCM" else held}
    for side, iv in intervals.items():
        gdcm[side] = "CCM" if mode_class(iv) == "CCM" else held
    gdcm["agree"] = gdcm["predicted"] == gdcm["lcp"] == gdcm["spice"]
    if not gdcm["agree"]:
        exact = exact_held(conv, p)
        sides = {side: (gdcm[side], held_fraction(iv, periods), resolution[side]) for side, iv in intervals.items()}
        gdcm["agree"], gdcm["notes"] = judge_held(gdcm["predicted"], exact, sides)
        gdcm["exact_held"] = exact
    return gdcm


def _run_pwm_scene(scene: Scene) -> SceneResult:
    conv = get_converter(scene.converter)
    c = compare(scene.converter, scene.params, periods=scene.run.get("periods"), window=scene.run.get("window"),
                h=scene.lcp.get("h"), theta=scene.lcp.get("theta"), spice_options=SpiceOptions(**scene.spice),
                start=scene.run.get("start"), thresholds=scene.checks, rtol=scene.lcp.get("rtol"))
    m = c.metrics
    checks = list(c.rows)
    gdcm = {}
    if conv.closed_form:
        p = c.params
        gdcm = _scene_classes(conv, p, c)
        checks.append(("gdcm_verdict", float(gdcm["agree"]), 1.0, gdcm["agree"]))
        if "closed_form_rel" in scene.checks:
            expected = analytic.conversion_ratio(p, conv.name) * p["Vin"]
            rel = abs(m["vout_mean_lcp_V"] / expected - 1.0)
            m["closed_form_V"] = expected
            checks.append(_check("closed_form_rel", rel, scene))
    files = {f"scenes/{scene.name}/lcp.parquet": _window(c.lcp, c.window_start),
             f"scenes/{scene.name}/spice.parquet": _window(c.spice, c.window_start),
             f"scenes/{scene.name}/overlay.png": comparison_plot(c),
             f"scenes/{scene.name}/modes.png": mode_timeline_plot(c.lcp.t, c.lcp.modes(), c.spice.t, c.spice.modes(),
                                                                  conv.period(c.params), scene.name),
             **_scope(scene, c, c.window_start)}
    ok = all(check[3] for check in checks)
    failed = [name for name, _, _, passed in checks if not passed]
    return SceneResult(scene, ok=ok, reason=("failed checks: " + ", ".join(failed)) if failed else "",
                       checks=checks, metrics=m, gdcm=gdcm, files=files,
                       accuracy=c.lcp.metadata.get("accuracy", {}), notes=list(c.notes) + gdcm.get("notes", []))


def _run_circuit_scene(scene: Scene) -> SceneResult:
    """A netlist's LCS against ngspice on the same file (validation.circuit_compare), with the scene's run,
    methods and thresholds."""
    from converters.models import Circuit

    from .circuit_compare import PERIODS, WINDOW, compare_circuit
    circuit = Circuit.from_netlist(scene.circuit)
    c = compare_circuit(circuit, scene.params, h=scene.lcp.get("h"),
                        spice_options=SpiceOptions(**scene.spice) if scene.spice else None,
                        start=scene.run.get("start"), periods=scene.run.get("periods", PERIODS),
                        window=scene.run.get("window", WINDOW), thresholds=scene.checks)
    period = circuit.period(c.params)
    if not math.isfinite(period):                   # the timeline shows the last tenth of the run in 3 parts
        period = (c.lcp.t[-1] - c.lcp.t[0]) / 30
    files = {f"scenes/{scene.name}/lcp.parquet": _window(c.lcp, c.window[0]),
             f"scenes/{scene.name}/spice.parquet": _window(c.spice, c.window[0]),
             f"scenes/{scene.name}/overlay.png": comparison_plot(c),
             f"scenes/{scene.name}/modes.png": mode_timeline_plot(c.lcp.t, c.lcp.modes(), c.spice.t, c.spice.modes(),
                                                                  period, scene.name),
             **_scope(scene, c, c.window[0])}
    checks = list(c.rows)
    failed = [name for name, _, _, passed in checks if not passed]
    return SceneResult(scene, ok=not failed, reason=("failed checks: " + ", ".join(failed)) if failed else "",
                       checks=checks, metrics=c.metrics, gdcm={}, files=files,
                       accuracy=c.lcp.metadata.get("accuracy", {}), notes=list(c.notes))


def _check(name, value, scene, label=None):
    """(label, value, threshold, pass) of the scene's threshold ``name``."""
    threshold = scene.checks[name]
    return (label or name, value, threshold, passes(name, value, threshold))


def _run_smc_scene(scene: Scene) -> SceneResult:
    from .smc import compare_smc, smc_checks, smc_plot
    t_end = scene.run.get("t_end", 30e-3)
    c = compare_smc(scene.params, t_end=t_end, h=scene.lcp.get("h"), spice_options=SpiceOptions(**scene.spice) if scene.spice else None)
    m = c.metrics
    checks = smc_checks(m, scene.checks, c.params, t_end)
    frame = c.lcp.waveforms()
    files = {f"scenes/{scene.name}/lcp.parquet": parquet_bytes(frame.iloc[::max(1, len(frame) // 200_000)]),
             f"scenes/{scene.name}/overlay.png": smc_plot(c),
             **_scope(scene, c, m["window_s"][0])}          # the measured window: the whole run is 3 MB a ms
    failed = [name for name, _, _, ok in checks if not ok]
    return SceneResult(scene, ok=not failed, reason=("failed checks: " + ", ".join(failed)) if failed else "",
                       checks=checks, metrics=m, files=files)


def _run_smc_implicit_scene(scene: Scene) -> SceneResult:
    from .smc import implicit_checks, implicit_metrics
    m, run = implicit_metrics(scene.params, t_end=scene.run.get("t_end", 30e-3), h=scene.lcp.get("h"))
    checks = implicit_checks(m, scene.checks)
    failed = [name for name, _, _, ok in checks if not ok]
    from .plots import png
    from .scope import of_trajectory, scope_files
    files = {f"scenes/{scene.name}/lcp.parquet": parquet_bytes(run.waveforms()),
             f"scenes/{scene.name}/waveforms.png": png(run.plot()),
             **scope_files(of_trajectory(run, title=f"Scene {scene.name}"), f"scenes/{scene.name}/scope.html")}
    return SceneResult(scene, ok=not failed, reason=("failed checks: " + ", ".join(failed)) if failed else "",
                       checks=checks, metrics=m, files=files)


#: The study of each scene kind other than a PWM converter's comparison: a netlist's, the sliding-mode boost's.
SCENE_RUNNERS = {"circuit": _run_circuit_scene, "smc": _run_smc_scene, "smc-implicit": _run_smc_implicit_scene}


def _scope(scene: Scene, c, t0: float) -> dict:
    """The scene's interactive scope over its compared window, ngspice beside pcsuite."""
    from .scope import of_comparison, scope_files
    return scope_files(of_comparison(c.lcp, c.spice, f"Scene {scene.name}: pcsuite against ngspice", t0=t0),
                       f"scenes/{scene.name}/scope.html")


def _window(tr, t0: float) -> bytes:
    """A run's waveforms from ``t0`` on (the window its comparison measures) as Parquet."""
    return parquet_bytes(tr.waveforms().iloc[tr.rows_between(t0, tr.t[-1])])


def scene_section(result: SceneResult) -> Section:
    s = result.scene
    title = f"Scene {s.name}"
    head = (f"<p>{esc(s.description)} Converter <code>{esc(s.converter)}</code>, parameters "
            f"<code>{esc(s.params or 'defaults')}</code>, scene file <code>"
            f"{esc(Path(s.path).name)}</code>; run time {result.wall_s:.2f} s.</p>")
    if not result.ok and not result.checks:
        return Section(title, head + f"<div class='failed-section'><b>Failed:</b> {esc(result.reason)}</div>",
                       ok=False, metrics={"error": result.reason}, reason=result.reason)
    checks = pd.DataFrame(result.checks, columns=["check", "value", "threshold", "pass"])
    checks["result"] = np.where(checks["pass"], "pass", "fail")
    verdict = ""
    if result.gdcm:
        g = result.gdcm
        verdict = (f"<p>Mode verdict: K = {g['K']:.4g}, Kcrit(D) = {g['Kcrit']:.4g}: predicted <b>{g['predicted']}</b>; "
                   f"detected LCP <b>{g['lcp']}</b>, ngspice <b>{g['spice']}</b> -> "
                   f"{'agree' if g['agree'] else 'DISAGREE'}.</p>")
    metrics = pd.DataFrame([(k, v) for k, v in result.metrics.items()], columns=["metric", "value"])
    base = f"scenes/{s.name}/"
    images = "".join(f"<img src='{url(base + name)}' alt='{esc(name[:-4])} {esc(s.name)}'>"
                     for name in ("overlay.png", "modes.png", "waveforms.png") if f"{base}{name}" in result.files)
    links = ", ".join(f"<a href='{url(base + name)}'>{label}</a>" for name, label in
                      (("scope.html", "interactive scope (zoom, cursors)"), ("lcp.parquet", "LCP (Parquet)"),
                       ("spice.parquet", "ngspice (Parquet)")) if f"{base}{name}" in result.files)
    notes = "".join(f"<p class='note'>Note: {esc(note)}</p>" for note in result.notes)
    body = (head + verdict + table_html(checks.drop(columns="pass"), "result", good=("pass",)) + notes
            + accuracy_html(result.accuracy) + images
            + "<details><summary>All metrics</summary>" + table_html(metrics) + "</details>"
            + f"<p>Waveforms: {links}.</p>")
    if not result.ok:
        body = f"<div class='failed-section'><b>Failed:</b> {esc(result.reason)}</div>" + body
    return Section(title, body, files=result.files, ok=result.ok, reason=result.reason,
                   metrics={"checks": {c[0]: {"value": c[1], "threshold": c[2], "pass": c[3]} for c in result.checks},
                            "gdcm": result.gdcm, "wall_s": result.wall_s})


def accuracy_html(accuracy: dict) -> str:
    """The LCP side's values with their error estimates, and the method and h chosen (accuracy on request)."""
    if not accuracy:
        return ""
    rows = [{"quantity": name, "value": f"{q['value']:.10g}", "error_estimate": q["error_estimate"],
             "relative": q["relative_error_estimate"]} for name, q in accuracy["quantities"].items()]
    rows += [{"quantity": f"{e['pair']} {e['kind']} (t/T)", "value": f"{e['time_T']:.10g}",
              "error_estimate": e["error_estimate_T"], "relative": e["error_estimate_T"]} for e in accuracy["events"]]
    how = (f"the stepper, theta {accuracy['theta']:g}, h = T/{accuracy['steps_per_period']}"
           if accuracy["steps_per_period"] else "the event method (exact flows)")
    verdict = "met" if accuracy["met"] else f"NOT met ({esc(accuracy['message'])})"
    return (f"<p>Accuracy on request: rtol {accuracy['rtol']:g} {verdict} by {how} in {accuracy['wall_s']:.3f} s "
            "(Richardson estimates from two steps, module converters.analysis.accuracy):</p>"
            + table_html(pd.DataFrame(rows)))


def _output_metric(metrics: dict, converter_key: str, suffix: str) -> float:
    """A comparison's metric of its output: a converter's ``vout_...`` key, else a netlist's first ``..._suffix``
    (its output's: the netlist comparison records vout first, under the file's output name, v(out))."""
    if converter_key in metrics:
        return metrics[converter_key]
    return next((v for k, v in metrics.items() if k.endswith(suffix) and isinstance(v, float)), float("nan"))


def scenes_summary(results: list[SceneResult]) -> Section:
    def ratio(m):
        if "runtime_ratio_spice_over_lcp" in m:
            return m["runtime_ratio_spice_over_lcp"]
        return m["spice_wall_s"] / m["lcp_wall_s"] if m.get("lcp_wall_s") and "spice_wall_s" in m else float("nan")
    # (a netlist scene's numbers are under its output's name, v(out): its columns were left empty)
    rows = [{"scene": r.scene.name, "converter": r.scene.converter, "result": "pass" if r.ok else "fail",
             "vout_lcp_V": _output_metric(r.metrics, "vout_mean_lcp_V", "_mean_lcp"),
             "vout_spice_V": _output_metric(r.metrics, "vout_mean_spice_V", "_mean_spice"),
             "rel_error": _output_metric(r.metrics, "vout_mean_rel_error", "_mean_rel_error"),
             "modes": r.metrics.get("mode_sequence_lcp", ""), "predicted": r.gdcm.get("predicted", ""),
             "spice/lcp time": ratio(r.metrics), "wall_s": r.wall_s, "reason": r.reason} for r in results]
    table = pd.DataFrame(rows)
    from .report import csv_bytes
    return Section("Scenes: LCP against ngspice", table_html(table, "result", good=("pass",)),
                   files={"scenes.csv": csv_bytes(table)}, ok=all(r.ok for r in results))


def _job(item):
    kind, payload = item
    if kind == "scene":
        return run_scene(payload)
    title, builder = payload
    return run_section(builder, title)


def _failed_job(item, message: str):
    """A job whose worker died or raised: a failed scene or section with the reason, never an abort."""
    kind, payload = item
    reason = f"worker failed: {message}"
    return (SceneResult(payload, ok=False, reason=reason) if kind == "scene"
            else Section(payload[0], f"<p>{esc(reason)}</p>", ok=False))


def run_suite(suite: str, sections=(), workers: int = 2, progress: bool = True, scenes=None, full: bool = False):
    """Run the suite's scenes (or ``scenes``, loaded by :func:`validation.scenes.load_scenes`: a user's files)
    and extra report sections in parallel processes (each job's ngspice worker shut down after it), then the
    sections marked :func:`validation.report.runs_alone` one at a time, each in its own process; results in
    input order. A section with a quick form (:func:`validation.report.has_quick_form`) runs it, or its full size
    with ``full``."""
    scenes = scenes_of(suite) if scenes is None else list(scenes)
    alone = [False] * len(scenes) + [getattr(builder, "runs_alone", False) for _, builder in sections]
    sections = [(title, partial(builder, full=full) if getattr(builder, "quick_form", False) else builder)
                for title, builder in sections]
    jobs = [("scene", s) for s in scenes] + [("section", sec) for sec in sections]
    results: list = [None] * len(jobs)
    for last, options in ((False, {"workers": workers, "label": f"suite {suite}"}),
                          (True, {"workers": 1, "tasks_per_process": 1, "label": f"suite {suite}, timed alone"})):
        where = [i for i, marked in enumerate(alone) if marked == last]
        if where:
            done = parallel_map(_job, [jobs[i] for i in where], progress=progress, unit="job",
                                finalize=close_spice_worker, on_lost=_failed_job, **options)
            for i, result in zip(where, done):
                results[i] = result
    scene_results = [r for (kind, _), r in zip(jobs, results) if kind == "scene"]
    section_results = [r for (kind, _), r in zip(jobs, results) if kind == "section"]
    return scene_results, section_results


__all__ = ["run_suite", "run_scene", "scene_section", "scenes_summary", "SceneResult"]
