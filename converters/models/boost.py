"""Boost (step-up) converter: Vin -> L -> switch to ground, diode to C || R."""
from .pwm2 import PWMTwoState


class Boost(PWMTwoState):
    name = "boost"
    title = "boost (step-up)"
    netlist_file = "boost.cir"
    topology = "boost"
