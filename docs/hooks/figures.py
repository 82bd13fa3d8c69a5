"""MkDocs hook: the measured figures a page quotes, read from the benchmarks' output files
(``benchmarks/results/NAME.json``, written by ``make bench``): ``{{ fig:NAME.KEY }}`` is one figure with its unit,
``{{ table:NAME }}`` a benchmark's whole table with its date and machine (``{{ table:NAME.KEY,KEY }}`` those rows), ``{{ measured:NAME }}`` the date and
machine alone. A placeholder naming a figure no file holds stops the build, so a page cannot quote a number that
no benchmark measured (``tests/test_figures.py`` checks the pages for figures written in by hand)."""
from __future__ import annotations

import re
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
import record  # noqa: E402  (benchmarks/record.py: one place formats a figure)

PLACEHOLDER = re.compile(r"\{\{\s*(fig|table|measured):([A-Za-z_]\w*)(?:\.([A-Za-z_][\w,]*))?\s*\}\}")


def substitute(markdown: str, records: dict | None = None) -> str:
    records = record.load() if records is None else records

    def one(match: re.Match) -> str:
        kind, name, key = match.groups()
        if name not in records:
            raise KeyError(f"{match.group(0)}: no benchmark output benchmarks/results/{name}.json")
        keys = key.split(",") if key else []
        for one_key in keys:
            if one_key not in records[name]["figures"]:
                raise KeyError(f"{match.group(0)}: benchmarks/results/{name}.json holds no figure {one_key!r}")
        if kind == "fig":
            if len(keys) != 1:
                raise KeyError(f"{match.group(0)}: a figure is NAME.KEY")
            return record.render(records[name], keys[0])
        return record.table(records[name], keys or None) if kind == "table" else record.measured(records[name])
    return PLACEHOLDER.sub(one, markdown)


def on_page_markdown(markdown, page, config, files):
    return substitute(markdown)
