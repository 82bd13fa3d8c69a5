"""Build the ahead-of-time module of the compiled kernels (:mod:`converters.compiled` says why and how it is
used): ``python -m converters.build_kernels`` (``make setup`` runs it) compiles, with numba.pycc, the functions
of :data:`converters.compiled.KERNELS` for this machine's CPU into ``converters/_kernels`` and records the
SHA-256 of every source they were compiled from in ``converters/_kernels.json``. ``--check``: only say whether
the module is current; ``--force``: rebuild a current one."""
from __future__ import annotations

import json
import os
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

from .compiled import (HERE, MAX_REGISTER_STATES, MODULE, RECORD, cpu_signature, digest,
                       file_stat, register_state, stale)

if TYPE_CHECKING:
    from collections.abc import Callable

    import numpy as np
    import numpy.typing as npt
    from numba.core.types import Array as NumbaArray
    from numba.core.types import Type as NumbaType
    from numba.core.typing.templates import Signature

    FloatArray = npt.NDArray[np.float64]

def _exports() -> list[tuple[str, Signature, Callable[..., Any]]]:
    """(exported name, numba signature, Python function) of every function the module holds."""
    from numba import types as T

    from .analysis.newton_kernel import newton_advance, newton_step
    from .lcp import dispatch, engine
    from .methods import theta_kernels as K

    def a(ndim: int, dtype: NumbaType = T.float64) -> NumbaArray:
        return T.Array(dtype, ndim, "C")

    run_args = (a(1, T.int32), a(3), a(2), a(3), a(3), a(2), a(3), a(4), a(3), a(3), a(2), a(2), a(2), a(2),
                T.int64, T.boolean, T.int64)

    def run_steps_with(state: tuple[float, ...] | None) -> Callable[..., Any]:
        def run(which: npt.NDArray[np.int32], Phi: FloatArray, Gamma: FloatArray, H: FloatArray, C: FloatArray,
                F: FloatArray, M: FloatArray, Phi_b: FloatArray, Gamma_b: FloatArray, CPhi: FloatArray, q0: FloatArray,
                x: FloatArray, u: FloatArray, y: FloatArray, start: int, inline: bool,
                period: int) -> tuple[int, int]:
            return K.run_steps(which, Phi, Gamma, H, C, F, M, Phi_b, Gamma_b, CPhi, q0, x, u, y, start, inline,
                               period, state)
        return run

    out = [(f"run_steps_r{n}", T.UniTuple(T.int64, 2)(*run_args), run_steps_with(register_state(n)))
           for n in range(1, MAX_REGISTER_STATES + 1)]
    out.append(("run_steps_rows", T.UniTuple(T.int64, 2)(*run_args), run_steps_with(None)))
    out.append(("set_matrices", T.boolean(a(3), a(3), a(3), a(3), a(2), a(2), a(1), T.float64, a(1, T.int32), a(3),
                                          a(2), a(3), a(3), a(4), a(3), a(3), a(2)), K.set_matrices.py_func))
    out.append(("step_jacobian", T.none(a(1, T.int32), a(2), a(4), a(3), a(3), a(3), a(2)), K.step_jacobian.py_func))
    out.append(("newton_step", T.Tuple((T.float64, T.float64, T.float64, T.int64))(a(1), a(1), a(2), T.float64,
                                                                                    a(1), a(2), T.float64, T.int64,
                                                                                    T.int64),
                newton_step.py_func))
    out.append(("newton_advance", T.int64(a(1), a(1), a(2), a(1), a(2), a(1), a(1), a(2), T.boolean, a(1, T.int64),
                                          a(1), T.float64, T.int64), newton_advance.py_func))
    out.append(("solve_many", T.none(a(3), a(2), a(2), a(2), T.int64, T.float64, T.int64, T.boolean, a(1), T.int64,
                                     a(1, T.int64), a(1, T.int64), a(1), a(1, T.int64), a(1, T.int64), a(1, T.int64),
                                     a(1)), engine.solve_many.py_func))
    out.append(("solve_once", T.Tuple((T.int64, T.int64, T.float64, T.int64, T.int64, T.int64, T.float64))(
        a(2), a(1), a(1), a(1), T.int64, T.float64, T.int64, T.boolean, a(1), T.int64), engine.solve_once.py_func))
    out.append(("lcp_default_options", a(1)(), dispatch.default_options.py_func))
    return out


def _sources() -> dict:
    """The files the kernels are compiled from, with their digests: the modules with compiled code and the modules
    whose constants they read (:data:`converters.kernel_cache.SOURCES`, the list numba's own cache is kept by:
    ``tests/test_kernel_cache.py`` checks that every name a compiled function reads is defined there) and this
    file (the exports and their signatures). Any of them changing makes the module stale; an edit anywhere else
    in the package (``errors.py``, ``trajectory.py``) leaves it in use."""
    from .kernel_cache import SOURCES
    return {relative: digest(HERE / relative) for relative in sorted(SOURCES + ("build_kernels.py",))}


def _argument(numba_type: NumbaType) -> str:
    """An argument's spec as :func:`converters.compiled.conforms` reads it: ``f8:2`` (a C-contiguous float64
    array of 2 dimensions), ``i4:1``, or a scalar: ``f8``, ``i8``, ``b1``."""
    from numba import types as T
    codes = {T.float64: "f8", T.int32: "i4", T.int64: "i8", T.boolean: "b1"}
    if isinstance(numba_type, T.Array):
        assert numba_type.layout == "C", numba_type
        return f"{codes[numba_type.dtype]}:{numba_type.ndim}"
    return codes[numba_type]  # type: ignore[index]  # numba's stubs key the dict by its scalar types


def build() -> str:
    """Compile :func:`_exports` into ``converters/_kernels`` and record its sources; returns a one-line summary.
    Written to a temporary directory and moved into place (the record last), so an interrupted build leaves
    the previous module, or none, never a half-written one."""
    import tempfile
    import time
    import warnings
    start = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")            # numba.pycc's pending deprecation (module docstring)
        from numba.pycc import CC
        exports = _exports()
        sources = _sources()
        with tempfile.TemporaryDirectory(prefix=".kernels-build.", dir=HERE) as tmp:
            cc = CC(MODULE)
            cc.output_dir = tmp
            cc.target_cpu = "host"
            cc.verbose = False
            for name, signature, function in exports:
                cc.export(name, signature)(function)
            cc.compile()
            built = [p for p in Path(tmp).iterdir() if p.name.startswith(MODULE + ".") and p.suffix in (".so", ".pyd")]
            if len(built) != 1:
                raise RuntimeError(f"numba.pycc wrote {sorted(p.name for p in Path(tmp).iterdir())}")
            import numpy
            record = {"python": sys.implementation.cache_tag, "numpy": numpy.__version__, "cpu": cpu_signature(),
                      "sources": sources,
                      "stats": {relative: file_stat(HERE / relative) for relative in sources},
                      "exports": {name: [_argument(t) for t in signature.args] for name, signature, _ in exports}}
            RECORD.unlink(missing_ok=True)         # stale from here until the new record lands
            os.replace(built[0], HERE / built[0].name)
            (Path(tmp) / "record").write_text(json.dumps(record, indent=1) + "\n")
            os.replace(Path(tmp) / "record", RECORD)
    return (f"converters/{built[0].name}: {len(exports)} kernels compiled ahead of time from "
            f"{len(record['sources'])} sources in {time.perf_counter() - start:.0f} s")


def main(argv: list[str] | None = None) -> int:
    """``python -m converters.build_kernels [--check] [--force]``: build the module when it is missing or stale (``--check``:
    only say whether it is current)."""
    args = sys.argv[1:] if argv is None else argv
    unknown = [a for a in args if a not in ("--check", "--force")]
    if unknown:
        print(f"build_kernels: unknown argument {unknown[0]!r}; the arguments are --check and --force", file=sys.stderr)
        return 2
    why = stale()
    if "--check" in args:
        print(f"ahead-of-time kernels: {why or 'current'}")
        return 1 if why else 0
    if not why and "--force" not in args:
        print("ahead-of-time kernels: current")
        return 0
    try:
        print(build())
    except Exception as exc:                       # noqa: BLE001 (no compiler, headers, ...: the JIT still works)
        print(f"ahead-of-time kernels not built ({type(exc).__name__}: {' '.join(str(exc).split())[:300]}); "
              "numba compiles them on first use instead", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
