"""The documentation: the site builds with warnings as errors, every example in it and in the README runs as
printed, the README stays a short entry point, and no file cites a document the repository does not hold."""
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

from validation.cli import main

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]
#: A command or code block that needs ngspice (it runs for real in CI under the spice mark).
NEEDS_SPICE = re.compile(r"\bcompare\b|--method spice|ngspice")


def _pages():
    """(page, [(kind, text)]) of every page with ```console or ```python blocks, in the README and the docs."""
    for page in PAGES:
        text = page.read_text()
        blocks = [(m.group(1), m.group(2)) for m in re.finditer(r"(?ms)^```(console|python)\n(.*?)^```", text)]
        if blocks:
            marks = [pytest.mark.spice] if any(NEEDS_SPICE.search(b) for _, b in blocks) else []
            yield pytest.param(blocks, id=str(page.relative_to(ROOT)), marks=marks)


@pytest.mark.slow
def test_the_site_builds_with_warnings_as_errors(tmp_path):
    done = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(tmp_path / "site")],
                          cwd=ROOT, capture_output=True, text=True, timeout=300,
                          env={**__import__("os").environ, "NO_MKDOCS_2_WARNING": "1"})
    assert done.returncode == 0, done.stderr[-3000:]
    cli = (tmp_path / "site" / "cli" / "index.html").read_text()
    assert "pcsuite mech simulate" in cli and "--steady-tol" in cli           # generated from the parser
    assert "Solve LCP(q, M)" in (tmp_path / "site" / "api" / "index.html").read_text()    # from the docstrings


@pytest.mark.parametrize("blocks", list(_pages()))
def test_every_example_in_the_docs_runs_as_printed(blocks, tmp_path, monkeypatch, capsys):
    """A page's blocks run in order in one empty directory beside the shipped netlists (a later block reads what an
    earlier one wrote): each ``$ pcsuite ...`` line of a console block exits 0 (its output shown in the page is one
    run's); each python block runs (its asserts are checks)."""
    (tmp_path / "netlists").symlink_to(ROOT / "netlists")
    monkeypatch.chdir(tmp_path)
    for kind, text in blocks:
        if kind == "python":
            exec(compile(text, "example", "exec"), {"__name__": "__example__"})
            continue
        commands = [line[2:] for line in text.splitlines() if line.startswith("$ ")]
        assert commands, text
        for command in commands:
            argv = shlex.split(command)
            assert argv[0] == "pcsuite", command
            code = main(argv[1:])
            assert code == 0, (command, capsys.readouterr().err)


def test_the_readme_is_a_short_entry_point():
    lines = (ROOT / "README.md").read_text().splitlines()
    assert len(lines) <= 200, len(lines)


def test_no_file_cites_a_document_the_repository_does_not_hold():
    tracked = subprocess.run(["git", "ls-files"], cwd=ROOT, capture_output=True, text=True).stdout.split()
    if not tracked:                                    # not a git checkout (an unpacked sdist): every file
        tracked = [str(p.relative_to(ROOT)) for p in ROOT.rglob("*") if p.is_file() and ".venv" not in p.parts]
    # this file names the patterns it looks for (it is skipped); a relative path that climbs out of the repository
    # to a file that exists there (a document a clone elsewhere does not have) is found by where it resolves, not by
    # its name (the hostile-input tests' "../../../../escaped" points nowhere)
    cited = re.compile(r"REFERENCE (section|sections|\d)|REFERENCE's|REFERENCE\.md|CONTRACT\.md|STYLE\.md")
    climbing = re.compile(r"(?:\.\./)+[\w.-]+")
    found = []
    for name in tracked:
        path = ROOT / name
        if path.suffix not in {".py", ".md", ".toml", ".cir", ".txt", ".yml", ".cfg"} or not path.is_file():
            continue
        for number, line in enumerate(path.read_text(errors="replace").splitlines(), 1):
            outside = [m for m in climbing.findall(line) if not (path.parent / m).resolve().is_relative_to(ROOT)
                       and (path.parent / m).resolve().exists()]
            if (cited.search(line) or outside) and path != Path(__file__).resolve():
                found.append(f"{name}:{number}: {line.strip()[:100]}")
    assert not found, "\n".join(found)
