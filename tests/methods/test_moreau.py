"""Moreau-Jean time-stepping: penetration O(h) and rest at the closed-form time (bouncing ball), stick
intervals converging to the event method's at first order (friction), impact times within 1 % (cam), and what
it refuses."""
import numpy as np
import pytest

from converters.analysis.mechanics import cam_checks, friction_agreement
from converters.errors import ParameterError
from converters.methods import EventDriven, MoreauJean
from converters.models import get_model
from converters.models.mechanics import accumulation_time, get_mechanical
from converters.simulate import simulate


def test_the_bouncing_ball_penetrates_by_o_h_and_comes_to_rest_at_the_closed_form_time():
    model = get_mechanical("bouncing-ball")
    p = model.resolve({})
    exact = accumulation_time(p["H"], p["g"], p["e"])
    out = []
    for h in (1e-4, 1e-5):
        run = simulate(model.problem(p, 1.5 * exact), MoreauJean(h=h))
        moving = np.flatnonzero(np.abs(run.x[:, 1]) > 1e-9)
        out.append((-run.x[:, 0].min(), run.t[moving[-1] + 1]))
    (pen1, rest1), (pen2, rest2) = out
    assert pen1 < 5e-4 and pen1 / pen2 == pytest.approx(10.0, rel=0.2)          # O(h)
    assert abs(rest2 - exact) < abs(rest1 - exact) and abs(rest2 / exact - 1.0) < 1e-3


def test_stick_intervals_converge_to_the_exact_ones_at_first_order():
    result = friction_agreement(steps=(500, 2000, 8000, 32000))
    rows = result["rows"]
    errors = np.array([r["max_error_T"] for r in rows])
    steps = np.array([r["steps_per_period"] for r in rows])
    assert all(r["sticks"] == len(result["exact"]) == 1 for r in rows)
    assert errors[1] < 1e-2                                   # within 1 % of the period from T/2000 on
    assert np.polyfit(np.log(1.0 / steps), np.log(errors), 1)[0] == pytest.approx(1.0, abs=0.15)


def test_impact_times_agree_with_the_event_method_within_one_percent():
    result = cam_checks()
    assert result["detachment_error_s"] < 1e-9
    assert all(r["max_error_T"] < 1e-2 for r in result["moreau"])
    assert result["moreau"][-1]["max_error_T"] < 1e-3


def test_moreau_jean_takes_mechanical_problems_only():
    buck = get_model("buck")
    p = buck.resolve({})
    with pytest.raises(ParameterError, match="the Moreau-Jean method takes mechanical problems"):
        simulate(buck.problem(p, 1e-4), MoreauJean(h=1e-7))
    with pytest.raises(ParameterError, match=r"theta must be in \[0.5, 1\]; got 0.2"):
        MoreauJean(h=1e-3, theta=0.2)
    with pytest.raises(ParameterError, match="h must be positive"):
        MoreauJean(h=0)


@pytest.mark.parametrize("h", [1e-4, 5e-5])
def test_a_follower_riding_a_lifting_cam_stays_on_it_until_the_spring_cannot_follow(h):
    """At 358 rpm the cam starts to lift at t = 0 with the follower on it: Moreau-Jean keeps the contact (its
    activation predicts the gap with the relative acceleration) and releases it where the event method does, within
    a step, with no impact before the follower's first landing (at 0.0929 s). Predicting with the rate alone, the
    gap's +2.5e-12 after the first step let the follower fly one step and bounce at t = 3e-4 s."""
    model = get_mechanical("cam-follower")
    p = model.resolve({"rpm": 358})
    exact = simulate(model.problem(p, 0.09), EventDriven()).events
    events = simulate(model.problem(p, 0.09), MoreauJean(h=h)).events
    assert list(events["kind"]) == ["detach"] and list(exact["kind"]) == ["detach"]
    assert abs(events["time"].iloc[0] - exact["time"].iloc[0]) <= h
