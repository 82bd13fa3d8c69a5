"""Global (variance-based) first-order sensitivity indices of a tolerance study, from its own sample.

The first-order index S1_i = Var(E[m | p_i]) / Var(m) is the share of the metric's variance that parameter i
explains alone (the rest, 1 - sum S1, is the interactions'). It is estimated from the study's sample as it stands,
with no extra runs, by RBD-FAST (random balance designs: Tarantola, Gatelli and Mara 2006; the ordering of
Plischke 2010, the bias correction of Tissot and Prieur 2012) as SALib implements it (``SALib.analyze.rbd_fast``,
valid for any sampler: the Latin hypercube or Sobol points of the study); its confidence is SALib's bootstrap
half-width. The exact local sensitivities (``pcsuite sensitivity``) predict these indices where the tolerances are
small: S1_i ~ (dm/dp_i)^2 Var(p_i) / sum_j (dm/dp_j)^2 Var(p_j).
"""
from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ..errors import ParameterError

if TYPE_CHECKING:
    import pandas as pd

#: Harmonics summed (SALib's M) and bootstrap resamples of the confidence.
HARMONICS = 10
RESAMPLES = 100
#: The fewest samples an index is taken of (the estimator's bias correction is 2 M / N).
MIN_SAMPLES = 100
METHOD = "RBD-FAST (SALib; Tarantola et al. 2006, Tissot and Prieur 2012)"


def first_order(frame: pd.DataFrame, parameters: list, metrics: list, seed: int = 0) -> dict:
    """{metric: {"S1": {parameter: index}, "S1_conf": {parameter: 95 % half-width}, "sum": sum S1, "samples": n}}
    over the rows of ``frame`` whose metric is finite (a failed point has none)."""
    from SALib.analyze import rbd_fast
    out = {}
    for metric in metrics:
        y = frame[metric].to_numpy(dtype=float) if metric in frame else np.full(len(frame), np.nan)
        keep = np.isfinite(y)
        n = int(keep.sum())
        if n < MIN_SAMPLES:
            raise ParameterError(f"--indices: {metric} has {n} finite samples; first-order indices need at least "
                                 f"{MIN_SAMPLES} (--samples)")
        x = frame[list(parameters)].to_numpy(dtype=float)[keep]
        if np.ptp(y[keep]) == 0.0:                 # a metric that does not move: no variance to share
            s1, conf = np.zeros(len(parameters)), np.zeros(len(parameters))
        else:
            problem = {"num_vars": len(parameters), "names": list(parameters),
                       "bounds": [[float(a), float(b)] for a, b in zip(x.min(axis=0), x.max(axis=0))]}
            found = rbd_fast.analyze(problem, x, y[keep], M=HARMONICS, num_resamples=RESAMPLES, seed=seed)
            s1, conf = np.asarray(found["S1"], dtype=float), np.asarray(found["S1_conf"], dtype=float)
        out[metric] = {"S1": dict(zip(parameters, map(float, s1))), "S1_conf": dict(zip(parameters, map(float, conf))),
                       "sum": float(s1.sum()), "samples": n}
    return out


__all__ = ["first_order", "MIN_SAMPLES", "METHOD"]
