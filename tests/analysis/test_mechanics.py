"""The mechanical studies (converters.analysis.mechanics) against closed forms, independent period maps and the
physics each regime implies: the two blocks' chaos and cycles, the cam-follower's chattering, its corner impacts and
grazings, the friction oscillator's domain of attraction."""
import warnings

import numpy as np
import pytest

from validation.defaults import MECHANICS


@pytest.mark.slow
def test_two_blocks_on_a_belt_chaos_at_low_speed_cycles_above_after_the_transient_has_decayed():
    """Each regime by a test that can fail on physics. At V = 0.1 m/s no cycle of up to half the recorded section
    points closes to 1e-9 and the largest Lyapunov exponent's 95 % interval lies above zero (0.114 +- 0.050 per time
    unit). At 0.46 (17 distinct section points after the old 60-unit transient) and 0.8 the section's states close
    into cycles of 2 and 1 points, every recorded point equal to the one k on to 1e-9 over 500 time units after a
    500-unit transient (so not a slow transient), and the exponent's interval contains the flow's zero."""
    from converters.analysis.mechanics import two_block_regime
    chaos, two, one = (two_block_regime({"V": V}) for V in (0.1, 0.46, 0.8))
    assert chaos["regime"] == "chaotic" and chaos["period"] == 0 and chaos["sections"] > 100
    assert chaos["lyapunov"] - chaos["half_width"] > 0.02
    for row, k in ((two, 2), (one, 1)):
        assert row["regime"] == "periodic" and row["period"] == k and max(row["closing"]) <= 1e-9
        assert abs(row["lyapunov"]) <= row["half_width"] < 0.02 and row["sections"] > 300


@pytest.mark.slow
def test_complete_chattering_at_175_rpm_and_incomplete_at_358():
    """The seed's 175 rpm: each revolution's impacts accumulate (completed in closed form), the follower then
    riding the cam; Siconos' 358 rpm: impacts that never accumulate before the next lift."""
    from converters.analysis.mechanics import chattering_table
    table = chattering_table({}, [100.0, 175.0, 358.0], workers=1).set_index("rpm")
    assert table.loc[100.0, "regime"] == "no impacts"
    assert table.loc[175.0, "regime"] == "complete chattering" and table.loc[175.0, "accumulations_per_revolution"] == 1
    assert table.loc[358.0, "regime"] == "incomplete chattering" and table.loc[358.0, "impacts_per_revolution"] > 1


@pytest.mark.slow
def test_complete_chattering_ends_where_its_ride_left_reaches_zero():
    """The period-one complete-chattering orbit (from the detachment, its impacts accumulate, it rides the cam to the
    next detachment) ends near 253 rpm where the ride left reaches zero; located to 1e-6 rpm from the side where it
    exists, the ride shrinking linearly into it; and the attractor from rest changes regime there: every revolution
    accumulates 0.02 rpm below it, not every one 0.02 rpm above."""
    from converters.analysis.mechanics import chattering_transition, ride_left
    from converters.analysis.mechanics.impacts import _Chattering
    found = chattering_transition({}, 250.0, 254.0)
    assert found["side"] == "below" and found["width"] <= 1e-6 and 0.0 < found["last"]["ride"] <= 1e-6
    assert found["rpm"] == pytest.approx(252.99229, abs=2e-5)
    r1, r2 = (ride_left({}, found["rpm"] - d)["ride"] for d in (0.02, 0.01))
    assert r1 > r2 > 0.0
    assert found["rpm"] - 0.01 + r2 * 0.01 / (r1 - r2) == pytest.approx(found["rpm"], abs=1e-3)
    assert ride_left({}, found["rpm"] + 0.01)["ride"] is None
    below, above = (_Chattering({}, transient=2, record=4)(found["rpm"] + d) for d in (-0.02, 0.02))
    assert below["regime"] == "complete chattering" and below["accumulations_per_revolution"] == 1.0
    assert above["accumulations_per_revolution"] < 1.0


@pytest.mark.slow
def test_domain_of_attraction_at_A_3_6_two_converged_orbits_and_a_resolved_boundary():
    """The seed's domain of attraction (A = 3.6, omega = 1.067): every initial state of the grid reaches one of two
    period-one orbits (converged by Newton on the event method's exact map, residual below 1e-10, stable), and a
    grid twice finer changes no cell off the basin boundary."""
    from converters.analysis.mechanics import basins, resolution_check
    box = dict(params={"A": 3.6, "omega": 1.067}, x_range=(-4.0, 4.0), v_range=(-4.0, 4.0))
    coarse = basins(n=20, refine=1, backend="local", workers=2, **box)
    fine = basins(n=39, refine=1, backend="local", workers=2, **box)
    serial = basins(n=5, refine=1, backend="serial", **box)     # the backends agree, state for state
    assert (serial.labels == basins(n=5, refine=1, backend="local", workers=2, **box).labels).all()
    assert len(coarse.attractors) == 2 and (coarse.labels >= 0).all() and (fine.labels >= 0).all()
    for a in coarse.attractors:
        assert a["period"] == 1 and a["residual"] < 1e-10 and max(a["multipliers"]) < 1.0
    sticking = [a for a in coarse.attractors if a["points"][0][1] == pytest.approx(1.0, abs=1e-12)]
    assert len(sticking) == 1                       # one of them starts each period stuck to the belt (v = Vdr)
    check = resolution_check(coarse, fine)
    assert check["off_boundary"] == 0 and 0 < check["boundary_cells"] < check["cells"]


def _cam_period_closed_form(rpm: float, x0, e: float = 0.8, m: float = 1.221, k: float = 1430.8, t0: float = 0.0,
                            revolutions: int = 1):
    """An independent period map of the cam-follower (no ODE solver, no event engine): the flight is m x'' + k x = 0 in
    closed form, each impact the first sign change of the gap x - c(t) on a grid of T/20000 refined by Brent, Newton's
    law v+ = c' - e (v- - c'). From x0 at t0 over ``revolutions``: returns (the end state, the impact times)."""
    from scipy.optimize import brentq

    from converters.models.mechanics.cam import CamOffset
    cam = CamOffset(2 * np.pi * rpm / 60)
    w, T = np.sqrt(k / m), 60 / rpm
    t, (x, v), impacts = t0, map(float, x0), []
    end = t0 + revolutions * T

    def flight(s):
        return x * np.cos(w * (s - t)) + v / w * np.sin(w * (s - t))
    while True:
        grid = np.linspace(t, end, max(3, int((end - t) / T * 20000)))
        gap = flight(grid) - cam.position(grid)[0]
        below = np.flatnonzero(gap[1:] < 0)
        if not below.size:
            x, v = flight(end), -x * w * np.sin(w * (end - t)) + v * np.cos(w * (end - t))
            return np.array([x, v]), impacts
        j = below[0] + 1
        hit = brentq(lambda s: flight(s) - cam.position(s)[0], grid[j - 1], grid[j], xtol=1e-15, rtol=1e-15)
        x, v = flight(hit), -x * w * np.sin(w * (hit - t)) + v * np.cos(w * (hit - t))
        c1 = float(cam.position(hit)[1])
        v = c1 - e * (v - c1)
        t = hit                                       # leaving the cam: the gap grows from zero (gap[1:] is tested)
        impacts.append(hit)


@pytest.mark.slow
def test_the_cam_p21_orbit_ends_in_a_corner_impact_at_the_flank_nose_joint():
    """The cam-follower's P(2, 1) orbit (two impacts a revolution), continued down in cam speed on the event method's
    map with its exact Jacobian (impact saltation), turns at 355.15 rpm where its first impact reaches the joint of
    the flank and the nose (beta = pi/2 + beta2, where h_c'' jumps): a corner-impact bifurcation, here a nonsmooth
    fold. Checked: the map's Jacobian against central differences (1e-6); the located orbit periodic and its impact
    on the joint to 1e-9, and again under an independent closed-form period map; above the corner a stable orbit
    (complex multipliers inside the circle) and a saddle (one multiplier above 1) meet there, det(I - J) of opposite
    signs (Feigin's condition for a nonsmooth fold), and no P(2, 1) orbit is found 0.01 rpm below it."""
    from converters.analysis.continuation import follow
    from converters.models.mechanics.cam import JOINTS
    from converters.analysis.mechanics import cam_family, corner_impacts, impact_angles
    family = cam_family({})
    seed = family.orbit(380.0, np.array([0.70, -6.27]))
    assert seed.converged
    end, jac = family.period_map(380.0)(seed.x0)
    central = np.column_stack([(family.period_map(380.0).end(seed.x0 + d) - family.period_map(380.0).end(seed.x0 - d))
                               / (2 * d[j]) for j, d in enumerate(np.eye(2) * 1e-6)])
    assert np.abs(jac - central).max() <= 1e-6 * np.abs(jac).max()
    assert family.period_map(380.0).jacobian_kind == "exact"                      # saltation, not differences
    branch = follow(family, 358.0, 354.0, seed.x0, warm_up=0, tol=1e-9, locate_tol=1e-7, fd_step=1e-6, max_step=0.5)
    corners = corner_impacts(family, branch)
    assert len(corners) == 1
    corner = corners[0]
    assert corner.joint == "flank | nose (rise)" and corner.kind == "nonsmooth fold" and corner.impact == 0
    assert abs(corner.rpm - 355.15452) < 1e-4 and corner.residual <= 1e-9 and abs(corner.off_joint) <= 1e-9
    assert "turns at a border collision" in branch.message                       # the corrector stopped there
    assert abs(branch.points[-1].value - corner.rpm) <= 1e-5
    end, impacts = _cam_period_closed_form(corner.rpm, corner.x0)
    assert np.abs(end - corner.x0).max() <= 1e-8 * (1 + np.abs(corner.x0).max()) and len(impacts) == 2
    beta = np.mod(2 * np.pi * corner.rpm / 60 * impacts[0] + np.pi / 2, 2 * np.pi)
    assert abs(beta - JOINTS["flank | nose (rise)"]) <= 1e-8
    assert len(corner.sides) == 2
    (value_s, _, stable, angle_s), (value_u, _, saddle, angle_u) = sorted(corner.sides, key=lambda s: np.abs(s[2]).max())
    assert value_s == value_u == corner.rpm + corner.offset
    assert np.abs(stable).max() < 1 and abs(stable[0].imag) > 0.1
    assert np.abs(saddle).max() > 1.05 and np.abs(saddle).min() < 1
    dets = [np.prod(1 - mu).real for mu in (stable, saddle)]
    assert dets[0] * dets[1] < 0
    assert (angle_s - corner.angle) * (angle_u - corner.angle) < 0                  # either side of the joint
    below = family.orbit(corner.rpm - 0.01, corner.x0)
    assert not below.converged or np.abs(impact_angles(family, corner.rpm - 0.01, below.x0)[0]
                                         - corner.angle) > 0.01


def test_a_corner_reached_from_several_starts_is_reported_once_the_best_located(monkeypatch):
    """A branch whose impact passes a joint between two orbits and that stops next to it starts the location twice
    (the pair, the end); the corner is one: the better located of the two is kept."""
    from types import SimpleNamespace

    from converters.models.mechanics.cam import JOINTS
    from converters.analysis.mechanics import impacts as mechanics
    joint = JOINTS["flank | nose (rise)"]
    angles = {1.0: [joint - 1e-2], 2.0: [joint + 1e-4], 3.0: [joint + 2e-4]}
    monkeypatch.setattr(mechanics, "impact_angles", lambda family, value, x0: np.array(angles[value]))
    located = iter([(1.99 + 1e-5, 1e-6), (1.99, 1e-9)])

    def corner_impact(family, name, impact, rpm, x0, offset=1e-3):
        value, residual = next(located)
        return mechanics.CornerImpact(name, joint, impact, value, np.zeros(2), residual, 0.0, offset, (), "persistence")
    monkeypatch.setattr(mechanics, "corner_impact", corner_impact)
    branch = SimpleNamespace(points=[SimpleNamespace(value=v, x0=np.zeros(2)) for v in (1.0, 2.0, 3.0)],
                             message="the corrector stopped")
    (corner,) = mechanics.corner_impacts(None, branch)
    assert corner.rpm == 1.99 and corner.residual == 1e-9


@pytest.mark.slow
def test_past_complete_chattering_an_orbit_of_two_revolutions_superstable_and_its_end_located():
    """Past the end of complete chattering (252.99229 rpm) the follower's sequence is cut by the lift and a later
    revolution's completes: at 256 and 257.3 rpm the orbit from the detachment accumulates once in n = 2
    revolutions, at 257.5 in 3; the two-revolution orbit's end between them is located where its ride falls to zero
    (its accumulation reaches the detachment two revolutions on). The orbit is superstable: a start 10 um and
    1 mm/s off the detachment state differs by more than 1e-6 m a revolution later, and a quarter revolution after
    the detachment two revolutions on is where the unperturbed orbit is, to 1e-9 m; its ride is the same, to 1e-8
    of a revolution, with the ODE's tolerance 100 times finer."""
    from converters.models.mechanics import get_mechanical
    from converters.methods import EventDriven
    from converters.simulate import simulate
    from converters.analysis.mechanics import impacts as mechanics
    from converters.analysis.mechanics import chattering_orbit, chattering_windows
    from converters.analysis.mechanics.impacts import _detachment
    found = chattering_windows({}, [257.3, 257.5], revolutions=3, workers=1)
    assert [row["n"] for row in found["rows"]] == [2, 3]
    end = next(b for b in found["borders"] if b["n"] == 2)
    assert end["side"] == "below" and end["rpm"] == pytest.approx(257.39055, abs=1e-4)
    assert end["width"] <= 1e-6 and 0.0 < end["ride"] <= 1e-5, end
    coarse = chattering_orbit({}, 256.0, 2)
    mechanics.EventDriven, default = (lambda: EventDriven(ode_rtol=1e-11)), mechanics.EventDriven
    try:
        fine = chattering_orbit({}, 256.0, 2)
    finally:
        mechanics.EventDriven = default
    assert coarse["n"] == fine["n"] == 2 and coarse["ride"] > 0.1
    assert abs(coarse["ride"] - fine["ride"]) <= 1e-8

    model = get_mechanical("cam-follower")
    p = model.resolve({"rpm": 256.0})
    T, t_d = model.period(p), _detachment(model, p)
    c, c1, _ = model.offset(p).position(t_d)

    def state(start, t_end):
        run = simulate(model.problem(p, t_end, np.array([c, c1]) + start, t_start=t_d), EventDriven())
        assert run.t[-1] == t_end
        return run.x[-1], run.events
    quarter, _ = state(np.zeros(2), t_d + 0.25 * T)              # in flight, a quarter revolution after leaving
    for start in (np.zeros(2), np.array([1e-5, 1e-3])):
        again, events = state(start, t_d + 2.25 * T)
        detach = events[(events["kind"] == "detach") & (events["time"] > t_d + 1e-9 * T)]["time"].to_numpy()
        assert detach[0] == pytest.approx(t_d + 2 * T, abs=1e-9 * T)
        np.testing.assert_allclose(again, quarter, atol=1e-9, rtol=0)
    flights = [state(start, t_d + T)[0] for start in (np.zeros(2), np.array([1e-5, 1e-3]))]
    assert abs(flights[0][0] - flights[1][0]) > 1e-6


@pytest.mark.slow
def test_an_incomplete_orbit_is_continued_through_the_end_of_complete_chattering_from_a_corner_to_a_grazing():
    """Through the transition: an incomplete-chattering orbit of one revolution (twelve impacts, its sequence cut by
    the lift every revolution, none accumulating), continued in cam speed with its exact multipliers from 248 rpm,
    below the end of complete chattering at 252.99229 rpm (where it coexists with the superstable complete-chattering
    orbit), through it unchanged, to 259.1804 rpm, where the flight that leaves the cam at the lift grazes the cam and
    a thirteenth impact appears (a border collision). Unstable all along: one multiplier 120-152, the other below
    1e-4. Below 248 rpm its last impact reaches the flank-nose joint of the profile, where the cam lifts away:
    a corner impact at 247.91494 rpm, a nonsmooth fold with an orbit whose last impact falls past the joint
    (multiplier -505; det(I - J) of opposite signs), no such orbit 0.001 rpm below. Checked against an independent
    closed-form map: at the end of complete chattering it closes the orbit to 5e-8 with twelve impacts and its
    central differences give the same multiplier to 1e-6; the angle of its orbits' last impact reaches the joint at
    the corner found, to 1e-6 rpm, with no orbit 0.001 rpm below; at the branch's last orbit, 2e-5 rpm before the
    grazing, its flight after the last impact passes within 1e-8 m of the cam (at 253.5 rpm the gap only grows)."""
    from converters.models.mechanics.cam import CamOffset
    from converters.analysis.mechanics import chattering_orbit, incomplete_across
    family, branch, (corner,) = incomplete_across(MECHANICS["across"])
    values = branch.values()
    end_of_complete = 252.9922856
    assert values[0] == 248.0 and 259.18 < values[-1] < 259.1805 and np.all(np.diff(values) > 0)
    assert chattering_orbit({}, 252.98, 1)["n"] == 1                        # complete chattering coexists below
    for pt in branch.points:
        events = family._events(pt.value, pt.x0)
        assert [e[1] for e in events] == ["impact"] * 12                    # incomplete: no accumulation, no ride
        radius = np.sort(np.abs(pt.multipliers))
        assert 120.0 < radius[1] < 152.0 and radius[0] < 1e-4
    (grazing,) = branch.bifurcations
    assert grazing.kind == "border-collision" and "appear: cam impact" in grazing.detail
    assert grazing.value == pytest.approx(259.1804, abs=1e-4)
    # located where the flight's least clearance reaches zero: 259.18040 rpm (the closed-form flights' clearance
    # extrapolates there; the event method's bracket, where it sees the touch within its tolerance, is 2e-5 early)
    from converters.analysis.mechanics import locate_grazing
    located, clearances = locate_grazing(family, branch, grazing)
    assert located == pytest.approx(259.18040, abs=5e-6) and located > grazing.value + 0.5 * grazing.width
    assert all(0.0 < gap < 3e-8 for _, gap in clearances)
    assert branch.message.startswith("stopped at the border-collision")

    near = min(branch.points, key=lambda pt: abs(pt.value - end_of_complete))
    at = family.orbit(end_of_complete, near.x0)
    assert at.converged
    t0 = family.problem_of(end_of_complete).t_span[0]
    end, impacts = _cam_period_closed_form(end_of_complete, at.x0, t0=t0)
    assert np.abs(end - at.x0).max() <= 5e-8 and len(impacts) == 12
    step = np.eye(2) * 1e-7
    jac = np.column_stack([(_cam_period_closed_form(end_of_complete, at.x0 + d, t0=t0)[0]
                            - _cam_period_closed_form(end_of_complete, at.x0 - d, t0=t0)[0]) / 2e-7 for d in step])
    assert np.abs(np.linalg.eigvals(jac)).max() == pytest.approx(np.abs(at.multipliers).max(), rel=1e-6)

    assert corner.joint == "flank | nose (rise)" and corner.impact == 11 and corner.kind == "nonsmooth fold"
    assert corner.rpm == pytest.approx(247.91494, abs=1e-4) and corner.residual <= 1e-7
    assert abs(corner.off_joint) <= 1e-9
    assert all(side[0] > corner.rpm for side in corner.sides)              # nothing below the corner
    past = [side for side in corner.sides if side[3] > corner.angle]        # its last impact past the joint
    assert len(past) == 1 and np.abs(past[0][2]).max() > 100
    assert np.prod(1 - branch.points[0].multipliers).real * np.prod(1 - past[0][2]).real < 0
    # Independently, on the closed-form map (its start at the same phase of the revolution): the branch's orbits
    # down to 0.001 rpm above the corner have their twelfth impact before the joint, its angle a straight line in
    # the speed there whose zero is the corner found; 0.001 rpm below there is no orbit.
    from scipy.optimize import fsolve
    phase = family.problem_of(corner.rpm).t_span[0] * corner.rpm / 60.0

    def closed(rpm, x):
        return _cam_period_closed_form(rpm, x, t0=phase * 60.0 / rpm)
    x, off = branch.points[0].x0, []
    speeds = (247.95, 247.93, 247.92, 247.917, 247.916, 247.9155, 247.915)   # steps short enough to keep to it
    with warnings.catch_warnings():         # fsolve's "not making good progress" at 1e-13: the residuals are asserted
        warnings.simplefilter("ignore", RuntimeWarning)
        for rpm in speeds:
            x = fsolve(lambda y: closed(rpm, y)[0] - y, x, xtol=1e-13)
            end, impacts = closed(rpm, x)
            off.append(np.mod(2 * np.pi * rpm / 60 * impacts[-1] + np.pi / 2, 2 * np.pi) - corner.angle)
            assert np.abs(end - x).max() <= 1e-10 and len(impacts) == 12 and off[-1] < 0.0
        below = fsolve(lambda y: closed(corner.rpm - 1e-3, y)[0] - y, x, xtol=1e-13)
    zero = speeds[-1] - off[-1] * (speeds[-2] - speeds[-1]) / (off[-2] - off[-1])
    assert abs(zero - corner.rpm) <= 1e-6
    assert np.abs(closed(corner.rpm - 1e-3, below)[0] - below).max() > 1e-7

    def clearance(pt):
        """The least local minimum of the gap (m) along the closed-form flight from the last impact to the map's end
        (the lift); inf where the gap only grows."""
        t_start = family.problem_of(pt.value).t_span[0]
        (x, v), hits = _cam_period_closed_form(pt.value, pt.x0, t0=t_start)
        t_end, w = t_start + 60.0 / pt.value, np.sqrt(1430.8 / 1.221)
        s = np.linspace(hits[-1], t_end, 400001)
        gap = x * np.cos(w * (s - t_end)) + v / w * np.sin(w * (s - t_end)) - CamOffset(2 * np.pi * pt.value / 60
                                                                                          ).position(s)[0]
        slope = np.diff(gap)
        minima = np.flatnonzero((slope[:-1] < 0) & (slope[1:] >= 0)) + 1
        return float(gap[minima].min()) if minima.size else np.inf
    start = min(branch.points, key=lambda pt: abs(pt.value - 253.5))
    assert clearance(start) == np.inf and 0.0 < clearance(branch.points[-1]) < 1e-8


@pytest.mark.slow
def test_an_incomplete_chattering_orbit_continued_down_in_speed_ends_in_a_fold():
    """From the other side of the transition: the stable P(6, 2) orbit of incomplete chattering at 330 rpm (three
    impacts a revolution, none accumulating; complex multipliers of modulus 0.26), continued down in cam speed on the
    event method's map with its exact Jacobian, ends in a smooth fold at 321.4332 rpm (a multiplier through +1, the
    other 0.069), where it meets its unstable twin. An independent closed-form map (harmonic flights, impacts by
    Brent, Newton's law) closes the orbits near the fold to 1e-8 with their six impacts; no such orbit 0.05 rpm
    below the fold."""
    from converters.analysis.mechanics import cam_family, incomplete_orbit
    family, branch = incomplete_orbit(MECHANICS["incomplete"])
    first = branch.points[0]
    assert first.value == 330.0 and first.stable and abs(first.multipliers[0].imag) > 0.1
    assert np.abs(first.multipliers).max() == pytest.approx(0.2621, abs=1e-3)
    folds = [b for b in branch.bifurcations if b.kind == "fold"]
    assert len(folds) == 1 and folds[0].value == pytest.approx(321.4332, abs=1e-3)
    fold = folds[0]
    assert np.abs(fold.multipliers).max() == pytest.approx(1.0, abs=1e-3)
    assert abs(np.sort(np.abs(fold.multipliers))[0] - 0.069) < 0.005
    assert fold.stable_before != fold.stable_after
    near = min(branch.points, key=lambda pt: abs(pt.value - fold.value))
    end, impacts = _cam_period_closed_form(near.value, near.x0, t0=0.78 * 60.0 / near.value, revolutions=2)
    assert np.abs(end - near.x0).max() <= 1e-8 * (1 + np.abs(near.x0).max()) and len(impacts) == 6
    below = cam_family({}, 2, 0.78).orbit(fold.value - 0.05, fold.x0)
    assert not below.converged or len([1 for _, kind, *_ in cam_family({}, 2, 0.78).period_map(fold.value - 0.05)
                                       .events(below.x0) if kind == "impact"]) != 6


@pytest.mark.parametrize("omega, mode, exact", [(2.5, "slip+", 0.1274194), (1.7, "stick", 0.0095632)])
def test_a_mechanisms_mode_fractions_hold_each_mode_up_to_its_event(omega, mode, exact):
    """The friction oscillator at A = 5: the time in each mode over the last time scale, against a tester's
    integration (scipy DOP853 at rtol 1e-12 with the events located, the stick phase in closed form). On the output
    grid, a sample at an event carrying the mode after it, slip+ had read 0.130 (2 % high) and the stick 0.010
    (4.6 %)."""
    from dataclasses import replace

    from converters.methods.base import get_method
    from converters.models.mechanics import get_mechanical
    from converters.simulate import simulate
    model = get_mechanical("friction")
    p = model.resolve({"A": 5.0, "omega": omega})
    run = simulate(model.problem(p, 60 * model.time_scale(p)), get_method("event").from_options(step=None))
    fractions = model.summary(replace(run, labels=model.labels(p)), p)["mode_fractions"]
    assert fractions[mode] == pytest.approx(exact, abs=1e-6)
    assert sum(fractions.values()) == pytest.approx(1.0, abs=1e-12)
