"""``python -m netlists``: write the standard netlist of each converter to ``netlists/<converter>.cir`` (a test
checks the files match what the builder makes)."""
from pathlib import Path

from .build import standard_netlist

CONVERTERS = ("buck", "boost", "buck-boost", "cuk", "prc")

if __name__ == "__main__":
    here = Path(__file__).resolve().parent
    for name in CONVERTERS:
        (here / f"{name}.cir").write_text(standard_netlist(name))
        print(f"wrote {here / f'{name}.cir'}")
