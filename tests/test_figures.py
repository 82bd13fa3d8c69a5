"""Every cost the README and the docs state comes from a benchmark's output file (``benchmarks/results/*.json``,
written by ``make bench`` with its date and machine, substituted by ``docs/hooks/figures.py``): a placeholder names
a figure a file holds, and no page writes a cost in by hand. History (what a figure was before) is the changelog's.

A cost is a number with a unit of time, memory, rate or ratio (``0.32 ms``, ``4 GiB``, ``1,291 points/s``,
``562x``) in a page's prose or tables; fenced code blocks are transcripts of the examples, which run as printed
(``test_docs.py``). The same units also measure what is simulated (a settling time, an impact instant) or chosen
(a step, a window, a limit): those are listed below, each with the words around it, so a new hand-written cost
fails here naming its page and line."""
import json
import re
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]
HISTORY = {ROOT / "docs" / "changelog.md"}
RESULTS = ROOT / "benchmarks" / "results"
sys.path.insert(0, str(ROOT / "docs" / "hooks"))
import figures  # noqa: E402  (docs/hooks/figures.py: the placeholders' one definition)
sys.path.pop(0)
PLACEHOLDER = figures.PLACEHOLDER

COST = re.compile(r"(?<![\w.^/=])(?<![eE][-+])(\d[\d,]*(?:\.\d+)?)(?:\s?(ns/step|ns|us|ms|s|min|MB|MiB|GB|GiB|kB)\b|(x)\b"
                  r"|\s(points/s|samples/s|per second))")
#: A parameter or a target written as one: ``h = 50 ns``, ``TMAX 5 ns``, ``T 100 us``, ``--t-end 30 ms``,
#: ``target 10 s``.
PARAMETER = re.compile(r"(?:\b[hT]|TMAX|=|--[\w-]+|\bat|\bfrom|\bevery|\bover|\blast|\bdefaults?|\bat most|\b[Tt]arget:?)\s*$")

#: What the same units measure that is not a cost: a simulated quantity or a chosen value, by page, with the words
#: around it (a substring of the line).
NOT_COSTS: dict[str, list[str]] = {
    "README.md": ["nothing over 2 s"],                                          # the fast tier's threshold
    "docs/architecture.md": ["take more than 2 s", "took more than 2 s"],
    "docs/guide/accuracy.md": ["more than 10x below", "within 10x of the true error",   # criteria
                               "charging in 6 ns after", "10 ns step", "the default 30 ms run",
                               "the estimates are 0.78x to 6.9x the true"],     # estimates against true errors
    "docs/guide/command-line.md": ["the 60 ms sliding-mode boost", "1.05 S + 0.5 s", "no process 2 s",
                                   "1 GiB (the command", "a 0.5-1 s limit", "20 s for"],
    "docs/guide/report.md": ["under 50 MB"],                                  # the report's own target
    "docs/guide/measurements.md": ["settles in 3.84 ms within the envelope's 3.92 ms"],
    "docs/guide/sliding-mode.md": ["30 ms from power-up", "| 9.017 ms | 9.006 ms"],
    "docs/guide/small-signal.md": ["band after 0.27 ms", "68.1 mV and 0.25 ms"],
    "docs/performance.md": ["ohm; 5 ms,", "10 ohm, 5 ms from rest", "periods per 20 ms", "1.5625 ns",
                            "~10x smaller constant", "beside a 10 us period", "a 60 s limit"],
    "docs/tutorials/bifurcations.md": ["runs 0.4 s at 33"],                       # simulated time
    "docs/tutorials/design-a-buck.md": ["takes 1.1 ms to settle"],
    "docs/tutorials/friction.md": ["1.354570922957193 s"],
    "docs/tutorials/sweeps.md": ["600 s limit"],
    "docs/tutorials/your-netlist.md": ["periods of 20 ms", "20 ms period to ngspice", "the 4 GiB memory limit", "TMAX of 5 ns"],
}


def _records() -> dict:
    return {path.stem: json.loads(path.read_text()) for path in sorted(RESULTS.glob("*.json"))}


def _prose(path: Path):
    """(line number, line) of a page outside its fenced code blocks, inline code and placeholders removed."""
    text = re.sub(r"(?ms)^```.*?^```", lambda m: "\n" * m.group(0).count("\n"), path.read_text())
    for number, line in enumerate(text.splitlines(), 1):
        yield number, re.sub(r"`[^`]*`", "``", PLACEHOLDER.sub("{{}}", line))


def hand_written_costs(path: Path) -> list[str]:
    name = str(path.relative_to(ROOT)) if path.is_relative_to(ROOT) else path.name
    allowed = NOT_COSTS.get(name, [])
    found = []
    for number, line in _prose(path):
        for match in COST.finditer(line):
            if PARAMETER.search(line[:match.start()]):
                continue
            if any(words in line and match.group(0) in words for words in allowed):
                continue
            found.append(f"{name}:{number}: {match.group(0)!r} in "
                         f"...{line[max(0, match.start() - 50):match.end() + 20]}...")
    return found


def test_every_page_quotes_its_costs_from_a_benchmark_output():
    found = [hit for page in PAGES if page not in HISTORY for hit in hand_written_costs(page)]
    assert not found, ("costs written into a page by hand (quote them as {{ fig:NAME.KEY }} from a benchmark's "
                       "output, move them to the changelog as history, or list a simulated or chosen value in "
                       "NOT_COSTS):\n" + "\n".join(found))


def test_every_listed_exemption_still_matches_its_page():
    stale = [(page, words) for page, listed in NOT_COSTS.items() for words in listed
             if words not in "\n".join(line for _, line in _prose(ROOT / page))]
    assert not stale, stale


def test_every_placeholder_names_a_figure_a_benchmark_wrote():
    records = _records()
    missing = []
    for page in PAGES:
        for number, line in enumerate(page.read_text().splitlines(), 1):
            for kind, name, keys in PLACEHOLDER.findall(line):
                if name not in records or any(key not in records[name]["figures"] for key in keys.split(",") if key) \
                        or (kind == "fig" and not keys):
                    missing.append(f"{page.relative_to(ROOT)}:{number}: {kind}:{name}.{keys}")
    assert not missing, missing
    assert not PLACEHOLDER.search((ROOT / "README.md").read_text()), "GitHub shows the README unsubstituted"


def test_every_output_says_when_and_where_it_was_measured():
    records = _records()
    assert records, "no benchmark output in benchmarks/results"
    for name, record in records.items():
        assert (ROOT / "benchmarks" / f"{name}.py").exists(), name
        assert re.fullmatch(r"\d{4}-\d{2}-\d{2}", record["date"]), (name, record["date"])
        assert record["machine"]["cores"] >= 1 and record["machine"]["cpu"], name
        assert record["figures"], name
        for key, figure in record["figures"].items():
            assert isinstance(figure["value"], float) and figure["label"], (name, key)


def test_the_hook_substitutes_a_figure_and_refuses_an_unknown_one():
    records = {"demo": {"benchmark": "demo", "about": "a demonstration", "date": "2026-12-02",
                        "command": "python benchmarks/demo.py",
                        "machine": {"cpu": "some CPU", "cores": 2, "load_1min": 0.5},
                        "figures": {"rate": {"value": 1290.6, "unit": "points/s", "label": "a rate", "digits": 3},
                                    "ratio": {"value": 561.7, "unit": "x", "label": "a ratio", "digits": 3},
                                    "step": {"value": 4.94, "unit": "ns/step", "label": "a step", "digits": 2}}}}
    text = figures.substitute("{{ fig:demo.rate }}, {{fig:demo.ratio}} and {{ fig:demo.step }}", records)
    assert text == "1,291 points/s, 562x and 4.9 ns/step"
    assert "measured 2026-12-02 by `python benchmarks/demo.py` on 2 cores of some CPU" in figures.substitute(
        "{{ table:demo }}", records)
    assert figures.substitute("{{ table:demo.ratio,rate }}", records).splitlines()[2:4] == [
        "| a ratio | 562x |  |", "| a rate | 1,291 points/s |  |"]
    with pytest.raises(KeyError, match="holds no figure 'nothing'"):
        figures.substitute("{{ fig:demo.nothing }}", records)
    with pytest.raises(KeyError, match="no benchmark output"):
        figures.substitute("{{ fig:absent.rate }}", records)


def test_the_scan_finds_a_cost_written_by_hand(tmp_path):
    page = tmp_path / "page.md"
    page.write_text("It takes 0.32 ms a period, 562x ngspice; h = 50 ns and --t-end 5 ms are parameters.\n\n"
                    "```text\nin 0.001 s\n```\n{{ fig:demo.rate }} and `in 2 s`\n")
    hits = [hit.split(": ")[1].split(" in ")[0] for hit in hand_written_costs(page)]
    assert hits == ["'0.32 ms'", "'562x'"]
    assert hand_written_costs(page)[0].startswith("page.md:1: '0.32 ms' in ...It takes 0.32 ms a period")
