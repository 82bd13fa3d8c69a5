"""The local backend: a function mapped over items in this machine's processes, results in input order.

Workers are forked (nothing is re-imported; compiled kernels loaded before the fork are shared) and get
whole chunks of items, so a cheap item does not pay a round trip of its own. ``workers=1`` runs in this
process, and gives the same results: chunks are fixed by ``chunk``, not by the number of workers.
"""
from __future__ import annotations

import concurrent.futures as futures
import multiprocessing
import os
import sys

from ..errors import ParameterError


def default_workers() -> int:
    """The processes this one may use (its CPU affinity), at least 1."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:                                  # not on Linux
        return max(1, os.cpu_count() or 1)


def _run_chunk(args):
    function, chunk, finalize = args
    try:
        return [function(item) for item in chunk]
    finally:
        if finalize is not None:
            finalize()


def parallel_map(function, items, *, workers: int | None = None, chunk: int = 1, progress: bool = False,
                 label: str = "", unit: str = "pt", finalize=None) -> list:
    """[function(item) for item in items], in processes.

    Parameters
    ----------
    function : picklable callable
        Applied to each item (a module-level function or a picklable object).
    workers : int, optional
        Processes to use (default: :func:`default_workers`); 1 runs here.
    chunk : int
        Items per task.
    progress : bool
        A tqdm progress bar on stderr, in items.
    finalize : callable, optional
        Called in a worker process after each of its chunks (e.g. to shut the worker's own sub-process
        down before the pool ends it); not called when the map runs in this process.
    """
    items = list(items)
    workers = default_workers() if workers is None else workers
    if not (isinstance(workers, int) and workers >= 1):
        raise ParameterError(f"workers must be an integer >= 1; got {workers!r}")
    if not (isinstance(chunk, int) and chunk >= 1):
        raise ParameterError(f"chunk must be an integer >= 1; got {chunk!r}")
    chunks = [items[i:i + chunk] for i in range(0, len(items), chunk)]
    from tqdm import tqdm
    out: list = []
    with tqdm(total=len(items), desc=label, unit=unit, file=sys.stderr, disable=not progress) as bar:
        if workers == 1 or len(chunks) <= 1:
            for c in chunks:
                out.extend(_run_chunk((function, c, None)))
                bar.update(len(c))
            return out
        method = "fork" if "fork" in multiprocessing.get_all_start_methods() else "spawn"
        with futures.ProcessPoolExecutor(max_workers=min(workers, len(chunks)),
                                         mp_context=multiprocessing.get_context(method)) as pool:
            for result in pool.map(_run_chunk, [(function, c, finalize) for c in chunks]):
                out.extend(result)
                bar.update(len(result))
    return out


__all__ = ["parallel_map", "default_workers"]
