"""``python -m netlists [DIR]``: write the standard netlist of each converter (defaults, ``STANDARD_PERIODS`` periods
from rest, ``.meas`` over the last 10) to ``DIR/<converter>.cir`` (default: the current directory), for ngspice to
run on its own. They are built on demand, never shipped: the circuits they come from are ``netlists/circuits``'s."""
import sys
from pathlib import Path

from .build import standard_netlist

CONVERTERS = ("buck", "boost", "buck-boost", "cuk", "prc")

if __name__ == "__main__":
    here = Path(sys.argv[1] if len(sys.argv) > 1 else ".")
    if not here.is_dir():
        sys.exit(f"python -m netlists: DIR must be an existing directory; got {str(here)!r}")
    for name in CONVERTERS:
        path = here / f"{name}.cir"
        path.write_text(standard_netlist(name))
        print(f"wrote {path}")
