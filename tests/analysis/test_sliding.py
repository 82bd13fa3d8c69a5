"""The seed's sliding bifurcations of the dry-friction oscillator (di Bernardo, Kowalczyk and Nordmark 2002), located by the
continuation on the event method's exact map and named from the orbit's events; the classifier on its own."""
import pytest

from converters.analysis.continuation import OrbitPoint
from converters.analysis.sliding import classify_sliding
from validation.mechanics import sliding_study


def _found(study, kind):
    return [b for b in study.bifurcations if b.kind == kind]


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
