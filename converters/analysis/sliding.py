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


__all__ = ["classify_sliding", "shortest_gap", "TYPES"]
