"""Open-loop load and input steps: the buck's input step against the averaged second-order closed form."""
import math

import pytest

from converters.errors import ParameterError
from converters.models import get_model
from converters.run import run_converter, run_summary

BUCK = {"L": "100u", "C": "100u", "R": 5, "D": 0.5}          # zeta = sqrt(L / C) / (2 R) = 0.1, wn = 1e4 rad/s


def test_an_input_steps_overshoot_and_settling_match_the_averaged_second_order_response():
    """Vin 12 -> 15 V at 10 ms: vout 6 -> 7.5 V; overshoot exp(-zeta pi / sqrt(1 - zeta^2)) = 0.7292 (measured
    0.7289), settling into 2 % of the step within the envelope's 3.92 ms and less than half an oscillation
    (pi / wd = 0.32 ms) before it (measured 3.85 ms)."""
    summary = run_summary(run_converter("buck", {**BUCK, "t_step": "10m", "Vin_step": 15}, t_end="20m"))
    step = summary["step"]
    zeta, wn = 0.1, 1e4
    assert step["vout_before"] == pytest.approx(6.0, rel=1e-3) and step["vout_final"] == pytest.approx(7.5, rel=1e-3)
    assert step["overshoot"] == pytest.approx(math.exp(-zeta * math.pi / math.sqrt(1 - zeta ** 2)), rel=5e-3)
    envelope = -math.log(0.02 * math.sqrt(1 - zeta ** 2)) / (zeta * wn)
    assert envelope - math.pi / (wn * math.sqrt(1 - zeta ** 2)) <= step["settling_time_s"] <= envelope
    assert step["settled"]


def test_a_load_step_on_the_open_loop_ccm_buck_barely_moves_vout_and_settles():
    summary = run_summary(run_converter("buck", {**BUCK, "t_step": "10m", "R_step": 2.5}, t_end="25m"))
    step = summary["step"]
    assert "overshoot" not in step and step["vout_final"] == pytest.approx(6.0, rel=1e-3)
    assert step["deviation_V"] > step["band_V"] and step["settled"] and step["settling_time_s"] < 10e-3


def test_a_step_needs_its_instant_and_a_steady_run_refuses_one():
    model = get_model("buck")
    with pytest.raises(ParameterError, match="t_step needs R_step"):
        model.resolve({"t_step": "1m"})
    with pytest.raises(ParameterError, match="R_step and Vin_step need t_step"):
        model.resolve({"R_step": 3})
    with pytest.raises(ParameterError, match="a run with a step"):
        run_converter("buck", {"t_step": "1m", "R_step": 3}, steady=True)


def test_a_step_outside_the_run_is_refused_not_ignored():
    with pytest.raises(ParameterError, match=r"t_step must lie inside the run, in \(0, 0.005\) s .* got 0.01 s: "
                                             r"the step would not happen"):
        run_converter("buck", {**BUCK, "t_step": "10m", "R_step": 2.5}, t_end="5m")
    with pytest.raises(ParameterError, match=r"t_step must lie inside the run"):
        run_converter(get_model("boost", "smc"), {"t_step": "40m", "R_step": 20}, t_end="30m")


def test_an_orbit_of_a_stepped_run_is_refused_wherever_it_is_asked_for():
    """gdcm, gdcm-map and steady_orbit shoot on one period of the circuit: with a step given they answered for the
    circuit before it (the step silently ignored)."""
    from converters.run import steady_orbit
    stepped = {**BUCK, "t_step": "1m", "R_step": 2.5}
    for ask in (lambda: steady_orbit("buck", stepped), lambda: run_converter("buck", stepped, steady=True)):
        with pytest.raises(ParameterError, match="a run with a step \\(t_step\\) is not periodic: run --periods N"):
            ask()
