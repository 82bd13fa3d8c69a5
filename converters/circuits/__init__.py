"""Circuits from SPICE netlists: read (:mod:`.netlist`) and compiled by modified nodal analysis into a linear
complementarity system (:mod:`.compile`); :class:`converters.models.netlist.Circuit` makes one a model like the
built-in ones."""
from .compile import Compiled, compile_netlist
from .netlist import NetlistError, read_netlist

__all__ = ["Compiled", "compile_netlist", "NetlistError", "read_netlist"]
