"""Boost (step-up) converter: Vin -> L -> switch to ground, diode to C || R."""
from __future__ import annotations

import math

from .analytic import SmallRipple, finite_ratio
from .pwm2 import PWMTwoState


class Boost(SmallRipple, PWMTwoState):
    name = "boost"
    title = "boost (step-up)"
    netlist_file = "boost.cir"
    topology = "boost"
    element_signals = {"i_in": "i(l1)", "i_switch": "i(s1)", "v_switch": "v(sw)", "i_diode": "i(d1)",
                       "v_diode": "v(sw,out)", "i_cap": "i(c1)"}

    @staticmethod
    def k_crit(D: float) -> float:
        return D * (1.0 - D) ** 2

    @staticmethod
    def ccm_ratio(D: float) -> float:
        finite_ratio("boost", D)
        return 1.0 / (1.0 - D)

    @staticmethod
    def dcm_ratio(D: float, K: float) -> float:
        return (1.0 + math.sqrt(1.0 + 4.0 * D ** 2 / K)) / 2.0

    @staticmethod
    def dcm_diode_fraction(D: float, M: float) -> float:
        return D / (M - 1.0)
