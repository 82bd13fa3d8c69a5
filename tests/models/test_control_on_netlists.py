"""A control closes its loop around a netlist (converters/models/plant.py): the voltage-mode law around
netlists/circuits/buck.cir is the built-in closed loop (Hamill, Deane and Jefferies' buck) to rounding, and what a
loop cannot read off a netlist is refused in one line. Before, every --control on a netlist was refused."""
import json
import pickle
from pathlib import Path

import numpy as np
import pytest

from converters.errors import ParameterError
from converters.models import get_model
from converters.run import run_converter
from validation.cli import main

BUCK = Path(__file__).resolve().parents[2] / "netlists" / "circuits" / "buck.cir"
#: The built-in voltage-mode buck's plant (its published values: converters/models/voltage_mode.py) by the netlist's
#: parameter names, as a user types them.
PLANT = {"Vin": 24, "L": "20m", "C": "47u", "R": 22, "f_sw": "2.5k"}


@pytest.mark.parametrize("method", ["event", "lcp"])
def test_the_voltage_mode_loop_around_the_bucks_netlist_is_the_built_in_closed_loop(method):
    builtin = run_converter("buck", {}, control="voltage-mode", method=method, steady=True, steady_tol=1e-12,
                            periods=1)
    netlist = run_converter(get_model(str(BUCK), "voltage-mode"), PLANT, method=method, steady=True,
                            steady_tol=1e-12, periods=1)
    # the netlist's states are (v(c1), i(l1)), the built-in's (iL, vC)
    assert netlist.state_names == ("v(c1)", "i(l1)")
    np.testing.assert_allclose(netlist.x[0][::-1], builtin.x[0], rtol=1e-10, atol=1e-12)
    a, b = (np.sort_complex(np.array([complex(*m) for m in tr.metadata["orbit"]["multipliers"]]))
            for tr in (netlist, builtin))
    # the stepper's Jacobian moves by 6e-7 when its start moves by 1e-13 (measured on the built-in alone: the
    # crossing's place inside its step is rounded), so its multipliers agree to that; the exact ones to rounding
    np.testing.assert_allclose(a, b, atol=1e-10 if method == "event" else 2e-6)
    # the period-1 orbit at Vin = 24, stable (the stepper's T/1000 within 8e-7 of the exact radius)
    assert abs(a).max() == pytest.approx(0.8241327994, abs=1e-9 if method == "event" else 2e-6)
    vn = netlist.mean("vout", t0=netlist.t[0], t1=netlist.t[-1])
    vb = builtin.mean("vout", t0=builtin.t[0], t1=builtin.t[-1])
    assert vn == pytest.approx(vb, rel=1e-10)
    # its modes are the netlist's names of the built-in's CCM-ON / CCM-OFF
    fractions = {"S1": "CCM-ON", "D1": "CCM-OFF"}
    built = builtin.mode_fractions()
    assert {fractions[k]: v for k, v in netlist.mode_fractions().items()} == pytest.approx(built, abs=1e-9)


def test_the_command_line_closes_the_loop_around_a_netlist(capsys):
    args = ["simulate", str(BUCK), "--control", "voltage-mode", "--steady", "--method", "event", "--json"]
    assert main(args + [f"-p{k}={v}" for k, v in PLANT.items()]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["vout_mean"] == pytest.approx(12.017902954642853, rel=1e-10)
    assert summary["orbit"]["stable"] and "vcon" in summary["measurements"]


def test_a_netlists_closed_loop_pickles_for_the_worker_processes():
    model = get_model(str(BUCK), "voltage-mode")
    again = pickle.loads(pickle.dumps(model))
    p = model.resolve(PLANT)
    assert again.key == model.key and again.resolve(PLANT) == p
    x0 = np.array([11.0, 0.5])
    assert np.array_equal(again.problem(p, 4e-4, x0).configurations[0].A, model.problem(p, 4e-4, x0).configurations[0].A)


NETLISTS = BUCK.parent


@pytest.mark.parametrize("file,control,params,message", [
    ("buck.cir", "peak-current", {}, "--control peak-current closes its loop around the built-in converters it names; "
     "a netlist takes --control voltage-mode (a loop that senses its output and drives its first switch)"),
    ("full-bridge.cir", "voltage-mode", {}, "full-bridge.cir: a control drives one switch between two "
     "configurations; its gates select 4 configurations on a schedule"),
    ("rectifier-1ph.cir", "voltage-mode", {}, "rectifier-1ph.cir: a control drives one switch between two "
     "configurations; this netlist has no switch"),
    ("boost.cir", "voltage-mode", {"rC": 0.1}, "--control voltage-mode senses the output, which on boost.cir "
     "depends on more than the circuit's state"),
    ("buck.cir", "smc", {}, "--control smc closes its loop around the built-in converters it names"),
])
def test_what_a_loop_cannot_read_off_a_netlist_is_refused_in_one_line(file, control, params, message):
    with pytest.raises(ParameterError) as error:
        model = get_model(str(NETLISTS / file), control)
        model.resolve(params)
    assert message in str(error.value) and "\n" not in str(error.value)
