"""Loss tables read as PLECS reads them (multilinear, extrapolated linearly), the thermal chains' step responses
against an independent matrix exponential, and descriptions in PLECS's XML and the table form, good and bad."""
import numpy as np
import pytest
from scipy.linalg import expm

from converters.errors import ParameterError
from converters.thermal import ThermalChain, energy_table, on_state_table, parse_plecs, parse_table, read_description

RNG = np.random.default_rng(59)


def _trilinear(v, i, t):
    return 1e-4 * (1 + 0.02 * v + 0.3 * i + 0.004 * t + 1e-3 * v * i + 2e-5 * v * t + 3e-4 * i * t + 1e-6 * v * i * t)


def test_multilinear_interpolation_reproduces_a_trilinear_energy_and_extrapolates_a_linear_one_exactly():
    v, i, t = np.array([0.0, 200.0, 450.0, 600.0]), np.array([0.0, 5.0, 12.0, 30.0]), np.array([25.0, 100.0, 150.0])
    grid = np.array([[[_trilinear(a, b, c) for b in i] for a in v] for c in t])      # [temperature][voltage][current]
    table = energy_table("E", v, i, t, grid)
    for a, b, c in RNG.uniform([0, 0, 25], [600, 30, 150], size=(200, 3)):
        assert table(a, b, c) == pytest.approx(_trilinear(a, b, c), rel=1e-12)

    def linear(a, b, c):
        return 1e-3 + 2e-6 * a + 3e-5 * b + 4e-7 * c
    table = energy_table("E", v, i, t, np.array([[[linear(a, b, c) for b in i] for a in v] for c in t]))
    for a, b, c in RNG.uniform([600, 30, 150], [900, 60, 200], size=(50, 3)):        # beyond every axis
        assert table(a, b, c) == pytest.approx(linear(a, b, c), rel=1e-12)


def test_one_temperature_is_constant_in_temperature_and_an_extrapolated_negative_energy_reads_zero():
    table = energy_table("E", [0, 100], [2, 10], [25], [[[1e-4, 5e-4], [2e-4, 1e-3]]])
    assert table(50, 6, 25) == table(50, 6, 175) == pytest.approx(0.5 * (3e-4 + 6e-4), rel=1e-12)
    assert table(50, 0.0, 25) == 0.0                        # the line through 2 A and 10 A falls below 0 J at 0 A
    on = on_state_table("V", [0, 10, 20], [25, 125], [[0, 0.5, 1.0], [0, 0.8, 1.6]])
    assert on(15, 75) == pytest.approx(0.5 * (0.75 + 1.2), rel=1e-12)


def _ladder_response(R, C, t):
    """An independent step response of a Cauer ladder (junction node first, the last R to the case): the nodal
    equations assembled here and integrated by scipy's expm, for 1 W."""
    n = len(R)
    G = np.zeros((n, n))
    for k in range(n):
        G[k, k] += 1 / R[k]
        if k + 1 < n:
            G[k:k + 2, k:k + 2] += np.array([[0, -1], [-1, 1]]) / R[k]
    A = -np.diag(1 / np.array(C)) @ G
    b = np.eye(n)[0] / C[0]
    return np.array([(np.linalg.solve(-A, (np.eye(n) - expm(A * s)) @ b))[0] for s in t])


@pytest.mark.parametrize("R, C", [([0.3], [2e-3]), ([0.05, 0.2, 0.4], [1e-3, 2e-2, 0.5]),
                                  ([1e-3, 0.8, 0.01, 0.3], [1e-4, 1.0, 3e-3, 20.0])])
def test_a_cauer_chains_step_response_is_its_ladders_and_its_steady_state_the_sum_of_its_resistances(R, C):
    chain = ThermalChain("cauer", tuple(R), tuple(C))
    t = np.geomspace(1e-6, 1e3, 40)
    assert np.allclose(chain.step(t, 1.0), _ladder_response(R, C, t), rtol=1e-9, atol=1e-14)
    assert chain.step(1e9, 25.0) == pytest.approx(25.0 * sum(R), rel=1e-12)
    assert sum(chain.foster()[0]) == pytest.approx(sum(R), rel=1e-12)


def test_a_foster_chains_step_response_is_the_datasheets_closed_form():
    R, tau = (0.02, 0.1, 0.25), (1e-4, 5e-3, 0.08)
    chain = ThermalChain("foster", R, tau)
    t = np.array([0.0, 1e-4, 1e-3, 0.01, 0.1, 1.0, 100.0])
    closed = [12.0 * sum(r * (1 - np.exp(-s / k)) for r, k in zip(R, tau)) for s in t]
    assert np.allclose(chain.step(t, 12.0), closed, rtol=1e-13, atol=0)
    # a single Cauer stage is a single Foster stage with tau = R C
    assert np.allclose(ThermalChain("cauer", (0.4,), (0.01,)).step(t, 3.0),
                       ThermalChain("foster", (0.4,), (0.004,)).step(t, 3.0), rtol=1e-13)


MOSFET = """<?xml version="1.0" encoding="UTF-8"?>
<SemiconductorLibrary xmlns="http://www.plexim.com/xml/semiconductors/" version="1.1">
  <Package class="MOSFET" vendor="Example" partnumber="EX100">
    <Variables/>
    <SemiconductorData type="MOSFET">
      <TurnOnLoss>
        <ComputationMethod>Table only</ComputationMethod>
        <CurrentAxis>0 10 20</CurrentAxis>
        <VoltageAxis>0 48</VoltageAxis>
        <TemperatureAxis>25 125</TemperatureAxis>
        <Energy scale="1e-6">
          <Temperature><Voltage>0 0 0</Voltage><Voltage>0 20 45</Voltage></Temperature>
          <Temperature><Voltage>0 0 0</Voltage><Voltage>0 26 58</Voltage></Temperature>
        </Energy>
      </TurnOnLoss>
      <TurnOffLoss>
        <ComputationMethod>Table only</ComputationMethod>
        <CurrentAxis>0 10 20</CurrentAxis>
        <VoltageAxis>0 48</VoltageAxis>
        <TemperatureAxis>25 125</TemperatureAxis>
        <Energy scale="1e-6">
          <Temperature><Voltage>0 0 0</Voltage><Voltage>0 10 22</Voltage></Temperature>
          <Temperature><Voltage>0 0 0</Voltage><Voltage>0 12 27</Voltage></Temperature>
        </Energy>
      </TurnOffLoss>
      <ConductionLoss>
        <ComputationMethod>Table only</ComputationMethod>
        <CurrentAxis>0 10 20</CurrentAxis>
        <TemperatureAxis>25 125</TemperatureAxis>
        <VoltageDrop scale="1">
          <Temperature>0 0.05 0.1</Temperature>
          <Temperature>0 0.08 0.16</Temperature>
        </VoltageDrop>
      </ConductionLoss>
    </SemiconductorData>
    <ThermalModel>
      <Branch type="Foster"><RTauElement R="0.2" Tau="0.001"/><RTauElement R="0.6" Tau="0.02"/></Branch>
    </ThermalModel>
    <Comment>illustrative values</Comment>
  </Package>
</SemiconductorLibrary>
"""

MOSFET_TOML = """
[device]
name = "EX100"
kind = "MOSFET"
[conduction]
current = [0, 10, 20]
temperature = [25, 125]
v_on = [[0, 0.05, 0.1], [0, 0.08, 0.16]]
[turn_on]
voltage = [0, 48]
current = [0, 10, 20]
temperature = [25, 125]
energy = [[[0, 0, 0], [0, 20e-6, 45e-6]], [[0, 0, 0], [0, 26e-6, 58e-6]]]
[turn_off]
voltage = [0, 48]
current = [0, 10, 20]
temperature = [25, 125]
energy = [[[0, 0, 0], [0, 10e-6, 22e-6]], [[0, 0, 0], [0, 12e-6, 27e-6]]]
[thermal]
kind = "foster"
R = [0.2, 0.6]
tau = [0.001, 0.02]
"""


def test_a_plecs_description_and_its_table_form_read_the_same_numbers(tmp_path):
    xml, toml = tmp_path / "ex100.xml", tmp_path / "ex100.toml"
    xml.write_text(MOSFET)
    toml.write_text(MOSFET_TOML)
    a, b = read_description(xml), read_description(toml)
    assert a.name == b.name == "EX100" and a.kind == b.kind == "MOSFET"
    # 24 V blocked, 15 A, 75 degC: the mean of the four corners' halves (multilinear)
    on = 0.5 * (0.5 * (0.5 * (20 + 45) + 0.5 * (26 + 58))) * 1e-6
    for d in (a, b):
        assert d.turn_on(24.0, 15.0, 75.0) == pytest.approx(on, rel=1e-12)
        assert d.turn_off(48.0, 20.0, 125.0) == pytest.approx(27e-6, rel=1e-12)
        assert d.conduction(10.0, 125.0) == pytest.approx(0.08, rel=1e-12)
        assert d.thermal.resistance == pytest.approx(0.8, rel=1e-15)


def test_a_diodes_switching_losses_are_read_at_the_magnitude_of_their_negative_blocked_voltage():
    text = MOSFET.replace('class="MOSFET"', 'class="Diode"').replace("<VoltageAxis>0 48</VoltageAxis>",
                                                                       "<VoltageAxis>-48 0</VoltageAxis>")
    # the rows follow the axis: at -48 V the energies, at 0 V none
    text = text.replace("<Voltage>0 0 0</Voltage><Voltage>0 10 22</Voltage>",
                        "<Voltage>0 10 22</Voltage><Voltage>0 0 0</Voltage>")
    diode = parse_plecs(text.encode())
    assert diode.turn_off(48.0, 20.0, 25.0) == pytest.approx(22e-6, rel=1e-12)
    assert diode.turn_off(24.0, 20.0, 25.0) == pytest.approx(11e-6, rel=1e-12)


BAD_XML = [
    (MOSFET.replace('class="MOSFET"', 'class="Thyristor"'), "the Package class must be one of"),
    (MOSFET.replace('class="MOSFET"', 'class="MOSFET with Diode"'), "the Package class must be one of"),
    (MOSFET.replace("<Comment>", "<Wiring/><Comment>"), "unknown element <Wiring> in <Package>"),
    (MOSFET.replace("<ConductionLoss>", "<GateCharge/><ConductionLoss>"), "unknown element <GateCharge>"),
    (MOSFET.replace("<Variables/>", "<Variables><Variable>Rg</Variable></Variables>"), "<Variables>"),
    (MOSFET.replace("<ComputationMethod>Table only</ComputationMethod>\n        <CurrentAxis>0 10 20</CurrentAxis>\n"
                    "        <VoltageAxis>0 48</VoltageAxis>",
                    "<ComputationMethod>Formula only</ComputationMethod>\n        <CurrentAxis>0 10 20</CurrentAxis>\n"
                    "        <VoltageAxis>0 48</VoltageAxis>", 1), "the computation method must be 'Table only'"),
    (MOSFET.replace("<VoltageAxis>0 48</VoltageAxis>", "", 1), "exactly one <VoltageAxis> expected"),
    (MOSFET.replace("<CurrentAxis>0 10 20</CurrentAxis>", "<CurrentAxis>0 20 10</CurrentAxis>", 1),
     "must increase strictly"),
    (MOSFET.replace("<Voltage>0 20 45</Voltage>", "<Voltage>0 -20 45</Voltage>"), "must be >= 0 J"),
    (MOSFET.replace("<Voltage>0 20 45</Voltage>", "<Voltage>0 20</Voltage>"), "rows differ in length"),
    (MOSFET.replace("<Voltage>0 20 45</Voltage>", "<Voltage>0 20 4x5</Voltage>"), "numbers separated by spaces"),
    (MOSFET.replace('<Energy scale="1e-6">', '<Energy scale="-1">', 1), "scale must be a number > 0"),
    (MOSFET.replace("<Temperature>0 0.05 0.1</Temperature>", "<Temperature>0 0.1 0.05</Temperature>"),
     "must not fall as the current rises"),
    (MOSFET.replace('<Temperature>0 0.05 0.1</Temperature>', ''), "must hold 2 <Temperature>"),
    (MOSFET.replace('type="Foster"', 'type="Ladder"'), "the Branch type must be Foster or Cauer"),
    (MOSFET.replace('R="0.2" Tau="0.001"', 'R="0.2" C="0.001"'), "each <RTauElement> needs its Tau attribute"),
    (MOSFET.replace('R="0.2" Tau="0.001"', 'R="0.2" Tau="0"'), "every tau (s) must be a finite number > 0"),
    (MOSFET.replace('R="0.2"', 'R="-0.2"'), "every R (K/W) must be a finite number > 0"),
    (MOSFET.replace('R="0.2"', 'R="0.2K/W"'), "must be a number (no unit)"),
    (MOSFET.replace("</ThermalModel>", "</ThermalModel><ThermalModel/>"), "more than one <ThermalModel>"),
    (MOSFET.replace('<Branch type="Foster"><RTauElement R="0.2" Tau="0.001"/><RTauElement R="0.6" Tau="0.02"/></Branch>',
                    ""), "one <Branch> (a Foster or Cauer chain) expected"),
    ('<?xml version="1.0"?><!DOCTYPE lolz [<!ENTITY lol "lol">]><Package class="MOSFET">&lol;</Package>',
     "document type declaration"),
    (MOSFET.replace("</Package>", ""), "not well-formed XML"),
    (MOSFET.replace("<VoltageAxis>0 48</VoltageAxis>", "<VoltageAxis>48</VoltageAxis>", 1).replace(
        "<Temperature><Voltage>0 0 0</Voltage><Voltage>0 20 45</Voltage></Temperature>",
        "<Temperature><Voltage>0 20 45</Voltage></Temperature>").replace(
        "<Temperature><Voltage>0 0 0</Voltage><Voltage>0 26 58</Voltage></Temperature>",
        "<Temperature><Voltage>0 26 58</Voltage></Temperature>"), "one voltage column (48 V)"),
]


@pytest.mark.parametrize("text, message", BAD_XML, ids=[m[:30] for _, m in BAD_XML])
def test_a_bad_plecs_description_is_refused_in_one_line_naming_what_is_wrong(text, message):
    with pytest.raises(ParameterError) as error:
        parse_plecs(text.encode(), "q1.xml")
    assert message in str(error.value) and "\n" not in str(error.value)
    assert str(error.value).startswith("q1.xml")


BAD_TOML = [
    (MOSFET_TOML.replace('kind = "MOSFET"', 'kind = "GTO"'), "[device] kind must be one of"),
    (MOSFET_TOML.replace("[thermal]", "[cooling]"), "unknown section [cooling]"),
    (MOSFET_TOML.replace("tau = [", "taus = ["), "unknown key 'taus' in [thermal]"),
    (MOSFET_TOML.replace('kind = "foster"', 'kind = "cauer"'), "[thermal] needs C"),
    (MOSFET_TOML.replace("v_on = [[0, 0.05, 0.1], [0, 0.08, 0.16]]", "v_on = [[0, 0.05, 0.1]]"),
     "must be 2 x 3 (temperature x current)"),
    (MOSFET_TOML.replace("current = [0, 10, 20]\ntemperature = [25, 125]\nv_on",
                         "current = [-10, 10, 20]\ntemperature = [25, 125]\nv_on"), "must start at >= 0 A"),
    (MOSFET_TOML.replace("temperature = [25, 125]\nenergy", "temperature = [125, 25]\nenergy", 1),
     "must increase strictly"),
    (MOSFET_TOML.replace("R = [0.2, 0.6]", 'R = [0.2, "x"]'), "numbers (nested lists of one shape) expected"),
    (MOSFET_TOML.replace("[device]", "[device\n"), "not a TOML table file"),
]


@pytest.mark.parametrize("text, message", BAD_TOML, ids=[m[:30] for _, m in BAD_TOML])
def test_a_bad_table_description_is_refused_in_one_line(text, message):
    with pytest.raises(ParameterError) as error:
        parse_table(text.encode(), "q1.toml")
    assert message in str(error.value) and "\n" not in str(error.value)


def test_a_file_that_is_neither_xml_nor_toml_nor_readable_is_refused_by_name(tmp_path):
    with pytest.raises(ParameterError, match="must be a PLECS .xml or a .toml"):
        read_description(tmp_path / "q1.csv")
    with pytest.raises(ParameterError, match="cannot read the thermal description"):
        read_description(tmp_path / "missing.xml")
