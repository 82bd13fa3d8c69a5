"""The HTML validation report: sections built from result tables, written atomically.

Each section builder returns a :class:`Section` (HTML fragment plus the files it refers to). A
section that raises is shown as failed with its reason; it never aborts the report.
"""
from __future__ import annotations

import html
import io
import json
import time
import traceback
import urllib.parse
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from converters.errors import ParameterError

from .environment import environment
from .io import MANIFEST, atomic_directory, safe_name

CSS = """
body{font-family:system-ui,sans-serif;margin:2em auto;max-width:1100px;color:#222}
table{border-collapse:collapse;margin:1em 0;font-size:0.85em}
th,td{border:1px solid #ccc;padding:3px 7px;text-align:right}
th{background:#eee} td.text{text-align:left}
.pass{background:#d9f2d9}.fail{background:#f8d0d0}.note{background:#fff3c4}
img{max-width:100%;border:1px solid #ddd;margin:0.5em 0}
.failed-section{border:2px solid #c33;padding:0.5em 1em}.skip{background:#e8e8e8}
section.section-fail{border-left:6px solid #c33;padding-left:0.8em}
section.section-skipped{border-left:6px solid #999;padding-left:0.8em;color:#555}
.verdict{font-size:1.3em;padding:0.5em 1em;border-radius:4px}.verdict.pass{background:#d9f2d9}.verdict.fail{background:#f8d0d0}
.wide{overflow-x:auto;max-width:100%}
code{background:#f4f4f4;padding:0 3px}
"""


@dataclass
class Section:
    """One report section. Its ``status`` is pass, fail or skipped (no data, not measured: never a pass);
    ``reason`` says why a section failed or was skipped (a failing one without its own reason: "a check
    failed", the checks in its table)."""

    title: str
    html: str
    files: dict = field(default_factory=dict)   # relative name -> bytes
    ok: bool = True
    metrics: dict = field(default_factory=dict)
    skipped: bool = False
    reason: str = ""
    form: str = ""              # "quick" or "full" for a section with a quick form (:func:`has_quick_form`)

    @property
    def status(self) -> str:
        return "skipped" if self.skipped else "pass" if self.ok else "fail"

    @property
    def why(self) -> str:
        if self.reason or self.status == "pass":
            return self.reason
        return self.metrics.get("error", "a check failed (see the section's table)") if not self.skipped else ""


STATUSES = ("pass", "fail", "skipped")


def table_html(frame: pd.DataFrame, status_column: str | None = None, good=("solved", "pass", True)) -> str:
    """A pandas table as HTML, with pass/fail colouring on ``status_column``."""
    head = "".join(f"<th>{html.escape(str(c))}</th>" for c in frame.columns)
    rows = []
    for _, row in frame.iterrows():
        cells = []
        for col in frame.columns:
            value = row[col]
            cls = ""
            if isinstance(value, (float, np.floating)):
                text = "" if np.isnan(value) else f"{value:.6g}"     # enough digits to show a 1e-5 difference
            else:
                text = str(value)
                cls = "text"
            if col == status_column:
                cls += " pass" if value in good else " fail"
            cells.append(f'<td class="{cls.strip()}">{html.escape(text)}</td>')
        rows.append("<tr>" + "".join(cells) + "</tr>")
    return f"<table><tr>{head}</tr>{''.join(rows)}</table>"


def esc(value) -> str:
    """Any value as HTML text or an attribute's value (quotes escaped too)."""
    return html.escape(str(value), quote=True)


def url(path: str) -> str:
    """A relative file name as the value of a quoted href or src attribute."""
    return html.escape(urllib.parse.quote(path, safe="/"), quote=True)


def figure_png(fig) -> bytes:
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=110, bbox_inches="tight")
    import matplotlib.pyplot as plt
    plt.close(fig)
    return buffer.getvalue()


def runs_alone(builder):
    """Mark a section builder whose measurement is wall time (returns it): :func:`validation.suite.run_suite` runs it
    after the other jobs, with the machine to itself (two runs at once on shared cores distort each other's times)."""
    builder.runs_alone = True
    return builder


def has_quick_form(builder):
    """Mark a section builder that takes ``full`` (returns it): it runs in a quick form (fewer points, fewer
    settings; the same checks on what it computes) unless the report is asked for the full size
    (``pcsuite report --full``), and says which in its Section's ``form``."""
    builder.quick_form = True
    return builder


def run_section(builder, title: str) -> Section:
    start = time.perf_counter()
    try:
        section = builder()
    except Exception as exc:  # a failing section is reported, never fatal
        detail = "".join(traceback.format_exception_only(type(exc), exc)).strip()
        return Section(title=title, ok=False,
                       html=f'<div class="failed-section"><p><b>Failed:</b> {html.escape(detail)}</p></div>',
                       metrics={"error": detail}, reason=detail)
    section.metrics.setdefault("section_wall_s", time.perf_counter() - start)
    return section


def write_report(sections: list[Section], out_dir, suite: str, options: dict | None = None) -> Path:
    """Write index.html, metrics.json and every section's files into ``out_dir`` atomically."""
    env = environment()
    header = "".join(f"<tr><td class='text'>{esc(k)}</td><td class='text'>{esc(v)}</td></tr>"
                     for k, v in env.items())
    summary = pd.DataFrame([{"section": s.title, "result": s.status, "form": s.form, "reason": s.why}
                            for s in sections])
    counts = {status: sum(s.status == status for s in sections) for status in STATUSES}
    failed = [s.title for s in sections if s.status == "fail"]
    verdict = ("FAIL: " + f"{counts['fail']} of {len(sections)} sections fail ({', '.join(failed)})" if failed else
               f"PASS: {counts['pass']} of {len(sections)} sections pass"
               + (f", {counts['skipped']} skipped (not measured)" if counts["skipped"] else ""))
    rows = "".join(
        f"<tr><td class='text'><a href='#{_anchor(s.title)}'>{esc(s.title)}</a></td>"
        f"<td class='text {'pass' if s.status == 'pass' else 'fail' if s.status == 'fail' else 'skip'}'>{s.status}</td>"
        f"<td class='text'>{esc(s.form)}</td><td class='text'>{esc(s.why)}</td></tr>" for s in sections)
    quick = [s.title for s in sections if s.form == "quick"]
    forms = (f"<p id='forms'>Quick form ({len(quick)} of {len(sections)} sections: fewer points than the full study, "
             f"the same checks; <code>pcsuite report {esc(suite)} --full</code> runs them at full size): "
             f"{esc(', '.join(quick))}.</p>" if quick else "")
    body = [f"<h1>pcsuite validation report: {esc(suite)}</h1>",
            f"<p class='verdict {'fail' if failed else 'pass'}' id='verdict'>{esc(verdict)}</p>",
            f"<table>{header}</table>",
            f"<p>Options: <code>{esc(json.dumps(options or {}))}</code></p>",
            "<h2>Summary</h2>", forms,
            f"<table id='summary'><tr><th>section</th><th>result</th><th>form</th><th>reason</th></tr>{rows}</table>"]
    for section in sections:
        badge = "" if section.status == "pass" else f" <small>({section.status}: {esc(section.why)})</small>"
        body.append(f"<section class='section-{section.status}'><h2 id='{_anchor(section.title)}'>{esc(section.title)}"
                    f"{badge}</h2><div class='wide'>{section.html}</div></section>")
    page = (f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>pcsuite report: {esc(suite)}"
            f"</title><style>{CSS}</style></head><body>{''.join(body)}</body></html>")
    out_dir = Path(out_dir)
    files = _section_files(sections)
    with atomic_directory(out_dir, manifest={"suite": suite}) as staging:
        for name, data in files.items():
            path = staging / name
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_bytes(data)
        metrics = {"suite": suite, "environment": env, "options": options or {}, "verdict": verdict,
                   "sections": {s.title: {"ok": s.ok, "status": s.status, "reason": s.why, "form": s.form,
                                          **s.metrics}
                                for s in sections}}
        (staging / "metrics.json").write_text(json.dumps(metrics, indent=2, default=_json_default))
        summary.to_csv(staging / "summary.csv", index=False)
        (staging / "index.html").write_text(page)
    return out_dir / "index.html"


#: Files the report itself writes: a section may not write them.
RESERVED = ("index.html", "metrics.json", "summary.csv", MANIFEST)


def _section_files(sections) -> dict:
    """Every section's files by relative name; each part of a name must be a safe name, no name twice."""
    files, owner = {}, {}
    for section in sections:
        for name, data in section.files.items():
            parts = str(name).split("/")
            for part in parts:
                safe_name(f"section {section.title!r}: file {name!r}: the part", part)
            if name in RESERVED or name in owner:
                raise ParameterError(f"section {section.title!r}: file {name!r} is already written by "
                                     f"{'the report' if name in RESERVED else repr(owner[name])}; names must be unique")
            owner[name] = section.title
            files[name] = data
    clash = sorted(set(owner) & {str(parent) for n in owner for parent in Path(n).parents})
    if clash:
        raise ParameterError(f"file {clash[0]!r} of section {owner[clash[0]]!r} is also a directory of another file")
    return files


def csv_bytes(frame: pd.DataFrame) -> bytes:
    return frame.to_csv(index=False).encode()


def _anchor(title: str) -> str:
    return "".join(ch if ch.isascii() and ch.isalnum() else "-" for ch in title.lower())


def _json_default(value):
    if isinstance(value, (np.floating, np.integer)):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    return str(value)
