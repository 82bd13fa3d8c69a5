"""A boost whose type II loop (E, R and C, A = 1e5, no duty limit) latches from rest: the integrator winds up, its
output stays above the ramp, S1 never opens, and the inductor's current rises by Vin T / L every period (S1 across
it alone: exact). There is no switching orbit to find; --steady used to say only that Newton did not converge, and
the transient's warning only to run longer. Both now say that a whole period stays in one mode."""
from pathlib import Path

import pytest

from converters.errors import SimulationError
from converters.models import Circuit
from converters.run import run_converter, run_summary

NETLISTS = Path(__file__).resolve().parents[2] / "netlists" / "circuits"


@pytest.fixture(scope="module")
def latched(tmp_path_factory):
    text = (NETLISTS / "type2-loop-buck.cir").read_text()
    for a, b in (("S1 in sw vcon ramp SWMOD", "S1 sw 0 vcon ramp SWMOD"), ("D1 0 sw DMOD", "D1 sw out DMOD"),
                 ("L1 sw out {L}", "L1 in sw {L}"), ("Vref=5", "Vref=24"), ("R=10 ", "R=50 ")):
        assert a in text
        text = text.replace(a, b)
    path = tmp_path_factory.mktemp("latch") / "boost-latch.cir"
    path.write_text(text)
    return Circuit.from_netlist(path)


def test_the_latched_transient_says_its_period_stays_in_one_mode(latched):
    p = latched.resolve({})
    T = latched.period(p)
    tr = run_converter(latched, {}, periods=200)
    summary = run_summary(tr)
    assert list(summary["mode_fractions"]) == ["S1"]
    i = tr.state_names.index("i(l1)")
    rows = tr.rows_between(float(tr.t[-1]) - T, float(tr.t[-1]))
    span = tr.t[rows[-1]] - tr.t[rows[0]]            # T, or a hair more: the ramp resets 5e-9 T before the period
    assert span == pytest.approx(T, rel=1e-8)
    assert tr.x[rows[-1], i] - tr.x[rows[0], i] == pytest.approx(p["vin"] * span / p["l"], rel=1e-9)
    (warning,) = [w for w in summary["warnings"] if "has not settled" in w]
    assert ("(its last period stays in one mode, S1: no switch changes state, so there is no switching orbit there: "
            "a loop latched at duty 1 or 0, its control beyond its ramp; it may stay there)") in warning


@pytest.mark.slow
def test_steady_says_where_the_transient_went(latched):
    """Newton's settling rounds (2,048 periods) end latched; the refusal says so (2 s)."""
    with pytest.raises(SimulationError, match=r"where the transient ends, a whole period stays in one mode \(S1\): "
                                              r"no switch changes state, so there is no switching orbit there") as error:
        run_converter(latched, {}, steady=True)
    assert str(error.value).endswith("; run --periods N without --steady to see where it goes")
