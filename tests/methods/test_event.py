"""The exact event-driven method: closed forms, the LCP stepper's h -> 0 limit, impulses, GDCM, any number of
complementarity pairs (the PRC's and the diode bridge's four diodes), and the command line."""
import json
import math
from dataclasses import replace

import numpy as np
import pytest
from scipy.optimize import brentq

from converters.analysis.gdcm import ccm_orbit
from converters.analysis.periodic import shoot
from converters.errors import ParameterError, SimulationError
from converters.methods import BackwardEuler, EventDriven, Smoothing, Theta
from converters.models import get_converter, get_model
from validation.core_checks import parallel_rlc_exact

from ..oracle_circuits import half_wave_rectifier
from converters.problems import Configuration, LCSProblem, Schedule
from converters.run import run_converter, run_summary, steady_orbit
from converters.simulate import simulate
from validation.cli import main


def exact_orbit(name, params):
    """The exact periodic orbit (Newton on the exact period map) and one period of it, labelled."""
    conv = get_converter(name)
    p = conv.resolve(params)
    T = conv.period(p)
    problem = conv.problem(p, T)
    orbit = shoot(problem, EventDriven(), ccm_orbit(problem).x0, tol=1e-11)
    assert orbit.converged and orbit.residual < 1e-13
    tr = replace(simulate(conv.problem(p, T, orbit.x0), EventDriven()), labels=conv.labels(p))
    return conv, p, T, orbit, tr


@pytest.mark.parametrize("D", [0.2, 0.4, 0.75])
def test_ccm_buck_mean_output_is_d_vin(D):
    # Ideal CCM buck: the inductor's volt-second balance makes the mean output exactly D * Vin.
    conv, p, T, orbit, tr = exact_orbit("buck", {"L": "100u", "D": D})
    assert tr.exact.event_kinds == []                 # CCM: no diode event inside the period
    assert tr.mean("vout") == pytest.approx(D * 12.0, rel=1e-9)
    run = run_converter("buck", {"L": "100u", "D": D}, method="event", steady=True)
    assert run_summary(run)["vout_mean"] == pytest.approx(D * 12.0, rel=1e-9)


def test_dcm_buck_mean_is_the_reference_value():
    # the exact periodic mean of the default DCM buck is 6.962476 V (the event method's orbit).
    conv, p, T, orbit, tr = exact_orbit("buck", {})
    assert tr.mean("vout") == pytest.approx(6.962476, abs=5e-7)
    assert tr.exact.event_kinds == ["activate"]


@pytest.mark.parametrize("name, params", [("buck", {}), ("boost", {}), ("boost", {"L": "1u"}),
                                          ("cuk", {"L1": "10u", "L2": "10u"})])
def test_event_agrees_with_the_lcp_stepper_extrapolated_to_h_zero(name, params):
    conv, p, T, orbit, tr = exact_orbit(name, params)
    exact = tr.mean("vout")
    means = []
    for steps in (4000, 8000):
        o = steady_orbit(conv, p, h=T / steps, theta=1.0, tol=1e-11)
        assert o.rule == "end"
        means.append(o.mean("vout"))                      # backward Euler's own (end-point) rule
    first_order = abs(means[1] - exact) / abs(exact)
    richardson = 2 * means[1] - means[0]                  # observed order 1
    assert abs(richardson - exact) / abs(exact) < 1e-6
    assert abs(richardson - exact) < abs(means[1] - exact) or first_order < 1e-9


def test_half_wave_rectifier_events_follow_the_closed_form():
    L, C, R, V0 = 1e-2, 1e-6, 1e3, 10.0
    solution = simulate(half_wave_rectifier(t_end=5e-3), EventDriven()).exact
    # Conducting (held pair, D = R > 0): the parallel RLC; the diode current vC / R reaches 0 with vC.
    grid = np.linspace(0.0, 1e-3, 2001)
    first_negative = grid[np.argmax(parallel_rlc_exact(grid, L, C, R, V0)[:, 0] < 0)]
    t_release = brentq(lambda t: parallel_rlc_exact([t], L, C, R, V0)[0, 0], first_negative - 5e-7, first_negative,
                       xtol=1e-16, rtol=1e-15)
    assert solution.event_kinds[0] == "release"
    assert solution.event_times[0] == pytest.approx(t_release, rel=1e-11)
    # Then the LC tank rings freely for half a period (vC < 0) until the diode conducts again.
    v1, i1 = parallel_rlc_exact([t_release], L, C, R, V0)[0]
    w = 1.0 / math.sqrt(L * C)
    tau = brentq(lambda s: v1 * math.cos(w * s) - i1 / (C * w) * math.sin(w * s), 1e-9, math.pi / w * 1.01)
    assert solution.event_kinds[1] == "activate"
    assert solution.event_times[1] == pytest.approx(t_release + tau, rel=1e-11)
    sample = solution.sample([t_release + 0.5 * tau])
    s = 0.5 * tau
    assert sample.x[0, 0] == pytest.approx(v1 * math.cos(w * s) - i1 / (C * w) * math.sin(w * s), rel=1e-10)
    assert sample.u[0, 0] == 0.0 and sample.y[0, 0] > 0.0


def test_cuk_gdcm_holds_i1_plus_i2_at_zero_exactly():
    conv, p, T, orbit, tr = exact_orbit("cuk", {"L1": "10u", "L2": "10u"})
    sol = tr.exact
    held = [seg for seg in sol.segments if seg.flow.held]
    assert len(held) == 1 and held[0].t1 == pytest.approx(T, rel=1e-14)
    t = np.linspace(held[0].t0, held[0].t1, 50)[1:]
    sample = sol.sample(t)
    assert np.abs(sample.x[:, 0] + sample.x[:, 2]).max() < 1e-12      # i1 + i2 = 0 (to rounding)
    assert sample.u.min() > 0.0
    # The LCP stepper's first GDCM label comes less than 1.5 steps after the exact entry, at every h.
    lags = []
    for steps in (4000, 8000, 16000):
        lcp = steady_orbit(conv, p, h=T / steps, theta=1.0, tol=1e-11)
        lags.append(lcp.t[np.flatnonzero(lcp.modes() == "GDCM-OFF")[0]] - held[0].t0)
    lags = np.array(lags) / (T / np.array([4000, 8000, 16000]))      # in steps: labels sit on grid points
    assert np.all((lags > 0) & (lags < 1.5))


@pytest.mark.parametrize("tol", [1e-2, 1e-4])
def test_a_loose_event_tolerance_places_the_event_just_past_the_crossing(tol):
    # Brent's method stops within tol T of the zero on either side; the event is taken past it (within
    # 2 tol T) so the mode selection sees the crossing, never a repeated event at one instant.
    conv, p, T, orbit, tr = exact_orbit("cuk", {"L1": "10u", "L2": "10u"})
    entry = tr.exact.event_times[0]
    sol = simulate(conv.problem(p, 20 * T, orbit.x0), EventDriven(event_tol=tol)).exact
    kinds = np.array(sol.event_kinds)
    late = (np.array(sol.event_times)[kinds == "activate"] - entry) % T / T
    assert late.size == 20 and np.all((late >= 0) & (late <= 2 * tol + 1e-12))


def test_configuration_entered_with_negative_y_jumps_by_the_moreau_impulse():
    # Buck OFF with iL = -1 A: the diode cannot carry it; the impulse sets iL to 0 at once.
    buck = get_converter("buck")
    off = buck.configurations(buck.resolve({}))[1]
    problem = LCSProblem((off,), Schedule.constant(), x0=[-1.0, 5.0], t_span=(0.0, 1e-6))
    sol = simulate(problem, EventDriven()).exact
    assert sol.event_kinds[0] == "impulse" and sol.event_times[0] == 0.0
    np.testing.assert_allclose(sol.segments[0].xt0[:2], [0.0, 5.0], atol=1e-15)
    # Backward Euler takes the same jump in its first step (the impulse is u h).
    be = simulate(problem, BackwardEuler(1e-9))
    assert be.x[1, 0] == pytest.approx(0.0, abs=1e-12)


def test_ill_posed_and_unsupported_problems_are_refused():
    bad = Configuration(A=[[0.0]], B=[[-1.0]], C=[[1.0]], D=[[0.0]], name="bad")   # C B < 0
    with pytest.raises(SimulationError, match=r"no impulse restores complementarity \(C B = \[\[-1.0\]\]"):
        simulate(LCSProblem((bad,), Schedule.constant(), x0=[-1.0], t_span=(0.0, 1.0)), EventDriven())
    smc = get_model("boost", "smc-implicit")
    with pytest.raises(ParameterError, match=r"the implicit relay is a time-stepping scheme: use --method lcp"):
        simulate(smc.problem(smc.resolve({}), 1e-4), EventDriven())
    with pytest.raises(ParameterError, match=r"event_tol must be in \(0, 1e-2\]"):
        EventDriven(event_tol=0.5)
    with pytest.raises(ParameterError, match=r"eps must be in \[1e-08, 0.1\]; got 0.0"):
        Smoothing(eps=0)
    with pytest.raises(ParameterError, match=r"eps must be in \[1e-08, 0.1\]; got 100000.0"):
        Smoothing(eps=1e5)           # was accepted: a 12 V buck then reported vout 13433 V
    with pytest.raises(ParameterError, match=r"unknown option 'eps' for method 'event'; valid options: event_tol"):
        run_converter("buck", {}, method="event", eps=1e-3)


def test_simulate_cli_event_and_smooth_methods(capsys, tmp_path):
    out = tmp_path / "w.csv"
    assert main(["simulate", "buck", "-p", "L=100u", "--method", "event", "--steady", "--json", "--out", str(out)]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["method"] == "event" and summary["vout_mean"] == pytest.approx(4.8, rel=1e-9)
    import pandas as pd
    frame = pd.read_csv(out)
    assert list(frame.columns) == ["time", "iL", "vC", "vout", "switch", "i_in", "i_switch", "v_switch", "i_diode",
                                   "v_diode", "i_cap", "mode"]
    assert main(["simulate", "buck", "--method", "smooth", "--eps", "1e-5", "--periods", "3", "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["method"] == "smooth" and summary["options"]["eps"] == 1e-5
    assert main(["simulate", "prc", "--method", "smooth"]) == 2
    assert "the smoothing method needs D = 0 in every configuration" in capsys.readouterr().err


def test_event_method_on_the_prc_agrees_with_the_steppers_extrapolation_to_h_zero():
    """Four diodes (k = 4): the mode-selection LCP at every event with held sets of any size. The Siconos
    PRC (2 ms from rest): mean v_o over the last ms is 0.6135396 V (measured independently)."""
    prc = get_converter("prc")
    p = prc.resolve({})
    problem = prc.problem(p, 2e-3)
    exact = replace(simulate(problem, EventDriven()), labels=prc.labels(p))
    assert exact.mean("vout", t0=1e-3) == pytest.approx(0.6135396, abs=5e-8)
    kinds = set(zip(exact.exact.event_kinds, exact.exact.event_pairs))
    assert {("activate", i) for i in range(4)} <= kinds and {("release", i) for i in range(4)} <= kinds
    means = {h: replace(simulate(problem, Theta(h, 0.5)), labels=prc.labels(p)).mean("vout", t0=1e-3)
             for h in (3.125e-9, 1.5625e-9)}
    richardson = 2 * means[1.5625e-9] - means[3.125e-9]             # observed order 1 through the events
    assert abs(richardson / exact.mean("vout", t0=1e-3) - 1.0) < 1e-6     # measured 1.1e-7
    assert abs(means[1.5625e-9] / richardson - 1.0) > 1e-5          # the stepper alone is not that close


def test_event_method_on_the_diode_bridge_is_its_closed_form_and_the_steppers_limit():
    from ..oracle_circuits import diode_bridge
    problem = diode_bridge(t_end=5e-3)
    exact = simulate(problem, EventDriven())
    np.testing.assert_allclose(exact.x, parallel_rlc_exact(exact.t), atol=1e-11)
    assert len(exact.exact.event_times) > 0                          # the bridge commutates at every zero of vC
    ends = {h: simulate(problem, Theta(h, 0.5)).x[-1, 0] for h in (5e-8, 2.5e-8)}
    richardson = 2 * ends[2.5e-8] - ends[5e-8]
    assert abs(richardson - exact.x[-1, 0]) / abs(exact.x[-1, 0]) < 1e-6    # measured 1.7e-7


@pytest.mark.parametrize("problem", ["C=1e-15", "C=1e-308", "R=1e-300", "t_end=1e30"])
def test_a_run_far_longer_than_the_fastest_time_constant_is_refused_not_hung(problem):
    # C = 1e-15 F in a 5 ms run had run for more than 280 s (2e13 substeps); R = 1e-300 divided by zero
    import time

    from converters.errors import ResourceError
    from ..oracle_circuits import half_wave_rectifier
    name, value = problem.split("=")
    started = time.process_time()            # CPU seconds: the work done, whatever else the machine runs
    with pytest.raises(ResourceError, match=r"^--method event: the stiffest mode's time constant is about .* "
                                            r"substeps \(at most 1e\+07\)"), np.errstate(all="ignore"):
        simulate(half_wave_rectifier(**{name: float(value)}), EventDriven())      # 1e-308: its series overflow
    assert time.process_time() - started < 5.0


def test_the_event_method_stops_at_the_memory_limit_while_it_runs(monkeypatch, capsys):
    """No estimate before the run bounds the event method's segments and events: the engine looks at the memory it holds every MEMORY_LOOK segments and
    stops in one line above the limit. Here the look comes every 16 segments and reads 5 GiB against 4 GiB."""
    from converters import limits
    from converters.errors import ResourceError
    from converters.methods.event import machine
    from converters.run import run_converter
    from validation.cli import main
    looks = []
    monkeypatch.setattr(machine, "MEMORY_LOOK", 16)
    monkeypatch.setattr(limits, "memory_in_use", lambda: looks.append(1) or 5 << 30)
    monkeypatch.delenv(limits.MEMORY_ENV, raising=False)
    with pytest.raises(ResourceError, match=r"--method event at t = .* holds 5 GiB, above the memory limit of 4 GiB"):
        run_converter("buck", method="event", periods=50)
    assert len(looks) == 1
    assert main(["simulate", "buck", "--method", "event", "--periods", "50"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "use --method lcp" in err


RC_100PS = """an RC of 100 ps charged from rest
V1 in 0 DC 10
R1 in a 1
C1 a 0 100p
.tran 1n 10u
.end
"""


def test_a_mean_over_a_window_far_longer_than_the_fastest_time_constant_is_exact_and_read_in_blocks(tmp_path):
    """A snubber's 100 ps beside a 10 us period: the event method's quadrature had every node of a window at once
    (pieces of a quarter time constant: 10 periods of a snubbered buck ran the machine out of memory, killed by the
    kernel). Read in blocks, the mean and RMS of v(a) = 10 (1 - e^(-t / tau)) over [0, t1] are their closed forms
    10 (1 - tau / t1) and 10 sqrt(1 - 1.5 tau / t1) (e^(-t1 / tau) = e^(-1e5) = 0), in a bounded memory."""
    import tracemalloc

    from converters import limits
    from converters.errors import ResourceError
    from converters.methods.event.solution import QUADRATURE_BLOCK
    path = tmp_path / "rc.cir"
    path.write_text(RC_100PS)
    tr = run_converter(get_model(str(path)), method="event")
    tau, t1 = 1e-10, 1e-5
    pieces = tr.exact.quadrature_pieces(0.0, t1)
    assert pieces > 30 * QUADRATURE_BLOCK                  # 550,001: 34 blocks
    tracemalloc.start()
    try:
        mean, rms = tr.mean("v(a)", t0=0.0, t1=t1), tr.rms("v(a)", t0=0.0, t1=t1)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert mean == pytest.approx(10.0 * (1.0 - tau / t1), rel=1e-12)
    assert rms == pytest.approx(10.0 * math.sqrt(1.0 - 1.5 * tau / t1), rel=1e-12)
    assert peak < 100e6                                    # measured 31 MB; all nodes at once (before): 4.3 GB
    assert tr.measurement_rows(t0=0.0, t1=t1)["v(a)"]["mean"] == mean      # one pass for every signal: the same sum
    # every node at once is what quadrature() still gives: checked against the limit before it is built
    previous = limits.max_memory()
    limits.set_max_memory("64M")
    try:
        with pytest.raises(ResourceError, match=r"^the event method's quadrature over \[0, 1e-05\] s needs about "):
            tr.exact.quadrature(0.0, t1)
    finally:
        limits.set_max_memory(str(previous))
