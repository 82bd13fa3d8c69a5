"""The compiler's schedules and inputs, against what the waveforms say."""
from pathlib import Path

import numpy as np
import pytest

from converters.models import Circuit
from converters.run import run_converter, run_summary

BUCK = """buck whose gate opens at t = 0 and closes later in the period
.param Vin=12 L=100u C=100u R=5 f=100k
.param T={{1/f}} e={{1e-6/f}}
Vin in 0 DC {{Vin}}
Vg gate 0 PULSE(0 1 {td} {{e}} {{e}} {pw} {{T}})
S1 in sw gate 0 SW1
D1 0 sw D1
L1 sw out {{L}}
C1 out 0 {{C}}
R1 out 0 {{R}}
.model SW1 SW(VT=0.5)
.model D1 D
.tran 100n 5m
.end
"""


def test_a_switch_that_is_off_at_the_start_and_the_end_of_the_period_is_on_only_between():
    """The gate rises at 0.2 T and falls at 0.6 T: the schedule is off, on, off (the last slot had been merged into
    the first across the period's end, which left the switch on from 0.2 T to T: a duty of 0.8, not 0.4)."""
    circuit = Circuit.from_netlist("late.cir", text=BUCK.format(td="{0.2*T - e/2}", pw="{0.4*T - e}"))
    p = circuit.resolve({})
    schedule = circuit.compiled(p).law
    assert [round(s / 1e-5, 12) for s in schedule.starts] == [0.0, 0.2, 0.6]
    summary = run_summary(run_converter(circuit, {}, steady=True, method="event"))
    assert summary["vout_mean"] == pytest.approx(0.4 * 12, rel=1e-9)          # CCM: D Vin
    assert summary["mode_fractions"]["S1"] == pytest.approx(0.4, abs=1e-12)


def test_a_circuit_with_more_diodes_than_the_inline_solver_takes_runs_in_the_stepper():
    """A 5-stage multiplier has k = 10 diodes, more than the compiled loop's enumerating solver takes (8): the loop
    pivots instead (tests/lcp/test_pivoting.py), every step of the run done there."""
    from converters.methods import Theta
    from converters.simulate import simulate
    from netlists.generators import cockcroft_walton
    circuit = Circuit.from_netlist("cw5.cir", text=cockcroft_walton(5))
    p = circuit.resolve({})
    T = circuit.period(p)
    tr = simulate(circuit.problem(p, 2 * T), Theta(h=T / 200, theta=0.5))
    assert circuit.compiled(p).configurations[0].k == 10 and tr.steps == 400 and tr.general_solves == 0
    assert circuit.compiled(p).law.starts == (0.0, T / 2)     # the edges' middles, none a rounding's 1e-21 s
    assert np.isfinite(tr.x).all()


VOLTAGE_MODE = Path(__file__).resolve().parents[2] / "netlists" / "circuits" / "voltage-mode-buck.cir"


@pytest.mark.parametrize("vin", [20, 24])
def test_a_comparator_on_the_circuits_own_voltages_is_the_hand_models_state_driven_law(vin):
    """The voltage-mode buck as a netlist (an E amplifier, a sawtooth PULSE, a switch whose control is v(ramp) -
    v(vcon)) compiles to the hand model's StateSwitching: the same period-1 orbit (to 1e-10) and Floquet multipliers.
    The hand model's sawtooth retraces at once; the file's PULSE over 2e-8 of the period (its orbit 3e-10 away),
    here over 2e-13."""
    from converters.methods import EventDriven
    from converters.models import get_model
    from converters.run import steady_state
    text = VOLTAGE_MODE.read_text()
    assert ".param e={1e-8*T}" in text
    circuit = Circuit.from_netlist("ideal-ramp.cir", text=text.replace(".param e={1e-8*T}", ".param e={1e-13*T}"))
    hand = get_model("buck", "voltage-mode")
    p_c, p_h = circuit.resolve({"Vin": vin}), hand.resolve({"Vin": vin})
    orbit_c = steady_state(circuit, p_c, EventDriven(), tol=1e-11)
    orbit_h = steady_state(hand, p_h, EventDriven(), tol=1e-11)
    assert abs(orbit_c.x0[::-1] - orbit_h.x0).max() <= 1e-10 * abs(orbit_h.x0).max()
    assert orbit_c.spectral_radius == pytest.approx(orbit_h.spectral_radius, rel=1e-9)


def test_the_voltage_mode_netlist_doubles_its_period_at_the_published_input_voltage(capsys):
    """Its period-1 orbit flips at Vin = 24.516573 V, as the hand model's (and Fossas and Olivar's) does."""
    import json

    from validation.cli import main
    assert main(["bifurcation", str(VOLTAGE_MODE), "--param", "Vin=20:26", "--points", "0", "--max-period", "2",
                 "--json"]) == 0
    flips = [b for b in json.loads(capsys.readouterr().out)["bifurcations"] if b["type"] == "period-doubling"]
    assert flips[0]["value"] == pytest.approx(24.516573, abs=2e-6)



def _literal_ramp_orbit(vin, e):
    """An independent reference: the voltage-mode buck (Hamill, Deane and Jefferies 1992: L 20 mH, C 47 uF, R 22 ohm,
    vcon = 8.4 (vout - 11.3), S1 closed while PULSE(3.8 8.2 0 T-2e e e T) exceeds it) with the PULSE as written: CCM
    flows by scipy's expm, the rising and falling crossings by brentq to 1e-15 of the period, the period-1 orbit by
    fsolve; the mean of vout over the period from the flow's integral row. Returns (mean vout, S1's opening / T)."""
    from scipy.linalg import expm
    from scipy.optimize import brentq, fsolve
    L, C, R, Vref, A, VL, VU, T = 20e-3, 47e-6, 22.0, 11.3, 8.4, 3.8, 8.2, 400e-6
    TR, PW, TF = T - 2 * e * T, e * T, e * T

    def ramp(t):
        return VL + (VU - VL) * t / TR if t <= TR else VU if t <= TR + PW else VU - (VU - VL) * (t - TR - PW) / TF

    def flow(z, on, dt):                               # z = (iL, vC, 1, integral of vC)
        m = np.zeros((4, 4))
        m[0, 1], m[0, 2], m[1, 0], m[1, 1], m[3, 1] = -1 / L, vin / L if on else 0.0, 1 / C, -1 / (R * C), 1.0
        return expm(m * dt) @ z

    def period(x0):
        z = np.array([x0[0], x0[1], 1.0, 0.0])
        closes = brentq(lambda t: ramp(t) - A * (flow(z, False, t)[1] - Vref), 0.0, TR, xtol=1e-18, rtol=1e-15)
        z1 = flow(z, False, closes)
        opens = brentq(lambda t: ramp(t) - A * (flow(z1, True, t - closes)[1] - Vref), TR + PW, T * (1 - 1e-15),
                       xtol=1e-18, rtol=1e-15)
        z2 = flow(z1, True, opens - closes)
        return flow(z2, False, T - opens), opens
    x = fsolve(lambda x0: period(x0)[0][:2] - x0, [0.55, 12.0], xtol=1e-13)
    z, opens = period(x)
    return z[3] / T, opens / T


@pytest.mark.parametrize("method", ["event", "lcp"])
def test_a_comparators_ramp_is_the_literal_pulses_but_for_half_its_fall(method):
    """A ramp PULSE(VL VU 0 T-2e e e T) falling over e = 5e-4 T: S1 opens as it falls (at 0.99979 T here). Taken as
    the sawtooth over the whole period (its slope (VU - VL) / T, its retrace at T) vout read 9.9e-5 V off an
    independent computation of the literal PULSE; with the PULSE's own slope and its reset at the fall's middle it
    is 2.2e-5 V off (the opening moved by 4.3e-5 T, less than TF / 2, as its note says). The period doubling with
    the fall of 1e-6 T: 24.5166175 V against the literal PULSE's 24.5166184 (the same reference's Floquet multiplier
    through -1, by central differences of its period map; the sawtooth over the whole period: 24.516573)."""
    from converters.run import run_converter
    text = VOLTAGE_MODE.read_text().replace(".param e={1e-8*T}", ".param e={5e-4*T}")
    literal, opens = _literal_ramp_orbit(20.0, 5e-4)
    assert 0.9995 < opens < 1.0                       # S1 opens inside the fall
    tr = run_converter(Circuit.from_netlist("ramp.cir", text=text), {"Vin": 20}, steady=True, method=method)
    assert abs(tr.mean("vout") - literal) < 2.5e-5
    sawtooth = run_converter("buck", {"Vin": 20}, control="voltage-mode", steady=True, method="event")
    assert abs(sawtooth.mean("vout") - literal) > 9e-5


@pytest.mark.slow
def test_the_voltage_mode_netlists_doubling_with_a_slow_fall_is_the_literal_pulses(capsys, tmp_path):
    """The doubling with the shipped file's ramp falling over 1e-6 T (the file before: e = 1e-6 T): 24.5166175 V,
    the literal PULSE's 24.5166184 (the independent reference of _literal_ramp_orbit: its multiplier through -1 by
    brentq on Vin, the Jacobian by central differences of 1e-5 and 5e-7, agreeing to 6e-9 V); the sawtooth over the
    whole period had given 24.516573, 4.6e-5 off, and a note now says a switching may move by 5e-7 of the period."""
    import json

    from validation.cli import main
    path = tmp_path / "ramp.cir"
    path.write_text(VOLTAGE_MODE.read_text().replace(".param e={1e-8*T}", ".param e={1e-6*T}"))
    assert main(["bifurcation", str(path), "--param", "Vin=24:25", "--points", "0", "--max-period", "2",
                 "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    flips = [b for b in out["bifurcations"] if b["type"] == "period-doubling"]
    assert flips[0]["value"] == pytest.approx(24.5166184, abs=1.5e-6)
    assert abs(flips[0]["value"] - 24.516573) > 4e-5

SYNC = VOLTAGE_MODE.with_name("voltage-mode-sync-buck.cir")


@pytest.mark.parametrize("R", ["22", "1k"])
def test_a_low_side_switch_on_the_same_comparator_is_its_complement(R):
    """S2 reads v(vcon) - v(ramp), the negative of S1's control, at VT = 0: it closes exactly while S1 is open (the
    law keeps two configurations: S1 closed and S2 open, or the reverse). At 22 ohm (CCM) the orbit is the
    diode-rectified buck's to 1e-10 (the diode carries what S2 does); at 1 kohm, where that buck enters DCM, the
    synchronous one stays in CCM with a negative inductor current for a while. Either way v(sw) is Vin while S1
    is closed and 0 while S2 is: on the orbit the inductor's mean voltage is 0, so mean vout = Vin times S1's
    fraction of the period, exactly."""
    from converters.run import run_converter
    sync, plain = Circuit.from_netlist(SYNC), Circuit.from_netlist(VOLTAGE_MODE)
    compiled = sync.compiled(sync.resolve({"R": R}))
    assert compiled.switch_names == ("s1", "s2") and compiled.closed == ((False, True), (True, False))
    tr = run_converter(sync, {"R": R}, method="event", steady=True, periods=1, steady_tol=1e-11)
    fractions = tr.mode_fractions(None, t0=tr.t[0], t1=tr.t[-1])
    assert set(fractions) == {"S1", "S2"}
    assert tr.mean("vout") == pytest.approx(24.0 * fractions["S1"], rel=1e-9)
    current = np.asarray(tr.signal("i(l1)", np.arange(tr.t.size)))
    other = run_converter(plain, {"R": R}, method="event", steady=True, periods=1, steady_tol=1e-11)
    if R == "22":
        assert np.abs(tr.x[0] - other.x[0]).max() <= 1e-10 * np.abs(other.x[0]).max() and current.min() > 0
    else:
        assert "off" in set(other.modes()) and current.min() < -0.04


def test_a_param_and_an_element_of_the_same_name_are_refused():
    """-p R1=7 had silently set one of them (.param r1 and the resistor R1: SPICE names ignore case)."""
    from converters.circuits.netlist import NetlistError
    text = "dup\n.param r1=5\nVin in 0 DC 12\nR1 in out 10\nC1 out 0 1u\n.tran 1u 1m\n.end\n"
    with pytest.raises(NetlistError, match=r"dup.cir:2: .param r1 and resistor R1 \(line 4\) share a name"):
        Circuit.from_netlist("dup.cir", text=text)
    # a source with a waveform is no parameter, but a .param of its name reached it as one: "-p vin: voltage source
    # Vin is a PWL source", where no -p was given
    text = "dup\n.param Vin=12\nVin in 0 PWL(0 12 5u 14 10u 12)\nR1 in out 10\nC1 out 0 1u\n.tran 1u 1m\n.end\n"
    with pytest.raises(NetlistError, match=r"dup.cir:2: .param vin and voltage source VIN \(line 3\) share a name"):
        Circuit.from_netlist("dup.cir", text=text)


TRIANGLE = """triangle through a half-wave rectifier
Vs in 0 PULSE(-10 10 0 {tr} {tr} {pw} 50u)
D1 in x DMOD
R1 x 0 1k
R2 x out 1Meg
C2 out 0 100n
.model DMOD D
.tran 50n 20m
.end
"""


@pytest.mark.parametrize("method", ["lcp", "event"])
def test_a_power_pulse_whose_edges_are_ramps_reads_a_trapezoid_through_a_rectifier(method, tmp_path):
    """A power PULSE whose edges take more than 1e-2 of its levels is a ramp of the LCS. A +-10 V trapezoid (20 us
    edges, 5 us levels, 50 us) through a half-wave rectifier had been refused (edges above T/1000; read as a square
    wave before that, a triangle gave 5.0026 V for 2.5 V). With no load on out, C2's charge balance makes v(out)'s
    mean v(x)'s: V = [(100 - c^2) / s + 10 PW + c t_off] / T, s = 1 V/us the slope, c = V R1 / (R1 + R2) the level
    of x while D1 blocks (for t_off = T - PW - 2 (10 - c) / s), solved by iteration: 3.0014994303 V. A triangle
    whose levels hold for less than 1 % of its period (100 ns of 50 us) is refused in one line: its ramp, pinned on
    its levels, would repeat from almost any offset."""
    from converters.circuits.netlist import NetlistError
    a, T, PW, slope, closed = 1e3 / 1.001e6, 50e-6, 5e-6, 1e6, 3.0
    for _ in range(50):
        c = closed * a
        closed = ((100 - c * c) / slope + 10 * PW + c * (T - PW - 2 * (10 - c) / slope)) / T
    path = tmp_path / "trapezoid.cir"
    path.write_text(TRIANGLE.replace("{tr}", "20u").replace("{pw}", "5u"))
    summary = run_summary(run_converter(str(path), {}, method=method, steady=True))
    assert summary["vout_mean"] == pytest.approx(closed, rel=1e-6)
    assert abs(summary["vout_mean"] / closed - 1) <= 3 * max(summary["accuracy"]["vout_mean_error_estimate"], 1e-8)
    path.write_text(TRIANGLE.replace("{tr}", "{25u-50n}").replace("{pw}", "100n"))
    with pytest.raises(NetlistError, match=r"trapezoid.cir:2: voltage source VS: its levels hold for 0.002 of its "
                                           r"period \(PW and PER - TR - PW - TF\); its ramp is pinned on the periodic "
                                           r"orbit by its levels, which must hold for at least 0.01 of it"):
        run_converter(str(path), {}, steady=True)


def test_a_network_singular_by_its_values_says_so_not_only_that_a_node_floats(tmp_path):
    """1 nohm beside 1e13 ohm resistors (a divider to node b): its matrix is singular in double precision and the
    refusal said only "node b has no path to ground", which is false (1e13 ohm leads there). It names the spread."""
    from converters.circuits.netlist import NetlistError
    path = tmp_path / "spread.cir"
    path.write_text("buck feeding a 1e13 ohm divider through 1 nohm\nVin in 0 DC 10\n"
                    "Vg g 0 PULSE(0 1 0 1n 1n {6u-2n} 10u)\nS1 in sw g 0 SWMOD\nD1 0 sw DMOD\nL1 sw out 100u\n"
                    "C1 out 0 10u\nR1 out 0 10\nRt out a 1e-9\nRx a b 1e13\nRy b 0 1e13\nRz a 0 1e13\n"
                    ".model SWMOD SW(VT=0.5)\n.model DMOD D\n.tran 10n 2m\n.end\n")
    with pytest.raises(NetlistError, match=r"or its values: the resistances span 1.0e\+22 \(RT 1e-09 ohm beside RZ "
                                           r"1e\+13 ohm\), beyond the 1e\+12 double precision resolves"):
        run_converter(str(path), {}, steady=True)
    path.write_text(path.read_text().replace("Rt out a 1e-9", "Rt out a 1e-3").replace(" 1e13", " 1e9"))
    run = run_converter(str(path), {}, method="event", steady=True, periods=1)
    assert run.mean("v(b)", t0=0.0, t1=1e-5) == pytest.approx(0.5 * run.mean("vout", t0=0.0, t1=1e-5), rel=1e-6)


def test_a_square_waves_two_levels_are_two_configurations_by_name_and_the_run_is_written(tmp_path):
    """The Cockcroft-Walton ladder has no switch: its configurations differ by its source's PULSE level alone and were
    both named "circuit", so `simulate --out` stopped on "Categorical categories must be unique"."""
    from validation.cli import main
    path = VOLTAGE_MODE.with_name("cockcroft-walton.cir")
    run = run_converter(str(path), {}, steady=True, periods=1)
    assert run.config_names == ("vs=v1", "vs=v2")
    assert set(run.to_pandas()["config"].cat.categories) == {"vs=v1", "vs=v2"}
    out = tmp_path / "cw.parquet"
    assert main(["simulate", str(path), "--steady", "--periods", "1", "--out", str(out)]) == 0 and out.stat().st_size


BUCK_FILE = VOLTAGE_MODE.with_name("buck.cir")
#: The buck's gate as a PULSE and as a repeated PWL with the same edges: falling around D T, rising over [T - e, T].
GATE = "Vg gate 0 PULSE(1 0 {D*T - e/2} {e} {e} {(1-D)*T - e} {T})"
GATE_PULSE = "Vg gate 0 PULSE(1 0 {D*T - e/2} {e} {e} {(1-D)*T - 3*e/2} {T})"
GATE_PWL = "Vg gate 0 PWL(0 1 {D*T - e/2} 1 {D*T + e/2} 0 {T - e} 0 {T} 1) r=0"


@pytest.mark.parametrize("D", ["0.4", "0.7"])
def test_a_repeated_pwl_gate_is_the_pulse_with_the_same_edges(D):
    """PWL(...) r=0 repeats its list with its last time as the period: as a gate its threshold crossings are found
    on the same piecewise-linear waveform as a PULSE's, so the schedules are equal to the last bit and so are the
    event method's orbits (DCM at D = 0.4, CCM at 0.7 with L = 100u)."""
    from converters.run import run_converter
    text = BUCK_FILE.read_text()
    assert GATE in text
    pulse = Circuit.from_netlist("pulse.cir", text=text.replace(GATE, GATE_PULSE))
    pwl = Circuit.from_netlist("pwl.cir", text=text.replace(GATE, GATE_PWL))
    params = {"D": D, "L": "100u"} if D == "0.7" else {"D": D}
    law_pulse, law_pwl = (c.compiled(c.resolve(params)).law for c in (pulse, pwl))
    assert law_pwl == law_pulse and law_pwl.period == 1e-5
    a = run_converter(pulse, params, method="event", steady=True, periods=1, steady_tol=1e-12)
    b = run_converter(pwl, params, method="event", steady=True, periods=1, steady_tol=1e-12)
    assert np.array_equal(a.x[0], b.x[0])


@pytest.mark.spice
def test_ngspice_runs_the_repeated_pwl_gate_and_agrees(tmp_path, capsys, ngspice):
    """The PWL is written back as PWL(...) r=0: compare passes on it."""
    import json

    from validation.cli import main
    path = tmp_path / "pwl-buck.cir"
    path.write_text(BUCK_FILE.read_text().replace(GATE, GATE_PWL))
    assert main(["compare", str(path), "--json"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert result["passed"] and result["metrics"]["v(out)_mean_rel_error"] < 1e-3


SERIES = """a boost whose output is two 100 uF in series: node fa is joined to the rest only through them
Vin in 0 DC 12
Vg g 0 PULSE(0 1 0 1n 1n 5u 10u)
L1 in sw 100u
S1 sw 0 g 0 SMOD
D1 sw out DIDEAL
C1 out fa 100u
C2 fa 0 100u
R1 out 0 50
{extra}
.model SMOD SW(VT=0.5)
.model DIDEAL D
.tran 10n 2m
.end
"""


@pytest.mark.parametrize("extra, islands", [
    ("", [(("fa",), ("C1", "C2"))]),
    ("R2 fa 0 1meg", []),                     # a path: the charge leaks
    ("I2 0 fa DC 1m", []),                    # a driven charge, not a conserved one
    ("S2 fa 0 g 0 SMOD", []),                 # a switch that may close joins the node
])
def test_a_node_joined_to_the_rest_only_through_capacitors_conserves_its_charge(extra, islands):
    from converters.circuits.compile import charge_islands
    from converters.circuits.netlist import read_netlist
    assert charge_islands(read_netlist(SERIES.format(extra=extra), name="series.cir")) == islands


def test_capacitors_in_series_across_a_boosts_output_reach_its_steady_state_as_their_series_capacitance(tmp_path):
    """C1 and C2 (100 uF each) in series beside Co, a loop of capacitors: refused before. Their midpoint's charge is
    held where the run starts (0, from rest: v(c1) = v(c2)) and the loop ties v(c1) + v(c2) = v(co), so the circuit
    is Co with 50 uF beside it: the same orbit, mean and ripple as that circuit's, exactly (the event method), and
    to the stepper's own accuracy; no multiplier at 1 (the slowest is R (Co + C1 C2 / (C1 + C2))'s)."""
    series = tmp_path / "series.cir"
    series.write_text(SERIES.format(extra="Co out 0 100u"))
    single = tmp_path / "single.cir"
    single.write_text(SERIES.format(extra="Co out 0 150u").replace("C1 out fa 100u\n", "").replace("C2 fa 0 100u\n", ""))
    for method, rel in (("event", 1e-11), ("lcp", 1e-7)):
        a = run_summary(run_converter(Circuit.from_netlist(series), method=method, steady=True))
        b = run_summary(run_converter(Circuit.from_netlist(single), method=method, steady=True))
        assert a["vout_mean"] == pytest.approx(b["vout_mean"], rel=rel)
        m = a["measurements"]
        assert m["v(c1)"]["mean"] == pytest.approx(m["v(c2)"]["mean"], rel=1e-9)
        assert m["v(c1)"]["mean"] + m["v(c2)"]["mean"] == pytest.approx(m["v(co)"]["mean"], rel=1e-9)
        assert a["orbit"]["spectral_radius"] == pytest.approx(b["orbit"]["spectral_radius"], abs=1e-9)


SPLIT = """two capacitors in series across a source{title}
V1 a 0 DC 10
C1 a m 1u
C2 m 0 3u
{extra}
.tran 1u 20m
.end
"""


@pytest.mark.parametrize("method, tol", [("event", 1e-12), ("lcp", 1e-6)])
def test_capacitors_in_series_across_a_source_share_its_voltage_by_charge_and_decay_through_a_resistor(tmp_path,
                                                                                                     method, tol):
    """V1 = 10 V across C1 = 1 uF and C2 = 3 uF in series, from rest: the start moves the charge as closing the loop
    would (q = C1 v1 = C2 v2, v1 + v2 = 10: 7.5 V and 2.5 V); the midpoint then holds 2.5 V, and with R2 = 1 kohm
    across C2 it decays as 2.5 e^(-t / (R2 (C1 + C2))) (tau = 4 ms) while C1 takes the whole 10 V."""
    t = np.array([0.0, 1e-3, 4e-3, 1e-2, 2e-2])
    for extra, expected in (("", 2.5 * np.ones(t.size)), ("R2 m 0 1k", 2.5 * np.exp(-t / 4e-3))):
        path = tmp_path / "split.cir"
        path.write_text(SPLIT.format(title=", " + extra if extra else "", extra=extra))
        model = Circuit.from_netlist(path)
        np.testing.assert_allclose(model.compiled(model.resolve({})).x0, [7.5, 2.5], rtol=1e-15)
        tr = run_converter(model, method=method)
        vm = np.interp(t, tr.t, tr.signal("v(m)"))
        np.testing.assert_allclose(vm, expected, rtol=tol, atol=tol * 2.5)
        np.testing.assert_allclose(np.interp(t, tr.t, tr.signal("v(c1)")) + vm, 10.0, rtol=1e-12)


@pytest.mark.parametrize("method, tol", [("event", 1e-12), ("lcp", 1e-5)])
def test_capacitors_in_parallel_and_across_a_source_are_the_circuit_spice_solves(tmp_path, method, tol):
    """Refused before as loops of capacitors (and sources): C1 and C2 in parallel charge through R1 as one 2 uF,
    v = 12 (1 - e^(-t / 20 us)), each at the same voltage; C3 across the 12 V source holds 12 V and changes
    nothing else."""
    path = tmp_path / "parallel.cir"
    path.write_text("RC with two capacitors in parallel and one across the source\nVin in 0 DC 12\nR1 in out 10\n"
                    "C1 out 0 1u\nC2 out 0 1u\nC3 in 0 1u\n.tran 0.1u 100u\n.end\n")
    tr = run_converter(Circuit.from_netlist(path), method=method)
    t = np.linspace(0.0, 1e-4, 11)
    expected = 12.0 * (1.0 - np.exp(-t / 2e-5))
    for name in ("v(c1)", "v(c2)"):
        np.testing.assert_allclose(np.interp(t, tr.t, tr.signal(name)), expected, rtol=tol, atol=12 * tol)
    np.testing.assert_allclose(tr.signal("v(c3)"), 12.0, rtol=1e-13)
    np.testing.assert_allclose(tr.signal("i(c1)"), tr.signal("i(c2)"), rtol=1e-9, atol=1e-12)


def test_the_charge_a_node_keeps_is_the_one_its_ic_gives(tmp_path):
    """Two 100 uF in series across the boost's output, .ic v(fa) = 3 V from rest elsewhere: the midpoint's charge
    q = C2 v2 - C1 v1 = 100u (3 + 3) = 6e-4 C is kept, so on the orbit v2 - v1 = 6 V and v1 + v2 = vout."""
    path = tmp_path / "series.cir"
    path.write_text(SERIES.format(extra=".ic v(fa)=3"))
    summary = run_summary(run_converter(Circuit.from_netlist(path), method="event", steady=True))
    m = summary["measurements"]
    assert m["v(c2)"]["mean"] - m["v(c1)"]["mean"] == pytest.approx(6.0, rel=1e-9)
    assert m["v(c1)"]["mean"] + m["v(c2)"]["mean"] == pytest.approx(summary["vout_mean"], rel=1e-12)


def test_what_a_circuit_holds_is_reported_and_an_ic_that_contradicts_it_is_said(tmp_path):
    """The summary lists each loop's and cutset's constraint and each charge island's charge, with its value: V1 =
    10 V across C1 and C2 in series holds v(c1) + v(c2) = 10 V and their midpoint's charge (0 from rest); the boost's series pair with .ic v(fa) = 3 V holds
    the midpoint's charge C2 v2 - C1 v1 = 6e-4 C. An .ic giving 4 V and 4 V on the first contradicts its loop: the
    run starts from 5.5 V and 4.5 V (the loop's 2 V shortfall made up by one charge through both, 1.5 uC: the
    midpoint keeps its 8 uC) and a warning says so; from rest, none."""
    path = tmp_path / "split.cir"
    path.write_text(SPLIT.format(title="", extra=""))
    summary = run_summary(run_converter(Circuit.from_netlist(path), method="event", t_end=1e-3))
    assert summary["invariants"] == [
        {"kind": "loop", "constraint": "v(c1) + v(c2)", "value": pytest.approx(10.0), "unit": "V"},
        {"kind": "charge", "constraint": "-1e-06 v(c1) + 3e-06 v(c2)", "value": 0.0, "unit": "C"}]
    assert "warnings" not in summary
    path.write_text(SPLIT.format(title="", extra=".ic v(a)=8 v(m)=4"))
    tr = run_converter(Circuit.from_netlist(path), method="event", t_end=1e-3)
    np.testing.assert_allclose(tr.x[0], [5.5, 4.5], rtol=1e-14)
    (warning,) = run_summary(tr)["warnings"]
    assert warning.startswith("the initial conditions contradict what the circuit holds (v(c1) + v(c2) = 10 V): the "
                              "run starts from v(c1) = 5.5 (not 4), v(c2) = 4.5 (not 4)")
    series = tmp_path / "series.cir"
    series.write_text(SERIES.format(extra=".ic v(fa)=3"))
    (held,) = run_summary(run_converter(Circuit.from_netlist(series), method="event", t_end=1e-4))["invariants"]
    assert held["kind"] == "charge" and held["unit"] == "C" and held["value"] == pytest.approx(6e-4, rel=1e-12)


SAWTOOTH = """buck: a DC level against a 0..1 sawtooth delayed by td T, the switch closed while {closed}
.param Vin=12 L=4.7u C=100u R=0.5 f=500k Vc={vc} td={td}
.param T={{1/f}} e={{1e-6/f}}
Vin in 0 DC {{Vin}}
Vc c 0 DC {{Vc}}
Vr r 0 PULSE(0 1 {{td*T}} {{T-2*e}} {{e}} {{e}} {{T}})
S2 in x {control} SWMOD
D2 0 x DMOD
L2 x out {{L}}
Co out 0 {{C}}
Rload out 0 {{R}}
.model SWMOD SW(VT=0)
.model DMOD D
.tran 2n 1m
.end
"""


@pytest.mark.parametrize("td", [0.0, 0.25, 1 / 3, 0.5, 0.6, 0.75])
@pytest.mark.parametrize("below, vc", [(True, 0.4), (True, 0.2), (False, 0.3)])
@pytest.mark.parametrize("method", ["event", "lcp"])
def test_a_comparator_against_a_delayed_sawtooth_closes_for_its_level_whatever_the_delay(td, below, vc, method):
    """The ramp (0 to 1 over T - 2e, back in e) is below Vc for Vc (T - 2e) of each period, whatever its delay: the
    duty is Vc closed while the ramp is below it, 1 - Vc while above (to 2e-6, its edges), and vout D Vin in CCM.
    The schedule's crossings were sought on the corners of [0, 2 T], and a ramp still rising at 2 T (td = T/3:
    restarted at 4T/3) lost its last segment with its crossing: 0.667 read for 0.4 (vout 8.0 V for 4.8 V), 0.25
    for 0.7 closed above."""
    control = "c r" if below else "r c"
    text = SAWTOOTH.format(vc=vc, td=td, closed="the ramp is below Vc" if below else "above", control=control)
    circuit = Circuit.from_netlist("saw.cir", text=text)
    fractions = run_summary(run_converter(circuit, {}, steady=True, method=method))["mode_fractions"]
    duty = vc if below else 1 - vc
    assert fractions["S2"] == pytest.approx(duty, abs=3e-6)


def _dickson(stages: int) -> str:
    lines = ["Dickson charge pump, two-phase square clocks, 10 ohm in every diode",
             ".param T=10u e=1e-11", "Vin in 0 DC 5", "Vp1 ck1 0 PULSE(0 5 0 {e} {e} {T/2-e} {T})",
             "Vp2 ck2 0 PULSE(5 0 0 {e} {e} {T/2-e} {T})", "D0 in n1 DMOD"]
    for i in range(1, stages + 1):
        lines += [f"C{i} n{i} ck{2 - i % 2} 100n", f"D{i} n{i} n{i + 1} DMOD"]
    lines += [f"Co n{stages + 1} 0 1u", f"Rl n{stages + 1} 0 1meg", ".model DMOD D(RS=10)", ".tran 10n 1m", ".end"]
    return "\n".join(lines) + "\n"


@pytest.mark.parametrize("stages", [12, 16, 48])
def test_the_event_method_finds_a_dickson_pumps_mode_inside_a_clock_edge(stages):
    """Through a clock's 10 ps edge the sources move 5e11 V/s, far faster than the ladder's own rates (RS C = 1 us):
    the mode-selection LCP's step (1e-3 of the fastest time constant, 1 ns) looked 100 edges ahead and chose the
    diodes the edge's end makes conduct, which the exact test refuses at its start ("did not find the mode at
    t = 5e-12 s" from 12 stages on). Solved again at shorter steps, it finds the instant's mode. The orbit is the
    ideal charge transfer's (Vin + N Vck) / (1 + N / (f C Rl)) less RS's incomplete transfer (3e-6 .. 4e-6)."""
    circuit = Circuit.from_netlist(f"dickson{stages}.cir", text=_dickson(stages))
    vout = run_converter(circuit, {}, steady=True, method="event", periods=1).mean(f"v(n{stages + 1})")
    ideal = (5 + stages * 5) / (1 + stages / (1e5 * 100e-9 * 1e6))
    assert 0 < ideal - vout < 1e-5 * ideal


def test_an_event_method_that_does_not_find_a_mode_past_its_enumeration_says_so_not_that_the_circuit_is_ill_posed(
        monkeypatch):
    """Past 12 pairs the event method tries only the mode-selection LCP's held sets (at its step and shorter ones)
    and their neighbours; a 16-stage Dickson pump (17 diodes, 10 ohm in each: unique at every instant) where they
    failed was refused as "the LCS is not well posed there". Without the shorter steps it fails there again: the
    refusal names the method's limit and the remedy (the stepper runs it)."""
    from converters.errors import SimulationError
    from converters.methods.event import machine
    monkeypatch.setattr(machine, "SELECT_REFINEMENTS", 0)
    circuit = Circuit.from_netlist("dickson16.cir", text=_dickson(16))
    with pytest.raises(SimulationError) as refused:
        run_converter(circuit, {}, steady=True, method="event")
    message = str(refused.value)
    assert "not well posed" not in message and "with 17 pairs" in message and message.endswith("use --method lcp")


def test_a_resistor_between_two_nodes_of_its_own_is_a_floating_node_not_an_interrupted_current(tmp_path):
    """Rf joins fa and fb to each other and to nothing else: the refusal had blamed "inductors and current sources
    (with s1=open)", neither of which is the cause."""
    from converters.circuits import NetlistError
    path = tmp_path / "island.cir"
    path.write_text("buck with a resistor of its own\nVin in 0 DC 12\nVg g 0 PULSE(1 0 4u 1n 1n 6u 10u)\n"
                    "S1 in sw g 0 SWMOD\nD1 0 sw DMOD\nL1 sw out 10u\nC1 out 0 100u\nR1 out 0 5\nRf fa fb 1k\n"
                    ".model SWMOD SW(VT=0.5)\n.model DMOD D\n.tran 10n 1m\n.end\n")
    with pytest.raises(NetlistError) as refused:
        Circuit.from_netlist(path)
    assert str(refused.value) == (f"{path}: nodes fa, fb have no path to ground through any element (RF connect "
                                  "only among them): a floating node; tie it to the circuit (SPICE needs a path to "
                                  "ground too)")


PARALLEL_L = """buck whose inductor is two in parallel{coupled}
Vin in 0 DC 12
Vg g 0 PULSE(1 0 4u 1n 1n 6u 10u)
S1 in sw g 0 SWMOD
D1 0 sw DMOD
L1 sw out 10u
L2 sw out 22u
{k}C1 out 0 100u
R1 out 0 5
.model SWMOD SW(VT=0.5)
.model DMOD D
.tran 10n 1m
.end
"""


@pytest.mark.parametrize("k", [0.0, 0.5])
@pytest.mark.parametrize("method", ["event", "lcp"])
def test_inductors_in_parallel_hold_their_loops_flux_and_are_the_buck_of_their_equivalent(method, k):
    """Two inductors in parallel make a loop of inductors alone: its flux sign^T M i (L1 i1 + M i2 - M i1 - L2 i2)
    is conserved, and without a hold every start had an orbit of its own (Newton stopped at "1 - rho = 8.6e-14
    amplifies" its rounding). Held at its start (0 from rest), the pair is one inductor of (L1 L2 - M^2) /
    (L1 + L2 - 2 M): the buck's orbit with it (the gate closes S1 for 0.3999 T), and the currents split so that
    the loop's flux is 0."""
    from converters.run import run_converter, run_summary
    M = k * (10e-6 * 22e-6) ** 0.5
    text = PARALLEL_L.format(coupled=f", coupled {k}" if k else "", k=f"K1 L1 L2 {k}\n" if k else "")
    circuit = Circuit.from_netlist("parallel.cir", text=text)
    summary = run_summary(run_converter(circuit, {}, steady=True, method=method))
    equivalent = (10e-6 * 22e-6 - M * M) / (10e-6 + 22e-6 - 2 * M)
    alone = run_summary(run_converter("buck", {"L": equivalent, "R": 5.0, "D": 0.3999}, steady=True,
                                      method="event"))
    assert summary["vout_mean"] == pytest.approx(alone["vout_mean"], rel=1e-8 if method == "event" else 1e-4)
    (held,) = summary["invariants"]
    assert held["kind"] == "flux" and held["value"] == 0.0 and held["unit"] == "Wb"
    i1, i2 = (summary["measurements"][f"i(l{j})"]["mean"] for j in (1, 2))
    assert (22e-6 - M) * i2 == pytest.approx((10e-6 - M) * i1, rel=1e-8)      # L1 i1 + M i2 = M i1 + L2 i2


@pytest.mark.parametrize("gate", ["PULSE 1 0 4u 1n 1n 6u 10u", "PULSE(1 0 4u 1n 1n 6u 10u)",
                                  "pulse  1 0 4u 1n 1n 6u 10u"])
def test_a_waveform_without_parentheses_is_read_as_spice_reads_it(gate):
    """ngspice takes PULSE 1 0 ... without parentheses; it had been refused as "PULSE ... is not read (DC, PULSE,
    SIN, PWL)", a list that names it. Read, it is the same source: the same orbit to rounding."""
    text = (f"buck\nVin in 0 DC 12\nVg g 0 {gate}\nS1 in sw g 0 SWMOD\nD1 0 sw DMOD\nL1 sw out 10u\nC1 out 0 100u\n"
            "R1 out 0 10\n.model SWMOD SW(VT=0.5)\n.model DMOD D\n.tran 10n 1m\n.end\n")
    circuit = Circuit.from_netlist("gate.cir", text=text)
    reference = Circuit.from_netlist("gate.cir", text=text.replace(gate, "PULSE(1 0 4u 1n 1n 6u 10u)"))
    mean = run_summary(run_converter(circuit, {}, steady=True, method="event"))["vout_mean"]
    assert mean == run_summary(run_converter(reference, {}, steady=True, method="event"))["vout_mean"]


def test_diodes_in_parallel_through_closed_switches_name_the_configuration_that_joins_them():
    """An interleaved boost with ideal diodes: where both phases' switches are closed (its gates overlap), the two
    diodes meet at ground and are in parallel to the output. The refusal had named only the diodes, which are not
    in parallel in the file; it names the switches that join them."""
    from converters.circuits import NetlistError
    text = """Two-phase interleaved boost, the gates overlapping
Vin in 0 DC 5
Vg1 g1 0 PULSE(1 0 4.5u 1p 1p 0.5u 5u)
Vg2 g2 0 PULSE(1 0 2u 1p 1p 0.5u 5u)
L1 in sw1 22u
L2 in sw2 22u
S1 sw1 0 g1 0 SWMOD
S2 sw2 0 g2 0 SWMOD
D1 sw1 out DMOD
D2 sw2 out DMOD
C1 out 0 47u
R1 out 0 200
.model SWMOD SW(VT=0.5)
.model DMOD D
.tran 5n 1m
.end
"""
    with pytest.raises(NetlistError) as refused:
        Circuit.from_netlist("boost2.cir", text=text)
    assert "diode D2 and diode D1 are ideal diodes in parallel where S1, S2 are closed" in str(refused.value)


FOUR_PHASE_BUCK = """Four-phase interleaved buck: comparators against sawtooth carriers delayed by 0, T/4, T/2, 3T/4
.param Vin=24 L=22u RL=50u C=220u R=0.4 f_sw=250k Vc=0.3
.param T={1/f_sw} e={1e-6/f_sw}
Vin in 0 DC {Vin}
Vc c 0 DC {Vc}
Vr1 r1 0 PULSE(0 1 0 {T-2*e} {e} {e} {T})
Vr2 r2 0 PULSE(0 1 {T/4} {T-2*e} {e} {e} {T})
Vr3 r3 0 PULSE(0 1 {T/2} {T-2*e} {e} {e} {T})
Vr4 r4 0 PULSE(0 1 {3*T/4} {T-2*e} {e} {e} {T})
S1 in x1 c r1 SWMOD
S2 in x2 c r2 SWMOD
S3 in x3 c r3 SWMOD
S4 in x4 c r4 SWMOD
D1 0 x1 DMOD
D2 0 x2 DMOD
D3 0 x3 DMOD
D4 0 x4 DMOD
RL1 x1 y1 {RL}
RL2 x2 y2 {RL}
RL3 x3 y3 {RL}
RL4 x4 y4 {RL}
L1 y1 out {L}
L2 y2 out {L}
L3 y3 out {L}
L4 y4 out {L}
C1 out 0 {C}
R1 out 0 {R}
.model SWMOD SW(VT=0)
.model DMOD D
.tran {T/1000} {500*T}
.end
"""


@pytest.mark.parametrize("method", ["lcp", "event"])
def test_an_interleaved_bucks_phases_share_the_load_equally_with_a_retrace_a_picosecond_before_the_period_ends(
        method):
    """Phase 1's carrier retraces 1.2 ps (3e-7 T) before T, where its switch turns on. The stepper's period map had
    dropped that last sliver of the period (its grid ended at the last point h/1000 short of T), so phase 1 lost
    3e-7 T of on-time each period; with 50 uohm in each inductor the phases' currents split by (Vin dD) / RL: phase
    1's read 4.3919 A for 4.4999 (-2.4 %) with an estimate of 1e-10. The phases are alike up to their delay, so each
    carries vout / (4 R), and vout = D Vin / (1 + RL / (4 R)) with D = 0.3 (1 - 1e-6)."""
    circuit = Circuit.from_netlist("ilv4.cir", text=FOUR_PHASE_BUCK)
    tr = run_converter(circuit, {}, steady=True, method=method, periods=1)
    vout = 0.3 * (1 - 1e-6) * 24 / (1 + 50e-6 / 1.6)
    assert tr.mean("v(out)") == pytest.approx(vout, rel=1e-7)
    for k in range(1, 5):
        assert tr.mean(f"i(l{k})") == pytest.approx(vout / 1.6, rel=1e-6), k


def test_a_netlist_without_an_output_takes_the_first_node_no_source_holds_not_its_dc_link():
    """No .meas and no node `out`: the output had been the first node, the DC link v(p) that Vdc holds at 200 V,
    which compare then matched against ngspice's 200 V and passed. It is now the first node no voltage source holds
    to ground: the split link's midpoint, at (D + td / T) Vdc = 74 V on the orbit (the load's mean voltage is 0 and
    the leg's node a spends D + td / T of the period at Vdc, S2 and D2 the rest at 0)."""
    text = """Half-bridge inverter, unequal split DC link 100u/330u, dead time, RL load to the midpoint
.param Vdc=200 Ca=100u Cb=330u L=2m R=8 f=20k D=0.35 td=1u
.param T={1/f} e={1e-6/f}
Vdc p 0 DC {Vdc}
C1 p m {Ca}
C2 m 0 {Cb}
Vg1 g1 0 PULSE(0 1 0 {e} {e} {D*T - e} {T})
Vg2 g2 0 PULSE(0 1 {D*T + td} {e} {e} {(1-D)*T - 2*td - e} {T})
S1 p a g1 0 SWMOD
S2 a 0 g2 0 SWMOD
D1 a p DMOD
D2 0 a DMOD
Rl a b {R}
Ll b m {L}
.model SWMOD SW(VT=0.5)
.model DMOD D
.tran {T/1000} {500*T}
.end
"""
    circuit = Circuit.from_netlist("hb.cir", text=text)
    assert circuit.output == "v(m)"
    summary = run_summary(run_converter(circuit, {}, steady=True, method="event"))
    assert summary["vout_mean"] == pytest.approx((0.35 + 1e-6 * 20e3) * 200, rel=1e-6)


def test_a_combination_of_comparators_with_no_configuration_says_why_when_a_run_reaches_it():
    """Two hysteretic phases whose second switch, closed with the first, shorts the source: the compiler leaves that
    combination without a configuration, and a run that got there had stopped with "no configuration for (w1
    closed, w2 closed)" alone. The compiler's reason now follows."""
    from converters.errors import SimulationError
    text = (Path(__file__).parents[2] / "netlists" / "circuits" / "two-phase-hysteretic-buck.cir").read_text()
    model = Circuit.from_netlist("short.cir", text=text.replace("W2 in sw2 Vs2 WMOD", "W2 sw1 0 Vs2 WMOD"))
    law = model.problem(model.resolve({}), 1e-3).switching
    with pytest.raises(SimulationError) as stopped:
        law.config(0, 0.0)                      # both channels below: both switches closed
    assert str(stopped.value) == (
        "at t = 0 s the comparators reach a combination of states the system has no configuration for (w1 closed, "
        "w2 closed): VIN, W1, W2 form a loop of voltage sources and closed switches (with w1=closed, w2=closed): "
        "their voltages are not independent")


def test_diodes_a_shorted_capacitance_ties_to_the_source_are_blocked_by_it_alone():
    """Two hysteretic phases with 2 nF across each switch. With both switches closed each Coss is shorted (the state
    jumps onto v(co) = 0 entering the configuration) and both diodes' cathodes sit at Vin: they are blocked by the
    source alone once the state has jumped, but their rows still read the Coss voltages, and the configuration was
    refused as "diodes in parallel where W1, W2 are closed": a run from rest stopped at t = 0, where both phases'
    comparators close. Each closing then redistributes 1/2 Coss Vin^2 (the diode conducts: the switch node at 0,
    Coss at Vin), exactly, in the event method's run from rest."""
    text = (Path(__file__).parents[2] / "netlists" / "circuits" / "two-phase-hysteretic-buck.cir").read_text()
    model = Circuit.from_netlist("coss.cir", text=text.replace("R1 out 0 {R}", "R1 out 0 {R}\nCo1 in sw1 2n\n"
                                                                             "Co2 in sw2 2n"))
    law = model.problem(model.resolve({}), 1e-3).switching
    assert -1 not in law.table
    tr = run_converter(model, t_end=1e-4, method="event")
    count, lost = tr.jump_losses(t0=0.0, t1=1e-4)
    assert count > 10
    assert lost == pytest.approx(count * 0.5 * 2e-9 * 12.0 ** 2, rel=1e-9)


def test_the_defaults_answer_with_the_exact_method_where_the_stepper_does_not_take_the_circuit():
    """Comparator phases with a capacitance across each switch: the stepper does not locate a jump inside its step,
    and the defaults had refused ("use --method event"). Without a method, step or option asked for, the exact
    method runs and a warning says why; a stepper asked for still refuses."""
    from converters.errors import ParameterError
    text = (Path(__file__).parents[2] / "netlists" / "circuits" / "two-phase-hysteretic-buck.cir").read_text()
    model = Circuit.from_netlist("coss.cir", text=text.replace("R1 out 0 {R}", "R1 out 0 {R}\nCo1 in sw1 2n\n"
                                                                             "Co2 in sw2 2n"))
    tr = run_converter(model, t_end=1e-4)
    assert tr.algorithm.exact
    count, lost = tr.jump_losses(t0=0.0, t1=1e-4)            # each closing: 1/2 Coss Vin^2 (the diode conducts)
    assert count > 10 and lost == pytest.approx(count * 0.5 * 2e-9 * 12.0 ** 2, rel=1e-9)
    (warning,) = [w for w in tr.metadata["warnings"] if w.startswith("the stepper does not take this circuit")]
    assert "is not stepped yet" in warning and warning.endswith("the exact (event) method's run is given")
    with pytest.raises(ParameterError, match="use --method event"):
        run_converter(model, t_end=1e-4, method="lcp")


@pytest.mark.parametrize("retrace, said", [("T/2", None), ("{1e-3*T}", "0.0005"), ("{2e-6*T}", "1e-06"),
                                           ("{2e-8*T}", None)])
def test_a_comparators_ramp_must_rise_over_its_period_and_a_slow_retrace_is_said(retrace, said):
    """The shipped voltage-mode buck with its ramp PULSE(VL VU 0 TR e e T): rising over half the period and resting
    at VL for the other half, it had been read as the sawtooth over the whole period (the loop gain 4.9 dB high,
    its mean 2.1 % off against an exact computation of the literal ramp): refused, naming the rise. A ramp whose
    fall (TF = e) is taken at its middle, a switching there moved by up to TF / 2 and its sawtooth past V2 for PW +
    TF / 2 = 1.5 e, says so with every run from 2e-8 of the period; the shipped one's (e = 1e-8 T) does not."""
    from converters.circuits.netlist import NetlistError
    text = (Path(__file__).parents[2] / "netlists" / "circuits" / "voltage-mode-buck.cir").read_text()
    if retrace == "T/2":
        text = text.replace("PULSE({VL} {VU} 0 {T - 2*e} {e} {e} {T})", "PULSE({VL} {VU} 0 {T/2} {e} {e} {T})")
    else:
        text = text.replace(".param e={1e-8*T}", f".param e={{{retrace[1:-1]}/2}}")
    if said is None and retrace == "T/2":
        with pytest.raises(NetlistError, match=r"VRAMP: in voltage-controlled switch S1's control a PULSE must be "
                                               r"one sawtooth ramp: .*rising over TR.*\(got TR = 0\.0002 s, "
                                               r"PER = 0\.0004 s\)"):
            Circuit.from_netlist("ramp.cir", text=text)
        return
    model = Circuit.from_netlist("ramp.cir", text=text)
    notes = model.compiled(model.resolve({})).notes
    if said is None:
        assert notes == ()
    else:
        (note,) = notes
        assert note.startswith(f"voltage source VRAMP's ramp is taken as a sawtooth with its slope, reset at the "
                               f"middle of its fall (TF = {said} of its period): in voltage-controlled switch S1's "
                               "comparator a switching as the ramp falls moves by up to")


@pytest.mark.slow
@pytest.mark.parametrize("vref", [0.3, 5.0])
def test_a_comparators_switching_inside_a_step_is_read_at_its_instant(vref):
    """The voltage-loop buck (a type III loop as E, R, C and a PWM comparator) at Vref = 0.3 V, D = 0.025, and at
    its 5 V: the stepper places each crossing inside its step but kept its samples on the grid, so its means read
    the whole step in the new configuration and the duty ratio in whole steps. The switch node's mean read 0.28800 V
    (24 steps of T/1000) where an ideal inductor's orbit makes it vout's, 0.2999998; the input power 5.9 % low, the
    input current's peak 2.6 % low; every estimate ~0 (h and 2h quantize alike). Each crossing is now a sample:
    v(sw) = vout to 1e-7, Vin i(vin) = vout^2 / R to 1e-6 (lossless), the peak the exact method's to 1e-6."""
    from converters.run import run_converter, run_summary
    path = VOLTAGE_MODE.with_name("voltage-loop-buck.cir")
    summary = run_summary(run_converter(str(path), {"Vref": vref}, steady=True))
    exact = run_summary(run_converter(str(path), {"Vref": vref}, steady=True, method="event"))
    assert summary["method"] == "lcp" and "warnings" not in summary
    m, e = summary["measurements"], exact["measurements"]
    assert m["v(sw)"]["mean"] == pytest.approx(summary["vout_mean"], rel=1e-7)
    assert 12.0 * -m["i(vin)"]["mean"] == pytest.approx(m["vout"]["rms"] ** 2 / 10.0, rel=1e-6)
    assert m["i(vin)"]["min"] == pytest.approx(e["i(vin)"]["min"], rel=1e-6)
    assert m["i(vin)"]["mean"] == pytest.approx(e["i(vin)"]["mean"], rel=1e-6)


@pytest.mark.parametrize("pulse, vref, literal", [("PULSE(3.8 8.2 0 {0.999*T} {1e-9*T} {0.000999*T} {T})", -8202, 0.0),
                                                  ("PULSE(3.8 8.2 0 {0.999*T} {1e-9*T} {1e-9*T} {T})", -3774, 24.0)])
def test_a_sawtooth_past_its_pulses_ends_is_said(pulse, vref, literal):
    """A ramp PULSE that holds V2 for 1e-3 of its period (PW), or rests at V1 for it, falling in 1e-9 of it: the
    sawtooth with the PULSE's slope runs on past V2 through the width, or below V1 through the rest, and a control
    2 mV beyond V2 (or V1) switches where the literal PULSE never does (vout 0.0130 V where S1 never closes, 23.987
    V where it never opens: an exact computation of the literal PULSE gives 0 and 24 V). Keyed on the fall alone,
    no note had said so; it now names the band, 4.4 mV above V2 or below V1."""
    from converters.run import run_converter, run_summary
    text = VOLTAGE_MODE.read_text()
    text = text.replace("PULSE({VL} {VU} 0 {T - 2*e} {e} {e} {T})", pulse).replace("A=8.4", "A=0.001")
    summary = run_summary(run_converter(Circuit.from_netlist("band.cir", text=text), {"Vref": vref}, steady=True,
                                        method="event"))
    assert abs(summary["vout_mean"] - literal) > 1e-2                # the sawtooth's number, not the PULSE's
    (note,) = [w for w in summary["warnings"] if "VRAMP's ramp is taken as a sawtooth" in w]
    band = "beyond V2 by less than 0.0044 V" if literal == 0.0 else "beyond V1 by less than 0.0044 V"
    assert band in note and "switches where the PULSE does not" in note


def test_a_resistance_too_high_to_resolve_is_named_as_a_path_not_as_an_open_element(tmp_path):
    """A 1 TOhm resistor (1e-12 S, at the rank tolerance beside the MNA's unit entries) is the only path of a node
    behind a 1 fH inductor: the refusal named it among "open switches, inductors or current sources". It names the
    resistor as the path, its conductance and the scale it is compared with."""
    from converters.circuits.netlist import NetlistError
    path = tmp_path / "tiny.cir"
    path.write_text("buck with a tera-ohm tail\nVin in 0 DC 12\nVg g 0 PULSE(0 1 0 10n 10n 4u 10u)\n"
                    "S1 in sw g 0 SWMOD\nD1 0 sw DMOD\nL1 sw out 10u\nLp out o2 1f\nRt o2 0 1t\nC1 out 0 100u\n"
                    "R1 out 0 10\n.model SWMOD SW(VT=0.5)\n.model DMOD D\n.tran 10n 1m\n.end\n")
    with pytest.raises(NetlistError) as refused:
        run_converter(str(path), {}, steady=True)
    said = str(refused.value)
    assert "node o2 reaches ground (with s1=open) only through RT (1e+12 ohm: 1e-12 S) beside LP" in said
    assert "at or below 1e-12 of the network's scale (1 S)" in said and "open switches" not in said
