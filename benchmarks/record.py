"""A benchmark's measured figures, written to ``benchmarks/results/NAME.json`` for the docs to quote.

Every cost the README and the docs state (a time, a rate, a memory peak, a ratio against a peer) is a figure one
benchmark recorded here, with the date and the machine it was measured on; the docs build substitutes it
(``docs/hooks/figures.py``: ``{{ fig:NAME.KEY }}``, ``{{ table:NAME }}``, ``{{ measured:NAME }}``) and
``tests/test_figures.py`` checks that no other cost figure is written into a page. A benchmark prints what it
measures as before and, at its end, ``figures.save()``; ``make bench`` runs them all. Older figures are history:
they go to the changelog, not back into the pages.

Formatting lives here too (``format_value``), so the hook, the test and a benchmark's own print agree.
"""
from __future__ import annotations

import datetime
import json
import math
import os
import platform
import sys
import tempfile
from pathlib import Path
from typing import Any

RESULTS = Path(__file__).resolve().parent / "results"
#: Where ``save()`` writes: ``PCSUITE_FIGURES_DIR`` sends a trial run's figures elsewhere (the committed ones stay).
OUTPUT = Path(os.environ.get("PCSUITE_FIGURES_DIR") or RESULTS)


def machine() -> dict[str, Any]:
    """What the figures were measured on: CPU model and count, the load when the run started, the versions."""
    model = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    versions = {"python": platform.python_version()}
    for name in ("numpy", "scipy", "numba"):
        module = sys.modules.get(name)
        if module is not None:
            versions[name] = getattr(module, "__version__", "?")
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    return {"cpu": model, "cores": os.cpu_count(), "load_1min": round(load, 2), "system": platform.system(),
            **versions}


def format_value(value: float, digits: int = 3) -> str:
    """``value`` to ``digits`` significant figures, thousands separated (1,291; 0.46; 4.9; 562; 3.8e-7)."""
    if value is None or not math.isfinite(value):
        return str(value)
    if value == 0:
        return "0"
    magnitude = math.floor(math.log10(abs(value)))
    if magnitude < -3 or magnitude >= 9:              # an error or a count of many digits: 3.8e-7, 2.1e+12
        mantissa, exponent = f"{value:.{digits - 1}e}".split("e")
        return f"{mantissa}e{int(exponent)}"
    decimals = max(0, digits - 1 - magnitude)
    rounded = round(value, decimals)
    return f"{rounded:,.{decimals}f}" if decimals else f"{rounded:,.0f}"


class Figures:
    """The figures of one benchmark run, saved atomically as ``results/NAME.json``.

    ``add(key, value, unit, label, target=None, digits=3)``: ``key`` names it in the docs (``NAME.KEY``), ``label``
    says what was measured in words (the docs' table shows it), ``target`` the goal it is held to, if any.
    """

    def __init__(self, name: str, about: str) -> None:
        if not name.isidentifier():
            raise ValueError(f"name: a benchmark's name is an identifier, got {name!r}")
        self.name = name
        self.about = about
        self.started = datetime.datetime.now(datetime.timezone.utc)
        self.machine = machine()
        self.figures: dict[str, dict[str, Any]] = {}

    def add(self, key: str, value: float, unit: str, label: str, target: str | None = None,
            digits: int = 3) -> float:
        if not key.isidentifier():
            raise ValueError(f"key: a figure's key is an identifier, got {key!r}")
        value = float(value)
        self.figures[key] = {"value": value, "unit": unit, "label": label, "digits": digits,
                             **({"target": target} if target else {})}
        return value

    def save(self, directory: Path = OUTPUT) -> Path:
        directory.mkdir(parents=True, exist_ok=True)
        record = {"benchmark": self.name, "about": self.about,
                  "date": self.started.strftime("%Y-%m-%d"), "started_utc": self.started.isoformat(timespec="seconds"),
                  "command": " ".join(["python", f"benchmarks/{self.name}.py", *sys.argv[1:]]), "machine": self.machine,
                  "figures": self.figures}
        path = directory / f"{self.name}.json"
        handle, temporary = tempfile.mkstemp(dir=directory, prefix=f".{self.name}.", suffix=".tmp")
        with os.fdopen(handle, "w") as stream:
            json.dump(record, stream, indent=1)
            stream.write("\n")
        os.chmod(temporary, 0o644)                   # mkstemp's 0600 would keep the figures from other readers
        os.replace(temporary, path)
        print(f"figures written to {path}")
        return path


def load(directory: Path = RESULTS) -> dict[str, dict[str, Any]]:
    """Every saved benchmark's record by name."""
    return {path.stem: json.loads(path.read_text()) for path in sorted(directory.glob("*.json"))}


def render(record: dict[str, Any], key: str) -> str:
    """One figure as the docs print it: ``4.9 ns/step``, ``562x``."""
    figure = record["figures"][key]
    text = format_value(figure["value"], figure.get("digits", 3))
    unit = figure["unit"]
    return text + unit if unit in ("x", "%") else f"{text} {unit}".rstrip()


def measured(record: dict[str, Any]) -> str:
    m = record["machine"]
    return (f"measured {record['date']} by `{record['command']}` on {m['cores']} cores of {m['cpu']} "
            f"(load {m['load_1min']} at the start)")


def table(record: dict[str, Any], keys: list[str] | None = None) -> str:
    """A benchmark's figures (``keys``, or all) as a Markdown table, with where and when they were measured."""
    rows = ["| measured | value | target |", "|---|---|---|"]
    for key in keys or list(record["figures"]):
        figure = record["figures"][key]
        rows.append(f"| {figure['label']} | {render(record, key)} | {figure.get('target', '')} |")
    return "\n".join(rows) + f"\n\n*{record['about']}: {measured(record)}.*\n"
