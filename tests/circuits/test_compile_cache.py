"""What a sweep keeps between compiles of one netlist at new values: the diodes' port forms per configuration and
each expression's parse tree. A compile with them equals a compile without them; where values change which
forms solve the network (a controlled source's gain), the forms are searched again."""
from pathlib import Path

import numpy as np
import pytest

from converters.circuits import compile as compiler
from converters.circuits.compile import compile_netlist
from converters.circuits.expressions import evaluate
from converters.circuits.netlist import read_netlist
from converters.errors import ParameterError
from converters.models import Circuit

NETLISTS = Path(__file__).resolve().parents[2] / "netlists" / "circuits"


def _same(a, b):
    assert a.pair_currents == b.pair_currents and a.state_names == b.state_names
    for x, y in zip(a.configurations, b.configurations, strict=True):
        for name in "ABCDEF":
            np.testing.assert_array_equal(getattr(x, name), getattr(y, name))
    for x, y in zip(a.signal_maps, b.signal_maps, strict=True):
        for m, n in zip(x, y, strict=True):
            np.testing.assert_array_equal(m, n)


@pytest.mark.parametrize("path", sorted(NETLISTS.glob("*.cir")), ids=lambda p: p.stem)
def test_a_compile_at_moved_values_with_the_kept_forms_equals_a_fresh_one(path):
    """Every shipped netlist, compiled at its values (the forms kept), then with each R, L and C parameter moved by
    7 %: the same LCS as a compile with nothing kept."""
    circuit = Circuit.from_netlist(path)
    p = circuit.resolve({})
    circuit.compiled(p)
    moved = {q.name: 1.07 * p[q.name] for q in circuit.parameters
             if q.unit in ("ohm", "H", "F") and p.get(q.name)}
    netlist = read_netlist(circuit.netlist.text, overrides=moved, name=str(path))
    kept = compile_netlist(netlist)
    compiler._FORMS.clear()
    _same(kept, compile_netlist(netlist))


GAIN = """a diode whose current only a controlled conductance can take (G1's gain g)
.param g=1
Vin in 0 DC 5
R1 in a 10
D1 a b DM
L1 b 0 1m
G1 b 0 b 0 {g}
.model DM D
.tran 1u 1m
.end
"""


def test_forms_kept_at_one_gain_are_searched_again_where_another_makes_them_singular():
    """At g = 1 node b has a path (the VCCS's conductance): the diode's port is its current. At g = 0 only the
    inductor reaches b, which fixes the diode's current: its port must be its voltage. Compiled at g = 0 after g = 1
    (the current form kept), the compile searches again and equals a fresh one; kept blindly it would be singular."""
    compiler._FORMS.clear()
    at_one = compile_netlist(read_netlist(GAIN, overrides={"g": 1.0}, name="gain.cir"))
    assert at_one.pair_currents == ((True,),)
    at_zero = compile_netlist(read_netlist(GAIN, overrides={"g": 0.0}, name="gain.cir"))
    assert at_zero.pair_currents == ((False,),)
    compiler._FORMS.clear()
    _same(at_zero, compile_netlist(read_netlist(GAIN, overrides={"g": 0.0}, name="gain.cir")))


def test_a_kept_parse_tree_reports_each_callers_own_name_and_values():
    """One text, parsed once: its value follows each caller's parameters, and a failure names each caller."""
    assert evaluate("{2*a + 1}", {"a": 1.0}) == 3.0
    assert evaluate("{2*a + 1}", {"a": 5.0}) == 11.0
    for what in ("R1 value", "C2 value"):
        with pytest.raises(ParameterError, match=rf"^{what}: 'b' is not a parameter"):
            evaluate("{2*b + 1}", {"a": 1.0}, what)
        with pytest.raises(ParameterError, match=rf"^{what}: a '\)' is missing"):
            evaluate("{(1+2}", {}, what)
