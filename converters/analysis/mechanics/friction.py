"""The dry-friction oscillator's studies: its sliding bifurcations along a parameter (the orbit's period read at the
path's ends by brute force, its branch followed by the continuation on the event method's exact map, each change of
the orbit's events named by :func:`converters.analysis.sliding.classify_sliding`), the degenerate switching-sliding
point, its domain of attraction, its brute-force diagram (Moreau-Jean: the attractor is what a diagram shows), its
largest Lyapunov exponent, and the event method against Moreau-Jean as h -> 0 (stick intervals).
"""
from __future__ import annotations

import time
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from converters.analysis.bifurcation import brute_force, detect_period
from converters.analysis.continuation import OrbitFamily, follow
from converters.analysis.sliding import TYPES, classify_sliding
from converters.errors import ParameterError, SimulationError
from converters.methods import EventDriven, MoreauJean
from converters.models.mechanics import get_mechanical
from converters.models.path import ParameterPath
from converters.simulate import simulate

from .orbits import CONTINUATION, mechanical_path, orbit_period


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
                  max_period: int = 8, points: int = 40, progress: bool = False) -> SlidingStudy:
    """The sliding bifurcations of the model's periodic orbit along ``name`` from ``start`` to ``stop``
    (``progress``: a bar over the path on stderr)."""
    model = get_mechanical(model_name)
    if not model.periodic(model.resolve(params)):
        raise ParameterError(f"sliding bifurcations of periodic orbits need a forced model (a forcing period); "
                             f"{model.key} is autonomous: use its diagram (pcsuite mech diagram)")
    path = mechanical_path(model, params or {}, name, start, stop)
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
    import sys

    from tqdm import tqdm
    with tqdm(total=abs(stop - start), desc=f"continuation along {name}", unit="",
              file=sys.stderr, disable=not progress, bar_format="{l_bar}{bar}| {n:.4g}/{total:.4g}") as bar:
        origin = first[0]

        def advance(value):
            bar.update(abs(value - origin) - bar.n)
        branch = follow(family, first[0], other, first[2], warm_up=0, max_step=max_step, on_point=advance,
                        **CONTINUATION)
        study.branches.append(branch)
        reached = branch.points and abs(branch.values()[-1] - other) <= 1e-9 * (1 + abs(other))
        if not reached and len(periodic) == 2:
            # The branch ended inside the path (a non-smooth fold, say): follow the other end's orbit back to it.
            back = follow(OrbitFamily(path, EventDriven(), periodic[1][1], classify=classify_sliding), periodic[1][0],
                          first[0], periodic[1][2], warm_up=0, max_step=max_step, **CONTINUATION)
            study.branches.append(back)
    for branch in study.branches:
        branch.bifurcations = [_refined(path, branch, b) if b.kind == "adding-sliding" else b
                               for b in branch.bifurcations]
    for branch in study.branches:
        if branch.message and branch.points:
            end = branch.values()[-1]
            at = [b for b in branch.bifurcations if abs(b.value - end) <= 1e-6 * (1.0 + abs(end))]
            if at:
                study.notes.append(f"the period-{branch.period} orbit ends at the {at[0].kind} at {at[0].value:.7g}: no "
                                   "orbit of its kind continues past it (a non-smooth fold of the branch)")
    study.wall_s = time.perf_counter() - clock
    return study


#: How narrow an adding-sliding point is located (relative; its stick margin is computed to ~1e-9, a few 1e-10 in
#: the parameter): the signature's bisection can be left wide where the
#: split orbit is not found near the point (velocity weakening makes the new slip begin at a finite size).
ADDING_SLIDING_TOL = 1e-9


def _refined(path, branch, bifurcation):
    """An adding-sliding point located as the end of the merged orbit's branch
    (:func:`converters.analysis.sliding.refine_adding_sliding`), from the branch's orbit nearest it on the side
    where the sliding segment is whole and the bracket's end on the other; as found where no such orbit is on the
    branch."""
    from dataclasses import replace

    from converters.analysis.sliding import refine_adding_sliding
    value, half = bifurcation.value, 0.5 * bifurcation.width
    below = [pt for pt in branch.points if pt.value < value - half]
    above = [pt for pt in branch.points if pt.value > value + half]
    near = [max(below, key=lambda pt: pt.value)] if below else []
    near += [min(above, key=lambda pt: pt.value)] if above else []
    if len(near) < 2 or len(near[0].signature) == len(near[1].signature):
        return bifurcation
    merged = min(near, key=lambda pt: len(pt.signature))
    bound = value + half if merged.value < value else value - half
    family = OrbitFamily(path, EventDriven(), branch.period, classify=classify_sliding)
    located, width, solved = refine_adding_sliding(family, merged, bound, tol=ADDING_SLIDING_TOL)
    return replace(bifurcation, value=float(located), width=float(width),
                   located_by=("the end of the branch of orbits whose sliding segment is whole: the secant zero of "
                               "its stick margin (the static friction less the stick force, at its interior "
                               f"minimum), approached from that side ({solved} orbits by Newton shooting); the "
                               f"signature's bisection had left {bifurcation.width:.2g}"))


@dataclass
class DegenerateSwitching:
    """The degenerate switching-sliding point (A, omega) of the friction oscillator, its :class:`Arrival`, and
    the curve it was continued along as (A, Arrival) rows."""

    A: float
    omega: float
    point: object
    curve: list
    params: dict
    ode_rtol: float
    wall_s: float

    def to_dict(self) -> dict:
        return {"A": self.A, "omega": self.omega, "margin": self.point.margin, "curvature": self.point.curvature,
                "arrival_time": self.point.time, "arrival_state": self.point.state.tolist(), "ode_rtol": self.ode_rtol,
                "curve": [{"A": a, "omega": p.value, "margin": p.margin, "curvature": p.curvature} for a, p in self.curve],
                "wall_s": self.wall_s}


def degenerate_switching(settings: Mapping[str, Any], params: dict | None = None,
                         progress: bool = False) -> DegenerateSwitching:
    """The seed's switching-sliding point at A = A_start continued in A until the slip field's fold at the sliding
    region's boundary turns from invisible to visible, that point located
    (:func:`converters.analysis.sliding.degenerate_switching_sliding`). ``settings``: ``A_start``, ``A_stop``,
    ``A_step``, ``omega`` (a bracket of the point at A_start), ``ode_rtol``, ``tol`` (the report's are
    ``[mechanics.degenerate]`` of validation's defaults)."""
    from converters.analysis.sliding import degenerate_switching_sliding

    cfg = settings
    model = get_mechanical("friction")
    base = dict(params or {})
    method = EventDriven(ode_rtol=cfg["ode_rtol"])

    def family_at(A):
        return OrbitFamily(mechanical_path(model, {**base, "A": A}, "omega", *cfg["omega"]), method)
    clock = time.perf_counter()
    start = family_at(cfg["A_start"])
    _, x = orbit_period(start.problem_of, 0.5 * sum(cfg["omega"]), np.zeros(2))
    import sys

    from tqdm import tqdm
    with tqdm(desc="switching-sliding curve in A", unit=" points", file=sys.stderr, disable=not progress) as bar:
        point, A, curve = degenerate_switching_sliding(family_at, cfg["A_start"], cfg["A_stop"], cfg["A_step"],
                                                       cfg["omega"], x, tol=cfg["tol"],
                                                       on_point=lambda b, p: bar.update(1))
    return DegenerateSwitching(A, point.value, point, curve, model.resolve({**base, "A": A}), cfg["ode_rtol"],
                               time.perf_counter() - clock)


def degenerate_portraits(study: DegenerateSwitching, offsets: tuple[float, float]) -> list:
    """The five orbits around the degenerate point the report draws, as (label, A, omega, trajectory, arrival):
    on either side of the switching-sliding curve at A* + dA, the point itself, on either side of the
    crossing-sliding curve at A* - dA (omega = the curve's +- domega; the arrival says which side is which), with
    ``offsets`` = (dA, domega)."""
    from dataclasses import replace

    from converters.analysis.sliding import arrival

    dA, dw = offsets
    model = get_mechanical("friction")
    method = EventDriven(ode_rtol=study.ode_rtol)
    curve = dict(study.curve)
    out = []

    def on_curve(A):
        # the curve's point at A by the secant through its two nearest continued points
        (a1, p1), (a2, p2) = sorted(curve.items(), key=lambda c: abs(c[0] - A))[:2]
        return p1.value + (p2.value - p1.value) * (A - a1) / (a2 - a1), p1.orbit
    specs = [(study.A + dA, -dw), (study.A + dA, +dw), (study.A, 0.0), (study.A - dA, +dw), (study.A - dA, -dw)]
    for k, (A, offset) in enumerate(specs, 1):
        w0, guess = (study.omega, study.point.orbit) if offset == 0.0 else on_curve(A)
        omega = w0 + offset
        family = OrbitFamily(ParameterPath(model, {**study.params, "A": A}, "omega"), method)
        orbit = family.orbit(omega, guess)
        x0 = orbit.x0 if orbit.converged else orbit_period(family.problem_of, omega, guess)[1]
        q = model.resolve({**study.params, "A": A, "omega": omega})
        T = model.period(q)
        run = simulate(model.problem(q, T, x0), EventDriven(ode_rtol=study.ode_rtol, output_step=T / 4000.0))
        out.append((f"Point {k}", A, omega, replace(run, labels=model.labels(q)),
                    arrival(family, omega, x0, side=study.point.side)))
    return out


@dataclass(frozen=True)
class _BasinChunk:
    """The stroboscopic samples x(nT), n = transient .. transient + record - 1, from each initial state of a chunk
    (Moreau-Jean at h = T h_fraction; picklable, for any backend)."""

    params: dict
    transient: int
    record: int
    h_fraction: float

    def __call__(self, states) -> np.ndarray:
        model = get_mechanical("friction")
        p = model.resolve(self.params)
        T = model.period(p)
        out = np.empty((len(states), self.record, 2))
        starts = np.arange(self.transient, self.transient + self.record) * T
        for i, x0 in enumerate(states):
            run = simulate(model.problem(p, (self.transient + self.record) * T, np.asarray(x0, dtype=float)),
                           MoreauJean(h=T * self.h_fraction))
            out[i] = run.x[np.minimum(np.searchsorted(run.t, starts - 1e-9 * T), run.t.size - 1)]
        return out


@dataclass
class Basins:
    """Initial states (x, v) at phase 0 on a grid, each labelled by the attractor it reaches (-1: none identified),
    the attractors (converged periodic orbits of the event method), and the boundary's refinement."""

    x: np.ndarray
    v: np.ndarray
    labels: np.ndarray                 # (len(v), len(x))
    attractors: list
    refined: list = field(default_factory=list)       # (x, v, label) of the refinement's initial states
    params: dict = field(default_factory=dict)
    wall_s: float = 0.0

    def boundary(self) -> np.ndarray:
        """Cells with a neighbour (of the 8 around) of another label."""
        L = self.labels
        padded = np.pad(L, 1, mode="edge")
        edge = np.zeros(L.shape, dtype=bool)
        rows, cols = L.shape
        for di in (-1, 0, 1):
            for dj in (-1, 0, 1):
                edge |= padded[1 + di:1 + di + rows, 1 + dj:1 + dj + cols] != L
        return edge

    def to_dict(self) -> dict:
        counts = {int(a): int((self.labels == a).sum()) for a in np.unique(self.labels)}
        return {"params": self.params, "grid": [len(self.x), len(self.v)], "cells": counts,
                "attractors": [{k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in a.items()}
                               for a in self.attractors],
                "boundary_cells": int(self.boundary().sum()), "refined": len(self.refined), "wall_s": self.wall_s}


def _match(samples: np.ndarray, attractors: list, tol: float) -> int:
    """The label of the attractor whose orbit's stroboscopic points are each within ``tol`` of the samples' last
    period (-1: none)."""
    for k, a in enumerate(attractors):
        points = a["points"]
        tail = samples[-len(points):]
        if all(np.min(np.linalg.norm(points - s, axis=1)) <= tol for s in tail) and \
                all(np.min(np.linalg.norm(tail - q, axis=1)) <= tol for q in points):
            return k
    return -1


def basins(params: dict | None, x_range, v_range, n: int, *, transient: int = 80, record: int = 16,
           h_fraction: float = 2e-3, match: float = 0.05, max_period: int = 8, refine: int = 3,
           backend="local", workers: int | None = None, progress: bool = False) -> Basins:
    """The friction oscillator's domains of attraction: an n x n grid of initial states (x, v) at phase 0, each
    run ``transient`` periods (Moreau-Jean, the grid's rows in parallel on ``backend``: serial, local or a Dask
    address), then labelled by the attractor its last ``record`` stroboscopic samples sit on (within ``match``).
    Each attractor is a periodic orbit solved by Newton shooting on the event method's exact map from the first
    state that reached it (period from the samples), kept only if its residual is below 1e-10; its event signature
    and Floquet multipliers are reported. Each boundary cell (a neighbour of another label, of the 8 around) is then refined by
    ``refine`` x ``refine`` initial states inside it, so the boundary is resolved by at least that many cells."""
    from converters.parallel import backend_for
    model = get_mechanical("friction")
    p = model.resolve(params)
    clock = time.perf_counter()
    xs, vs = np.linspace(*x_range, n), np.linspace(*v_range, n)
    task = _BasinChunk(p, int(transient), int(record), float(h_fraction))

    def run(states, label):
        chunks = [states[i:i + n] for i in range(0, len(states), n)]
        if backend == "serial":
            parts = [task(c) for c in chunks]
        else:
            engine = backend_for(backend, workers=workers)
            parts = [None] * len(chunks)
            from tqdm import tqdm
            with tqdm(total=len(chunks), desc=label, unit=" rows", disable=not progress) as bar:
                for position, result in engine.map_chunks(task, chunks):
                    if not isinstance(result, np.ndarray):
                        raise SimulationError(f"a chunk of the basin grid was lost: {result.message}")
                    parts[position] = result
                    bar.update(1)
        return np.concatenate(parts)
    grid = [(x, v) for v in vs for x in xs]
    samples = run(grid, "basins")
    attractors: list = []
    scale = 1.0 + np.max(np.abs(samples[:, -1]))
    family_for = {}

    def label_of(series, start):
        k = _match(series, attractors, match * scale)
        if k >= 0:
            return k
        period = detect_period(series, 1e-3)
        if not 1 <= period <= max_period:
            return -1
        family = family_for.setdefault(period, OrbitFamily(ParameterPath(model, p, "omega"), EventDriven(), period))
        orbit = family.orbit(p["omega"], series[-1])
        if not orbit.converged or orbit.residual > 1e-10:
            return -1
        one = family.period_map(p["omega"], 1)
        points = [orbit.x0]
        for _ in range(period - 1):
            points.append(one.end(points[-1]))
        attractors.append({"label": len(attractors), "period": period, "points": np.array(points),
                           "residual": float(orbit.residual), "multipliers": np.abs(orbit.multipliers).tolist(),
                           "signature": [f"{kind}" for kind, _, _ in family.signature(p["omega"], orbit.x0)],
                           "first_from": list(map(float, start))})
        return _match(series, attractors, match * scale)
    labels = np.array([label_of(series, start) for series, start in zip(samples, grid)]).reshape(n, n)
    result = Basins(xs, vs, labels, attractors, params=p)
    if refine > 1:
        dx, dv = xs[1] - xs[0], vs[1] - vs[0]
        offsets = (np.arange(refine) + 0.5) / refine - 0.5
        inner = [(xs[j] + a * dx, vs[i] + b * dv) for i, j in zip(*np.nonzero(result.boundary()))
                 for b in offsets for a in offsets]
        if inner:
            more = run(inner, "boundary refinement")
            result.refined = [(x, v, label_of(series, (x, v))) for (x, v), series in zip(inner, more)]
    result.wall_s = time.perf_counter() - clock
    return result


def resolution_check(coarse: Basins, fine: Basins) -> dict:
    """A grid twice finer (2 n - 1 points over the same ranges: the coarse states and the midpoints between them)
    against the coarse one: each coarse cell's 3 x 3 fine states around its centre should carry its label unless
    the cell is on the boundary. Returns the cells changed off the boundary (0 wanted) and on it."""
    n = len(coarse.x)
    if len(fine.x) != 2 * n - 1 or not np.allclose(fine.x[::2], coarse.x) or not np.allclose(fine.v[::2], coarse.v):
        raise ParameterError(f"the fine grid must have 2 n - 1 = {2 * n - 1} points over the coarse grid's ranges; "
                             f"got {len(fine.x)}")
    if len(fine.attractors) != len(coarse.attractors) or any(
            _match(a["points"], coarse.attractors, 1e-8) != k for k, a in enumerate(fine.attractors)):
        raise SimulationError("the two resolutions found different attractors")
    edge = coarse.boundary()
    changed = np.zeros(edge.shape, dtype=bool)
    for i in range(n):
        for j in range(n):
            block = fine.labels[max(2 * i - 1, 0):2 * i + 2, max(2 * j - 1, 0):2 * j + 2]
            changed[i, j] = bool(np.any(block != coarse.labels[i, j]))
    return {"off_boundary": int((changed & ~edge).sum()), "on_boundary": int((changed & edge).sum()),
            "boundary_cells": int(edge.sum()), "cells": n * n}


def friction_diagram(params: dict | None, name: str, values, *, h_fraction: float = 1e-3, transient: int = 150,
                     record: int = 48, workers: int | None = None, progress: bool = False):
    """The friction oscillator's x(nT) after the transient at each value (Moreau-Jean, h = T h_fraction)."""
    model = get_mechanical("friction")
    path = ParameterPath(model, model.resolve(params), name)
    T = model.period(path.resolve(values[0]))
    return brute_force(path, MoreauJean(h=T * h_fraction), values, np.zeros(2), transient=transient, record=record,
                       workers=workers, progress=progress)


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

