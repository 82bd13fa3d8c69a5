"""The closed loops in ngspice (each control's netlist: the converter's own file with the loop written as behavioural
sources and a clocked latch) against the LCS on the same circuit, started on the event method's orbit."""
import numpy as np
import pytest

from converters.methods import EventDriven
from converters.run import resolve_model, run_converter, steady_state

pytestmark = pytest.mark.spice


def _from_the_orbit(model, params: dict, periods: int = 30):
    """(the event method's run, ngspice's, T): both ``periods`` periods from the event method's orbit."""
    orbit = steady_state(model, model.resolve(params), EventDriven())
    lcs = run_converter(model, params, method="event", periods=periods, x0=orbit.x0)
    spice = run_converter(model, params, method="spice", periods=periods, x0=orbit.x0)
    return lcs, spice, model.period(model.resolve(params))


def _per_period(tr, t0: float, T: float, count: int) -> np.ndarray:
    return np.array([tr.mean("vout", t0=t0 + j * T, t1=t0 + (j + 1) * T) for j in range(count)])


def test_the_type_iii_compensated_buck_in_ngspice_regulates_and_recovers_from_a_load_step_as_the_lcs():
    """The default voltage loop (the type III designed for 10 kHz and 60 degrees): from the orbit, 1 ms, then R 10 ->
    5 ohm: the steady means agree to 4e-6 (issue: 0.1 %), the per-period undershoot 60.28 and 60.14 mV (0.24 % apart;
    issue: 5 %)."""
    model = resolve_model("buck", "voltage-loop")
    orbit = steady_state(model, model.resolve({}), EventDriven())
    T, step = 1e-5, {"t_step": "1m", "R_step": 5}
    lcs = run_converter(model, step, method="event", t_end="2m", x0=orbit.x0)
    spice = run_converter(model, step, method="spice", t_end="2m", x0=orbit.x0)
    before = [tr.mean("vout", t0=0.9e-3, t1=1e-3) for tr in (lcs, spice)]
    assert before[1] == pytest.approx(before[0], rel=1e-3)
    undershoot = [5.0 - _per_period(tr, 1e-3, T, 100).min() for tr in (lcs, spice)]
    assert undershoot[0] > 0.05
    assert undershoot[1] == pytest.approx(undershoot[0], rel=0.05)
    final = [_per_period(tr, 1.9e-3, T, 10).mean() for tr in (lcs, spice)]
    assert final[1] == pytest.approx(final[0], rel=1e-3)


@pytest.mark.parametrize("converter, params", [("buck", {"Iref": 0.6, "ma": 2e4}),
                                               ("buck-boost", {"Iref": 2.0, "ma": 1e4, "R": 10})])
def test_peak_current_mode_in_ngspice_stays_on_the_lcs_orbit(converter, params):
    """30 periods from the event method's orbit: the means of vout over the last 10 agree to 1.4e-5 and 2.3e-5."""
    model = resolve_model(converter, "peak-current")
    lcs, spice, T = _from_the_orbit(model, params)
    assert spice.mean("vout", t0=20 * T) == pytest.approx(lcs.mean("vout", t0=20 * T), rel=1e-4)


@pytest.mark.parametrize("params", [{"Iv": 0.5}, {"Iv": 0.3, "ma": 3e4}])
def test_valley_current_mode_in_ngspice_stays_near_the_lcs_orbit(params):
    """30 periods from the event method's orbit: 5.1e-4 and 7.7e-4 apart (measured; peak current mode's latch is
    15 to 50 times closer: not yet explained)."""
    model = resolve_model("buck", "valley-current")
    lcs, spice, T = _from_the_orbit(model, params)
    assert spice.mean("vout", t0=20 * T) == pytest.approx(lcs.mean("vout", t0=20 * T), rel=1e-3)


@pytest.mark.parametrize("control", ["voltage-loop", "peak-current", "current-loop"])
def test_compare_runs_the_clocked_loops_against_ngspice(capsys, control):
    """pcsuite compare on a closed loop: both started on the LCS's orbit, every check passes (measured: the type III
    buck's mean 1e-5 apart, its turn-off 6.1e-5 T; peak current mode's 6.3e-5 T)."""
    import json

    from validation.cli import main
    assert main(["compare", "buck", "--control", control, "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["passed"] and summary["metrics"]["mode_agreement"] == 1.0
    assert summary["metrics"]["vout_mean_rel_error"] < 1e-4 and summary["metrics"]["turn_off_error_T"] < 1e-3


def test_the_leading_edge_voltage_loop_in_ngspice_stays_near_the_lcs_orbit():
    """-p leading=1: the clock turns the switch off, vc meeting the falling carrier turns it on (the latch reset by
    the clock): 30 periods from the orbit, the means 1.5e-4 apart (trailing edge, the same run: 1.5e-4)."""
    model = resolve_model("buck", "voltage-loop")
    lcs, spice, T = _from_the_orbit(model, {"leading": 1})
    assert spice.mean("vout", t0=20 * T) == pytest.approx(lcs.mean("vout", t0=20 * T), rel=1e-3)
    assert lcs.mean("vout", t0=20 * T) == pytest.approx(5.0, rel=1e-9)


def test_the_maximum_duty_ratio_in_ngspice():
    """Peak current mode with a command never reached and Dmax = 0.8 (the latch reset by a second pulse at 0.8 T):
    ngspice's mean 2e-4 from the LCS's (the open-loop buck's at D = 0.8) over 30 periods from the orbit."""
    model = resolve_model("buck", "peak-current")
    params = {"Iref": 5.0, "Dmax": 0.8}
    lcs, spice, T = _from_the_orbit(model, params)
    assert spice.mean("vout", t0=20 * T) == pytest.approx(lcs.mean("vout", t0=20 * T), rel=1e-3)
