"""Run an ensemble over parameter points on a backend, streaming rows chunk by chunk.

An *ensemble* is a picklable object with ``row(index, point) -> dict`` (one point, the serial path),
``rows(items) -> list[dict]`` (a chunk of (index, point) items, batched where it can be),
``failed(index, point, message) -> dict`` (the row of a point that gave no result) and ``chunk_hint``
(points per chunk). :class:`~converters.sweeps.ensemble.ModelSweep` is the converters' ensemble.

Backends: ``serial`` (``row`` per point, here), ``batched`` (``rows`` per chunk, here), ``local``
(:class:`.local.LocalBackend`, the default) or a Dask cluster (:class:`.cluster.DaskBackend`: an address
``tcp://HOST:PORT`` or a ``dask.distributed.Client``). A chunk travels as its point indices and is turned
into points where it runs, so memory holds the chunks in flight, never the whole sweep; a chunk a backend
loses (a dead worker, a time limit) comes back as failed rows. Every backend gives the same rows.
"""
from __future__ import annotations

import re
import sys
from collections.abc import Callable, Generator, Iterable
from typing import Any, Protocol

import numpy as np
import numpy.typing as npt

from ..errors import ParameterError
from .local import LocalBackend, Lost

BACKENDS = ("serial", "batched", "local")


class Ensemble(Protocol):
    """What :func:`run_ensemble` runs (module docstring)."""

    @property
    def chunk_hint(self) -> int: ...

    def row(self, index: int, point: dict) -> dict: ...

    def rows(self, items: list[tuple[int, dict]]) -> list[dict]: ...

    def failed(self, index: int, point: dict, message: str) -> dict: ...


class Points(Protocol):
    """Parameter points addressed by index (:mod:`converters.sweeps.points`)."""

    @property
    def size(self) -> int: ...

    def points(self, indices: npt.ArrayLike) -> list[tuple[int, dict]]: ...


class Backend(Protocol):
    """Where chunks run: (position, result or :class:`.local.Lost`) for each chunk, as they complete."""

    def map_chunks(self, function: Callable[[Any], Any],
                   chunks: Iterable[Any]) -> Generator[tuple[int, Any], None, None]: ...


def backend_for(spec: Any = "local", *, workers: int | None = None) -> str | Backend:
    """A backend from its name (serial, batched, local), a Dask address (tcp://...), a Dask Client, or a
    backend object (returned as is)."""
    if hasattr(spec, "map_chunks") or spec in ("serial", "batched"):
        return spec
    if spec == "local":
        return LocalBackend(workers)
    if isinstance(spec, str) and "://" in spec:
        from .cluster import DaskBackend
        return DaskBackend(check_address(spec))
    if type(spec).__name__ == "Client":
        from .cluster import DaskBackend
        return DaskBackend(spec)
    raise ParameterError(f"scheduler must be one of {', '.join(BACKENDS)} or a Dask address tcp://HOST:PORT; "
                         f"got {spec!r}")


_ADDRESS = re.compile(r"tcp://(\[[0-9A-Fa-f:.]+\]|[A-Za-z0-9_.-]+):([0-9]{1,5})")


def check_address(spec: str) -> str:
    """A Dask scheduler address this process can reach as given: tcp://HOST:PORT, PORT in [1, 65535] (tls://
    needs a security context, which a plain address cannot carry: pass a dask.distributed Client instead)."""
    match = _ADDRESS.fullmatch(spec)
    if match is None or not 1 <= int(match.group(2)) <= 65535:
        raise ParameterError("scheduler must be a Dask address tcp://HOST:PORT with PORT in [1, 65535] (or one of "
                             f"{', '.join(BACKENDS)}; tls:// needs a dask.distributed Client with its security); "
                             f"got {spec!r}")
    return spec


class _Chunk:
    """The work of one chunk where it runs: its indices -> points -> rows."""

    def __init__(self, ensemble: Ensemble, points: Points, serial: bool = False) -> None:
        self.ensemble, self.points, self.serial = ensemble, points, serial

    def __call__(self, indices: npt.NDArray[np.int64]) -> list[dict]:
        items = self.points.points(indices)
        if self.serial:
            return [self.ensemble.row(i, point) for i, point in items]
        return self.ensemble.rows(items)


def run_ensemble(ensemble: Ensemble, points: Points, *, backend: Any = "local", indices: npt.ArrayLike | None = None,
                 chunk: int | None = None, on_rows: Callable[[list[dict]], object] | None = None,
                 progress: bool = False, label: str = "sweep", workers: int | None = None,
                 done: int = 0) -> list[dict] | int:
    """The ensemble's rows at ``points`` (a :class:`.points.Grid` or :class:`.points.LatinHypercube`).

    Parameters
    ----------
    backend : str, backend object or dask.distributed.Client
        Where the chunks run (module docstring).
    indices : array of int, optional
        The points to compute (default: all); a resumed sweep passes the missing ones.
    chunk : int, optional
        Points per chunk (default: the ensemble's ``chunk_hint``).
    on_rows : callable, optional
        ``on_rows(rows)`` for each finished chunk, as chunks finish (a writer streaming to disk); then
        nothing is kept here and the number of rows is returned. Without it: the rows, by index.
    progress : bool
        A tqdm progress bar on stderr, in points (``done``: points already computed, a resumed sweep's).
    """
    backend = backend_for(backend, workers=workers)
    if indices is None:
        indices = np.arange(points.size, dtype=np.int64)
    else:       # 0.7 would truncate to 0, 5 of a 3-point grid fail deep in numpy
        from ..validate import check_indices
        indices = check_indices("indices", indices, points.size)
    chunk = ensemble.chunk_hint if chunk is None else chunk      # 0 is refused, not replaced by the default
    if isinstance(chunk, bool) or not (isinstance(chunk, (int, np.integer)) and chunk >= 1):
        raise ParameterError(f"chunk must be an integer >= 1; got {chunk!r}")
    chunks = [indices[i:i + chunk] for i in range(0, indices.size, chunk)]
    kept: list = []
    count = 0
    from tqdm import tqdm
    with tqdm(total=int(indices.size) + done, initial=done, desc=label, unit="pt", file=sys.stderr, disable=not progress,
              smoothing=0.1) as bar:
        if backend in ("serial", "batched"):
            work = _Chunk(ensemble, points, serial=backend == "serial")
            stream = ((k, work(c)) for k, c in enumerate(chunks))
        else:
            stream = backend.map_chunks(_Chunk(ensemble, points), chunks)
        for position, rows in stream:
            if isinstance(rows, Lost):
                rows = [ensemble.failed(i, point, rows.message) for i, point in points.points(chunks[position])]
            count += len(rows)
            if on_rows is None:
                kept.extend(rows)
            else:
                on_rows(rows)
            bar.update(len(rows))
    if on_rows is not None:
        return count
    return sorted(kept, key=lambda row: row["index"])


__all__ = ["run_ensemble", "backend_for", "BACKENDS"]
