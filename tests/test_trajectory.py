"""The one Trajectory type: its measures by rule (end point, linear, exact), windows, measured signals,
mode fractions and concatenation."""
import json

import numpy as np
import pytest

from converters.methods import EventDriven, Theta
from converters.simulate import simulate
from converters.trajectory import ReturnCode, Samples, Stats, Trajectory, concatenate


class _Labels:
    """A model's laws in miniature: vout = 2 x, switch = x > 0.5, every point 'A' or 'B' by the switch."""

    signal_names = ("vout", "switch")

    def signal(self, name, samples: Samples):
        return 2.0 * samples.x[:, 0] if name == "vout" else (samples.x[:, 0] > 0.5).astype(np.int8)

    def conducting(self, samples):
        return np.ones((samples.t.size, 1), dtype=bool)

    def modes(self, conducting, switch, x):
        return np.where(np.asarray(switch) >= 0.5, "B", "A").astype(object)


def ramp(rule, n=11, period=0.5):
    t = np.linspace(0.0, 1.0, n)
    return Trajectory(t=t, x=t[:, None], state_names=("x",), rule=rule, labels=_Labels(), period=period)


def test_means_and_rms_follow_the_rule_of_the_samples():
    linear = ramp("linear")
    assert linear.mean("x") == pytest.approx(0.5, abs=1e-15)              # exact for a linear signal
    assert linear.rms("x") == pytest.approx(np.sqrt(1 / 3), abs=1e-15)
    assert linear.mean("vout") == pytest.approx(1.0, abs=1e-15)
    end = ramp("end")
    assert end.mean("x") == pytest.approx(0.55, abs=1e-15)                # each step by its end point
    assert end.rms("x") == pytest.approx(np.sqrt(np.mean(np.linspace(0.1, 1.0, 10) ** 2)), abs=1e-15)
    assert linear.ripple("vout") == pytest.approx(2.0)


def test_windows_in_periods_or_times():
    tr = ramp("linear")
    assert tr.window(periods=1) == (0.5, 1.0)
    assert tr.mean("x", periods=1) == pytest.approx(0.75, abs=1e-15)
    assert tr.mean("x", t0=0.2, t1=0.4) == pytest.approx(0.3, abs=1e-15)
    with pytest.raises(ValueError, match="needs a switching period"):
        ramp("linear", period=float("inf")).window(periods=1)


def test_mode_fractions_count_each_step_by_its_end_point_label():
    tr = ramp("end")
    assert tr.mode_fractions(periods=2) == {"A": pytest.approx(0.5), "B": pytest.approx(0.5)}
    assert list(tr.waveforms().columns) == ["time", "x", "vout", "switch", "mode"]


def test_measured_signals_take_the_place_of_the_models_laws():
    t = np.linspace(0.0, 1.0, 5)
    tr = Trajectory(t=t, x=t[:, None], state_names=("x",), labels=_Labels(),
                    measured={"vout": np.full(5, 3.0), "switch": np.ones(5), "conducting": np.zeros((5, 1), bool)})
    assert tr.mean("vout") == pytest.approx(3.0)
    assert set(tr.modes()) == {"B"}
    assert not tr.conducting().any()
    with pytest.raises(KeyError, match="signal must be one of x, vout, switch; got 'iL'"):
        tr.signal("iL")


def test_concatenated_runs_share_the_joint_point():
    a, b = ramp("end"), ramp("end")
    b = Trajectory(t=b.t + 1.0, x=b.x + 1.0, state_names=("x",), rule="end", labels=_Labels(), period=0.5)
    joined = concatenate([a, b])
    assert joined.t.size == 21 and joined.t[-1] == 2.0 and np.all(np.diff(joined.t) > 0)
    assert joined.mean("x") == pytest.approx((0.55 + 1.55) / 2)


def test_exact_and_sampled_windows_cover_the_same_span():
    """A window reaching past the run is cut to the run for every rule; one shorter than a step still
    takes the step around it."""
    from dataclasses import replace

    from converters.methods import EventDriven
    from converters.models import get_converter
    from converters.simulate import simulate
    conv = get_converter("buck")
    p = conv.resolve({})
    T = conv.period(p)
    tr = replace(simulate(conv.problem(p, 20 * T), EventDriven()), labels=conv.labels(p))
    end = tr.t[-1]
    assert tr.mean("vout", t0=end - 5 * T, t1=end + 5 * T) == pytest.approx(tr.mean("vout", t0=end - 5 * T), rel=1e-15)
    lcp = ramp("end")
    assert lcp.mean("x", t0=0.52, t1=0.53) == pytest.approx(0.6)           # the step [0.5, 0.6] by its end point
    with pytest.raises(ValueError, match="holds no time of the run"):
        lcp.mean("x", t0=2.0)


def test_exact_mode_fractions_put_an_event_where_it_is():
    """The event method's samples carry their segment's mode: the DCM buck's diode stops at 0.62279 T of
    the period exactly, and the fractions say so (not an output step off through the rounding of y)."""
    from converters.run import run_converter
    run = run_converter("buck", {}, method="event", periods=50)
    events = run.events
    last = run.t[-1] - run.period
    stop = events.loc[(events["kind"] == "activate") & (events["time"] > last), "time"].iloc[0]
    fractions = run.mode_fractions(1)
    assert fractions["CCM-OFF"] == pytest.approx((stop - last) / run.period - 0.4, abs=1e-12)


@pytest.mark.parametrize("method", [Theta(h=1e-6, theta=0.5), EventDriven()], ids=["lcp", "event"])
def test_a_bare_lcs_run_plots_its_states_and_the_pairs_that_hold(method):
    """Trajectory.plot() raised on any run of a plain LCSProblem (no model labels): it draws the states and, as its
    mode timeline, the pairs that hold at each step (the diode bridge: D1 with D3, then D2 with D4)."""
    from .oracle_circuits import diode_bridge
    fig = simulate(diode_bridge(), method).plot()
    axes = fig.axes
    assert [ax.get_ylabel() for ax in axes] == ["vC (V)", "iL (A)", "held pairs"]
    legend = {text.get_text() for text in axes[-1].get_legend().get_texts()}
    assert legend == {"D3+D1", "D4+D2"}
    assert fig.texts[0].get_text() == f"LCS ({method.key})"


@pytest.mark.parametrize("method", ["lcp", "event"])
def test_a_solution_carries_its_problem_its_method_and_what_it_cost(method):
    """sol.prob, sol.alg and the statistics, as DifferentialEquations.jl's solutions carry them: the accuracy check of
    a run re-runs its own method object at another step, read from the trajectory (steady runs on the stepper's
    plan included)."""
    from .oracle_circuits import diode_bridge
    from converters.run import run_converter
    problem = diode_bridge()
    algorithm = Theta(h=1e-6, theta=0.5) if method == "lcp" else EventDriven()
    tr = simulate(problem, algorithm)
    assert tr.problem is problem and tr.algorithm is algorithm and tr.method == method
    stats = tr.stats                              # a typed record; its mapping form reads the same
    assert isinstance(stats, Stats) and stats.steps == stats["steps"] == tr.steps > 0
    assert stats.unit == ("steps" if method == "lcp" else "segments") and stats.general_solves == 0
    assert stats.events == len(tr.events) > 0 and stats.wall_s == tr.wall_s and tr.retcode is ReturnCode.SUCCESS
    with pytest.raises(KeyError):
        stats["nfev"]
    steady = run_converter("buck", {}, steady=True, method=method)
    assert steady.algorithm is not None and steady.algorithm.key == method and steady.problem is not None


def test_a_return_code_given_by_its_value_is_the_typed_code_and_writes_as_its_value():
    tr = Trajectory(t=np.zeros(1), x=np.zeros((1, 1)), state_names=("x",), retcode="not_converged")
    assert tr.retcode is ReturnCode.NOT_CONVERGED and tr.retcode == "not_converged"
    assert json.dumps({"retcode": tr.retcode}) == '{"retcode": "not_converged"}' and str(tr.retcode) == "not_converged"


def test_configurations_named_alike_stay_apart_in_a_table():
    """A model may name two configurations alike (its name need not say every level or slope it holds): the table's
    categorical column keeps them apart (it raised "Categorical categories must be unique")."""
    t = np.linspace(0.0, 1.0, 5)
    tr = Trajectory(t=t, x=t[:, None], state_names=("x",), config=np.array([0, 1, 0, 1, 2]),
                    config_names=("circuit", "circuit", "other"))
    column = tr.to_pandas()["config"]
    assert list(column.cat.categories) == ["circuit#0", "circuit#1", "other"]
    assert list(column.astype(str)) == ["circuit#0", "circuit#1", "circuit#0", "circuit#1", "other"]


@pytest.mark.parametrize("h", [1e-8, 2e-8])
def test_the_step_after_a_switching_edge_starts_from_the_new_configurations_pair_at_the_edges_state(h):
    """The synchronous buck's dead time (netlists/circuits/sync-buck-thermal.cir): the linear rule's step after each
    edge starts in the new configuration, whose LCP at the edge's state gives the idle high-side body diode 0 and
    the low side's the inductor's current. The stepper's pair a step later, at another state, had given the idle
    diode 12.025 - 12.036 = -0.011 A (its rms 1.4e-4 A at T/1000, 3.0e-4 at T/500, where it is 0) and the low
    side's mean 5.4e-5 (1.4e-4) low. Against the event method's exact quadrature the means now agree to 1e-10."""
    from pathlib import Path

    from converters.run import run_converter
    path = str(Path(__file__).resolve().parents[1] / "netlists" / "circuits" / "sync-buck-thermal.cir")
    exact = run_converter(path, steady=True, method="event", periods=1)
    run = run_converter(path, steady=True, h=h, periods=1)
    assert run.rms("i(d1)") == 0.0 and run.mean("i(d1)") == 0.0
    for name in ("i(d2)", "i(s2)", "i(vin)"):
        assert run.mean(name) == pytest.approx(exact.mean(name), rel=1e-10), name
