"""The standard netlists (``python -m netlists DIR``, built on demand): run by ngspice on its own (``ngspice -b``),
their .meas mean of vout the same as ``pcsuite simulate --method spice`` on the same circuit."""
import json
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from netlists import standard_netlist
from netlists.build import STANDARD_PERIODS
from validation.cli import main

CONVERTERS = ("buck", "boost", "buck-boost", "cuk", "prc")


def test_python_m_netlists_writes_each_standard_netlist_into_the_directory_given(tmp_path):
    done = subprocess.run([sys.executable, "-m", "netlists", str(tmp_path)], capture_output=True, text=True,
                          timeout=300)
    assert done.returncode == 0, done.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(f"{name}.cir" for name in CONVERTERS)
    assert (tmp_path / "cuk.cir").read_text() == standard_netlist("cuk")
    refused = subprocess.run([sys.executable, "-m", "netlists", str(tmp_path / "absent")], capture_output=True,
                             text=True, timeout=300)
    assert refused.returncode != 0 and "DIR must be an existing directory" in refused.stderr
    assert not (Path(__file__).resolve().parents[2] / "netlists" / "buck.cir").exists()     # nothing shipped


@pytest.mark.parametrize("name", CONVERTERS)
def test_ngspice_runs_the_file_alone_and_its_meas_mean_is_pcsuites(name, ngspice, tmp_path, capsys):
    binary = shutil.which("ngspice")
    path = tmp_path / f"{name}.cir"
    path.write_text(standard_netlist(name))
    out = subprocess.run([binary, "-b", str(path)], capture_output=True, text=True, timeout=300, cwd=tmp_path)
    assert out.returncode == 0, out.stderr[-2000:]
    meas = {m.group(1).lower(): float(m.group(2))
            for m in re.finditer(r"^(\w+)\s*=\s*([-+0-9.eE]+)\s+from=", out.stdout, re.MULTILINE)}
    assert {"vout_mean", "vout_ripple"} <= set(meas), out.stdout[-2000:]
    assert meas["vout_ripple"] > 0
    assert main(["simulate", name, "--method", "spice", "--periods", str(STANDARD_PERIODS), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["window_periods"] == 10
    assert meas["vout_mean"] == pytest.approx(summary["vout_mean"], rel=1e-5)      # measured <= 1.3e-7 (7 digits)


def test_the_sliding_mode_netlist_measures_over_the_summary_window_as_pcsuite_does(ngspice, tmp_path, capsys):
    # it had a .tran and no .meas: `ngspice -b` said "no simulations run" and printed nothing
    path = tmp_path / "smc.cir"
    assert main(["netlist", "boost", "--control", "smc", "--out", str(path)]) == 0
    out = subprocess.run([shutil.which("ngspice"), "-b", str(path)], capture_output=True, text=True, timeout=300,
                         cwd=tmp_path)
    assert out.returncode == 0, out.stderr[-2000:]
    meas = {m.group(1).lower(): (float(m.group(2)), float(m.group(3)), float(m.group(4))) for m in re.finditer(
        r"^(\w+)\s*=\s*([-+0-9.eE]+)\s+from=\s*([-+0-9.eE]+)\s+to=\s*([-+0-9.eE]+)", out.stdout, re.MULTILINE)}
    capsys.readouterr()
    assert main(["simulate", "boost", "--control", "smc", "--method", "spice", "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    mean, t0, t1 = meas["vout_mean"]
    assert [t0, t1] == pytest.approx(summary["window_s"], rel=1e-9)       # the same window: the last 2 ms
    assert mean == pytest.approx(summary["vout_mean"], rel=1e-4)
    assert mean == pytest.approx(20.0, rel=1e-3)                          # Vref, held by the sliding law


@pytest.mark.parametrize("vin", ["33", "40"])
def test_the_voltage_mode_netlist_runs_through_the_chaotic_band(ngspice, capsys, vin):
    """At 33 V (chaos) ngspice had stopped at 0.18 s ("timestep too small", trouble with node ctrl): the comparator's
    output now reaches the switch through an RC of 1e-5 T. The attractor's 10-period mean is the event method's to
    1 % (chaotic trajectories part; measured 0.16 % at 33 V, 0.21 % at 40 V)."""
    means = {}
    for method in ("spice", "event"):
        assert main(["simulate", "buck", "--control", "voltage-mode", "--method", method, "-p", f"Vin={vin}",
                     "--json"]) == 0
        means[method] = json.loads(capsys.readouterr().out)["vout_mean"]
    assert means["spice"] == pytest.approx(means["event"], rel=1e-2)


def test_the_voltage_mode_netlist_runs_at_the_defaults(ngspice, tmp_path, capsys):
    # Vin = 24 V from rest: the hard-clipped comparator stopped ngspice at 3.6 ms ("timestep too small")
    path = tmp_path / "vm.cir"
    assert main(["netlist", "buck", "--control", "voltage-mode", "--out", str(path)]) == 0
    out = subprocess.run([shutil.which("ngspice"), "-b", str(path)], capture_output=True, text=True, timeout=300,
                         cwd=tmp_path)
    assert out.returncode == 0 and "too small" not in out.stdout + out.stderr, out.stdout[-2000:]
    mean = float(re.search(r"^vout_mean\s*=\s*([-+0-9.eE]+)", out.stdout, re.MULTILINE).group(1))
    capsys.readouterr()
    assert main(["simulate", "buck", "--control", "voltage-mode", "--t-end", "0.2", "--json"]) == 0
    lcp = json.loads(capsys.readouterr().out)["vout_mean"]               # the same last 10 periods
    assert mean == pytest.approx(lcp, rel=1e-4)                           # measured 2.1e-5


@pytest.mark.parametrize("name", ["buck", "boost", "buck-boost"])
def test_with_an_esr_the_capacitor_voltage_is_read_behind_it(name):
    """With rC the output node carries the ESR's drop too: vC (and the exported file's vC_mean) is read on the
    capacitor's own plate (it had been read on the output node)."""
    from netlists.build import build_netlist, standalone
    netlist = build_netlist(name, {"rC": 0.1}, 1e-3)
    assert netlist.probes["vC"][0] == "cp" and netlist.probes["vout"][0] == "out"        # C1's plate behind Rc
    assert ".meas tran vC_mean AVG v(cp) " in standalone(netlist, 1e-5, ("iL", "vC"))


@pytest.mark.spice
@pytest.mark.parametrize("name", ["buck", "boost", "buck-boost"])
def test_ngspices_capacitor_voltage_with_an_esr_is_the_lcps(name, ngspice, capsys):
    """rC = 0.1 ohm puts 30 mV of ESR ripple on the buck's output beside the capacitor's own 3.7 mV: ngspice's vC
    ripple is the LCP's (measured within 3.7 %), not vout's."""
    params = ["-p", "rC=0.1", "-p", "L=100u", "-p", "D=0.5"]
    ripples = {}
    for method in ("spice", "lcp"):
        assert main(["simulate", name, *params, "--steady", "--method", method, "--json"]) == 0
        measurements = json.loads(capsys.readouterr().out)["measurements"]
        ripples[method] = (measurements["vC"]["ripple"], measurements["vout"]["ripple"])
    assert ripples["spice"][0] == pytest.approx(ripples["lcp"][0], rel=0.05)
    assert ripples["spice"][1] == pytest.approx(ripples["lcp"][1], rel=0.05) and ripples["lcp"][1] > 4 * ripples["lcp"][0]


@pytest.mark.parametrize("step", [{"R_step": 5}, {"Vin_step": 10}, {"R_step": 5, "Vin_step": 10}])
def test_ngspice_runs_the_load_and_input_steps_the_model_runs(step, ngspice):
    """A step at 1 ms on a CCM buck (L 100 uH, D 0.5): ngspice's vout over the 20 periods after it is the event
    method's to 0.2 % (measured 0.09 %); the netlist had left the steps out, and ngspice had stayed at the 6.30 V
    before them."""
    from converters.run import run_converter
    params = {"t_step": "1m", "D": 0.5, "L": "100u", **step}
    means = [run_converter("buck", params, method=m, t_end=1.5e-3).mean("vout", t0=1e-3, t1=1.2e-3)
             for m in ("event", "spice")]
    assert means[1] == pytest.approx(means[0], rel=2e-3)
    assert means[0] < 5.6                                              # the step moves vout by more than 10 %


def test_the_voltage_mode_netlist_is_the_bucks_own_with_its_parasitics_and_load_step(ngspice):
    """The closed loop's netlist is the buck's file with the comparator on its gate: with rL, Ron, the ESR (the
    comparator reads v(out) behind it, as the model senses vout) and a load step at 40 ms, ngspice's 4 ms means
    before and after the step are the event method's to 1e-4 (measured 8e-6 and 1.3e-7), its ripple to 3 %
    (measured 1.2 %)."""
    from converters.run import run_converter
    params = {"Vin": 20, "rC": 0.05, "rL": 0.2, "Ron": 0.1, "t_step": "40m", "R_step": 11}
    runs = {m: run_converter("buck", params, control="voltage-mode", method=m, t_end=0.08) for m in ("event", "spice")}
    for t0, t1 in ((0.036, 0.04), (0.076, 0.08)):
        assert runs["spice"].mean("vout", t0=t0, t1=t1) == pytest.approx(runs["event"].mean("vout", t0=t0, t1=t1),
                                                                         rel=1e-4)
    assert runs["spice"].ripple("vout", t0=0.076) == pytest.approx(runs["event"].ripple("vout", t0=0.076), rel=3e-2)
    from netlists.build import build_voltage_mode_netlist
    text = build_voltage_mode_netlist(params, 0.08).text
    assert "V=0.5+0.5*tanh(100*(V(ramp)-8.4*(V(out)-11.3)))" in text and "Bstep out 0" in text


NETLISTS = Path(__file__).resolve().parents[2] / "netlists" / "circuits"


def test_the_netlist_of_a_netlist_file_is_what_ngspice_runs_with_its_output_measured(capsys):
    """``pcsuite netlist FILE.cir`` had refused every file ("CONVERTER must be one of ...; got 'buck.cir'"): it
    writes the circuit as compare runs it (the file's own ngspice settings, sense sources, no .control), measuring
    the file's output as vout and each state under a .meas word."""
    assert main(["netlist", str(NETLISTS / "buck.cir")]) == 0
    text = capsys.readouterr().out
    assert "* vout_mean and vout_ripple measure v(out)" in text
    assert ".meas tran vout_mean AVG v(out) FROM=0.0049 TO=0.005" in text            # 500 periods of 10 us
    assert ".meas tran i_l1_mean AVG i(vsense_l1) " in text and ".tran 5e-08 0.005 0 5e-08 UIC" in text
    assert main(["netlist", str(NETLISTS / "buck.cir"), "--control", "smc"]) == 2
    assert "--control applies to the built-in converters" in capsys.readouterr().err


def test_ngspice_runs_a_netlist_files_netlist_alone_as_simulate_runs_it(ngspice, tmp_path, capsys):
    path = tmp_path / "buck.cir"
    assert main(["netlist", str(NETLISTS / "buck.cir"), "--out", str(path)]) == 0
    out = subprocess.run([shutil.which("ngspice"), "-b", str(path)], capture_output=True, text=True, timeout=300,
                         cwd=tmp_path)
    assert out.returncode == 0, out.stderr[-2000:]
    meas = {m.group(1).lower(): float(m.group(2))
            for m in re.finditer(r"^(\w+)\s*=\s*([-+0-9.eE]+)\s+from=", out.stdout, re.MULTILINE)}
    capsys.readouterr()
    assert main(["simulate", str(NETLISTS / "buck.cir"), "--method", "spice", "--periods", "500", "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert meas["vout_mean"] == pytest.approx(summary["vout_mean"], rel=1e-6)        # 6.961939 both
    assert meas["v_c1_mean"] == meas["vout_mean"]
    assert meas["i_l1_mean"] == pytest.approx(meas["vout_mean"] / 10, rel=1e-4)         # the load's 10 ohm
