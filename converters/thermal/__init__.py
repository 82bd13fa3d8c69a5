"""Device losses and junction temperatures: loss tables read as PLECS reads them, Foster and Cauer chains, and the
descriptions engineers already have (PLECS's XML thermal description, or a plain table file)."""
from .chains import ThermalChain
from .description import DeviceDescription, parse_plecs, parse_table, read_description
from .tables import Table, energy_table, on_state_table

__all__ = ["ThermalChain", "DeviceDescription", "parse_plecs", "parse_table", "read_description", "Table",
           "energy_table", "on_state_table"]
