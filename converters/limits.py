"""Resource limits: the size of a run is known before it starts, and every long computation has a time limit.

Every command estimates what a run will allocate (steps x state size, map size, LCP size, ngspice
points) and calls :func:`check_memory` before allocating; iterative solvers and ngspice runs take their
limit from :func:`time_limit`. Both limits travel in environment variables so that worker processes
(forked or spawned, local or Dask) see what the command line set:

- ``PCSUITE_MAX_MEMORY`` (``--max-memory`` on every command): bytes, with a binary suffix allowed
  (``512MiB``, ``4G`` = 4 GiB); default 4 GiB.
- ``PCSUITE_TIME_LIMIT`` (``--time-limit``): seconds for one ngspice run or one iterative LCP solve; default 600
  s for ngspice and 20 s for ``pcsuite lcp solve`` (each caller states its own default).
"""
from __future__ import annotations

import math
import os
import re
import sys
import time
from typing import Any

from .errors import ResourceError

MEMORY_ENV = "PCSUITE_MAX_MEMORY"
TIME_ENV = "PCSUITE_TIME_LIMIT"
DEFAULT_MAX_MEMORY = 4 << 30
#: Bounds a user may set: 16 MiB .. 1 TiB of memory, 0.1 s .. 7 days of time.
MEMORY_RANGE = (1 << 24, 1 << 40)
TIME_RANGE = (0.1, 7 * 86400.0)

_BYTES = re.compile(r"^\s*(\d+(?:\.\d*)?|\.\d+)(?:[eE]([+-]?\d+))?\s*([kKmMgGtT]i?[bB]?|[bB])?\s*$")
_FACTOR = {"": 1, "b": 1, "k": 1 << 10, "m": 1 << 20, "g": 1 << 30, "t": 1 << 40}


def parse_bytes(name: str, text: object, bounds: tuple[float, float] = MEMORY_RANGE) -> int:
    """Bytes from ``4G``, ``512MiB``, ``1e9`` (binary multiples: K, M, G, T = 2^10 .. 2^40), within ``bounds``."""
    from .validate import shown
    if isinstance(text, (int, float)) and not isinstance(text, bool):
        try:
            value = float(text)
        except OverflowError:           # an int beyond a double: beyond every bound
            value = math.inf
    else:
        match = _BYTES.match(str(text))
        if not match:
            raise ResourceError(f"{name} must be a size in bytes such as 512M, 4G or 2e9; got {shown(str(text), 80)}")
        mantissa, exponent, suffix = match.groups()
        # float() reads any exponent (1e400 -> inf, 1e-400 -> 0); 10.0 ** int(...) overflowed, and int() of a
        # 5,000-digit exponent raised Python's digit limit
        value = float(f"{mantissa}e{exponent or 0}") * _FACTOR[(suffix or "")[:1].lower()]
    if not (math.isfinite(value) and bounds[0] <= value <= bounds[1]):
        raise ResourceError(f"{name} must be in [{human_bytes(bounds[0])}, {human_bytes(bounds[1])}]; "
                            f"got {shown(text if isinstance(text, (int, float)) else str(text), 80)}")
    return int(value)


def human_bytes(nbytes: float) -> str:
    for unit, size in (("TiB", 1 << 40), ("GiB", 1 << 30), ("MiB", 1 << 20), ("KiB", 1 << 10)):
        if nbytes >= size:
            return f"{nbytes / size:.3g} {unit}"
    return f"{nbytes:.0f} B"


def max_memory() -> int:
    """The memory a run may plan to allocate (bytes)."""
    text = os.environ.get(MEMORY_ENV)
    return DEFAULT_MAX_MEMORY if not text else parse_bytes(MEMORY_ENV, text)


def set_max_memory(text: object) -> int:
    """Set the limit for this process and every worker it starts (``--max-memory``)."""
    value = parse_bytes("--max-memory", text)
    os.environ[MEMORY_ENV] = str(value)
    return value


def check_memory(what: str, nbytes: float, remedy: str = "") -> None:
    """Refuse, before allocating, a run whose estimated size is above the limit.

    ``what`` names the run and its size (``"simulate buck: 1e+09 steps x 6 values"``); ``remedy`` says what
    to change (``"a larger --h or a shorter --t-end"``)."""
    limit = max_memory()
    if not nbytes <= limit:        # NaN and inf are refused too
        needed = human_bytes(nbytes) if math.isfinite(nbytes) else "an unbounded amount"
        if math.isfinite(nbytes) and nbytes <= MEMORY_RANGE[1]:
            mib = 2 ** max(4, math.ceil(math.log2(nbytes / (1 << 20))))
            size = f"{mib >> 10}G" if mib >= 1024 else f"{mib}M"
            raise_it = f"raise the limit with --max-memory {size} (or {MEMORY_ENV})"
        else:
            raise_it = f"no --max-memory allows it (at most {human_bytes(MEMORY_RANGE[1])})"
        raise ResourceError(f"{what} needs about {needed}, above the memory limit of {human_bytes(limit)}; "
                            + (f"use {remedy}; " if remedy else "") + raise_it)


def memory_in_use() -> int:
    """This process's resident memory in bytes (0 where /proc is not there)."""
    try:
        with open("/proc/self/statm") as statm:
            return int(statm.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")
    except (OSError, ValueError, IndexError):
        return 0


def check_in_use(what: str, remedy: str = "") -> None:
    """Stop a run whose memory grows past the limit while it runs, where no estimate before it can bound it (the
    event method's segments and events on a circuit that chatters)."""
    limit, used = max_memory(), memory_in_use()
    if used > limit:
        raise ResourceError(f"{what} holds {human_bytes(used)}, above the memory limit of {human_bytes(limit)}; "
                            + (f"use {remedy}; " if remedy else "") + f"raise the limit with --max-memory (or "
                            f"{MEMORY_ENV})")


def time_limit(default: float) -> float:
    """Seconds one ngspice run or one iterative solve may take (``--time-limit``, else ``default``)."""
    text = os.environ.get(TIME_ENV)
    return default if not text else parse_seconds(TIME_ENV, text)


def parse_seconds(name: str, text: str | float) -> float:
    try:
        value = float(text)
    except (TypeError, ValueError):
        raise ResourceError(f"{name} must be a number of seconds in [{TIME_RANGE[0]:g}, {TIME_RANGE[1]:g}]; "
                            f"got {text!r}") from None
    if not TIME_RANGE[0] <= value <= TIME_RANGE[1]:
        raise ResourceError(f"{name} must be in [{TIME_RANGE[0]:g}, {TIME_RANGE[1]:g}] s; got {text!r}")
    return value


def set_time_limit(text: str | float) -> float:
    value = parse_seconds("--time-limit", text)
    os.environ[TIME_ENV] = repr(value)
    return value


class Deadline:
    """A wall-clock limit checked inside long loops: ``deadline.expired()`` is cheap (one clock read)."""

    def __init__(self, seconds: float) -> None:
        self.seconds = float(seconds)
        self.end = time.monotonic() + self.seconds

    def expired(self) -> bool:
        return time.monotonic() > self.end

    def message(self, what: str) -> str:
        return (f"{what} reached the time limit of {self.seconds:g} s; raise it with --time-limit S "
                f"(or {TIME_ENV})")


# ------------------------------------------------------------------------------ the time spent compiling
# A time limit measures the work it limits, never a compile. numba compiles a kernel (or loads it from its disk
# cache) at its first call with new argument types, inside the first run that needs it: with an empty cache (a
# fresh machine, a kernel source changed) tens of seconds, more than a limit a user sets for the run. The clock
# below counts, per thread, the time spent in numba's compiler (whose lock spans every compile and cache load:
# the "numba:compiler_lock" event), so that a limit can leave it out: an LCP solve's deadline
# (:mod:`converters.lcp.solve`) and the command line's alarm for a one-run command (:mod:`validation.cli`).

_compiled: dict = {}            # thread id -> seconds spent in numba's compiler, compiles that have ended
_compiling: dict = {}           # thread id -> (lock depth, monotonic time of the outermost acquisition)
_compile_clock: list = []


def install_compile_clock() -> None:
    """Start counting the time each thread spends in numba's compiler (imports numba; once per process)."""
    if _compile_clock:
        return
    import threading

    from numba.core import event
    ident = threading.get_ident

    class CompileClock(event.Listener):
        def on_start(self, event: Any) -> None:
            depth, since = _compiling.get(ident(), (0, 0.0))      # the lock is re-entrant: its outermost hold
            _compiling[ident()] = (depth + 1, since if depth else time.monotonic())

        def on_end(self, event: Any) -> None:
            depth, since = _compiling.pop(ident(), (0, 0.0))
            if depth > 1:
                _compiling[ident()] = (depth - 1, since)
            elif depth == 1:
                _compiled[ident()] = _compiled.get(ident(), 0.0) + time.monotonic() - since
            # depth 0: taken before the clock was installed, so before anything it times began

    clock = CompileClock()
    event.register("numba:compiler_lock", clock)
    _compile_clock.append(clock)


def compile_seconds(ident: int | None = None) -> float:
    """Seconds thread ``ident`` (default: this one) has spent in numba's compiler since :func:`install_compile_clock`,
    a compile under way included (0 before it)."""
    if ident is None:
        import threading
        ident = threading.get_ident()
    depth, since = _compiling.get(ident, (0, 0.0))
    return _compiled.get(ident, 0.0) + (time.monotonic() - since if depth else 0.0)


#: ``PCSUITE_MALLOC_PAD``: bytes of freed memory glibc's malloc keeps for the next run (0: leave malloc alone).
MALLOC_PAD_ENV = "PCSUITE_MALLOC_PAD"
DEFAULT_MALLOC_PAD = 64 << 20
MALLOC_PAD_RANGE = (0, 1 << 30)
_M_TOP_PAD, _M_MMAP_THRESHOLD = -2, -3     # glibc's mallopt parameter numbers (malloc.h)
#: Blocks up to this size come from the heap (glibc's own ceiling for its adaptive threshold), larger ones from mmap.
_MMAP_THRESHOLD = 32 << 20


def keep_freed_memory() -> bool:
    """Ask glibc's malloc to keep up to ``PCSUITE_MALLOC_PAD`` (default 64 MiB) of freed memory at the top of
    its heap rather than hand it back to the OS at once (``mallopt(M_TOP_PAD)``), and to serve blocks up to
    32 MiB from that heap (``M_MMAP_THRESHOLD``; setting the pad turns glibc's adaptive threshold off, and
    its 128 KiB start would send every result array to mmap). A run allocates its grid
    and its x, u, y afresh (5 MB for 100k steps of the buck); returned to the OS after each run, every next
    run page-faults them in again (750-1,300 faults: 0.7-1 ms of a 1.7-2 ms warm run, ``benchmarks/peers.py``); kept,
    it reuses them. Returns True when the setting took (glibc only; elsewhere nothing changes)."""
    raw = os.environ.get(MALLOC_PAD_ENV, "").strip()
    pad = DEFAULT_MALLOC_PAD
    if raw:
        try:
            pad = parse_bytes(MALLOC_PAD_ENV, raw, MALLOC_PAD_RANGE)
        except ResourceError as exc:          # a tuning knob: warn, keep the default, do not stop the run
            import warnings
            warnings.warn(f"{exc}; using the default {DEFAULT_MALLOC_PAD >> 20}M", stacklevel=2)
    if pad <= 0 or not sys.platform.startswith("linux"):
        return False
    return bool(_mallopt(_M_MMAP_THRESHOLD, _MMAP_THRESHOLD)) and bool(_mallopt(_M_TOP_PAD, pad))


def _mallopt(parameter: int, value: int) -> int:
    """glibc's mallopt (1 when the setting took, 0 otherwise, or when there is no mallopt: musl)."""
    try:
        import ctypes
        return ctypes.CDLL(None).mallopt(parameter, value)
    except (OSError, AttributeError):
        return 0
