"""The four codimension-one sliding bifurcations of a periodic orbit, named from its events.

A Filippov system's orbit meets the switching surface in a few ways, each an event of its run: ``stick``
(it reaches the surface inside the sliding region and slides), ``slip`` (a sliding segment ends at the
boundary of the sliding region), ``cross`` (it crosses the surface outside the sliding region). At a sliding
bifurcation the orbit touches the boundary of the sliding region and a new piece of orbit is born with zero
length (di Bernardo, Kowalczyk and Nordmark 2002; for the seed's dry-friction oscillator Kowalczyk and
Piiroinen 2008). Next to the bifurcation that piece is the shortest gap between consecutive events on the
side with more events, and what bounds it names the bifurcation:

    grazing-sliding    stick -> slip, two events more: a short sliding segment inside a slip phase (the orbit
                       grazes the surface at the sliding region's boundary)
    adding-sliding     slip -> stick, two events more: a short slip excursion splits a sliding segment (a
                       sliding segment is added)
    crossing-sliding   stick -> slip, one event more: a crossing at the sliding region's boundary turns into a
                       short slide (cross becomes stick, slip)
    switching-sliding  cross -> stick, one event more: the orbit crosses the surface just before it slides
                       (stick becomes cross, stick: its arrival at the sliding region switches side)

Anything else is a plain border collision.
"""
from __future__ import annotations

import numpy as np

from ..errors import SimulationError

TYPES = ("grazing-sliding", "adding-sliding", "crossing-sliding", "switching-sliding")


def shortest_gap(timed: tuple):
    """(first event, next event, gap) of the two consecutive events closest in time (cyclically, in fractions
    of the orbit's period)."""
    best = None
    for k, event in enumerate(timed):
        following = timed[(k + 1) % len(timed)]
        gap = (following[0] - event[0]) % 1.0
        if best is None or gap < best[2]:
            best = (event, following, gap)
    return best


def classify_sliding(below, above):
    """(type, explanation) of the border collision between the orbits ``below`` and ``above`` (OrbitPoints on
    either side, their ``timed_events`` (fraction, kind, pair, config)), or None when it is none of the four."""
    fewer, more = (below, above) if len(below.signature) < len(above.signature) else (above, below)
    change = len(more.signature) - len(fewer.signature)
    if change not in (1, 2) or len(more.timed_events) < 2:
        return None
    first, second, gap = shortest_gap(more.timed_events)
    pair = first[2]
    if second[2] != pair:
        return None
    kinds = (first[1], second[1])
    side = "above" if more is above else "below"
    if change == 2 and kinds == ("stick", "slip"):
        return "grazing-sliding", (f"a sliding segment of pair {pair} ({gap:.2g} of the period) exists {side} it: the "
                                   "orbit grazes the surface at the sliding region's boundary")
    if change == 2 and kinds == ("slip", "stick"):
        return "adding-sliding", (f"a slip excursion of pair {pair} ({gap:.2g} of the period) splits a sliding segment "
                                  f"{side} it: a sliding segment is added")
    if change == 1 and kinds == ("stick", "slip") and any(e[0] == "cross" and e[1] == pair for e in fewer.signature):
        return "crossing-sliding", (f"{side} it a crossing of pair {pair} is a short sliding segment ({gap:.2g} of the "
                                    "period): the crossing point passes the sliding region's boundary")
    if change == 1 and kinds == ("cross", "stick"):
        return "switching-sliding", (f"{side} it pair {pair} crosses the surface {gap:.2g} of the period before it "
                                     "slides: its arrival at the sliding region switches side")
    return None




#: Samples per sliding segment where its stick margin's interior minima are looked for before they are refined.
MARGIN_SAMPLES = 100


def stick_margin(family, value: float, x0) -> float:
    """The smallest interior minimum of a sliding segment's margin, F_s - |lambda(t)| (the static friction less the
    force that keeps the contact stuck), over the orbit of ``family`` through x0 at ``value``: the test function of
    adding-sliding, zero where the stick force touches the static limit tangentially inside a sliding segment.
    Each segment's margin ends at zero (where it slips) and is sampled, its interior local minima refined by a
    bounded scalar minimisation on the exact flow; inf where no sliding segment dips."""
    from scipy.optimize import minimize_scalar

    from ..methods.event.mechanical import MechanicalMachine
    problem = family.problem(value)
    solution = MechanicalMachine(problem, family.method).run(np.asarray(x0, dtype=float))[0]
    static = np.array([f.law.static for f in problem.frictions])
    best = np.inf
    for segment in solution.segments:
        if not segment.mode.stick or segment.t1 - segment.t0 <= 0.0:
            continue
        for i in segment.mode.stick:
            def margin(t, i=i):
                return float(static[i] - abs(solution.sample([t]).u[0, i]))
            times = np.linspace(segment.t0, segment.t1, MARGIN_SAMPLES)
            values = static[i] - np.abs(solution.sample(times).u[:, i])
            for k in np.flatnonzero((values[1:-1] < values[:-2]) & (values[1:-1] <= values[2:])) + 1:
                if k >= MARGIN_SAMPLES - 2:             # the end of the segment, where the margin reaches zero
                    continue
                found = minimize_scalar(margin, bounds=(times[k - 1], times[k + 1]), method="bounded",
                                        options={"xatol": 1e-13 * (1.0 + abs(times[k]))})
                best = min(best, float(found.fun))
    return best


def refine_adding_sliding(family, merged, bound: float, tol: float = 1e-10, max_iter: int = 40):
    """(value, width, orbits solved) of the adding-sliding point between the orbit ``merged`` (an OrbitPoint: the
    sliding segment still whole) and the parameter value ``bound`` (where it is split, or no such orbit was found),
    located as the end of the merged orbit's
    branch: the zero of its :func:`stick_margin`, a smooth function there that reaches zero with a nonzero slope.
    The secant's zero from the last two merged orbits is approached from the merged side (each trial 99 % of the
    way to it, Newton shooting from the nearest merged orbit, inside the bracket): a trial whose orbit does not keep
    the merged signature narrows the bracket from the other side. Stops where the secant's zero is within ``tol``
    (relative) of the last merged orbit; ``width`` is that distance, or the bracket where it could not close."""
    signature = merged.signature
    points = [(merged.value, stick_margin(family, merged.value, merged.x0), merged.x0)]
    solved = 0
    for _ in range(max_iter):
        v_last, f_last, x_last = points[-1]
        if abs(bound - v_last) <= tol * (1.0 + abs(v_last)):      # the bracket itself is narrow enough
            return 0.5 * (v_last + bound), abs(bound - v_last), solved
        if len(points) >= 2 and points[-2][1] != f_last:
            v_prev, f_prev, _ = points[-2]
            zero = v_last - f_last * (v_last - v_prev) / (f_last - f_prev)
            if abs(zero - v_last) <= tol * (1.0 + abs(v_last)):
                return zero, abs(zero - v_last), solved
            trial = v_last + 0.99 * (zero - v_last)
        else:                                   # one point: a step a tenth of the way to the other side
            trial = v_last + 0.1 * (bound - v_last)
        if not min(v_last, bound) < trial < max(v_last, bound):
            trial = 0.5 * (v_last + bound)
        solved += 1
        try:
            orbit = family.orbit(trial, x_last)
            if orbit.converged and family.signature(trial, orbit.x0) == signature:
                margin = stick_margin(family, trial, orbit.x0)
                if np.isfinite(margin):
                    points.append((trial, margin, orbit.x0))
                    continue
        except (SimulationError, ArithmeticError, ValueError):    # a run that cannot follow the orbit there
            pass
        bound = trial                           # past the end of the merged branch (or no orbit there)
    v_last = points[-1][0]
    return 0.5 * (v_last + bound), abs(bound - v_last), solved


__all__ = ["classify_sliding", "shortest_gap", "stick_margin", "refine_adding_sliding", "TYPES"]
