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

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt

from ..errors import SimulationError

if TYPE_CHECKING:
    from .continuation.family import OrbitFamily, OrbitPoint

TYPES = ("grazing-sliding", "adding-sliding", "crossing-sliding", "switching-sliding")


def shortest_gap(timed: tuple) -> tuple[tuple, tuple, float] | None:
    """(first event, next event, gap) of the two consecutive events closest in time (cyclically, in fractions
    of the orbit's period)."""
    best = None
    for k, event in enumerate(timed):
        following = timed[(k + 1) % len(timed)]
        gap = (following[0] - event[0]) % 1.0
        if best is None or gap < best[2]:
            best = (event, following, gap)
    return best


def classify_sliding(below: OrbitPoint, above: OrbitPoint) -> tuple[str, str] | None:
    """(type, explanation) of the border collision between the orbits ``below`` and ``above`` (OrbitPoints on
    either side, their ``timed_events`` (fraction, kind, pair, config)), or None when it is none of the four."""
    fewer, more = (below, above) if len(below.signature) < len(above.signature) else (above, below)
    change = len(more.signature) - len(fewer.signature)
    if change not in (1, 2) or len(more.timed_events) < 2:
        return None
    found = shortest_gap(more.timed_events)
    assert found is not None                    # two events at least: a gap between them
    first, second, gap = found
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


def stick_margin(family: OrbitFamily, value: float, x0: npt.ArrayLike) -> float:
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
            def margin(t: float, i: int = i) -> float:
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


def approach_zero(evaluate: Callable[[float], tuple[float, Any] | None], start: tuple[float, float, Any], bound: float,
                  tol: float, max_iter: int = 40,
                  ftol: float = 0.0) -> tuple[float, float, list[tuple[float, float, Any]], int]:
    """The zero of a test function that exists on one side of it only (the end of a branch of orbits), approached
    from that side: ``start`` = (value, f, payload) there, ``bound`` a value past the zero (no such orbit), and
    ``evaluate(value)`` -> (f, payload), or None where the value is past the end (its orbit lost, or on the other
    side). The secant's zero from the last two points is approached from the known side (each trial 99 % of the
    way to it, inside the bracket; a tenth of the way to ``bound`` from a single point); a trial past the end
    narrows the bracket from the other side. Stops where the secant's zero is within ``tol`` (relative) of the last
    point, or the last point's |f| is at most ``ftol``. Returns (value, width, points, trials): the zero and that
    distance, or the bracket's middle and width where it could not close, and the points on the known side in the
    order found."""
    points, trials = [tuple(start)], 0
    for _ in range(max_iter):
        v_last, f_last, _ = points[-1]
        if abs(bound - v_last) <= tol * (1.0 + abs(v_last)):      # the bracket itself is narrow enough
            return 0.5 * (v_last + bound), abs(bound - v_last), points, trials
        if abs(f_last) <= ftol:
            return v_last, 0.0, points, trials
        if len(points) >= 2 and points[-2][1] != f_last:
            v_prev, f_prev, _ = points[-2]
            zero = v_last - f_last * (v_last - v_prev) / (f_last - f_prev)
            if abs(zero - v_last) <= tol * (1.0 + abs(v_last)):
                return zero, abs(zero - v_last), points, trials
            trial = v_last + 0.99 * (zero - v_last)
        else:
            trial = v_last + 0.1 * (bound - v_last)
        if not min(v_last, bound) < trial < max(v_last, bound):
            trial = 0.5 * (v_last + bound)
        trials += 1
        try:
            found = evaluate(trial)
        except (SimulationError, ArithmeticError, ValueError):    # a run that cannot follow the orbit there
            found = None
        if found is None:
            bound = trial
        else:
            points.append((trial, *found))
    v_last = points[-1][0]
    return 0.5 * (v_last + bound), abs(bound - v_last), points, trials


def refine_adding_sliding(family: OrbitFamily, merged: OrbitPoint, bound: float, tol: float = 1e-10,
                          max_iter: int = 40) -> tuple[float, float, int]:
    """(value, width, orbits solved) of the adding-sliding point between the orbit ``merged`` (an OrbitPoint: the
    sliding segment still whole) and the parameter value ``bound`` (where it is split, or no such orbit was found),
    located as the end of the merged orbit's branch by :func:`approach_zero`: the zero of its :func:`stick_margin`,
    a smooth function there that reaches zero with a nonzero slope. Each trial's orbit is solved by Newton shooting
    from the last merged one and counts only if it keeps the merged signature."""
    signature = merged.signature
    last = [merged.x0]

    def evaluate(trial: float) -> tuple[float, np.ndarray] | None:
        orbit = family.orbit(trial, last[-1])
        if not (orbit.converged and family.signature(trial, orbit.x0) == signature):
            return None
        margin = stick_margin(family, trial, orbit.x0)
        if not np.isfinite(margin):
            return None
        last.append(orbit.x0)
        return margin, orbit.x0
    value, width, _, solved = approach_zero(evaluate, (merged.value, stick_margin(family, merged.value, merged.x0),
                                                       merged.x0), bound, tol, max_iter)
    return value, width, solved


@dataclass(frozen=True)
class Arrival:
    """Where an orbit reaches a friction contact's surface before it sticks: at ``time`` in ``state``, coming from
    slip direction -``side``; ``margin`` and ``curvature`` as :func:`~converters.methods.event.mechanical.sliding_boundary`
    (the margin positive where it arrives outside the sliding region and crosses first), ``value`` the parameter."""

    value: float
    time: float
    state: np.ndarray
    side: float
    margin: float
    curvature: float
    orbit: np.ndarray


def arrival(family: OrbitFamily, value: float, x0: npt.ArrayLike, pair: int = 0, side: float | None = None) -> Arrival:
    """The arrival of the orbit of ``family`` through x0 at ``value`` at its sliding region nearest the region's
    boundary (the smallest |margin|; given ``side``, only arrivals from slip direction -side: the one followed
    along a parameter, where another, after a short excursion to the other side, may come closer): each stick of
    ``pair`` preceded by a crossing of the same pair (a short excursion past the surface) arrives at that crossing,
    any other at the stick itself."""
    from ..methods.event.mechanical import SLIP_NEG, SLIP_POS, MechanicalMachine, sliding_boundary
    problem = family.problem(value)
    solution = MechanicalMachine(problem, family.method).run(np.asarray(x0, dtype=float))[0]
    events = [e for e in solution.events if e[2] == pair]
    moving = [seg for seg in solution.segments if seg.t1 > seg.t0]
    best = None
    for k, event in enumerate(events):
        if event[1] != "stick":
            continue
        previous = events[k - 1]                # cyclically: the orbit's last event precedes its first
        t = float(previous[0] if previous[1] == "cross" else event[0])
        before = [seg for seg in moving if seg.t1 <= t + 1e-12 * (1.0 + abs(t))]
        states = (before[-1] if before else moving[-1]).mode.states
        if states[pair] not in (SLIP_POS, SLIP_NEG):
            continue
        beyond = -1.0 if states[pair] == SLIP_POS else 1.0
        if side is not None and beyond != side:
            continue
        state = solution.sample([t]).x[0]
        margin, curvature = sliding_boundary(problem, states, pair, beyond, t, state)
        if best is None or abs(margin) < abs(best.margin):
            best = Arrival(float(value), t, state, beyond, margin, curvature, np.array(x0, dtype=float))
    if best is None:
        raise SimulationError(f"the orbit at {value:.10g} never arrives at the sliding region of pair {pair} from a "
                              "slip: it has no switching-sliding point to follow")
    return best


#: Newton iterations for an orbit near a known one (it takes 2 to 4; near a degenerate point, where the map is not
#: Lipschitz, it may not converge at all: that trial is then past the end of the branch).
NEWTON_ITERATIONS = 10
#: The switching-sliding point's margin (|lambda| / F(0) - 1 at the arrival) at which its location stops.
MARGIN_TOL = 1e-10


def switching_sliding_point(family: OrbitFamily, low: float, high: float, x_guess: npt.ArrayLike, pair: int = 0,
                            tol: float = 1e-10, side: float | None = None) -> Arrival:
    """The switching-sliding point between ``low`` and ``high``: the zero of the arrival's margin, approached from
    the side where the orbit arrives inside the sliding region (margin < 0) by :func:`approach_zero` to ``tol``
    (relative) or a margin within MARGIN_TOL of zero; each orbit by Newton shooting from the last one, the arrival
    the one from slip direction -``side`` (default: whichever is nearest its boundary). Only that side is used: on
    the other, close to a degenerate point, the orbit that crosses first may not exist (the map is not Lipschitz
    there; a period-3 attractor was found 1e-9 from the friction oscillator's point). Returns the :class:`Arrival`
    of the last orbit, nearest the point."""
    last = [np.asarray(x_guess, dtype=float)]

    def evaluate(value: float, max_iter: int = NEWTON_ITERATIONS) -> tuple[float, Arrival] | None:
        orbit = family.orbit(value, last[-1], max_iter=max_iter)
        if not orbit.converged:
            return None
        found = arrival(family, value, orbit.x0, pair, side)
        if found.margin >= 0.0:
            return None
        last.append(orbit.x0)
        return found.margin, found
    ends = {}
    for value in (low, high):
        last[:] = [np.asarray(x_guess, dtype=float)]
        try:
            ends[value] = evaluate(value, 30)
        except (SimulationError, ArithmeticError, ValueError):
            ends[value] = None
    inside = [(v, e) for v, e in ends.items() if e is not None]
    if len(inside) != 1:
        raise SimulationError(f"no switching-sliding point between {low:.10g} and {high:.10g}: the orbit arrives "
                              f"{'inside' if inside else 'outside'} the sliding region at both ends")
    (start, found), = inside
    bound = high if start == low else low
    last[:] = [found[1].orbit]
    _, _, points, _ = approach_zero(evaluate, (start, *found), bound, tol, ftol=MARGIN_TOL)
    return points[-1][2]


def degenerate_switching_sliding(family_at: Callable[[float], OrbitFamily], start: float, stop: float, step: float,
                                 first: tuple[float, float], x_guess: npt.ArrayLike, pair: int = 0, tol: float = 1e-10,
                                 on_point: Callable[[float, Arrival], object] | None = None
                                 ) -> tuple[Arrival, float, list[tuple[float, Arrival]]]:
    """The codimension-two point on a curve of switching-sliding points where the slip field's fold at the sliding
    region's boundary turns from invisible to visible (the :class:`Arrival`'s curvature is zero: a cubic tangency);
    past it the same curve is one of crossing-sliding points (the orbit that arrives inside the region sticks only
    briefly, slips at once to the other side and comes back).

    ``family_at(b)`` is the orbit family along the first parameter at the second's value b. The curve is continued
    in the second parameter from ``start`` towards ``stop`` in steps of ``step`` (``first`` brackets its point at
    ``start``; each next point is located by :func:`switching_sliding_point` in a bracket predicted by the secant
    through the two nearest points, the second point a hundredth of a step from the first) until the curvature
    changes sign, and its zero is then found by Brent's method to ``tol`` (relative). Returns (Arrival at the
    point, its second parameter's value, the curve's points as (second, Arrival) in order of the second);
    ``on_point(second, arrival)`` is called as each point is located."""
    from scipy.optimize import brentq
    curve: dict[float, Arrival] = {}

    def located(b: float) -> Arrival:
        b = float(b)
        if b in curve:
            return curve[b]
        nearest = sorted(curve.items(), key=lambda c: abs(c[0] - b))[:2]
        if len(nearest) == 2:                   # the curve's secant through the two nearest points
            (b1, a1), (b2, a2) = nearest
            predicted = a1.value + (a2.value - a1.value) * (b - b1) / (b2 - b1)
            width = max(abs(predicted - a1.value), 1e-6 * (1.0 + abs(predicted)))
        elif nearest:
            predicted, width = nearest[0][1].value, 0.5 * abs(first[1] - first[0])
        else:
            predicted, width = 0.5 * (first[0] + first[1]), 0.5 * abs(first[1] - first[0])
        x, side = (nearest[0][1].orbit, nearest[0][1].side) if nearest else (np.asarray(x_guess, dtype=float), None)
        family = family_at(b)
        for _ in range(4):
            try:
                point = switching_sliding_point(family, predicted - width, predicted + width, x, pair, side=side)
                break
            except SimulationError:
                width *= 2.0
        else:
            raise SimulationError(f"the switching-sliding curve is lost at {b:.10g}: no point found within "
                                  f"{width:.3g} of {predicted:.10g}")
        curve[b] = point
        if on_point is not None:
            on_point(b, point)
        return point
    step = abs(step) * (1.0 if stop > start else -1.0)
    previous = located(start)
    located(start + 0.01 * step)
    b = start
    while True:
        following = b + step
        if (following - stop) * step > 0.0:
            following = stop
        current = located(following)
        if previous.curvature * current.curvature <= 0.0:
            break
        if following == stop:
            raise SimulationError(f"the fold's curvature keeps its sign ({current.curvature:.3g}) along the "
                                  f"switching-sliding curve from {start:.10g} to {stop:.10g}: no degenerate point")
        b, previous = following, current
    root = brentq(lambda v: located(v).curvature, b, following, xtol=tol * (1.0 + abs(b)),
                  rtol=4.0 * np.finfo(float).eps)
    return located(root), float(root), sorted(curve.items())


__all__ = ["classify_sliding", "shortest_gap", "stick_margin", "refine_adding_sliding", "Arrival", "arrival",
           "switching_sliding_point", "degenerate_switching_sliding", "TYPES"]
