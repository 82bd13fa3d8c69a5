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
