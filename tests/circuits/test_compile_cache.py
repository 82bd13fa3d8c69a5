"""What a sweep keeps between compiles of one netlist at new values: the diodes' port forms per configuration and
each expression's parse tree. A compile with them equals a compile without them; where values change which
forms solve the network (a controlled source's gain), the forms are searched again. A sweep chunk's points
compiled together (compile_points) and read by rebinding values (with_values) equal each read and compiled alone."""
from pathlib import Path

import numpy as np
import pytest

from converters.circuits import compile as compiler
from converters.circuits.compile import compile_netlist
from converters.circuits.expressions import evaluate
from converters.circuits.netlist import read_netlist, with_values
from converters.errors import ParameterError
from converters.models import Circuit

NETLISTS = Path(__file__).resolve().parents[2] / "netlists" / "circuits"
#: The inverters' 20 ms periods hold ~1,600 switchings: seconds to compile twice (the slow tier).
SLOW = {"full-bridge", "three-phase-inverter"}
FILES = [pytest.param(path, marks=pytest.mark.slow) if path.stem in SLOW else path
         for path in sorted(NETLISTS.glob("*.cir"))]


def _same(a, b):
    assert a.pair_currents == b.pair_currents and a.state_names == b.state_names
    for x, y in zip(a.configurations, b.configurations, strict=True):
        for name in "ABCDEF":
            np.testing.assert_array_equal(getattr(x, name), getattr(y, name))
    for x, y in zip(a.signal_maps, b.signal_maps, strict=True):
        for m, n in zip(x, y, strict=True):
            np.testing.assert_array_equal(m, n)


@pytest.mark.parametrize("path", FILES, ids=lambda p: p.stem)
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


# --- compiles made together (a sweep chunk's points: compile_points) and reads without reading (with_values) ---

def _varied(circuit, rng, count: int) -> list[dict]:
    """``count`` parameter sets of ``circuit``: its R, L, C values each spread by 5 % (normal)."""
    p = circuit.resolve({})
    names = [q.name for q in circuit.parameters if q.unit in ("ohm", "H", "F") and p.get(q.name)]
    return [{**p, **{name: p[name] * (1 + 0.05 * rng.standard_normal()) for name in names}} for _ in range(count)]


@pytest.mark.parametrize("path", FILES, ids=lambda p: p.stem)
def test_netlists_compiled_together_equal_each_compiled_alone_to_the_bit(path):
    """Every shipped netlist at five sets of R, L, C values: compile_points stamps and solves them as one stack
    (each circuit's G per point, its R shared); every matrix and signal map, x0 and the schedule equal a compile
    of each alone, to the bit. A circuit the stack cannot take (a comparator's law depends on the values) gives
    None for all but the first point."""
    circuit = Circuit.from_netlist(path)
    netlists = [read_netlist(circuit.netlist.text, overrides=p, name=str(path))
                for p in _varied(circuit, np.random.default_rng(7), 5)]
    together = compiler.compile_points(netlists)
    first = compiler._Compiler(netlists[0])
    first.run()
    for netlist, compiled in zip(netlists, together):
        if compiled is None:
            assert not first.batchable()
            continue
        alone = compile_netlist(netlist)
        _same(compiled, alone)
        np.testing.assert_array_equal(compiled.x0, alone.x0)
        assert repr(compiled.law) == repr(alone.law) and compiled.period == alone.period
        for x, y in zip(compiled.inputs or (), alone.inputs or (), strict=True):
            np.testing.assert_array_equal(x, y)
    assert sum(c is not None for c in together) == (5 if first.batchable() else 1)


def test_a_point_whose_values_change_the_structure_or_make_it_singular_is_compiled_alone():
    """Points of GAIN at g = 1 (the diode's port its current), g = 0 (that port singular: the search gives its
    voltage) and g = 2: g = 0 is None in the stack (its own compile takes it), the others compile together. A
    resistor set to 0 (a short: a branch of its own) is another structure: its own group."""
    compiler._FORMS.clear()                     # no forms kept from another test's g = 0 (the voltage port)
    netlists = [read_netlist(GAIN, overrides={"g": g}, name="gain.cir") for g in (1.0, 0.0, 2.0)]
    together = compiler.compile_points(netlists)
    assert together[1] is None and together[0] is not None and together[2] is not None
    _same(together[2], compile_netlist(netlists[2]))
    assert compile_netlist(netlists[1]).pair_currents == ((False,),)
    shorted = [read_netlist(GAIN, overrides={"r1": r}, name="gain.cir") for r in (10.0, 0.0, 20.0)]
    assert len({compiler._structure(n) for n in shorted}) == 2
    for netlist, compiled in zip(shorted, compiler.compile_points(shorted), strict=True):
        _same(compiled, compile_netlist(netlist))


GATE = """a buck whose gate compares a DC level with a sawtooth (Vc: its duty ratio)
.param vc=0.4
Vin in 0 DC 12
Vc c 0 DC {vc}
Vramp ramp 0 PULSE(0 1 0 10u 1n 1n 10.002u)
Egate g 0 c ramp 1
S1 in sw g 0 SW
D1 0 sw DM
L1 sw out 100u
C1 out 0 10u
R1 out 0 5
.model SW SW(VT=0 RON=0.01)
.model DM D
.tran 10n 1m
.end
"""


def test_a_gate_level_that_moves_the_schedule_is_not_stamped_with_another_points_schedule():
    """Vc is a DC source in the gate's control: its value sets the switching instants, so a point at another Vc
    is compiled alone (its own schedule), while one at another R1 shares the stack."""
    netlists = [read_netlist(GATE, overrides=o, name="gate.cir")
                for o in ({"vc": 0.4}, {"vc": 0.6}, {"vc": 0.4, "r1": 7.0})]
    together = compiler.compile_points(netlists)
    assert together[1] is None and together[2] is not None
    alone = compile_netlist(netlists[1])
    assert repr(alone.law) != repr(together[0].law)
    _same(together[2], compile_netlist(netlists[2]))


@pytest.mark.parametrize("path", FILES, ids=lambda p: p.stem)
def test_a_netlist_rebound_to_new_values_equals_the_reader_s_or_is_refused(path):
    """with_values on every parameter of every shipped netlist (moved 3 %, a coupling moved down): where it takes
    the change (a .param that only element values name, or an element's own value) the netlist equals the reader's
    at those values, field by field; where it does not (a .param in a model, a waveform, another .param or .tran)
    it gives None. At least the R, L, C values are taken."""
    circuit = Circuit.from_netlist(path)
    p = circuit.resolve({})
    base = read_netlist(circuit.netlist.text, overrides=p, name=str(path))
    taken = set()
    for q in circuit.parameters:
        if not p.get(q.name):
            continue
        value = p[q.name] * (0.997 if q.high == 1.0 else 1.03)
        rebound = with_values(base, {q.name: value})
        if rebound is not None:
            assert rebound == read_netlist(circuit.netlist.text, overrides={**p, q.name: value}, name=str(path))
            taken.add(q.name)
    assert {q.name for q in circuit.parameters if q.unit in ("ohm", "H", "F") and p.get(q.name)} <= taken


def test_a_rebinding_is_refused_where_the_parameter_reaches_more_than_element_values():
    """buck.cir: L and R feed element values alone (taken); Ron a .model's RON, f_sw the gate's PULSE and the
    derived T, T itself derived: each refused (None), as is a name the netlist does not have and a value the
    reader would refuse (a negative inductance)."""
    netlist = read_netlist(NETLISTS / "buck.cir")
    assert with_values(netlist, {"l": 20e-6, "r": 5.0}) is not None
    for changed in ({"ron": 0.1}, {"f_sw": 200e3}, {"t": 1e-5}, {"nothing": 1.0}, {"l": -1e-6}):
        assert with_values(netlist, changed) is None, changed


DIVIDED = """a buck whose gate reaches its switch through a divider (R2 sets the control's amplitude, so its instants)
Vin in 0 DC 12
Vg g 0 PULSE(0 2 0 2u 2u 3u 10u)
R2 g c 1k
R3 c 0 1k
S1 in sw c 0 SW
D1 0 sw DM
L1 sw out 100u
C1 out 0 10u
R1 out 0 5
.model SW SW(VT=0.5)
.model DM D
.tran 10n 1m
.end
"""


def test_a_value_in_a_gate_s_path_that_moves_the_schedule_is_compiled_alone():
    """R2 divides the gate's PULSE before the switch's threshold: at 3 kohm the control crosses 0.5 V later than at
    1 kohm (another schedule), so that point is compiled alone; a point at another load R1 shares the stack."""
    netlists = [read_netlist(DIVIDED, overrides=o, name="divided.cir") for o in ({}, {"r2": 3e3}, {"r1": 7.0})]
    together = compiler.compile_points(netlists)
    assert together[1] is None and together[2] is not None
    assert repr(compile_netlist(netlists[1]).law) != repr(together[0].law)
    _same(together[2], compile_netlist(netlists[2]))
