"""Detection and location of bifurcations between two orbits: a test function's change of sign, a change of the
orbit's event signature (a border collision), located by bisection on the chord."""
from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np

from .corrector import _correct
from .family import TEST_NAMES, Bifurcation, OrbitPoint

if TYPE_CHECKING:
    from .corrector import _Scaling
    from .family import OrbitFamily


def _detect(family: OrbitFamily, scaling: _Scaling, a: OrbitPoint, b: OrbitPoint, tol: float,
            locate_tol: float) -> list[Bifurcation]:
    """Every bifurcation between consecutive orbits a and b (module docstring)."""
    found: list[Bifurcation] = []
    collision = None
    if a.signature != b.signature:
        lo, hi, note = _locate(family, scaling, a, b, lambda s: s.signature == a.signature, None, tol, locate_tol)
        collision = _border_collision(family, lo, hi, note)
    tests_a, tests_b = a.tests, b.tests
    for kind in ("period-doubling", "fold", "neimark-sacker"):
        fa, fb = tests_a[kind], tests_b[kind]
        if fa is None or fb is None or fa == 0.0 or np.sign(fa) == np.sign(fb):
            continue
        lo, hi, note = _locate(family, scaling, a, b,
                               lambda s, kind=kind: s.tests[kind] is not None and np.sign(s.tests[kind]) == np.sign(fa),
                               lambda s, kind=kind: s.tests[kind], tol, locate_tol)
        at_collision = collision is not None and abs(0.5 * (lo.value + hi.value) - collision.value) <= (
            2.0 * (collision.width + abs(hi.value - lo.value)) + 1e-12 * (1.0 + abs(collision.value)))
        if at_collision:                                         # the multipliers jump at the border collision
            crossing = {"period-doubling": "-1", "fold": "+1"}.get(kind, "the unit circle")
            collision = replace(collision, detail=collision.detail + f"; {TEST_NAMES[kind]} changes sign there (a "
                                f"multiplier jumps across {crossing})")
            continue
        f_lo, f_hi = lo.tests[kind], hi.tests[kind]
        if f_lo is not None and f_hi is not None and f_lo != f_hi:
            value = lo.value + (hi.value - lo.value) * f_lo / (f_lo - f_hi)
        else:
            value = 0.5 * (lo.value + hi.value)
        near = lo if abs(f_lo or 0.0) <= abs(f_hi or 0.0) else hi
        below, above = (lo, hi) if lo.value <= hi.value else (hi, lo)
        found.append(Bifurcation(kind, float(value), family.periods, near.multipliers, near.x0,
                                 f"false position (Illinois) on {TEST_NAMES[kind]} along the branch, then the secant zero "
                                 "of the final bracket" + (f" ({note})" if note else ""), abs(hi.value - lo.value),
                                 below.stable, above.stable))
    if collision is not None:
        found.append(collision)
    return sorted(found, key=lambda b: b.value)


def _locate(family: OrbitFamily, scaling: _Scaling, a: OrbitPoint, b: OrbitPoint,
            # each called with an OrbitPoint (`...`: the callers' lambdas bind their kind as a default argument)
            same_as_a: Callable[..., bool], test: Callable[..., float | None] | None, tol: float,
            locate_tol: float) -> tuple[OrbitPoint, OrbitPoint, str]:
    """Bracket the change between orbits a and b of the predicate ``same_as_a`` (true at a, false at b), to a
    chord of ``locate_tol`` in scaled variables. Each new orbit is solved on the plane normal to the chord
    through the trial point, so that a bracket around a fold narrows too. The trial point is the chord's
    midpoint (bisection), or with a signed ``test`` function its false-position zero (Illinois: the
    retained end's value is halved, so both ends converge). Returns (lo, hi, note): the final bracket, lo
    on a's side, and a note when it could not be narrowed."""
    lo, hi = a, b
    f_lo, f_hi = (test(a), test(b)) if test is not None else (None, None)
    retained = 0
    for _ in range(100):
        z_lo, z_hi = scaling.z(lo.x0, lo.value), scaling.z(hi.x0, hi.value)
        chord = z_hi - z_lo
        length = float(np.linalg.norm(chord))
        if length <= locate_tol:
            return lo, hi, ""
        fraction = 0.5
        # an end whose test is undefined (no complex pair for the Neimark-Sacker test) is bisected towards
        if f_lo is not None and f_hi is not None and f_lo != f_hi:
            fraction = min(max(f_lo / (f_lo - f_hi), 0.02), 0.98)   # a step off the ends, so the bracket shrinks
        trial = z_lo + fraction * chord
        solved = _correct(family, scaling, trial, chord / length, trial, tol)
        if solved is None:
            return lo, hi, f"bracket left at chord length {length:.2g}: no orbit found inside it"
        mid = family.point(solved.value, solved.x, solved.jacobian)
        f_mid = test(mid) if test is not None else None
        if same_as_a(mid):
            lo, f_lo = mid, f_mid
            retained = retained + 1 if retained >= 0 else 1       # hi retained again: halve its value
            if f_hi is not None and retained >= 2:
                f_hi *= 0.5
        else:
            hi, f_hi = mid, f_mid
            retained = retained - 1 if retained <= 0 else -1
            if f_lo is not None and retained <= -2:
                f_lo *= 0.5
    return lo, hi, "bracket left after 100 steps"


def _border_collision(family: OrbitFamily, lo: OrbitPoint, hi: OrbitPoint, note: str) -> Bifurcation:
    pairs, configs = family.event_names(lo.value)
    below, above = (lo, hi) if lo.value <= hi.value else (hi, lo)
    detail = (f"events per orbit {len(below.signature)} -> {len(above.signature)}: "
              + _describe_change(below.signature, above.signature, pairs, configs))
    how = "bisection on the orbit's event signature along the branch" + (f" ({note})" if note else "")
    kind = "border-collision"
    named = family.classify(below, above) if family.classify is not None else None
    if named is not None:
        kind, explanation = named
        detail = f"{explanation}; {detail}"
    return Bifurcation(kind, 0.5 * (lo.value + hi.value), family.periods, below.multipliers,
                       below.x0, how, abs(hi.value - lo.value), below.stable, above.stable,
                       multipliers_after=above.multipliers, detail=detail)


def _event_label(event: tuple[str, int, int], pairs: Sequence[str], configs: Sequence[str]) -> str:
    kind, pair, config = event
    if kind == "switch":
        return f"switching to {configs[config] if 0 <= config < len(configs) else config}"
    name = pairs[pair] if 0 <= pair < len(pairs) else f"pair {pair}"
    where = f" in {configs[config]}" if 0 <= config < len(configs) else ""
    # In the LCS's own terms: which of the pair's u and y is held at zero is the model's business.
    state = {"activate": "held (y = 0)", "release": "freed (u = 0)"}.get(kind, kind)
    if kind in ("stick", "slip", "cross", "touch", "impact", "chatter", "detach"):     # mechanical contacts
        where = f" ({configs[config]})" if 0 <= config < len(configs) else ""
    return f"{name} {state}{where}"


def _describe_change(before: tuple, after: tuple, pairs: Sequence[str], configs: Sequence[str]) -> str:
    from collections import Counter
    count_before, count_after = Counter(before), Counter(after)
    gained = [f"{_event_label(e, pairs, configs)} x{count_after[e] - count_before[e]}"
              for e in count_after if count_after[e] > count_before[e]]
    lost = [f"{_event_label(e, pairs, configs)} x{count_before[e] - count_after[e]}"
            for e in count_before if count_before[e] > count_after[e]]
    parts = ([f"appear: {', '.join(gained)}"] if gained else []) + ([f"vanish: {', '.join(lost)}"] if lost else [])
    return "; ".join(parts) or "the order of the events changes"


# --- branch switching -------------------------------------------------------------------------------
