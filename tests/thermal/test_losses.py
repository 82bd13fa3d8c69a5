"""A buck's device losses from its tables against the hand calculation from the same tables: P_cond = R_on I_rms^2
+ V_0 I_avg for a drop linear in the current, P_sw = f (E_on + E_off) at the orbit's commutations."""
import numpy as np
import pytest

from converters.errors import ParameterError
from converters.models import get_model
from converters.run import run_converter
from converters.thermal import DeviceDescription, ThermalChain, energy_table, on_state_table
from converters.thermal.losses import device_losses

TEMPERATURES = [25.0, 125.0]
# on-state drops linear in the current at each temperature: V_0 + R_on i
SWITCH_DROP = {25.0: (0.10, 0.050), 125.0: (0.14, 0.080)}
DIODE_DROP = {25.0: (0.70, 0.020), 125.0: (0.60, 0.030)}
# switching energies bilinear in V and I: k V I (J), k per temperature
K_ON, K_OFF, K_RR = {25.0: 2e-8, 125.0: 3e-8}, {25.0: 1e-8, 125.0: 1.5e-8}, {25.0: 4e-9, 125.0: 7e-9}


def _drop_table(drops):
    current = [0.0, 30.0]
    return on_state_table("drop", current, TEMPERATURES, [[v0 + r * i for i in current] for v0, r in
                                                          (drops[t] for t in TEMPERATURES)])


def _energy(k):
    voltage, current = [0.0, 24.0], [0.0, 30.0]
    return energy_table("E", voltage, current, TEMPERATURES,
                        [[[k[t] * v * i for i in current] for v in voltage] for t in TEMPERATURES])


def _at(pairs, tj):
    """A quantity linear in the temperature between the two tabulated ones (what the tables interpolate)."""
    w = (tj - 25.0) / 100.0
    return tuple((1 - w) * a + w * b for a, b in zip(pairs[25.0], pairs[125.0]))


DESCRIPTIONS = {
    "s1": DeviceDescription("Q1", "MOSFET", _energy(K_ON), _energy(K_OFF), _drop_table(SWITCH_DROP),
                            ThermalChain("foster", (0.5,), (1e-3,))),
    "d1": DeviceDescription("D1", "Diode", None, _energy(K_RR), _drop_table(DIODE_DROP)),
}


@pytest.mark.parametrize("method", ["event", "lcp"])
def test_a_ccm_bucks_losses_are_the_hand_calculation_from_the_same_tables(method):
    model = get_model("netlists/circuits/buck.cir")
    p = model.resolve({"L": "100u"})                        # CCM: both commutations at a nonzero current
    tr = run_converter(model, p, steady=True, method=method, periods=2)
    T = model.period(p)
    t1 = float(tr.t[-1])
    t0 = t1 - T
    tj = {"s1": 80.0, "d1": 60.0}
    losses = device_losses(model, p, tr, DESCRIPTIONS, tj, t0, t1)
    v0, r = _at({t: SWITCH_DROP[t] for t in TEMPERATURES}, 80.0)
    hand = r * tr.rms("i(s1)", t0=t0, t1=t1) ** 2 + v0 * tr.mean("i(s1)", t0=t0, t1=t1)
    assert losses["s1"].conduction_W == pytest.approx(hand, rel=1e-9)
    v0, r = _at({t: DIODE_DROP[t] for t in TEMPERATURES}, 60.0)
    hand = r * tr.rms("i(d1)", t0=t0, t1=t1) ** 2 + v0 * tr.mean("i(d1)", t0=t0, t1=t1)
    assert losses["d1"].conduction_W == pytest.approx(hand, rel=1e-9)
    # the commutations: the switch turns on at the period's start at the inductor's valley current, off at D T at
    # its peak; the diode recovers as the switch turns on. Vin = 12 V blocked (ideal diode, no drop).
    i_l = tr.state_names.index("i(l1)")
    valley = float(tr.x[np.argmin(np.abs(tr.t - t0)), i_l])
    peak = float(tr.x[np.argmin(np.abs(tr.t - (t0 + p["d"] * T))), i_l])
    assert valley > 0.2 and peak > valley
    f = 1.0 / T
    k_on, k_off, k_rr = (_at({t: (k[t],) for t in TEMPERATURES}, tj_)[0]
                         for k, tj_ in ((K_ON, 80.0), (K_OFF, 80.0), (K_RR, 60.0)))
    assert losses["s1"].turn_ons == losses["s1"].turn_offs == 1
    assert losses["s1"].turn_on_W == pytest.approx(f * k_on * 12.0 * valley, rel=1e-9)
    assert losses["s1"].turn_off_W == pytest.approx(f * k_off * 12.0 * peak, rel=1e-9)
    assert losses["d1"].turn_offs == 1 and losses["d1"].turn_on_W == 0.0
    assert losses["d1"].turn_off_W == pytest.approx(f * k_rr * 12.0 * valley, rel=1e-9)


def test_a_description_on_no_device_or_the_wrong_kind_is_refused_by_name():
    model = get_model("netlists/circuits/buck.cir")
    p = model.resolve({"L": "100u"})
    tr = run_converter(model, p, steady=True, method="event", periods=1)
    t1 = float(tr.t[-1])
    with pytest.raises(ParameterError, match="names 'q7', which is no switch"):
        device_losses(model, p, tr, {"q7": DESCRIPTIONS["s1"]}, {"q7": 25.0}, t1 - 1e-5, t1)
    with pytest.raises(ParameterError, match="d1: a MOSFET description on a diode"):
        device_losses(model, p, tr, {"d1": DESCRIPTIONS["s1"]}, {"d1": 25.0}, t1 - 1e-5, t1)


def test_the_junction_temperatures_in_steady_state_are_the_closed_form_of_losses_linear_in_temperature():
    """Losses linear in T_j (the tables interpolate linearly in temperature), P_k(T) = a_k + b_k T: on a shared
    heatsink T_hs = T_a + R_ha (P_1 + P_2), T_j,k = T_hs + (R_ch,k + R_jc,k) P_k, a linear system solved here
    directly; the fixed point reaches it to 1e-6 K."""
    from types import SimpleNamespace

    from converters.thermal.network import Heatsink, Mount, ThermalSetup
    q = {"s1": DESCRIPTIONS["s1"], "d1": DeviceDescription("D1", "Diode", None, None, None,
                                                           ThermalChain("cauer", (0.3, 0.9), (1e-3, 0.1)))}
    setup = ThermalSetup(40.0, {"s1": Mount(q["s1"], "hs", 0.2), "d1": Mount(q["d1"], "hs", 0.4)},
                         {"hs": Heatsink(1.5, 80.0)})
    a, b = {"s1": 3.0, "d1": 1.2}, {"s1": 0.012, "d1": 0.004}
    steady = setup.steady(lambda tj: {d: SimpleNamespace(total_W=a[d] + b[d] * tj[d]) for d in tj})
    r = {"s1": 0.2 + 0.5, "d1": 0.4 + 1.2}
    # T_k = T_a + R_ha sum_m (a_m + b_m T_m) + r_k (a_k + b_k T_k): two linear equations in T_s1, T_d1
    M = np.array([[1 - 1.5 * b["s1"] - r["s1"] * b["s1"], -1.5 * b["d1"]],
                  [-1.5 * b["s1"], 1 - 1.5 * b["d1"] - r["d1"] * b["d1"]]])
    rhs = np.array([40 + 1.5 * (a["s1"] + a["d1"]) + r[d] * a[d] for d in ("s1", "d1")])
    exact = np.linalg.solve(M, rhs)
    assert [steady.junction["s1"], steady.junction["d1"]] == pytest.approx(exact, abs=1e-6)
    assert steady.heatsink["hs"] == pytest.approx(40 + 1.5 * sum(a[d] + b[d] * t for d, t in zip(("s1", "d1"), exact)),
                                                  abs=1e-6)


def test_a_loss_that_outgrows_its_heatsink_is_refused_as_thermal_runaway():
    from types import SimpleNamespace

    from converters.errors import SimulationError
    from converters.thermal.network import Heatsink, Mount, ThermalSetup
    setup = ThermalSetup(25.0, {"s1": Mount(DESCRIPTIONS["s1"], "hs", 0.0)}, {"hs": Heatsink(4.0)})
    with pytest.raises(SimulationError, match="thermal runaway"):              # R dP/dT = 4.5 * 0.3 > 1
        setup.steady(lambda tj: {"s1": SimpleNamespace(total_W=1.0 + 0.3 * tj["s1"])})


def test_a_loss_step_heats_the_junction_as_the_foster_chain_and_the_heatsink_in_closed_form():
    """Constant losses stepping from P0 to P1 at t = 0 (two devices on one heatsink, one Foster, one Cauer): the
    junction of the Foster device follows T_a + R_ha (P0_tot + dP_tot (1 - e^-t/tau_hs)) + R_ch P1 + sum R_k (P0 + dP
    (1 - e^-t/tau_k)), the exponential integrator exact for losses that do not change with temperature."""
    from types import SimpleNamespace

    from converters.thermal.network import Heatsink, Mount, ThermalSetup, thermal_transient
    foster = DeviceDescription("Q", "MOSFET", thermal=ThermalChain("foster", (0.2, 0.5, 0.3), (1e-4, 2e-3, 2e-2)))
    cauer = DeviceDescription("D", "Diode", thermal=ThermalChain("cauer", (0.3, 0.9), (1e-3, 0.1)))
    setup = ThermalSetup(40.0, {"s1": Mount(foster, "hs", 0.5), "d1": Mount(cauer, "hs", 0.4)},
                         {"hs": Heatsink(2.0, 5.0)})
    P0, P1 = {"s1": 1.0, "d1": 0.3}, {"s1": 2.5, "d1": 0.1}
    start = setup.temperatures(P0)[0]
    run = thermal_transient(setup, lambda tj: {d: SimpleNamespace(total_W=P1[d]) for d in tj}, start, 60.0)
    t = run.t
    sink = 40.0 + 2.0 * (1.3 + (2.6 - 1.3) * -np.expm1(-t / 10.0))
    chain = sum(r * (1.0 + 1.5 * -np.expm1(-t / k)) for r, k in zip((0.2, 0.5, 0.3), (1e-4, 2e-3, 2e-2)))
    assert np.allclose(run.heatsink["hs"], sink, rtol=0, atol=1e-9)
    assert np.allclose(run.junction["s1"], sink + 0.5 * 2.5 + chain, rtol=0, atol=1e-9)
    # six heatsink time constants on, each junction short of its new steady state by the heatsink's e^-6 alone
    # (the Cauer diode's own chain settled: its slowest mode 0.1 s)
    for d in ("s1", "d1"):
        assert run.junction[d][-1] == pytest.approx(setup.temperatures(P1)[0][d] - 2.0 * 1.3 * np.exp(-6.0), abs=1e-9)
