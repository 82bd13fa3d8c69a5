"""Inverting buck-boost converter: Vin -> switch -> L to ground, diode from the (negative) output.

The state holds |vo|; ``vout`` is negative.
"""
import math

from .analytic import SmallRipple, finite_ratio
from .pwm2 import PWMTwoState


class BuckBoost(SmallRipple, PWMTwoState):
    name = "buck-boost"
    title = "buck-boost (inverting)"
    netlist_file = "buck-boost.cir"
    topology = "buck-boost"

    @staticmethod
    def k_crit(D):
        return (1.0 - D) ** 2

    @staticmethod
    def ccm_ratio(D):
        finite_ratio("buck-boost", D)
        return -D / (1.0 - D)

    @staticmethod
    def dcm_ratio(D, K):
        return -D / math.sqrt(K)

    @staticmethod
    def dcm_diode_fraction(D, M):
        return D / M
