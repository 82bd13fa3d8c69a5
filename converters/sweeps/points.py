"""Parameter points of a sweep: a full grid or a Latin hypercube over named ranges, addressed by index.

A point is computed from its index alone (never a list of all points), so a sweep of any size holds only
the chunk it is working on, and a resumed sweep finds the same point under the same index. Grid order is
C order: the first axis varies slowest.
"""
from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

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

    def __post_init__(self) -> None:
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


def _check_names(axes: Sequence[Axis]) -> None:
    if not axes:
        raise ParameterError("a sweep needs at least one --grid NAME=START:STOP:COUNT")
    names = [a.name for a in axes]
    if len(set(names)) != len(names):
        raise ParameterError(f"--grid: each parameter once; got {', '.join(names)}")


class Grid:
    """Every combination of the axes' values."""

    kind = "grid"

    def __init__(self, axes: Iterable[Axis]) -> None:
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

    def points(self, indices: npt.ArrayLike) -> list[tuple[int, dict]]:
        indices = check_indices("indices", indices, self.size)
        where = np.unravel_index(indices, self.shape)
        return [(int(i), {a.name: float(self._values[k][where[k][j]]) for k, a in enumerate(self.axes)})
                for j, i in enumerate(indices)]

    def extremes(self) -> list[dict]:
        """Each parameter at each end of its range (checked against the model's ranges before a sweep runs)."""
        return [{a.name: value} for a in self.axes for value in (a.start, a.stop)]

    def describe(self) -> dict:
        return {"kind": "grid", "axes": [a.text() for a in self.axes]}


def _check_sampling(option: str, n: object, seed: object) -> None:
    """A sample count in [1, MAX_POINTS] (given as ``option``) and a seed >= 0, integers (bool refused)."""
    if isinstance(n, bool) or not (isinstance(n, (int, np.integer)) and 1 <= n <= MAX_POINTS):
        raise ParameterError(f"{option} must be an integer in [1, {MAX_POINTS:,}]; got {n!r}")
    if isinstance(seed, bool) or not (isinstance(seed, (int, np.integer)) and seed >= 0):
        raise ParameterError(f"--seed must be an integer >= 0; got {seed!r}")


class LatinHypercube:
    """``n`` points of a Latin hypercube over the axes' ranges (scipy.stats.qmc, seeded: the same points on
    every run)."""

    kind = "lhs"

    def __init__(self, axes: Iterable[Axis], n: int, seed: int = 0) -> None:
        self.axes = tuple(axes)
        _check_names(self.axes)
        _check_sampling("--lhs", n, seed)
        from scipy.stats import qmc
        self.size, self.seed, self.shape = int(n), int(seed), (int(n),)
        unit = qmc.LatinHypercube(d=len(self.axes), seed=self.seed).random(n)
        self._samples = np.column_stack([a.scale(unit[:, k]) for k, a in enumerate(self.axes)])

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(a.name for a in self.axes)

    def points(self, indices: npt.ArrayLike) -> list[tuple[int, dict]]:
        return [(int(i), {a.name: float(self._samples[i, k]) for k, a in enumerate(self.axes)})
                for i in check_indices("indices", indices, self.size)]

    def extremes(self) -> list[dict]:
        return [{a.name: value} for a in self.axes for value in (a.start, a.stop)]

    def describe(self) -> dict:
        return {"kind": "lhs", "axes": [f"{a.name}={a.start:g}:{a.stop:g}" + (":log" if a.log else "")
                                        for a in self.axes], "n": self.size, "seed": self.seed}


#: A tolerance's distributions: normal (the tolerance is 3 sigma, truncated there), uniform (over +-tolerance),
#: lognormal (median the nominal, the tolerance 3 sigma of its logarithm, truncated there).
DISTRIBUTIONS = ("normal", "uniform", "lognormal")
#: Samplers of a tolerance study's unit hypercube (scipy.stats.qmc, seeded).
SAMPLERS = ("lhs", "sobol")
#: How many sigma a tolerance is, and where a normal or lognormal sample is truncated.
SIGMAS = 3.0


@dataclass(frozen=True)
class Tolerance:
    """A parameter's spread about its nominal value: a relative tolerance (0 < tol < 1) and a distribution."""

    name: str
    nominal: float
    tolerance: float
    distribution: str = "normal"

    def __post_init__(self) -> None:
        if self.distribution not in DISTRIBUTIONS:
            raise ParameterError(f"--tolerance {self.name}: the distribution must be one of {', '.join(DISTRIBUTIONS)}; "
                                 f"got {self.distribution!r}")
        if not (isinstance(self.tolerance, float) and 0.0 < self.tolerance < 1.0):
            raise ParameterError(f"--tolerance {self.name}: the tolerance must be in (0, 100) %; got "
                                 f"{100 * self.tolerance:g} %" if isinstance(self.tolerance, float) else
                                 f"--tolerance {self.name}: the tolerance must be a number; got {self.tolerance!r}")
        if not (isinstance(self.nominal, float) and math.isfinite(self.nominal) and self.nominal != 0.0):
            raise ParameterError(f"--tolerance {self.name}: a relative tolerance needs a nonzero nominal value; got "
                                 f"{self.nominal!r} (give it with -p {self.name}=VALUE)")
        if self.distribution == "lognormal" and self.nominal < 0.0:
            raise ParameterError(f"--tolerance {self.name}: a lognormal spread needs a positive nominal; got "
                                 f"{self.nominal:g}")

    @classmethod
    def parse(cls, text: str, nominals: dict) -> "Tolerance":
        """``NAME=TOL[%][:DIST]`` (``C=5%``, ``L=10%:uniform``, ``R=0.01:lognormal``); the nominal from ``nominals``
        (the model's resolved parameters: -p or its default)."""
        name, sep, spec = str(text).partition("=")
        name = name.strip()
        if not sep or not name or not spec.strip():
            raise ParameterError(f"--tolerance takes NAME=TOL[%][:DIST] (e.g. C=5% or L=10%:uniform); got {text!r}")
        tol_text, _, distribution = spec.partition(":")
        tol_text = tol_text.strip()
        percent = tol_text.endswith("%")
        tolerance = parse_value(f"--tolerance {name}", tol_text[:-1] if percent else tol_text)
        tolerance = tolerance / 100.0 if percent else tolerance
        if name not in nominals:
            raise ParameterError(f"--tolerance {name}: not a parameter of the model; valid names: "
                                 f"{', '.join(nominals)}")
        nominal = nominals[name]
        if nominal is None:
            raise ParameterError(f"--tolerance {name}: the parameter has no value to vary (an optional one that is "
                                 f"not set): give it with -p {name}=VALUE")
        return cls(name, float(nominal), float(tolerance), distribution.strip().lower() or "normal")

    def values(self, unit: np.ndarray) -> np.ndarray:
        """Samples at the unit hypercube's coordinates ``unit`` in (0, 1) (the inverse of the truncated CDF)."""
        from scipy.stats import truncnorm
        if self.distribution == "uniform":
            return self.nominal * (1.0 + self.tolerance * (2.0 * unit - 1.0))
        z = truncnorm.ppf(unit, -SIGMAS, SIGMAS)
        if self.distribution == "normal":
            return self.nominal * (1.0 + self.tolerance * z / SIGMAS)
        return self.nominal * np.exp(math.log1p(self.tolerance) * z / SIGMAS)

    def limits(self) -> tuple[float, float]:
        """The extremes a sample can take (the worst-case corners' values)."""
        if self.distribution == "lognormal":
            ends = (self.nominal / (1.0 + self.tolerance), self.nominal * (1.0 + self.tolerance))
        else:
            ends = (self.nominal * (1.0 - self.tolerance), self.nominal * (1.0 + self.tolerance))
        return min(ends), max(ends)

    def text(self) -> str:
        return f"{self.name}={100 * self.tolerance:g}%:{self.distribution}"


class Tolerances:
    """``n`` samples of parameters spread by their tolerances (a Monte Carlo study): the unit hypercube by a Latin
    hypercube or a scrambled Sobol sequence (scipy.stats.qmc, seeded: the same samples on every run), mapped through
    each distribution's inverse CDF."""

    kind = "tolerance"

    def __init__(self, tolerances: Iterable[Tolerance], n: int, seed: int = 0, sampler: str = "lhs") -> None:
        self.tolerances = tuple(tolerances)
        names = [t.name for t in self.tolerances]
        if not names:
            raise ParameterError("a tolerance study needs at least one --tolerance NAME=TOL[%][:DIST]")
        if len(set(names)) != len(names):
            raise ParameterError(f"--tolerance: each parameter once; got {', '.join(names)}")
        _check_sampling("--samples", n, seed)
        if sampler not in SAMPLERS:
            raise ParameterError(f"--sampler must be one of {', '.join(SAMPLERS)}; got {sampler!r}")
        import warnings

        from scipy.stats import qmc
        self.size, self.seed, self.sampler, self.shape = int(n), int(seed), sampler, (int(n),)
        d = len(self.tolerances)
        if sampler == "sobol":
            with warnings.catch_warnings():        # a count that is not a power of two loses some balance: allowed
                warnings.simplefilter("ignore", UserWarning)
                unit = qmc.Sobol(d=d, scramble=True, seed=self.seed).random(self.size)
        else:
            unit = qmc.LatinHypercube(d=d, seed=self.seed).random(self.size)
        unit = np.clip(unit, 1e-12, 1.0 - 1e-12)
        self._samples = np.column_stack([t.values(unit[:, k]) for k, t in enumerate(self.tolerances)])

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(t.name for t in self.tolerances)

    def points(self, indices: npt.ArrayLike) -> list[tuple[int, dict]]:
        return [(int(i), {t.name: float(self._samples[i, k]) for k, t in enumerate(self.tolerances)})
                for i in check_indices("indices", indices, self.size)]

    def extremes(self) -> list[dict]:
        return [{t.name: value} for t in self.tolerances for value in t.limits()]

    def corners(self) -> list[dict]:
        """The 2^k worst-case corners: every combination of each parameter's extremes."""
        import itertools
        return [dict(zip(self.names, combo)) for combo in itertools.product(*(t.limits() for t in self.tolerances))]

    def describe(self) -> dict:
        return {"kind": "tolerance", "tolerances": [t.text() for t in self.tolerances],
                "nominals": {t.name: t.nominal for t in self.tolerances}, "n": self.size, "seed": self.seed,
                "sampler": self.sampler}


__all__ = ["Axis", "Grid", "LatinHypercube", "Tolerance", "Tolerances", "DISTRIBUTIONS", "SAMPLERS", "MAX_POINTS"]
