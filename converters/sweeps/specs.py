"""Specifications on a sweep's measures (``vout_ripple<50m``, ``efficiency>0.95``) and the yield of a tolerance
study: the fraction of samples meeting every one, with its exact (Clopper-Pearson) confidence interval."""
from __future__ import annotations

import re
from collections.abc import Iterable
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt

from ..errors import ParameterError
from ..validate import parse_value

if TYPE_CHECKING:
    import pandas as pd

    from .points import Grid, LatinHypercube, Tolerances

#: METRIC OP VALUE, OP one of <, <=, >, >= (the metric may hold dots and parentheses: v(out).ripple).
_SPEC = re.compile(r"^\s*(?P<metric>[^<>=\s]+)\s*(?P<op><=|>=|<|>)\s*(?P<value>\S+)\s*$")
CONFIDENCE = 0.95


@dataclass(frozen=True)
class Spec:
    """A measure's bound: ``metric op limit``."""

    metric: str
    op: str
    limit: float

    @staticmethod
    def metric_of(text: str) -> str:
        """The metric a spec names (its form checked; its value read by :meth:`parse`, with the metric's unit)."""
        match = _SPEC.match(str(text))
        if match is None:
            raise ParameterError(f"--spec takes METRIC<VALUE or METRIC>VALUE (<= and >= too; e.g. vout_ripple<50m, "
                                 f"efficiency>0.95); got {text!r}")
        return match["metric"]

    @classmethod
    def parse(cls, text: str, units: dict | None = None) -> "Spec":
        """The spec, its value in the metric's unit where ``units`` knows it (``vout_mean<3V``; a unit that
        contradicts it is refused, as a parameter's is)."""
        metric = cls.metric_of(text)
        match = _SPEC.match(str(text))
        assert match is not None
        unit = (units or {}).get(metric) or None
        return cls(metric, match["op"], parse_value(f"--spec {metric}", match["value"], unit))

    def holds(self, values: npt.ArrayLike) -> np.ndarray:
        """Where the values meet the bound (NaN, a failed point's, never does)."""
        v = np.asarray(values, dtype=float)
        with np.errstate(invalid="ignore"):
            return {"<": v < self.limit, "<=": v <= self.limit, ">": v > self.limit, ">=": v >= self.limit}[self.op]

    def margin(self, values: npt.ArrayLike) -> np.ndarray:
        """How far inside the bound (negative: outside): the worst sample has the smallest margin."""
        v = np.asarray(values, dtype=float)
        return self.limit - v if self.op in ("<", "<=") else v - self.limit

    def text(self) -> str:
        return f"{self.metric}{self.op}{self.limit:g}"


def yield_interval(passed: int, total: int, confidence: float = CONFIDENCE) -> tuple[float, float, float]:
    """(the yield passed/total, and its exact two-sided confidence interval): Clopper and Pearson's, by
    scipy.stats.binomtest."""
    from scipy.stats import binomtest
    if total <= 0:
        return float("nan"), float("nan"), float("nan")
    ci = binomtest(int(passed), int(total)).proportion_ci(confidence_level=confidence, method="exact")
    return passed / total, float(ci.low), float(ci.high)


def study_summary(frame: pd.DataFrame, specs: Iterable[Spec],
                  tolerances: Grid | LatinHypercube | Tolerances | None = None) -> dict:
    """Per spec its pass fraction and worst sample, and the yield (every spec met; a failed point counts as a
    failure) with its confidence interval."""
    ok = (frame["status"] == "ok").to_numpy()
    total = len(frame)
    every = ok.copy()
    rows = []
    for spec in specs:
        values = frame[spec.metric].to_numpy(dtype=float) if spec.metric in frame else np.full(total, np.nan)
        meets = spec.holds(values) & ok
        every &= meets
        margins = np.where(ok, spec.margin(values), np.inf)
        worst = int(np.argmin(margins)) if total else None
        names = list(tolerances.names) if tolerances is not None else []
        rows.append({"spec": spec.text(), "passed": int(meets.sum()), "fraction": float(meets.mean()) if total else
                     float("nan"), "worst_value": float(values[worst]) if worst is not None else float("nan"),
                     "worst_point": {n: float(frame[n].iloc[worst]) for n in names} if worst is not None else {}})
    value, low, high = yield_interval(int(every.sum()), total)
    return {"samples": total, "failed_points": int((~ok).sum()), "passed": int(every.sum()), "yield": value,
            "yield_low": low, "yield_high": high, "confidence": CONFIDENCE, "specs": rows}
