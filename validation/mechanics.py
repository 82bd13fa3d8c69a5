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

from converters.analysis.bifurcation import brute_force, detect_period, lyapunov_interval, section_diagram
from converters.analysis.continuation import OrbitFamily, check_path, follow, locate_condition
from converters.analysis.periodic import multipliers_of
from converters.analysis.sliding import TYPES, classify_sliding
from converters.errors import ParameterError, SimulationError
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
                  max_period: int = 8, points: int = 40, progress: bool = False) -> SlidingStudy:
    """The sliding bifurcations of the model's periodic orbit along ``name`` from ``start`` to ``stop``
    (``progress``: a bar over the path on stderr)."""
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


def degenerate_switching(params: dict | None = None, progress: bool = False) -> DegenerateSwitching:
    """The seed's switching-sliding point at A = A_start continued in A until the slip field's fold at the sliding
    region's boundary turns from invisible to visible, that point located
    (:func:`converters.analysis.sliding.degenerate_switching_sliding`; settings in defaults.toml,
    ``[mechanics.degenerate]``)."""
    from converters.analysis.sliding import degenerate_switching_sliding

    from .defaults import MECHANICS
    cfg = MECHANICS["degenerate"]
    model = get_mechanical("friction")
    base = dict(params or {})
    method = EventDriven(ode_rtol=cfg["ode_rtol"])

    def family_at(A):
        return OrbitFamily(_mechanical_path(model, {**base, "A": A}, "omega", *cfg["omega"]), method)
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


def degenerate_portraits(study: DegenerateSwitching) -> list:
    """The five orbits around the degenerate point the report draws, as (label, A, omega, trajectory, arrival):
    on either side of the switching-sliding curve at A* + dA, the point itself, on either side of the
    crossing-sliding curve at A* - dA (omega = the curve's +- domega; the arrival says which side is which)."""
    from dataclasses import replace

    from converters.analysis.sliding import arrival

    from .defaults import MECHANICS
    dA, dw = MECHANICS["degenerate"]["offsets"]
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
    from converters.analysis.bifurcation import detect_period
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


def incomplete_orbit(params: dict | None = None, settings: dict | None = None):
    """The incomplete-chattering orbit of ``settings`` (default ``[mechanics.incomplete]``: m impacts in n
    revolutions, none accumulating), seeded from the attractor ``warm_up`` revolutions after rest at ``start`` rpm
    and continued down in cam speed towards the end of complete chattering with its Floquet multipliers (exact:
    impact saltation matrices), until it ends (``max_points`` orbits). Returns (family, branch)."""
    from .defaults import MECHANICS
    settings = settings or MECHANICS["incomplete"]
    model = get_mechanical("cam-follower")
    family = cam_family(params, settings["revolutions"], settings["phase"])
    p = model.resolve({**(params or {}), "rpm": settings["start"]})
    T = model.period(p)
    seed = simulate(model.problem(p, (settings["warm_up"] + settings["phase"]) * T), EventDriven()).x[-1]
    branch = follow(family, settings["start"], settings["stop"], seed, warm_up=0, tol=CONTINUATION["tol"],
                    locate_tol=CONTINUATION["locate_tol"], fd_step=1e-6, max_step=settings["max_step"],
                    max_points=settings["max_points"])
    return family, branch


def incomplete_across(params: dict | None = None, settings: dict | None = None):
    """An incomplete-chattering orbit of one revolution continued through the end of complete chattering
    (``settings``, default ``[mechanics.across]``): seeded at ``start`` rpm by the flight that leaves the cam at the
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

    from .defaults import MECHANICS
    settings = settings or MECHANICS["across"]
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


def lyapunov_of_flow(model_name: str, params: dict | None, *, span_units: float = 1.0, transient: int = 60,
                     blocks: int = 20, block: int = 25, x0=None) -> tuple[float, float]:
    """The largest Lyapunov exponent of an autonomous model's flow per time unit, with the half-width of its 95 %
    interval: the event method's exact map over ``span_units`` time units iterated with its Jacobians from x0 (the
    model's start by default), ``blocks`` batches of ``block`` maps after ``transient``
    (:func:`converters.analysis.bifurcation.lyapunov_interval`)."""
    model = get_mechanical(model_name)
    p = model.resolve(params)
    unit = model.time_scale(p)
    period_map = EventDriven().period_map(model.problem(p, span_units * unit))
    start = model.problem(p, 1.0).x0 if x0 is None else x0
    exponent, half, _ = lyapunov_interval(period_map, start, transient, blocks, block)
    return exponent / span_units, half / span_units


def two_block_regime(params: dict | None, *, transient: float = 500.0, record: float = 500.0, tol: float = 1e-9,
                     blocks: int = 20, block: int = 25) -> dict:
    """The two-block system's regime at one belt velocity, by two tests that can fail: (1) the states where block 1
    starts to stick, after ``transient`` time units over ``record`` more, close into a cycle of k section points to
    ``tol`` (:func:`converters.analysis.bifurcation.detect_period`), the closing shown by the largest difference
    over the record's first and last k points (a transient still decaying has the first well above the last);
    (2) the largest Lyapunov exponent per time unit with its 95 % interval, from the run's end. Regime: "periodic"
    when a cycle closes (a periodic orbit of a flow has exponent 0: the interval must contain it or lie below);
    "chaotic" when none does and the interval lies above 0; otherwise "undetermined"."""
    p = get_mechanical("stick-slip").resolve(params)
    (row,) = two_block_diagram(p, "V", [p["V"]], transient=transient, record=record, workers=1)
    if row.error:
        raise SimulationError(f"the two-block run at V = {p['V']:g} m/s failed: {row.error}")
    points = row.states[:, [0, 1, 3]]                                   # v1 = V there: x1, x2, v2
    k = detect_period(points, tol) if len(points) >= 4 else 0
    exponent, half = lyapunov_of_flow("stick-slip", p, transient=0, blocks=blocks, block=block, x0=row.states[-1])
    closing = None
    if k:
        gaps = np.abs(points[k:] - points[:-k]).max(axis=1)
        closing = (float(gaps[:k].max()), float(gaps[-k:].max()))
    regime = ("periodic" if k and exponent - half <= 0.0 else "chaotic" if not k and exponent - half > 0.0
              else "undetermined")
    return {"V": p["V"], "sections": len(points), "period": k, "closing": closing, "lyapunov": exponent,
            "half_width": half, "regime": regime}


@dataclass(frozen=True)
class _TwoBlockRegime:
    """:func:`two_block_regime` at one belt velocity (picklable, for a process pool)."""

    params: dict

    def __call__(self, V: float) -> dict:
        return two_block_regime({**self.params, "V": V})


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


# --- the report's sections ----------------------------------------------------------------------------------

def _orbit_run(model, p: dict, name: str, point, periods: int):
    """One period of a continuation orbit (the event method), labelled."""
    from dataclasses import replace
    q = model.resolve({**p, name: point.value})
    run = simulate(model.problem(q, periods * model.period(q), point.x0), EventDriven())
    return replace(run, labels=model.labels(q))


def _sides(branch, value):
    """The branch's orbits just below and just above ``value``."""
    points = sorted(branch.points, key=lambda pt: pt.value)
    below = [pt for pt in points if pt.value < value]
    above = [pt for pt in points if pt.value > value]
    return (below[-1] if below else None), (above[0] if above else None)


def sliding_section():
    """The seed's four sliding bifurcations of the dry-friction oscillator: located, named, against the seed."""
    import pandas as pd

    from .defaults import MECHANICS, SEED_SLIDING
    from .mechanics_plots import diagram_figure, phase_portraits
    from .report import Section, csv_bytes, table_html
    model = get_mechanical("friction")
    studies = {}
    for row in SEED_SLIDING:
        key = (row["A"], tuple(row["path"]))
        if key not in studies:
            studies[key] = sliding_study("friction", {"A": row["A"]}, "omega", *row["path"])
    rows, panels, ok = [], [], True
    for row in SEED_SLIDING:
        study = studies[(row["A"], tuple(row["path"]))]
        found = [b for b in study.bifurcations if b.kind == row["type"]]
        if "seed" in row:
            best = min(found, key=lambda b: abs(b.value - row["seed"])) if found else None
            error = abs(best.value / row["seed"] - 1.0) if best else float("inf")
            # a bracket wider than the tolerance locates nothing to it: a failure, whatever its midpoint
            passed = best is not None and error <= row["tolerance"] and best.width <= row["tolerance"] * abs(best.value)
            reference, limit = f"{row['seed']:g}", f"{row['tolerance']:.1%}"
        else:
            low, high = row["seed_range"]
            best = next((b for b in found if low <= b.value <= high), None)
            error = float("nan")
            passed = best is not None and best.width <= row["width"] * abs(best.value)
            reference, limit = f"between {low:g} and {high:g}", f"inside, bracket {row['width']:.0e}"
        ok = ok and passed
        rows.append({"type": row["type"], "A (N)": row["A"], "path (rad/s)": f"{row['path'][0]:g}..{row['path'][1]:g}",
                     "seed": reference, "found": f"{best.value:.7f}" if best else "none",
                     "relative difference": error, "limit": limit,
                     "bracket": f"{best.width:.1e}" if best else "", "orbit period (T)": best.period if best else "",
                     "located by": best.located_by if best else "", "result": "pass" if passed else "fail"})
        if best is not None:
            branch = next(br for br in study.branches if best in br.bifurcations)
            for label, point in zip(("below", "above"), _sides(branch, best.value)):
                if point is not None:
                    panels.append((f"{row['type'].capitalize()} Bifurcation, A = {row['A']:g}: W = {point.value:.5g} ({label})",
                                   _orbit_run(model, {"A": row["A"]}, "omega", point, branch.period)))
    table = pd.DataFrame(rows)
    A = MECHANICS["friction_diagram_A"]
    diagram_study = next(s for (a, _), s in studies.items() if a == A)
    attractors = friction_diagram({"A": A}, "omega", np.linspace(*diagram_study_path(diagram_study),
                                                                 MECHANICS["friction_diagram_points"]), workers=1)
    notes = "".join(f"<li>A = {s.params['A']:g}: {'; '.join(s.notes)} ({s.wall_s:.0f} s)</li>" for s in studies.values())
    text = ("<p>The dry-friction oscillator on a moving belt (Popp and Stelter 1990; k = m = 1, g = 10, Vdr = 1, Popp's law alpha = "
            "0.3, gamma = 1.42, beta = 0.1, eta = 0.01) forced by A cos(omega t). Each path is followed by "
            "pseudo-arclength continuation on the event method's exact stroboscopic map (DOP853 between events, "
            "variational equations, saltation matrices, the sliding projector); each change of the orbit's event "
            "signature is bracketed by bisection and named from the short piece of orbit born there "
            "(<code>converters.analysis.sliding</code>). Against the seed's values:</p>"
            + table_html(table, "result", good=("pass",)) + f"<ul>{notes}</ul>"
            + "<img src='friction_orbits.png' alt='phase portraits'>"
            + f"<p>Brute force at A = {A:g} (Moreau-Jean, h = T/1000, x(nT) after 150 periods) with the located "
              "bifurcations and the continued orbit:</p><img src='friction_diagram.png' alt='friction diagram'>")
    files = {"friction_orbits.png": phase_portraits(panels, model),
             "friction_diagram.png": diagram_figure(model, "omega", attractors, diagram_study,
                                                    title="Sliding Bifurcations in a dry friction oscillator"),
             "sliding_bifurcations.csv": csv_bytes(table)}
    metrics = {f"A={a:g}": s.to_dict() for (a, _), s in studies.items()}
    return Section("Mechanics: the dry-friction oscillator's sliding bifurcations", text, files, ok=ok, metrics=metrics)


def degenerate_section():
    """The degenerate switching-sliding point: located on the continued curve, its two conditions, five orbits."""
    import pandas as pd

    from .defaults import MECHANICS
    from .mechanics_plots import degenerate_curve_figure, degenerate_figure
    from .report import Section, csv_bytes, table_html
    cfg = MECHANICS["degenerate"]
    study = degenerate_switching()
    portraits = degenerate_portraits(study)
    point, limit = study.point, cfg["conditions"]
    ok = abs(point.margin) <= limit and abs(point.curvature) <= limit
    curve = pd.DataFrame([{"A (N)": a, "omega (rad/s)": p.value, "arrival margin": p.margin,
                           "fold curvature (m/s^3)": p.curvature,
                           "kind": "switching-sliding" if p.curvature > 0 else "crossing-sliding"} for a, p in study.curve])
    text = (f"<p>The switching-sliding point of the friction oscillator at A = {cfg['A_start']:g} (the seed's "
            "2.7992) is continued in A. Along the curve the orbit arrives at the switching surface (v = Vdr) from "
            "below exactly at the sliding region's boundary, where the stick force reaches the static limit: the first "
            "test function is that <em>arrival margin</em>, |lambda| / F(0) - 1 (zero on the curve; each point located "
            "as the end of the branch of orbits that arrive inside, approached by secant steps). The second is the "
            "<em>fold curvature</em> there, -s'' along the slip field beyond the surface (s = v - Vdr; here "
            "(k Vdr + A omega sin(omega t)) / m): positive where the fold is invisible, so that an orbit crossing just "
            "outside the region comes back to it after a short excursion (switching-sliding), negative where it is "
            "visible and an orbit arriving just inside sticks briefly, slips to the other side and returns "
            "(crossing-sliding). The curvature changes sign along the curve at a cubic tangency, the codimension-two "
            "point (a degenerate sliding bifurcation in the sense of Kowalczyk and di Bernardo, Physica D 204, 2005), "
            f"located by Brent's method in A to {cfg['tol']:g} (the event method at ODE tolerance "
            f"{study.ode_rtol:g}; {study.wall_s:.0f} s):</p>"
            + table_html(pd.DataFrame([{"A (N)": f"{study.A:.9f}", "omega (rad/s)": f"{study.omega:.9f}",
                                        "arrival margin": f"{point.margin:.2e}",
                                        "fold curvature (m/s^3)": f"{point.curvature:.2e}", "limit": f"{limit:g}",
                                        "result": "pass" if ok else "fail"}]), "result", good=("pass",))
            + "<img src='degenerate_curve.png' alt='the curve in (A, omega)'>"
            + f"<p>Five orbits around it: at A* + {cfg['offsets'][0]:g} on either side of the switching-sliding curve, "
              f"the point itself, and at A* - {cfg['offsets'][0]:g} on either side of the crossing-sliding curve "
              f"(omega {cfg['offsets'][1]:g} off the curve):</p><img src='degenerate_orbits.png' alt='five orbits'>"
            + "<p>The continued curve:</p>" + table_html(curve))
    files = {"degenerate_orbits.png": degenerate_figure(portraits, study, get_mechanical("friction")),
             "degenerate_curve.png": degenerate_curve_figure(study, portraits),
             "degenerate_curve.csv": csv_bytes(curve)}
    return Section("Mechanics: the degenerate switching-sliding bifurcation", text, files, ok=ok,
                   metrics=study.to_dict())


def basins_section():
    """The seed's domain of attraction at A = 3.6, omega = 1.067, with the check at a grid twice finer."""
    import pandas as pd

    from .defaults import MECHANICS
    from .mechanics_plots import basin_figure
    from .report import Section, table_html
    cfg = MECHANICS["basins"]
    box = dict(params={"A": cfg["A"], "omega": cfg["omega"]}, x_range=cfg["x"], v_range=cfg["v"])
    coarse = basins(n=cfg["n"], refine=cfg["refine"], **box)
    fine = basins(n=2 * cfg["n"] - 1, refine=1, **box)
    check = resolution_check(coarse, fine)
    model = get_mechanical("friction")
    p = coarse.params
    T = model.period(p)
    orbits = [simulate(model.problem(p, a["period"] * T, a["points"][0]), EventDriven(output_step=T / 400.0))
              for a in coarse.attractors]
    ok = (check["off_boundary"] == 0 and (coarse.labels >= 0).all() and bool(coarse.attractors)
          and all(a["residual"] < 1e-10 for a in coarse.attractors))
    rows = pd.DataFrame([{"attractor": a["label"], "period (T)": a["period"], "events": ", ".join(a["signature"]),
                          "x(0) (m)": f"{a['points'][0][0]:.6f}", "v(0) (m/s)": f"{a['points'][0][1]:.6f}",
                          "Newton residual": f"{a['residual']:.1e}",
                          "|Floquet multipliers|": ", ".join(f"{m:.3g}" for m in a["multipliers"]),
                          "share of the grid": f"{(coarse.labels == a['label']).mean():.1%}"} for a in coarse.attractors])
    text = (f"<p>Initial states (x, v) at phase 0 on a {cfg['n']} x {cfg['n']} grid, each run {80} forcing periods "
            "(Moreau-Jean, h = T/500, the grid's rows in parallel on the local backend) and labelled by the attractor "
            "its last 16 stroboscopic samples sit on; each attractor is the periodic orbit solved by Newton shooting "
            "on the event method's exact map from the first state that reached it. Each boundary cell is refined by "
            f"{cfg['refine']} x {cfg['refine']} more initial states (dots). A grid twice finer ({2 * cfg['n'] - 1} "
            f"points a side) changes {check['off_boundary']} cells off the boundary ({check['on_boundary']} of its "
            f"{check['boundary_cells']} cells on it); unlabelled cells: {int((coarse.labels < 0).sum())}; "
            f"{coarse.wall_s + fine.wall_s:.0f} s.</p>" + table_html(rows)
            + "<img src='basins.png' alt='domain of attraction'>")
    return Section("Mechanics: the friction oscillator's domain of attraction", text,
                   {"basins.png": basin_figure(coarse, orbits)}, ok=ok,
                   metrics={**coarse.to_dict(), "resolution_check": check})


def diagram_study_path(study) -> tuple[float, float]:
    return min(study.start, study.stop), max(study.start, study.stop)


def agreement_section():
    """Event-driven against Moreau-Jean (friction stick intervals, cam impacts) and the ball's closed form."""
    import pandas as pd

    from .defaults import MECHANICS
    from .report import Section, csv_bytes, table_html
    limit = MECHANICS["agreement_rel"]
    friction = friction_agreement()
    cam = cam_checks()
    ball = ball_check()
    f_rows = pd.DataFrame(friction["rows"])
    c_rows = pd.DataFrame(cam["moreau"])
    b_rows = pd.DataFrame(ball["moreau"])
    ok = (bool((f_rows["max_error_T"] <= limit).all()) and bool((c_rows["max_error_T"] <= limit).all())
          and ball["relative_error"] <= MECHANICS["ball_rel"] and ball["restitution_max_error"] <= 1e-6
          and f_rows["max_error_T"].iloc[-1] < f_rows["max_error_T"].iloc[0] / 10)
    text = (f"<p><b>Friction</b> (A = {friction['params']['A']:g}, omega = {friction['params']['omega']:g}): the exact "
            f"periodic orbit's stick interval {friction['exact']} (fractions of T) against Moreau-Jean's after 50 "
            "periods from the exact orbit, as h shrinks (first order):</p>" + table_html(f_rows)
            + f"<p><b>Cam-follower</b> ({cam['params']['rpm']:g} rpm, from rest on the cam): the first detachment at "
              f"{cam['first_detachment_s']:.12f} s where k c + m c'' first reaches zero ({cam['margin_zero_s']:.12f} s: "
              f"{cam['detachment_error_s']:.1e} s apart); the first impacts {', '.join(f'{t:.6f}' for t in cam['first_impacts_s'])} s "
              "against Moreau-Jean's nearest ones:</p>" + table_html(c_rows)
            + f"<p><b>Bouncing ball</b> (H = 1 m, e = 0.5): the event method completes the chattering at "
              f"{ball['event_accumulation_s']:.15f} s against sqrt(2H/g)(1 + 2e/(1 - e)) = {ball['closed_form_s']:.15f} s "
              f"({ball['relative_error']:.1e} relative) after {ball['impacts_before_accumulation']} impacts; successive "
              f"flight times shrink by e to {ball['restitution_max_error']:.1e}. Moreau-Jean's largest penetration and "
              "the time it comes to rest:</p>" + table_html(b_rows)
            + f"<p>Limits: {limit:.0%} of the period for the event times, {MECHANICS['ball_rel']:g} for the ball.</p>")
    files = {"friction_agreement.csv": csv_bytes(f_rows), "cam_impacts.csv": csv_bytes(c_rows),
             "ball.csv": csv_bytes(b_rows)}
    return Section("Mechanics: event-driven against Moreau-Jean and the closed forms", text, files, ok=ok,
                   metrics={"friction": friction, "cam": {k: v for k, v in cam.items() if k != "params"}, "ball": ball})


def cam_section():
    """The cam-follower's impact phases against its speed, its regimes, and where complete chattering ends."""
    import pandas as pd

    from .defaults import MECHANICS
    from .mechanics_plots import cam_profile_figure, diagram_figure
    from .report import Section, csv_bytes, table_html
    model = get_mechanical("cam-follower")
    values = np.linspace(*MECHANICS["cam_rpm"], MECHANICS["cam_points"])
    rows = impact_phase_diagram({}, values, h_fraction=2.5e-4, workers=1)
    counts = {f"{r.value:g}": int(r.times.size) for r in rows}
    regimes = chattering_table({}, MECHANICS["cam_regime_rpm"], workers=1)
    transitions = [chattering_transition({}, *bracket) for bracket in MECHANICS["cam_transitions"]]
    marks = {"the seed's 175 rpm (chattering)": 175.0, "Siconos' example, 358 rpm": 358.0}
    marks.update({f"complete chattering ends, {t['rpm']:.4f} rpm": t["rpm"] for t in transitions})
    picture = diagram_figure(model, "rpm", rows, marks=marks, title="Bifurcation Analysis - Chattering orbits "
                             "(transition from complete chattering to no-complete chattering marked)")
    errors = sum(bool(r.error) for r in rows)
    located = pd.DataFrame([{"bracket (rpm)": f"{lo:g}..{hi:g}", "located (rpm)": f"{t['rpm']:.7f}",
                             "width (rpm)": f"{t['width']:.1e}", "ride left at the last orbit (revolutions)":
                             f"{t['last']['ride']:.1e}", "impacts before it accumulates": t["last"]["impacts"],
                             "runs": t["runs"]} for (lo, hi), t in zip(MECHANICS["cam_transitions"], transitions)])
    text = ("<p>The cam-follower of Siconos' CamFollower example (after di Bernardo, Osorio and Santini; "
            "m = 1.221 kg, k = 1430.8 N/m, e = 0.8). Its cam is piecewise smooth: "
            "four arcs, mirrored, whose second derivative jumps at each joint (the follower's impacts are one "
            "nonsmoothness, the profile the other):</p><img src='cam_profile.png' alt='cam profile'><p>The phase of every "
            "impact (Moreau-Jean, h = T/4000, 20 cam revolutions after 20 of transient) against the cam speed, "
            "over a range holding the seed's 175 rpm and Siconos' 358 rpm. At low speed the follower stays on the "
            "cam (no impacts); above the speed where the cam's deceleration first exceeds what the spring supplies "
            "it detaches and returns in impacts, in sequences that accumulate (complete chattering) or are cut "
            "short by the next lift (incomplete).</p><img src='cam_impacts.png' alt='impact phases'>"
            "<p>The regime at selected speeds (the event method, revolutions 10 to 20; an accumulation is a chattering "
            "sequence completed in closed form, the follower then riding the cam):</p>" + table_html(regimes)
            + "<p>Transition from complete chattering to no-complete chattering, located: the period-one "
              "complete-chattering orbit leaves the cam at its detachment (where k c + m c'' falls through zero), "
              "impacts it, its impacts accumulate and it rides the cam to the next revolution's detachment, where "
              "its state is the cam's again (periodic without shooting; every perturbation is erased at the "
              "accumulation). Its test function is the ride left between the accumulation and the next detachment; "
              "where it reaches zero the accumulation no longer completes within the revolution. Each end is "
              "approached by secant steps from the side where the orbit exists (the event method):</p>"
            + table_html(located))
    return Section("Mechanics: the cam-follower's impact phases", text,
                   {"cam_impacts.png": picture, "cam_profile.png": cam_profile_figure(),
                    "cam_regimes.csv": csv_bytes(regimes),
                    "cam_transitions.csv": csv_bytes(located)},
                   ok=errors == 0 and sum(counts.values()) > 0 and all(t["width"] <= 1e-6 * t["rpm"] for t in transitions),
                   metrics={"impacts_per_rpm": counts, "errors": errors, "regimes": regimes.to_dict(orient="records"),
                            "transitions": [{**{k: v for k, v in t.items() if k != "last"},
                                             "ride": float(t["last"]["ride"])} for t in transitions]})


def cam_continuation(params: dict | None = None) -> dict:
    """The cam-follower's P(2, 1) orbit (two impacts a revolution) continued in cam speed (the settings of
    ``[mechanics.cam_continuation]``): started from the attractor after ``warm_up`` revolutions from rest at
    ``start`` rpm, followed down to where it turns at a corner impact (:func:`corner_impacts`; the continuation
    turns there and goes on as the saddle, or stops and the saddle is followed from the corner) and up over the
    path; the P(4, 2) orbit from the period doubling. Returns the families and branches by name, the corner
    impacts on every branch, and the other bifurcations: a multiplier test that changes sign where a corner impact
    is located (its Jacobian jumps there: not a smooth fold or doubling) is reported as that corner impact."""
    from converters.analysis.continuation import switch_branch

    from .defaults import MECHANICS
    settings = MECHANICS["cam_continuation"]
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


def cam_continuation_section():
    """The source's slides "Continuation of periodic orbits" and "Corner-impact bifurcation in a P(2,1:1)": the
    cam-follower's impacting orbits continued in cam speed over the brute-force impact phases, and the corner impact
    located on the P(2, 1) orbit."""
    import pandas as pd

    from .defaults import MECHANICS
    from .mechanics_plots import cam_branches_figure, corner_figure
    from .report import Section, csv_bytes, table_html
    settings = MECHANICS["cam_continuation"]
    study = cam_continuation()
    values = np.linspace(*settings["path"], settings["points"])
    rows = impact_phase_diagram({}, values, transient=settings["transient"], record=settings["record"],
                                h_fraction=2.5e-4, workers=1)
    branch_picture = cam_branches_figure(study, rows, "Moreau-Jean, h = T/4000")
    corner_picture = corner_figure(study)
    table = pd.DataFrame([{"bifurcation": b.kind, "cam speed (rpm)": f"{b.value:.7f}",
                           "multipliers": ", ".join(f"{m:.4g}" for m in b.multipliers), "located by": b.located_by,
                           "bracket (rpm)": f"{b.width:.1e}"} for b in study["bifurcations"] if b.kind != "fold"]
                         + [{"bifurcation": f"corner impact ({c.kind}) of the P({2 * c.revolutions},{c.revolutions}) "
                                            f"orbit, its impact {c.impact + 1} at the {c.joint} joint, "
                                            f"beta = {c.angle:.7f} rad",
                             "cam speed (rpm)": f"{c.rpm:.7f}",
                             "multipliers": "; ".join(", ".join(f"{m:.4g}" for m in side[2]) for side in c.sides),
                             "located by": f"bordered Newton: orbit residual {c.residual:.1e} m, impact "
                                           f"{c.off_joint:.1e} rad off the joint", "bracket (rpm)": ""}
                            for c in study["corners"]])
    orbits = pd.DataFrame([{"orbit": name, "cam speed (rpm)": pt.value, "stable": pt.stable,
                            "multipliers": ", ".join(f"{m:.6g}" for m in pt.multipliers),
                            "impact phases (revolutions)": ", ".join(
                                f"{t / family.problem_of(pt.value).period:.6f}"
                                for t in family.event_times(pt.value, pt.x0, "impact"))}
                           for name, parts in study["branches"].items() for branch in parts
                           for family in [study["families"][name]] for pt in branch.points])
    points = len(orbits)
    corner_ok = [c for c in study["corners"] if c.kind == "nonsmooth fold" and c.residual <= 1e-9
                 and abs(c.off_joint) <= 1e-9 and c.revolutions == 1]
    text = ("<p>Periodic impacting orbits P(m, n) (m impacts in n revolutions) of the cam-follower, continued in cam "
            "speed by pseudo-arclength continuation on the event method's period map, whose Jacobian is exact: the "
            "variational equations between impacts and each impact's saltation matrix (Newton's law differentiated, "
            "its instant moving with the gap's rate). The P(2, 1) orbit is started from the attractor "
            f"{settings['warm_up']} revolutions after rest at {settings['start']:g} rpm; the P(4, 2) orbit from its "
            f"period doubling (at most {settings['max_points']} orbits). Stable orbits solid, unstable dashed, over the "
            "brute-force impact phases of the attractor from rest (Moreau-Jean, h = T/4000, "
            f"{settings['record']:g} revolutions after {settings['transient']:g}).</p>"
            "<img src='cam_continuation.png' alt='continued orbits'><p>Every orbit with its multipliers and "
            "impact phases: cam_orbits.csv.</p>"
            "<p>Going down in speed the P(2, 1) orbit's first impact moves towards the joint of the cam's flank and "
            "nose (beta = pi/2 + beta2), where the profile's curvature, and with it the cam's acceleration c'', "
            "jumps. There the map stays continuous but its Jacobian jumps (the saltation matrix holds c''): a "
            "corner-impact bifurcation (Osorio, di Bernardo and Santini 2008). It is located by Newton on the orbit "
            "and the impact's angle together. Just above it the stable orbit (complex multipliers inside the unit "
            "circle) and a saddle (one real multiplier above 1), each with its impact on one side of the joint, "
            "meet at the corner; det(I - J) has opposite signs on the two (Feigin's condition): they vanish together "
            "in a nonsmooth fold, not a smooth one (no multiplier passes through 1).</p>"
            "<img src='cam_corner.png' alt='corner-impact bifurcation'>"
            + "".join(f"<p>The P({2 * c.revolutions}, {c.revolutions}) orbit born at the period doubling meets the "
                      f"{c.joint} joint too, at {c.rpm:.7f} rpm ({c.kind}): there its multiplier test functions jump "
                      "sign without a multiplier passing -1 or +1, so the continuation's fold and doubling next to it "
                      "are this corner impact, reported once.</p>" for c in study["corners"] if c.revolutions > 1)
            + table_html(table))
    return Section("Mechanics: continuation of periodic orbits and the corner-impact bifurcation", text,
                   {"cam_continuation.png": branch_picture, "cam_corner.png": corner_picture,
                    "cam_continuation.csv": csv_bytes(table), "cam_orbits.csv": csv_bytes(orbits)},
                   ok=bool(corner_ok) and points > 10,
                   metrics={"corners": [{"rpm": c.rpm, "joint": c.joint, "kind": c.kind, "residual": c.residual,
                                         "off_joint": c.off_joint} for c in study["corners"]],
                            "bifurcations": [{"kind": b.kind, "rpm": b.value} for b in study["bifurcations"]],
                            "orbits": points})


def quick_form_note(full: bool, what: str) -> str:
    """The paragraph a section with a quick form opens with: which form ran, and what the full size covers."""
    if full:
        return ""
    return (f"<p class='note'>Quick form: {what}. <code>pcsuite report mechanics --full</code> runs the full study "
            "(the settings in <code>validation/data/defaults.toml</code>, <code>[mechanics]</code> against "
            "<code>[mechanics.quick]</code>).</p>")


def chattering_windows_section(full: bool = False):
    """Past the end of complete chattering: the superstable orbits through the detachment (one accumulation per n
    revolutions) followed in cam speed, and their windows' borders located (:func:`chattering_windows`); an
    incomplete orbit continued through the transition, from its corner impact to its grazing
    (:func:`incomplete_across`); from above, the P(6,2) orbit down to its fold (:func:`incomplete_orbit`). The quick
    form (``full`` False) takes ``[mechanics.quick]``'s grid and continuation settings."""
    import pandas as pd

    from .defaults import MECHANICS, mechanics_settings
    from .mechanics_plots import chattering_windows_figure, incomplete_figure
    from .report import Section, csv_bytes, table_html
    form = mechanics_settings(full)
    settings = form["chattering_windows"]
    values = np.linspace(*settings["path"], settings["points"])
    study = chattering_windows({}, values, revolutions=settings["revolutions"])
    picture = chattering_windows_figure(study, settings["revolutions"])
    other = form["incomplete"]
    family, branch = incomplete_orbit(settings=other)
    across_family, across, corners = incomplete_across(settings=form["across"])
    full_grid, full_other = MECHANICS["chattering_windows"], MECHANICS["incomplete"]
    note = quick_form_note(full, f"the grid of {settings['points']} cam speeds over {settings['path'][0]:g}-"
                                 f"{settings['path'][1]:g} rpm (full: {full_grid['points']} over "
                                 f"{full_grid['path'][0]:g}-{full_grid['path'][1]:g} rpm, every window border between "
                                 f"them located); the incomplete orbit continued from {other['start']:g} rpm in steps "
                                 f"of at most {other['max_step']:g} rpm (full: from {full_other['start']:g} rpm, "
                                 f"{full_other['max_step']:g} rpm)")
    complete_end = next((b["rpm"] for b in study["borders"] if b["n"] == 1 and b["side"] == "below"), None)
    grazings = [b for b in across.bifurcations if b.kind == "border-collision"]
    located = locate_grazing(across_family, across, grazings[0]) if grazings else None
    m_across = {across_family.event_times(pt.value, pt.x0, "impact").size for pt in across.points}
    radius = [pt.spectral_radius for pt in across.points]
    crossed = complete_end is not None and across.values()[0] < complete_end < across.values()[-1]
    impacts = family.event_times(branch.points[0].value, branch.points[0].x0, "impact").size
    folds = [b for b in branch.bifurcations if b.kind == "fold"]
    found = pd.DataFrame([{"bifurcation": b.kind, "cam speed (rpm)": f"{b.value:.7f}",
                           "bracket (rpm)": f"{b.width:.1e}", "multipliers": ", ".join(f"{m:.4g}" for m in b.multipliers),
                           "located by": b.located_by} for b in branch.bifurcations])
    grid = pd.DataFrame([{"cam speed (rpm)": r["rpm"], "n (revolutions per accumulation)": r["n"],
                          "impacts per orbit": r["impacts"] if r["n"] else None,
                          "ride left (revolutions)": None if r["ride"] is None else float(r["ride"])}
                         for r in study["rows"]])
    borders = pd.DataFrame([{"border (rpm)": f"{b['rpm']:.7f}", "bracket (rpm)": f"{b['width']:.1e}",
                             "orbit": f"n = {b['n']}, {b['side']} the border",
                             "its ride at the last orbit (revolutions)": f"{b['ride']:.1e}",
                             "at the border": "the orbit ends: its accumulation reaches the detachment"
                             if b["ride"] <= 1e-5 else "bracketed, its ride not resolved to zero (steep there, or "
                             "the orbit ends otherwise: an earlier sequence completing)"}
                            for b in study["borders"]])
    ends = [b for b in study["borders"] if b["ride"] <= 1e-5]
    text = (note + "<p>Past the end of complete chattering the follower does not go over to incomplete chattering at "
            "once. Its chattering sequence is cut by the next lift, but it leaves the cam nearly in the cam's own "
            "state, and a later revolution's sequence completes: the orbit through the detachment then accumulates "
            "once every n revolutions. Each such orbit is periodic without shooting (after the accumulation the "
            "follower rides the cam to a detachment, where its state is the cam's) and superstable: every "
            "perturbation is erased at the accumulation, its Floquet multipliers are zero. It is followed in cam "
            "speed by running it from the detachment at each speed (the event method, which completes a sequence "
            "in closed form), and each change of n between neighbours of the grid is approached from both sides "
            "by secant steps on the orbit's ride left (the fraction of a revolution between the accumulation and "
            "the detachment that ends the orbit): where the ride falls to zero the orbit ends, its accumulation "
            "reaching the detachment. Where no sequence accumulates within "
            f"{settings['revolutions']} revolutions the follower is in incomplete chattering (or in an orbit of "
            "more revolutions); incomplete P(m, n) orbits at higher speed are continued below and in the next section.</p>"
            "<p>Through the transition: an incomplete-chattering orbit of one revolution, P("
            + "/".join(str(m) for m in sorted(m_across)) + ", 1), its sequence cut every revolution by the lift at the "
            "detachment, seeded by the flight that leaves the cam there and continued both ways in cam speed with "
            f"its exact multipliers ({len(across.points)} orbits, {across.values()[0]:.7g} to "
            f"{across.values()[-1]:.7f} rpm). "
            + (f"It passes the end of complete chattering ({complete_end:.7f} rpm) unchanged: below it, it coexists "
               "with the superstable complete-chattering orbit; the transition is a bifurcation of the "
               "complete-chattering orbit alone. " if crossed else "It does not reach the end of complete chattering. ")
            + f"It is unstable all along (largest multiplier {min(radius):.1f} to {max(radius):.1f}, the other below "
              f"{max(np.sort(np.abs(pt.multipliers))[0] for pt in across.points):.0e}), so a simulation does not settle "
              "on it. "
            + (f"It ends at a grazing at {located[0]:.6f} rpm, where the flight leaving the cam at the lift touches "
               f"the cam and an impact appears ({grazings[0].detail}): located where the flight's least clearance "
               f"reaches zero, extrapolated from {located[1][0][1]:.2e} m and {located[1][1][1]:.2e} m at "
               f"{located[1][0][0]:.6f} and {located[1][1][0]:.6f} rpm; the event method, which sees a touch within "
               f"its event tolerance of the cam, brackets it at {grazings[0].value:.6f} rpm (width "
               f"{grazings[0].width:.1e} rpm). "
               if grazings else f"No end was located: {across.message}. ")
            + "".join(f"Going down, its impact {c.impact + 1} reaches the {c.joint} joint of the cam profile (where "
                      "the cam lifts away: the detachment is at that joint), a corner impact located at "
                      f"{c.rpm:.7f} rpm (residual {c.residual:.1e}, {abs(c.off_joint):.1e} rad off the joint) from "
                      f"the branch's orbit at {across.values()[0]:g} rpm: a {c.kind} (Newton from the corner orbit "
                      f"and beyond it, {c.offset:g} rpm either side: "
                      + "; ".join(f"at {side[0]:.6f} rpm an orbit of {np.abs(side[2]).max():.1f} largest multiplier, "
                                  + ("its impact past the joint" if side[3] > c.angle else "its impact before the joint"
                                     if side[3] < c.angle else "without that impact") for side in c.sides)
                      + (", none below" if all(side[0] > c.rpm for side in c.sides) else "") + "). " for c in corners)
            + "Settings <code>[mechanics.across]</code>.</p><img src='cam_across.png' alt='an orbit through the "
              "transition'>"
            "<img src='cam_chattering_windows.png' alt='chattering windows'>"
            "<p>The grid (cam_chattering_grid.csv):</p>" + table_html(grid)
            + "<p>The borders located (an orbit between two grid speeds of other n is not seen; the windows are "
              "many and narrow):</p>" + table_html(borders)
            + f"<p>From the other side: the incomplete-chattering orbit P({impacts}, {other['revolutions']}) "
              f"({impacts} impacts in {other['revolutions']} revolutions, none accumulating), seeded from the "
              f"attractor {other['warm_up']} revolutions after rest at {other['start']:g} rpm, continued down in cam "
              "speed by pseudo-arclength continuation on the event method's map (its Jacobian exact: each impact's "
              f"saltation matrix; {len(branch.points)} orbits). "
              + (f"It is stable down to a fold at {folds[0].value:.7f} rpm (a multiplier through +1), where it "
                 "meets its unstable twin; below it the follower has no such orbit and its sequences begin to "
                 "complete in some revolutions (the windows above)." if folds else
                 f"No fold was found: {branch.message or 'it reaches the path end'}.")
            + "</p><img src='cam_incomplete.png' alt='incomplete-chattering orbit'>" + table_html(found))
    return Section("Mechanics: past the end of complete chattering", text,
                   {"cam_chattering_windows.png": picture, "cam_chattering_grid.csv": csv_bytes(grid),
                    "cam_chattering_borders.csv": csv_bytes(borders),
                    "cam_incomplete.png": incomplete_figure(family, branch), "cam_incomplete.csv": csv_bytes(found),
                    "cam_across.png": incomplete_figure(across_family, across, marks={
                        **({"end of complete chattering": complete_end} if complete_end is not None else {}),
                        **{f"corner impact ({c.kind})": c.rpm for c in corners}})},
                   ok=bool(ends) and all(b["width"] <= 1e-6 * b["rpm"] for b in study["borders"]) and bool(folds)
                   and crossed and bool(grazings) and min(radius) > 1.0
                   and 0.0 <= located[0] - (grazings[0].value - 0.5 * grazings[0].width) <= 1e-3
                   and all(c.residual <= 1e-7 and abs(c.off_joint) <= 1e-9 for c in corners) and bool(corners),
                   form="full" if full else "quick",
                   metrics={"borders": study["borders"], "n": {f"{r['rpm']:g}": r["n"] for r in study["rows"]},
                            "incomplete": {"impacts": impacts, "revolutions": other["revolutions"],
                                           "orbits": len(branch.points),
                                           "bifurcations": [{"kind": b.kind, "rpm": b.value,
                                                             "multipliers": [complex(m) for m in b.multipliers]}
                                                            for b in branch.bifurcations]},
                            "across": {"impacts": sorted(m_across), "from": float(across.values()[0]),
                                       "to": float(across.values()[-1]), "largest_multiplier": [min(radius), max(radius)],
                                       "grazing": [{"rpm": located[0], "detected_rpm": b.value, "width": b.width,
                                                    "clearances": located[1], "detail": b.detail} for b in grazings],
                                       "corner": [{"rpm": c.rpm, "joint": c.joint, "impact": c.impact, "kind": c.kind,
                                                   "residual": c.residual} for c in corners]}})


def two_block_section(full: bool = False):
    """Two blocks on a belt: the section against the belt velocity, and the regime at chosen velocities by a cycle
    closing on the section or a Lyapunov exponent above zero with its interval (:func:`two_block_regime`). The quick
    form (``full`` False) draws fewer velocities and tests the regime at fewer (``[mechanics.quick]``)."""
    import pandas as pd

    from converters.parallel import parallel_map

    from .defaults import MECHANICS, mechanics_settings
    from .mechanics_plots import diagram_figure
    from .report import Section, csv_bytes, table_html
    model = get_mechanical("stick-slip")
    settings = mechanics_settings(full)
    values = np.linspace(*settings["two_block_V"], settings["two_block_points"])
    transient = settings["two_block_transient"]
    rows = two_block_diagram({}, "V", values, transient=transient)
    regimes = parallel_map(_TwoBlockRegime({}), [float(V) for V in settings["two_block_regimes"]])
    note = quick_form_note(full, f"the section at {len(values)} belt velocities and the regime tested at "
                                 f"{', '.join(f'{V:g}' for V in settings['two_block_regimes'])} m/s (full: "
                                 f"{MECHANICS['two_block_points']} velocities, the regime at "
                                 f"{', '.join(f'{V:g}' for V in MECHANICS['two_block_regimes'])} m/s)")
    how = two_block_regime.__kwdefaults__                                # what _TwoBlockRegime ran with
    table = pd.DataFrame([{"V (m/s)": r["V"], "regime": r["regime"],
                           "cycle (section points)": r["period"] or f"none to {how['tol']:g}",
                           "cycle closing: first, last period of the record": "" if r["closing"] is None else
                           f"{r['closing'][0]:.1e}, {r['closing'][1]:.1e}",
                           "largest Lyapunov exponent (per time unit, 95 %)": f"{r['lyapunov']:+.4f} +- {r['half_width']:.4f}",
                           "section points recorded": r["sections"]} for r in regimes])
    text = (note + "<p>" + model.title + ": m1 = m2 = 1 kg, k1 = 1 N/m, k2 = 1.5 N/m, kc = 1 N/m, Popp friction "
            "with normal "
            "loads m g (the parameters are stated in <code>converters/models/mechanics/stickslip.py</code>; the seed "
            "gives none, and the published configurations it cites could not be reached: this is the project's own "
            f"model). The section: x2 each time block 1 starts to stick (the event method), after {transient:g} time "
            "units of transient (the slower block's natural period, 2 pi max_i sqrt(m_i / (k_i + kc)): "
            f"{model.time_scale(model.resolve({})):.4g} s here, block 1's), over 60 more, against the belt velocity V.</p>"
            "<img src='two_block.png' alt='two-block section'>"
            f"<p>The regime at chosen velocities, each by a test that can fail: after {how['transient']:g} time units "
            f"the section's states (x1, x2, v2) over {how['record']:g} more close into a cycle of k points to "
            f"{how['tol']:g} (every point k on equal to it: a transient still decaying would not), or they do not and "
            "the largest Lyapunov exponent of the flow (the event method's exact Jacobians, one tangent vector over "
            f"{how['blocks']} batches of {how['block']} time units from the run's end; the interval Student's t over "
            "the batches) lies above zero. A periodic orbit of a flow has exponent "
            "zero, so a cycle with an interval above zero, or neither test passing, is reported undetermined.</p>"
            + table_html(table))
    return Section("Mechanics: two blocks on a belt", text,
                   {"two_block.png": diagram_figure(model, "V", rows, title="Bifurcations in a two-block stick-slip "
                                                    "system (this project's model)"),
                    "two_block_regimes.csv": csv_bytes(table)},
                   ok=all(not r.error for r in rows) and all(r["regime"] != "undetermined" for r in regimes),
                   form="full" if full else "quick",
                   metrics={"distinct_section_points": {f"{r.value:.3g}": int(np.unique(np.round(r.states[:, 1], 4)).size)
                                                        for r in rows},
                            "regimes": regimes})


__all__ = ["basins", "Basins", "resolution_check", "sliding_study", "degenerate_switching", "degenerate_portraits", "DegenerateSwitching", "friction_diagram", "two_block_diagram", "two_block_regime", "impact_phase_diagram", "ball_check",
           "friction_agreement", "cam_checks", "ride_left", "chattering_orbit", "chattering_windows", "chattering_transition", "sliding_section", "degenerate_section", "basins_section", "agreement_section", "cam_section", "chattering_windows_section", "two_block_section", "cam_family", "incomplete_orbit", "incomplete_across", "impact_angles",
           "locate_corner", "corner_impacts", "corner_impact", "CornerImpact", "cam_continuation", "cam_continuation_section"]
