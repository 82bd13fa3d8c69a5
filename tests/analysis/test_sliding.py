"""The seed's sliding bifurcations of the dry-friction oscillator (di Bernardo, Kowalczyk and Nordmark 2002), located by the
continuation on the event method's exact map and named from the orbit's events; the classifier on its own."""
import pytest

from converters.analysis.continuation import OrbitPoint
from converters.analysis.mechanics import sliding_study
from converters.analysis.sliding import TYPES, classify_sliding


def _found(study, kind):
    return [b for b in study.bifurcations if b.kind == kind]


@pytest.mark.slow
def test_crossing_and_switching_sliding_at_A_5():
    """The seed: crossing-sliding at (5, 1.65768), switching-sliding at (5, 2.7992), each within 0.5 %."""
    crossing = _found(sliding_study("friction", {"A": 5.0}, "omega", 1.6, 1.72, points=12), "crossing-sliding")
    assert len(crossing) == 1 and crossing[0].value == pytest.approx(1.65768, rel=5e-3)
    assert crossing[0].value == pytest.approx(1.6572505, abs=1e-5)       # the value the note and README give
    switching = _found(sliding_study("friction", {"A": 5.0}, "omega", 2.75, 2.85, points=10), "switching-sliding")
    assert len(switching) == 1 and switching[0].value == pytest.approx(2.7992, rel=5e-3)
    assert switching[0].width < 1e-6


@pytest.mark.slow
def test_grazing_and_adding_sliding_at_A_half():
    """The seed: grazing-sliding at (0.5, 2.8942) within 0.1 %; adding-sliding between omega = 2.9 and 2.908."""
    study = sliding_study("friction", {"A": 0.5}, "omega", 2.89, 2.92, points=12)
    grazing, adding = _found(study, "grazing-sliding"), _found(study, "adding-sliding")
    assert len(grazing) == 1 and grazing[0].value == pytest.approx(2.8942, rel=1e-3)
    assert len(adding) == 1 and 2.9 < adding[0].value < 2.908
    assert grazing[0].period == adding[0].period == 4          # a period-4 orbit (in forcing periods)
    assert any("ends at the grazing-sliding" in note for note in study.notes)
    # adding-sliding located to 1e-9 (the signature's bisection had left 3e-4 here), where an independent
    # computation (4 T periodicity, the stick force touching the static limit tangentially) puts it
    assert adding[0].width <= 1e-9 * (1 + adding[0].value) and "stick margin" in adding[0].located_by
    assert adding[0].value == pytest.approx(2.904315908, abs=3e-9)
    # the closed-form margin on the merged orbits (above it) 2 and 1 ppm away, extrapolated: zero at the located value
    above = [adding[0].value + d for d in (2e-6, 1e-6)]
    m1, m2 = (_closed_form_margin(w) for w in above)
    assert 0 < m2 < m1
    assert above[1] + m2 * (above[1] - above[0]) / (m1 - m2) == pytest.approx(adding[0].value, abs=1e-8)


def _closed_form_margin(omega, A=0.5, k=1.0, m=1.0, g=10.0, Vdr=1.0, alpha=0.3, beta=0.1):
    """The static friction less the stick force at its interior extremum, on the period-4 orbit at omega, in closed
    form: while stuck x = x_s + Vdr (t - t_s) and the force that holds it is lambda = k x - A cos(omega t), whose
    extrema are where lambda' = k Vdr + A omega sin(omega t) = 0. The orbit's stick segments (their start x_s, t_s
    and end) are the event method's."""
    import math

    import numpy as np

    from converters.analysis.continuation import OrbitFamily
    from converters.analysis.mechanics import mechanical_path, orbit_period
    from converters.methods import EventDriven
    from converters.methods.event.mechanical import MechanicalMachine
    from converters.models.mechanics import get_mechanical
    model = get_mechanical("friction")
    path = mechanical_path(model, {"A": A}, "omega", 2.85, 2.95)
    family = OrbitFamily(path, EventDriven(), 4)
    _, guess = orbit_period(path, 2.906, np.zeros(2))
    x = guess
    for value in (2.906, 2.905, 2.9045, 2.9044, 2.90435, 2.90433, 2.90432, omega):  # down the merged branch
        x = family.orbit(value, x).x0
    run = MechanicalMachine(family.problem(omega), EventDriven()).run(x)[0]
    base = math.asin(-k * Vdr / (A * omega))
    best = math.inf
    for segment in run.segments:
        if not segment.mode.stick:
            continue
        t0, t1, x_s = segment.t0, segment.t1, segment.x0[0]
        for phase in (base, math.pi - base):
            for turn in range(-1, 2 + int(t1 * omega / (2 * math.pi))):
                t = (phase + 2 * math.pi * turn) / omega
                if t0 < t < t1:
                    force = k * (x_s + Vdr * (t - t0)) - A * math.cos(omega * t)
                    best = min(best, m * g * (alpha + beta) - abs(force))
    return best


def _point(events, count):
    return OrbitPoint(0.0, None, None, None, None, tuple(e[1:] for e in events), tuple(events))


@pytest.mark.parametrize("more, fewer, kind", [
    ([(0.1, "stick", 0, 0), (0.1001, "slip", 0, 2), (0.5, "stick", 0, 0), (0.8, "slip", 0, 2)],
     [(0.5, "stick", 0, 0), (0.8, "slip", 0, 2)], "grazing-sliding"),
    ([(0.1, "stick", 0, 0), (0.6, "slip", 0, 2), (0.6001, "stick", 0, 0), (0.8, "slip", 0, 2)],
     [(0.1, "stick", 0, 0), (0.8, "slip", 0, 2)], "adding-sliding"),
    ([(0.3, "stick", 0, 0), (0.3001, "slip", 0, 2), (0.9, "cross", 0, 1)],
     [(0.3, "cross", 0, 2), (0.9, "cross", 0, 1)], "crossing-sliding"),
    ([(0.9, "cross", 0, 1), (0.9001, "stick", 0, 0), (0.3, "slip", 0, 2)],
     [(0.1, "stick", 0, 0), (0.3, "slip", 0, 2)], "switching-sliding"),
])
def test_the_classifier_names_the_short_new_segment(more, fewer, kind):
    more = sorted(more)
    assert classify_sliding(_point(fewer, 0), _point(more, 0))[0] == kind
    assert classify_sliding(_point(more, 0), _point(fewer, 0))[0] == kind
    assert classify_sliding(_point(fewer, 0), _point(fewer, 0)) is None


@pytest.mark.slow
def test_degenerate_switching_sliding_point_satisfies_both_conditions():
    """The switching-sliding point continued in A from (5, 2.7992): the slip field's fold at the arrival turns
    visible at a codimension-two point. Both conditions hold there to 1e-8 as computed and in closed form (the
    stick force k x - A cos(omega t) at the static limit 4 N, its rate k Vdr + A omega sin(omega t) zero); an
    independent integration (closed-form stick, scipy's DOP853 slip) closes the orbit through the arrival in one
    period; and the continuation's classifier names the curve switching-sliding above A* and crossing-sliding below."""
    import math

    import numpy as np
    from scipy.integrate import solve_ivp
    from scipy.optimize import brentq

    from validation.mechanics import degenerate_section
    section = degenerate_section()
    metrics = section.metrics
    A, omega, t_a = metrics["A"], metrics["omega"], metrics["arrival_time"]
    x_a, v_a = metrics["arrival_state"]
    assert section.ok and abs(metrics["margin"]) <= 1e-8 and abs(metrics["curvature"]) <= 1e-8
    k, m, g, Vdr, Fs = 1.0, 1.0, 10.0, 1.0, 10.0 * (0.3 + 0.1)
    assert v_a == pytest.approx(Vdr, abs=1e-12)
    assert abs(abs(-k * x_a + A * math.cos(omega * t_a)) / Fs - 1.0) <= 1e-8
    assert abs((k * Vdr + A * omega * math.sin(omega * t_a)) / m) <= 1e-8
    assert A == pytest.approx(4.8356901, abs=1e-6) and omega == pytest.approx(2.5354292, abs=1e-6)
    # one period from the arrival: stuck until the force reaches -Fs, then slipping back (s < 0) until v = Vdr
    T = 2.0 * math.pi / omega

    def force(t):
        return -k * (x_a + Vdr * (t - t_a)) + A * math.cos(omega * t)
    grid = t_a + np.linspace(0.0, T, 20001)
    values = np.array([force(t) for t in grid])
    assert values.max() <= Fs * (1.0 + 1e-8)                 # the cubic tangency: it stays stuck
    first = int(np.argmax(values < -Fs))
    t_s = brentq(lambda t: force(t) + Fs, grid[first - 1], grid[first], xtol=1e-15)

    def slip(t, y):
        s = y[1] - Vdr
        mu = 0.3 / (1.0 + 1.42 * abs(s)) + 0.1 + 0.01 * s * s
        return [y[1], (-k * y[0] + A * math.cos(omega * t) + m * g * mu) / m]

    def back(t, y):
        return y[1] - Vdr
    back.terminal, back.direction = True, 1.0
    run = solve_ivp(slip, (t_s, t_a + 1.5 * T), [x_a + Vdr * (t_s - t_a), Vdr - 1e-14], method="DOP853",
                    rtol=1e-12, atol=1e-13, events=back)
    t_r, (x_r, _) = run.t_events[0][0], run.y_events[0][0]
    assert t_r == pytest.approx(t_a + T, abs=1e-7) and x_r == pytest.approx(x_a, abs=1e-7)
    # the curve on either side: what the classifier (from the orbits' events alone) names it
    curve = {row["A"]: row for row in metrics["curve"]}
    for side, kind in ((+1, "switching-sliding"), (-1, "crossing-sliding")):
        a = min(curve, key=lambda v: abs(v - (A + side * 0.05)) if side * (v - A) > 0 else np.inf)
        w = curve[a]["omega"]
        study = sliding_study("friction", {"A": a}, "omega", w - 0.01, w + 0.01, points=6)
        found = [b for b in study.bifurcations if b.kind in TYPES]
        assert [b.kind for b in found] == [kind] and found[0].value == pytest.approx(w, abs=1e-6)
