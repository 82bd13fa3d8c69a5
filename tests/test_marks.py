"""Tests that need ngspice carry the spice mark, whether they ask for the ngspice fixture or are marked by hand,
and a spice test without ngspice fails in CI instead of skipping."""
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.slow
def test_every_test_that_asks_for_ngspice_is_spice_marked_and_none_is_left_unmarked():
    done = subprocess.run([sys.executable, "-m", "pytest", "--collect-only", "-q", "-p", "no:cacheprovider",
                           "-m", "not spice", "tests/circuits/test_one_shot.py", "tests/validation/test_report.py"],
                          cwd=ROOT, capture_output=True, text=True, timeout=120)
    unmarked = [line for line in done.stdout.splitlines() if "::" in line]
    assert unmarked and not any("compare_runs_the_load_step" in line or "headless_chromium" in line
                                or "every_default_scene" in line for line in unmarked), done.stdout
    marked = subprocess.run([sys.executable, "-m", "pytest", "--collect-only", "-q", "-p", "no:cacheprovider",
                             "-m", "spice", "tests/validation/test_report.py"],
                            cwd=ROOT, capture_output=True, text=True, timeout=120).stdout
    assert "test_the_page_loads_every_image_in_headless_chromium" in marked          # through its report fixture


@pytest.mark.slow
def test_a_spice_test_fails_in_ci_without_ngspice(tmp_path):
    (tmp_path / "test_needs.py").write_text("import pytest\n\n@pytest.mark.spice\ndef test_x():\n    pass\n")
    (tmp_path / "conftest.py").write_text((ROOT / "tests" / "conftest.py").read_text())
    env = {"PATH": str(tmp_path), "CI": "1", "PYTHONPATH": str(ROOT)}         # no ngspice on this PATH
    done = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-m", "spice",
                           str(tmp_path / "test_needs.py")], cwd=tmp_path, capture_output=True, text=True,
                          env=env, timeout=120)
    assert done.returncode == 1 and "must be installed in CI" in done.stdout, done.stdout[-2000:]
    del env["CI"]
    done = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-rs",
                           str(tmp_path / "test_needs.py")], cwd=tmp_path, capture_output=True, text=True,
                          env=env, timeout=120)
    assert done.returncode == 0 and "1 skipped" in done.stdout and "ngspice not installed" in done.stdout


@pytest.mark.slow
def test_the_fast_tier_holds_at_least_four_fifths_of_the_tests():
    """make check runs the Makefile's FAST_TIER selection: at least 80 % of what make test runs."""
    import re
    tier = re.search(r"^FAST_TIER := (.+)$", (ROOT / "Makefile").read_text(), re.M).group(1)

    def count(*marks):
        done = subprocess.run([sys.executable, "-m", "pytest", "--collect-only", "-q", "-p", "no:cacheprovider",
                               *marks], cwd=ROOT, capture_output=True, text=True, timeout=300)
        return sum("::" in line for line in done.stdout.splitlines())
    every, fast = count(), count("-m", tier)
    assert every > 2000 and fast >= 0.8 * every, (fast, every)
