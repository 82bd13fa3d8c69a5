"""Parameter points of a sweep: a full grid or a Latin hypercube over named ranges, addressed by index.

A point is computed from its index alone (never a list of all points), so a sweep of any size holds only
the chunk it is working on, and a resumed sweep finds the same point under the same index. Grid order is
C order: the first axis varies slowest.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import ParameterError
from ..validate import check_indices, parse_value, shown

#: The most points a sweep may ask for (a typo like COUNT=1e9 is refused, not started).
MAX_POINTS = 10_000_000


@dataclass(frozen=True)
class Axis:
    """``count`` values of parameter ``name`` from ``start`` to ``stop`` (linear, or geometric when ``log``)."""

    name: str
    start: float
    stop: float
    count: int = 1
    log: bool = False

    def __post_init__(self):
        # Axis.parse checks the text; an Axis built directly is checked here (NaN ends, count 0 or 2.5, a log axis
        # across zero would pass or fail deep in numpy)
        if not (isinstance(self.name, str) and self.name.strip()):
            raise ParameterError(f"an axis needs a parameter name; got {self.name!r}")
        for end in ("start", "stop"):
            value = getattr(self, end)
            if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)) \
                    or not np.isfinite(value):
                raise ParameterError(f"--grid {self.name}: {end.upper()} must be a finite number; got {value!r}")
        if isinstance(self.count, bool) or not (isinstance(self.count, (int, np.integer)) and self.count >= 1):
            raise ParameterError(f"--grid {self.name}: COUNT must be an integer >= 1; got {self.count!r}")
        if self.log and not (self.start > 0 and self.stop > 0):
            raise ParameterError(f"--grid {self.name}: a log axis needs START and STOP > 0; got "
                                 f"{self.start:g}:{self.stop:g}")

    @classmethod
    def parse(cls, text: str, *, count_required: bool = True) -> "Axis":
        """``NAME=START:STOP:COUNT[:log]`` (values with SPICE suffixes: ``L=10u:100u:10``); with
        ``count_required`` False (a Latin hypercube's range), ``NAME=START:STOP[:log]``: a COUNT is refused,
        as it would be ignored."""
        name, sep, spec = str(text).partition("=")
        fields = spec.split(":")
        usage = "NAME=START:STOP:COUNT[:log]" if count_required else "NAME=START:STOP[:log]"
        log = fields[-1].strip().lower() == "log"
        if log:
            fields = fields[:-1]
        if sep and name.strip() and len(fields) == 3 and not count_required:
            raise ParameterError(f"--grid {name.strip()}: COUNT does not apply with --lhs (the hypercube draws its "
                                 f"N points over START:STOP); give {name.strip()}=START:STOP[:log]; got {text!r}")
        if not sep or not name.strip() or len(fields) != (3 if count_required else 2):
            example = "R=1:50:100" if count_required else "R=1:50"
            raise ParameterError(f"--grid takes {usage} (e.g. {example}); got {text!r}")
        name = name.strip()
        start, stop = parse_value(f"{name} start", fields[0]), parse_value(f"{name} stop", fields[1])
        count = 1
        if len(fields) == 3:
            raw = fields[2].strip()
            # ASCII digits only ('５' and '²' are digits to str.isdigit), and no more than the largest grid has: int()
            # of a 5,000-digit text raises Python's digit limit, naming nothing
            if not (raw.isascii() and raw.isdigit()) or len(raw) > len(str(MAX_POINTS)) or not 1 <= int(raw) <= MAX_POINTS:
                raise ParameterError(f"--grid {name}: COUNT must be an integer in [1, {MAX_POINTS:,}]; got {shown(raw)}")
            count = int(raw)
        if log and not (start > 0 and stop > 0):
            raise ParameterError(f"--grid {name}: a log axis needs START and STOP > 0; got {start:g}:{stop:g}")
        return cls(name, start, stop, count, log)

    def values(self) -> np.ndarray:
        if self.count == 1:
            return np.array([self.start])
        return (np.geomspace if self.log else np.linspace)(self.start, self.stop, self.count)

    def scale(self, unit: np.ndarray) -> np.ndarray:
        """Map samples in [0, 1) onto the axis's range."""
        if self.log:
            return np.exp(np.log(self.start) + unit * (np.log(self.stop) - np.log(self.start)))
        return self.start + unit * (self.stop - self.start)

    def text(self) -> str:
        return f"{self.name}={self.start:g}:{self.stop:g}:{self.count}" + (":log" if self.log else "")


def _check_names(axes) -> None:
    if not axes:
        raise ParameterError("a sweep needs at least one --grid NAME=START:STOP:COUNT")
    names = [a.name for a in axes]
    if len(set(names)) != len(names):
        raise ParameterError(f"--grid: each parameter once; got {', '.join(names)}")


class Grid:
    """Every combination of the axes' values."""

    kind = "grid"

    def __init__(self, axes):
        self.axes = tuple(axes)
        _check_names(self.axes)
        self.shape = tuple(a.count for a in self.axes)
        self.size = math.prod(self.shape)
        if self.size > MAX_POINTS:
            raise ParameterError(f"--grid: at most {MAX_POINTS:,} points; got {self.size:,}")
        self._values = [a.values() for a in self.axes]

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(a.name for a in self.axes)

    def points(self, indices) -> list[tuple[int, dict]]:
        indices = check_indices("indices", indices, self.size)
        where = np.unravel_index(indices, self.shape)
        return [(int(i), {a.name: float(self._values[k][where[k][j]]) for k, a in enumerate(self.axes)})
                for j, i in enumerate(indices)]

    def describe(self) -> dict:
        return {"kind": "grid", "axes": [a.text() for a in self.axes]}


class LatinHypercube:
    """``n`` points of a Latin hypercube over the axes' ranges (scipy.stats.qmc, seeded: the same points on
    every run)."""

    kind = "lhs"

    def __init__(self, axes, n: int, seed: int = 0):
        self.axes = tuple(axes)
        _check_names(self.axes)
        if isinstance(n, bool) or not (isinstance(n, (int, np.integer)) and 1 <= n <= MAX_POINTS):
            raise ParameterError(f"--lhs must be an integer in [1, {MAX_POINTS:,}]; got {n!r}")
        if not (isinstance(seed, (int, np.integer)) and not isinstance(seed, bool) and seed >= 0):
            raise ParameterError(f"--seed must be an integer >= 0; got {seed!r}")
        from scipy.stats import qmc
        self.size, self.seed, self.shape = int(n), int(seed), (int(n),)
        unit = qmc.LatinHypercube(d=len(self.axes), seed=self.seed).random(n)
        self._samples = np.column_stack([a.scale(unit[:, k]) for k, a in enumerate(self.axes)])

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(a.name for a in self.axes)

    def points(self, indices) -> list[tuple[int, dict]]:
        return [(int(i), {a.name: float(self._samples[i, k]) for k, a in enumerate(self.axes)})
                for i in check_indices("indices", indices, self.size)]

    def describe(self) -> dict:
        return {"kind": "lhs", "axes": [f"{a.name}={a.start:g}:{a.stop:g}" + (":log" if a.log else "")
                                        for a in self.axes], "n": self.size, "seed": self.seed}


__all__ = ["Axis", "Grid", "LatinHypercube", "MAX_POINTS"]
