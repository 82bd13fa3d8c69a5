"""Keep numba's on-disk cache of the compiled kernels consistent with their sources.

numba stamps each cached function with its own file's modification time and size only. A compiled
function that calls a compiled function (or reads a constant) of another module keeps, in its cache, the
old copy when only that other module changes (numba issue 6845). The kernels call across their modules
(the step loops call the small-LCP kernels, the LCP methods call result.check and each other, every one reads
constants of lcp/state.py and compiled.py); so :func:`refresh`, run when :mod:`converters` is imported (before
any kernel loads), hashes their sources and, when the hash differs from the one recorded beside them, removes
every compiled module's cache files, beside the sources and in NUMBA_CACHE_DIR when it is set (numba then
compiles them again, once). A directory that cannot be written is left alone. The ahead-of-time module
(:mod:`converters.compiled`) has its own record of the sources it was built from.
"""
from __future__ import annotations

import hashlib
import os
from pathlib import Path

#: The modules with compiled code (paths under converters/; numba keeps a function's cache beside the module that
#: defines it: floquet.py's spectral_radius is compiled by sweeps/batch.py): a test checks this is every one.
COMPILED = ("lcp/result.py", "lcp/fastpaths.py", "lcp/lemke.py", "lcp/murty.py", "lcp/pgs.py", "lcp/newton.py",
            "lcp/enumeration.py", "lcp/dispatch.py", "lcp/auto.py", "lcp/engine.py", "lcp/kernels.py",
            "methods/theta_kernels.py", "methods/moreau_kernels.py", "analysis/newton_kernel.py", "sweeps/batch.py",
            "analysis/floquet.py", "thermal/kernels.py", "circuits/kernels.py")
#: Their sources: those modules and the constants they read at compile time.
SOURCES = COMPILED + ("lcp/state.py", "compiled.py")
STAMP = "kernel-sources.sha256"


def refresh(root: Path | None = None) -> bool:
    """Remove the compiled modules' cache files when any source changed; True when it removed them."""
    root = root or Path(__file__).parent
    try:
        digest = hashlib.sha256(b"".join((root / name).read_bytes() for name in SOURCES)).hexdigest()
    except OSError:
        return False
    stamp = root / "__pycache__" / STAMP
    try:
        if stamp.read_text() == digest:
            return False
    except OSError:
        pass
    try:
        stamp.parent.mkdir(exist_ok=True)
        for name in COMPILED:
            path = Path(name)
            for cache in _cache_directories(root / path.parent):
                for stale in list(cache.glob(f"{path.stem}.*.nbi")) + list(cache.glob(f"{path.stem}.*.nbc")):
                    stale.unlink(missing_ok=True)
        temporary = stamp.parent / f"{STAMP}.{os.getpid()}.tmp"
        temporary.write_text(digest)
        os.replace(temporary, stamp)
    except OSError:
        return False
    return True


def _cache_directories(source_directory: Path) -> list:
    """Where numba caches the functions of modules in ``source_directory``: its __pycache__ and, when
    NUMBA_CACHE_DIR is set, numba's directory for it there (``<name>_<sha1 of its absolute path>``, as
    numba.core.caching names it)."""
    out = [source_directory / "__pycache__"]
    user = os.environ.get("NUMBA_CACHE_DIR")
    if user:
        absolute = os.path.abspath(source_directory)
        out.append(Path(user) / f"{os.path.basename(absolute)}_{hashlib.sha1(absolute.encode()).hexdigest()}")
    return out
