"""The mechanical studies: what ``pcsuite mech`` and the report's ``mechanics`` suite show.

* Sliding bifurcations of the dry-friction oscillator along a parameter: the orbit's period is read at the
  path's ends (brute force), its branch followed by the continuation on the event method's exact map, and
  each change of the orbit's events named by :func:`converters.analysis.sliding.classify_sliding`.
* Brute-force diagrams: the friction oscillator's x(nT) against omega (Moreau-Jean: compiled, and the
  attractor is what a diagram shows), the two-block system's section where block 1 starts to stick against
  the belt velocity, the cam-follower's impact phases against its speed.
* Cross-checks: the event method against Moreau-Jean (stick intervals, impact times) as h -> 0, the
  bouncing ball's accumulation against its closed form, the cam's detachment against k c + m c'' = 0.

Nothing here integrates or shoots: every run is ``simulate`` or a method's period map, every orbit the
continuation's (the mechanical module reuses the core and the bifurcation tools).
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from converters.analysis.bifurcation import brute_force, detect_period, iterate, section_diagram
from converters.analysis.continuation import OrbitFamily, check_path, follow
from converters.analysis.sliding import TYPES, classify_sliding
from converters.errors import ParameterError
from converters.methods import EventDriven, MoreauJean
from converters.models.mechanics import accumulation_time, get_mechanical
from converters.run import ParameterPath
from converters.simulate import simulate

#: Continuation settings for the event method's maps (accurate to its ODE tolerance, 1e-9): Newton to 1e-8
#: (scaled), bifurcations bracketed to 1e-7, d F / d p by a forward difference of relative step 1e-5.
CONTINUATION = {"tol": 1e-8, "locate_tol": 1e-7, "fd_step": 1e-5}


def _mechanical_path(model, params: dict, name: str, start: float, stop: float) -> ParameterPath:
    spec = {p.name: p for p in model.parameters}
    if name not in spec:
        raise ParameterError(f"--param must name a parameter of {model.key} ({', '.join(spec)}); got {name!r}")
    p = spec[name]
    check_path(name, start, stop, p.low, p.high, p.low_open, p.high_open)
    return ParameterPath(model, model.resolve(params), name)


def orbit_period(path, value: float, x0, *, warm_up: int = 300, record: int = 48, max_period: int = 8) -> tuple[int, np.ndarray]:
    """(period in forcing periods (0: none up to max_period), a state on the attractor) at ``value``: the event
    method's stroboscopic map iterated from x0."""
    from dataclasses import replace
    problem = path(value)
    one = EventDriven().period_map(replace(problem, t_span=(problem.t_span[0], problem.t_span[0] + problem.period)))
    x = np.array(x0, dtype=float)
    for _ in range(warm_up):
        x = one.end(x)
    samples = []
    for _ in range(record):
        samples.append(x)
        x = one.end(x)
    period = detect_period(np.array(samples), 1e-6)
    return (period if period <= max_period else 0), x


@dataclass
class SlidingStudy:
    model: object
    params: dict
    name: str
    start: float
    stop: float
    branches: list = field(default_factory=list)
    notes: list = field(default_factory=list)
    wall_s: float = 0.0

    @property
    def bifurcations(self) -> list:
        found = sorted((b for br in self.branches for b in br.bifurcations), key=lambda b: b.value)
        unique = []
        for b in found:                  # a point found from both ends of the path is one point
            if not any(u.kind == b.kind and abs(u.value - b.value) <= 1e-6 * (1 + abs(b.value)) for u in unique):
                unique.append(b)
        return unique

    def to_dict(self) -> dict:
        return {"model": self.model.name, "param": self.name, "start": self.start, "stop": self.stop,
                "params": self.params, "method": "event",
                "bifurcations": [{**b.to_dict(), "sliding": b.kind in TYPES} for b in self.bifurcations],
                "branches": [{"period": br.period, "orbits": len(br.points),
                              "from": float(br.values().min()) if br.points else None,
                              "to": float(br.values().max()) if br.points else None,
                              "complete": br.complete, "message": br.message} for br in self.branches],
                "notes": self.notes, "wall_s": self.wall_s}


def sliding_study(model_name: str, params: dict | None, name: str, start: float, stop: float, *,
                  max_period: int = 8, points: int = 40) -> SlidingStudy:
    """The sliding bifurcations of the model's periodic orbit along ``name`` from ``start`` to ``stop``."""
    model = get_mechanical(model_name)
    if not model.periodic(model.resolve(params)):
        raise ParameterError(f"sliding bifurcations of periodic orbits need a forced model (a forcing period); "
                             f"{model.key} is autonomous: use its diagram (pcsuite mech diagram)")
    path = _mechanical_path(model, params or {}, name, start, stop)
    study = SlidingStudy(model, path.params, name, start, stop)
    clock = time.perf_counter()
    x_rest = np.zeros(len(model.state_names))
    ends = []
    for value in (start, stop):
        period, x = orbit_period(path, value, x_rest, max_period=max_period)
        ends.append((value, period, x))
        study.notes.append(f"at {name} = {value:g} the attractor has " + (f"period {period}" if period else
                           f"no period up to {max_period}"))
    periodic = [end for end in ends if end[1]]
    if not periodic:
        study.notes.append("no periodic orbit at either end of the path: nothing to follow")
        study.wall_s = time.perf_counter() - clock
        return study
    first = periodic[0]
    other = stop if first[0] == start else start
    family = OrbitFamily(path, EventDriven(), first[1], classify=classify_sliding)
    max_step = abs(stop - start) / points
    branch = follow(family, first[0], other, first[2], warm_up=0, max_step=max_step, **CONTINUATION)
    study.branches.append(branch)
    reached = branch.points and abs(branch.values()[-1] - other) <= 1e-9 * (1 + abs(other))
    if not reached and len(periodic) == 2:
        # The branch ended inside the path (a non-smooth fold, say): follow the other end's orbit back to it.
        back = follow(OrbitFamily(path, EventDriven(), periodic[1][1], classify=classify_sliding), periodic[1][0],
                      first[0], periodic[1][2], warm_up=0, max_step=max_step, **CONTINUATION)
        study.branches.append(back)
    study.wall_s = time.perf_counter() - clock
    return study


# --- diagrams -------------------------------------------------------------------------------------------

def friction_diagram(params: dict | None, name: str, values, *, h_fraction: float = 1e-3, transient: int = 150,
                     record: int = 48, workers: int | None = None, progress: bool = False):
    """The friction oscillator's x(nT) after the transient at each value (Moreau-Jean, h = T h_fraction)."""
    model = get_mechanical("friction")
    path = ParameterPath(model, model.resolve(params), name)
    T = model.period(path.resolve(values[0]))
    return brute_force(path, MoreauJean(h=T * h_fraction), values, np.zeros(2), transient=transient, record=record,
                       workers=workers, progress=progress)


def two_block_diagram(params: dict | None, name: str, values, *, transient: float = 60.0, record: float = 60.0,
                      workers: int | None = None, progress: bool = False):
    """The two-block system on the section where block 1 starts to stick (the event method), against ``name``."""
    model = get_mechanical("stick-slip")
    p = model.resolve(params)
    path = ParameterPath(model, p, name)
    return section_diagram(path, EventDriven(), values, model.problem(p, 1.0).x0, kind="stick", pair=0,
                           transient=transient, record=record, unit=model.time_scale(p), workers=workers,
                           progress=progress)


def impact_phase_diagram(params: dict | None, values, *, transient: float = 20.0, record: float = 20.0,
                         h_fraction: float | None = None, workers: int | None = None, progress: bool = False):
    """The cam-follower's impact phases (fractions of the cam's period) against rpm: the event method, or
    Moreau-Jean with h = T h_fraction."""
    model = get_mechanical("cam-follower")
    p = model.resolve(params)
    path = ParameterPath(model, p, "rpm")
    method = EventDriven() if h_fraction is None else MoreauJean(h=model.period(p) * h_fraction)
    return section_diagram(path, method, values, model.problem(p, 1.0).x0, kind="impact", pair=0,
                           transient=transient, record=record, workers=workers, progress=progress)


def lyapunov_of_flow(model_name: str, params: dict | None, *, span_units: float = 1.0, transient: int = 60,
                     record: int = 200) -> float:
    """The largest Lyapunov exponent of an autonomous model's flow, per time unit: the event method's exact
    map over ``span_units`` time units iterated with its Jacobians (:func:`converters.analysis.bifurcation.iterate`)."""
    model = get_mechanical(model_name)
    p = model.resolve(params)
    unit = model.time_scale(p)
    period_map = EventDriven().period_map(model.problem(p, span_units * unit))
    _, exponent = iterate(period_map, model.problem(p, 1.0).x0, transient, record, True)
    return exponent / span_units


# --- cross-checks -----------------------------------------------------------------------------------------

def ball_check(params: dict | None = None) -> dict:
    """The bouncing ball: the event method's accumulation time against sqrt(2H/g)(1 + 2e/(1 - e)), each impact's
    velocity ratio against -e, and Moreau-Jean's penetration and settling time as h shrinks."""
    model = get_mechanical("bouncing-ball")
    p = model.resolve(params)
    exact = accumulation_time(p["H"], p["g"], p["e"])
    problem = model.problem(p, 1.5 * exact)
    run = simulate(problem, EventDriven())
    events = run.events
    chatter = events.loc[events["kind"] == "chatter", "time"].to_numpy()
    impacts = events.loc[events["kind"] == "impact", "time"].to_numpy()
    # A flight between impacts takes 2 v+ / g: successive flight times have the ratio of the rebound velocities,
    # which Newton's law makes e.
    flights = np.diff(impacts)
    ratios = flights[1:] / flights[:-1] if flights.size > 1 else np.empty(0)
    moreau = []
    for h in (1e-3, 1e-4, 1e-5):
        mj = simulate(problem, MoreauJean(h=h))
        moving = np.flatnonzero(np.abs(mj.x[:, 1]) > 1e-9)
        moreau.append({"h": h, "penetration": float(-min(mj.x[:, 0].min(), 0.0)),
                       "settled_at": float(mj.t[moving[-1] + 1]) if moving.size else 0.0})
    return {"closed_form_s": exact, "event_accumulation_s": float(chatter[0]) if chatter.size else float("nan"),
            "relative_error": float(abs(chatter[0] / exact - 1.0)) if chatter.size else float("inf"),
            "impacts_before_accumulation": int(impacts.size),
            "restitution_from_flights": ratios[:10].tolist(),
            "restitution_max_error": float(np.abs(ratios - p["e"]).max()) if ratios.size else float("nan"),
            "moreau": moreau}


def stick_intervals(run, T: float, t_from: float) -> list[tuple[float, float]]:
    """(start, end) of each stick of friction pair 0 after t_from, as fractions of T from t_from."""
    events = run.events
    events = events[(events["pair"] == 0) & (events["time"] >= t_from)]
    out, start = [], None
    for row in events.itertuples():
        if row.kind == "stick":
            start = row.time
        elif row.kind == "slip" and start is not None:
            out.append(((start - t_from) / T, (row.time - t_from) / T))
            start = None
    return out


def friction_agreement(params: dict | None = None, steps=(500, 2000, 8000, 32000)) -> dict:
    """The event method's periodic orbit (its stick intervals) against Moreau-Jean's at h = T / steps, started on
    the exact orbit and read after 50 periods: the largest difference of a stick's start or end, in periods."""
    from converters.analysis.periodic import shoot
    model = get_mechanical("friction")
    p = model.resolve(params or {"A": 5.0, "omega": 2.5})
    T = model.period(p)
    problem = model.problem(p, T)
    orbit = shoot(problem, EventDriven(), warm_up=100, tol=1e-10)
    exact = stick_intervals(simulate(model.problem(p, 2 * T, orbit.x0), EventDriven()), T, T)
    rows = []
    for count in steps:
        run = simulate(model.problem(p, 51 * T, orbit.x0), MoreauJean(h=T / count))
        found = stick_intervals(run, T, 50 * T)
        if len(found) != len(exact):
            rows.append({"steps_per_period": count, "sticks": len(found), "max_error_T": float("inf")})
            continue
        error = max(max(abs(a[0] - b[0]), abs(a[1] - b[1])) for a, b in zip(found, exact))
        rows.append({"steps_per_period": count, "sticks": len(found), "max_error_T": error})
    return {"params": p, "exact": exact, "rows": rows, "orbit": orbit.x0.tolist(), "period_s": T}


def cam_checks(params: dict | None = None, periods: int = 3) -> dict:
    """The cam-follower from rest on the cam: the first detachment against the first zero of k c + m c''
    (the cam's deceleration beyond the spring), and the first impacts of the event method against Moreau-Jean's."""
    from scipy.optimize import brentq
    model = get_mechanical("cam-follower")
    p = model.resolve(params)
    T = model.period(p)
    run = simulate(model.problem(p, periods * T), EventDriven())
    events = run.events
    detach = events.loc[events["kind"] == "detach", "time"].to_numpy()
    grid = np.linspace(0.0, T, 20001)
    margin = model.detachment_margin(p, grid)
    k = int(np.flatnonzero((margin[:-1] >= 0) & (margin[1:] < 0))[0])
    zero = brentq(lambda t: float(model.detachment_margin(p, t)), grid[k], grid[k + 1], xtol=1e-15)
    # The first impacts after the detachment, well apart (a chattering cluster follows them, whose bounces a
    # time-stepper merges at a coarse h): each against Moreau-Jean's nearest impact.
    impacts = events.loc[events["kind"] == "impact", "time"].to_numpy()[:3]
    rows = []
    for fraction in (1e-3, 2.5e-4, 6.25e-5):
        mj = simulate(model.problem(p, periods * T), MoreauJean(h=T * fraction))
        hits = mj.events.loc[mj.events["kind"] == "impact", "time"].to_numpy()
        errors = [np.abs(hits - t_hit).min() for t_hit in impacts] if hits.size else [np.inf]
        rows.append({"h_fraction": fraction, "impacts_compared": len(impacts), "max_error_T": float(max(errors) / T)})
    return {"params": p, "first_detachment_s": float(detach[0]) if detach.size else float("nan"),
            "margin_zero_s": zero, "detachment_error_s": float(abs(detach[0] - zero)) if detach.size else float("inf"),
            "first_impacts_s": impacts.tolist(), "moreau": rows}
