"""The netlist reader and its expressions, unit by unit: SPICE numbers and suffixes, ``{...}`` and ``'...'``
expressions, continuation lines, inline comments, subcircuit parameters, case-insensitivity; and what the
messages of a refusal hold (file, line, element)."""
from __future__ import annotations

import math
from pathlib import Path

import pytest

from converters.circuits.expressions import evaluate, number
from converters.circuits.netlist import NetlistError, Pulse, check_overrides, read_netlist
from converters.errors import ParameterError
from converters.models import Circuit

NETLISTS = Path(__file__).resolve().parents[2] / "netlists" / "circuits"


@pytest.mark.parametrize("text, value", [
    ("10u", 1e-5), ("1meg", 1e6), ("1MEG", 1e6), ("2.2n", 2.2e-9), ("100k", 1e5), ("4.7p", 4.7e-12), ("1m", 1e-3),
    ("1M", 1e-3), ("3f", 3e-15), ("2g", 2e9), ("1t", 1e12), ("1mil", 25.4e-6), ("10uF", 1e-5), ("48V", 48.0),
    ("1kohm", 1e3), ("1e3", 1e3), ("1.5e-3k", 1.5), (".5", 0.5), ("100u", 1e-4)])
def test_numbers_take_spice_suffixes(text, value):
    assert evaluate(text, {}) == value           # exact: 100u is 1e-4, not 9.999999999999999e-05


def test_number_reports_what_it_read():
    assert number("10uF rest") == (1e-5, 4)
    assert number("x") == (0.0, 0) or math.isnan(number("x")[0])


@pytest.mark.parametrize("text, value", [
    ("{a*b}", 6.0), ("'a*b'", 6.0), ("{ a * b }", 6.0), ("a*b", 6.0), ("2**3", 8.0), ("2^3^2", 512.0),
    ("-a+b", 1.0), ("--a", 2.0), ("-+-a", 2.0), ("(a+b)/2", 2.5), ("sqrt(16)", 4.0), ("max(a, b)", 3.0),
    ("min(A,B)", 2.0), ("pi", math.pi), ("1/A*b", 1.5), ("abs(-1u)", 1e-6)])
def test_expressions(text, value):
    assert evaluate(text, {"a": 2.0, "b": 3.0}) == pytest.approx(value, rel=1e-15)


@pytest.mark.parametrize("text, fragment", [
    ("{(1+2}", "')' is missing"), ("1/0", "division by zero"), ("1/(a-a)", "division by zero"),
    ("c*2", "'c' is not a parameter"), ("__import__('os')", "unknown function '__import__'"),
    ("1e999", "not a finite number"), ("exp(1000)", "is not defined"), ("sqrt(-1)", "is not defined"),
    ("max(1)", "takes 2 arguments"), ("2 3", "cannot read"), ("a.b", "'a.b' is not a parameter"),
    ("(" * 150 + "1" + ")" * 150, "nested deeper than 100"), ("sqrt(" * 150 + "1" + ")" * 150, "nested deeper"),
    ("1" + "^1" * 500, "nested deeper"), ("1+" * 1500 + "1", "at most 2000")])
def test_expression_errors_are_one_parameter_error(text, fragment):
    with pytest.raises(ParameterError, match=None) as info:
        evaluate(text, {"a": 2.0}, "R1 value")
    message = str(info.value)
    assert fragment in message and message.startswith("R1 value: ") and len(message) < 400


def test_a_run_of_signs_is_not_a_recursion():
    assert evaluate("-" * 1998 + "1", {}) == 1.0                 # an even count of minus signs
    assert evaluate("-" * 1997 + "1", {}) == -1.0


READ = """Test circuit
* a comment line
.PARAM Vin=12 ; an inline comment
.param L={10u * 2}
+ C='1u*100'
Vin IN 0 DC {vin}
L1 in out {L} IC=0.5
C1 OUT 0 {c}  $ another comment
R1 out 0 5
+ IC=0
X1 out 0 divider params: r=2k
.subckt DIVIDER a b params: r=1k
R1 a m {r}
R2 m b {2*r}
.ends DIVIDER
.tran 1u 1m UIC
.end
"""


def test_read_continuations_comments_case_and_subcircuit_parameters():
    nl = read_netlist(READ, name="t.cir")
    values = {e.name: e.value for e in nl.elements}
    assert nl.params == {"vin": 12.0, "l": 2e-5, "c": pytest.approx(1e-4, rel=1e-15)}
    assert nl.element("vin").waveform == 12.0 and nl.element("vin").nodes == ("in", "0")
    assert values["l1"] == 2e-5 and nl.element("l1").ic == 0.5
    assert values["c1"] == pytest.approx(1e-4, rel=1e-15) and nl.element("C1").nodes == ("out", "0")
    assert values["x1.r1"] == 2e3 and values["x1.r2"] == 4e3            # the instance's r, not the default
    assert nl.element("x1.r1").nodes == ("out", "x1.m") and nl.element("x1.r2").nodes == ("x1.m", "0")
    assert nl.tran.tstop == 1e-3 and nl.tran.uic
    assert nl.element("r1").line == 9 and nl.element("x1.r2").line == 14
    assert nl.param_lines["c"] == (4, "'1u*100'")                    # a continuation keeps its first line
    assert nl.where("C") == "t.cir:4" and nl.where("r1") == "t.cir:9" and nl.where("nothing") == "t.cir"


def test_subcircuit_defaults_apply():
    nl = read_netlist(READ.replace(" params: r=2k", ""), name="t.cir")
    assert nl.element("x1.r1").value == 1e3


def test_values_with_blanks_inside_braces_quotes_and_calls():
    nl = read_netlist("t\n.param a=2 b=3\nR1 x 0 {a * b}\nR2 x 0 'a * b'\nC1 x 0 {max(a, b)*1u} IC = 1\n"
                      "V1 x 0 PULSE(0 {max(a, b)} 0 1u 1u {a*1u} 10u)\n.model S SW(VT=0.5, VH=0.1 RON={min(a,b)})\n"
                      ".tran {1u / 10} 1m\n", name="t")
    assert nl.element("r1").value == nl.element("r2").value == 6.0
    assert nl.element("c1").value == 3e-6 and nl.element("c1").ic == 1.0
    assert nl.element("v1").waveform == Pulse(0.0, 3.0, 0.0, 1e-6, 1e-6, 2e-6, 1e-5)
    assert nl.models["s"].params == {"VT": 0.5, "VH": 0.1, "RON": 2.0}
    assert nl.tran.tstep == 1e-7


def test_a_multiplicity_is_refused_not_ignored():
    with pytest.raises(NetlistError, match=r"^t:2: resistor R1: M=2 \(a multiplicity"):
        read_netlist("t\nR1 x 0 10 m=2\n", name="t")
    assert read_netlist("t\nR1 x 0 10 m=1\n", name="t").element("r1").value == 10.0


def test_overrides_reach_parameters_and_elements():
    nl = read_netlist(READ, overrides={"VIN": 24, "R1": 7}, name="t.cir")
    assert nl.element("vin").waveform == 24.0 and nl.element("r1").value == 7.0


@pytest.mark.parametrize("text, where", [
    ("t\nR1 a 0 1\nR2 a 0 1\x00\n", "t:3: a NUL byte at column 9"),
    ("\x00t\nR1 a 0 1\n", "t:1: a NUL byte at column 1"),
    ("t\r\nR1 a 0 1\r\n\x00", "t:3: a NUL byte at column 1"),
    ("t\rR1 a 0 1\r\rR2\x00", "t:4: a NUL byte at column 3")])
def test_nul_bytes_are_placed_by_line(text, where):
    with pytest.raises(NetlistError, match=None) as info:
        read_netlist(text, name="t")
    assert str(info.value).startswith(where)


def test_bytes_not_utf8_are_placed_by_line(tmp_path):
    path = tmp_path / "latin1.cir"
    path.write_bytes("t\nR1 a 0 1\nC1 a 0 100µF\n".encode("latin-1"))
    with pytest.raises(NetlistError, match=rf"^{path}:3: not UTF-8 text: byte 0xb5 at column 11 "):
        read_netlist(path)


def test_control_is_refused_before_any_line_is_evaluated():
    text = "t\n.param a={1/0}\nQ1 a b c QMOD\n.end\n.control\nshell rm -rf /\n.endc\n"
    with pytest.raises(NetlistError, match=r"^t:5: \.control: a \.control block holds ngspice commands"):
        read_netlist(text, name="t")


def test_elements_inside_an_instance_are_named_with_it():
    text = "t\nX1 a 0 BAD\n.subckt BAD p q\nR1 p q -1\n.ends\n"
    with pytest.raises(NetlistError, match=r"^t:4: resistor R1 \(in X1\): its value must be non-negative; got -1$"):
        read_netlist(text, name="t")


DERIVED = "t\n.param f=100k D=0.5\n.param T={1/f} ton={D*T}\nVin in 0 DC 12\nR1 in out 10\nC1 out 0 {1u}\n" \
          ".tran 1u 1m\n"


def test_check_overrides_names_file_line_and_what_is_wrong():
    circuit = Circuit.from_netlist("d.cir", text=DERIVED)
    nl, parameters = circuit.netlist, circuit.parameters
    check_overrides(nl, {"F": "200k", "r1": 5}, parameters)                    # valid: nothing said
    with pytest.raises(NetlistError, match=r"^d\.cir:3: -p ton: \.param ton = \{D\*T\} is an expression of other "
                                           r"parameters, not a parameter of its own; set those \(d, f\)$"):
        check_overrides(nl, {"ton": 1e-6}, parameters)
    with pytest.raises(NetlistError, match=r"^d\.cir: -p X: unknown parameter 'x'; valid names: f, d, vin, r1, c1$"):
        check_overrides(nl, {"X": 1}, parameters)
    with pytest.raises(NetlistError, match=r"^d\.cir:5: -p R1=-5: r1 \(resistor R1 \(line 5\)\) must be in \[0, inf\)"):
        check_overrides(nl, {"R1": "-5"}, parameters)


def test_every_example_netlist_reads(tmp_path):
    from pathlib import Path
    for path in sorted((Path(__file__).resolve().parents[2] / "netlists" / "circuits").glob("*.cir")):
        nl = read_netlist(path)
        assert nl.elements and nl.tran is not None, path


def test_options_keep_the_transients_tolerances_and_method():
    """RELTOL, ABSTOL (with suffixes and parameters) and METHOD are read for ngspice's run of the file; flags and
    other options are left to ngspice; a later .options line wins."""
    net = read_netlist("t\n.param tol=1u\nR1 a 0 1\nV1 a 0 1\n.options noacct RELTOL=1e-4 ABSTOL={tol} itl1=500\n"
                       ".option method=trapezoidal\n.opt METHOD=Gear\n.tran 1u 1m\n.end\n")
    assert net.spice_options == {"reltol": 1e-4, "abstol": 1e-6, "method": "gear"}
    assert read_netlist("t\nR1 a 0 1\nV1 a 0 1\n.options METHOD=trap\n.tran 1u 1m\n.end\n").spice_options == {
        "method": "trap"}


def test_the_files_tmax_and_options_are_ngspices_unless_options_are_given(tmp_path):
    """A periodic file's TMAX is kept as a fraction of its period (so -p f=... keeps T/2000 a period), its
    tolerances with it; options given on the command line replace them; a file without them gets the defaults."""
    from netlists import SpiceOptions
    from netlists.circuit import file_spice_options
    from netlists.circuit import circuit_netlist
    cw = Circuit.from_netlist(NETLISTS / "cockcroft-walton.cir")
    options = file_spice_options(cw)
    assert options.tmax_fraction == pytest.approx(1 / 2000, rel=1e-12) and options.abstol == 1e-6
    text = circuit_netlist(cw, cw.resolve({"f": "200k"}), 1e-4, options).text
    assert ".tran 2.5e-09 0.0001 0 2.5e-09 UIC" in text and "ABSTOL=1e-06" in text
    given = SpiceOptions(tmax_fraction=1 / 100)
    assert file_spice_options(cw, given) is given
    assert file_spice_options(Circuit.from_netlist(NETLISTS / "rectifier-1ph.cir")) == SpiceOptions()


def test_an_element_whose_value_is_an_expression_follows_the_parameters_it_names():
    """L1 = {k*L}: -p k=3 triples it (the element is not a parameter of its own, which would pin it at its default)."""
    from converters.models import Circuit
    text = "t\n.param L=10u k=2\nV1 a 0 DC 1\nR1 a b 1\nL1 b 0 {k*L}\n.tran 1u 1m\n.end\n"
    circuit = Circuit.from_netlist("t.cir", text=text)
    assert "l1" not in [q.name for q in circuit.parameters]
    for k in (2.0, 3.0):
        A = circuit.compiled(circuit.resolve({"k": k})).configurations[0].A
        assert A[0, 0] == pytest.approx(-1.0 / (k * 10e-6), rel=1e-14)
