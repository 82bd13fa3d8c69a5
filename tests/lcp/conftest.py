import pytest


class TickingClock:
    """A monotonic clock that advances ``step`` seconds each time it is read: a solve's time limit becomes a number
    of looks at the clock, so a test of the limit counts looks and pivots instead of timing a loaded machine (the
    time a slice of work takes is measured in benchmarks/time_limits.py)."""

    def __init__(self, step: float):
        self.now, self.step, self.reads = 1000.0, step, 0

    def __call__(self) -> float:
        self.reads += 1
        self.now += self.step
        return self.now


@pytest.fixture
def ticking_clock(monkeypatch):
    """The LCP solves' clock (converters.lcp.solve._monotonic) replaced by a :class:`TickingClock` of 10 ms a
    read, and the set-up time a solve leaves out (numba's compiles and cache loads, the engine's import: real
    seconds) none: subtracted from the ticking clock, a first solve's cache load (0.5 s alone, 0 after another
    test) gave the limit 47 more looks."""
    from converters.lcp import solve
    clock = TickingClock(0.01)
    monkeypatch.setattr(solve, "_monotonic", clock)
    monkeypatch.setattr(solve, "_setup_seconds", lambda: 0.0)
    return clock
