"""Tolerance studies: parameters drawn from their distributions (seeded, Latin hypercube or Sobol), metrics on
demand as columns (the same on every backend), specifications and the yield with its exact confidence interval."""
import json
import math
import operator

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings, strategies as st

from converters.errors import ParameterError
from converters.parallel import run_ensemble
from converters.sweeps import ModelSweep
from converters.sweeps.points import Tolerance, Tolerances
from converters.sweeps.specs import Spec, study_summary, yield_interval
from validation.cli import main

NOMINALS = {"C": 100e-6, "L": 10e-6, "R": 10.0, "rC": None, "Io": 0.0}


@pytest.mark.parametrize("sampler", ["lhs", "sobol"])
def test_each_distribution_keeps_its_samples_inside_the_tolerance_and_has_its_spread(sampler):
    """normal: sigma = tol/3 truncated at +-3 sigma (std 0.9865 sigma); uniform: std tol/sqrt(3); lognormal: the
    median at the nominal, log-sigma ln(1 + tol)/3 truncated at its own 3 sigma."""
    study = Tolerances([Tolerance.parse("C=6%", NOMINALS), Tolerance.parse("L=10%:uniform", NOMINALS),
                        Tolerance.parse("R=30%:lognormal", NOMINALS)], 4096, seed=3, sampler=sampler)
    x = np.array([[p[n] for n in ("C", "L", "R")] for _, p in study.points(range(study.size))])
    c, L, R = x[:, 0] / 100e-6 - 1, x[:, 1] / 10e-6 - 1, np.log(x[:, 2] / 10.0)
    assert np.abs(c).max() <= 0.06 and np.abs(L).max() <= 0.10 and np.abs(R).max() <= math.log(1.3) / 3 * 3 + 1e-12
    assert c.std() == pytest.approx(0.02 * 0.98658, rel=0.02)
    assert L.std() == pytest.approx(0.10 / math.sqrt(3), rel=0.02)
    assert np.median(R) == pytest.approx(0.0, abs=0.01) and R.std() == pytest.approx(math.log(1.3) / 3 * 0.98658, rel=0.02)
    again = Tolerances(study.tolerances, 4096, seed=3, sampler=sampler)
    assert again.points([0, 4095]) == study.points([0, 4095])                       # seeded: the same samples
    expected = [(c, l, r) for c in (94e-6, 106e-6) for l in (9e-6, 11e-6) for r in (10 / 1.3, 13.0)]
    corners = [tuple(p[n] for n in "CLR") for p in study.corners()]
    np.testing.assert_allclose(corners, expected, rtol=1e-15)


@pytest.mark.parametrize("text, message", [
    ("C=150%", "--tolerance C: the tolerance must be in (0, 100) %; got 150 %"),
    ("C=5%:weibull", "--tolerance C: the distribution must be one of normal, uniform, lognormal; got 'weibull'"),
    ("Cx=5%", "--tolerance Cx: not a parameter of the model; valid names: C, L, R, rC, Io"),
    ("rC=5%", "--tolerance rC: the parameter has no value to vary (an optional one that is not set): give it with "
              "-p rC=VALUE"),
    ("Io=5%", "--tolerance Io: a relative tolerance needs a nonzero nominal value; got 0.0"),
    ("C", "--tolerance takes NAME=TOL[%][:DIST]"),
])
def test_a_bad_tolerance_is_refused_naming_it(text, message):
    with pytest.raises(ParameterError) as error:
        Tolerance.parse(text, NOMINALS)
    assert message in str(error.value)


def test_the_yield_interval_is_clopper_and_pearsons():
    """Against the beta quantiles written out: [B(a/2; k, n-k+1), B(1-a/2; k+1, n-k)]."""
    from scipy.stats import beta
    for k, n in ((407, 500), (0, 100), (100, 100), (9731, 10000)):
        value, low, high = yield_interval(k, n)
        assert value == k / n
        assert low == pytest.approx(beta.ppf(0.025, k, n - k + 1) if k else 0.0, abs=1e-12)
        assert high == pytest.approx(beta.ppf(0.975, k + 1, n - k) if k < n else 1.0, abs=1e-12)


def test_specs_count_failed_points_as_failures_and_find_the_worst_sample():
    frame = pd.DataFrame({"index": range(5), "C": [1.0, 2.0, 3.0, 4.0, 5.0], "status": ["ok"] * 4 + ["failed"],
                          "vout_ripple": [0.01, 0.03, 0.02, 0.049, np.nan], "efficiency": [0.99, 0.97, 0.96, 0.99, np.nan]})
    specs = [Spec.parse("vout_ripple<50m"), Spec.parse("efficiency >= 0.97")]
    found = study_summary(frame, specs, Tolerances([Tolerance.parse("C=5%", {"C": 3.0})], 5))
    assert found["passed"] == 3 and found["yield"] == 0.6 and found["failed_points"] == 1
    assert [s["passed"] for s in found["specs"]] == [4, 3]
    assert found["specs"][0]["worst_value"] == 0.049 and found["specs"][0]["worst_point"] == {"C": 4.0}
    assert found["specs"][1]["worst_value"] == 0.96 and found["specs"][1]["worst_point"] == {"C": 3.0}
    with pytest.raises(ParameterError, match="--spec takes METRIC<VALUE or METRIC>VALUE"):
        Spec.parse("vout_ripple=5m")


OPERATORS = {"<": operator.lt, "<=": operator.le, ">": operator.gt, ">=": operator.ge}
FINITE = st.floats(-1e6, 1e6, allow_nan=False)


@settings(max_examples=300, deadline=None)
@given(op=st.sampled_from(list(OPERATORS)), limit=FINITE, values=st.lists(FINITE, min_size=1, max_size=8),
       on_the_limit=st.booleans())
def test_every_spec_operator_holds_as_its_comparison_and_its_margin_is_the_signed_distance_inside(op, limit, values,
                                                                                                 on_the_limit):
    """For each of <, <=, >, >=: the spec holds exactly where Python's comparison does (a value on the limit too:
    it meets <= and >=, never < or >); its margin is how far inside the bound a value lies (limit - v for an upper
    bound, v - limit for a lower one), positive where a strict bound holds, at least 0 where an inclusive one does;
    NaN (a failed point's value) meets none."""
    if on_the_limit:
        values = values + [limit]
    spec = Spec.parse(f"vout_ripple {op} {limit!r}")
    assert (spec.metric, spec.op, spec.limit) == ("vout_ripple", op, limit)
    v = np.array(values)
    expected = np.array([OPERATORS[op](x, limit) for x in values])
    np.testing.assert_array_equal(spec.holds(v), expected)
    margin = spec.margin(v)
    np.testing.assert_array_equal(margin, limit - v if op in ("<", "<=") else v - limit)
    np.testing.assert_array_equal(spec.holds(v), margin > 0 if op in ("<", ">") else margin >= 0)
    assert not spec.holds([np.nan]).any()


def test_metrics_on_demand_are_the_power_balance_and_the_signals_statistics():
    """On the event method's exact orbit the balance closes: input = output + every loss; efficiency = output /
    input; vout.max - vout.min = vout_ripple."""
    metrics = ("efficiency", "input_W", "output_W", "total_loss_W", "losses.Ron", "losses.rL", "vout.max", "vout.min",
               "iL.rms", "fraction.CCM-ON", "fraction.CCM-OFF", "fraction.DCM")
    sweep = ModelSweep("buck", "pwm", {"Vin": 48, "D": 0.25, "L": 100e-6, "Ron": 0.05, "rL": 0.02}, method="event",
                       metrics=metrics)
    row = sweep.rows([(0, {"R": 10.0})])[0]
    assert row["status"] == "ok", row
    assert row["input_W"] == pytest.approx(row["output_W"] + row["total_loss_W"], rel=1e-9)
    assert row["total_loss_W"] == pytest.approx(row["losses.Ron"] + row["losses.rL"], rel=1e-12)
    assert row["efficiency"] == pytest.approx(row["output_W"] / row["input_W"], rel=1e-12)
    assert row["vout.max"] - row["vout.min"] == pytest.approx(row["vout_ripple"], rel=1e-12)
    assert row["losses.rL"] == pytest.approx(0.02 * row["iL.rms"] ** 2, rel=1e-12)
    assert row["fraction.CCM-ON"] == pytest.approx(0.25, abs=1e-9) and row["fraction.DCM"] == 0.0      # CCM at D = 0.25
    assert row["fraction.CCM-ON"] + row["fraction.CCM-OFF"] == pytest.approx(1.0, abs=1e-12)
    assert sweep.units["efficiency"] == "1" and sweep.units["losses.Ron"] == "W" and sweep.units["iL.rms"] == "A"
    with pytest.raises(ParameterError, match=r"metric 'losses.rC': the losses of buck here are losses.rL, losses.Ron"):
        ModelSweep("buck", "pwm", {"Ron": 0.05, "rL": 0.02}, metrics=("losses.rC",))
    with pytest.raises(ParameterError, match=r"metric 'vout.std': a sweep's metrics are SIGNAL.STAT"):
        ModelSweep("buck", metrics=("vout.std",))


SEPIC = str(__import__("pathlib").Path(__file__).resolve().parents[2] / "netlists" / "circuits" / "sepic.cir")


@pytest.mark.parametrize("backend", ["local", pytest.param("dask", marks=pytest.mark.slow)])
@pytest.mark.parametrize("model, base, axis, metrics", [
    ("buck", {"Ron": 0.05}, "R=2:40:6", ("efficiency", "losses.Ron", "i_switch.rms")),
    (SEPIC, {}, "r=5:40:6", ("v(out).ripple", "i(l1).rms", "fraction.S1")),
], ids=["buck", "sepic.cir"])
def test_metrics_on_demand_are_the_same_rows_on_every_backend(backend, model, base, axis, metrics, request):
    from converters.sweeps import Axis, Grid
    grid = Grid([Axis.parse(axis)])
    sweep = ModelSweep(model, "pwm", base, metrics=metrics)
    serial = pd.DataFrame(run_ensemble(sweep, grid, backend="serial")).set_index("index").sort_index()
    target = request.getfixturevalue("dask_client") if backend == "dask" else backend
    other = pd.DataFrame(run_ensemble(sweep, grid, backend=target, workers=2, chunk=2)).set_index("index").sort_index()
    columns = [*metrics, "vout_mean"]
    assert (serial["status"] == "ok").all() and serial[list(metrics)].notna().all().all()
    np.testing.assert_allclose(other[columns].to_numpy(float), serial[columns].to_numpy(float), rtol=1e-12, atol=0)


@pytest.mark.parametrize("model, base, tolerances, metrics", [
    ("buck", {"Vin": 48, "D": 0.25, "L": 100e-6, "Ron": 0.05, "rL": 0.02}, ["C=5%", "L=10%:uniform", "R=1%"],
     ("efficiency", "losses.Ron", "i_switch.rms")),
    (SEPIC, {}, ["l1=10%", "c2=5%", "r=1%"], ("v(out).ripple", "i(l1).rms")),
], ids=["buck", "sepic.cir"])
def test_a_chunk_compiled_together_gives_the_rows_of_its_points_compiled_alone(model, base, tolerances, metrics,
                                                                              monkeypatch):
    """ModelSweep.rows compiles a chunk's circuits together (Model.prepare: the netlist rebound to each point's
    values and its networks solved as one stack); without that step every point reads and compiles its netlist
    alone. The rows are the same, to the bit."""
    from converters.models import get_model
    from converters.models import netlist as netlist_models
    sweep = ModelSweep(model, "pwm", base, metrics=metrics)
    nominals = {**{q.name: q.default for q in get_model(model).parameters}, **get_model(model).resolve(base)}
    study = Tolerances([Tolerance.parse(t, nominals) for t in tolerances], 40, seed=5)
    items = study.points(range(40))
    together = sweep.rows(items)
    netlist_models._compile.cache_clear()
    netlist_models._builtin_configurations.cache_clear()
    monkeypatch.setattr(type(get_model(model)), "prepare", lambda self, points: None)
    alone = sweep.rows(items)
    columns = [c for c in together[0] if c != "wall_s"]
    assert all(row["status"] == "ok" for row in together)
    assert [[row[c] for c in columns] for row in together] == [[row[c] for c in columns] for row in alone]


def test_a_tolerance_study_on_the_command_line_gives_the_yield_the_worst_corner_and_units(capsys, tmp_path):
    out = tmp_path / "study"
    argv = ["sweep", "buck", "-p", "Vin=48", "-p", "D=0.25", "-p", "L=100u", "-p", "Ron=0.05", "--tolerance", "C=5%",
            "--tolerance", "L=10%:uniform", "--tolerance", "R=1%", "--samples", "64", "--steady", "--spec",
            "vout_ripple<12m", "--spec", "efficiency>0.98", "--metric", "vout_ripple", "--corners", "--out", str(out),
            "--scheduler", "serial", "--no-progress", "--json"]
    assert main(argv) == 0
    summary = json.loads(capsys.readouterr().out)
    study = summary["study"]
    frame = pd.read_parquet(out / "parts")
    assert len(frame) == 64 and {"C", "L", "R", "vout_ripple", "efficiency"} <= set(frame.columns)
    meets = (frame["vout_ripple"] < 12e-3) & (frame["efficiency"] > 0.98)
    assert study["passed"] == int(meets.sum()) and study["yield_low"] <= study["yield"] <= study["yield_high"]
    assert 0 < study["passed"] < 64                                   # the ripple spec splits the samples
    # the worst corner: the smallest L and C give the largest ripple
    worst = study["corners"]["specs"][0]["worst_point"]
    assert worst["L"] == pytest.approx(90e-6) and worst["C"] == pytest.approx(95e-6) and study["corners"]["count"] == 8
    import pyarrow.parquet as pq
    units = json.loads(pq.read_schema(next((out / "parts").iterdir())).metadata[b"units"])
    assert units["vout_ripple"] == "V" and units["efficiency"] == "1" and units["L"] == "H"
    picture = (out / "summary.png").read_bytes()
    assert picture[:4] == b"\x89PNG"
    # a row per metric (vout_ripple, then the efficiency spec's): twice the height of one metric's
    from validation.sweep import tolerance_plot
    one = tolerance_plot(frame, _study_points(), "vout_ripple")
    height = lambda png: int.from_bytes(png[20:24], "big")          # noqa: E731 (the IHDR chunk's height)
    assert height(picture) == pytest.approx(2 * height(one), rel=0.02)


def _study_points():
    from converters.sweeps.points import Tolerance, Tolerances
    nominal = {"C": 100e-6, "L": 100e-6, "R": 10.0}
    return Tolerances([Tolerance.parse(t, nominal) for t in ("C=5%", "L=10%:uniform", "R=1%")], 64)


def test_a_study_with_indices_shares_each_metrics_variance_among_its_parameters(capsys, tmp_path):
    """The 48 V buck's ripple: L (10 %, uniform) explains most of its variance, R (1 %) none; the indices are
    in the JSON with their confidence, and equal to the library's on the stored sample."""
    out = tmp_path / "study"
    argv = ["sweep", "buck", "-p", "Vin=48", "-p", "D=0.25", "-p", "L=100u", "--tolerance", "C=5%", "--tolerance",
            "L=10%:uniform", "--tolerance", "R=1%", "--samples", "200", "--steady", "--metric", "vout_ripple",
            "--indices", "--out", str(out), "--scheduler", "batched", "--no-progress", "--json"]
    assert main(argv) == 0
    found = json.loads(capsys.readouterr().out)["study"]["indices"]
    assert found["method"].startswith("RBD-FAST")
    ripple = found["metrics"]["vout_ripple"]
    assert ripple["samples"] == 200 and ripple["S1"]["L"] > 0.8 and abs(ripple["S1"]["R"]) <= ripple["S1_conf"]["R"]
    from converters.sweeps.indices import first_order
    again = first_order(pd.read_parquet(out / "parts"), ["C", "L", "R"], ["vout_ripple"], seed=0)["vout_ripple"]
    assert again["S1"] == pytest.approx(ripple["S1"], rel=1e-12)


@pytest.mark.parametrize("argv, message", [
    (["--tolerance", "C=150%"], "the tolerance must be in (0, 100) %; got 150 %"),
    (["--tolerance", "C=5%", "--spec", "vout_rippel<5m"], "metric 'vout_rippel': a sweep's metrics are SIGNAL.STAT"),
    (["--tolerance", "C=5%:gamma"], "the distribution must be one of normal, uniform, lognormal; got 'gamma'"),
    (["--tolerance", "rC=5%"], "--tolerance rC: the parameter has no value to vary"),
    (["--tolerance", "C=5%", "--grid", "R=1:2:2"], "give either --tolerance or --grid/--lhs"),
    (["--grid", "R=1:2:2", "--samples", "10"], "--samples sets the tolerance study; it does not apply without"),
    (["--metric", "efficiency", "--grid", "R=1:2:2", "--method", "spice"], "an ngspice sweep's measures are"),
    (["--indices", "--grid", "R=1:2:2"], "--indices sets the tolerance study; it does not apply without --tolerance"),
    (["--tolerance", "C=5%", "--samples", "50", "--indices"],
     "--indices: first-order indices need at least 100 samples; got --samples 50"),
])
def test_bad_study_input_is_one_line_and_nothing_runs(capsys, tmp_path, monkeypatch, argv, message):
    monkeypatch.chdir(tmp_path)
    code = main(["sweep", "buck", *argv, "--out", "x"])
    out, err = capsys.readouterr()
    assert code == 2 and out == "" and err.count("\n") == 1 and message in err, err
    assert list(tmp_path.iterdir()) == []


@pytest.fixture(scope="module")
def dask_client():
    """A 2-worker Dask LocalCluster of processes (dask[distributed] is in the test extras: never skipped)."""
    import sys

    import cloudpickle
    import distributed
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None)
    client = distributed.Client(cluster)
    cloudpickle.register_pickle_by_value(sys.modules[__name__])
    yield client
    client.close()
    cluster.close()
