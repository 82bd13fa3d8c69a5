"""The rules a review's mutations survived, each pinned by a test that fails when the rule changes: Newton
shooting's one stopping rule (the distance bound with rho, its rho = 1 edge, the tolerance edge, rounding,
exhaustion), shared by the serial and the batched drivers; the orbit's stability at rho = 1; event estimates
matched by pair and kind; a step response's overshoot sign and settling window."""
import math

import numpy as np
import pytest

from converters import compiled
from converters.analysis.accuracy import Estimate, _estimates, _guarded, paired_events
from converters.analysis.newton_kernel import newton_advance as jit_newton_advance
from converters.analysis.newton_kernel import newton_step as jit_newton_step
from converters.analysis.periodic import PeriodicOrbit
from converters.models.base import LOAD_BAND, SETTLED_PERIODS, SETTLING_BAND, step_response
from converters.parallel import run_ensemble
from converters.sweeps import Axis, Grid, ModelSweep

STEPS = {"jit": jit_newton_step, "ahead-of-time": None}


@pytest.fixture(params=list(STEPS))
def newton_step(request):
    """The kernel as numba's JIT runs it, and as the serial engine calls it (the ahead-of-time module)."""
    return STEPS[request.param] or compiled.kernel("newton_step")


def _verdict(newton_step, jac, rho, residual_vector, tol=1e-10, iteration=0, max_iter=50, x=None):
    n = jac.shape[0]
    x = np.zeros(n) if x is None else x
    step = np.empty(n)
    return newton_step(x, x + residual_vector, jac, rho, step, np.empty((n, n + 1)), tol, iteration, max_iter), step


def test_the_distance_is_bounded_by_the_residual_over_one_minus_rho(newton_step):
    """jac = 0.5 I: the Newton step is 2 r. With rho = 1 - 1e-5 given, the distance is r / 1e-5 = 1e-7, far above
    the step: not converged at tol 1e-10, though the step (2e-12) is far below it."""
    jac = 0.5 * np.eye(2)
    (residual, worst, distance, verdict), step = _verdict(newton_step, jac, 1 - 1e-5, np.array([1e-12, 0.0]))
    assert np.allclose(step, [2e-12, 0.0], rtol=1e-12, atol=0)
    assert worst == 1e-12 and residual == 1e-12
    assert distance == pytest.approx(1e-7, rel=1e-9) and verdict == compiled.NEWTON_CONTINUE
    (_, _, distance, verdict), _ = _verdict(newton_step, jac, 0.5, np.array([1e-12, 0.0]))
    assert distance == pytest.approx(2e-12, rel=1e-12) and verdict == compiled.NEWTON_CONVERGED


def test_at_rho_one_the_distance_is_the_newton_step_alone(newton_step):
    """rho = 1 bounds nothing (1 / (1 - rho) is infinite): the step is the estimate, and it converges."""
    (_, _, distance, verdict), _ = _verdict(newton_step, 0.5 * np.eye(2), 1.0, np.array([1e-12, 0.0]))
    assert distance == pytest.approx(2e-12, rel=1e-12) and verdict == compiled.NEWTON_CONVERGED


def test_the_tolerance_is_met_at_equality_and_not_an_ulp_above(newton_step):
    """Distance 2^-39 exactly (the step 2 x 2^-40 at scale 1): converged at tol = 2^-39, not at the float below."""
    r = np.array([2.0 ** -40, 0.0])
    tol = 2.0 ** -39
    (_, _, distance, verdict), _ = _verdict(newton_step, 0.5 * np.eye(2), 0.5, r, tol=tol)
    assert distance == tol and verdict == compiled.NEWTON_CONVERGED
    (_, _, _, verdict), _ = _verdict(newton_step, 0.5 * np.eye(2), 0.5, r, tol=np.nextafter(tol, 0.0))
    assert verdict == compiled.NEWTON_CONTINUE


def test_the_distance_is_relative_to_one_plus_the_largest_state(newton_step):
    """At x = (999, 0) the scale is 1000: a residual of 1e-9 with the step 2e-9 is a distance of 2e-12."""
    (residual, _, distance, verdict), _ = _verdict(newton_step, 0.5 * np.eye(2), 0.5, np.array([1e-9, 0.0]),
                                                   x=np.array([999.0, 0.0]))
    assert residual == pytest.approx(1e-12, rel=1e-6) and distance == pytest.approx(2e-12, rel=1e-6)
    assert verdict == compiled.NEWTON_CONVERGED


def test_rounding_exhaustion_and_a_multiplier_at_one_are_told_apart(newton_step):
    jac = 0.5 * np.eye(2)
    near_one = 1 - 1e-5                      # the residual's rounding amplified past the tolerance
    at_rounding = compiled.ROUNDING * np.finfo(float).eps
    (_, _, _, verdict), _ = _verdict(newton_step, jac, near_one, np.array([at_rounding, 0.0]), tol=1e-12)
    assert verdict == compiled.NEWTON_ROUNDING
    (_, _, _, verdict), _ = _verdict(newton_step, jac, near_one, np.array([2 * at_rounding, 0.0]), tol=1e-12)
    assert verdict == compiled.NEWTON_CONTINUE
    (_, _, _, verdict), _ = _verdict(newton_step, jac, near_one, np.array([1e-9, 0.0]), iteration=7, max_iter=7)
    assert verdict == compiled.NEWTON_EXHAUSTED
    (_, _, _, verdict), _ = _verdict(newton_step, jac, near_one, np.array([1e-9, 0.0]), iteration=6, max_iter=7)
    assert verdict == compiled.NEWTON_CONTINUE
    (_, _, distance, verdict), _ = _verdict(newton_step, np.eye(2), 1.0, np.array([1e-9, 0.0]))
    assert verdict == compiled.NEWTON_SINGULAR and distance == math.inf


ADVANCES = {"jit": jit_newton_advance, "ahead-of-time": None}


@pytest.fixture(params=list(ADVANCES))
def advance(request):
    """The driver as numba's JIT runs it (the batched steady states) and as the serial engine calls it."""
    return ADVANCES[request.param] or compiled.kernel("newton_advance")


class _Driver:
    """newton_advance's state and work arrays for an n-state map, and the requests it made."""

    def __init__(self, advance, x0, px, jac, tol=1e-12, max_iter=50):
        n = len(x0)
        self.advance, self.tol, self.max_iter = advance, tol, max_iter
        self.x, self.px, self.jac = np.array(x0, float), np.array(px, float), np.array(jac, float)
        self.dx, self.work = np.empty(n), np.empty((n, n + 1))
        self.trial, self.p_trial, self.jac_trial = np.empty(n), np.empty(n), np.empty((n, n))
        self.istate, self.rstate = np.zeros(4, dtype=np.int64), np.array([np.inf, np.inf, np.inf, 0.0])
        self.requests, self.trials = [], []

    def run(self, answer):
        """Drive to a verdict, answering each map request with ``answer(trial) -> (ok, P, P')``."""
        ok = True
        while True:
            verdict = self.advance(self.x, self.px, self.jac, self.dx, self.work, self.trial, self.p_trial,
                                   self.jac_trial, ok, self.istate, self.rstate, self.tol, self.max_iter)
            self.requests.append(int(verdict))
            if verdict == compiled.NEWTON_RADIUS:
                self.rstate[3] = max(abs(np.linalg.eigvals(self.jac)))
            elif verdict == compiled.NEWTON_EVALUATE:
                self.trials.append(self.trial.copy())
                ok, self.p_trial[:], self.jac_trial[:, :] = answer(self.trial)
            else:
                return int(verdict)


def test_the_driver_asks_for_rho_then_the_map_and_lands_on_an_affine_maps_fixed_point(advance):
    A, b = np.array([[0.5, 0.1], [0.0, -0.3]]), np.array([1.0, 2.0])
    star = np.linalg.solve(np.eye(2) - A, b)
    driver = _Driver(advance, [0.0, 0.0], b, A)
    verdict = driver.run(lambda x: (True, A @ x + b, A))
    R, E = compiled.NEWTON_RADIUS, compiled.NEWTON_EVALUATE
    assert verdict == compiled.NEWTON_CONVERGED and driver.requests == [R, E, R, compiled.NEWTON_CONVERGED]
    np.testing.assert_allclose(driver.trials[0], star, rtol=1e-15)      # Newton is exact on an affine map
    assert driver.istate[1] == 1 and driver.rstate[3] == pytest.approx(0.5)


def test_a_step_the_map_cannot_take_is_halved_eight_times_then_one_plain_period(advance):
    """A map refused at every trial: the steps dx, dx/2, ..., dx/128 are tried, then P(x) itself (a plain period);
    a plain period refused is NO_SOLUTION, one that leaves the finite numbers NONFINITE, one taken is accepted."""
    A, b = np.array([[0.5]]), np.array([1.0])
    for plain, expected in (((False, [0.0], [[0.0]]), compiled.NEWTON_NO_SOLUTION),
                            ((True, [np.nan], [[0.5]]), compiled.NEWTON_NONFINITE)):
        driver = _Driver(advance, [0.0], b, A)
        verdict = driver.run(lambda x: plain if np.array_equal(x, b) else (False, [0.0], [[0.0]]))
        assert verdict == expected
        steps = [t[0] for t in driver.trials]
        assert steps == [2.0 / 2 ** k for k in range(8)] + [1.0]       # dx = 2 (fixed point 2), halved; then P(0)
        assert driver.istate[3] == 1
    # a trial whose residual does not fall is refused like one the map cannot take
    driver = _Driver(advance, [0.0], b, A, max_iter=1)
    verdict = driver.run(lambda x: (True, x + 5.0, A) if len(driver.trials) < 9 else (True, A @ x + b, A))
    assert [t[0] for t in driver.trials] == [2.0 / 2 ** k for k in range(8)] + [1.0]
    assert driver.istate[1] == 1 and driver.istate[3] == 1 and verdict == compiled.NEWTON_EXHAUSTED


@pytest.mark.parametrize("multipliers, stable", [([1.0, 0.2], False), ([1.0 - 1e-12, 0.2], True),
                                                 ([-1.0, 0.5], False), ([0.6 + 0.8j, 0.1], False),
                                                 ([0.6 + 0.79j, 0.1], True), ([1.0 + 1e-12], False)])
def test_an_orbit_is_stable_only_with_every_multiplier_inside_the_unit_circle(multipliers, stable):
    orbit = PeriodicOrbit(np.zeros(1), 1.0, np.eye(1), np.array(multipliers, dtype=complex), 0.0, 0.0, 0, 0, True,
                          "exact")
    assert orbit.stable is stable and orbit.summary()["stable"] is stable


def test_a_batched_sweep_stops_where_the_serial_engine_does_near_rho_one():
    """Light loads (R up to 10 kohm, boost at D 0.3, L 10 uH: 1 - rho down to ~1e-5), where the residual alone
    would stop 1 / (1 - rho) too early: the batched driver takes the serial engine's iterations, point for point,
    and the same orbit."""
    grid = Grid([Axis.parse("R=100:10k:4:log"), Axis.parse("D=0.3:0.5:2")])
    sweep = ModelSweep("boost", base={"L": "10u"})
    serial = sorted(run_ensemble(sweep, grid, backend="serial"), key=lambda r: r["index"])
    batched = sorted(run_ensemble(sweep, grid, backend="batched"), key=lambda r: r["index"])
    assert all(r["status"] == "ok" for r in serial), [r["message"] for r in serial]
    assert max(r["spectral_radius"] for r in serial) > 1 - 1e-3                    # rho near 1 is in the grid
    assert [r["iterations"] for r in batched] == [r["iterations"] for r in serial]
    for a, b in zip(serial, batched):
        assert b["status"] == a["status"] and b["vout_mean"] == pytest.approx(a["vout_mean"], rel=1e-12)
        assert b["orbit_distance"] == pytest.approx(a["orbit_distance"], rel=1e-6, abs=1e-300)  # the same bound


def test_a_batched_sweep_bounds_the_distance_by_rho_where_the_newton_step_alone_would_not():
    """A lightly damped CCM buck (L 1 mH, C 1 uF, R 1 kohm: a complex pair of multipliers of modulus 0.995 at
    angle ~0.3 rad). The Newton step there is about residual / |1 - lambda|, far below the bound
    residual / (1 - rho) the driver states: a batch answering the driver with a wrong rho (0) reports the step
    (1.2e-15 against the serial engine's 2.3e-13, measured), so the bound it reports must be the serial one."""
    grid = Grid([Axis.parse("R=100:1k:2:log"), Axis.parse("D=0.9:0.9:1")])
    sweep = ModelSweep("buck", base={"L": "1m", "C": "1u"}, theta=1.0)      # the numbers above: backward Euler
    serial = sorted(run_ensemble(sweep, grid, backend="serial"), key=lambda r: r["index"])
    batched = sorted(run_ensemble(sweep, grid, backend="batched"), key=lambda r: r["index"])
    assert [r["mode"] for r in serial] == ["CCM", "CCM"] and serial[1]["spectral_radius"] > 0.99
    for a, b in zip(serial, batched):
        assert b["status"] == a["status"] == "ok" and b["iterations"] == a["iterations"]
        assert b["orbit_distance"] == pytest.approx(a["orbit_distance"], rel=1e-6, abs=0.0)
    assert serial[1]["orbit_distance"] > 1e-14                   # the rho bound, not the rounding-sized step


# --- event estimates: the same event, pair and kind -----------------------------------------------------------

def test_event_estimates_pair_events_of_the_same_pair_and_kind_only():
    """Two runs with as many events, one of them of another kind: not the same sequence, so no event gets an
    estimate (inf), and a previous run's estimate does not guard a different event."""
    fine = [(0, "release", 0.30), (0, "activate", 0.70)]
    coarse_same = [(0, "release", 0.31), (0, "activate", 0.69)]
    coarse_swapped = [(0, "activate", 0.31), (0, "release", 0.69)]
    coarse_other_pair = [(1, "release", 0.31), (0, "activate", 0.69)]
    assert paired_events(fine, coarse_same) == [(0, 0), (1, 1)] and paired_events(fine, coarse_swapped) is None
    assert paired_events(fine, coarse_other_pair) is None and paired_events(fine, coarse_same[:1]) is None
    _, events = _estimates({}, {}, fine, coarse_same, order=1.0, floor=0.0)
    assert [e.error_estimate for _, _, e in events] == pytest.approx([0.01, 0.01])
    for coarse in (coarse_swapped, coarse_other_pair):
        _, events = _estimates({}, {}, fine, coarse, order=1.0, floor=0.0)
        assert all(e.error_estimate == math.inf for _, _, e in events)
    now = [(0, "release", Estimate(0.30, 1e-6, 1.0)), (0, "activate", Estimate(0.70, 1e-6, 1.0))]
    before_same = [(0, "release", Estimate(0.31, 1.0, 1.0)), (0, "activate", Estimate(0.69, 1.0, 1.0))]
    before_other = [(0, "activate", Estimate(0.31, 1.0, 1.0)), (0, "release", Estimate(0.69, 1.0, 1.0))]
    _, guarded = _guarded({}, now, (100, {}, before_same), 200, 1.0)
    assert [e.error_estimate for _, _, e in guarded] == pytest.approx([0.05, 0.05])      # GUARD 0.1 x (1/2)^1 x 1
    _, unguarded = _guarded({}, now, (100, {}, before_other), 200, 1.0)
    assert [e.error_estimate for _, _, e in unguarded] == [1e-6, 1e-6]


def test_events_of_different_pairs_that_swap_places_keep_their_estimates():
    """A 12-stage ladder on a SIN source: its diodes d22 and d24 become held at nearly one instant and swap places
    from 1,600 to 3,200 steps a period; a strict order gave every event an infinite estimate, so --rtol 1e-3
    doubled the step count to 102,400 (100 s, 7.5 GB) with every mean already within 5e-6. Each pair's own
    sequence still decides: its k-th event pairs with its k-th."""
    fine = [("d24", "held", 0.1201), ("d22", "held", 0.1207), ("d22", "release", 0.5), ("d24", "release", 0.6)]
    coarse = [("d22", "held", 0.1206), ("d24", "held", 0.1208), ("d22", "release", 0.52), ("d24", "release", 0.62)]
    assert paired_events(fine, coarse) == [(0, 1), (1, 0), (2, 2), (3, 3)]
    _, events = _estimates({}, {}, fine, coarse, order=1.0, floor=0.0)
    assert [e.error_estimate for _, _, e in events] == pytest.approx([7e-4, 1e-4, 0.02, 0.02])
    previous = [(pair, kind, Estimate(t, 1e-3, 1.0)) for pair, kind, t in coarse]
    _, guarded = _guarded({}, events, (100, {}, previous), 200, 1.0)
    assert [e.error_estimate for _, _, e in guarded] == pytest.approx([7e-4, 1e-4, 0.02, 0.02])
    now = [(pair, kind, Estimate(t, 0.0, 1.0)) for pair, kind, t in fine]
    _, guarded = _guarded({}, now, (100, {}, previous), 200, 1.0)
    assert [e.error_estimate for _, _, e in guarded] == pytest.approx([5e-5] * 4)      # 0.1 x (1/2) x 1e-3
    reordered = [("d22", "release", 0.1206), ("d24", "held", 0.1208), ("d22", "held", 0.52), ("d24", "release", 0.6)]
    assert paired_events(fine, reordered) is None                          # d22's own sequence differs


# --- a step response on known per-period means --------------------------------------------------------------

class _Means:
    """A run whose per-period means of vout are given: period j of [t0 + jT, t0 + (j + 1) T] has means[j]."""

    def __init__(self, means, T=1.0):
        self.means, self.T = np.asarray(means, dtype=float), T
        self.t = np.array([0.0, len(means) * T])

    def mean(self, name, t0, t1):
        assert name == "vout" and t1 - t0 == pytest.approx(self.T)
        return self.means[int(round(t0 / self.T))]


UP = [10.0] * 10 + [12.5, 11.3, 12.2, 11.9, 12.05, 12.0, 12.03, 11.97] + [12.0] * 12
DOWN = [14.0] * 10 + [11.5, 12.3, 11.8, 12.1, 11.95, 12.0, 11.97, 12.03] + [12.0] * 12


@pytest.mark.parametrize("means, deviation", [(UP, 0.7), (DOWN, 0.5)])
def test_a_step_overshoots_past_its_final_value_in_the_steps_direction(means, deviation):
    """Up from 10 V, the means reach 12.5 above the final 12 V (then dip 0.7 below it: a deviation, not an
    overshoot); down from 14 V, 11.5 below it (then 12.3 above: not an overshoot of a downward step): 0.5 V each
    way, a quarter of the 2 V step."""
    step = step_response(_Means(means), t_step=10.0, T=1.0, target=12.0)
    assert step["overshoot_V"] == pytest.approx(0.5, abs=1e-12)
    assert step["overshoot_of_step"] == pytest.approx(0.25, abs=1e-12)
    assert step["overshoot_percent"] == pytest.approx(100 * 0.5 / 12.0, abs=1e-12)
    assert step["deviation_V"] == pytest.approx(deviation, abs=1e-12)


def test_a_step_that_undershoots_only_has_no_overshoot():
    means = [10.0] * 10 + [11.0, 11.6, 11.9, 11.99] + [12.0] * 12
    assert step_response(_Means(means), t_step=10.0, T=1.0, target=12.0)["overshoot_V"] == 0.0


def test_settling_ends_with_the_last_period_outside_the_band_and_settled_needs_ten_inside():
    """The band is 2 % of the 2 V step, 0.04 V: the last mean outside it is 12.05, the 5th period after the step,
    so settling takes 5 periods; 12.03 and 11.97 are inside. Ten periods inside at the end make it settled."""
    assert SETTLING_BAND == 0.02 and SETTLED_PERIODS == 10 and LOAD_BAND == 1e-3
    step = step_response(_Means(UP), t_step=10.0, T=1.0, target=12.0)
    assert step["band_V"] == pytest.approx(0.04, abs=1e-12)
    assert step["settling_time_s"] == pytest.approx(5.0, abs=1e-12) and step["settled"]
    for inside in (SETTLED_PERIODS, SETTLED_PERIODS - 1):   # after 12.05: 12.0, 12.03, 11.97, then 12.0s
        means = UP[:18] + [12.0] * (inside - 3)
        assert step_response(_Means(means), t_step=10.0, T=1.0, target=12.0)["settled"] is (inside == SETTLED_PERIODS)
    late = UP[:-1] + [12.5]                             # outside in the last period: settling runs to the end
    step = step_response(_Means(late), t_step=10.0, T=1.0, target=12.0)
    assert step["settling_time_s"] == pytest.approx(len(late) - 10.0, abs=1e-12) and not step["settled"]
