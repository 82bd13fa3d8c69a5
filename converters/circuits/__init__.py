"""Circuits from SPICE netlists: read (:mod:`.netlist`), compiled by modified nodal analysis into a linear
complementarity system (:mod:`.compile`), and wrapped as a model like the built-in ones (:mod:`.model`)."""
from .model import Circuit, is_netlist
from .netlist import NetlistError, read_netlist

__all__ = ["Circuit", "is_netlist", "NetlistError", "read_netlist"]
