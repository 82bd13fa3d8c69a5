"""Named parameter sets: data with units and ranges, validated in one place.

An unknown name gets an error listing the valid ones; a value outside its range gets an error
naming the parameter, the range and the value. Values accept SPICE suffixes (``10u``, ``100k``).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from .errors import ParameterError
from .validate import parse_value


#: Physically plausible magnitudes by unit (beyond them a value is a slip: 1e300 H, 1e-300 Hz), on top of each
#: parameter's own range; wide enough for the stability map's extremes (L, C 1e-9 .. 0.1, R 1e-3 .. 1e9).
PLAUSIBLE = {"H": (1e-15, 1e4), "F": (1e-18, 1e4), "ohm": (1e-12, 1e15), "Hz": (1e-6, 1e12), "V": (1e-12, 1e7),
             "A": (1e-12, 1e7), "s": (1e-15, 1e9)}


@dataclass(frozen=True)
class Param:
    """One parameter: default (None = optional, only modelled when given), unit, meaning, valid range."""

    name: str
    default: float | None
    unit: str
    doc: str
    low: float = 0.0
    high: float = math.inf
    low_open: bool = True      # (low, ...] by default: strictly positive
    high_open: bool = True

    def check(self, value: object) -> float:
        value = parse_value(self.name, value, self.unit)
        below = value <= self.low if self.low_open else value < self.low
        above = value >= self.high if self.high_open else value > self.high
        if below or above:
            raise ParameterError(f"{self.name} ({self.doc}) must be in {self.range_text()} {self.unit}".rstrip()
                                 + f"; got {value!r}")
        low, high = PLAUSIBLE.get(self.unit, (-math.inf, math.inf))
        if value != 0.0 and not low <= abs(value) <= high:
            raise ParameterError(f"{self.name} ({self.doc}) must be within [{low:g}, {high:g}] {self.unit} in magnitude "
                                 f"(a physically plausible range; 0 where the parameter allows it); got {value!r}")
        return value

    def range_text(self) -> str:
        lb = "(" if self.low_open else "["
        rb = ")" if self.high_open else "]"
        high = "inf" if math.isinf(self.high) else f"{self.high:g}"
        return f"{lb}{self.low:g}, {high}{rb}"


def positive(name: str, default: float | None, unit: str, doc: str) -> Param:
    return Param(name, default, unit, doc)


def nonnegative(name: str, default: float | None, unit: str, doc: str) -> Param:
    return Param(name, default, unit, doc, low=0.0, low_open=False)


def resolve(params: tuple[Param, ...], given: dict[str, Any], owner: str) -> dict[str, Any]:
    """Defaults overlaid with ``given``; optional parameters appear only when given."""
    known = {p.name: p for p in params}
    unknown = [name for name in given if name not in known]
    if unknown:
        raise ParameterError(f"unknown parameter {unknown[0]!r} for {owner}; valid names: {', '.join(known)}")
    values = {p.name: p.default for p in params if p.default is not None}
    for name, value in given.items():
        values[name] = known[name].check(value)
    return values


def parse_assignments(items: list[str] | None) -> dict[str, str]:
    """``["L=10u", "R=5"]`` -> {"L": "10u", "R": "5"} (values are checked later, against the spec)."""
    out: dict[str, str] = {}
    for item in items or []:
        name, sep, value = item.partition("=")
        if not sep or not name.strip():
            raise ParameterError(f"-p takes NAME=VALUE (e.g. -p L=10u); got {item!r}")
        if name.strip() in out:     # which one was meant? (the last would silently win)
            raise ParameterError(f"-p {name.strip()} is given twice ({name.strip()}={out[name.strip()]} and {item.strip()}); "
                                 "give it once")
        out[name.strip()] = value.strip()
    return out
