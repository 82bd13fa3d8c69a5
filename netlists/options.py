"""What every netlist pcsuite writes for ngspice shares: the transient settings (:class:`SpiceOptions`), the
netlist with its probes (:class:`Netlist`), and the only way a value enters the text (:func:`_num`: a finite
float, formatted here; nothing typed by a user reaches a netlist otherwise)."""
from __future__ import annotations

import math
from dataclasses import dataclass, field

from converters.errors import ParameterError
from converters.validate import parse_value


#: ngspice's default ABSTOL in A.
NGSPICE_ABSTOL = 1e-12


@dataclass(frozen=True)
class SpiceOptions:
    """Transient settings. ``tmax`` defaults to T/200; ``method`` is 'trap' or 'gear'."""

    tmax_fraction: float = 1.0 / 200.0
    reltol: float = 1e-3
    method: str = "gear"
    diode_n: float = 0.001
    diode_is: float = 1e-14
    switch_ron: float = 1e-3
    switch_roff: float = 1e6
    # The gate's edge: ngspice's SW switch changes state at the first time point past its threshold, and where its
    # time points fall inside the edge shifts with the rounding of t from period to period: at 1e-4 T a 48 V ->
    # 12 V buck's switch-on moved by up to ~36 ps, its steady mean wandering between levels 34 ppm apart for
    # thousands of periods (RELTOL and TMAX changed nothing); at 1e-6 T it settles in 90 periods.
    edge_fraction: float = 1e-6
    # ngspice's own ABSTOL (then not written); the power-electronics tolerances (CONVERGENCE_FALLBACK) loosen it.
    abstol: float = NGSPICE_ABSTOL
    # The diodes' junction capacitance CJO in F (0: none, the near-ideal default).
    diode_cjo: float = 0.0

    def __post_init__(self):
        for name in ("tmax_fraction", "reltol", "diode_n", "diode_is", "switch_ron", "switch_roff", "edge_fraction",
                     "abstol", "diode_cjo"):
            value = parse_value(name, getattr(self, name))
            if value < 0 or (value == 0 and name != "diode_cjo"):
                raise ParameterError(f"{name} must be {'non-negative' if name == 'diode_cjo' else 'positive'}; "
                                     f"got {value!r}")
            object.__setattr__(self, name, value)
        if self.method not in ("trap", "gear"):
            raise ParameterError(f"method must be one of trap, gear; got {self.method!r}")


@dataclass(frozen=True)
class Netlist:
    text: str
    converter: str
    params: dict
    t_end: float
    options: SpiceOptions
    # state name -> (vector, sign) or ((vector_a, vector_b), sign) difference, see validation.spice;
    # "switch" -> ({vector: coefficient}, threshold): the switch is on where the combination >= threshold
    probes: dict = field(default_factory=dict)
    #: Probe names of each complementarity pair's device current, in the model's pair order.
    pairs: tuple = ("i_D",)


def _num(name: str, value) -> str:
    """The only way a value enters a netlist: a finite float, formatted here."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        value = parse_value(name, value)
    value = float(value)
    if not math.isfinite(value):
        raise ParameterError(f"{name} must be a finite number for the netlist; got {value!r}")
    return f"{value:.12g}"


def diode_parameters(options: SpiceOptions) -> str:
    """The near-ideal diode's ``.model`` parameters: IS, N, and CJO where the options give one."""
    text = f"IS={_num('diode_is', options.diode_is)} N={_num('diode_n', options.diode_n)}"
    return text + (f" CJO={_num('diode_cjo', options.diode_cjo)}" if options.diode_cjo else "")


def options_line(options: SpiceOptions, extra: str = "") -> str:
    """The ``.options`` line every pcsuite netlist carries."""
    abstol = f" ABSTOL={_num('abstol', options.abstol)}" if options.abstol != NGSPICE_ABSTOL else ""
    return f".options RELTOL={_num('reltol', options.reltol)}{abstol} METHOD={options.method} ITL4=100{extra}"
