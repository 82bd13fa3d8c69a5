"""Buck (step-down) converter: Vin -> switch -> L -> C || R, freewheeling diode to ground."""
from __future__ import annotations

import math

from .analytic import SmallRipple
from .pwm2 import PWMTwoState


class Buck(SmallRipple, PWMTwoState):
    name = "buck"
    title = "buck (step-down)"
    netlist_file = "buck.cir"
    topology = "buck"
    element_signals = {"i_in": "i(s1)", "i_switch": "i(s1)", "v_switch": "v(in,sw)", "i_diode": "i(d1)",
                       "v_diode": "v(0,sw)", "i_cap": "i(c1)"}

    @staticmethod
    def k_crit(D: float) -> float:
        return 1.0 - D

    @staticmethod
    def ccm_ratio(D: float) -> float:
        return D

    @staticmethod
    def dcm_ratio(D: float, K: float) -> float:
        return 2.0 / (1.0 + math.sqrt(1.0 + 4.0 * K / D ** 2))

    @staticmethod
    def dcm_diode_fraction(D: float, M: float) -> float:
        return D * (1.0 - M) / M
