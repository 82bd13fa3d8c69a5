"""The impacting models' studies: the cam-follower's chattering (complete and incomplete, the ends of complete
chattering located), its orbits continued in cam speed with their corner impacts and grazings, its impact phases
against the speed, and the cross-checks (the cam's detachment against k c + m c'' = 0, the event method's impacts
against Moreau-Jean's, the bouncing ball's accumulation against its closed form).
"""
from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from converters.analysis.bifurcation import section_diagram
from converters.analysis.continuation import OrbitFamily, follow, locate_condition
from converters.analysis.periodic import multipliers_of
from converters.errors import SimulationError
from converters.methods import EventDriven, MoreauJean
from converters.models.mechanics import accumulation_time, get_mechanical
from converters.models.path import ParameterPath
from converters.simulate import simulate

from .orbits import CONTINUATION


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


@dataclass(frozen=True)
class _Chattering:
    """At one cam speed, after ``transient`` revolutions, over ``record`` more (the event method): impacts and
    completed accumulations per revolution (picklable, for a process pool)."""

    params: dict
    transient: int = 10
    record: int = 10

    def __call__(self, rpm: float) -> dict:
        model = get_mechanical("cam-follower")
        p = model.resolve({**self.params, "rpm": rpm})
        T = model.period(p)
        events = simulate(model.problem(p, (self.transient + self.record) * T), EventDriven()).events
        events = events[events["time"] >= self.transient * T]
        impacts = int((events["kind"] == "impact").sum())
        completed = int((events["kind"] == "chatter").sum())
        regime = ("no impacts" if impacts == 0 else "complete chattering" if completed >= self.record
                  else "incomplete chattering" if completed == 0 else "mixed")
        return {"rpm": rpm, "impacts_per_revolution": impacts / self.record,
                "accumulations_per_revolution": completed / self.record, "regime": regime}


def chattering_table(params: dict | None, speeds, workers: int | None = None):
    """Complete chattering (each revolution's impacts accumulate, the event method completing them in closed
    form), incomplete (impacts that do not accumulate before the next lift), or none, at each cam speed."""
    import pandas as pd

    from converters.parallel import parallel_map
    return pd.DataFrame(parallel_map(_Chattering(dict(params or {})), list(speeds), workers=workers))


def _detachment(model, p: dict) -> float:
    """The first instant of a revolution where k c + m c'' falls through zero: a follower riding the cam leaves it
    there (the cam decelerates faster than the spring can follow)."""
    from scipy.optimize import brentq
    T = model.period(p)
    grid = np.linspace(0.0, T, 20001)
    margin = model.detachment_margin(p, grid)
    k = int(np.flatnonzero((margin[:-1] >= 0) & (margin[1:] < 0))[0])
    return brentq(lambda t: float(model.detachment_margin(p, t)), grid[k], grid[k + 1], xtol=1e-15)


def chattering_orbit(params: dict | None, rpm: float, revolutions: int = 1) -> dict:
    """The orbit through the cam's detachment that completes a chattering sequence within ``revolutions`` cam
    revolutions, if it does: from the detachment (where k c + m c'' falls through zero, the follower riding the cam
    leaves it) the follower flies and impacts the cam, in sequences cut short by the next lift (incomplete) until
    one accumulates (the event method completes it in closed form); it then rides the cam to a detachment, where its
    state is the cam's again. So it is periodic without shooting, of n revolutions (n the revolution whose
    detachment ends that ride), and superstable: every perturbation is erased at the accumulation (its Floquet
    multipliers are zero). Returns ``n`` (None where no sequence accumulates by the last revolution, or the ride ends
    at another phase), ``impacts`` before the ride, ``ride``: the fraction of a revolution ridden between the
    accumulation and that detachment (its test function: where it reaches zero the accumulation misses the
    detachment and the orbit ends), ``detachment``: the detachment's phase."""
    model = get_mechanical("cam-follower")
    p = model.resolve({**(params or {}), "rpm": rpm})
    T = model.period(p)
    t_d = _detachment(model, p)
    c, c1, _ = model.offset(p).position(t_d)
    run = simulate(model.problem(p, t_d + (revolutions + 0.5) * T, np.array([float(c), float(c1)]), t_start=t_d),
                   EventDriven())
    times, kinds = run.events["time"].to_numpy(), list(run.events["kind"])
    detached = [t for t, kind in zip(times, kinds) if kind == "detach" and t > t_d + 1e-9 * T]
    end = detached[0] if detached else np.inf
    accumulated = [t for t, kind in zip(times, kinds) if kind == "chatter" and t < end]
    n = round((end - t_d) / T) if detached else None
    periodic = bool(accumulated and n and abs(end - (t_d + n * T)) <= 1e-9 * T)
    impacts = sum(1 for t, kind in zip(times, kinds) if kind == "impact" and t < end)
    return {"rpm": rpm, "detachment": t_d / T, "n": n if periodic else None, "impacts": impacts,
            "ride": (end - accumulated[-1]) / T if periodic else None}


def ride_left(params: dict | None, rpm: float) -> dict:
    """The period-one complete-chattering orbit at ``rpm`` (:func:`chattering_orbit` of one revolution): ``ride``
    None where its impacts have not accumulated before the next detachment."""
    return chattering_orbit(params, rpm, revolutions=1)


def chattering_transition(params: dict | None, low: float, high: float, tol: float = 1e-9) -> dict:
    """The cam speed between ``low`` and ``high`` where the period-one complete-chattering orbit
    (:func:`ride_left`) ends: its ride left reaches zero (the accumulation reaches the next detachment), located
    from the side where it exists by :func:`converters.analysis.sliding.approach_zero` to ``tol`` (relative)."""
    from converters.analysis.sliding import approach_zero
    ends = [ride_left(params, low), ride_left(params, high)]
    exists = [end["ride"] is not None for end in ends]
    if exists[0] == exists[1]:
        raise SimulationError(f"the period-one complete-chattering orbit {'exists' if exists[0] else 'is absent'} at "
                              f"both {low:g} and {high:g} rpm: no transition between them to locate")
    start, bound = (ends[0], high) if exists[0] else (ends[1], low)

    def evaluate(rpm):
        row = ride_left(params, rpm)
        return None if row["ride"] is None else (row["ride"], row)
    value, width, points, trials = approach_zero(evaluate, (start["rpm"], start["ride"], start), bound, tol)
    last = points[-1][2]
    return {"rpm": float(value), "width": float(width), "last": last, "runs": trials + 2,
            "side": "below" if exists[0] else "above"}


@dataclass(frozen=True)
class _Accumulating:
    """:func:`chattering_orbit` at one speed (picklable, for a process pool)."""

    params: dict
    revolutions: int

    def __call__(self, rpm: float) -> dict:
        return chattering_orbit(self.params, rpm, self.revolutions)


def chattering_windows(params: dict | None, values, revolutions: int = 8, tol: float = 1e-9,
                       workers: int | None = None) -> dict:
    """The superstable orbits of :func:`chattering_orbit` (one accumulation per n revolutions) followed in cam
    speed over ``values``, and the borders between their windows located. Past the end of complete chattering the
    follower does not settle into incomplete chattering at once: a sequence cut by the lift leaves it nearly on the
    cam and a later revolution's sequence completes, so orbits of n = 2, 3, ... revolutions per accumulation
    follow, in windows. Where n changes between neighbours of the grid an end of each side's orbit is approached
    from its grid speed by :func:`converters.analysis.sliding.approach_zero` on the orbit's ride (to ``tol``,
    relative): where the ride falls to zero the orbit ends (its accumulation reaches a detachment); where it stays
    finite the bracket still closes (the ride steep there, or the orbit ending otherwise: ``ride`` says which).
    The ride is not monotone (its sequences gain and lose impacts as the speed changes), so the orbit need not
    exist at every speed between its grid speed and the end found. ``rows``: each grid speed's orbit;
    ``borders``: rpm, width, n, side (of the border the orbit lies on), ride, impacts."""
    from converters.analysis.sliding import approach_zero
    from converters.parallel import parallel_map
    params = dict(params or {})
    rows = parallel_map(_Accumulating(params, revolutions), [float(v) for v in values], workers=workers)
    borders = []
    for a, b in zip(rows, rows[1:]):
        if a["n"] == b["n"]:
            continue
        for known, other in ((a, b), (b, a)):
            if known["n"] is None:
                continue

            def evaluate(rpm, n=known["n"]):
                row = chattering_orbit(params, rpm, n)
                return None if row["n"] != n else (row["ride"], row)
            value, width, points, _ = approach_zero(evaluate, (known["rpm"], known["ride"], known), other["rpm"], tol)
            last = points[-1][2]
            borders.append({"rpm": float(value), "width": float(width), "n": known["n"],
                            "side": "below" if known is a else "above", "ride": float(last["ride"]),
                            "impacts": last["impacts"]})
    return {"rows": rows, "borders": borders}


def cam_family(params: dict | None, revolutions: int = 1, phase: float = 0.0) -> OrbitFamily:
    """The cam-follower's orbits of ``revolutions`` cam revolutions as a family in the cam speed (rpm), on the event
    method's map from the instant ``phase`` (a fraction of a revolution: away from the orbit's impacts, so Newton's
    trial states do not cross the cam at the map's start): its Jacobian the variational equations with each
    impact's saltation matrix (exact for orbits whose impacts do not accumulate)."""
    model = get_mechanical("cam-follower")
    base = model.resolve(params)

    def problem_of(rpm):
        p = dict(base, rpm=float(rpm))
        T = model.period(p)
        return model.problem(p, (1.0 + phase) * T, t_start=phase * T)
    return OrbitFamily(problem_of, EventDriven(), periods=revolutions)


def incomplete_orbit(settings: Mapping[str, Any], params: dict | None = None):
    """The incomplete-chattering orbit of ``settings`` (the report's: ``[mechanics.incomplete]``; m impacts in n
    revolutions, none accumulating), seeded from the attractor ``warm_up`` revolutions after rest at ``start`` rpm
    and continued down in cam speed towards the end of complete chattering with its Floquet multipliers (exact:
    impact saltation matrices), until it ends (``max_points`` orbits). Returns (family, branch)."""
    model = get_mechanical("cam-follower")
    family = cam_family(params, settings["revolutions"], settings["phase"])
    p = model.resolve({**(params or {}), "rpm": settings["start"]})
    T = model.period(p)
    seed = simulate(model.problem(p, (settings["warm_up"] + settings["phase"]) * T), EventDriven()).x[-1]
    branch = follow(family, settings["start"], settings["stop"], seed, warm_up=0, tol=CONTINUATION["tol"],
                    locate_tol=CONTINUATION["locate_tol"], fd_step=1e-6, max_step=settings["max_step"],
                    max_points=settings["max_points"])
    return family, branch


def incomplete_across(settings: Mapping[str, Any], params: dict | None = None):
    """An incomplete-chattering orbit of one revolution continued through the end of complete chattering
    (``settings``, the report's ``[mechanics.across]``): seeded at ``start`` rpm by the flight that leaves the cam at the
    detachment (its state one revolution on, at the map's start ``after_detachment`` revolutions past the
    detachment), Newton's shooting, then pseudo-arclength continuation down to ``low`` and up until it ends at a
    border collision (the grazing where an impact appears), with its exact multipliers (impact saltation). Its
    sequence is cut by the lift at the detachment every revolution, on both sides of the end of complete chattering.
    Going down, its last impact reaches the cam's flank-nose joint, where the cam lifts away (the detachment is at
    that joint): a corner impact, located from the branch's last orbit by :func:`corner_impact` (the corrector
    creeps next to it). Returns (family, branch: its orbits in increasing speed and the bifurcations of both
    directions, [CornerImpact]).
    """
    from converters.analysis.continuation import Branch
    from converters.models.mechanics.cam import JOINTS

    model = get_mechanical("cam-follower")
    p = model.resolve({**(params or {}), "rpm": settings["start"]})
    T = model.period(p)
    t_d = _detachment(model, p)
    phase = t_d / T + settings["after_detachment"]
    family = cam_family(params, 1, phase)
    c, c1, _ = model.offset(p).position(t_d)
    seed = simulate(model.problem(p, (1.0 + phase) * T, np.array([float(c), float(c1)]), t_start=t_d),
                    EventDriven()).x[-1]
    options = {"warm_up": 0, "tol": CONTINUATION["tol"], "locate_tol": CONTINUATION["locate_tol"],
               "fd_step": settings["fd_step"], "max_step": settings["max_step"], "max_points": settings["max_points"]}
    down = follow(family, settings["start"], settings["low"], seed, **options)
    if not down.points:
        raise SimulationError(f"no incomplete-chattering orbit at {settings['start']:g} rpm: {down.message}")
    up = follow(family, settings["start"], settings["high"], seed, stop_at="border-collision", **options)
    branch = Branch(1, down.points[::-1] + up.points[1:], down.bifurcations + up.bifurcations,
                    "; ".join(m for m in (down.message, up.message) if m))
    last = down.points[-1]
    angles = impact_angles(family, last.value, last.x0)
    joint = min(JOINTS, key=lambda name: abs(JOINTS[name] - angles[-1]))
    return family, branch, [corner_impact(family, joint, angles.size - 1, last.value, last.x0)]


def least_clearance(family: OrbitFamily, rpm: float, x0) -> float:
    """The least local minimum of the gap x - c(t) (m) along the flight after the orbit's last impact, to the
    map's end (inf where the gap only grows): the event method's dense solution, sampled at T/20,000 and its
    minimum refined by the parabola through the three samples around it."""
    model = get_mechanical("cam-follower")
    problem = family.problem_of(rpm)
    t0, t1 = problem.t_span
    impacts = family.event_times(rpm, x0, "impact")
    start = impacts[-1] if impacts.size else t0
    tr = simulate(problem, EventDriven(output_step=(t1 - t0) / 20_000), x0=x0)
    rows = tr.t > start
    t = tr.t[rows]
    gap = tr.x[rows, 0] - model.offset(dict(model.resolve({}), rpm=float(rpm))).position(t)[0]
    slope = np.diff(gap)
    minima = np.flatnonzero((slope[:-1] < 0) & (slope[1:] >= 0)) + 1
    if not minima.size:
        return np.inf
    i = minima[np.argmin(gap[minima])]
    a, b, c = gap[i - 1], gap[i], gap[i + 1]
    return float(b - 0.125 * (c - a) ** 2 / (a - 2 * b + c)) if a - 2 * b + c > 0 else float(b)


def locate_grazing(family: OrbitFamily, branch, grazing, offsets=(2e-4, 1e-4)) -> tuple[float, list]:
    """The grazing where the branch's border collision is, located as the cam speed where the least clearance of
    the flight after the last impact reaches zero, extrapolated linearly (a smooth minimum's value moves linearly
    with the parameter) from the orbits ``offsets`` rpm below the bracket's lower end. The bracket itself is where
    the event method first sees the touch, which it does within its event tolerance of the cam (2e-5 rpm early
    here, where the clearance is 2e-9 m). Returns (rpm, [(rpm, clearance in m)])."""
    low = grazing.value - 0.5 * grazing.width
    near = min(branch.points, key=lambda pt: abs(pt.value - low))
    x, seen = near.x0, []
    for offset in offsets:
        rpm = low - offset
        orbit = family.orbit(rpm, x)
        if not orbit.converged:
            raise SimulationError(f"the orbit at {rpm:.7f} rpm below the grazing was not found: {orbit.message}")
        x = orbit.x0
        seen.append((rpm, least_clearance(family, rpm, x)))
    (r1, g1), (r2, g2) = seen[-2:]
    return float(r2 - g2 * (r2 - r1) / (g2 - g1)), seen


def impact_angles(family: OrbitFamily, rpm: float, x0) -> np.ndarray:
    """The cam angle beta (rad, in [0, 2 pi)) of each impact of the orbit from x0 at ``rpm``, in time order."""
    return get_mechanical("cam-follower").cam_angle({"rpm": rpm}, family.event_times(rpm, x0, "impact"))


@dataclass(frozen=True)
class CornerImpact:
    """An impact of a continued orbit reaching a joint of the cam profile (where h_c'' jumps): the orbit there,
    located as (x0, rpm) with the orbit's residual and the impact's angle off the joint, and the orbits either side
    of the joint at ``offset`` rpm from it (their multipliers: a corner collision changes the map's Jacobian, not its
    value)."""

    joint: str
    angle: float
    impact: int
    rpm: float
    x0: np.ndarray
    residual: float
    off_joint: float
    offset: float
    #: [(rpm, x0, multipliers, impact angle)] of the orbits found at rpm +- offset (the angle NaN where the orbit
    #: has no such impact: it vanished past the joint).
    sides: tuple
    #: "nonsmooth fold" when two orbits lie on one side of the corner in rpm and none on the other (they meet at
    #: the corner and vanish together), "persistence" when the orbit crosses it, else "undetermined".
    kind: str
    #: The orbit's period in cam revolutions (n of P(m, n)).
    revolutions: int = 1


def locate_corner(family: OrbitFamily, joint: float, impact: int, rpm: float, x0,
                  tol: float = 1e-11) -> tuple[float, np.ndarray, float, float]:
    """(rpm, x0, residual, angle off the joint) of the orbit whose impact number ``impact`` hits the profile at
    ``joint`` (rad), from a nearby orbit: :func:`converters.analysis.continuation.locate_condition` with the impact's
    angle minus the joint's. The angle is a C1 function of (x0, rpm) through the corner (the impact time depends on
    the cam's position and velocity, which are smooth there)."""
    return locate_condition(family, lambda value, x: float(impact_angles(family, value, x)[impact]) - joint, rpm, x0,
                            tol=tol)


def corner_impacts(family: OrbitFamily, branch, offset: float = 1e-3, near: float = 1e-3) -> list:
    """Every corner impact on a continued branch: where an impact's angle passes a joint of the profile
    (:data:`converters.models.mechanics.cam.JOINTS`) between consecutive orbits, or where the branch stopped with
    an impact within ``near`` rad of one (the corrector cannot pass a corner where the branch turns), located by
    :func:`locate_corner`. Its kind from the orbits at ``offset`` rpm either side of it (Newton from the corner
    orbit, then from points beyond it on the line through the orbit found, for the other side of the joint): two
    on one side and none on the other is a nonsmooth fold; one on each side, the orbit persisting through it."""
    from converters.models.mechanics.cam import JOINTS
    points = branch.points
    angles = [impact_angles(family, pt.value, pt.x0) for pt in points]
    starts = []
    for a, angles_a, angles_b in zip(points, angles, angles[1:]):
        for name, joint in JOINTS.items():
            starts += [(name, joint, i, a) for i, (before, after) in enumerate(zip(angles_a, angles_b))
                       if (before - joint) * (after - joint) < 0.0 and abs(after - before) < 0.5]
    if branch.message and points:
        for name, joint in JOINTS.items():
            starts += [(name, joint, i, points[-1]) for i, angle in enumerate(angles[-1]) if abs(angle - joint) <= near]
    out = []
    for name, _, i, start in starts:
        found = corner_impact(family, name, i, start.value, start.x0, offset)
        # One corner reached from several starts (consecutive orbits and the branch's end): the best located.
        same = [k for k, c in enumerate(out) if (c.joint, c.impact) == (name, i) and abs(c.rpm - found.rpm) <= offset]
        if not same:
            out.append(found)
        elif found.residual < out[same[0]].residual:
            out[same[0]] = found
    return out


def corner_impact(family: OrbitFamily, name: str, impact: int, rpm: float, x0, offset: float = 1e-3) -> CornerImpact:
    """The corner impact where impact number ``impact`` of the orbit near (rpm, x0) reaches the joint ``name`` of
    :data:`converters.models.mechanics.cam.JOINTS`, located by :func:`locate_corner`; its kind from the orbits at
    ``offset`` rpm either side of it (Newton from the corner orbit, then from points beyond it on the line through
    the orbit found, for the other side of the joint): two on one side and none on the other is a nonsmooth fold;
    one on each side, the orbit persisting through it."""
    from converters.models.mechanics.cam import JOINTS
    joint = JOINTS[name]
    rpm, x0, residual, off = locate_corner(family, joint, impact, rpm, x0)
    sides = []
    scale = 1e-9 * (1.0 + np.abs(x0).max())
    for value in (rpm + offset, rpm - offset):
        found = family.orbit(value, x0)
        if not found.converged:
            continue
        orbits = [found]
        # the other side of the joint: along the line through the corner orbit, beyond it (the two orbits
        # leave the corner at different rates)
        for reach in (1.0, 3.0, 10.0, 30.0, 100.0):
            other = family.orbit(value, x0 - reach * (found.x0 - x0))
            if other.converged and np.abs(other.x0 - found.x0).max() > scale:
                orbits.append(other)
                break
        for orbit in orbits:
            jac = family.period_map(value)(orbit.x0)[1]
            angles_there = impact_angles(family, value, orbit.x0)
            sides.append((value, orbit.x0, multipliers_of(jac),
                          float(angles_there[impact]) if impact < angles_there.size else np.nan))
    above = [side for side in sides if side[0] > rpm]
    below = [side for side in sides if side[0] < rpm]
    kind = ("nonsmooth fold" if sorted([len(above), len(below)]) == [0, 2] else
            "persistence" if len(above) == len(below) == 1 else "undetermined")
    return CornerImpact(name, float(joint), impact, float(rpm), x0, residual, float(off), offset, tuple(sides), kind,
                        family.periods)


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


def cam_checks(params: dict | None = None, periods: int = 3) -> dict:
    """The cam-follower from rest on the cam: the first detachment against the first zero of k c + m c''
    (the cam's deceleration beyond the spring), and the first impacts of the event method against Moreau-Jean's."""
    model = get_mechanical("cam-follower")
    p = model.resolve(params)
    T = model.period(p)
    run = simulate(model.problem(p, periods * T), EventDriven())
    events = run.events
    detach = events.loc[events["kind"] == "detach", "time"].to_numpy()
    zero = _detachment(model, p)
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


def cam_continuation(settings: Mapping[str, Any], params: dict | None = None) -> dict:
    """The cam-follower's P(2, 1) orbit (two impacts a revolution) continued in cam speed (the settings of
    ``[mechanics.cam_continuation]``): started from the attractor after ``warm_up`` revolutions from rest at
    ``start`` rpm, followed down to where it turns at a corner impact (:func:`corner_impacts`; the continuation
    turns there and goes on as the saddle, or stops and the saddle is followed from the corner) and up over the
    path; the P(4, 2) orbit from the period doubling. Returns the families and branches by name, the corner
    impacts on every branch, and the other bifurcations: a multiplier test that changes sign where a corner impact
    is located (its Jacobian jumps there: not a smooth fold or doubling) is reported as that corner impact."""
    from converters.analysis.continuation import switch_branch

    model = get_mechanical("cam-follower")
    family = cam_family(params)
    low, high = settings["path"]
    start = settings["start"]
    options = {"tol": CONTINUATION["tol"], "locate_tol": CONTINUATION["locate_tol"], "fd_step": 1e-6,
               "max_step": settings["max_step"]}
    rest = model.problem(model.resolve({**(params or {}), "rpm": start}), 1.0).x0
    down = follow(family, start, low, rest, warm_up=settings["warm_up"], **options)
    if not down.points:
        raise SimulationError(f"no P(2, 1) orbit at {start:g} rpm: {down.message}")
    up = follow(family, start, high, down.points[0].x0, warm_up=0, **options)
    families, branches = {"P(2,1)": family}, {"P(2,1)": [down, up]}
    corners = corner_impacts(family, down)
    for corner in corners:
        if corner.kind == "nonsmooth fold" and down.message:        # the corrector stopped at it: leave on the saddle
            saddle = max(corner.sides, key=lambda side: np.abs(side[2]).max())
            branches["P(2,1)"].append(follow(family, saddle[0], high if saddle[0] > corner.rpm else low, saddle[1],
                                             warm_up=0, **options))
    doublings = [b for branch in (down, up) for b in branch.bifurcations if b.kind == "period-doubling"]
    if doublings:
        families["P(4,2)"] = family.doubled()
    for bifurcation in doublings:
        child = switch_branch(family, bifurcation, low, high, max_points=settings["max_points"], **options)
        branches.setdefault("P(4,2)", []).append(child)
        corners += corner_impacts(families["P(4,2)"], child)
    others = []
    for name, parts in branches.items():
        for branch in parts:
            for b in branch.bifurcations:
                near = [c for c in corners if c.revolutions == families[name].periods
                        and abs(c.rpm - b.value) <= max(10.0 * b.width, 1e-6 * c.rpm)]
                if not near:
                    others.append(b)
    return {"families": families, "branches": branches, "corners": corners, "bifurcations": others}

