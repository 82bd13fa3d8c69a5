"""Pictures of the mechanical studies: brute-force and section diagrams with the located bifurcations, and
phase portraits of orbits, as PNG or SVG bytes."""
from __future__ import annotations

import io

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

_MARKERS = {"grazing-sliding": ("v", "#c44e52"), "adding-sliding": ("^", "#8172b2"),
            "crossing-sliding": ("s", "#dd8452"), "switching-sliding": ("D", "#55a868"),
            "border-collision": ("o", "#937860"), "period-doubling": ("o", "#4c72b0"), "fold": ("P", "#64b5cd"),
            "neimark-sacker": ("X", "#ccb974")}


def _save(fig, fmt: str = "png") -> bytes:
    buffer = io.BytesIO()
    fig.savefig(buffer, format=fmt, dpi=110, bbox_inches="tight")
    plt.close(fig)
    return buffer.getvalue()


def _unit(model, name: str) -> str:
    spec = {p.name: p for p in model.parameters}
    return spec[name].unit if name in spec else ""


def diagram_figure(model, name: str, rows, study=None, fmt: str = "png", marks: dict | None = None,
                   title: str | None = None) -> bytes:
    """Stroboscopic attractors (x(nT) against the parameter), a section (a state at each section event), or the
    cam's impact phases; the study's bifurcations marked and listed in the legend; ``marks``: label -> value,
    drawn as vertical lines (reference values); ``title``: the source slide's (default the model's)."""
    fig, ax = plt.subplots(figsize=(9, 5))
    unit = _unit(model, name)
    if rows and hasattr(rows[0], "samples"):
        i = list(model.state_names).index(model.output_state)
        xs = np.concatenate([np.full(r.samples.shape[0], r.value) for r in rows if not r.error])
        ys = np.concatenate([r.samples[:, i] for r in rows if not r.error])
        ax.plot(xs, ys, ".", ms=1.5, color="0.3", label="attractor at the forcing period (Moreau-Jean)")
        ylabel = f"{model.output_state}(nT)"
    elif rows and model.contact_names:
        xs = np.concatenate([np.full(r.phases.size, r.value) for r in rows])
        ys = np.concatenate([r.phases for r in rows])
        ax.plot(xs, ys, ".", ms=1.5, color="0.3", label="impacts")
        ylabel = "impact phase (fraction of the cam's period)"
    elif rows:
        i = list(model.state_names).index(model.output_state)
        xs = np.concatenate([np.full(r.times.size, r.value) for r in rows])
        ys = np.concatenate([r.states[:, i] for r in rows])
        ax.plot(xs, ys, ".", ms=1.5, color="0.3", label=f"{model.output_state} where block 1 starts to stick")
        ylabel = f"{model.output_state} on the section"
    else:
        ylabel = model.output_state
    if study is not None:
        i = list(model.state_names).index(model.output_state)
        seen = set()
        for b in study.bifurcations:
            marker, colour = _MARKERS.get(b.kind, ("o", "k"))
            ax.axvline(b.value, color=colour, lw=0.8, ls=":")
            ax.plot([b.value], [b.x0[i]], marker, color=colour, mec="k", ms=7, zorder=5,
                    label=f"{b.kind} at {b.value:.6g}" + ("" if b.kind not in seen else ""))
            seen.add(b.kind)
        for branch in study.branches:
            if len(branch.points) > 1:
                values = branch.values()
                samples = np.array([pt.samples[:, i] for pt in branch.points])
                stable = np.array([pt.stable for pt in branch.points])
                for m in range(samples.shape[1]):
                    ax.plot(values, np.where(stable, samples[:, m], np.nan), "-", color="#4c72b0", lw=1.0,
                            label=f"period-{branch.period} orbit (continuation)" if m == 0 else None)
                    ax.plot(values, np.where(~stable, samples[:, m], np.nan), "--", color="#4c72b0", lw=0.8)
    for k, (label, value) in enumerate((marks or {}).items()):
        ax.axvline(value, color=("#c44e52", "#55a868", "#8172b2")[k % 3], lw=1.0, ls="--", label=label)
    ax.set_xlabel(f"{name} ({unit})" if unit else name)
    ax.set_ylabel(ylabel)
    ax.ticklabel_format(useOffset=False, style="plain")
    ax.grid(alpha=0.3)
    ax.set_title(title or model.title, fontsize=9)
    handles, labels = ax.get_legend_handles_labels()
    if handles:
        ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    return _save(fig, fmt)


def phase_portraits(panels: list[tuple[str, object]], model, fmt: str = "png", title: str | None = None) -> bytes:
    """One phase portrait (x, v) per (title, trajectory), the stick segments drawn thick; ``title`` the figure's."""
    cols = min(len(panels), 4)
    rows = int(np.ceil(len(panels) / cols))
    fig, axes = plt.subplots(rows, cols, figsize=(3.2 * cols, 3.0 * rows), squeeze=False)
    for ax, (title, run) in zip(axes.ravel(), panels):
        x, v = run.x[:, 0], run.x[:, 1]
        ax.plot(x, v, lw=0.8, color="#4c72b0")
        if run.held is not None:
            held = run.held[:, 0]
            ax.plot(np.where(held, x, np.nan), np.where(held, v, np.nan), lw=2.5, color="#c44e52")
        ax.set_title(title, fontsize=8)
        ax.set_xlabel(f"{model.state_names[0]} (m)", fontsize=8)
        ax.set_ylabel(f"{model.state_names[1]} (m/s)", fontsize=8)
        ax.tick_params(labelsize=7)
        ax.grid(alpha=0.3)
    for ax in axes.ravel()[len(panels):]:
        ax.axis("off")
    fig.suptitle(title or f"{model.title}: orbits on either side of each sliding bifurcation (stick thick)", fontsize=9)
    fig.tight_layout()
    return _save(fig, fmt)


def degenerate_figure(portraits: list, study, model, fmt: str = "png") -> bytes:
    """The five orbits around the degenerate switching-sliding point: each whole orbit (x, v), stick thick, and
    below it the arrival at the sliding region magnified (x - x_a, v - Vdr over a fifth of the period around it)."""
    fig, axes = plt.subplots(2, len(portraits), figsize=(3.0 * len(portraits), 5.6), squeeze=False)
    belt = study.params["Vdr"]
    for k, (label, A, omega, run, arrive) in enumerate(portraits):
        top, bottom = axes[0, k], axes[1, k]
        x, v = run.x[:, 0], run.x[:, 1]
        held = run.held[:, 0] if run.held is not None else np.zeros(x.size, dtype=bool)
        for ax, (xs, vs) in ((top, (x, v)), (bottom, (x - arrive.state[0], v - belt))):
            ax.plot(xs, vs, lw=0.8, color="#4c72b0")
            ax.plot(np.where(held, xs, np.nan), np.where(held, vs, np.nan), lw=2.5, color="#c44e52")
            ax.tick_params(labelsize=7)
            ax.grid(alpha=0.3)
        top.plot([arrive.state[0]], [belt], "o", mfc="none", mec="k", ms=8)
        where = "outside" if arrive.margin > 1e-9 else ("inside" if arrive.margin < -1e-9 else "on the boundary")
        top.set_title(f"{label}: A = {A:.5g} N, omega = {omega:.6g} rad/s\narrives {where}: margin "
                      f"{arrive.margin:+.1e}\nfold curvature {arrive.curvature:+.2g} m/s^3", fontsize=7)
        top.set_xlabel("x (m)", fontsize=8)
        top.set_ylabel("v (m/s)", fontsize=8)
        T = 2.0 * np.pi / omega
        after = (run.t - arrive.time + 0.5 * T) % T - 0.5 * T
        near = (after >= -0.01 * T) & (after <= 0.04 * T)
        rise = max(float(np.max(v[near] - belt)), 1e-6)          # the excursion past the surface, if any
        bottom.set_ylim(-3.0 * rise, 1.5 * rise)
        above = near & (v - belt > 1e-12)
        reach = max(float(np.max(x[above] - arrive.state[0])) if above.any() else 0.0, 0.01) * 1.3
        bottom.set_xlim(-0.1 * reach, reach)
        bottom.ticklabel_format(useOffset=False, style="sci", scilimits=(-2, 2))
        bottom.set_xlabel("x - x_arrival (m)", fontsize=8)
        bottom.set_ylabel("v - Vdr (m/s)", fontsize=8)
    fig.suptitle("Degenerate Switching-sliding Bifurcation (stick thick; below: the arrival at the sliding region, "
                 "magnified)", fontsize=9)
    fig.tight_layout()
    return _save(fig, fmt)


def _padded(values) -> tuple[float, float]:
    low, high = float(np.min(values)), float(np.max(values))
    pad = 0.08 * (high - low) or 1e-6
    return low - pad, high + pad


def degenerate_curve_figure(study, portraits: list, fmt: str = "png") -> bytes:
    """The continued curve of switching-sliding points in (A, omega): solid where the fold is invisible
    (switching-sliding), dashed where it is visible (crossing-sliding), the degenerate point and the portraits'."""
    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    A = np.array([a for a, _ in study.curve])
    omega = np.array([p.value for _, p in study.curve])
    curvature = np.array([p.curvature for _, p in study.curve])
    ax.plot(A, np.where(curvature > 0, omega, np.nan), "-o", ms=3, color=_MARKERS["switching-sliding"][1],
            label="switching-sliding (fold invisible)")
    ax.plot(A, np.where(curvature < 0, omega, np.nan), "--o", ms=3, color=_MARKERS["crossing-sliding"][1],
            label="crossing-sliding (fold visible)")
    ax.plot([study.A], [study.omega], "*", ms=14, color="k",
            label=f"degenerate point A = {study.A:.8f} N, omega = {study.omega:.8f} rad/s")
    for label, a, w, _, _ in portraits:
        ax.plot([a], [w], "x", color="0.3")
        ax.annotate(label.split()[-1], (a, w), textcoords="offset points", xytext=(4, 4), fontsize=8)
    ax.set_xlabel("A (N)")
    ax.set_ylabel("omega (rad/s)")
    ax.ticklabel_format(useOffset=False, style="plain")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    ax.set_title("The switching-sliding point continued in A (event method)", fontsize=9)
    return _save(fig, fmt)


def basin_figure(result, orbits: list, fmt: str = "png") -> bytes:
    """The domains of attraction: each grid cell coloured by the attractor its initial state reaches, the boundary's
    refinement as dots, each attractor's orbit over one period drawn over it (its stroboscopic points marked)."""
    from matplotlib.colors import ListedColormap
    colours = ["#c7d7ea", "#f2c9a5", "#c9e3c4", "#e0c6e6", "#f3e3a8", "#d9d9d9"]
    k = max(len(result.attractors), 1)
    cmap = ListedColormap(["#ffffff"] + colours[:k])
    fig, ax = plt.subplots(figsize=(7.5, 6.0))
    dx, dv = result.x[1] - result.x[0], result.v[1] - result.v[0]
    edges_x = np.append(result.x - 0.5 * dx, result.x[-1] + 0.5 * dx)
    edges_v = np.append(result.v - 0.5 * dv, result.v[-1] + 0.5 * dv)
    ax.pcolormesh(edges_x, edges_v, result.labels + 1, cmap=cmap, vmin=-0.5, vmax=k + 0.5, shading="flat")
    if result.refined:
        refined = np.array(result.refined)
        darker = ["#4c72b0", "#dd8452", "#55a868", "#8172b2", "#ccb974", "#7f7f7f"]
        for label in np.unique(refined[:, 2]).astype(int):
            pick = refined[:, 2] == label
            ax.plot(refined[pick, 0], refined[pick, 1], ".", ms=1.2, color=darker[label % 6] if label >= 0 else "k")
    for a, run in zip(result.attractors, orbits):
        ax.plot(run.x[:, 0], run.x[:, 1], "-", color="k", lw=1.2)
        ax.plot(a["points"][:, 0], a["points"][:, 1], "o", color="k", mfc="w", ms=6)
        share = (result.labels == a["label"]).mean()
        ax.plot([], [], "s", color=colours[a["label"] % 6], ms=8,
                label=f"attractor {a['label']}: period {a['period']} ({', '.join(a['signature'])}), "
                      f"|mu| max {max(a['multipliers']):.3g}, {share:.0%} of the grid")
    ax.set_xlabel("x (m) at phase 0")
    ax.set_ylabel("v (m/s) at phase 0")
    ax.set_xlim(edges_x[0], edges_x[-1])
    ax.set_ylim(edges_v[0], edges_v[-1])
    ax.legend(fontsize=7, loc="lower left")
    ax.set_title(f"Domain of Attraction, A = {result.params['A']:g} N, W = {result.params['omega']:g} rad/s "
                 f"({len(result.x)} x {len(result.v)} initial states; the orbits over one period in black)", fontsize=9)
    return _save(fig, fmt)


def _impact_phases(family, value: float, x0) -> np.ndarray:
    """The impact instants of the orbit from x0 at ``value`` as fractions of the cam's revolution, in [0, 1)."""
    return np.mod(family.event_times(value, x0, "impact") / family.problem_of(value).period, 1.0)


def cam_branches_figure(study: dict, rows, brute_force: str, fmt: str = "png") -> bytes:
    """The brute-force impact phases (grey; ``brute_force`` says how they were computed) with the continued orbits'
    impact phases over them, stable solid, unstable dashed, one colour per orbit family; period doublings and corner
    impacts marked."""
    fig, ax = plt.subplots(figsize=(9, 5.5))
    xs = np.concatenate([np.full(r.phases.size, r.value) for r in rows if r.phases.size])
    ys = np.concatenate([r.phases for r in rows if r.phases.size])
    ax.plot(xs, ys, ".", ms=2, color="0.6", label=f"impacts of the attractor from rest ({brute_force})")
    colours = ["#4c72b0", "#c44e52", "#55a868", "#8172b2"]
    for colour, (name, parts) in zip(colours, study["branches"].items()):
        family = study["families"][name]
        labelled = set()
        for branch in parts:
            points = sorted(branch.points, key=lambda pt: pt.value) if len(parts) == 1 else branch.points
            phases = [np.sort(_impact_phases(family, pt.value, pt.x0)) for pt in points]
            width = max((p.size for p in phases), default=0)
            if not width:
                continue
            values = np.array([pt.value for pt in points])
            table = np.array([np.pad(p, (0, width - p.size), constant_values=np.nan) for p in phases])
            stable = np.array([pt.stable for pt in points])
            for m in range(width):
                for style, which, word in (("-", stable, "stable"), ("--", ~stable, "unstable")):
                    label = f"{name} ({word})" if which.any() and word not in labelled else None
                    ax.plot(values, np.where(which, table[:, m], np.nan), style, color=colour,
                            lw=1.6 if word == "stable" else 1.2, label=label)
                    if label:
                        labelled.add(word)
    for b in study["bifurcations"]:
        if b.kind == "period-doubling":
            ax.axvline(b.value, color="#4c72b0", lw=0.8, ls=":")
            ax.plot([], [], ":", color="#4c72b0", label=f"period doubling of a period-{b.period} orbit, {b.value:.4f} rpm")
    for c in study["corners"]:
        phase = np.mod((c.angle - np.pi / 2) / (2 * np.pi), 1.0)
        ax.plot([c.rpm], [phase], "*", color="k" if c.revolutions == 1 else "#c44e52", ms=12, zorder=6,
                label=f"corner impact of P({2 * c.revolutions},{c.revolutions}) ({c.kind}), {c.rpm:.4f} rpm")
    ax.set_xlabel("cam speed (rpm)")
    ax.set_ylabel("impact phase (fraction of the cam's revolution)")
    ax.set_ylim(0, 1)
    ax.legend(fontsize=7, loc="upper right")
    ax.set_title("Continuation of periodic orbits", fontsize=10)
    return _save(fig, fmt)


def corner_figure(study: dict, fmt: str = "png") -> bytes:
    """At each corner impact: the impact's cam angle against the cam speed on the two orbits that meet there (the
    joint's angle drawn), and their Floquet multipliers in the complex plane."""
    from converters.models.mechanics import get_mechanical
    cam = get_mechanical("cam-follower")
    corners = [c for c in study["corners"] if c.revolutions == 1]
    family = study["families"]["P(2,1)"]
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.6))
    ax, plane = axes
    span = 3.0
    for c in corners[:1]:
        for branch in study["branches"]["P(2,1)"]:
            near = [pt for pt in branch.points if abs(pt.value - c.rpm) <= span]
            if not near:
                continue
            values = [pt.value for pt in near]
            angles = [cam.cam_angle({"rpm": pt.value}, family.event_times(pt.value, pt.x0, "impact"))[c.impact]
                      for pt in near]
            stable = [pt.stable for pt in near]
            flips = [k for k in range(1, len(near)) if stable[k] != stable[k - 1]
                     and max(abs(values[k - 1] - c.rpm), abs(values[k] - c.rpm)) < 1.0]
            for k in reversed(flips):                    # the corner between the two orbits, drawn in both styles
                values[k:k] = [c.rpm, c.rpm]
                angles[k:k] = [c.angle, c.angle]
                stable[k:k] = [stable[k - 1], stable[k]]
            values, angles, stable = np.array(values), np.array(angles), np.array(stable)
            ax.plot(values, np.where(stable, angles, np.nan), "-", color="#4c72b0", lw=1.6)
            ax.plot(values, np.where(~stable, angles, np.nan), "--", color="#c44e52", lw=1.4)
            for pt in near[::max(1, len(near) // 12)]:
                mu = pt.multipliers
                plane.plot(mu.real, mu.imag, "o" if pt.stable else "x", ms=4,
                           color="#4c72b0" if pt.stable else "#c44e52")
        ax.axhline(c.angle, color="k", lw=0.8, ls=":", label=f"the {c.joint} joint, beta = {c.angle:.5f} rad")
        ax.plot([c.rpm], [c.angle], "*", color="k", ms=12, label=f"corner impact, {c.rpm:.6f} rpm")
        ax.plot([], [], "-", color="#4c72b0", label="P(2,1), stable")
        ax.plot([], [], "--", color="#c44e52", label="P(2,1), unstable")
        ax.set_xlim(c.rpm - 0.2 * span, c.rpm + span)
        ax.set_title(f"the cam angle of impact {c.impact + 1} (counted from the revolution's start)", fontsize=9)
        fig.suptitle("Corner-impact bifurcation in a P(2,1:1)", fontsize=10)
    ax.set_xlabel("cam speed (rpm)")
    ax.set_ylabel("cam angle beta at the impact (rad)")
    ax.legend(fontsize=7)
    circle = np.linspace(0, 2 * np.pi, 200)
    plane.plot(np.cos(circle), np.sin(circle), "-", color="0.5", lw=0.8)
    plane.set_aspect("equal")
    plane.set_xlabel("Re mu")
    plane.set_ylabel("Im mu")
    plane.set_title(f"Floquet multipliers within {span:g} rpm (o stable, x unstable)", fontsize=9)
    return _save(fig, fmt)


def cam_profile_figure(fmt: str = "png") -> bytes:
    """The cam's lift h_c and its second derivative against the cam angle, the profile's joints marked: h_c'' jumps at
    each (the cam-follower is piecewise smooth through its impacts and through its profile)."""
    from converters.models.mechanics.cam import JOINTS, profile
    beta = np.linspace(0.0, 2.0 * np.pi, 4001)
    h, _, h2 = profile(np.where(beta > np.pi, 2.0 * np.pi - beta, beta))
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(8, 5.5), sharex=True)
    top.plot(beta, h, color="#4c72b0")
    bottom.plot(beta, h2, ".", ms=1.2, color="#c44e52")
    for name, angle in JOINTS.items():
        for ax in (top, bottom):
            ax.axvline(angle, color="0.5", lw=0.7, ls=":")
        top.text(angle, h.min() + 0.45 * (h.max() - h.min()), " " + name.split(" (")[0], rotation=90, fontsize=6,
                 va="center", ha="right")
    top.set_ylabel("lift h_c (m)")
    bottom.set_ylabel("h_c'' (m/rad^2)")
    bottom.set_xlabel("cam angle beta (rad)")
    for ax in (top, bottom):
        ax.grid(alpha=0.3)
    fig.suptitle("Cam Profile (its joints dotted: h_c'' jumps there)", fontsize=10)
    return _save(fig, fmt)


def chattering_windows_figure(study: dict, revolutions: int, fmt: str = "png") -> bytes:
    """Past the end of complete chattering: n, the revolutions per accumulation of the superstable orbit through
    the detachment, at each grid speed (none within ``revolutions``: x at n = 0), and the located ends between them
    (an orbit's ride need not keep one sign between a grid speed and its end: windows are many and narrow); below,
    the ride left at the grid's speeds and at the last orbit before each border (log scale: a ride that falls to
    zero is an orbit's end)."""
    rows, borders = study["rows"], study["borders"]
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(10, 7), sharex=True)
    found = [r for r in rows if r["n"] is not None]
    top.plot([r["rpm"] for r in found], [r["n"] for r in found], "o", color="#4c72b0", ms=5,
             label="an orbit with one accumulation per n revolutions (multipliers 0)")
    missing = [r for r in rows if r["n"] is None]
    if missing:
        top.plot([r["rpm"] for r in missing], [0] * len(missing), "x", color="#c44e52", ms=5,
                 label=f"no accumulation within {revolutions} revolutions")
    for b in borders:
        top.plot([b["rpm"]], [b["n"]], "|", color="k" if b["ride"] <= 1e-5 else "0.55", ms=14, mew=1.5)
    top.plot([], [], "|", color="k", ms=10, mew=1.5, label="border located, the orbit's ride falling to zero")
    top.plot([], [], "|", color="0.55", ms=10, mew=1.5, label="border bracketed, its ride not resolved to zero")
    top.set_ylabel("n (revolutions per accumulation)")
    top.set_ylim(-0.5, max([r["n"] for r in found] + [1]) + 0.5)
    top.set_title("Transition from complete chattering to no-complete chattering: the orbits through the detachment",
                  fontsize=10)
    bottom.semilogy([r["rpm"] for r in found], [r["ride"] for r in found], "o", color="#4c72b0", ms=4,
                    label="ride left at the grid's speeds")
    bottom.semilogy([b["rpm"] for b in borders], [b["ride"] for b in borders], "v", color="k", ms=6,
                    label="at the last orbit before each border")
    bottom.set_ylabel("ride left (revolutions)")
    bottom.set_xlabel("cam speed (rpm)")
    for ax in (top, bottom):
        ax.ticklabel_format(axis="x", useOffset=False, style="plain")
        ax.grid(alpha=0.3)
    handles = [h for ax in (top, bottom) for h in ax.get_legend_handles_labels()[0]]
    labels = [lab for ax in (top, bottom) for lab in ax.get_legend_handles_labels()[1]]
    fig.legend(handles, labels, loc="lower center", ncol=2, fontsize=7, bbox_to_anchor=(0.5, -0.06))
    return _save(fig, fmt)


def incomplete_figure(family, branch, fmt: str = "png", marks: dict | None = None) -> bytes:
    """An incomplete-chattering orbit continued in cam speed: its Floquet multipliers' largest modulus (stable
    solid, unstable dashed) and the phases of its impacts in the cam's revolution, its bifurcations marked;
    ``marks``: {label: rpm} drawn as vertical lines (a transition the orbit passes through)."""
    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4.4))
    points = branch.points
    values = np.array([pt.value for pt in points])
    radius = np.array([pt.spectral_radius for pt in points])
    stable = np.array([pt.stable for pt in points])
    left.plot(values, np.where(stable, radius, np.nan), "-", color="#4c72b0", lw=1.6, label="stable")
    left.plot(values, np.where(~stable, radius, np.nan), "--", color="#c44e52", lw=1.4, label="unstable")
    left.axhline(1.0, color="0.5", lw=0.8, ls=":")
    for b in branch.bifurcations:
        marker, color = _MARKERS.get(b.kind, ("o", "k"))
        left.plot([b.value], [np.abs(b.multipliers).max()], marker, color=color, ms=8,
                  label=f"{b.kind}, {b.value:.5f} rpm")
    for (label, rpm), (color, style) in zip((marks or {}).items(), [("0.3", "-."), ("#8172b2", "--"), ("#55a868", ":")]
                                            * 3):
        for ax in (left, right):
            ax.axvline(rpm, color=color, lw=1.0, ls=style, label=f"{label}, {rpm:.5f} rpm" if ax is left else None)
    left.set_xlabel("cam speed (rpm)")
    left.set_ylabel("largest |Floquet multiplier|")
    left.legend(fontsize=7)
    for pt in points[::max(1, len(points) // 80)]:
        phases = _impact_phases(family, pt.value, pt.x0)
        right.plot([pt.value] * len(phases), phases, ".", ms=3, color="#4c72b0" if pt.stable else "#c44e52")
    right.set_xlabel("cam speed (rpm)")
    right.set_ylabel("impact phase (revolutions)")
    right.set_title("impacts of the orbit (blue stable, red unstable)", fontsize=9)
    for ax in (left, right):
        ax.ticklabel_format(axis="x", useOffset=False, style="plain")
        ax.grid(alpha=0.3)
    impacts = _impact_phases(family, points[0].value, points[0].x0).size
    fig.suptitle(f"Continuation of periodic orbits: incomplete chattering, P({impacts},{family.periods})", fontsize=10)
    return _save(fig, fmt)

