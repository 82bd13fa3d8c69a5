"""Number parsing with SPICE suffixes: the gate every value passes before a model or a netlist."""
import numpy as np
import pytest

from converters.errors import ParameterError
from converters.validate import parse_value


@pytest.mark.parametrize("text,value", [("100u", 1e-4), ("10u", 1e-5), ("2.2n", 2.2e-9), ("1meg", 1e6),
                                        ("100k", 1e5), ("4.7M", 4.7e-3), ("1e-3m", 1e-6), (".5", 0.5),
                                        ("-3", -3.0), (" 12 ", 12.0), (7, 7.0), (1e-9, 1e-9)])
def test_spice_suffixes(text, value):
    assert parse_value("x", text) == value


@pytest.mark.parametrize("text", ["1;shell", "R=1\n.control", "nan", "inf", "1e400", "", "1 2", "0x10", "1,5"])
def test_anything_but_a_plain_finite_number_is_refused(text):
    with pytest.raises(ParameterError, match=r"^x must be (a number|a finite number)"):
        parse_value("x", text)


def test_a_value_beyond_double_precision_is_refused_with_what_was_typed():
    with pytest.raises(ParameterError, match=r"^x must be 0 or at least 5e-324 in magnitude .*; got '1e-400'$"):
        parse_value("x", "1e-400")          # was read as 0 (while 1e-20 V is refused as implausible)
    assert parse_value("x", "1e-320") == 1e-320 and parse_value("x", "0e-400") == 0.0
    with pytest.raises(ParameterError, match=r"at most 1.8e308 in magnitude; got '99999999999999999999\.\.\.9999999999 "
                                             r"\(1000 characters\)'$"):
        parse_value("x", "9" * 1000)        # was "got inf"


@pytest.mark.parametrize("text,message", [
    ("1e99999999999999999999",
     "x must be a finite number, at most 1.8e308 in magnitude; got '1e99999999999999999999'"),
    ("-1e99999999999999999999",
     "x must be a finite number, at most 1.8e308 in magnitude; got '-1e99999999999999999999'"),
    ("1e-99999999999999999999", "x must be 0 or at least 5e-324 in magnitude"),
    ("0e99999999999999999999", None),                                  # zero whatever its exponent
    ("1e99999999999999999999u", "x must be a finite number, at most 1.8e308 in magnitude"),
    (10 ** 400, "x must be a finite number, at most 1.8e308 in magnitude; got an integer of 401 digits"),
    (-10 ** 5000, "x must be a finite number, at most 1.8e308 in magnitude; got an integer of 5001 digits"),
    (np.float64(1e300), None),
], ids=["exponent-huge", "exponent-huge-negative", "exponent-tiny", "zero-exponent-huge", "exponent-huge-suffix",
        "int-400-digits", "int-5001-digits", "float64"])
def test_an_exponent_or_an_integer_beyond_any_float_is_refused_naming_the_parameter(text, message):
    """decimal.InvalidOperation (an exponent beyond Decimal's), OverflowError (an int beyond a float) and
    ValueError "Exceeds the limit (4300 digits)" (its repr), naming nothing, before."""
    if message is None:
        assert parse_value("x", text) == float(text)
        return
    with pytest.raises(ParameterError) as refused:
        parse_value("x", text)
    assert str(refused.value).startswith(message), str(refused.value)


def test_an_integer_option_beyond_int64_is_refused_naming_it():
    from converters.validate import check_integer
    assert check_integer("periods", 2 ** 63 - 1, 1) == 2 ** 63 - 1
    for value, shown in ((2 ** 63, "9223372036854775808"), (10 ** 5000, "an integer of 5001 digits")):
        with pytest.raises(ParameterError) as refused:
            check_integer("periods", value, 1)
        assert str(refused.value) == f"periods must be an integer >= 1 (at most 2^63 - 1); got {shown}"
    with pytest.raises(ParameterError, match=r"^n must be an integer in \[0, 10\]; got an integer of 5001 digits$"):
        check_integer("n", -10 ** 5000, 0, 10)


def test_a_unit_on_a_value_without_one_is_refused():
    with pytest.raises(ParameterError, match=r"^x: the unit 'H' in '10uH' contradicts the parameter \(it takes no unit\)"):
        parse_value("x", "10uH")


@pytest.mark.parametrize("name, text, value", [
    ("L", "10uH", 10e-6), ("f_sw", "250kHz", 250e3), ("Vin", "48V", 48.0), ("C", "2.2nF", 2.2e-9),
    ("f_sw", "1meg", 1e6), ("f_sw", "1megHz", 1e6), ("R", "4.7kohm", 4700.0), ("R", "10 Ω", 10.0), ("L", "10u", 10e-6),
])
def test_values_as_spice_users_type_them(name, text, value):
    from converters.models import get_model
    assert get_model("buck").resolve({name: text})[name] == pytest.approx(value, rel=1e-15)


@pytest.mark.parametrize("name, text, message", [
    ("L", "10uF", "L: the unit 'F' in '10uF' contradicts the parameter (its unit is H)"),
    ("C", "100uH", "C: the unit 'H' in '100uH' contradicts the parameter (its unit is F)"),
    ("D", "0.5V", "D: the unit 'V' in '0.5V' contradicts the parameter (it takes no unit)"),
    ("f_sw", "1M", "f_sw: '1M' means milli in SPICE (M = m); did you mean 1meg?"),
    ("f_sw", "250MHz", "f_sw: '250MHz' means milli in SPICE (M = m); did you mean 250megHz?"),
    ("L", "1M", "L: '1M' means milli in SPICE (M = m); did you mean 1meg?"),
    ("L", "10u shell", "L: the unit 'shell' in '10u shell' contradicts the parameter"),
    ("L", "10u; .control", "L must be a number"),
])
def test_a_unit_that_contradicts_the_parameter_or_spices_milli_m_is_refused(name, text, message):
    from converters.models import get_model
    with pytest.raises(ParameterError) as info:
        get_model("buck").resolve({name: text})
    assert str(info.value).startswith(message)


def test_the_cli_takes_units_and_refuses_a_contradicting_one_in_one_line(capsys):
    from validation.cli import main
    assert main(["simulate", "buck", "-p", "Vin=48V", "-p", "f_sw=250kHz", "-p", "L=22uH", "-p", "D=0.25",
                 "--periods", "5", "--json"]) == 0
    capsys.readouterr()
    assert main(["simulate", "buck", "-p", "L=10uF", "--periods", "5"]) == 2
    err = capsys.readouterr().err.strip()
    assert err == "pcsuite: error: L: the unit 'F' in '10uF' contradicts the parameter (its unit is H)"


@pytest.mark.parametrize("call,error,message", [
    # a public entry point given what would be mangled, ignored or crash deep inside: one error naming it
    (lambda: __import__("converters.lcp", fromlist=["x"]).solve_lcp(np.eye(2) + 1j, -np.ones(2)), "LCPError",
     "M must be a matrix of real numbers; got complex values"),                  # the imaginary part was dropped
    (lambda: __import__("converters.lcp", fromlist=["x"]).solve_lcp([[True, False], [False, True]], -np.ones(2)),
     "LCPError", "M must be a matrix of real numbers; got boolean values"),
    (lambda: __import__("converters.lcp", fromlist=["x"]).solve_lcp([[10**400, 0], [0, 1]], -np.ones(2)), "LCPError",
     "M must be a numeric matrix of doubles; got [[1000"),                        # OverflowError traceback
    (lambda: __import__("converters.lcp", fromlist=["x"]).solve_lcp(np.eye(2), -np.ones(2), fast_paths="False"),
     "LCPError", "fast_paths must be True or False; got 'False'"),               # "False" was true
    (lambda: __import__("converters.run", fromlist=["x"]).run_converter(None), "ParameterError",
     "the converter must be one of buck, boost, buck-boost, cuk, prc, a netlist FILE.cir or a Model; "
     "got None"),                                                                  # AttributeError
    (lambda: __import__("converters.models", fromlist=["x"]).get_converter(["buck"]), "ParameterError",
     "CONVERTER must be one of buck, boost, buck-boost, cuk, prc or a netlist FILE.cir; got ['buck']"),   # unhashable
    (lambda: __import__("converters.run", fromlist=["x"]).run_converter("buck", "D=0.5"), "ParameterError",
     "params must be a dict of NAME: VALUE; got 'D=0.5'"),
    (lambda: __import__("converters.run", fromlist=["x"]).run_converter("buck", steady="no"), "ParameterError",
     "steady must be True or False; got 'no'"),                                  # was read as True
    (lambda: __import__("converters.run", fromlist=["x"]).run_converter("buck", periods=True), "ParameterError",
     "periods must be an integer >= 1; got True"),
    # beyond any float: decimal.InvalidOperation, OverflowError or "Exceeds the limit (4300 digits)" before
    (lambda: __import__("converters.run", fromlist=["x"]).run_converter("buck", {"L": "1e99999999999999999999"}),
     "ParameterError", "L must be a finite number, at most 1.8e308 in magnitude; got '1e99999999999999999999'"),
    (lambda: __import__("converters.run", fromlist=["x"]).run_converter("buck", {"L": 10 ** 400}), "ParameterError",
     "L must be a finite number, at most 1.8e308 in magnitude; got an integer of 401 digits"),
    (lambda: __import__("converters.run", fromlist=["x"]).run_converter("buck", {"D": 10 ** 5000}), "ParameterError",
     "D must be a finite number, at most 1.8e308 in magnitude; got an integer of 5001 digits"),
    (lambda: __import__("converters.run", fromlist=["x"]).run_converter("buck", h="1e99999999999999999999"),
     "ParameterError", "h must be a finite number, at most 1.8e308 in magnitude"),
    (lambda: __import__("converters.run", fromlist=["x"]).run_converter("buck", h=10 ** 400), "ParameterError",
     "h must be a finite number, at most 1.8e308 in magnitude; got an integer of 401 digits"),
    (lambda: __import__("converters.run", fromlist=["x"]).run_converter("buck", t_end=10 ** 400), "ParameterError",
     "t_end must be a finite number, at most 1.8e308 in magnitude; got an integer of 401 digits"),
    (lambda: __import__("converters.run", fromlist=["x"]).run_converter("buck", periods=10 ** 400), "ParameterError",
     "periods must be an integer >= 1 (at most 2^63 - 1); got an integer of 401 digits"),
    (lambda: __import__("converters.run", fromlist=["x"]).run_converter("buck", periods=10 ** 5000), "ParameterError",
     "periods must be an integer >= 1 (at most 2^63 - 1); got an integer of 5001 digits"),
])
def test_the_python_api_refuses_what_it_would_mangle(call, error, message):
    with pytest.raises(Exception) as refused:
        call()
    assert type(refused.value).__name__ == error and str(refused.value).startswith(message)


def test_a_state_that_leaves_the_finite_numbers_is_an_error_not_a_trajectory():
    from converters.errors import SimulationError
    from converters.methods import EventDriven, Theta
    from .oracle_circuits import diode_bridge
    from converters.run import run_converter
    from converters.simulate import simulate
    for method in (Theta(h=1e-6), EventDriven()):
        with pytest.raises(SimulationError, match=r"the state left the finite numbers at t = "):
            with np.errstate(all="ignore"):
                simulate(diode_bridge(), method, x0=[-1e308, 1e308])     # returned inf and NaN before
    run = run_converter("buck", periods=5)
    for window in ({"periods": np.nan}, {"t0": np.nan}, {"periods": -1.0}):  # NaN meant the whole run
        with pytest.raises(ValueError):
            run.mean("vout", **window)


def test_an_unknown_signal_is_a_key_error_the_command_line_reports_in_one_line():
    from converters.run import run_converter
    run = run_converter("buck", periods=3)
    for call in (lambda: run.mean("nope"), lambda: run.to_pandas(columns=["time", "nope"])):
        with pytest.raises(KeyError) as refused:                      # still a lookup error by name
            call()
        assert isinstance(refused.value, ValueError) and "got 'nope'" in str(refused.value)
        assert not str(refused.value).startswith("'")                 # the message, not its repr


@pytest.mark.parametrize("build,message", [
    (lambda: __import__("converters.problems.switching", fromlist=["x"]).Relay(None, 0, 1),
     "function must be a SwitchingFunction; got None"),               # an AttributeError later, before
    (lambda: __import__("converters.problems.switching", fromlist=["x"]).StateSwitching(None, 0, 1),
     "function must be a SwitchingFunction; got None"),
    (lambda: __import__("converters.analysis.bifurcation", fromlist=["x"]).brute_force(None, None, "abc", [0.0]),
     "values must be finite numbers, at least one; got 'abc'"),        # numpy's words, no parameter
])
def test_switching_laws_and_diagrams_refuse_what_fails_later(build, message):
    with pytest.raises(ParameterError) as refused:
        build()
    assert str(refused.value) == message
