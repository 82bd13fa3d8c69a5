"""The mechanical module in the report's ``mechanics`` suite: each section runs a study of
:mod:`converters.analysis.mechanics` with the seed's settings (``[mechanics]`` of ``data/defaults.toml``), checks it
against the seed's values and closed forms, and draws it.
"""
from __future__ import annotations

import numpy as np

from converters.analysis.mechanics import (ball_check, basins, cam_checks, cam_continuation, chattering_table,
                                           chattering_transition, chattering_windows, degenerate_portraits,
                                           degenerate_switching, friction_agreement, friction_diagram,
                                           impact_phase_diagram, incomplete_across, incomplete_orbit, locate_grazing,
                                           resolution_check, sliding_study, two_block_diagram, two_block_regime,
                                           two_block_regimes)
from converters.methods import EventDriven
from converters.models.mechanics import get_mechanical
from converters.simulate import simulate


def _orbit_run(model, p: dict, name: str, point, periods: int):
    """One period of a continuation orbit (the event method), labelled."""
    from dataclasses import replace
    q = model.resolve({**p, name: point.value})
    run = simulate(model.problem(q, periods * model.period(q), point.x0), EventDriven())
    return replace(run, labels=model.labels(q))


def _sides(branch, value):
    """The branch's orbits just below and just above ``value``."""
    points = sorted(branch.points, key=lambda pt: pt.value)
    below = [pt for pt in points if pt.value < value]
    above = [pt for pt in points if pt.value > value]
    return (below[-1] if below else None), (above[0] if above else None)


def sliding_section():
    """The seed's four sliding bifurcations of the dry-friction oscillator: located, named, against the seed."""
    import pandas as pd

    from .defaults import MECHANICS, SEED_SLIDING
    from .mechanics_plots import diagram_figure, phase_portraits
    from .report import Section, csv_bytes, table_html
    model = get_mechanical("friction")
    studies = {}
    for row in SEED_SLIDING:
        key = (row["A"], tuple(row["path"]))
        if key not in studies:
            studies[key] = sliding_study("friction", {"A": row["A"]}, "omega", *row["path"])
    rows, panels, ok = [], [], True
    for row in SEED_SLIDING:
        study = studies[(row["A"], tuple(row["path"]))]
        found = [b for b in study.bifurcations if b.kind == row["type"]]
        if "seed" in row:
            best = min(found, key=lambda b: abs(b.value - row["seed"])) if found else None
            error = abs(best.value / row["seed"] - 1.0) if best else float("inf")
            # a bracket wider than the tolerance locates nothing to it: a failure, whatever its midpoint
            passed = best is not None and error <= row["tolerance"] and best.width <= row["tolerance"] * abs(best.value)
            reference, limit = f"{row['seed']:g}", f"{row['tolerance']:.1%}"
        else:
            low, high = row["seed_range"]
            best = next((b for b in found if low <= b.value <= high), None)
            error = float("nan")
            passed = best is not None and best.width <= row["width"] * abs(best.value)
            reference, limit = f"between {low:g} and {high:g}", f"inside, bracket {row['width']:.0e}"
        ok = ok and passed
        rows.append({"type": row["type"], "A (N)": row["A"], "path (rad/s)": f"{row['path'][0]:g}..{row['path'][1]:g}",
                     "seed": reference, "found": f"{best.value:.7f}" if best else "none",
                     "relative difference": error, "limit": limit,
                     "bracket": f"{best.width:.1e}" if best else "", "orbit period (T)": best.period if best else "",
                     "located by": best.located_by if best else "", "result": "pass" if passed else "fail"})
        if best is not None:
            branch = next(br for br in study.branches if best in br.bifurcations)
            for label, point in zip(("below", "above"), _sides(branch, best.value)):
                if point is not None:
                    panels.append((f"{row['type'].capitalize()} Bifurcation, A = {row['A']:g}: W = {point.value:.5g} ({label})",
                                   _orbit_run(model, {"A": row["A"]}, "omega", point, branch.period)))
    table = pd.DataFrame(rows)
    A = MECHANICS["friction_diagram_A"]
    diagram_study = next(s for (a, _), s in studies.items() if a == A)
    attractors = friction_diagram({"A": A}, "omega", np.linspace(*diagram_study_path(diagram_study),
                                                                 MECHANICS["friction_diagram_points"]), workers=1)
    notes = "".join(f"<li>A = {s.params['A']:g}: {'; '.join(s.notes)} ({s.wall_s:.0f} s)</li>" for s in studies.values())
    text = ("<p>The dry-friction oscillator on a moving belt (Popp and Stelter 1990; k = m = 1, g = 10, Vdr = 1, Popp's law alpha = "
            "0.3, gamma = 1.42, beta = 0.1, eta = 0.01) forced by A cos(omega t). Each path is followed by "
            "pseudo-arclength continuation on the event method's exact stroboscopic map (DOP853 between events, "
            "variational equations, saltation matrices, the sliding projector); each change of the orbit's event "
            "signature is bracketed by bisection and named from the short piece of orbit born there "
            "(<code>converters.analysis.sliding</code>). Against the seed's values:</p>"
            + table_html(table, "result", good=("pass",)) + f"<ul>{notes}</ul>"
            + "<img src='friction_orbits.png' alt='phase portraits'>"
            + f"<p>Brute force at A = {A:g} (Moreau-Jean, h = T/1000, x(nT) after 150 periods) with the located "
              "bifurcations and the continued orbit:</p><img src='friction_diagram.png' alt='friction diagram'>")
    files = {"friction_orbits.png": phase_portraits(panels, model),
             "friction_diagram.png": diagram_figure(model, "omega", attractors, diagram_study,
                                                    title="Sliding Bifurcations in a dry friction oscillator"),
             "sliding_bifurcations.csv": csv_bytes(table)}
    metrics = {f"A={a:g}": s.to_dict() for (a, _), s in studies.items()}
    return Section("Mechanics: the dry-friction oscillator's sliding bifurcations", text, files, ok=ok, metrics=metrics)


def degenerate_section():
    """The degenerate switching-sliding point: located on the continued curve, its two conditions, five orbits."""
    import pandas as pd

    from .defaults import MECHANICS
    from .mechanics_plots import degenerate_curve_figure, degenerate_figure
    from .report import Section, csv_bytes, table_html
    cfg = MECHANICS["degenerate"]
    study = degenerate_switching(cfg)
    portraits = degenerate_portraits(study, tuple(cfg["offsets"]))
    point, limit = study.point, cfg["conditions"]
    ok = abs(point.margin) <= limit and abs(point.curvature) <= limit
    curve = pd.DataFrame([{"A (N)": a, "omega (rad/s)": p.value, "arrival margin": p.margin,
                           "fold curvature (m/s^3)": p.curvature,
                           "kind": "switching-sliding" if p.curvature > 0 else "crossing-sliding"} for a, p in study.curve])
    text = (f"<p>The switching-sliding point of the friction oscillator at A = {cfg['A_start']:g} (the seed's "
            "2.7992) is continued in A. Along the curve the orbit arrives at the switching surface (v = Vdr) from "
            "below exactly at the sliding region's boundary, where the stick force reaches the static limit: the first "
            "test function is that <em>arrival margin</em>, |lambda| / F(0) - 1 (zero on the curve; each point located "
            "as the end of the branch of orbits that arrive inside, approached by secant steps). The second is the "
            "<em>fold curvature</em> there, -s'' along the slip field beyond the surface (s = v - Vdr; here "
            "(k Vdr + A omega sin(omega t)) / m): positive where the fold is invisible, so that an orbit crossing just "
            "outside the region comes back to it after a short excursion (switching-sliding), negative where it is "
            "visible and an orbit arriving just inside sticks briefly, slips to the other side and returns "
            "(crossing-sliding). The curvature changes sign along the curve at a cubic tangency, the codimension-two "
            "point (a degenerate sliding bifurcation in the sense of Kowalczyk and di Bernardo, Physica D 204, 2005), "
            f"located by Brent's method in A to {cfg['tol']:g} (the event method at ODE tolerance "
            f"{study.ode_rtol:g}; {study.wall_s:.0f} s):</p>"
            + table_html(pd.DataFrame([{"A (N)": f"{study.A:.9f}", "omega (rad/s)": f"{study.omega:.9f}",
                                        "arrival margin": f"{point.margin:.2e}",
                                        "fold curvature (m/s^3)": f"{point.curvature:.2e}", "limit": f"{limit:g}",
                                        "result": "pass" if ok else "fail"}]), "result", good=("pass",))
            + "<img src='degenerate_curve.png' alt='the curve in (A, omega)'>"
            + f"<p>Five orbits around it: at A* + {cfg['offsets'][0]:g} on either side of the switching-sliding curve, "
              f"the point itself, and at A* - {cfg['offsets'][0]:g} on either side of the crossing-sliding curve "
              f"(omega {cfg['offsets'][1]:g} off the curve):</p><img src='degenerate_orbits.png' alt='five orbits'>"
            + "<p>The continued curve:</p>" + table_html(curve))
    files = {"degenerate_orbits.png": degenerate_figure(portraits, study, get_mechanical("friction")),
             "degenerate_curve.png": degenerate_curve_figure(study, portraits),
             "degenerate_curve.csv": csv_bytes(curve)}
    return Section("Mechanics: the degenerate switching-sliding bifurcation", text, files, ok=ok,
                   metrics=study.to_dict())


def basins_section():
    """The seed's domain of attraction at A = 3.6, omega = 1.067, with the check at a grid twice finer."""
    import pandas as pd

    from .defaults import MECHANICS
    from .mechanics_plots import basin_figure
    from .report import Section, table_html
    cfg = MECHANICS["basins"]
    box = dict(params={"A": cfg["A"], "omega": cfg["omega"]}, x_range=cfg["x"], v_range=cfg["v"])
    coarse = basins(n=cfg["n"], refine=cfg["refine"], **box)
    fine = basins(n=2 * cfg["n"] - 1, refine=1, **box)
    check = resolution_check(coarse, fine)
    model = get_mechanical("friction")
    p = coarse.params
    T = model.period(p)
    orbits = [simulate(model.problem(p, a["period"] * T, a["points"][0]), EventDriven(output_step=T / 400.0))
              for a in coarse.attractors]
    ok = (check["off_boundary"] == 0 and (coarse.labels >= 0).all() and bool(coarse.attractors)
          and all(a["residual"] < 1e-10 for a in coarse.attractors))
    rows = pd.DataFrame([{"attractor": a["label"], "period (T)": a["period"], "events": ", ".join(a["signature"]),
                          "x(0) (m)": f"{a['points'][0][0]:.6f}", "v(0) (m/s)": f"{a['points'][0][1]:.6f}",
                          "Newton residual": f"{a['residual']:.1e}",
                          "|Floquet multipliers|": ", ".join(f"{m:.3g}" for m in a["multipliers"]),
                          "share of the grid": f"{(coarse.labels == a['label']).mean():.1%}"} for a in coarse.attractors])
    text = (f"<p>Initial states (x, v) at phase 0 on a {cfg['n']} x {cfg['n']} grid, each run {80} forcing periods "
            "(Moreau-Jean, h = T/500, the grid's rows in parallel on the local backend) and labelled by the attractor "
            "its last 16 stroboscopic samples sit on; each attractor is the periodic orbit solved by Newton shooting "
            "on the event method's exact map from the first state that reached it. Each boundary cell is refined by "
            f"{cfg['refine']} x {cfg['refine']} more initial states (dots). A grid twice finer ({2 * cfg['n'] - 1} "
            f"points a side) changes {check['off_boundary']} cells off the boundary ({check['on_boundary']} of its "
            f"{check['boundary_cells']} cells on it); unlabelled cells: {int((coarse.labels < 0).sum())}; "
            f"{coarse.wall_s + fine.wall_s:.0f} s.</p>" + table_html(rows)
            + "<img src='basins.png' alt='domain of attraction'>")
    return Section("Mechanics: the friction oscillator's domain of attraction", text,
                   {"basins.png": basin_figure(coarse, orbits)}, ok=ok,
                   metrics={**coarse.to_dict(), "resolution_check": check})


def diagram_study_path(study) -> tuple[float, float]:
    return min(study.start, study.stop), max(study.start, study.stop)


def agreement_section():
    """Event-driven against Moreau-Jean (friction stick intervals, cam impacts) and the ball's closed form."""
    import pandas as pd

    from .defaults import MECHANICS
    from .report import Section, csv_bytes, table_html
    limit = MECHANICS["agreement_rel"]
    friction = friction_agreement()
    cam = cam_checks()
    ball = ball_check()
    f_rows = pd.DataFrame(friction["rows"])
    c_rows = pd.DataFrame(cam["moreau"])
    b_rows = pd.DataFrame(ball["moreau"])
    ok = (bool((f_rows["max_error_T"] <= limit).all()) and bool((c_rows["max_error_T"] <= limit).all())
          and ball["relative_error"] <= MECHANICS["ball_rel"] and ball["restitution_max_error"] <= 1e-6
          and f_rows["max_error_T"].iloc[-1] < f_rows["max_error_T"].iloc[0] / 10)
    text = (f"<p><b>Friction</b> (A = {friction['params']['A']:g}, omega = {friction['params']['omega']:g}): the exact "
            f"periodic orbit's stick interval {friction['exact']} (fractions of T) against Moreau-Jean's after 50 "
            "periods from the exact orbit, as h shrinks (first order):</p>" + table_html(f_rows)
            + f"<p><b>Cam-follower</b> ({cam['params']['rpm']:g} rpm, from rest on the cam): the first detachment at "
              f"{cam['first_detachment_s']:.12f} s where k c + m c'' first reaches zero ({cam['margin_zero_s']:.12f} s: "
              f"{cam['detachment_error_s']:.1e} s apart); the first impacts {', '.join(f'{t:.6f}' for t in cam['first_impacts_s'])} s "
              "against Moreau-Jean's nearest ones:</p>" + table_html(c_rows)
            + f"<p><b>Bouncing ball</b> (H = 1 m, e = 0.5): the event method completes the chattering at "
              f"{ball['event_accumulation_s']:.15f} s against sqrt(2H/g)(1 + 2e/(1 - e)) = {ball['closed_form_s']:.15f} s "
              f"({ball['relative_error']:.1e} relative) after {ball['impacts_before_accumulation']} impacts; successive "
              f"flight times shrink by e to {ball['restitution_max_error']:.1e}. Moreau-Jean's largest penetration and "
              "the time it comes to rest:</p>" + table_html(b_rows)
            + f"<p>Limits: {limit:.0%} of the period for the event times, {MECHANICS['ball_rel']:g} for the ball.</p>")
    files = {"friction_agreement.csv": csv_bytes(f_rows), "cam_impacts.csv": csv_bytes(c_rows),
             "ball.csv": csv_bytes(b_rows)}
    return Section("Mechanics: event-driven against Moreau-Jean and the closed forms", text, files, ok=ok,
                   metrics={"friction": friction, "cam": {k: v for k, v in cam.items() if k != "params"}, "ball": ball})


def cam_section():
    """The cam-follower's impact phases against its speed, its regimes, and where complete chattering ends."""
    import pandas as pd

    from .defaults import MECHANICS
    from .mechanics_plots import cam_profile_figure, diagram_figure
    from .report import Section, csv_bytes, table_html
    model = get_mechanical("cam-follower")
    values = np.linspace(*MECHANICS["cam_rpm"], MECHANICS["cam_points"])
    rows = impact_phase_diagram({}, values, h_fraction=2.5e-4, workers=1)
    counts = {f"{r.value:g}": int(r.times.size) for r in rows}
    regimes = chattering_table({}, MECHANICS["cam_regime_rpm"], workers=1)
    transitions = [chattering_transition({}, *bracket) for bracket in MECHANICS["cam_transitions"]]
    marks = {"the seed's 175 rpm (chattering)": 175.0, "Siconos' example, 358 rpm": 358.0}
    marks.update({f"complete chattering ends, {t['rpm']:.4f} rpm": t["rpm"] for t in transitions})
    picture = diagram_figure(model, "rpm", rows, marks=marks, title="Bifurcation Analysis - Chattering orbits "
                             "(transition from complete chattering to no-complete chattering marked)")
    errors = sum(bool(r.error) for r in rows)
    located = pd.DataFrame([{"bracket (rpm)": f"{lo:g}..{hi:g}", "located (rpm)": f"{t['rpm']:.7f}",
                             "width (rpm)": f"{t['width']:.1e}", "ride left at the last orbit (revolutions)":
                             f"{t['last']['ride']:.1e}", "impacts before it accumulates": t["last"]["impacts"],
                             "runs": t["runs"]} for (lo, hi), t in zip(MECHANICS["cam_transitions"], transitions)])
    text = ("<p>The cam-follower of Siconos' CamFollower example (after di Bernardo, Osorio and Santini; "
            "m = 1.221 kg, k = 1430.8 N/m, e = 0.8). Its cam is piecewise smooth: "
            "four arcs, mirrored, whose second derivative jumps at each joint (the follower's impacts are one "
            "nonsmoothness, the profile the other):</p><img src='cam_profile.png' alt='cam profile'><p>The phase of every "
            "impact (Moreau-Jean, h = T/4000, 20 cam revolutions after 20 of transient) against the cam speed, "
            "over a range holding the seed's 175 rpm and Siconos' 358 rpm. At low speed the follower stays on the "
            "cam (no impacts); above the speed where the cam's deceleration first exceeds what the spring supplies "
            "it detaches and returns in impacts, in sequences that accumulate (complete chattering) or are cut "
            "short by the next lift (incomplete).</p><img src='cam_impacts.png' alt='impact phases'>"
            "<p>The regime at selected speeds (the event method, revolutions 10 to 20; an accumulation is a chattering "
            "sequence completed in closed form, the follower then riding the cam):</p>" + table_html(regimes)
            + "<p>Transition from complete chattering to no-complete chattering, located: the period-one "
              "complete-chattering orbit leaves the cam at its detachment (where k c + m c'' falls through zero), "
              "impacts it, its impacts accumulate and it rides the cam to the next revolution's detachment, where "
              "its state is the cam's again (periodic without shooting; every perturbation is erased at the "
              "accumulation). Its test function is the ride left between the accumulation and the next detachment; "
              "where it reaches zero the accumulation no longer completes within the revolution. Each end is "
              "approached by secant steps from the side where the orbit exists (the event method):</p>"
            + table_html(located))
    return Section("Mechanics: the cam-follower's impact phases", text,
                   {"cam_impacts.png": picture, "cam_profile.png": cam_profile_figure(),
                    "cam_regimes.csv": csv_bytes(regimes),
                    "cam_transitions.csv": csv_bytes(located)},
                   ok=errors == 0 and sum(counts.values()) > 0 and all(t["width"] <= 1e-6 * t["rpm"] for t in transitions),
                   metrics={"impacts_per_rpm": counts, "errors": errors, "regimes": regimes.to_dict(orient="records"),
                            "transitions": [{**{k: v for k, v in t.items() if k != "last"},
                                             "ride": float(t["last"]["ride"])} for t in transitions]})


def cam_continuation_section():
    """The source's slides "Continuation of periodic orbits" and "Corner-impact bifurcation in a P(2,1:1)": the
    cam-follower's impacting orbits continued in cam speed over the brute-force impact phases, and the corner impact
    located on the P(2, 1) orbit."""
    import pandas as pd

    from .defaults import MECHANICS
    from .mechanics_plots import cam_branches_figure, corner_figure
    from .report import Section, csv_bytes, table_html
    settings = MECHANICS["cam_continuation"]
    study = cam_continuation(settings)
    values = np.linspace(*settings["path"], settings["points"])
    rows = impact_phase_diagram({}, values, transient=settings["transient"], record=settings["record"],
                                h_fraction=2.5e-4, workers=1)
    branch_picture = cam_branches_figure(study, rows, "Moreau-Jean, h = T/4000")
    corner_picture = corner_figure(study)
    table = pd.DataFrame([{"bifurcation": b.kind, "cam speed (rpm)": f"{b.value:.7f}",
                           "multipliers": ", ".join(f"{m:.4g}" for m in b.multipliers), "located by": b.located_by,
                           "bracket (rpm)": f"{b.width:.1e}"} for b in study["bifurcations"] if b.kind != "fold"]
                         + [{"bifurcation": f"corner impact ({c.kind}) of the P({2 * c.revolutions},{c.revolutions}) "
                                            f"orbit, its impact {c.impact + 1} at the {c.joint} joint, "
                                            f"beta = {c.angle:.7f} rad",
                             "cam speed (rpm)": f"{c.rpm:.7f}",
                             "multipliers": "; ".join(", ".join(f"{m:.4g}" for m in side[2]) for side in c.sides),
                             "located by": f"bordered Newton: orbit residual {c.residual:.1e} m, impact "
                                           f"{c.off_joint:.1e} rad off the joint", "bracket (rpm)": ""}
                            for c in study["corners"]])
    orbits = pd.DataFrame([{"orbit": name, "cam speed (rpm)": pt.value, "stable": pt.stable,
                            "multipliers": ", ".join(f"{m:.6g}" for m in pt.multipliers),
                            "impact phases (revolutions)": ", ".join(
                                f"{t / family.problem_of(pt.value).period:.6f}"
                                for t in family.event_times(pt.value, pt.x0, "impact"))}
                           for name, parts in study["branches"].items() for branch in parts
                           for family in [study["families"][name]] for pt in branch.points])
    points = len(orbits)
    corner_ok = [c for c in study["corners"] if c.kind == "nonsmooth fold" and c.residual <= 1e-9
                 and abs(c.off_joint) <= 1e-9 and c.revolutions == 1]
    text = ("<p>Periodic impacting orbits P(m, n) (m impacts in n revolutions) of the cam-follower, continued in cam "
            "speed by pseudo-arclength continuation on the event method's period map, whose Jacobian is exact: the "
            "variational equations between impacts and each impact's saltation matrix (Newton's law differentiated, "
            "its instant moving with the gap's rate). The P(2, 1) orbit is started from the attractor "
            f"{settings['warm_up']} revolutions after rest at {settings['start']:g} rpm; the P(4, 2) orbit from its "
            f"period doubling (at most {settings['max_points']} orbits). Stable orbits solid, unstable dashed, over the "
            "brute-force impact phases of the attractor from rest (Moreau-Jean, h = T/4000, "
            f"{settings['record']:g} revolutions after {settings['transient']:g}).</p>"
            "<img src='cam_continuation.png' alt='continued orbits'><p>Every orbit with its multipliers and "
            "impact phases: cam_orbits.csv.</p>"
            "<p>Going down in speed the P(2, 1) orbit's first impact moves towards the joint of the cam's flank and "
            "nose (beta = pi/2 + beta2), where the profile's curvature, and with it the cam's acceleration c'', "
            "jumps. There the map stays continuous but its Jacobian jumps (the saltation matrix holds c''): a "
            "corner-impact bifurcation (Osorio, di Bernardo and Santini 2008). It is located by Newton on the orbit "
            "and the impact's angle together. Just above it the stable orbit (complex multipliers inside the unit "
            "circle) and a saddle (one real multiplier above 1), each with its impact on one side of the joint, "
            "meet at the corner; det(I - J) has opposite signs on the two (Feigin's condition): they vanish together "
            "in a nonsmooth fold, not a smooth one (no multiplier passes through 1).</p>"
            "<img src='cam_corner.png' alt='corner-impact bifurcation'>"
            + "".join(f"<p>The P({2 * c.revolutions}, {c.revolutions}) orbit born at the period doubling meets the "
                      f"{c.joint} joint too, at {c.rpm:.7f} rpm ({c.kind}): there its multiplier test functions jump "
                      "sign without a multiplier passing -1 or +1, so the continuation's fold and doubling next to it "
                      "are this corner impact, reported once.</p>" for c in study["corners"] if c.revolutions > 1)
            + table_html(table))
    return Section("Mechanics: continuation of periodic orbits and the corner-impact bifurcation", text,
                   {"cam_continuation.png": branch_picture, "cam_corner.png": corner_picture,
                    "cam_continuation.csv": csv_bytes(table), "cam_orbits.csv": csv_bytes(orbits)},
                   ok=bool(corner_ok) and points > 10,
                   metrics={"corners": [{"rpm": c.rpm, "joint": c.joint, "kind": c.kind, "residual": c.residual,
                                         "off_joint": c.off_joint} for c in study["corners"]],
                            "bifurcations": [{"kind": b.kind, "rpm": b.value} for b in study["bifurcations"]],
                            "orbits": points})


def quick_form_note(full: bool, what: str) -> str:
    """The paragraph a section with a quick form opens with: which form ran, and what the full size covers."""
    if full:
        return ""
    return (f"<p class='note'>Quick form: {what}. <code>pcsuite report mechanics --full</code> runs the full study "
            "(the settings in <code>validation/data/defaults.toml</code>, <code>[mechanics]</code> against "
            "<code>[mechanics.quick]</code>).</p>")


def chattering_windows_section(full: bool = False):
    """Past the end of complete chattering: the superstable orbits through the detachment (one accumulation per n
    revolutions) followed in cam speed, and their windows' borders located (:func:`chattering_windows`); an
    incomplete orbit continued through the transition, from its corner impact to its grazing
    (:func:`incomplete_across`); from above, the P(6,2) orbit down to its fold (:func:`incomplete_orbit`). The quick
    form (``full`` False) takes ``[mechanics.quick]``'s grid and continuation settings."""
    import pandas as pd

    from .defaults import MECHANICS, mechanics_settings
    from .mechanics_plots import chattering_windows_figure, incomplete_figure
    from .report import Section, csv_bytes, table_html
    form = mechanics_settings(full)
    settings = form["chattering_windows"]
    values = np.linspace(*settings["path"], settings["points"])
    study = chattering_windows({}, values, revolutions=settings["revolutions"])
    picture = chattering_windows_figure(study, settings["revolutions"])
    other = form["incomplete"]
    family, branch = incomplete_orbit(other)
    across_family, across, corners = incomplete_across(form["across"])
    full_grid, full_other = MECHANICS["chattering_windows"], MECHANICS["incomplete"]
    note = quick_form_note(full, f"the grid of {settings['points']} cam speeds over {settings['path'][0]:g}-"
                                 f"{settings['path'][1]:g} rpm (full: {full_grid['points']} over "
                                 f"{full_grid['path'][0]:g}-{full_grid['path'][1]:g} rpm, every window border between "
                                 f"them located); the incomplete orbit continued from {other['start']:g} rpm in steps "
                                 f"of at most {other['max_step']:g} rpm (full: from {full_other['start']:g} rpm, "
                                 f"{full_other['max_step']:g} rpm)")
    complete_end = next((b["rpm"] for b in study["borders"] if b["n"] == 1 and b["side"] == "below"), None)
    grazings = [b for b in across.bifurcations if b.kind == "border-collision"]
    located = locate_grazing(across_family, across, grazings[0]) if grazings else None
    m_across = {across_family.event_times(pt.value, pt.x0, "impact").size for pt in across.points}
    radius = [pt.spectral_radius for pt in across.points]
    crossed = complete_end is not None and across.values()[0] < complete_end < across.values()[-1]
    impacts = family.event_times(branch.points[0].value, branch.points[0].x0, "impact").size
    folds = [b for b in branch.bifurcations if b.kind == "fold"]
    found = pd.DataFrame([{"bifurcation": b.kind, "cam speed (rpm)": f"{b.value:.7f}",
                           "bracket (rpm)": f"{b.width:.1e}", "multipliers": ", ".join(f"{m:.4g}" for m in b.multipliers),
                           "located by": b.located_by} for b in branch.bifurcations])
    grid = pd.DataFrame([{"cam speed (rpm)": r["rpm"], "n (revolutions per accumulation)": r["n"],
                          "impacts per orbit": r["impacts"] if r["n"] else None,
                          "ride left (revolutions)": None if r["ride"] is None else float(r["ride"])}
                         for r in study["rows"]])
    borders = pd.DataFrame([{"border (rpm)": f"{b['rpm']:.7f}", "bracket (rpm)": f"{b['width']:.1e}",
                             "orbit": f"n = {b['n']}, {b['side']} the border",
                             "its ride at the last orbit (revolutions)": f"{b['ride']:.1e}",
                             "at the border": "the orbit ends: its accumulation reaches the detachment"
                             if b["ride"] <= 1e-5 else "bracketed, its ride not resolved to zero (steep there, or "
                             "the orbit ends otherwise: an earlier sequence completing)"}
                            for b in study["borders"]])
    ends = [b for b in study["borders"] if b["ride"] <= 1e-5]
    text = (note + "<p>Past the end of complete chattering the follower does not go over to incomplete chattering at "
            "once. Its chattering sequence is cut by the next lift, but it leaves the cam nearly in the cam's own "
            "state, and a later revolution's sequence completes: the orbit through the detachment then accumulates "
            "once every n revolutions. Each such orbit is periodic without shooting (after the accumulation the "
            "follower rides the cam to a detachment, where its state is the cam's) and superstable: every "
            "perturbation is erased at the accumulation, its Floquet multipliers are zero. It is followed in cam "
            "speed by running it from the detachment at each speed (the event method, which completes a sequence "
            "in closed form), and each change of n between neighbours of the grid is approached from both sides "
            "by secant steps on the orbit's ride left (the fraction of a revolution between the accumulation and "
            "the detachment that ends the orbit): where the ride falls to zero the orbit ends, its accumulation "
            "reaching the detachment. Where no sequence accumulates within "
            f"{settings['revolutions']} revolutions the follower is in incomplete chattering (or in an orbit of "
            "more revolutions); incomplete P(m, n) orbits at higher speed are continued below and in the next section.</p>"
            "<p>Through the transition: an incomplete-chattering orbit of one revolution, P("
            + "/".join(str(m) for m in sorted(m_across)) + ", 1), its sequence cut every revolution by the lift at the "
            "detachment, seeded by the flight that leaves the cam there and continued both ways in cam speed with "
            f"its exact multipliers ({len(across.points)} orbits, {across.values()[0]:.7g} to "
            f"{across.values()[-1]:.7f} rpm). "
            + (f"It passes the end of complete chattering ({complete_end:.7f} rpm) unchanged: below it, it coexists "
               "with the superstable complete-chattering orbit; the transition is a bifurcation of the "
               "complete-chattering orbit alone. " if crossed else "It does not reach the end of complete chattering. ")
            + f"It is unstable all along (largest multiplier {min(radius):.1f} to {max(radius):.1f}, the other below "
              f"{max(np.sort(np.abs(pt.multipliers))[0] for pt in across.points):.0e}), so a simulation does not settle "
              "on it. "
            + (f"It ends at a grazing at {located[0]:.6f} rpm, where the flight leaving the cam at the lift touches "
               f"the cam and an impact appears ({grazings[0].detail}): located where the flight's least clearance "
               f"reaches zero, extrapolated from {located[1][0][1]:.2e} m and {located[1][1][1]:.2e} m at "
               f"{located[1][0][0]:.6f} and {located[1][1][0]:.6f} rpm; the event method, which sees a touch within "
               f"its event tolerance of the cam, brackets it at {grazings[0].value:.6f} rpm (width "
               f"{grazings[0].width:.1e} rpm). "
               if grazings else f"No end was located: {across.message}. ")
            + "".join(f"Going down, its impact {c.impact + 1} reaches the {c.joint} joint of the cam profile (where "
                      "the cam lifts away: the detachment is at that joint), a corner impact located at "
                      f"{c.rpm:.7f} rpm (residual {c.residual:.1e}, {abs(c.off_joint):.1e} rad off the joint) from "
                      f"the branch's orbit at {across.values()[0]:g} rpm: a {c.kind} (Newton from the corner orbit "
                      f"and beyond it, {c.offset:g} rpm either side: "
                      + "; ".join(f"at {side[0]:.6f} rpm an orbit of {np.abs(side[2]).max():.1f} largest multiplier, "
                                  + ("its impact past the joint" if side[3] > c.angle else "its impact before the joint"
                                     if side[3] < c.angle else "without that impact") for side in c.sides)
                      + (", none below" if all(side[0] > c.rpm for side in c.sides) else "") + "). " for c in corners)
            + "Settings <code>[mechanics.across]</code>.</p><img src='cam_across.png' alt='an orbit through the "
              "transition'>"
            "<img src='cam_chattering_windows.png' alt='chattering windows'>"
            "<p>The grid (cam_chattering_grid.csv):</p>" + table_html(grid)
            + "<p>The borders located (an orbit between two grid speeds of other n is not seen; the windows are "
              "many and narrow):</p>" + table_html(borders)
            + f"<p>From the other side: the incomplete-chattering orbit P({impacts}, {other['revolutions']}) "
              f"({impacts} impacts in {other['revolutions']} revolutions, none accumulating), seeded from the "
              f"attractor {other['warm_up']} revolutions after rest at {other['start']:g} rpm, continued down in cam "
              "speed by pseudo-arclength continuation on the event method's map (its Jacobian exact: each impact's "
              f"saltation matrix; {len(branch.points)} orbits). "
              + (f"It is stable down to a fold at {folds[0].value:.7f} rpm (a multiplier through +1), where it "
                 "meets its unstable twin; below it the follower has no such orbit and its sequences begin to "
                 "complete in some revolutions (the windows above)." if folds else
                 f"No fold was found: {branch.message or 'it reaches the path end'}.")
            + "</p><img src='cam_incomplete.png' alt='incomplete-chattering orbit'>" + table_html(found))
    return Section("Mechanics: past the end of complete chattering", text,
                   {"cam_chattering_windows.png": picture, "cam_chattering_grid.csv": csv_bytes(grid),
                    "cam_chattering_borders.csv": csv_bytes(borders),
                    "cam_incomplete.png": incomplete_figure(family, branch), "cam_incomplete.csv": csv_bytes(found),
                    "cam_across.png": incomplete_figure(across_family, across, marks={
                        **({"end of complete chattering": complete_end} if complete_end is not None else {}),
                        **{f"corner impact ({c.kind})": c.rpm for c in corners}})},
                   ok=bool(ends) and all(b["width"] <= 1e-6 * b["rpm"] for b in study["borders"]) and bool(folds)
                   and crossed and bool(grazings) and min(radius) > 1.0
                   and 0.0 <= located[0] - (grazings[0].value - 0.5 * grazings[0].width) <= 1e-3
                   and all(c.residual <= 1e-7 and abs(c.off_joint) <= 1e-9 for c in corners) and bool(corners),
                   form="full" if full else "quick",
                   metrics={"borders": study["borders"], "n": {f"{r['rpm']:g}": r["n"] for r in study["rows"]},
                            "incomplete": {"impacts": impacts, "revolutions": other["revolutions"],
                                           "orbits": len(branch.points),
                                           "bifurcations": [{"kind": b.kind, "rpm": b.value,
                                                             "multipliers": [complex(m) for m in b.multipliers]}
                                                            for b in branch.bifurcations]},
                            "across": {"impacts": sorted(m_across), "from": float(across.values()[0]),
                                       "to": float(across.values()[-1]), "largest_multiplier": [min(radius), max(radius)],
                                       "grazing": [{"rpm": located[0], "detected_rpm": b.value, "width": b.width,
                                                    "clearances": located[1], "detail": b.detail} for b in grazings],
                                       "corner": [{"rpm": c.rpm, "joint": c.joint, "impact": c.impact, "kind": c.kind,
                                                   "residual": c.residual} for c in corners]}})


def two_block_section(full: bool = False):
    """Two blocks on a belt: the section against the belt velocity, and the regime at chosen velocities by a cycle
    closing on the section or a Lyapunov exponent above zero with its interval (:func:`two_block_regime`). The quick
    form (``full`` False) draws fewer velocities and tests the regime at fewer (``[mechanics.quick]``)."""
    import pandas as pd

    from .defaults import MECHANICS, mechanics_settings
    from .mechanics_plots import diagram_figure
    from .report import Section, csv_bytes, table_html
    model = get_mechanical("stick-slip")
    settings = mechanics_settings(full)
    values = np.linspace(*settings["two_block_V"], settings["two_block_points"])
    transient = settings["two_block_transient"]
    rows = two_block_diagram({}, "V", values, transient=transient)
    regimes = two_block_regimes({}, settings["two_block_regimes"])
    note = quick_form_note(full, f"the section at {len(values)} belt velocities and the regime tested at "
                                 f"{', '.join(f'{V:g}' for V in settings['two_block_regimes'])} m/s (full: "
                                 f"{MECHANICS['two_block_points']} velocities, the regime at "
                                 f"{', '.join(f'{V:g}' for V in MECHANICS['two_block_regimes'])} m/s)")
    how = two_block_regime.__kwdefaults__                                # what two_block_regimes ran with
    table = pd.DataFrame([{"V (m/s)": r["V"], "regime": r["regime"],
                           "cycle (section points)": r["period"] or f"none to {how['tol']:g}",
                           "cycle closing: first, last period of the record": "" if r["closing"] is None else
                           f"{r['closing'][0]:.1e}, {r['closing'][1]:.1e}",
                           "largest Lyapunov exponent (per time unit, 95 %)": f"{r['lyapunov']:+.4f} +- {r['half_width']:.4f}",
                           "section points recorded": r["sections"]} for r in regimes])
    text = (note + "<p>" + model.title + ": m1 = m2 = 1 kg, k1 = 1 N/m, k2 = 1.5 N/m, kc = 1 N/m, Popp friction "
            "with normal "
            "loads m g (the parameters are stated in <code>converters/models/mechanics/stickslip.py</code>; the seed "
            "gives none, and the published configurations it cites could not be reached: this is the project's own "
            f"model). The section: x2 each time block 1 starts to stick (the event method), after {transient:g} time "
            "units of transient (the slower block's natural period, 2 pi max_i sqrt(m_i / (k_i + kc)): "
            f"{model.time_scale(model.resolve({})):.4g} s here, block 1's), over 60 more, against the belt velocity V.</p>"
            "<img src='two_block.png' alt='two-block section'>"
            f"<p>The regime at chosen velocities, each by a test that can fail: after {how['transient']:g} time units "
            f"the section's states (x1, x2, v2) over {how['record']:g} more close into a cycle of k points to "
            f"{how['tol']:g} (every point k on equal to it: a transient still decaying would not), or they do not and "
            "the largest Lyapunov exponent of the flow (the event method's exact Jacobians, one tangent vector over "
            f"{how['blocks']} batches of {how['block']} time units from the run's end; the interval Student's t over "
            "the batches) lies above zero. A periodic orbit of a flow has exponent "
            "zero, so a cycle with an interval above zero, or neither test passing, is reported undetermined.</p>"
            + table_html(table))
    return Section("Mechanics: two blocks on a belt", text,
                   {"two_block.png": diagram_figure(model, "V", rows, title="Bifurcations in a two-block stick-slip "
                                                    "system (this project's model)"),
                    "two_block_regimes.csv": csv_bytes(table)},
                   ok=all(not r.error for r in rows) and all(r["regime"] != "undetermined" for r in regimes),
                   form="full" if full else "quick",
                   metrics={"distinct_section_points": {f"{r.value:.3g}": int(np.unique(np.round(r.states[:, 1], 4)).size)
                                                        for r in rows},
                            "regimes": regimes})


def __getattr__(name: str):
    """The studies moved to :mod:`converters.analysis.mechanics`: an import of one from here still works, with a
    warning naming the new place."""
    import converters.analysis.mechanics as studies
    if name in studies.__all__:
        import warnings
        warnings.warn(f"validation.mechanics.{name} is converters.analysis.mechanics.{name}", DeprecationWarning,
                      stacklevel=2)
        return getattr(studies, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
