"""First-order (variance-based) indices from a tolerance study's own sample: against closed forms, and against the
exact local sensitivities where the tolerances are small."""
from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest
from scipy.stats import qmc

from converters.analysis.sensitivity import sensitivities
from converters.errors import ParameterError
from converters.parallel import run_ensemble
from converters.sweeps import ModelSweep
from converters.sweeps.indices import first_order
from converters.sweeps.points import Tolerance, Tolerances


def _ishigami_s1(a=7.0, b=0.1):
    """Ishigami and Homma's function sin x1 + a sin^2 x2 + b x3^4 sin x1, x_i uniform on (-pi, pi): its first-order
    indices in closed form (V1 = (1 + b pi^4 / 5)^2 / 2, V2 = a^2 / 8, V3 = 0; V = a^2 / 8 + b pi^4 / 5 +
    b^2 pi^8 / 18 + 1 / 2)."""
    v1 = 0.5 * (1 + b * math.pi ** 4 / 5) ** 2
    v2 = a ** 2 / 8
    v = a ** 2 / 8 + b * math.pi ** 4 / 5 + b ** 2 * math.pi ** 8 / 18 + 0.5
    return np.array([v1, v2, 0.0]) / v


@pytest.mark.parametrize("sampler", ["lhs", "sobol"])
def test_indices_of_ishigamis_function_are_its_closed_forms(sampler):
    n = 4096
    unit = (qmc.LatinHypercube(d=3, seed=3) if sampler == "lhs" else qmc.Sobol(d=3, scramble=True, seed=3)).random(n)
    x = -math.pi + 2 * math.pi * unit
    y = np.sin(x[:, 0]) + 7 * np.sin(x[:, 1]) ** 2 + 0.1 * x[:, 2] ** 4 * np.sin(x[:, 0])
    found = first_order(pd.DataFrame({"x1": x[:, 0], "x2": x[:, 1], "x3": x[:, 2], "y": y}), ["x1", "x2", "x3"],
                        ["y"])["y"]
    exact = _ishigami_s1()
    np.testing.assert_allclose(exact, [0.31390519, 0.44241114, 0.0], atol=1e-8)       # the published values
    for name, value in zip(("x1", "x2", "x3"), exact):
        assert abs(found["S1"][name] - value) <= found["S1_conf"][name], (name, found)


def test_an_additive_function_shares_its_variance_by_its_terms():
    """y = 2 a + b, a and b uniform on (0, 1): S1 = 4/5 and 1/5, summing to 1 (no interaction)."""
    unit = qmc.LatinHypercube(d=3, seed=1).random(2000)
    frame = pd.DataFrame({"a": unit[:, 0], "b": unit[:, 1], "c": unit[:, 2], "y": 2 * unit[:, 0] + unit[:, 1]})
    found = first_order(frame, ["a", "b", "c"], ["y"])["y"]
    for name, value in (("a", 0.8), ("b", 0.2), ("c", 0.0)):
        assert abs(found["S1"][name] - value) <= found["S1_conf"][name], (name, found)
    with pytest.raises(ParameterError, match=r"--indices: y has 99 finite samples; first-order indices need at least "
                                             r"100"):
        first_order(frame.iloc[:99], ["a", "b"], ["y"])


def test_the_dcm_boosts_indices_are_its_exact_sensitivities_linearised():
    """A DCM boost (its output depends on L, R and D through K = 2 L / (R T)) with small tolerances: the sample's
    indices equal (dm/dp_i)^2 Var(p_i) / sum_j (dm/dp_j)^2 Var(p_j) from the exact sensitivities, within their
    confidence."""
    base = {"L": 10e-6, "R": 100.0, "D": 0.4}
    points = Tolerances([Tolerance.parse("L=2%:uniform", base), Tolerance.parse("R=1%", base),
                         Tolerance.parse("C=5%", {"C": 100e-6})], 1000, seed=2)
    sweep = ModelSweep("boost", "pwm", base)
    frame = pd.DataFrame(run_ensemble(sweep, points, backend="batched"))
    assert (frame["status"] == "ok").all() and (frame["mode"] == "DCM").all()
    found = first_order(frame, ["L", "R", "C"], ["vout_mean"])["vout_mean"]
    exact = {s.parameter: s.derivative for s in sensitivities("boost", base, parameters=["L", "R", "C"]).rows}
    share = {name: exact[name] ** 2 * frame[name].var() for name in ("L", "R", "C")}
    for name in ("L", "R", "C"):
        predicted = share[name] / sum(share.values())
        assert abs(found["S1"][name] - predicted) <= found["S1_conf"][name], (name, predicted, found)
    assert found["S1"]["L"] > 0.5 and found["S1"]["C"] < 0.01
