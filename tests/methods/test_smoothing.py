"""The smoothing method: its error is first order in eps, its stiffness grows like 1/eps, and its output
keeps every schedule interval."""
from dataclasses import replace

import numpy as np
import pytest

from converters.analysis.gdcm import ccm_orbit
from converters.analysis.periodic import shoot
from converters.methods import EventDriven, Smoothing
from converters.models import get_converter
from converters.simulate import simulate


def test_smoothing_error_is_first_order_in_eps_and_stiffness_grows_like_one_over_eps():
    conv = get_converter("buck")
    p = conv.resolve({})
    T = conv.period(p)
    orbit = shoot(conv.problem(p, T), EventDriven(), ccm_orbit(conv.problem(p, T)).x0, tol=1e-11)
    exact = replace(simulate(conv.problem(p, T, orbit.x0), EventDriven()), labels=conv.labels(p)).mean("vout")
    problem = conv.problem(p, 4 * T, x0=orbit.x0)
    errors, stiffness = [], []
    for eps in (1e-2, 1e-3, 1e-4):
        tr = replace(simulate(problem, Smoothing(eps=eps, solver_rtol=1e-8, output_step=T / 2000)), labels=conv.labels(p))
        assert tr.rule == "linear"
        errors.append(abs(tr.mean("vout") - exact) / exact)
        stiffness.append(tr.metadata["stats"]["max_rho_T"])
    assert errors[0] > 5e-4 and errors[2] < 1e-4
    ratios = np.array(errors[:-1]) / np.array(errors[1:])
    assert np.all((ratios > 5.0) & (ratios < 20.0))         # O(eps)
    np.testing.assert_allclose(np.array(stiffness[1:]) / np.array(stiffness[:-1]), 10.0, rtol=0.05)


def test_smoothing_output_grid_keeps_every_schedule_interval():
    # An interval shorter than output_step (D = 1e-4: the switch conducts 1 ns) keeps both its edges,
    # and samples are never farther apart than output_step; the energy drawn matches the exact method's.
    conv = get_converter("buck")
    p = conv.resolve({"D": 1e-4})
    T = conv.period(p)
    problem = conv.problem(p, 5 * T)
    tr = simulate(problem, Smoothing(eps=1e-4, solver_rtol=1e-8, output_step=T / 1000))
    edges = np.concatenate([np.arange(6) * T, np.arange(5) * T + 1e-4 * T])
    assert np.abs(tr.t[None, :] - edges[:, None]).min(axis=1).max() < 1e-12 * T
    assert np.diff(tr.t).max() <= T / 1000 * (1 + 1e-9)
    on = tr.config[1:] == 0
    drawn = float(np.sum(np.diff(tr.t) * 0.5 * (tr.x[1:, 0] + tr.x[:-1, 0]) * on)) * p["Vin"]
    nodes, w = simulate(problem, EventDriven()).exact.quadrature()
    exact = float(np.sum(w * nodes.x[:, 0] * (nodes.config == 0))) * p["Vin"]
    assert exact > 0 and drawn == pytest.approx(exact, rel=1e-3)


def test_a_small_eps_runs_without_a_numpy_warning():
    # eps = 1e-6 made scipy's Radau predictor divide by zero on the way (harmless: capped by its min(1, .)),
    # which the CLI printed as "pcsuite: warning: divide by zero encountered in scalar divide"
    import warnings
    conv = get_converter("buck")
    p = conv.resolve({})
    T = conv.period(p)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        tr = simulate(conv.problem(p, 50 * T), Smoothing(eps=1e-6, solver_rtol=1e-6, output_step=T / 1000))
    assert tr.metadata["stats"]["nlu"] > 100 and np.isfinite(tr.x).all()
