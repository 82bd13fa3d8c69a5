"""Interactive scopes: a run's waveforms in one offline HTML page (``simulate/compare --plot FILE.html``,
``pcsuite view``, the report's scenes).

One chart per signal, stacked on one time axis, the conduction mode as a band under them; zoom (drag, wheel),
pan, two cursors with the time and value differences between them and each signal's mean and RMS between them;
signals shown or hidden; in ``compare`` ngspice's trace beside pcsuite's. Drawn by uPlot (MIT; its 51 kB script and
stylesheet ship in ``validation/data/scope`` and are inlined: the page fetches nothing from the network). uPlot
rather than Plotly or Bokeh: it draws a million points in tens of milliseconds from typed arrays and weighs 51 kB
where Plotly's bundle is 3.5 MB, so a scope page costs its data and little else.

The data travels in chunks of rows (:data:`CHUNK_ROWS`, consecutive chunks share their boundary row), every step of
the run, each value exact (float64, or float32 where that holds it; compressed: :func:`_packed`): inline in the
page for a run up to :data:`INLINE_BYTES` of samples, otherwise
as script files in a folder beside the page (``NAME_files/``) that the page loads when a zoom or a cursor needs
them (a ``<script>`` element loads from a local file where a fetch may not). What the page shows of a window
holding more rows than the screen has columns is decimated to the first, last, minimum and maximum row of each
column (:func:`minmax_rows`, and the same in the page): a spike one step wide is never lost. The page opens on an
overview decimated here, so a run of a million steps opens without reading its chunks.

Between the cursors the page gives each signal's mean and RMS by the run's own rule
(:meth:`converters.trajectory.Trajectory.mean`): per step, the linear rule (with a step that starts at a switching
edge read in its own configuration: the edge's start values travel with the page) or the end-point rule; each
chunk's sums computed here, the partial chunks at the cursors summed in the page from the same float64 samples.
An event-driven run's own rule integrates its exact pieces, which the page does not hold: its scope says it reads
the linear rule on the samples instead.
"""
from __future__ import annotations

import base64
import html
import json
import math
import re
import zlib
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

from converters.errors import ParameterError

#: Rows per data chunk (the page loads a window's chunks when a zoom shows few enough rows to draw every one).
CHUNK_ROWS = 1 << 16
#: A run whose samples (float64, every signal) take up to this many bytes travels inside the page.
INLINE_BYTES = 8 << 20
#: Screen columns of the overview the page opens on.
OVERVIEW_COLUMNS = 2000
#: What an event-driven run's scope says: the page has its samples, not its exact pieces.
EXACT_NOTE = ("the run integrates its exact pieces; the page's mean and RMS use the linear rule on its samples (the "
              "run's summary and Trajectory.mean give the exact ones)")
#: Mode band colours (the static plots' own, then a cycle for a netlist's held-set labels).
PALETTE = ("#4c72b0", "#55a868", "#c44e52", "#8172b2", "#ccb974", "#64b5cd", "#dd8452", "#937860", "#da8bc3",
           "#8c8c8c")


@dataclass(frozen=True)
class Trace:
    """One simulator's signals on its own time base (pcsuite's run, or ngspice's beside it in ``compare``).

    ``rule`` is how the page integrates between the cursors: ``linear`` or ``end``, as the run itself does;
    ``edge_rows`` are the steps (by their first row) that start at a switching edge, with each algebraic signal's
    start value there in ``edge_values`` (the linear rule reads such a step in its own configuration); ``note``
    says where the page's rule is not the run's own."""

    source: str
    t: np.ndarray
    values: dict[str, np.ndarray]
    rule: str = "linear"
    edge_rows: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    edge_values: dict[str, np.ndarray] = field(default_factory=dict)
    modes: np.ndarray | None = None
    note: str = ""

    def __post_init__(self) -> None:
        if self.rule not in ("linear", "end"):
            raise ParameterError(f"rule must be 'linear' or 'end'; got {self.rule!r}")
        t = np.asarray(self.t, dtype=float)
        if t.ndim != 1 or t.size < 2 or not np.all(np.isfinite(t)) or np.any(np.diff(t) < 0):
            raise ParameterError(f"a scope's time must be finite and non-decreasing, with 2 samples or more; got "
                                 f"{t.size} samples")
        for name, v in self.values.items():
            if np.shape(v) != t.shape:
                raise ParameterError(f"signal {name!r} has {np.size(v)} samples where time has {t.size}")

    def step_terms(self, name: str) -> tuple[np.ndarray, np.ndarray]:
        """Per step, the integral of the signal and of its square by the trace's rule (what ``Trajectory.mean``
        and ``rms`` sum)."""
        t, v = np.asarray(self.t, dtype=float), np.asarray(self.values[name], dtype=float)
        dt, b = np.diff(t), v[1:]
        if self.rule == "end":
            return dt * b, dt * (b * b)
        a = v[:-1]
        if name in self.edge_values and self.edge_rows.size:
            a = a.copy()
            a[self.edge_rows] = self.edge_values[name]
        return dt * (0.5 * (a + b)), dt * ((a * a + a * b + b * b) / 3.0)


@dataclass(frozen=True)
class Scope:
    """What a scope page shows: its title, the traces (the first is the run's own; its modes make the band), the
    signals in chart order and their units."""

    title: str
    traces: tuple[Trace, ...]
    signals: tuple[str, ...]
    units: dict[str, str] = field(default_factory=dict)
    #: The horizontal axis: time in s, or a swept parameter (a sweep's summary), on a log scale where it was swept so.
    x_name: str = "time"
    x_unit: str = "s"
    x_log: bool = False


def minmax_rows(v: np.ndarray, columns: int) -> np.ndarray:
    """The rows that draw ``v`` on ``columns`` screen columns as every row would: each column's first, last,
    minimum and maximum row and its first NaN (a gap), in order (every row where there are no more than 4 per
    column)."""
    v = np.asarray(v, dtype=float)
    n = v.size
    if n <= 4 * columns:
        return np.arange(n)
    per = -(-n // columns)
    columns = -(-n // per)
    padded = np.concatenate([v, np.full(per * columns - n, v[-1])]).reshape(columns, per)
    base = np.arange(columns) * per
    finite = np.where(np.isnan(padded), np.inf, padded)
    low = base + np.argmin(finite, axis=1)
    high = base + np.argmax(np.where(np.isnan(padded), -np.inf, padded), axis=1)
    last = np.minimum(base + per - 1, n - 1)
    gaps = base[np.isnan(padded).any(axis=1)] + np.argmax(np.isnan(padded), axis=1)[np.isnan(padded).any(axis=1)]
    return np.unique(np.minimum(np.concatenate([base, low, high, last, gaps]), n - 1))


def of_trajectory(tr: Any, signals: list[str] | None = None, title: str = "",
                  spice: Any = None, t0: float | None = None) -> Scope:
    """A run's scope (states and its model's signals, or ``signals``), and in ``compare`` ngspice's run beside it
    (``spice``: its trajectory, the signals it has); from ``t0`` on (a comparison's window) where given."""
    names = list(signals) if signals is not None else _default_signals(tr)
    unknown = [n for n in names if n not in tr.signal_names]
    if unknown:
        raise ParameterError(f"signals must be among {', '.join(tr.signal_names)}; got {unknown[0]!r}")
    traces = [_trace_of(tr, names, "pcsuite" if spice is not None else (tr.method or "run"), t0)]
    if spice is not None:
        traces.append(_trace_of(spice, [n for n in names if n in spice.signal_names], "ngspice", t0))
    units = dict(getattr(getattr(tr.labels, "model", None), "signal_units", {}) or {})
    from converters.trajectory import signal_unit
    return Scope(title, tuple(traces), tuple(names), {n: signal_unit(units, n) for n in names})


def of_comparison(lcp: Any, spice: Any, title: str, t0: float | None = None) -> Scope:
    """A comparison's scope: vout and the states both simulators have, ngspice's trace beside pcsuite's."""
    names = [n for n in ("vout", *lcp.state_names) if n in spice.signal_names and n in lcp.signal_names]
    return of_trajectory(lcp, list(dict.fromkeys(names)), title=title, spice=spice, t0=t0)


def of_sweep(frame: Any, parameter: str, metrics: list[str], units: dict | None = None, log: bool = False,
             title: str = "") -> Scope:
    """A one-parameter sweep's summary as a scope: each metric over the swept parameter (the points in order; a
    failed point a gap), the points' conduction modes as the band."""
    frame = frame.sort_values(parameter, kind="stable")
    ok = (frame["status"] == "ok").to_numpy() if "status" in frame else np.ones(len(frame), dtype=bool)
    import pandas as pd
    values = {m: np.where(ok, pd.to_numeric(frame[m], errors="coerce").to_numpy(dtype=float), np.nan)
              for m in metrics if m in frame}
    if not values:
        raise ParameterError(f"metrics must be among the sweep's columns ({', '.join(map(str, frame.columns))}); "
                             f"got {', '.join(metrics)}")
    modes = frame["mode"].fillna("failed").astype(str).to_numpy() if "mode" in frame else None
    units = units or {}
    trace = Trace("sweep", frame[parameter].to_numpy(dtype=float), values, modes=modes,
                  note="mean and RMS between the cursors are over the swept parameter (the linear rule between points)")
    return Scope(title, (trace,), tuple(values), {m: str(units.get(m, "")) for m in values}, x_name=parameter,
                 x_unit=str(units.get(parameter, "")), x_log=log)


def pair_note(names: list[str]) -> str:
    """What a scope says of the signals whose run's mean reads the stepper's pair share by the end-point rule
    (:meth:`converters.trajectory.Trajectory.pair_moved`), which the page's linear rule does not."""
    return (f"the run's means of {', '.join(names[:4])}{' and more' if len(names) > 4 else ''} read the diodes' "
            "share at each step's end, as the stepper moved the charge; the page's read the linear rule on the "
            "samples (half a step of each jump apart)")


def _default_signals(tr: Any) -> list[str]:
    names = list(tr.state_names)
    for extra in ("vout", "switch"):
        if extra in tr.signal_names and extra not in names:
            names.append(extra)
    return names


def _trace_of(tr: Any, names: list[str], source: str, t0: float | None = None) -> Trace:
    rows = _rows(tr, t0)
    values = {n: np.asarray(tr.signal(n), dtype=float)[rows] for n in names}
    rule, edge_rows, edge_values = _rule_of(tr, rows, names)
    notes = []
    if tr.rule == "exact":
        notes.append(EXACT_NOTE)
    notes += [pair_note(moved) for moved in [tr.pair_moved(names)] if moved]
    if rows[0] > 0 and tr.t[0] < tr.resolved_from and (t0 is None or t0 < tr.resolved_from):
        notes.append(f"the run kept every step from {tr.resolved_from:.6g} s on (--output-step before it): the scope "
                     "shows that part")
    modes = None
    if tr.labels is not None or "mode" in tr.measured:
        from converters.errors import SignalError
        try:
            modes = np.asarray(tr.modes(rows))
        except SignalError:                      # a run with no mode rule: the band is left out, not the scope
            modes = None
    return Trace(source, tr.t[rows], values, rule, edge_rows, edge_values, modes, "; ".join(notes))


def _rows(tr: Any, t0: float | None) -> np.ndarray:
    """The rows a scope shows: from ``t0`` (default: the start) on, and only where the run kept every step."""
    start = max(tr.resolved_from, tr.t[0] if t0 is None else t0)
    return np.arange(tr.t.size) if start <= tr.t[0] else tr.rows_between(start, tr.t[-1])


def _rule_of(tr: Any, rows: np.ndarray, names: list[str]) -> tuple[str, np.ndarray, dict[str, np.ndarray]]:
    """How the page integrates the run's ``rows`` as the run does: its rule, and for the linear rule the steps that
    start at a switching edge (positions in ``rows``) with each algebraic signal's start value there."""
    rule = "end" if tr.rule == "end" else "linear"
    algebraic = [n for n in names if n not in tr.state_names and n not in tr.measured]
    if rule == "linear" and tr.labels is not None and algebraic and tr.config is not None:
        edges, _, first = tr.edges(rows)
        if edges.size:
            return rule, edges.astype(np.int64), {n: np.asarray(tr.labels.signal(n, first), dtype=float)
                                                  for n in algebraic}
    return rule, np.zeros(0, dtype=np.int64), {}


def of_frame(frame: Any, meta: dict | None = None, title: str = "") -> Scope:
    """A stored run's scope (``pcsuite view RUN.parquet``): its time, float columns and mode; the rule and edge
    start values where the file's metadata carries them (:func:`scope_meta`)."""
    meta = meta or {}
    if "time" not in frame.columns:
        raise ParameterError(f"a run's waveform file has a 'time' column; got columns "
                             f"{', '.join(map(str, frame.columns))}")
    skip = re.compile(r"^(u_|y_|active_)|^(time|mode|config)$")
    names = [c for c in frame.columns if not skip.match(str(c)) and frame[c].dtype.kind in "fiub"]
    if not names:
        raise ParameterError("the run's waveform file has no numeric signal to show")
    stored = meta.get("scope")
    rule, edge_rows, edge_values = _stored_rule(stored, len(frame), names)
    note = "the file does not say how its run integrates (or says it in a form not read here): the page reads the " \
           "linear rule on its samples"
    if rule:
        note = EXACT_NOTE if stored.get("exact") is True else ""
        moved = stored.get("pair_moved")
        moved = [str(n) for n in moved if str(n) in names] if isinstance(moved, list) else []
        if moved:
            note = "; ".join(filter(None, (note, pair_note(moved))))
    modes = frame["mode"].astype(str).to_numpy() if "mode" in frame.columns else None
    trace = Trace(str(meta.get("method") or "run")[:40], frame["time"].to_numpy(dtype=float),
                  {n: frame[n].to_numpy(dtype=float) for n in names}, rule or "linear", edge_rows, edge_values, modes,
                  note)
    units = meta.get("units") if isinstance(meta.get("units"), dict) else {}
    return Scope(title, (trace,), tuple(names), {n: str(units.get(n, ""))[:20] for n in names})


def _stored_rule(stored: Any, rows: int, names: list[str]) -> tuple[str | None, np.ndarray, dict[str, np.ndarray]]:
    """The rule and edge start values a waveform file's metadata gives (:func:`scope_meta`), checked: a file is not
    trusted; anything malformed gives (None, no edges)."""
    none: tuple[str | None, np.ndarray, dict[str, np.ndarray]] = (None, np.zeros(0, dtype=np.int64), {})
    if not isinstance(stored, dict) or stored.get("rule") not in ("linear", "end"):
        return none
    try:
        given = np.asarray(stored.get("edge_rows", []), dtype=float).reshape(-1)
        values = {str(n): np.asarray(v, dtype=float).reshape(-1) for n, v in (stored.get("edge_values") or {}).items()}
    except (TypeError, ValueError, AttributeError, OverflowError):
        return none
    if given.size and not (np.all(np.isfinite(given)) and np.all(given == np.round(given)) and given.min() >= 0
                           and given.max() < rows - 1 and np.all(np.diff(given) > 0)):
        return none
    if any(v.size != given.size for v in values.values()):
        return none
    return str(stored["rule"]), given.astype(np.int64), {n: v for n, v in values.items() if n in names}


def scope_meta(tr: Any, names: list[str]) -> dict:
    """What a waveform file stores for its scope to integrate as the run does: the rule, and the edge steps with
    their start values (``pcsuite view`` reads them back)."""
    rule, edge_rows, edge_values = _rule_of(tr, _rows(tr, None), names)
    return {"rule": rule, "exact": tr.rule == "exact", "edge_rows": edge_rows.tolist(),
            "edge_values": {n: v.tolist() for n, v in edge_values.items()}, "pair_moved": tr.pair_moved(names)}


# --- the page --------------------------------------------------------------------------------------------------

def _number(value: float) -> float | None:
    """A sum for the page's JSON: a NaN sample (a failed sweep point) makes it null, which JSON has (NaN it has not)."""
    value = float(value)
    return value if math.isfinite(value) else None


def _b64(a: np.ndarray) -> str:
    return base64.b64encode(np.ascontiguousarray(a, dtype="<f8").tobytes()).decode("ascii")


def _packed(v: np.ndarray) -> str:
    """A chunk's samples of one signal, compressed: float32 where that holds every value exactly (a switch command,
    a current held at 0), else float64; the bytes split into planes (every value's first byte, then every second
    byte...: the sign, exponent and leading mantissa of neighbouring samples repeat) and deflated (zlib), as
    Parquet's byte-stream split does. A buck's window shrinks 4x to 6x; the page inflates it with the browser's
    own DecompressionStream. Marked "z4:" or "z8:" and base64."""
    v = np.asarray(v, dtype="<f8")
    single = v.astype("<f4")
    exact = np.array_equal(single.astype(float), v, equal_nan=True)
    data = single if exact else v
    width = data.dtype.itemsize
    planes = np.ascontiguousarray(data.view(np.uint8).reshape(-1, width).T).tobytes()
    return f"z{width}:" + base64.b64encode(zlib.compress(planes, 6)).decode("ascii")


def _aliases(values: dict[str, np.ndarray], names: list[str]) -> dict[str, str]:
    """Signals whose samples equal an earlier signal's (a buck's vout and vC): sent once."""
    same: dict[str, str] = {}
    for j, n in enumerate(names):
        for m in names[:j]:
            if m not in same and np.array_equal(values[n], values[m], equal_nan=True):
                same[n] = m
                break
    return same


def _chunks(n: int) -> list[tuple[int, int]]:
    """Row ranges [r0, r1] (inclusive) of the chunks: consecutive chunks share a row, so each step lies in one."""
    bounds = list(range(0, n - 1, CHUNK_ROWS)) + [n - 1]
    return [(a, b) for a, b in zip(bounds[:-1], bounds[1:])]


def _mode_runs(modes: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Where each run of one mode starts (rows) and its label."""
    modes = np.asarray(modes)
    starts = np.concatenate([[0], np.flatnonzero(modes[1:] != modes[:-1]) + 1])
    return starts, modes[starts].astype(str)


def _mode_bands(scope: Scope) -> dict | None:
    """The mode band of every trace that has modes (pcsuite's and, in compare, ngspice's, one stripe each): the
    labels of all of them with one colour each, and per trace its runs' start times and label codes."""
    runs = {i: _mode_runs(tr.modes, tr.t) for i, tr in enumerate(scope.traces) if tr.modes is not None}
    if not runs:
        return None
    labels = sorted(set().union(*(set(names.tolist()) for _, names in runs.values())))
    code = {label: k for k, label in enumerate(labels)}
    return {"labels": labels, "colours": [PALETTE[k % len(PALETTE)] for k in range(len(labels))],
            "stripes": [{"trace": i, "source": scope.traces[i].source, "t": _b64(scope.traces[i].t[starts]),
                         "code": _b64(np.array([code[n] for n in names], dtype=float))}
                        for i, (starts, names) in runs.items()]}


def _payload(scope: Scope, data_dir: str | None) -> tuple[dict, list[tuple[int, int, str]]]:
    """The page's JSON and its chunks as (trace, chunk, script text)."""
    traces, scripts = [], []
    for i, tr in enumerate(scope.traces):
        names = [n for n in scope.signals if n in tr.values]
        terms = {n: tr.step_terms(n) for n in names}
        same = _aliases(tr.values, names)
        chunks = []
        for k, (r0, r1) in enumerate(_chunks(tr.t.size)):
            chunks.append({"r0": r0, "r1": r1, "t0": float(tr.t[r0]), "t1": float(tr.t[r1]),
                           "sums": {n: [_number(terms[n][0][r0:r1].sum()), _number(terms[n][1][r0:r1].sum())]
                                    for n in names}})
            body = json.dumps({n: _packed(tr.values[n][r0:r1 + 1]) for n in names if n not in same}
                              ).replace("<", "\\u003c")      # a signal's name cannot end the page's script element
            scripts.append((i, k, f'pcsuiteChunk({i},{k},"{_packed(tr.t[r0:r1 + 1])}",{body});'))
        overview = {}
        for n in names if data_dir is not None else ():     # inline, every row is there from the start
            rows = minmax_rows(tr.values[n], OVERVIEW_COLUMNS)
            overview[n] = {"t": _b64(tr.t[rows]), "v": _b64(tr.values[n][rows])}
        traces.append({"source": tr.source, "rule": tr.rule, "note": tr.note, "rows": int(tr.t.size), "same": same,
                       "signals": names, "chunks": chunks, "overview": overview,
                       "edges": {"rows": _b64(tr.edge_rows.astype(float)),
                                 "values": {n: _b64(v) for n, v in tr.edge_values.items() if n in names}},
                       })
    return {"title": scope.title, "signals": list(scope.signals), "units": scope.units, "traces": traces,
            "x": {"name": scope.x_name, "unit": scope.x_unit, "log": scope.x_log}, "modes": _mode_bands(scope),
            "dataDir": data_dir, "chunkRows": CHUNK_ROWS}, scripts


def _asset(name: str) -> str:
    return resources.files("validation").joinpath("data", "scope", name).read_text(encoding="utf-8")


def _script(text: str) -> str:
    return "<script>" + text.replace("</", "<\\/") + "</script>"


def page(scope: Scope, data_dir: str | None = None) -> tuple[str, list[tuple[int, int, str]]]:
    """The page's HTML, and the chunk scripts that go in ``data_dir`` (none when ``data_dir`` is None: every
    chunk is inline)."""
    payload, scripts = _payload(scope, data_dir)
    inline = "" if data_dir is not None else "\n".join(_script(s) for _, _, s in scripts)
    title = html.escape(scope.title or "pcsuite scope")
    # every "<" escaped: a column name or unit read from a file cannot end the script element or open a comment
    data = json.dumps(payload, allow_nan=False).replace("<", "\\u003c")
    text = f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>{title}</title>
<style>{_asset("uPlot.min.css")}</style><style>{_asset("scope.css")}</style></head>
<body><h1>{title}</h1>
<div id="controls"></div><div id="charts"></div><div id="readout"></div>
<script id="scope-data" type="application/json">{data}</script>
{_script(_asset("uPlot.iife.min.js"))}
{_script(_asset("scope.js"))}
{inline}
<script>pcsuiteScope.start();</script>
</body></html>
"""
    return text, ([] if data_dir is None else scripts)


def scope_files(scope: Scope, name: str) -> dict[str, bytes]:
    """The page ``name`` (a file name or a path relative to a report) and, for a run over :data:`INLINE_BYTES`, its
    chunk scripts in the folder ``STEM_files/`` beside it: {relative path: bytes}."""
    raw = sum(tr.t.size * 8 * (1 + len(tr.values)) for tr in scope.traces)
    if raw <= INLINE_BYTES:
        return {name: page(scope)[0].encode()}
    path = Path(name)
    folder = path.stem + "_files"
    text, scripts = page(scope, data_dir=folder)
    files = {str(path.with_name(folder) / f"t{i}-c{k}.js"): s.encode() for i, k, s in scripts}
    files[name] = text.encode()
    return files


def write_scope(scope: Scope, path: Path) -> list[Path]:
    """Write the page (and, for a large run, its chunk folder ``NAME_files/`` beside it) atomically: every file
    lands together or none does. Returns the files written."""
    from .io import atomic_write_files
    path = Path(path)
    files = {path.parent / rel: data for rel, data in scope_files(scope, path.name).items()}
    folder = path.with_name(path.stem + "_files")
    if len(files) > 1:
        if folder.exists() and not folder.is_dir():
            raise ParameterError(f"the scope's data folder {str(folder)!r} exists and is not a folder")
        folder.mkdir(exist_ok=True)
    written = atomic_write_files(files)
    if folder.is_dir():
        for stale in folder.iterdir():               # an earlier, longer run's chunks (only names the page gives)
            if re.fullmatch(r"t\d+-c\d+\.js", stale.name) and stale not in files:
                stale.unlink()
    return written
