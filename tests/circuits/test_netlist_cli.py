"""A netlist file wherever a converter name is accepted: simulate (every method, ngspice included) and compare,
which runs ngspice on the same file (its ideal devices mapped to near-ideal models)."""
import json
import math
from pathlib import Path

import pytest

from converters.models import Circuit
from validation.cli import main

from .test_stiff import STIFF

NETLISTS = Path(__file__).resolve().parents[2] / "netlists" / "circuits"


def run_cli(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


@pytest.mark.parametrize("method", ["lcp", "event"])
def test_simulate_a_netlist_reports_every_signal_under_its_spice_name(capsys, method):
    code, out, err = run_cli(capsys, "simulate", NETLISTS / "buck.cir", "-p", "R=5", "-p", "D=0.5", "-p", "L=100u", "--steady",
                             "--method", method, "--json")
    summary = json.loads(out)
    assert code == 0 and summary["converter"] == "buck.cir"
    assert summary["vout_mean"] == pytest.approx(6.0, rel=1e-3)           # CCM: D Vin
    rows = summary["measurements"]
    assert {"v(out)", "v(sw)", "i(l1)", "i(d1)", "i(r1)", "i(vin)"} <= set(rows)
    assert rows["i(r1)"]["mean"] == pytest.approx(rows["v(out)"]["mean"] / 5.0, rel=1e-9)
    assert rows["i(l1)"]["mean"] == pytest.approx(rows["i(r1)"]["mean"], rel=1e-6)      # the capacitor's charge balance
    assert set(summary["mode_fractions"]) == {"S1", "D1"}


def test_a_netlist_parameter_is_refused_by_name(capsys):
    code, out, err = run_cli(capsys, "simulate", NETLISTS / "buck.cir", "-p", "Lx=1u")
    assert code == 2 and "unknown parameter 'lx'" in err and "valid names" in err and len(err.splitlines()) == 1


@pytest.mark.spice
@pytest.mark.parametrize("name", ["buck", "boost", "buck-boost", "cuk", "diode-bridge", "half-wave", "sync-buck",
                                  "sepic", "flyback", "interleaved-buck", "voltage-mode-buck", "voltage-mode-sync-buck",
                                  "voltage-loop-buck", "bridge-rectifier", "rectifier-1ph", "rectifier-3ph"])
def test_compare_runs_ngspice_on_the_same_netlist_and_passes(capsys, ngspice, name):
    code, out, err = run_cli(capsys, "compare", NETLISTS / f"{name}.cir", "--json")
    result = json.loads(out)
    assert code == 0 and result["passed"], (result["checks"], result["metrics"])
    if name not in ("diode-bridge", "half-wave"):            # periodic: per named output, mean and ripple
        # (spice_own_start: where ngspice from its own start had not settled, it approaches its run from the orbit)
        assert {k: v for k, v in result["checks"].items() if k != "spice_own_start"} == {
            "mean_rel": True, "ripple_rel": True, "mode_agreement": True}
        key = "v(p,n)_mean_rel_error" if "rectifier" in name else "v(out)_mean_rel_error"
        assert result["metrics"][key] <= 1e-3 and result["metrics"]["spice_settled"]
    if "rectifier" in name:       # the capacitor-input bridges stop ngspice at their first commutation by default
        assert any("ABSTOL 1e-06 A, diode CJO 1e-12 F" in note for note in result["notes"]), result["notes"]


@pytest.mark.spice
def test_compare_on_the_cockcroft_walton_ladder_passes_with_the_modes_read_alike_at_the_files_own_steps(capsys, ngspice):
    """The ladder's file asks ngspice for TMAX = T/2000 and ABSTOL = 1 uA (.tran, .options): its mean and ripple
    then meet the LCP's (3.7e-5 and 2.3e-3 measured); refined from compare's default T/200, its mean moves 7.4e-4. The mode
    sequences agree in every period, the even diodes' second conduction (at 1e-3 to 2e-3 of their peak) included,
    when both runs are read by the same rule (a diode conducts above 0.1 % of its peak) and the stepper takes the
    file's TSTEP = T/4000. Read by the LCS's own rule, D1 conducts on (its current decaying through RS towards 1e-6
    of its peak) until the source reverses, so there is no ``off`` after it; at T/1000 D6's tail reaches 0.11 %
    of its peak, ngspice's stays below 0.1 %."""
    from dataclasses import replace

    from converters.models import Circuit
    from validation.circuit_compare import _mode_sequences, compare_circuit
    from netlists.circuit import file_spice_options
    code, out, err = run_cli(capsys, "compare", NETLISTS / "cockcroft-walton.cir", "--json")
    result = json.loads(out)
    m = result["metrics"]
    assert code == 0 and {k: v for k, v in result["checks"].items() if k != "spice_own_start"} == {
        "mean_rel": True, "ripple_rel": True, "mode_agreement": True}, m
    assert m["v(out)_mean_rel_error"] < 1e-4 and m["v(out)_ripple_rel_error"] < 5e-3 and m["mode_agreement"] == 1.0
    assert m["mode_sequence_lcp"] == m["mode_sequence_spice"] == (
        "D1+D3+D5+D7 > D1+D3+D5 > D1+D3 > D1 > off > D2+D4+D6+D8 > D2+D4+D6 > D2+D4 > D2 > D2+D4 > D4 > off > D8")
    assert m["spice_settled"] and result["spice_options"]["tmax_fraction"] == pytest.approx(5e-4)
    circuit = Circuit.from_netlist(NETLISTS / "cockcroft-walton.cir")
    p = circuit.resolve({})
    T = circuit.period(p)
    assert circuit.default_h(p) == pytest.approx(T / 4000, rel=1e-12)
    coarse = compare_circuit(circuit, h=T / 1000, spice_options=replace(file_spice_options(circuit),
                                                                         tmax_fraction=1 / 200))
    # the modes fail at the stepper's T/1000, so ngspice is refined from T/200: its mean moves by more than 3e-4
    first = next(n for n in coarse.notes if n.startswith("ngspice at TMAX = 0.00125 T"))
    assert float(first.split("moved ")[1].split(" ")[0]) > 3e-4 and coarse.metrics["mode_agreement"] < 1.0
    exact = replace(coarse.lcp, measured={})                 # the LCS's own rule: D1 never reads off
    t1 = float(exact.t[-1])
    assert "D1 > off" not in " > ".join(_mode_sequences(exact, t1 - 10 * T, T, 10)[-1])


@pytest.mark.spice
def test_compare_reads_a_self_oscillating_circuit_by_its_cycles(capsys, ngspice):
    """The hysteretic buck (W1, no clock): ngspice's cycle is 3e-3 longer at TMAX 5 ns, so over its ~2,900 cycles
    the two oscillators drift apart in phase and a point-by-point reading (the transient's) sees them in the same
    mode about half the time; by its cycles over the last tenth the comparison passes: means, per-cycle ripples,
    the cycle, and the time in each mode."""
    import copy

    from converters.models import Circuit
    from validation.circuit_compare import THRESHOLDS, _transient, compare_circuit
    code, out, err = run_cli(capsys, "compare", NETLISTS / "hysteretic-buck.cir", "--json")
    result = json.loads(out)
    assert code == 0 and result["checks"] == {"mean_rel": True, "ripple_rel": True, "cycle_rel": True,
                                              "mode_fraction_apart": True}, result["metrics"]
    metrics = result["metrics"]
    assert metrics["cycle_rel_error"] < 5e-3 and metrics["v(out)_mean_rel_error"] < 5e-4
    assert metrics["cycle_lcp_s"] == pytest.approx(2 * 0.2 * 10e-6 * (1 / 7 + 1 / 5), rel=1e-4)
    circuit = Circuit.from_netlist(NETLISTS / "hysteretic-buck.cir")
    comparison = compare_circuit(circuit)
    pointwise = _transient(copy.copy(comparison), circuit, THRESHOLDS["circuit"])
    assert pointwise.metrics["mode_time_agreement"] < 0.9 and not pointwise.passed


@pytest.mark.spice
def test_the_convergence_fallback_is_what_lets_ngspice_run_a_capacitor_input_bridge(ngspice):
    """Without the fallback tolerances ngspice stops on the square-fed bridge (the reason the fallback exists)."""
    from converters.models import get_model
    from netlists import SpiceOptions
    from netlists.circuit import circuit_netlist
    from validation.spice import CONVERGENCE_FALLBACK, SpiceError, run_spice
    circuit = get_model(str(NETLISTS / "bridge-rectifier.cir"))
    p = circuit.resolve({})
    with pytest.raises(SpiceError, match="(?i)timestep too small"):
        run_spice(circuit_netlist(circuit, p, 6e-4, SpiceOptions()))
    result = run_spice(circuit_netlist(circuit, p, 6e-4, SpiceOptions(**CONVERGENCE_FALLBACK)))
    assert result.time[-1] >= 6e-4 * 0.999


@pytest.mark.spice
def test_simulate_a_netlist_in_ngspice_reads_the_same_signals(capsys, ngspice):
    code, out, err = run_cli(capsys, "simulate", NETLISTS / "boost.cir", "--method", "spice", "--steady", "--json")
    spice = json.loads(out)
    code2, out2, _ = run_cli(capsys, "simulate", NETLISTS / "boost.cir", "--steady", "--json")
    lcp = json.loads(out2)
    assert code == code2 == 0
    assert spice["vout_mean"] == pytest.approx(lcp["vout_mean"], rel=1e-3)
    assert spice["measurements"]["i(l1)"]["mean"] == pytest.approx(lcp["measurements"]["i(l1)"]["mean"], rel=2e-3)


@pytest.mark.slow
def test_bifurcation_follows_a_netlists_orbits_and_finds_the_hand_models_border_collision(capsys):
    """The buck along R (case-insensitive, as SPICE names are): the CCM/DCM border collision (the diode's
    turn-off appears) at the R the hand-derived buck gives, 3.3267 ohm (the small-ripple 2 L / ((1 - D) T) = 3.333)."""
    values = []
    for name, control in ((NETLISTS / "buck.cir", None), ("buck", "pwm")):
        argv = ["bifurcation", name, "--param", "R=2:20", "--points", "0", "--json"]
        code, out, err = run_cli(capsys, *argv, *(["--control", control] if control else []))
        assert code == 0, err
        collisions = [b for b in json.loads(out)["bifurcations"] if b["type"] == "border-collision"]
        values.append(collisions[0]["value"])
    assert values[0] == pytest.approx(values[1], rel=1e-6) and values[0] == pytest.approx(3.3267, rel=1e-3)


@pytest.mark.spice
@pytest.mark.parametrize("name, params, expected", [
    ("buck", [], "DCM"), ("buck", ["-p", "L=100u"], "CCM"), ("cuk", ["-p", "L1=10u", "-p", "L2=10u"], "GDCM"),
    ("sepic", ["-p", "R=100"], "GDCM")])
def test_gdcm_on_a_netlist_classifies_its_conduction_in_both_simulators(capsys, ngspice, name, params, expected):
    """A netlist has no closed-form prediction: gdcm reports the class each simulator shows on the same file (an
    interval with nothing conducting: DCM where the inductor currents are zero there, GDCM where they circulate:
    the Cuk's and the SEPIC's i1 = -i2) and the modes' fractions. The DCM buck's diode conducts for
    D (Vin - vout)/vout of the period, vout = 2 Vin/(1 + sqrt(1 + 4K/D^2)), K = 2L/(RT) = 0.2: 0.28941."""
    code, out, err = run_cli(capsys, "gdcm", NETLISTS / f"{name}.cir", *params, "--json")
    result = json.loads(out)
    assert code == 0 and result["agree"], result
    assert result["conduction"] == {"lcp": expected, "spice": expected}
    if expected == "DCM":
        vout = 2 * 12 / (1 + math.sqrt(1 + 4 * 0.2 / 0.4 ** 2))
        assert result["lcp"]["D1"] == pytest.approx(0.4 * (12 - vout) / vout, abs=1e-3)        # h = T/1000



@pytest.mark.spice
def test_compare_runs_ngspice_to_its_own_steady_state_so_a_wrong_orbit_is_not_passed(tmp_path, monkeypatch, ngspice):
    """pcsuite's orbit made wrong on purpose (the output capacitor at 1,000 V behind the blocked diode, as theta 0.5
    left it at 1.36 MV): ngspice started on that orbit keeps it (its 1e12 ohm leak takes 1e6 s) and compare passed;
    from its own start ngspice charges the capacitor to the wave's 10 V and compare fails."""
    from dataclasses import replace

    import numpy as np

    import validation.circuit_compare as cc
    from converters.models import Circuit
    path = tmp_path / "stiff.cir"
    path.write_text(STIFF.format(r="10", c="10n"))
    circuit = Circuit.from_netlist(path)
    right = cc.steady_state
    wrong = lambda *args, **kwargs: replace(right(*args, **kwargs), x0=np.array([0.0, 1000.0]))  # noqa: E731
    monkeypatch.setattr(cc, "steady_state", wrong)
    handed = cc.compare_circuit(circuit, spice_start="orbit")
    assert handed.passed and handed.metrics["v(out)_mean_spice"] == pytest.approx(1000.0, rel=1e-4)
    own = cc.compare_circuit(circuit)
    assert not own.passed and own.metrics["v(out)_mean_spice"] == pytest.approx(10.0, rel=1e-2)
    assert own.metrics["v(out)_mean_rel_error"] > 0.98


LIGHT_DCM_BOOST = """boost, 1 MHz, deep DCM at 10 Mohm: the diode conducts about 1.4e-3 T
Vin in 0 DC 5
Vg g 0 PULSE(0 1 0 0.01n 0.01n {0.3u-0.01n} 1u)
L1 in sw 10u
S1 sw 0 g 0 SWMOD
D1 sw out DMOD
C1 out 0 100n
R1 out 0 10Meg
.model SWMOD SW(VT=0.5)
.model DMOD D
.tran 1n 1m
.end
"""


@pytest.mark.slow
@pytest.mark.spice
def test_compare_does_not_pass_a_mean_that_ngspice_only_kept_from_pcsuites_orbit(tmp_path, capsys, ngspice):
    """A 1 MHz boost in deep DCM at 10 Mohm: the exact mean is the closed form Vin (1 + sqrt(1 + 4 D^2 / K)) / 2,
    K = 2 L / (R T): 1063.163 V. ngspice from its own start has not settled after 600 periods (a multiplier at
    0.999998), runs from pcsuite's orbit and keeps it. At the default, pcsuite's side is simulate --steady's answer:
    its stepper reads 1127.95 V (6.1 % high) and says so (estimate 0.18), so the exact orbit is compared, the closed
    form to 1e-9 (compare had compared the stepper's 1127.95 V). At a step given (--h, the default's T/1000), the
    stepper's 1127.95 V is compared, and the means agreed to 5e-7 and passed: it fails, saying why."""
    path = tmp_path / "light-dcm-boost.cir"
    path.write_text(LIGHT_DCM_BOOST)
    D, L, R, T = 0.3, 10e-6, 10e6, 1e-6
    exact = 5.0 * (1 + math.sqrt(1 + 4 * D * D / (2 * L / (R * T)))) / 2
    code, out, err = run_cli(capsys, "compare", path, "--json")
    result = json.loads(out)
    m = result["metrics"]
    assert abs(m["v(out)_mean_lcp"] / exact - 1) < 1e-9 and result["checks"]["mean_rel"] is True
    assert result["notes"][0].startswith("pcsuite's side: the default step's values are off by more than the defaults "
                                         "promise (its check at h and 2h: vout mean may be 1.8e-01 off")
    assert result["notes"][0].endswith("the exact (event) method's orbit is given")
    code, out, err = run_cli(capsys, "compare", path, "--h", "1n", "--json")
    result = json.loads(out)
    m = result["metrics"]
    assert abs(m["v(out)_mean_lcp"] / exact - 1) > 0.05 and m["v(out)_mean_rel_error"] < 1e-3
    assert m["lcp_mean_error_estimate"] > 0.05 and result["checks"]["mean_rel"] is False
    assert any(n.startswith("pcsuite's own estimate says its mean may be 0.18 off") for n in result["notes"])
    assert code != 0 and not result["passed"]


@pytest.mark.spice
def test_compare_on_the_stiff_node_says_where_ngspice_is_the_one_unresolved(tmp_path, capsys, ngspice):
    """The stiff node (10 ohm, 10 nF): pcsuite's 10 V is exact (1e-9 of droop a period). ngspice at the file's TMAX
    reads 10.015 V (its mean fails); its ripple and modes fail too, so it is refined twice (TMAX T/800, RELTOL 1e-4:
    10.0087 V, moved 6.6e-3; T/3200, 1e-5: 10.00027 V, moved 8.4e-4) and its mean passes at 2.7e-5: the verdict says
    ngspice resolves the mean to about 8.4e-4, not to 2.7e-5. The ripples (pcsuite's 5e-9 V, ngspice's 4.6e-6 V) both
    lie far below what RELTOL 1e-5 resolves on 10 V (1e-4 V): the ripple check fails on ngspice's rounding, and says
    so."""
    path = tmp_path / "stiff.cir"
    path.write_text(STIFF.format(r="10", c="10n"))
    code, out, err = run_cli(capsys, "compare", path, "--json")
    result = json.loads(out)
    m = result["metrics"]
    assert m["v(out)_mean_lcp"] == pytest.approx(10.0, abs=1e-8)
    assert 1e-5 < m["v(out)_mean_rel_error"] < 1e-4
    assert result["spice_options"]["reltol"] == 1e-5
    (resolved,) = [n for n in result["notes"] if n.startswith("ngspice's last refinement moved its mean")]
    moved = float(resolved.split("moved its mean ")[1].split(",")[0])
    assert moved > 3 * m["v(out)_mean_rel_error"]
    (ripple,) = [n for n in result["notes"] if n.startswith("both ripples of v(out)")]
    assert m["v(out)_ripple_spice"] < 0.1 * 1e-5 * 10.0 and "RELTOL 1e-05" in ripple
    assert not result["passed"] and code != 0


@pytest.mark.spice
def test_compare_runs_ngspice_finer_where_its_tmax_does_not_resolve_the_circuit_and_says_so(capsys, ngspice):
    """The DCM flyback with ngspice at TMAX = T/25 (RELTOL 1e-3): its mean is off by more than the 1e-3 threshold
    (the ringing after the diode's turn-off is not resolved); at T/100 and RELTOL 1e-4 it moves by ~7e-3, at T/400
    and 1e-5 by under 1e-3, and meets the LCP's within 1e-3: the verdict names each refinement and the TMAX
    compared. Without the refinement the comparison failed."""
    code, out, err = run_cli(capsys, "compare", NETLISTS / "flyback.cir", "--spice-tmax", "400n", "--json")
    result = json.loads(out)
    assert code == 0 and result["passed"] and result["metrics"]["v(out)_mean_rel_error"] < 1e-3
    first, second = [n for n in result["notes"] if n.startswith("ngspice at TMAX")]
    assert first.startswith("ngspice at TMAX = 0.01 T, RELTOL 0.0001: its mean of vout moved")
    assert second.startswith("ngspice at TMAX = 0.0025 T, RELTOL 1e-05: its mean of vout moved")
    assert float(first.split("moved ")[1].split(" ")[0]) > 1e-3
    assert result["spice_options"]["tmax_fraction"] == pytest.approx(1 / 400) and result["spice_options"]["reltol"] == 1e-5


#: A six-pulse rectifier on stiff 60 Hz sources with a DC-side LC filter: its commutations are microseconds long
RECTIFIER_LC = """Three-phase six-pulse diode rectifier (100 V phase peak, 60 Hz, stiff sources) with a DC-side LC filter
.param Vpk=100 f=60 Ldc=5m Cdc=2.2m R=20
Va a 0 SIN(0 {Vpk} {f} 0 0 0)
Vb b 0 SIN(0 {Vpk} {f} 0 0 -120)
Vc c 0 SIN(0 {Vpk} {f} 0 0 120)
D1 a p DM
D3 b p DM
D5 c p DM
D4 n a DM
D6 n b DM
D2 n c DM
Ldc p x {Ldc}
Cdc x n {Cdc}
R1 x n {R}
.model DM D
.tran 10u 500m
.meas tran vdc AVG v(x,n) FROM={480m} TO={500m}
.end
"""


@pytest.mark.slow
@pytest.mark.spice
def test_compare_runs_ngspice_finer_where_its_modes_or_ripple_fail_though_its_mean_agrees(tmp_path, capsys, ngspice):
    """ngspice's default TMAX (T/200, 83 us) on the LC-filtered rectifier: its mean agrees to 1e-5, but its diodes'
    commutations are read on its steps, so a period's modes agree at 0.4 and its ripple fails; refined to T/800 and
    T/3200 (RELTOL 1e-4, 1e-5) both pass (ripple 3.3e-3, modes 1.0). While the refinement ran only where the mean
    failed, this compare failed on its modes and ripple."""
    netlist = tmp_path / "rectifier-lc.cir"
    netlist.write_text(RECTIFIER_LC)
    code, out, err = run_cli(capsys, "compare", netlist, "--json")
    result = json.loads(out)
    assert code == 0 and result["passed"], result["checks"]
    assert result["metrics"]["mode_agreement"] == 1.0
    assert result["metrics"]["v(x,n)_ripple_rel_error"] < 0.02
    assert any(n.startswith("ngspice at TMAX = 0.00125 T, RELTOL 0.0001") for n in result["notes"])


FILTERED_BUCK = """Type II voltage-mode buck behind a lightly damped LC input filter
.param Vs=12 Lf=100u rLf=0.05 Cf=10u L=100u C=100u Resr=0.2 R=10 f_sw=100k
.param Vref=5 Aol=1e5 Ri=10k Rz=20k Cz=15n Cp=270p
.param T={1/f_sw} e={1e-8/f_sw}
Vs src 0 DC {Vs}
Lf src lfr {Lf}
RLf lfr in {rLf}
Cf in 0 {Cf}
S1 in sw vcon ramp SWMOD
D1 0 sw DMOD
L1 sw out {L}
C1 out ce {C}
Resr ce 0 {Resr}
R1 out 0 {R}
R2 out fb {Ri}
C2 vcon nz {Cz}
R4 nz fb {Rz}
C4 vcon fb {Cp}
Vr ref 0 DC {Vref}
E1 vcon 0 ref fb {Aol}
Vramp ramp 0 PULSE(0 1 0 {T - 2*e} {e} {e} {T})
.model SWMOD SW(VT=0)
.model DMOD D
.tran {T/500} {2000*T} 0 {T/2000} UIC
.end
"""


@pytest.mark.slow
def test_compare_refuses_an_orbit_the_circuit_does_not_settle_on(tmp_path, capsys):
    """A type II buck whose loop's negative input resistance (-12.5 ohm) undamps its input filter (Z0 3.16 ohm,
    Middlebrook): its orbit's multipliers 0.957 +- 0.298j lie outside the unit circle (radius 1.00249), and from rest
    it oscillates at ~4.8 kHz about it (v(in) 6.9 to 14.6 V after 4000 periods; the orbit's ripple 0.057 V, the
    circuit's 0.27 V). compare had PASSed (mean 4.2e-6, ripple 7.4e-4): ngspice, not settled from its own start,
    was compared from pcsuite's orbit and stayed near it. It refuses as simulate --steady does."""
    path = tmp_path / "filtered.cir"
    path.write_text(FILTERED_BUCK)
    code, out, err = run_cli(capsys, "compare", path, "--json")
    assert code == 2 and out == "" and len(err.strip().splitlines()) == 1
    assert "is unstable (Floquet spectral radius 1.00249" in err and "a multiplier at 0.957" in err
    assert "an oscillation about it at about 4.81e+03 Hz" in err and "--start rest" in err


SPLIT_OUTPUT = """Boost with a split output (100u over 47u) and 1 Gohm balancing resistors
.param Vin=12 L=47u C1=100u C2=47u Rb=1G R=20 f_sw=100k D=0.5
.param T={1/f_sw} e={1e-6/f_sw}
Vin in 0 DC {Vin}
Vg gate 0 PULSE(1 0 {D*T - e/2} {e} {e} {(1-D)*T - e} {T})
L1 in sw {L}
S1 sw 0 gate 0 SWMOD
D1 sw out DMOD
C1 out mid {C1}
C2 mid 0 {C2}
Rb1 out mid {Rb}
Rb2 mid 0 {Rb}
R1 out 0 {R}
.model SWMOD SW(VT=0.5)
.model DMOD D
.tran {T/1000} {1000*T} 0 {T/200} UIC
.end
"""


def test_compare_offers_what_compare_takes_where_newton_does_not_find_the_orbit(tmp_path, capsys):
    """The midpoint of a split output balanced by 1 Gohm settles over ~1e10 periods (1 - rho = 1.36e-10): Newton
    resolves its orbit to ~3e-5, not the 1e-6 compare takes. The refusal had offered simulate's --steady-tol, which
    compare does not take ("unrecognized arguments"); it offers --start rest, and sensitivity simulate's run from
    rest."""
    path = tmp_path / "split.cir"
    path.write_text(SPLIT_OUTPUT)
    code, out, err = run_cli(capsys, "compare", path)
    assert code == 2 and len(err.strip().splitlines()) == 1
    assert "Newton shooting did not find the periodic orbit of split.cir" in err and "1 - rho = 1.36e-10" in err
    assert err.rstrip().endswith("; compare both from rest with --start rest") and "--steady-tol" not in err
    code, out, err = run_cli(capsys, "sensitivity", path)                  # no tolerance to loosen there either
    assert code == 2 and err.rstrip().endswith("; see where the circuit goes with pcsuite simulate --periods N")


LLC = """LLC half-bridge: complementary switches with dead time and body diodes, Cr Lr Lm, ideal transformer (E/F)
.param Vin=400 Lr=60u Cr=24n Lm=300u n=8 Co=20u R=10 f_sw=120k td=200n
.param T={1/f_sw} e={1e-6/f_sw}
Vin in 0 DC {Vin}
Vg1 g1 0 PULSE(1 0 {T/2 - td - e/2} {e} {e} {T/2 + td - e} {T})
Vg2 g2 0 PULSE(0 1 {T/2 - e/2} {e} {e} {T/2 - td - e} {T})
S1 in hb g1 0 SWMOD
D1 hb in DMOD
S2 hb 0 g2 0 SWMOD
D2 0 hb DMOD
Cr hb a {Cr}
Lr a p {Lr}
Lm p 0 {Lm}
Et s 0 p 0 {1/n}
Vt s b DC 0
Ft p 0 Vt {1/n}
D3 b out DMOD
D4 0 out DMOD
D5 nn 0 DMOD
D6 nn b DMOD
Co out nn {Co}
R1 out nn {R}
.model SWMOD SW(VT=0.5)
.model DMOD D
.tran {T/1000} {1000*T} 0 {T/200} UIC
.meas tran vo_mean AVG v(out,nn) FROM={990*T} TO={1000*T}
.end
"""


def test_compare_says_what_it_tried_where_ngspice_stops_on_every_retry(tmp_path, capsys, ngspice):
    """An LLC's output bridge behind an ideal transformer stops ngspice ("timestep too small" at a sense source
    beside a diode) at RELTOL 1e-3 through the ABSTOL and CJO fallback and three quarterings of TMAX: the refusal
    had been ngspice's last message alone; it says what was tried and what runs it. At RELTOL 1e-2 ngspice runs it
    and agrees with the LCP (mean 1.7e-4 apart, modes alike)."""
    path = tmp_path / "llc.cir"
    path.write_text(LLC)
    code, out, err = run_cli(capsys, "compare", path)
    assert code == 2 and len(err.strip().splitlines()) == 1 and "Timestep too small" in err
    assert "after 4 runs more (ABSTOL 1e-06 A, diode CJO 1e-12 F, TMAX down to 7.8125e-05 T)" in err
    assert "a looser --spice-reltol" in err
    code, out, err = run_cli(capsys, "compare", path, "--spice-reltol", "1e-2", "--json")
    result = json.loads(out)
    assert code == 0 and result["metrics"]["v(out,nn)_mean_rel_error"] < 1e-3
    assert result["metrics"]["mode_agreement"] == 1.0


def test_a_refinement_ngspice_cannot_run_leaves_the_comparison_made(tmp_path, ngspice):
    """The LLC at RELTOL 1e-2 held to a ripple within 1e-9 (its mean agrees to 1.7e-4): compare refines ngspice to
    RELTOL 1e-3, where it stops on every retry. That had ended the command with ngspice's error; the comparison made
    stands, and says why it was not refined. (A mean held within 1e-5 is not refined: ngspice's models dissipate
    8.2e-5 of the input power there, a difference no finer run removes.)"""
    from validation.circuit_compare import compare_circuit
    from validation.ngspice import spice_settings
    path = tmp_path / "llc.cir"
    path.write_text(LLC)
    circuit = Circuit.from_netlist(path)
    options = spice_settings(circuit.period(circuit.resolve({})), None, 1e-2, None)
    result = compare_circuit(circuit, spice_options=options, thresholds={"ripple_rel": 1e-9})
    assert not result.passed and not next(ok for name, *_, ok in result.rows if name == "ripple_rel")
    assert 1e-5 < result.metrics["v(out,nn)_mean_rel_error"] < 1e-3
    (note,) = [n for n in result.notes if "did not run" in n]
    assert note.startswith("ngspice at TMAX = 0.00125 T, RELTOL 0.001 did not run (")
    assert note.endswith("): compared at TMAX = 0.005 T, RELTOL 0.01")


def test_a_refinement_past_the_memory_limit_leaves_the_comparison_made(monkeypatch, ngspice):
    """A refinement whose ngspice run would pass the memory limit (a push-pull's at TMAX T/3200 needed 8.33 GiB)
    had ended compare with that error, the comparison already made lost. The buck held to a ripple within 1e-12
    under 32 MiB: refined once, then the next run (57.6 MiB) is a note, and the comparison at the last TMAX stands."""
    from validation.circuit_compare import compare_circuit
    monkeypatch.setenv("PCSUITE_MAX_MEMORY", "32M")
    result = compare_circuit(Circuit.from_netlist(NETLISTS / "buck.cir"), thresholds={"ripple_rel": 1e-12})
    assert not result.passed and result.metrics["v(out)_mean_rel_error"] < 1e-3
    (note,) = [n for n in result.notes if "did not run" in n]
    assert note.startswith("ngspice at TMAX = 0.0003125 T, RELTOL 1e-05 did not run (")
    assert "above the memory limit of 32 MiB): compared at TMAX = 0.00125 T, RELTOL 0.0001" in note
    assert "--spice-tmax" not in note


@pytest.mark.slow
def test_compare_does_not_refine_ngspice_where_its_models_losses_make_the_difference(tmp_path, ngspice):
    """A boost at D = 0.99 (1200 V from 12 V): ngspice's RON dissipates ~1 % of the input power on pcsuite's orbit,
    and its mean is 1.04 % lower. compare refined ngspice (TMAX / 4, RELTOL / 10), which ran to its 600 s time limit
    before the same FAIL; the models' losses make that difference at any resolution, so it does not refine."""
    from validation.circuit_compare import compare_circuit
    from ..analysis.test_periodic import DCM_BOOST
    path = tmp_path / "boost99.cir"
    path.write_text(DCM_BOOST)
    result = compare_circuit(Circuit.from_netlist(path), {"D": 0.99, "L": 10e-6, "C": 100e-6, "R": 1000.0,
                                                           "f_sw": 100e3})
    assert not result.passed and 0.009 < result.metrics["v(out)_mean_rel_error"] < 0.012
    assert not any(note.startswith("ngspice at TMAX") for note in result.notes), result.notes
    assert any("ngspice's switch and diode models (RON = 0.001 ohm" in note for note in result.notes)
    # every ngspice run it made (two settlings of 600 periods) against the last chunk's alone
    assert result.metrics["spice_total_s"] > 10 * result.metrics["spice_wall_s"]


def test_a_meas_of_a_difference_is_measured_by_simulate_and_compared_by_compare(tmp_path, capsys, ngspice):
    """A second .meas of v(in,sw) (the switch's voltage) beside the output: compare had stopped with "signal must
    be one of ...; got 'v(in,sw)'" and simulate had left it out of its measurements. Its mean over the orbit is
    Vin - vout's mean (an inductor's mean voltage is 0 over a period); simulate's and compare's, read on the run's
    steps (T/1000) by the linear rule, are within h vout / (2 T) = 3.5e-3 V of it (the diode's turn-off inside a
    step, where v(sw) jumps by vout), and ngspice's within the mean check's 1e-3."""
    text = (NETLISTS / "buck.cir").read_text().replace(
        ".end", ".meas tran vsw AVG v(in,sw) FROM={490*T} TO={500*T}\n.end")
    path = tmp_path / "buck-vsw.cir"
    path.write_text(text)
    code, out, err = run_cli(capsys, "simulate", path, "--steady", "--json")
    rows = json.loads(out)["measurements"]
    assert code == 0 and rows["v(in,sw)"]["unit"] == "V"
    exact = 12.0 - rows["v(out)"]["mean"]
    assert abs(rows["v(in,sw)"]["mean"] - exact) <= 1e-3 * rows["v(out)"]["mean"] / 2
    code, out, err = run_cli(capsys, "compare", path, "--json")
    result = json.loads(out)
    assert code == 0 and result["passed"] and result["metrics"]["v(in,sw)_mean_rel_error"] < 1e-3
    assert result["metrics"]["v(in,sw)_mean_lcp"] == pytest.approx(rows["v(in,sw)"]["mean"], rel=1e-9)
    assert abs(result["metrics"]["v(in,sw)_mean_spice"] - exact) <= 1e-3 * exact


SEPIC_SPLIT = """SEPIC whose coupling capacitor is two in series (their junction m touches nothing else)
.param Vin=12 L1=47u L2=47u Ca=4.7u Cb=10u C=100u R=12 f_sw=100k D=0.6
.param T={1/f_sw} e={1e-6/f_sw}
Vin in 0 DC {Vin}
Vg gate 0 PULSE(1 0 {D*T - e/2} {e} {e} {(1-D)*T - e} {T})
L1 in sw {L1}
S1 sw 0 gate 0 SWMOD
Ca sw m {Ca}
Cb m k {Cb}
L2 k 0 {L2}
D1 k out DMOD
Co out 0 {C}
R1 out 0 {R}
.model SWMOD SW(VT=0.5)
.model DMOD D
.tran {T/1000} {1000*T} 0 {T/200} UIC
.meas tran vout_mean AVG v(out) FROM={990*T} TO={1000*T}
.end
"""


def test_netlist_steady_starts_on_the_orbit_found_to_simulates_tolerance(tmp_path, capsys):
    """A SEPIC at rho = 1 - 3.6e-6 (its light damping): Newton resolves the orbit to 2.6e-10 in double precision,
    and `netlist --steady` had asked for 1e-10 and refused it, where `simulate --steady` (1e-6) runs. The netlist
    now starts on the orbit found to simulate's tolerance: its IC of Co is simulate's orbit's v(co) to 1e-6."""
    import re

    from converters.run import run_converter
    path = tmp_path / "sepic.cir"
    path.write_text(SEPIC_SPLIT)
    code, out, err = run_cli(capsys, "netlist", path, "--steady")
    assert code == 0, err
    ic = float(re.search(r"^Co out 0 \S+ IC=(\S+)$", out, re.M).group(1))
    tr = run_converter(str(path), steady=True, periods=1)
    assert ic == pytest.approx(tr.x[0, tr.state_names.index("v(co)")], rel=1e-6)


def test_compare_refuses_the_llc_read_at_its_floating_secondary(tmp_path, capsys):
    """Read at v(out), the secondary's node against ground, which the ideal bridge leaves floating while its diodes
    block (pcsuite's 12.906 V is one pick; ngspice's 13.227 V is its RSHUNT's): compare refuses in one line before
    ngspice runs, naming the nodes and the difference to measure."""
    path = tmp_path / "llc.cir"
    path.write_text(LLC.replace(".meas tran vo_mean AVG v(out,nn) FROM={990*T} TO={1000*T}\n", ""))
    code, out, err = run_cli(capsys, "compare", path)
    assert code == 2 and len(err.strip().splitlines()) == 1
    assert "compare: llc.cir's output v(out) (" in err
    assert "is not set by the circuit: while D3, D4, D5 and D6 block, nodes out, nn float" in err
    assert "measure a voltage across the floating nodes (v(out,nn))" in err


HALF_BRIDGE = """Half-bridge inverter, 560 V split link, 50 Hz sine-triangle PWM (2 kHz), R-L load to the link midpoint
.param Vlink=560 Cdc=1m m=0.9 f0=50 fcar=2k Rl=8 Ll=12m
.param Tcar={1/fcar} ee={1e-7/fcar}
Vlink bus 0 DC {Vlink}
Ctop bus mid {Cdc}
Cbot mid 0 {Cdc}
Vmod vmod 0 SIN(0 {m} {f0})
Vcar vcar 0 PULSE(-1 1 0 {Tcar/2-ee} {Tcar/2-ee} {ee} {Tcar})
Shi bus ph vmod vcar SWI
Slo ph 0 vcar vmod SWI
Dhi ph bus DFW
Dlo 0 ph DFW
Rload ph x {Rl}
Lload x mid {Ll}
.model SWI SW(VT=0)
.model DFW D
.tran {Tcar/100} {10/f0} 0 {Tcar/100} UIC
.meas tran il_rms RMS i(Lload) FROM={9/f0} TO={10/f0}
.end
"""


@pytest.mark.slow
def test_a_refinement_of_an_ac_output_says_its_move_against_the_outputs_rms(tmp_path, capsys, ngspice):
    """The half-bridge's load current has a mean of ~3e-12 A against an RMS of ~28 A: at TMAX T/200 its modes fail,
    and ngspice's mean moves 4 mA at T/800. That move was said relative to the mean ("moved 9e+08"); it is 1.4e-4 of
    the RMS, what the mean's error is measured against."""
    path = tmp_path / "hb.cir"
    path.write_text(HALF_BRIDGE)
    code, out, err = run_cli(capsys, "compare", path, "--spice-tmax", "100u", "--json")
    result = json.loads(out)
    assert code == 0 and abs(result["metrics"]["i(lload)_mean_lcp"]) < 1e-9
    (note,) = [n for n in result["notes"] if n.startswith("ngspice at TMAX = 0.00125 T")]
    moved = float(note.split("moved ")[1].split(" ")[0])
    assert 1e-5 < moved < 1e-3 and result["metrics"]["i(lload)_mean_rel_error"] < 1e-3


def test_an_estimate_the_checks_own_orbit_cannot_give_says_whose_tolerance_it_missed(tmp_path, capsys):
    """At --steady-tol 1e-4 the split output's orbit is found (resolved to 5.3e-5); the accuracy check's orbit, shot
    again to 1e-8, is not: its warning had read "> tol 1e-08" as if that were the run's. The mean is the event
    method's (exact flows; 23.991557232 V at the same settings) to 1.4e-9."""
    path = tmp_path / "split.cir"
    path.write_text(SPLIT_OUTPUT)
    code, out, err = run_cli(capsys, "simulate", path, "--steady", "--steady-tol", "1e-4", "--json")
    summary = json.loads(out)
    (warning,) = summary["warnings"]
    assert code == 0 and warning.startswith("vout mean's error could not be estimated: the check's own orbit (Newton "
                                            "from the run's end to 1e-8, or to 1e-06 where rounding stops it)")
    assert summary["vout_mean"] == pytest.approx(23.991557232, rel=1e-8)
