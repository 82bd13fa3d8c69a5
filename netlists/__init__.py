"""ngspice netlists of the converters, generated from the same parameter sets the LCS uses."""
from .build import (Netlist, SpiceOptions, build_netlist, build_smc_netlist, build_voltage_mode_netlist,
                    model_netlist, standalone, standard_netlist)

__all__ = ["Netlist", "SpiceOptions", "build_netlist", "build_smc_netlist", "build_voltage_mode_netlist", "model_netlist",
           "standalone", "standard_netlist"]
