"""The compiled kernels of the hot loops, and where they come from: a module built ahead of time when the
package is installed, or numba's just-in-time compiler.

The kernels are written once, in Python, for numba (:mod:`.methods.theta_kernels`, :mod:`.lcp.kernels`,
:mod:`.analysis.newton_kernel`, the LCP methods of :mod:`.lcp`). ``make setup`` (or ``python -m converters.build_kernels``) also compiles the ones a
plain run needs with numba's ahead-of-time compiler (``numba.pycc``, the same front end and LLVM code as the
JIT, for this machine's CPU) into the extension module ``converters/_kernels``; beside it, ``_kernels.json``
records the SHA-256 of every kernel source (:data:`converters.kernel_cache.SOURCES`: the modules with compiled code
and those whose constants the kernels read, and the build script; an edit anywhere else leaves the module in use),
the Python, numpy and CPU it was built for, and each export's argument types. A process whose sources (and Python, numpy, CPU) still match loads
that module: it imports neither numba nor scipy (about 0.25 s) and compiles nothing (numba's first call of a cached
kernel costs 0.05-0.1 s more each), so ``pcsuite simulate`` starts in about a tenth of a second. When the
module is missing, stale (a kernel source edited since the build) or unloadable, :func:`kernel` returns the
numba dispatcher instead: the same code, compiled on first call and cached on disk. ``PCSUITE_KERNELS=jit``
forces the JIT (both give the same numbers: ``tests/methods/test_compiled.py``). numba.pycc's wrappers check
only that an array argument is an ndarray, so :func:`kernel` checks every argument's dtype, dimensions and
C order (:func:`conforms`, ~2 us a call) and hands any other kind to the JIT, which compiles a version for it.

Why numba.pycc: it compiles the very functions the JIT runs (one source of truth), and the module it writes
depends on NumPy only. numba marks it "pending deprecation" since 0.57 while a replacement is developed; it is
still shipped (0.68) and, if it ever goes, the JIT path is unchanged.

This module itself imports neither numba nor the kernels' modules: it also holds the constants the callers
share with the kernels (status codes, sizes).
"""
from __future__ import annotations

import hashlib
import importlib
import json
import os
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from collections.abc import Callable, Sequence
    from types import ModuleType

    import numpy as np
    import numpy.typing as npt

#: Status codes of the compiled step loops (:func:`.methods.theta_kernels.run_steps` and the state-driven ones).
OK, NEEDS_GENERAL_SOLVER, NO_SOLUTION = 0, 1, 2
#: Extra status of the state-switched loop: the event buffers are full (the caller grows them, resumes).
EVENTS_FULL = 3
#: Extra status of the state-switched loop: the channels entered a combination of states with no configuration.
FORBIDDEN = 4
#: The verdicts of one Newton-shooting iteration (:func:`.analysis.newton_kernel.newton_step`: the one stopping
#: rule of the serial and the batched drivers): go on; converged (the estimated distance to the orbit within the
#: tolerance); the residual at the rounding level (ROUNDING machine epsilons, relative: iterating cannot help);
#: the iterations spent; the Jacobian minus I singular (a multiplier at 1); and of the driver
#: (:func:`.analysis.periodic.newton_iterate`): a relaxation period the map could not take (a step LCP without a
#: solution), or one that left the finite numbers.
NEWTON_CONTINUE, NEWTON_CONVERGED, NEWTON_ROUNDING, NEWTON_EXHAUSTED, NEWTON_SINGULAR = 0, 1, 2, 3, 4
NEWTON_NO_SOLUTION, NEWTON_NONFINITE = 5, 6
#: What the driver (:func:`.analysis.newton_kernel.newton_advance`) asks of its caller: the spectral radius of the
#: Jacobian at the current iterate, or the period map at the trial state.
NEWTON_RADIUS, NEWTON_EVALUATE = 10, 11
ROUNDING = 64
#: Largest k solved inline by the step loops (:func:`.lcp.kernels.solve_small_lcp`); above it they pivot
#: (:func:`.lcp.murty.solve_warm`), at most PIVOTS_PER_PAIR k flips a step before the general solver takes it.
MAX_INLINE_K = 8
PIVOTS_PER_PAIR = 4
#: Up to this many states the one-pair loop carries the state in registers (a tuple of n floats, its
#: length fixing n at compile time: one specialisation per n, cached); above it, in the rows of x
#: (measured: registers 4.4 ns/step at n = 2, 7.1 at n = 4; rows 7.1 and 19.7; even at n = 8, 40 against 31).
MAX_REGISTER_STATES = 6


def register_state(n: int) -> tuple[float, ...] | None:
    """The ``state`` argument of the one-pair loop: n zeros (the state in registers) or None (in x)."""
    return (0.0,) * n if n <= MAX_REGISTER_STATES else None


HERE = Path(__file__).resolve().parent
MODULE = "_kernels"
RECORD = HERE / f"{MODULE}.json"
#: name -> (module, function): the kernels this module serves.
KERNELS = {
    "run_steps": ("converters.methods.theta_kernels", "run_steps"),
    "set_matrices": ("converters.methods.theta_kernels", "set_matrices"),
    "step_jacobian": ("converters.methods.theta_kernels", "step_jacobian"),
    "newton_step": ("converters.analysis.newton_kernel", "newton_step"),
    "newton_advance": ("converters.analysis.newton_kernel", "newton_advance"),
    "solve_once": ("converters.lcp.engine", "solve_once"),
    "solve_many": ("converters.lcp.engine", "solve_many"),
    "lcp_default_options": ("converters.lcp.dispatch", "default_options"),
}

#: Exports called without :func:`conforms` (the caller has checked every argument's type itself: the thin path
#: of :func:`converters.lcp.solve_lcp`, where the check would cost as much as the solve).
UNCHECKED = ("solve_once", "lcp_default_options")
_loaded: dict = {}
_decided: list = []     # [the ahead-of-time module or None, "ahead-of-time" or "jit: <why>"], once decided
#: Values of PCSUITE_KERNELS: ``auto`` (the default: ahead of time when current) or ``jit``.
KERNEL_SOURCES = ("auto", "jit")


def kernel(name: str) -> Callable[..., Any]:
    """The compiled function ``name`` of :data:`KERNELS`: from the ahead-of-time module when it is built from the
    current sources (and ``PCSUITE_KERNELS`` is not ``jit``), else numba's dispatcher."""
    if name not in _loaded:
        module = _ahead_of_time()[0]
        if module is not None:
            _loaded[name] = (_run_steps_by_size(module) if name == "run_steps" else
                             getattr(module, name) if name in UNCHECKED else
                             _checked(name, getattr(module, name), _record()["exports"][name]))
        else:
            _loaded[name] = _jit(name)
    return _loaded[name]


def _jit(name: str) -> Callable[..., Any]:
    """numba's dispatcher of kernel ``name`` (its module imported on first use)."""
    where, function = KERNELS[name]
    return getattr(importlib.import_module(where), function)


def source() -> str:
    """Where the kernels come from in this process: ``ahead-of-time`` or ``jit: <the reason>``."""
    return _ahead_of_time()[1]


def _ahead_of_time() -> list[Any]:
    """(module or None, source), decided once per process."""
    if not _decided:
        _decided.extend(_decide())
    return _decided


def _decide() -> tuple[ModuleType | None, str]:
    choice = os.environ.get("PCSUITE_KERNELS", "").strip().lower() or "auto"
    if choice not in KERNEL_SOURCES:
        import warnings
        warnings.warn(f"PCSUITE_KERNELS must be one of {', '.join(KERNEL_SOURCES)}; got {choice!r}; using auto",
                      stacklevel=3)
    if choice == "jit":
        return None, "jit: PCSUITE_KERNELS=jit"
    why = stale()
    if why:
        return None, f"jit: {why}"
    try:
        return importlib.import_module(f"converters.{MODULE}"), "ahead-of-time"
    except ImportError as exc:
        return None, f"jit: the ahead-of-time module does not load ({exc})"


def file_stat(path: Path) -> list:
    """[size, modification time in ns]: a file with both unchanged since the build is not read again."""
    info = path.stat()
    return [info.st_size, info.st_mtime_ns]


def digest(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _record(_read: dict[Path, Any] = {}) -> dict:
    """The build's record (read once per path)."""
    if RECORD not in _read:
        _read[RECORD] = json.loads(RECORD.read_text())
    return _read[RECORD]


def stale() -> str:
    """Why the ahead-of-time module cannot be used ('' when it can): not built, built for another Python, numpy or
    CPU, or a source changed since."""
    try:
        record = json.loads(RECORD.read_text())
        if not isinstance(record.get("exports"), dict):
            raise ValueError("no argument specs")
    except (OSError, ValueError):
        return "the ahead-of-time module is not built (make setup, or python -m converters.build_kernels)"
    if record.get("python") != sys.implementation.cache_tag:
        return f"the ahead-of-time module was built for {record.get('python')}, not {sys.implementation.cache_tag}"
    import numpy
    if record.get("numpy") != numpy.__version__:
        return f"the ahead-of-time module was built against numpy {record.get('numpy')}, not {numpy.__version__}"
    if record.get("cpu") != cpu_signature():
        return "the ahead-of-time module was built for another CPU (its instruction set may not run here)"
    stats = record.get("stats", {})
    for relative, recorded in record.get("sources", {}).items():
        try:
            if file_stat(HERE / relative) != stats.get(relative) and digest(HERE / relative) != recorded:
                return f"{relative} changed since the ahead-of-time build"      # (same size and time: unchanged)
        except OSError:
            return f"{relative} is missing since the ahead-of-time build"
    if not record.get("sources"):
        return "the ahead-of-time record lists no sources"
    return ""


def cpu_signature() -> str:
    """What the ahead-of-time code was compiled for (this CPU's model and instruction-set flags, hashed): the
    module is built for the host CPU, and a directory shared with another machine must not run it there."""
    text = os.uname().machine if hasattr(os, "uname") else sys.platform
    try:
        with open("/proc/cpuinfo", encoding="ascii", errors="replace") as info:
            for line in info:
                if line.startswith(("model name", "flags", "Features", "CPU part")):
                    text += line
                elif not line.strip() and ("flags" in text or "Features" in text):
                    break                                      # the first processor's block is enough
    except OSError:
        pass
    return hashlib.sha256(text.encode()).hexdigest()[:16]


_DTYPES = {"f8": "float64", "i4": "int32", "i8": "int64"}


def _parsed(specs: Sequence[str]) -> tuple:
    """(numpy dtype or scalar code, ndim) per argument spec (``f8:2``: a float64 array of 2 dimensions)."""
    import numpy as np
    out = []
    for spec in specs:
        code, _, ndim = spec.partition(":")
        out.append((np.dtype(_DTYPES[code]), int(ndim)) if ndim else (code, 0))
    return tuple(out)


def conforms(specs: Sequence[Any], args: Sequence[Any]) -> bool:
    """True when ``args`` are exactly what the ahead-of-time export takes (``specs`` from its record, or parsed
    by :func:`_parsed`): numpy's ndarray of that dtype and ndim, C-contiguous, or a Python float / int / bool.
    numba.pycc's wrappers check only that an array is an ndarray: anything else would be read wrongly."""
    import numpy as np
    if len(specs) != len(args):
        return False
    for (kind, ndim), arg in zip(specs if specs and isinstance(specs[0], tuple) else _parsed(specs), args):
        if ndim:
            if not (arg.__class__ is np.ndarray and arg.dtype == kind and arg.ndim == ndim
                    and arg.flags.c_contiguous):
                return False
        elif kind == "f8":
            if not isinstance(arg, (float, np.floating)):
                return False
        elif kind == "b1":
            if not isinstance(arg, (bool, np.bool_)):
                return False
        elif not isinstance(arg, (int, np.integer)) or isinstance(arg, bool):
            return False
    return True


def _checked(name: str, function: Callable[..., Any], specs: Sequence[str]) -> Callable[..., Any]:
    """The export behind a check of its arguments (:func:`conforms`); arguments of any other kind go to numba's
    JIT of the same function, which compiles a version for them."""
    parsed = _parsed(specs)

    def call(*args: Any) -> Any:
        if conforms(parsed, args):
            return function(*args)
        return _jit(name)(*args)
    call.__name__ = call.__qualname__ = name
    call.__doc__ = f"{name} from the ahead-of-time module (arguments checked: {', '.join(specs)})"
    return call


def _run_steps_by_size(module: ModuleType) -> Callable[..., tuple[int, int]]:
    """run_steps with numba's signature: the ahead-of-time module has one export per register size."""
    by_size = {n: getattr(module, f"run_steps_r{n}") for n in range(1, MAX_REGISTER_STATES + 1)}
    rows = module.run_steps_rows

    specs = _parsed(_record()["exports"]["run_steps_rows"])

    def run_steps(which: npt.NDArray[np.int32], Phi: npt.NDArray[np.float64], Gamma: npt.NDArray[np.float64],
                  H: npt.NDArray[np.float64], C: npt.NDArray[np.float64], F: npt.NDArray[np.float64],
                  M: npt.NDArray[np.float64], Phi_b: npt.NDArray[np.float64], Gamma_b: npt.NDArray[np.float64],
                  CPhi: npt.NDArray[np.float64], q0: npt.NDArray[np.float64], x: npt.NDArray[np.float64],
                  u: npt.NDArray[np.float64], y: npt.NDArray[np.float64], start: int, inline: bool, period: int,
                  state: tuple[float, ...] | None) -> tuple[int, int]:
        args = (which, Phi, Gamma, H, C, F, M, Phi_b, Gamma_b, CPhi, q0, x, u, y, start, inline, period)
        if not conforms(specs, args) or not (state is None or len(state) in by_size):
            return _jit("run_steps")(*args, state)
        return (rows if state is None else by_size[len(state)])(*args)
    return run_steps
