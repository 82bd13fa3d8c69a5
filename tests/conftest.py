import os

import pytest

from validation.peer import peer_directory


@pytest.fixture(scope="session", autouse=True)
def compiled_kernels():
    """Every kernel compiled before the first test (validation.warm: once per checkout and kernel sources, a stamp
    beside numba's cache saying so), so that no test pays a compile inside its own time or CPU bound."""
    from validation.warm import ensure
    ensure(progress=None)


@pytest.fixture(scope="session")
def peer():
    """The Siconos peer collection shipped in validation/data (never skipped: the data is in the project)."""
    return peer_directory()


def _ngspice_found() -> bool:
    import shutil
    from pathlib import Path
    return bool(shutil.which("ngspice")) and any(Path(d).glob("libngspice.so*") for d in
                                                 ("/usr/lib/x86_64-linux-gnu", "/usr/lib/aarch64-linux-gnu", "/usr/lib"))


def _require_ngspice() -> None:
    """In CI (``.ci/run`` sets CI) a missing ngspice is a failure, never a silent skip; elsewhere a skip that says
    how to get it."""
    if not _ngspice_found():
        if os.environ.get("CI"):
            pytest.fail("ngspice and libngspice must be installed in CI (make test installs them)")
        pytest.skip("ngspice not installed (make test installs it)")


@pytest.fixture(scope="session")
def ngspice():
    """ngspice through PySpice (the test carries the spice mark: :func:`pytest_collection_modifyitems`)."""
    _require_ngspice()
    return True


@pytest.fixture(scope="session")
def chromium():
    """A function that starts headless Chromium (Selenium, its console log kept): ``browser = chromium()``. In CI a
    missing browser is a failure; the test carries the spice mark (:func:`pytest_collection_modifyitems`)."""
    import shutil
    binary, driver = shutil.which("chromium"), shutil.which("chromedriver")
    if not (binary and driver):
        if os.environ.get("CI"):
            pytest.fail("chromium and chromedriver must be installed in CI (make test installs them)")
        pytest.skip("chromium not installed (make test installs it)")
    from selenium import webdriver

    def start():
        options = webdriver.ChromeOptions()
        options.binary_location = binary
        for arg in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
                    "--disable-background-networking", "--disable-component-update", "--disable-sync",
                    "--no-first-run", "--allow-file-access-from-files", "--window-size=1400,1000"):
            options.add_argument(arg)
        options.set_capability("goog:loggingPrefs", {"browser": "ALL"})
        return webdriver.Chrome(options=options, service=webdriver.ChromeService(executable_path=driver))
    return start


def pytest_collection_modifyitems(items):
    """Every test that asks for ngspice or Chromium carries the spice mark (``pytest -m "not spice"`` leaves them
    all out; in CI they run for real)."""
    for item in items:
        if {"ngspice", "chromium"} & set(getattr(item, "fixturenames", ())):
            item.add_marker(pytest.mark.spice)


def pytest_runtest_setup(item):
    """A spice-marked test runs only with ngspice there, whether or not it asks for the fixture."""
    if item.get_closest_marker("spice") is not None:
        _require_ngspice()


#: A test over this many seconds (setup, call and teardown) belongs in the slow tier (the Makefile's FAST_TIER).
SLOW_S = 2.0
_durations: dict = {}


def pytest_runtest_logreport(report):
    _durations[report.nodeid] = _durations.get(report.nodeid, 0.0) + report.duration


def pytest_terminal_summary(terminalreporter, config):
    """In a run that leaves the slow tests out, name the tests that took longer than SLOW_S: mark them slow (a
    loaded machine stretches every time: look twice before marking one)."""
    if "not slow" not in (config.getoption("markexpr") or ""):
        return
    slow = sorted(((seconds, nodeid) for nodeid, seconds in _durations.items() if seconds > SLOW_S), reverse=True)
    if slow:
        terminalreporter.write_sep("-", f"{len(slow)} tests of the fast tier took more than {SLOW_S:g} s: mark them slow")
        for seconds, nodeid in slow:
            terminalreporter.write_line(f"{seconds:6.1f} s  {nodeid}")
