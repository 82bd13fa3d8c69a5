"""The continuation engine on maps with closed-form bifurcations (tests/analysis/maps.py), then on the
voltage-mode buck's exact stroboscopic map."""
import numpy as np
import pytest

from converters.analysis import continuation
from converters.analysis.continuation import OrbitFamily, cascade, check_path, follow, switch_branch
from converters.errors import ParameterError

from .maps import TENT_A, TENT_B, MapFamily, MapMethod


def family(kind, periods=1):
    return OrbitFamily(MapFamily(kind), MapMethod(), periods)


def kinds(branch):
    return [b.kind for b in branch.bifurcations]


def test_the_logistic_cascade_doubles_at_3_and_1_plus_sqrt6_with_the_closed_form_period_2_orbit():
    branches = cascade(family("logistic"), 2.5, 3.5, [0.5], max_period=2)
    assert [b.period for b in branches] == [1, 2]
    first, second = branches
    assert first.complete and second.complete
    assert kinds(first) == ["period-doubling"]
    pd1 = first.bifurcations[0]
    assert pd1.value == pytest.approx(3.0, abs=1e-7)
    assert pd1.stable_before and not pd1.stable_after
    assert np.real(pd1.multipliers[0]) == pytest.approx(-1.0, abs=1e-6)
    pd2 = [b for b in second.bifurcations if b.kind == "period-doubling"]
    assert len(pd2) == 1 and pd2[0].value == pytest.approx(1.0 + np.sqrt(6.0), abs=1e-7)
    assert second.parent is pd1
    for point in second.points[1:]:                    # after the pitchfork point itself
        p = point.value
        exact = ((p + 1) + np.array([-1.0, 1.0]) * np.sqrt((p - 3) * (p + 1))) / (2 * p)
        # next to the pitchfork P^2 - I is nearly singular: the orbit is resolved less finely there
        assert np.sort(point.samples[:, 0]) == pytest.approx(exact, abs=1e-9 if p > 3.01 else 1e-7)
        assert point.stable == (p < 1 + np.sqrt(6.0))
    # the period-1 orbit keeps its closed form along the whole path, unstable after p = 3
    for point in first.points:
        assert point.x0[0] == pytest.approx(1 - 1 / point.value, abs=1e-10)
        assert point.multipliers[0].real == pytest.approx(2 - point.value, abs=1e-8)


@pytest.mark.parametrize("max_step", [0.02, 0.1])
def test_located_values_do_not_depend_on_the_step(max_step):
    branch = follow(family("logistic"), 2.2, 3.3, [0.5], max_step=max_step)
    assert branch.bifurcations[0].value == pytest.approx(3.0, abs=1e-8)
    assert branch.bifurcations[0].width < 1e-6


def test_pseudo_arclength_passes_the_fold_and_locates_it():
    """x -> p + x - x^2 from p = 0.5 (x = sqrt(0.5)) down to p = -1: the branch turns at p = 0 and comes back
    on x = -sqrt(p); the fold test det(J - I) = -2 x changes sign there."""
    branch = follow(family("fold"), 0.5, -1.0, [0.7], warm_up=0)
    folds = [b for b in branch.bifurcations if b.kind == "fold"]
    assert len(folds) == 1
    assert folds[0].value == pytest.approx(0.0, abs=1e-7)
    values = branch.values()
    assert values.min() == pytest.approx(0.0, abs=1e-3)            # it never goes below the fold
    assert branch.points[-1].x0[0] == pytest.approx(-np.sqrt(0.5), abs=1e-9)   # back on the other side at p = 0.5
    for point in branch.points:
        assert point.x0[0] ** 2 == pytest.approx(point.value, abs=1e-9)
        assert point.stable == (point.x0[0] > 0)


def test_a_complex_pair_crossing_the_unit_circle_is_a_neimark_sacker_bifurcation():
    """The delayed logistic map: the fixed point's multipliers have modulus sqrt(p - 1)."""
    branch = follow(family("delayed"), 1.6, 2.4, [0.4, 0.4], warm_up=0)
    ns = [b for b in branch.bifurcations if b.kind == "neimark-sacker"]
    assert len(ns) == 1 and ns[0].value == pytest.approx(2.0, abs=1e-7)
    assert np.abs(ns[0].multipliers) == pytest.approx([1.0, 1.0], abs=1e-6)
    assert ns[0].stable_before and not ns[0].stable_after
    assert "period-doubling" not in kinds(branch) and "fold" not in kinds(branch)


def test_a_border_collision_is_located_with_the_jump_of_its_multiplier():
    """The skew tent map: the fixed point crosses the border at p = 0; its multiplier jumps from 0.5 to -1.5
    there (across -1), which is the border collision, not a smooth period doubling."""
    branch = follow(family("tent"), -1.0, 1.0, [-1.0], warm_up=0)
    assert kinds(branch) == ["border-collision"]
    bc = branch.bifurcations[0]
    assert bc.value == pytest.approx(0.0, abs=1e-7)
    assert bc.multipliers[0].real == pytest.approx(TENT_A)
    assert bc.multipliers_after[0].real == pytest.approx(TENT_B)
    assert bc.stable_before and not bc.stable_after
    assert "det(J + I) changes sign" in bc.detail and "switching to config1" in bc.detail


def test_a_branch_can_end_at_the_first_bifurcation_of_a_kind():
    """stop_at: the tent map's branch ends at its border collision (x = 0) instead of the path's end, the
    collision located as without it; a kind that is not one is refused, naming the kinds."""
    whole = follow(family("tent"), -1.0, 1.0, [-1.0], warm_up=0)
    cut = follow(family("tent"), -1.0, 1.0, [-1.0], warm_up=0, stop_at=("border-collision",))
    assert whole.values().max() == 1.0 and whole.complete
    assert kinds(cut) == ["border-collision"] and cut.bifurcations[0].value == whole.bifurcations[0].value
    assert 0.0 < cut.values().max() < 0.5 and cut.message.startswith("stopped at the border-collision at ")
    alone = follow(family("tent"), -1.0, 1.0, [-1.0], warm_up=0, stop_at="border-collision")     # one kind, a str
    assert alone.values().max() == cut.values().max()
    with pytest.raises(ParameterError, match="stop_at must name bifurcation kinds .*; got 'grazing'"):
        follow(family("tent"), -1.0, 1.0, [-1.0], stop_at=("grazing",))


def test_branch_switching_needs_a_period_doubling_and_paths_are_checked():
    branch = follow(family("tent"), -1.0, 1.0, [-1.0], warm_up=0)
    with pytest.raises(ParameterError, match="starts at a period doubling; got a border-collision"):
        switch_branch(family("tent"), branch.bifurcations[0], -1.0, 1.0)
    with pytest.raises(ParameterError, match=r"the path of Vin must lie in \(0, inf\); got -5:36"):
        check_path("Vin", -5.0, 36.0, 0.0, np.inf)
    with pytest.raises(ParameterError, match="START != STOP"):
        check_path("Vin", 20.0, 20.0, 0.0, np.inf)
    with pytest.raises(ParameterError, match="STOP != START"):
        follow(family("logistic"), 3.0, 3.0, [0.5])


def test_a_branch_that_cannot_start_says_why_and_keeps_what_it_has():
    """No fixed point of x -> p + x - x^2 for p < 0: Newton fails and the branch says so."""
    branch = follow(family("fold"), -1.0, -0.5, [1.0], warm_up=0)
    assert not branch.complete and branch.points == []
    assert "no orbit of period 1 at -1" in branch.message


def test_the_test_functions():
    J = np.array([[-1.2, 0.0], [0.0, 0.5]])
    t = continuation.test_functions(J, np.linalg.eigvals(J))
    assert t["period-doubling"] == pytest.approx(-0.2 * 1.5) and t["fold"] == pytest.approx(-2.2 * -0.5)
    assert t["neimark-sacker"] is None
    R = 1.1 * np.array([[np.cos(1.0), -np.sin(1.0)], [np.sin(1.0), np.cos(1.0)]])
    assert continuation.test_functions(R, np.linalg.eigvals(R))["neimark-sacker"] == pytest.approx(0.1)


def test_a_branch_that_fails_part_way_says_where_and_keeps_its_orbits():
    """A model that refuses values above 3.2 (as a parameter's range would): the branch stops just below with
    the reason, and every orbit found up to there is kept."""
    class Refusing(MapFamily):
        def __call__(self, value):
            if value > 3.2:
                raise ParameterError(f"p must be <= 3.2; got {value}")
            return super().__call__(value)
    branch = follow(OrbitFamily(Refusing("logistic"), MapMethod(), 1), 2.5, 3.5, [0.5])
    assert not branch.complete
    assert branch.message.startswith("continuation of the period-1 orbit stopped at 3.1999")
    assert "the model or method refused the next orbit (p must be <= 3.2; got 3.2" in branch.message
    assert branch.values().max() == pytest.approx(3.2, abs=1e-3) and len(branch.points) > 10
    assert [b.kind for b in branch.bifurcations] == ["period-doubling"]      # found before it stopped


def test_locating_a_sign_change_bisects_past_orbits_whose_test_is_undefined(monkeypatch):
    """A Neimark-Sacker test is undefined (None) where the multipliers are real: a false-position trial that lands
    there is not on a's side, and the next trial bisects towards it instead of dividing by None (it had raised a
    TypeError). Here the test is v - 0.75 on a 1-D branch, undefined on (0.5, 0.74): the first trial (0.75 by
    false position) is past the zero, the second lands where the test is undefined, and the bracket closes on
    where a's side ends, 0.5."""
    from types import SimpleNamespace

    from converters.analysis.continuation import detection

    def point(value):
        test = None if 0.5 < value < 0.74 else value - 0.75
        return SimpleNamespace(value=value, x0=np.array([value]), tests={"neimark-sacker": test})

    family = SimpleNamespace(point=lambda value, x, jacobian: point(value))
    scaling = SimpleNamespace(z=lambda x0, value: np.array([value]))
    monkeypatch.setattr(detection, "_correct", lambda family, scaling, trial, direction, guess, tol:
                        SimpleNamespace(value=float(trial[0]), x=trial.copy(), jacobian=None))
    a, b = point(0.0), point(1.0)
    lo, hi, note = detection._locate(
        family, scaling, a, b, lambda s: s.tests["neimark-sacker"] is not None and s.tests["neimark-sacker"] < 0,
        lambda s: s.tests["neimark-sacker"], 1e-9, 1e-8)
    assert note == ""
    assert lo.value <= 0.5 <= hi.value and hi.value - lo.value <= 1e-8
    assert lo.tests["neimark-sacker"] < 0 and hi.tests["neimark-sacker"] is None
