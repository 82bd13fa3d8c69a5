"""Keep numba's on-disk cache of the compiled LCP methods consistent with their sources.

numba stamps each cached function with its own file's modification time and size only. A compiled
function that calls a compiled function (or reads a constant) of another module keeps, in its cache, the
old copy when only that other module changes (numba issue 6845). The LCP methods call across their
modules (result.check, kernels.solve_augmented, the state layout, ...); so :func:`refresh`, run when
:mod:`converters.lcp` is imported, hashes their sources and, when the hash differs from the one recorded
next to the cache, removes their cache files (numba then compiles them again, once). A cache directory
that cannot be written is left alone (numba then keeps its cache in NUMBA_CACHE_DIR or compiles in memory).
"""
from __future__ import annotations

import hashlib
import os
from pathlib import Path

#: Modules with compiled LCP code, whose cache files go when any source changes.
COMPILED = ("result", "fastpaths", "lemke", "murty", "pgs", "newton", "enumeration", "dispatch", "auto", "engine")
#: Their sources: those modules, the state layout they index with, and the stepper kernels they call.
SOURCES = COMPILED + ("state", "kernels")
STAMP = "lcp-compiled-sources.sha256"


def refresh(directory: Path | None = None) -> bool:
    """Remove the compiled modules' cache files when their sources changed; True when it removed them."""
    directory = directory or Path(__file__).parent
    try:
        digest = hashlib.sha256(b"".join((directory / f"{name}.py").read_bytes() for name in SOURCES)).hexdigest()
    except OSError:
        return False
    cache = directory / "__pycache__"
    stamp = cache / STAMP
    try:
        if stamp.read_text() == digest:
            return False
    except OSError:
        pass
    try:
        cache.mkdir(exist_ok=True)
        for name in COMPILED:
            for path in list(cache.glob(f"{name}.*.nbi")) + list(cache.glob(f"{name}.*.nbc")):
                path.unlink(missing_ok=True)
        temporary = cache / f"{STAMP}.{os.getpid()}.tmp"
        temporary.write_text(digest)
        os.replace(temporary, stamp)
    except OSError:
        return False
    return True
