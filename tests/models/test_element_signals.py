"""The built-in converters' element signals are their netlists' (read on the compiled signal maps); the formulas
derived by hand from the state and the pair, which the models had used, are the independent oracle here."""
import numpy as np
import pytest

from converters.models import ON
from converters.run import run_converter

PARASITICS = {"rL": 0.05, "Ron": 0.03, "Vf": 0.4, "Rd": 0.02, "rC": 0.1, "L": "20u"}
DCM = {"L": "3u", "R": 30}


def hand(topology: str, tr, p: dict) -> dict:
    """Input, switch, diode and capacitor currents, switch and diode voltages from x = (iL, vC) and the pair
    (u = i_D in ON, u = -v_D in OFF): the OFF forms are L iL' + rL iL rearranged, exact whether the diode conducts
    or blocks; vout's magnitude a vC + b i_node through the ESR."""
    Vin, R = p["Vin"], p["R"]
    Ron, Vf, Rd, rC = (p.get(k, 0.0) for k in ("Ron", "Vf", "Rd", "rC"))
    a, b = R / (R + rC), R * rC / (R + rC)
    iL, vC, u = tr.x[:, 0], tr.x[:, 1], tr.u[:, 0]
    on = np.asarray(tr.config) == ON
    i_d = np.where(on, u, iL)
    i_s = np.where(on, iL - u, 0.0)
    i_node = iL if topology == "buck" else i_d
    v_node = a * vC + b * i_node
    if topology == "buck":
        v_sw = np.where(on, Vin - Ron * i_s, u - Vf - Rd * iL)
        v_s, v_d = Vin - v_sw, -v_sw
    elif topology == "boost":
        v_sw = np.where(on, Ron * i_s, Vf + (Rd + b) * iL + a * vC - u)
        v_s, v_d = v_sw, v_sw - v_node
    else:
        v_sw = np.where(on, Vin - Ron * i_s, u - Vf - (Rd + b) * iL - a * vC)
        v_s, v_d = Vin - v_sw, -v_node - v_sw
    return {"i_in": iL if topology == "boost" else i_s, "i_switch": i_s, "v_switch": v_s, "i_diode": i_d,
            "v_diode": v_d, "i_cap": i_node - v_node / R}


@pytest.mark.parametrize("name", ["buck", "boost", "buck-boost"])
@pytest.mark.parametrize("params", [PARASITICS, DCM], ids=["ccm-parasitics", "dcm"])
@pytest.mark.parametrize("method", ["event", "lcp"])
def test_element_signals_are_the_netlists_and_match_the_hand_derivation(name, params, method):
    tr = run_converter(name, params, method=method, periods=30)
    p = tr.metadata["params"]
    for signal, expected in hand(name, tr, p).items():
        got = tr.signal(signal)
        scale = np.abs(expected).max()
        assert scale > 0 and np.abs(got - expected).max() <= 1e-12 * scale, (signal, np.abs(got - expected).max())
    if params is DCM:
        assert "DCM" in tr.mode_fractions()


@pytest.mark.parametrize("params", [{"rL1": 0.05, "rL2": 0.04, "Ron": 0.03, "Vf": 0.4, "Rd": 0.02},
                                    {"L1": "10u", "L2": "10u", "R": 40}], ids=["parasitics", "gdcm"])
def test_the_cuks_switch_and_diode_currents_are_its_netlists(params):
    """i_S = i1 + i2 - u, i_D = u in ON; 0 and i1 + i2 in OFF (the diode carries both inductors' currents), GDCM-OFF
    included."""
    tr = run_converter("cuk", params, method="event", periods=30)
    i1, i2, u = tr.x[:, 0], tr.x[:, 2], tr.u[:, 0]
    on = np.asarray(tr.config) == ON
    np.testing.assert_allclose(tr.signal("i_switch"), np.where(on, i1 + i2 - u, 0.0), rtol=0, atol=1e-12)
    np.testing.assert_allclose(tr.signal("i_diode"), np.where(on, u, i1 + i2), rtol=0, atol=1e-12)
    if "R" in params:
        assert "GDCM-OFF" in tr.mode_fractions()
