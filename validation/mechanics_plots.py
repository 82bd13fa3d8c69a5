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


def diagram_figure(model, name: str, rows, study=None, fmt: str = "png", marks: dict | None = None) -> bytes:
    """Stroboscopic attractors (x(nT) against the parameter), a section (a state at each section event), or the
    cam's impact phases; the study's bifurcations marked and listed in the legend; ``marks``: label -> value,
    drawn as vertical lines (reference values)."""
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
    ax.set_title(model.title, fontsize=9)
    handles, labels = ax.get_legend_handles_labels()
    if handles:
        ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    return _save(fig, fmt)


def phase_portraits(panels: list[tuple[str, object]], model, fmt: str = "png") -> bytes:
    """One phase portrait (x, v) per (title, trajectory), the stick segments drawn thick."""
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
    fig.suptitle(f"{model.title}: orbits on either side of each sliding bifurcation (stick thick)", fontsize=9)
    fig.tight_layout()
    return _save(fig, fmt)
