"""ngspice as a method (validation.ngspice.Spice): registered like the others, run through run_converter and
summarised by run_summary, its own way of saying how a run ended (retcode) and how accurate it is."""
import numpy as np
import pytest

from converters.errors import ParameterError
from converters.methods.base import METHODS, get_method
from converters.run import run_converter, run_summary
from converters.trajectory import Trajectory
from validation.ngspice import Spice

pytestmark = pytest.mark.spice


def test_spice_is_a_registered_method_of_the_circuit_domain_whose_error_is_its_devices():
    assert get_method("spice") is Spice and METHODS["spice"].domains == ("circuit",)
    assert Spice.error_kind == "model" and not Spice.step_option
    with pytest.raises(ParameterError, match="ngspice runs a circuit's netlist, not an LCS problem"):
        Spice().solve(None, None)
    with pytest.raises(ParameterError, match=r"--spice-reltol must be in \[1e-09, 0.1\]; got 1"):
        Spice(spice_reltol=1.0)
    with pytest.raises(ParameterError, match="h does not apply to the spice method"):
        run_converter("buck", {}, method="spice", h=1e-8)


def test_run_converter_runs_the_models_netlist_and_run_summary_reads_it(ngspice):
    tr = run_converter("buck", {}, method=Spice(spice_tmax="50n"))               # 500 periods from rest
    summary = run_summary(tr)
    assert tr.algorithm == Spice(spice_tmax="50n") and tr.method == "spice" and tr.retcode == "success"
    assert summary["options"]["tmax_fraction"] == pytest.approx(5e-3) and summary["retcode"] == "success"
    # the same circuit's periodic orbit (LCP stepper) within compare's 0.1 % (the near-ideal devices' drops apart)
    lcp = run_summary(run_converter("buck", {}, steady=True))
    assert summary["vout_mean"] == pytest.approx(lcp["vout_mean"], rel=1e-3)
    assert summary["accuracy"]["checked"] is False and summary["accuracy"]["transient"] < 1e-5


def test_a_steady_state_that_does_not_settle_returns_not_converged_with_its_warning(ngspice, monkeypatch):
    from validation import compare
    monkeypatch.setattr(compare, "MAX_SPICE_PERIODS", 20)      # one 20-period run, then no more
    monkeypatch.setattr(compare, "SPICE_SETTLE", 1e-15)        # a move no run reaches
    tr = run_converter("buck", {}, method="spice", steady=True)
    summary = run_summary(tr)
    assert tr.retcode == "not_converged" and summary["retcode"] == "not_converged"
    assert summary["spice_settled"] is False and summary["steady_periods"] == 20
    assert summary["warnings"][0].startswith("ngspice has not settled after 20 periods")


def test_a_trajectory_refuses_a_return_code_it_does_not_know():
    with pytest.raises(ValueError, match="retcode must be one of success, not_converged; got 'ok'"):
        Trajectory(t=np.zeros(1), x=np.zeros((1, 1)), state_names=("x",), retcode="ok")

