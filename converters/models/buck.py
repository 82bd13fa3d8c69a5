"""Buck (step-down) converter: Vin -> switch -> L -> C || R, freewheeling diode to ground."""
from .pwm2 import PWMTwoState


class Buck(PWMTwoState):
    name = "buck"
    title = "buck (step-down)"
    netlist_file = "buck.cir"
    topology = "buck"
