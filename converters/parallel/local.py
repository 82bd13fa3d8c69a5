"""The local backend: chunks of work in this machine's processes, surviving a lost worker.

Each worker is a :class:`ProcessSlot`, one forked process that runs one chunk at a time (nothing is
re-imported; compiled kernels loaded before the fork are shared). One chunk per process at a time means
the backend knows which chunk a dead or hung process was running: that chunk alone is retried (a crash) or
given up (a time limit), the others go on. A chunk the backend cannot complete comes back as :class:`Lost`
with the reason, for the caller to record (a sweep stores it as failed rows).

``parallel_map`` is the ordered ``[function(item) ...]`` over this backend that the D-K maps, the brute-force
diagrams, the report suites and the stability map use; the ngspice runner is one recycled ProcessSlot.
"""
from __future__ import annotations

import concurrent.futures as futures
import multiprocessing
import os
import sys
import time
from collections.abc import Callable, Generator, Iterable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, TypeVar

from ..errors import ParameterError, TimeLimitReached
from ..limits import TIME_RANGE
from ..validate import check_integer, check_range

if TYPE_CHECKING:
    from multiprocessing.context import BaseContext

_T = TypeVar("_T")

#: Most worker processes a backend starts: each holds a Python with numpy and the kernels (~50-100 MB).
MAX_WORKERS = 64
#: Longest time a chunk may be given (seconds): the longest time limit of a run.
MAX_TIMEOUT = TIME_RANGE[1]


def default_workers() -> int:
    """The processes this one may use (its CPU affinity), at least 1."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:                                  # not on Linux
        return max(1, os.cpu_count() or 1)


def _worker_init(parent: int) -> None:
    """A worker leaves SIGINT to its parent (a Ctrl-C reaches the whole process group: the parent stops the
    workers itself, without a traceback from each), dies at SIGTERM whatever handler it inherited, and ends
    itself when its parent is gone (killed with SIGKILL, nothing left to stop it): no orphan runs on.

    The watch is a thread polling the parent's pid, not ``PR_SET_PDEATHSIG`` (which fires when the *thread*
    that forked ends, and pools fork from whichever thread submits)."""
    import signal
    import threading
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)

    def watch() -> None:
        while os.getppid() == parent:
            time.sleep(_PARENT_POLL_S)
        os._exit(1)
    threading.Thread(target=watch, name="parent-watch", daemon=True).start()


_PARENT_POLL_S = 0.2
#: Seconds a discarded pool's manager thread is given to wind down (it only notices its dead worker).
MANAGER_JOIN_S = 5.0


def _context() -> BaseContext:
    # fork: the worker needs nothing re-imported (works from scripts, stdin and notebooks alike)
    return multiprocessing.get_context("fork" if "fork" in multiprocessing.get_all_start_methods() else "spawn")


@dataclass(frozen=True)
class Lost:
    """A chunk the backend could not complete, and why (``exception``: what the function raised, if it did)."""

    message: str
    exception: BaseException | None = None


class ProcessSlot:
    """One worker process, created on first use: submit a call, wait for it with a time limit, terminate it
    when it hangs; recycled (a fresh process) after ``tasks_per_process`` calls, which returns what a
    leaky library (PySpice) accumulated to the system. Safe across fork: a child never touches the
    parent's process."""

    def __init__(self, tasks_per_process: int | None = None) -> None:
        self.tasks_per_process = tasks_per_process
        self._pool: futures.ProcessPoolExecutor | None = None
        self._tasks = 0
        self._owner = os.getpid()

    def _forget_inherited(self) -> None:
        # in a forked child the parent's pool object is a copy whose process belongs to the parent: shutting it
        # down here would send the parent's worker its exit sentinel. Forget it instead.
        if self._owner != os.getpid():
            self._pool, self._tasks, self._owner = None, 0, os.getpid()

    def submit(self, function: Callable[..., _T], *args: Any) -> futures.Future[_T]:
        self._forget_inherited()
        if self._pool is not None and self.tasks_per_process is not None and self._tasks >= self.tasks_per_process:
            self.close()
        if self._pool is None:
            self._pool = futures.ProcessPoolExecutor(max_workers=1, mp_context=_context(),
                                                     initializer=_worker_init, initargs=(os.getpid(),))
            self._tasks = 0
        self._tasks += 1
        return self._pool.submit(function, *args)

    def call(self, function: Callable[..., _T], *args: Any, timeout: float | None = None,
             watch: Callable[[float], None] | None = None, every: float = 5.0) -> _T:
        """``function(*args)`` in the process. Raises ``concurrent.futures.TimeoutError`` (the process is then
        terminated) or ``concurrent.futures.process.BrokenProcessPool`` (it died; the next call gets a new one).
        ``watch(elapsed s)``, called every ``every`` s while the call runs, may raise to end it (the process is
        then terminated and its error raised)."""
        start = time.monotonic()
        try:
            future = self.submit(function, *args)
            while True:
                left = None if timeout is None else timeout - (time.monotonic() - start)
                wait = left if watch is None else (every if left is None else min(every, left))
                try:
                    return future.result(timeout=None if wait is None else max(wait, 0.0))
                except futures.TimeoutError:
                    if watch is None or (left is not None and left <= every):
                        raise
                try:
                    watch(time.monotonic() - start)
                except Exception:                       # the watch ends the call
                    self.kill()
                    raise
        except futures.TimeoutError:
            self.kill()
            raise
        except futures.process.BrokenProcessPool:
            self.discard()
            raise
        except (KeyboardInterrupt, TimeLimitReached):   # Ctrl-C, --time-limit: end the process now (close() at
            self.kill()                                 # exit would wait for its run)
            raise

    def kill(self) -> None:
        """Terminate the process (close() would wait for a hung one)."""
        self._forget_inherited()
        if self._pool is not None:
            for process in list((getattr(self._pool, "_processes", None) or {}).values()):
                process.terminate()
            self.discard()

    def discard(self) -> None:
        if self._pool is not None:
            manager = getattr(self._pool, "_executor_manager_thread", None)
            self._pool.shutdown(wait=False, cancel_futures=True)
            self._pool = None
            # CPython 3.11's exit hook wakes every pool's manager thread through a pipe that a manager still
            # handling its dead worker may be closing at that moment ("Bad file descriptor" traceback at exit,
            # fixed in 3.12 with a lock): let the manager finish first (bounded: a stuck one is left behind).
            if manager is not None and manager.is_alive():
                manager.join(MANAGER_JOIN_S)

    def close(self) -> None:
        self._forget_inherited()
        if self._pool is not None:
            self._pool.shutdown(wait=True, cancel_futures=True)
            self._pool = None


class _Call:
    """``function(chunk)`` in a worker, then ``finalize()`` (e.g. shut the worker's own ngspice process down
    before the slot's process ends)."""

    def __init__(self, function: Callable[[Any], Any], finalize: Callable[[], object] | None = None) -> None:
        self.function, self.finalize = function, finalize

    def __call__(self, chunk: Any) -> Any:
        try:
            return self.function(chunk)
        finally:
            if self.finalize is not None:
                self.finalize()


class LocalBackend:
    """Chunks in ``workers`` processes of this machine.

    Parameters
    ----------
    workers : int, optional
        Processes (default :func:`default_workers`); 1 still runs in a separate process.
    timeout : float, optional
        Seconds a chunk may run; past it its process is terminated and the chunk is lost (not retried).
    attempts : int
        Runs a chunk gets when its process dies under it (a crash, an out-of-memory kill) before it is lost.
    tasks_per_process : int, optional
        A fresh process after this many chunks (1: every chunk in its own process).
    finalize : callable, optional
        Called in the worker after each chunk.
    """

    name = "local"

    def __init__(self, workers: int | None = None, *, timeout: float | None = None, attempts: int = 3,
                 tasks_per_process: int | None = None, finalize: Callable[[], object] | None = None) -> None:
        workers = min(default_workers(), MAX_WORKERS) if workers is None else check_integer("workers", workers, 1,
                                                                                             MAX_WORKERS)
        if timeout is not None:
            timeout = check_range("timeout (seconds)", timeout, 0.0, MAX_TIMEOUT, low_open=True)
        attempts = check_integer("attempts", attempts, 1, 100)
        if tasks_per_process is not None:
            tasks_per_process = check_integer("tasks_per_process", tasks_per_process, 1)
        if finalize is not None and not callable(finalize):
            raise ParameterError(f"finalize must be callable or None; got {finalize!r}")
        self.workers, self.timeout, self.attempts = workers, timeout, attempts
        self.tasks_per_process, self.finalize = tasks_per_process, finalize

    def map_chunks(self, function: Callable[[Any], Any],
                   chunks: Iterable[Any]) -> Generator[tuple[int, Any], None, None]:
        """Yield (position, result or :class:`Lost`) for each chunk, as they complete."""
        chunks = list(chunks)
        call = _Call(function, self.finalize)
        check_picklable(call)
        queue = list(range(len(chunks)))[::-1]              # popped from the end: in order
        tries = [0] * len(chunks)
        slots = [ProcessSlot(self.tasks_per_process) for _ in range(min(self.workers, len(chunks)))]
        running: dict = {}                                  # future -> (position, slot, started)
        idle = list(slots)
        try:
            while queue or running:
                while queue and idle:
                    position, slot = queue.pop(), idle.pop()
                    tries[position] += 1
                    running[slot.submit(call, chunks[position])] = (position, slot, time.monotonic())
                wait = None
                if self.timeout is not None:
                    wait = max(0.0, min(started + self.timeout for _, _, started in running.values()) - time.monotonic())
                done, _ = futures.wait(running, timeout=wait, return_when=futures.FIRST_COMPLETED)
                for future in done:
                    position, slot, _ = running.pop(future)
                    idle.append(slot)
                    try:
                        yield position, future.result()
                    except futures.process.BrokenProcessPool:
                        slot.discard()
                        if tries[position] < self.attempts:
                            queue.append(position)
                        else:
                            yield position, Lost(f"worker lost: its process died {tries[position]} times running this chunk")
                    except Exception as exc:                # the function raised: the caller decides
                        yield position, Lost(f"{type(exc).__name__}: {exc}", exc)
                if self.timeout is not None:
                    now = time.monotonic()
                    for future, (position, slot, started) in list(running.items()):
                        if not future.done() and now - started >= self.timeout:
                            del running[future]
                            slot.kill()
                            idle.append(slot)
                            yield position, Lost(f"timeout: did not finish within {self.timeout:g} s")
        finally:
            for slot in slots:                              # interrupted or done: no process outlives the map
                if any(s is slot for _, s, _ in running.values()):
                    slot.kill()
                else:
                    slot.close()


def check_picklable(function: object) -> None:
    """Refuse up front a function that cannot reach a worker process (a lambda, a function defined inside
    another): each chunk would otherwise come back lost with pickle's words."""
    import pickle
    try:
        pickle.dumps(function)
    except (pickle.PicklingError, AttributeError, TypeError) as exc:
        raise ParameterError(f"function must be picklable to run in worker processes (a module-level function or a "
                             f"picklable object; a lambda or a nested function is not), or use workers=1; "
                             f"{type(exc).__name__}: {exc}") from None


def parallel_map(function: Callable[[Any], Any], items: Iterable[Any], *, workers: int | None = None, chunk: int = 1,
                 progress: bool = False, label: str = "", unit: str = "pt",
                 finalize: Callable[[], object] | None = None, timeout: float | None = None,
                 tasks_per_process: int | None = None, attempts: int = 3,
                 on_lost: Callable[[Any, str], Any] | None = None) -> list:
    """[function(item) for item in items] on the local backend, in input order.

    Parameters
    ----------
    function : picklable callable
        Applied to each item (a module-level function or a picklable object).
    workers : int, optional
        Processes (default :func:`default_workers`); 1 runs in this process (no time limit, no isolation),
        with the same results: chunks are fixed by ``chunk``, not by the number of workers.
    chunk : int
        Items per task.
    progress : bool
        A tqdm progress bar on stderr, in items.
    finalize, timeout, tasks_per_process, attempts
        As :class:`LocalBackend`.
    on_lost : callable, optional
        ``on_lost(item, message)`` stands in for each item of a chunk that was lost (a dead worker: the
        message starts ``worker lost``; a time limit: ``timeout``; an exception: its type and text);
        without it a lost chunk raises.
    """
    if not callable(function):
        raise ParameterError(f"function must be callable; got {function!r}")
    items = list(items)
    chunk = check_integer("chunk", chunk, 1)
    chunks = [items[i:i + chunk] for i in range(0, len(items), chunk)]
    backend = LocalBackend(workers, timeout=timeout, attempts=attempts, tasks_per_process=tasks_per_process,
                           finalize=finalize)
    from tqdm import tqdm
    results: list = [None] * len(chunks)
    with tqdm(total=len(items), desc=label, unit=unit, file=sys.stderr, disable=not progress) as bar:
        if backend.workers == 1 and timeout is None and tasks_per_process is None:
            stream = ((i, _in_process(_Apply(function), c)) for i, c in enumerate(chunks))
        else:
            stream = backend.map_chunks(_Apply(function), chunks)
        for position, result in stream:
            if isinstance(result, Lost):
                if on_lost is None:
                    if result.exception is not None:
                        raise result.exception
                    raise RuntimeError(f"{label or 'parallel_map'}: {result.message}")
                result = [on_lost(item, result.message) for item in chunks[position]]
            results[position] = result
            bar.update(len(result))
    return [r for chunk_results in results for r in chunk_results]


def _in_process(function: Callable[[Any], Any], chunk: Any) -> Any:
    try:
        return function(chunk)
    except Exception as exc:                                # as a worker's exception comes back
        return Lost(f"{type(exc).__name__}: {exc}", exc)


class _Apply:
    def __init__(self, function: Callable[[Any], Any]) -> None:
        self.function = function

    def __call__(self, chunk: Iterable[Any]) -> list[Any]:
        return [self.function(item) for item in chunk]


__all__ = ["parallel_map", "default_workers", "LocalBackend", "ProcessSlot", "Lost", "MAX_WORKERS", "check_picklable"]
