"""Operating points, scene defaults and pass/fail thresholds, read once from ``data/defaults.toml``.

Everything that decides pass or fail, or names a standard operating point, lives in that one file;
scenes, the report, the tests and the benchmarks read it from here.
"""
from __future__ import annotations

import tomllib
from pathlib import Path

DEFAULTS_FILE = Path(__file__).with_name("data") / "defaults.toml"
_DATA = tomllib.loads(DEFAULTS_FILE.read_text())

#: Thresholds per study (``compare``, ``smc``, ``smc-implicit``, ``closed_form``).
THRESHOLDS: dict[str, dict[str, float]] = {study: dict(values) for study, values in _DATA["thresholds"].items()}
#: Checks whose threshold is a minimum (every other threshold is a maximum).
AT_LEAST = frozenset({"mode_agreement", "mode_time_agreement"})
#: (converter, parameters, expected mode) checked against the closed forms.
OPERATING_POINTS: list[tuple[str, dict, str]] = [(p["converter"], dict(p["params"]), p["mode"])
                                                 for p in _DATA["operating_points"]]
#: The trade-off cases: name, converter, parameters.
TRADEOFF_CASES: list[dict] = [dict(case) for case in _DATA["tradeoff_cases"]]
#: The stability map's base point.
STABILITY_BASE: dict = dict(_DATA["stability_base"])
#: D-K maps: K range per converter, the D range, the band around the closed-form boundary.
K_RANGES: dict[str, tuple] = {name: tuple(r) for name, r in _DATA["dk_maps"]["k_range"].items()}
D_RANGE: tuple = tuple(_DATA["dk_maps"]["d_range"])
BOUNDARY_BAND: float = _DATA["dk_maps"]["boundary_band"]
#: The bifurcation study: model, path, diagram and ngspice settings, and the published values it is checked against.
BIFURCATION: dict = {key: value for key, value in _DATA["bifurcation"].items() if key != "published"}
PUBLISHED_BIFURCATIONS: dict = dict(_DATA["bifurcation"]["published"])
#: The mechanical module: the seed's sliding bifurcations and the report's ranges and thresholds.
MECHANICS: dict = {key: value for key, value in _DATA["mechanics"].items() if key not in ("sliding", "quick")}
SEED_SLIDING: list[dict] = [dict(row) for row in _DATA["mechanics"]["sliding"]]
#: What the report's quick form of the mechanics sections changes in MECHANICS (``[mechanics.quick]``).
MECHANICS_QUICK: dict = dict(_DATA["mechanics"]["quick"])


def mechanics_settings(full: bool = True) -> dict:
    """MECHANICS, or its quick form (``[mechanics.quick]`` over it: a table's keys replaced one by one)."""
    if full:
        return MECHANICS
    return {key: ({**value, **MECHANICS_QUICK[key]} if isinstance(value, dict) else MECHANICS_QUICK[key])
            if key in MECHANICS_QUICK else value for key, value in MECHANICS.items()}


def passes(check: str, value: float, threshold: float) -> bool:
    """A check's verdict: value >= threshold for the AT_LEAST checks, value <= threshold otherwise."""
    return bool(value >= threshold) if check in AT_LEAST else bool(value <= threshold)
