"""The bifurcation study of a converter along one parameter: what ``pcsuite bifurcation`` and the report's
``bifurcation`` suite show.

Data flow: the model and its parameters give a :class:`~converters.run.ParameterPath` (value -> problem);

* the continuation (:mod:`converters.analysis.continuation`, the event method: exact maps, saltation
  Jacobians) follows the period-1 orbit over the path and every period-doubled orbit born where one loses
  stability, up to ``max_period``, locating each bifurcation;
* the brute-force diagram (:mod:`converters.analysis.bifurcation`, the compiled stepper by default)
  samples the attractor at ``points`` values, in parallel;
* the cross-checks: the diagram's attractors against the exact stable orbits at the same values (two
  methods, one answer), and ngspice's orbit at one value against the event method's.

The model declares which state the diagram shows (``output_state``); nothing here knows the circuit.
"""
from __future__ import annotations

import html
import time
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from converters.analysis.bifurcation import aperiodic_onset, brute_force, period_windows
from converters.analysis.continuation import OrbitFamily, cascade, check_path
from converters.errors import ParameterError
from converters.methods.event import EventDriven
from converters.models import Model, get_model
from converters.models.path import ParameterPath
from converters.validate import parse_value

from .defaults import BIFURCATION, PUBLISHED_BIFURCATIONS, THRESHOLDS

#: The universal Feigenbaum constant (ratio of successive period-doubling intervals in the limit).
FEIGENBAUM_DELTA = 4.669201609


def parse_path(text: str) -> tuple[str, float, float]:
    """``NAME=START:STOP`` (values with SPICE suffixes) -> (name, start, stop)."""
    name, sep, span = str(text).partition("=")
    start, colon, stop = span.partition(":")
    if not sep or not colon or not name.strip():
        raise ParameterError(f"--param takes NAME=START:STOP (e.g. --param Vin=20:36); got {text!r}")
    return name.strip(), parse_value(f"{name.strip()} (path start)", start.strip()), \
        parse_value(f"{name.strip()} (path stop)", stop.strip())


@dataclass
class Study:
    """The outcome of :func:`run_study`."""

    model: Model
    params: dict
    name: str
    start: float
    stop: float
    branches: list
    attractors: list | None
    continuation_s: float
    diagram_s: float
    diagram_method: str
    state: str
    checks: dict = field(default_factory=dict)

    @property
    def bifurcations(self) -> list:
        return sorted((b for branch in self.branches for b in branch.bifurcations), key=lambda b: (b.value, b.period))

    def doublings(self) -> list:
        """The period doublings where an orbit loses stability, in path order."""
        return [b for b in self.bifurcations if b.kind == "period-doubling" and b.stable_before != b.stable_after]

    def feigenbaum(self) -> dict:
        """Ratios of successive doubling intervals and the cascade's accumulation point estimated from the last
        two doublings with the universal delta."""
        values = sorted(b.value for b in self.doublings())
        if len(values) < 2:
            return {}
        gaps = np.diff(values)
        ratios = (gaps[:-1] / gaps[1:]).tolist()
        return {"doublings": values, "ratios": ratios,
                "accumulation": values[-1] + gaps[-1] / (FEIGENBAUM_DELTA - 1.0)}

    def state_index(self) -> int:
        return list(self.model.state_names).index(self.state)

    def diagram_summary(self) -> dict:
        if self.attractors is None:
            return {}
        return {"points": len(self.attractors), "method": self.diagram_method, "wall_s": self.diagram_s,
                "aperiodic_onset": aperiodic_onset(self.attractors), "windows": period_windows(self.attractors),
                "errors": sum(bool(a.error) for a in self.attractors), "unconfirmed": self.unconfirmed()}

    def unconfirmed(self) -> list[dict]:
        """The diagram's values whose period is not that of the orbit the continuation (the exact method) holds
        stable there, where it holds one: [{value, period, stable_period}]. The stepper's map at T/500 may carry
        an attractor the circuit does not have (the voltage-mode buck at Vin = 30 V from the previous value: period
        6 at T/500 and T/1000, where the exact method and the stepper at T/250 and T/2000 settle on the period-2
        orbit the continuation holds stable over 24.517..31.118 V). A value near a bifurcation, where the
        transient is slow, may be listed too; a coexisting attractor would be, and is worth a look."""
        stable = [(b["period"], lo, hi) for b in (branch_summary(branch) for branch in self.branches)
                  for lo, hi in b["stable"]]
        out = []
        for a in self.attractors or []:
            holding = [period for period, lo, hi in stable if lo < a.value < hi]
            if not a.error and holding and a.period not in holding:
                out.append({"value": float(a.value), "period": int(a.period), "stable_period": int(holding[0])})
        return out

    def to_dict(self) -> dict:
        out = {"converter": self.model.name, "control": self.model.control, "param": self.name, "start": self.start,
               "stop": self.stop, "params": self.params, "method": "event", "state": self.state,
               "bifurcations": [b.to_dict() for b in self.bifurcations],
               "branches": [branch_summary(b) for b in self.branches],
               "feigenbaum": self.feigenbaum(), "wall_s": {"continuation": self.continuation_s}}
        if self.attractors is not None:
            out["diagram"] = self.diagram_summary()
            out["wall_s"]["diagram"] = self.diagram_s
        if self.checks:
            out["checks"] = self.checks
        return out


def branch_summary(branch) -> dict:
    """Period, extent, stable stretches (ending at the located bifurcations where stability changes, not at the
    last stable orbit computed) and why it stopped early (if it did)."""
    changes = sorted([b.value for b in branch.bifurcations if b.stable_before != b.stable_after]
                     + ([branch.parent.value] if branch.parent is not None else []))
    stretches, current = [], None
    points = sorted(branch.points, key=lambda pt: pt.value)
    for previous, pt in zip([None] + points[:-1], points):
        if pt.stable and current is None:
            crossed = [v for v in changes if previous is not None and previous.value <= v <= pt.value]
            current = [crossed[-1] if crossed else pt.value, pt.value]
        elif pt.stable:
            current[1] = pt.value
        elif current is not None:
            crossed = [v for v in changes if previous.value <= v <= pt.value]
            current[1] = crossed[0] if crossed else current[1]
            stretches.append(current)
            current = None
    if current is not None:
        stretches.append(current)
    values = branch.values()
    return {"period": branch.period, "orbits": len(branch.points),
            "from": float(values.min()) if values.size else None, "to": float(values.max()) if values.size else None,
            "stable": stretches, "born_at": branch.parent.value if branch.parent is not None else None,
            "complete": branch.complete, "message": branch.message}


def diagram_method(model: Model, params: dict, theta: float | None = None, steps: int | None = None,
                   key: str = "lcp"):
    """The brute-force diagram's method: a ``step`` method at theta = 0.5 (second order, where it takes a theta)
    and T / 500 steps (defaults.toml); an exact one sampled once a period."""
    from converters.methods.base import get_method
    cls = get_method(key)
    T = model.period(params)
    if not cls.fixed_step:
        return cls.from_options(step=T)
    options = {"theta": theta or BIFURCATION["diagram_theta"]} if "theta" in cls.option_names() else {}
    return cls.from_options(step=T / (steps or BIFURCATION["diagram_steps"]), **options)


def run_study(converter: str, control: str, params: dict | None, name: str, start: float, stop: float, *,
              max_period: int = 8, points: int = 800, transient: int = 200, record: int = 64,
              diagram: str = "lcp", state: str | None = None, workers: int | None = None, progress: bool = False,
              max_step: float | None = None) -> Study:
    """Continuation (the event method) and the brute-force diagram (``diagram``: ``lcp``, the compiled stepper,
    or ``event``) of ``converter`` under ``control`` along ``name`` from ``start`` to ``stop``; ``points = 0``
    skips the diagram."""
    model = get_model(converter, control)
    base = model.resolve(params)
    if not model.periodic(base):
        raise ParameterError(f"bifurcation analysis follows orbits of the stroboscopic map: {model.key} has no fixed "
                             "switching period")
    spec = {p.name: p for p in model.parameters}
    name = getattr(model, "parameter_name", str)(name)
    if name not in spec:
        raise ParameterError(f"--param must name a parameter of {model.key} ({', '.join(spec)}); got {name!r}")
    p = spec[name]
    check_path(name, start, stop, p.low, p.high, p.low_open, p.high_open)
    for value in (start, stop):
        model.resolve({**base, name: value})      # e.g. a VL path that crosses VU: one clear line
    for key, count, low in (("max_period", max_period, 1), ("points", points, 0), ("transient", transient, 0),
                            ("record", record, 2)):
        if not (isinstance(count, (int, np.integer)) and count >= low):
            raise ParameterError(f"{key} must be an integer >= {low}; got {count!r}")
    from converters.sweeps.ensemble import sweep_methods
    if diagram not in sweep_methods():
        raise ParameterError(f"the diagram's method must be {' or '.join(sweep_methods())}; got {diagram!r}")
    if points:
        from converters.limits import check_memory
        # each value keeps its recorded period starts (and the list of attractors its summaries): 4 copies
        check_memory(f"the brute-force diagram: {points} values x {record} recorded periods",
                     4.0 * points * (record * len(model.state_names) * 8 + 2000), remedy="fewer --points or --record")
    state = state or model.output_state
    if state not in model.state_names:
        raise ParameterError(f"state must be one of {', '.join(model.state_names)}; got {state!r}")
    path = ParameterPath(model, base, name)
    clock = time.perf_counter()
    family = OrbitFamily(path, EventDriven(), 1)
    x_start = np.array(path(start).x0, dtype=float)          # the model's own start (a current loop: iL at half the command)
    branches = cascade(family, start, stop, x_start, max_period=max_period, max_step=max_step)
    continuation_s = time.perf_counter() - clock
    attractors, diagram_s, label = None, 0.0, ""
    if points:
        T = model.period(base)
        method = diagram_method(model, base, key=diagram)
        from dataclasses import replace as _replace
        one = path(start)          # each value is one run of transient + record periods: refuse it here, not per value
        method.check_memory(_replace(one, t_span=(one.t_span[0], one.t_span[0] + (transient + record) * T)),
                             remedy="fewer --transient or --record periods")
        label = (f"{method.key} {method.label}, h = T/{round(T / method.step)}" if method.step
                 else f"{method.key} (exact)")
        # Every chunk starts on the operating point: the first orbit of the continuation (from rest, a start-up
        # transient can wander for hundreds of periods: transient chaos).
        seed = branches[0].points[0].x0 if branches[0].points else x_start
        clock = time.perf_counter()
        attractors = brute_force(path, method, np.linspace(start, stop, points), seed, transient=transient,
                                 record=record, workers=workers, progress=progress)
        diagram_s = time.perf_counter() - clock
    return Study(model, base, name, start, stop, branches, attractors, continuation_s, diagram_s, label, state)


def branch_agreement(study: Study, every: int = 10, guard: float | None = None) -> dict:
    """The diagram's attractors against the exact stable orbits at the same parameter values: at every
    ``every``-th diagram value whose attractor has the period of a stable stretch of a branch (and which is
    farther than ``guard`` from every bifurcation, where convergence slows), the exact orbit is solved by Newton
    from the branch and compared with the attractor's samples (each sample to its nearest orbit point).
    Returns the largest distance, relative to 1 + |x|, and how many values were compared."""
    if not study.attractors:
        return {}
    guard = guard if guard is not None else 0.01 * abs(study.stop - study.start)
    marks = np.array([b.value for b in study.bifurcations] or [np.inf])
    worst, compared = 0.0, 0
    for attractor in study.attractors[::every]:
        if attractor.error or attractor.period == 0 or np.abs(marks - attractor.value).min() < guard:
            continue
        for branch in study.branches:
            family = OrbitFamily(ParameterPath(study.model, study.params, study.name), EventDriven(), branch.period)
            values = branch.values()
            if branch.period != attractor.period or not values.size or not values.min() <= attractor.value <= values.max():
                continue
            nearest = branch.points[int(np.argmin(np.abs(values - attractor.value)))]
            if not nearest.stable:
                continue
            orbit = family.orbit(attractor.value, nearest.x0, tol=1e-12)
            if not orbit.converged:
                continue
            exact = family.point(attractor.value, orbit.x0, orbit.jacobian).samples
            gaps = np.abs(attractor.samples[:, None, :] - exact[None, :, :]).max(axis=2).min(axis=1)
            worst = max(worst, float(gaps.max() / (1.0 + np.abs(exact).max())))
            compared += 1
            break
    return {"values_compared": compared, "max_rel_distance": worst}


def spice_orbit(study_params: dict, converter: str, control: str, name: str, value: float, periods: int,
                window: int, tmax_fraction: float, state: str | None = None) -> dict:
    """ngspice from rest at ``name = value`` for ``periods`` switching periods, against the event method.

    ngspice's samples of ``state`` at the last ``window`` period starts are split into p phases; its period is
    the p (up to 8) whose largest spread within a phase is below a quarter of every shorter p's (ngspice's
    own jitter, from switchings that are not breakpoints, stays). The event method's orbit of that period
    (from rest over the same periods, then Newton) is aligned in phase and compared point by point."""
    from netlists import SpiceOptions, model_netlist

    from .spice import run_spice
    model = get_model(converter, control)
    p = model.resolve({**study_params, name: value})
    T = model.period(p)
    state = state or model.output_state
    netlist = model_netlist(model, p, periods * T, SpiceOptions(tmax_fraction=tmax_fraction))
    result = run_spice(netlist)
    times = T * np.arange(periods - window, periods)
    samples = np.interp(times, result.time, result.signal(netlist.probes[state]))
    # Period of ngspice's samples: the p (up to 8) whose phase means leave the smallest spread within phases.
    best = None
    for period in range(1, 9):
        phases = [samples[i::period] for i in range(period)]
        spread = max(float(np.ptp(ph)) for ph in phases)
        if best is None or spread < 0.25 * best[1]:
            best = (period, spread, [float(np.mean(ph)) for ph in phases])
    period, spread, means = best
    path = ParameterPath(model, study_params, name)
    family = OrbitFamily(path, EventDriven(), period)
    one = family.period_map(value, 1)
    x = np.zeros(len(model.state_names))
    for _ in range(periods):
        x = one.end(x)
    orbit = family.orbit(value, x, tol=1e-12)
    exact = family.point(value, orbit.x0, orbit.jacobian).samples[:, list(model.state_names).index(state)]
    # Align the phases (ngspice's window starts at an arbitrary phase of the orbit).
    shifts = [np.abs(np.roll(exact, -s) - np.array(means)).max() for s in range(period)]
    exact = np.roll(exact, -int(np.argmin(shifts)))
    rel = float(np.abs(np.array(means) / exact - 1.0).max())
    return {"value": value, "state": state, "spice_period": period, "spice_samples": means, "spice_spread": spread,
            "event_period": period, "event_samples": exact.tolist(), "event_converged": bool(orbit.converged),
            "max_rel_difference": rel, "spice_wall_s": result.wall_s, "spice_steps": result.accepted_steps,
            "tmax_fraction": tmax_fraction, "periods": periods, "window": window}


# --- the picture ----------------------------------------------------------------------------------------

_MARKERS = {"period-doubling": ("o", "#c44e52"), "fold": ("s", "#8172b2"), "neimark-sacker": ("D", "#ccb974"),
            "border-collision": ("^", "#dd8452")}
_COLOURS = ["#4c72b0", "#55a868", "#8172b2", "#dd8452", "#64b5cd", "#937860"]


def _engineering(value: float, unit: str) -> str:
    from matplotlib.ticker import EngFormatter
    return EngFormatter(unit=unit, places=None, sep=" ")(value).strip() if unit else f"{value:g}"


def _zoom_range(study: Study):
    """The end of the period-doubling cascade: from before the third-last doubling to past the aperiodic onset."""
    doublings = sorted(b.value for b in study.doublings())
    if len(doublings) < 3:
        return None
    onset = aperiodic_onset(study.attractors) if study.attractors else None
    width = doublings[-1] - doublings[-3]
    return doublings[-3] - 0.1 * width, max(onset or doublings[-1], doublings[-1]) + 0.3 * width


def _draw(ax, study: Study, i: int, legend: bool) -> None:
    if study.attractors:
        xs = np.concatenate([np.full(a.samples.shape[0], a.value) for a in study.attractors if not a.error])
        ys = np.concatenate([a.samples[:, i] for a in study.attractors if not a.error])
        ax.plot(xs, ys, ".", ms=1.2, color="0.45", alpha=0.5, rasterized=True,
                label=f"brute force ({study.diagram_method})" if legend else None)
    for branch in study.branches:
        colour = _COLOURS[int(np.log2(branch.period)) % len(_COLOURS)]
        values = branch.values()
        if values.size < 2:
            continue
        stable = np.array([pt.stable for pt in branch.points])
        samples = np.array([pt.samples[:, i] for pt in branch.points])       # (points, k)
        # A segment is drawn solid when both its ends are stable, dashed otherwise.
        solid = stable[:-1] & stable[1:]
        for m in range(branch.period):
            for flag, style, width in ((True, "-", 1.2), (False, "--", 0.8)):
                y = samples[:, m].copy()
                keep = np.zeros(values.size, dtype=bool)
                segments = solid if flag else ~solid
                keep[:-1] |= segments
                keep[1:] |= segments
                y[~keep] = np.nan
                ax.plot(values, y, style, color=colour, lw=width,
                        label=f"period {branch.period}, {'stable' if flag else 'unstable'}" if legend and m == 0 else None)
    onset = aperiodic_onset(study.attractors) if study.attractors else None
    if onset is not None:
        ax.axvline(onset, color="0.3", ls=":", lw=1, label=f"aperiodic from {onset:.4g} (brute force)" if legend else None)
    for b in study.bifurcations:
        marker, colour = _MARKERS[b.kind]
        ax.plot([b.value], [b.x0[i]], marker, color=colour, ms=6, mec="k", mew=0.6, zorder=5,
                label=f"{b.kind} at {b.value:.5f} (period {b.period})" if legend else None)


def diagram_figure(study: Study, fmt: str = "png") -> bytes:
    """The brute-force diagram (grey dots), the continuation branches over it (stable solid, unstable dashed,
    one colour per period), the bifurcations (markers, listed in the legend) and the brute-force aperiodic
    onset, with a zoom on the end of the period-doubling cascade when there is one; PNG or SVG bytes."""
    import io

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    spec = {p.name: p for p in study.model.parameters}
    i = study.state_index()
    zoom = _zoom_range(study)
    fig, axes = plt.subplots(1, 2 if zoom else 1, figsize=(13 if zoom else 9, 5.5), squeeze=False,
                             gridspec_kw={"width_ratios": [3, 2]} if zoom else None)
    _draw(axes[0, 0], study, i, legend=True)
    if zoom:
        ax = axes[0, 1]
        _draw(ax, study, i, legend=False)
        ax.set_xlim(*zoom)
        # Vertical range: the orbits inside the zoom (the chaotic spread beyond would squeeze the cascade).
        inside = [pt.samples[:, i] for b in study.branches for pt in b.points if zoom[0] <= pt.value <= zoom[1]]
        if inside:
            low, high = float(np.min([v.min() for v in inside])), float(np.max([v.max() for v in inside]))
            pad = 0.15 * (high - low + 1e-12)
            ax.set_ylim(low - pad, high + pad)
        ax.set_title("the end of the period-doubling cascade", fontsize=9)
    unit = spec[study.name].unit
    state_unit = {"i": "A", "v": "V"}.get(study.state[:1].lower(), "")
    for ax in axes[0]:
        ax.set_xlabel(f"{study.name} ({unit})" if unit else study.name)
        ax.set_ylabel(f"{study.state}(nT) ({state_unit})" if state_unit else f"{study.state}(nT)")
        ax.ticklabel_format(useOffset=False, style="plain")
        ax.grid(alpha=0.3)
    fixed = ", ".join(f"{k} = {_engineering(v, spec[k].unit)}" for k, v in study.params.items() if k != study.name)
    fig.suptitle(f"{study.model.title}: {study.state} at the period starts against {study.name}\n{fixed}", fontsize=9)
    axes[0, 0].legend(fontsize=7, loc="upper left", framealpha=0.9)
    buffer = io.BytesIO()
    fig.savefig(buffer, format=fmt, dpi=120, bbox_inches="tight")
    plt.close(fig)
    return buffer.getvalue()


# --- the report section ------------------------------------------------------------------------------------

def bifurcation_table(study: Study) -> pd.DataFrame:
    rows = []
    for b in study.bifurcations:
        rows.append({"type": b.kind, "value": f"{b.value:.6f}", "period": b.period,
                     "multipliers": ", ".join(f"{m.real:.4f}{m.imag:+.4f}j" if abs(m.imag) > 1e-9 else f"{m.real:.4f}"
                                              for m in b.multipliers),
                     "stability below -> above": f"{'stable' if b.stable_before else 'unstable'} -> "
                                                 f"{'stable' if b.stable_after else 'unstable'}",
                     "bracket": f"{b.width:.1e}", "located by": b.located_by, "detail": b.detail})
    return pd.DataFrame(rows)


def published_checks(study: Study) -> list[tuple]:
    """(check, value, published, |difference|, pass) against the literature."""
    limit = THRESHOLDS["bifurcation"]["published_abs"]
    doublings = [b.value for b in study.doublings()]
    onset = aperiodic_onset(study.attractors) if study.attractors else None
    rows = []
    for label, value, published in (("first period doubling (V)", doublings[0] if doublings else None,
                                     PUBLISHED_BIFURCATIONS["first_doubling"]),
                                    ("second period doubling (V)", doublings[1] if len(doublings) > 1 else None,
                                     PUBLISHED_BIFURCATIONS["second_doubling"]),
                                    ("aperiodic from (brute force, V)", onset, PUBLISHED_BIFURCATIONS["chaos"])):
        ok = value is not None and abs(value - published) <= limit
        rows.append((label, value, published, None if value is None else abs(value - published), ok))
    return rows


SECTION_TITLE = (f"Bifurcations: {BIFURCATION['converter']} --control {BIFURCATION['control']} along "
                 f"{BIFURCATION['param']}")


def bifurcation_section(workers: int | None = 1):
    """The default study (defaults.toml [bifurcation]) with its checks: published values, the diagram on the exact
    branches, ngspice's period-2 orbit. ``workers``: processes for the diagram (1 inside a suite whose own pool
    keeps the cores busy)."""
    from .report import Section, csv_bytes, table_html
    cfg = BIFURCATION
    study = run_study(cfg["converter"], cfg["control"], dict(cfg["params"]), cfg["param"], cfg["start"], cfg["stop"],
                      max_period=cfg["max_period"], points=cfg["points"], transient=cfg["transient"],
                      record=cfg["record"], workers=workers)
    checks = published_checks(study)
    agreement = branch_agreement(study)
    spice = spice_orbit(study.params, cfg["converter"], cfg["control"], cfg["param"], cfg["spice_value"],
                        cfg["spice_periods"], cfg["spice_window"], cfg["spice_tmax_fraction"])
    th = THRESHOLDS["bifurcation"]
    check_rows = [{"check": label, "value": "none" if value is None else f"{value:.4f}", "reference": f"{published:g}",
                   "|difference|": diff, "limit": th["published_abs"], "result": "pass" if ok else "fail"}
                  for label, value, published, diff, ok in checks]
    check_rows.append({"check": "diagram on the exact stable orbits (rel.)",
                       "value": f"{agreement.get('max_rel_distance', float('nan')):.2e}", "reference": "0", "|difference|": agreement.get("max_rel_distance"),
                       "limit": th["diagram_branch_rel"],
                       "result": "pass" if agreement.get("values_compared") and agreement["max_rel_distance"]
                       <= th["diagram_branch_rel"] else "fail"})
    spice_ok = spice["spice_period"] == 2 and spice["max_rel_difference"] <= th["spice_orbit_rel"]
    check_rows.append({"check": f"ngspice period-2 orbit at {cfg['param']} = {cfg['spice_value']:g} (rel.)",
                       "value": f"{spice['max_rel_difference']:.2e}", "reference": "0",
                       "|difference|": spice["max_rel_difference"], "limit": th["spice_orbit_rel"],
                       "result": "pass" if spice_ok else "fail"})
    table = pd.DataFrame(check_rows)
    feigenbaum = study.feigenbaum()
    summary = study.diagram_summary()
    windows = []
    for w in summary["windows"]:                  # stretches of 3 values or more, neighbours of one period merged
        if w["count"] < 3:
            continue
        if windows and windows[-1]["period"] == w["period"]:
            windows[-1].update(last=w["last"], count=windows[-1]["count"] + w["count"])
        else:
            windows.append(dict(w))
    windows = pd.DataFrame([{"period": w["period"], "from": f"{w['first']:.3f}", "to": f"{w['last']:.3f}",
                             "values": w["count"]} for w in windows])
    branches = pd.DataFrame([{"period": s["period"], "orbits": s["orbits"], "from": f"{s['from']:.4f}",
                              "to": f"{s['to']:.4f}", "stable": "; ".join(f"{a:.4f} to {b:.4f}" for a, b in s["stable"]),
                              "born at": "" if s["born_at"] is None else f"{s['born_at']:.6f}",
                              "complete": s["complete"], "message": s["message"]}
                             for s in (branch_summary(b) for b in study.branches)])
    spec = {p.name: p for p in study.model.parameters}
    fixed = ", ".join(f"{k} = {_engineering(v, spec[k].unit)}" for k, v in study.params.items() if k != study.name)
    text = (f"<p>{html.escape(study.model.title)} along {study.name} from {study.start:g} to {study.stop:g} "
            f"(parameters: {html.escape(fixed)}). "
            "Continuation: pseudo-arclength on the event method's exact stroboscopic map (state-transition and "
            "saltation matrices), every period doubling where an orbit loses stability followed onto the "
            f"period-doubled branch up to period {cfg['max_period']}, in {study.continuation_s:.1f} s. "
            f"Brute force: {summary['points']} values, {cfg['transient']} periods dropped and {cfg['record']} kept "
            f"at each ({study.diagram_method}), in {study.diagram_s:.1f} s.</p>"
            + table_html(table, "result", good=("pass",))
            + "<img src='bifurcation_diagram.png' alt='bifurcation diagram'>"
            + "<h3>Bifurcations</h3>" + table_html(bifurcation_table(study))
            + (f"<p>Feigenbaum: successive doubling intervals shrink by {', '.join(f'{r:.3f}' for r in feigenbaum['ratios'])} "
               f"(the universal limit is {FEIGENBAUM_DELTA:.4f}); the cascade accumulates near "
               f"{feigenbaum['accumulation']:.4f} (extrapolated from the last two doublings).</p>" if feigenbaum.get("ratios") else "")
            + "<h3>Branches</h3>" + table_html(branches)
            + "<h3>Periods seen by the brute-force diagram</h3><p>Stretches of at least 3 values (a value next to a "
              "bifurcation converges slowly and may show no period); period 0: no period "
              f"up to {cfg['record'] // 2} (chaotic, or not settled next to a bifurcation).</p>" + table_html(windows)
            + f"<h3>ngspice at {cfg['param']} = {cfg['spice_value']:g}</h3><p>From rest, {cfg['spice_periods']} periods, "
              f"TMAX = T/{round(1 / cfg['spice_tmax_fraction'])}: {study.state}(nT) over the last {cfg['spice_window']} "
              f"periods has period {spice['spice_period']} (spread within each phase {spice['spice_spread']:.2g}): "
              f"{', '.join(f'{v:.5f}' for v in spice['spice_samples'])} against the event method's "
              f"{', '.join(f'{v:.5f}' for v in spice['event_samples'])}.</p>")
    files = {"bifurcation_diagram.png": diagram_figure(study),
             "bifurcations.csv": csv_bytes(bifurcation_table(study)),
             "branches.csv": csv_bytes(pd.concat([b.to_frame(study.model.state_names) for b in study.branches],
                                                 ignore_index=True))}
    ok = bool((table["result"] == "pass").all())
    metrics = {**study.to_dict(), "branch_agreement": agreement, "spice": spice}
    return Section(SECTION_TITLE, text, files, ok=ok, metrics=metrics)
