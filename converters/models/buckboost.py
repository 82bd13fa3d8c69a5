"""Inverting buck-boost converter: Vin -> switch -> L to ground, diode from the (negative) output.

The state holds |vo|; ``vout`` is negative.
"""
from .analytic import InvertingRatios
from .pwm2 import PWMTwoState


class BuckBoost(InvertingRatios, PWMTwoState):
    name = "buck-boost"
    title = "buck-boost (inverting)"
    netlist_file = "buck-boost.cir"
    topology = "buck-boost"
    element_signals = {"i_in": "i(s1)", "i_switch": "i(s1)", "v_switch": "v(in,sw)", "i_diode": "i(d1)",
                       "v_diode": "v(out,sw)", "i_cap": "i(c1)"}
