"""The thermal network stepped with an electrical run, period by period (converters.thermal.summary.
thermal_of_transient): a cold start's junction temperature against its closed form, and its end against the
steady state's fixed point where the losses depend on the temperature."""
import numpy as np
import pytest

from converters.models import get_model
from converters.run import run_converter
from converters.thermal.network import read_setup
from converters.thermal.summary import thermal_of_transient, thermal_summary

from .test_vendor_example import DEVICE, NETLIST, R_TH, SETUP, T_A

TAU = 1e-5          # s: the junction's one Foster stage, 2.5 switching periods


def _circuit(tmp_path, device):
    (tmp_path / "b5973d.cir").write_text(NETLIST)
    (tmp_path / "switch.toml").write_text(device.replace("tau = [1.0]", f"tau = [{TAU}]"))
    (tmp_path / "setup.toml").write_text(SETUP)
    model = get_model(str(tmp_path / "b5973d.cir"))
    return model, model.resolve({}), read_setup(tmp_path / "setup.toml")


def test_a_cold_starts_junction_follows_the_foster_stages_closed_form(tmp_path):
    model, p, setup = _circuit(tmp_path, DEVICE)            # tables that do not depend on the temperature
    tr = run_converter(model, p, steady=True, periods=20)   # 20 periods on the orbit: the same losses in each
    run = thermal_of_transient(model, p, tr, setup)
    power = run.losses["s1"]
    assert np.ptp(power) < 1e-12 * power[0] and power[0] == pytest.approx(0.9001, abs=1e-4)
    closed = T_A + R_TH * power[0] * (1.0 - np.exp(-(run.t - run.t[0]) / TAU))
    assert np.max(np.abs(run.junction["s1"] - closed)) < 1e-9          # K (1.4e-11)
    assert run.t.size == 21 and run.t[-1] == pytest.approx(20 * model.period(p), rel=1e-12)


def test_the_co_simulations_end_is_the_steady_states_fixed_point(tmp_path):
    # R_DS(on) 0.25 ohm at 25 degC, 0.5 at 150 degC (the datasheet's figures): the losses rise with the junction
    device = DEVICE.replace("v_on = [[0, 1.6], [0, 1.6]]", "v_on = [[0, 1.0], [0, 2.0]]")
    model, p, setup = _circuit(tmp_path, device)
    tr = run_converter(model, p, steady=True, periods=60)   # 24 time constants
    run = thermal_of_transient(model, p, tr, setup)
    steady = thermal_summary(model, p, tr, setup)["devices"]["s1"]
    assert run.junction["s1"][-1] == pytest.approx(steady["tj_C"], abs=1e-4)      # K
    assert run.losses["s1"][-1] == pytest.approx(steady["total_W"], rel=1e-6)
    assert run.losses["s1"][0] < run.losses["s1"][-1]                         # colder: less loss at first
