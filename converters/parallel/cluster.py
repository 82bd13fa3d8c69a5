"""The Dask backend: chunks on an existing Dask distributed cluster (``tcp://HOST:PORT`` or a
``dask.distributed.Client``), for when one machine is not enough.

Dask itself recovers a lost worker: the scheduler reruns the chunks that worker held on another one; a chunk
that takes ``distributed.scheduler.allowed-failures`` workers down with it comes back as :class:`.Lost`.
At most ``in_flight`` chunks per worker thread are submitted at a time, so a long sweep never queues all its
work (nor its results) at once. The workers import this package themselves: it must be installed where
they run.
"""
from __future__ import annotations

from collections.abc import Callable, Generator, Iterable
from typing import TYPE_CHECKING, Any

from ..errors import ParameterError
from .local import Lost

if TYPE_CHECKING:
    from distributed import Client

#: Seconds to reach a scheduler and hear its handshake (or --time-limit when shorter). Dask's own connect bounds
#: the TCP connection only: a server that accepts and never answers held the client's first read forever.
CONNECT_TIMEOUT_S = 10.0


class DaskBackend:
    """Chunks on a Dask distributed cluster.

    Parameters
    ----------
    scheduler : str or dask.distributed.Client
        The scheduler's address (``tcp://HOST:PORT``) or a client already connected.
    in_flight : int
        Chunks submitted per worker thread ahead of their results.
    """

    name = "dask"

    def __init__(self, scheduler: str | Client, *, in_flight: int = 2) -> None:
        if isinstance(scheduler, str) and not scheduler.startswith(("tcp://", "tls://", "inproc://", "ws://", "wss://")):
            raise ParameterError(f"scheduler must be local or a Dask scheduler address like tcp://HOST:PORT; "
                                 f"got {scheduler!r}")
        if not (isinstance(in_flight, int) and in_flight >= 1):
            raise ParameterError(f"in_flight must be an integer >= 1; got {in_flight!r}")
        self.scheduler, self.in_flight = scheduler, in_flight
        self._client: Client | None = None

    def client(self) -> Client:
        try:
            from distributed import Client
        except ImportError:
            raise ParameterError("a Dask scheduler needs dask.distributed: pip install 'dask[distributed]'") from None
        if isinstance(self.scheduler, Client):
            return self.scheduler
        if self._client is None:
            timeout = _connect_timeout()
            _handshake(self.scheduler, timeout)
            try:
                self._client = Client(self.scheduler, timeout=f"{timeout}s")
            except OSError as exc:
                raise ParameterError(f"scheduler: no Dask scheduler answers at {self.scheduler} ({exc})") from None
            except Exception as exc:    # something else answers there (an HTTP server: its bytes read as frame sizes)
                raise ParameterError(f"scheduler: what answers at {self.scheduler} is not a Dask scheduler "
                                     f"({type(exc).__name__}: {str(exc)[:120]})") from None
        return self._client

    def close(self) -> None:
        if self._client is not None:
            self._client.close()
            self._client = None

    def map_chunks(self, function: Callable[[Any], Any],
                   chunks: Iterable[Any]) -> Generator[tuple[int, Any], None, None]:
        """Yield (position, result or :class:`.Lost`) for each chunk, as they complete."""
        from distributed import as_completed
        client = self.client()
        chunks = list(chunks)
        threads = max(1, sum(client.nthreads().values()))
        queue = list(range(len(chunks)))[::-1]
        pending: dict[Any, int] = {}                      # future -> position
        stream = as_completed()
        try:
            def top_up() -> None:
                while queue and len(pending) < self.in_flight * threads:
                    position = queue.pop()
                    future = client.submit(function, chunks[position], pure=False)
                    pending[future] = position
                    stream.add(future)
            top_up()
            for future in stream:
                position = pending.pop(future)
                if future.status == "finished":
                    yield position, future.result()
                else:
                    exc = future.exception()
                    name = type(exc).__name__
                    message = (f"worker lost: {exc}" if name == "KilledWorker" else f"{name}: {exc}")
                    yield position, Lost(message, exc if name != "KilledWorker" else None)
                future.release()
                top_up()
        finally:
            for future in pending:                           # interrupted: nothing keeps running for us
                future.cancel()


def _connect_timeout() -> float:
    from ..limits import time_limit
    return min(CONNECT_TIMEOUT_S, time_limit(CONNECT_TIMEOUT_S))


def _handshake(address: str, timeout: float) -> None:
    """Reach ``address`` (tcp://HOST:PORT) and hear Dask's handshake within ``timeout`` s each, or refuse in one
    line. The probe runs in a thread of its own, whatever event loop the caller runs."""
    if not address.startswith("tcp://"):
        return
    import asyncio
    import socket
    from concurrent.futures import ThreadPoolExecutor

    from distributed.comm import connect
    from distributed.comm.addressing import parse_address, parse_host_port
    host, port = parse_host_port(parse_address(address)[1])
    try:                                # a refused port is said at once (Dask's connect retries it until timeout)
        socket.create_connection((host, port), timeout=timeout).close()
    except TimeoutError:
        raise ParameterError(f"scheduler: no Dask scheduler answered at {address} within {timeout:g} s (the connection "
                             "was not accepted); check the address") from None
    except OSError as exc:
        raise ParameterError(f"scheduler: no Dask scheduler answers at {address} ({exc.strerror or exc})") from None

    async def probe() -> None:
        comm = await connect(address, timeout=timeout)
        await comm.close()
    try:
        with ThreadPoolExecutor(1) as pool:
            pool.submit(asyncio.run, asyncio.wait_for(probe(), timeout)).result()
    except TimeoutError:
        raise ParameterError(f"scheduler: no Dask scheduler answered at {address} within {timeout:g} s (the connection "
                             "is accepted, the handshake never answered); check the address") from None
    except OSError as exc:
        raise ParameterError(f"scheduler: no Dask scheduler answers at {address} ({exc})") from None
    except Exception as exc:        # something else answers there (an HTTP server: its bytes read as frame sizes)
        raise ParameterError(f"scheduler: what answers at {address} is not a Dask scheduler "
                             f"({type(exc).__name__}: {str(exc)[:120]})") from None


__all__ = ["DaskBackend"]
