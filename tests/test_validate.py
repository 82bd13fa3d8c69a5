"""Number parsing with SPICE suffixes: the gate every value passes before a model or a netlist."""
import pytest

from converters.errors import ParameterError
from converters.validate import parse_value


@pytest.mark.parametrize("text,value", [("100u", 1e-4), ("10u", 1e-5), ("2.2n", 2.2e-9), ("1meg", 1e6),
                                        ("100k", 1e5), ("4.7M", 4.7e-3), ("1e-3m", 1e-6), (".5", 0.5),
                                        ("-3", -3.0), (" 12 ", 12.0), (7, 7.0), (1e-9, 1e-9)])
def test_spice_suffixes(text, value):
    assert parse_value("x", text) == value


@pytest.mark.parametrize("text", ["10uH", "1;shell", "R=1\n.control", "nan", "inf", "1e400", "", "1 2",
                                  "0x10", "1,5"])
def test_anything_but_a_plain_finite_number_is_refused(text):
    with pytest.raises(ParameterError, match=r"^x must be (a number|a finite number)"):
        parse_value("x", text)
