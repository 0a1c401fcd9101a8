"""Where the runs of a campaign are made: this process, local processes, or a Dask cluster.

Every engine takes the per-run function ``fn(campaign, seed, index) -> outcome`` (a
picklable top-level function: :func:`~lightcraft_opt.campaign.run.run_one`), the
campaign, the seed and the indices to make, and yields the outcomes as they finish, in
whatever order. What a run gives does not depend on the engine (campaign/run.py).

* :func:`serial`: in this process, in index order (tests, debugging).
* :func:`local_processes`: a ``ProcessPoolExecutor`` of "spawn" workers (no fork of a
  process holding CasADi's threads); the campaign is sent once to each worker.
* :func:`dask_cluster`: ``distributed.Client(address)``; the campaign is scattered once
  to every worker. Dask is imported here, on first use only: the rest of the library
  never needs it. The address is checked for its form first (:func:`scheduler_address`),
  then a plain TCP connection and Dask's handshake, under a deadline, tell whether a
  scheduler answers there, so a bad or unreachable address fails in seconds; a client
  that failed to connect is closed before the error is raised (nothing is left to time
  out at exit).

Local workers die with the process that started them: on Linux the kernel sends them
SIGTERM when it exits (``PR_SET_PDEATHSIG``), and on POSIX systems a watchdog thread in
each worker ends it within :data:`ORPHAN_POLL` seconds of its parent's death (its parent pid
changes); a worker started after its parent died exits in its initializer. The
multiprocessing resource tracker then exits too (its pipe closes with the last worker). A
SIGKILLed campaign leaves no worker flying runs nobody will record.
"""

from __future__ import annotations

import asyncio
import contextlib
import ctypes
import json
import multiprocessing
import os
import signal
import socket
import sys
import threading
import time
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import (
    FIRST_COMPLETED,
    Future,
    ProcessPoolExecutor,
    ThreadPoolExecutor,
    wait,
)
from pathlib import Path
from typing import Any, NoReturn

from lightcraft_opt.errors import ParameterError

__all__ = [
    "RunFunction",
    "dask_cluster",
    "default_workers",
    "local_processes",
    "scheduler_address",
    "serial",
]

#: ``fn(campaign, seed, index) -> outcome``.
RunFunction = Callable[[Any, int, int], Any]

#: Connecting to a scheduler gives up after this long [s].
CONNECT_TIMEOUT = 10.0
#: The first, plain TCP connection to a scheduler gives up after this long [s].
PROBE_TIMEOUT = 3.0
#: A local worker whose parent died exits within this long [s].
ORPHAN_POLL = 0.5
#: Dask's comm schemes (``host:port`` alone is tcp).
SCHEMES = ("tcp", "tls", "ws", "wss", "ucx", "inproc")


def default_workers() -> int:
    """Worker processes by default: the CPUs this process may use."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - not Linux
        return max(1, os.cpu_count() or 1)


def serial(fn: RunFunction, campaign: Any, seed: int, indices: Sequence[int]) -> Iterator[Any]:
    """The runs one after the other in this process."""
    for i in indices:
        yield fn(campaign, seed, i)


# the worker processes' campaign, set once by their initializer
_WORKER: dict[str, Any] = {}


def _init_worker(fn: RunFunction, campaign: Any, seed: int, parent: int) -> None:
    _die_with(parent)
    _WORKER.update(fn=fn, campaign=campaign, seed=seed)


def _die_with(parent: int) -> None:
    """End this worker when process ``parent`` (the campaign's) dies: SIGTERM from the
    kernel on Linux, and a watchdog thread everywhere (module docstring)."""
    if sys.platform.startswith("linux"):
        try:
            libc = ctypes.CDLL(None, use_errno=True)
            libc.prctl(1, int(signal.SIGTERM), 0, 0, 0)  # 1: PR_SET_PDEATHSIG
        except (OSError, AttributeError):  # pragma: no cover - no prctl: the thread does it
            pass
    if os.getppid() != parent:  # died before the request above took effect
        os._exit(1)
    threading.Thread(target=_watch_parent, args=(parent,), daemon=True).start()


def _watch_parent(parent: int) -> None:
    while os.getppid() == parent:
        time.sleep(ORPHAN_POLL)
    os._exit(1)


def _run_in_worker(index: int) -> Any:
    return _WORKER["fn"](_WORKER["campaign"], _WORKER["seed"], index)


def local_processes(
    fn: RunFunction, campaign: Any, seed: int, indices: Sequence[int], workers: int
) -> Iterator[Any]:
    """The runs on ``workers`` local processes, at most two queued per worker (so an
    interrupted campaign leaves little work in flight)."""
    if not indices:
        return
    context = multiprocessing.get_context("spawn")
    pool = ProcessPoolExecutor(
        max_workers=workers,
        mp_context=context,
        initializer=_init_worker,
        initargs=(fn, campaign, seed, os.getpid()),
    )
    pending: set[Future[Any]] = set()
    todo = iter(indices)
    try:
        for i in todo:
            pending.add(pool.submit(_run_in_worker, i))
            if len(pending) >= 2 * workers:
                break
        while pending:
            done, pending = wait(pending, return_when=FIRST_COMPLETED)
            for fut in done:
                nxt = next(todo, None)
                if nxt is not None:
                    pending.add(pool.submit(_run_in_worker, nxt))
                yield fut.result()
    finally:
        pool.shutdown(wait=True, cancel_futures=True)


def scheduler_address(text: str) -> str:
    """The Dask scheduler address ``text`` names: ``[scheme://]host:port`` (scheme one of
    :data:`SCHEMES`, tcp if absent) or the path of a scheduler file (the JSON
    ``dask scheduler --scheduler-file`` writes) holding one. Returns it as
    ``scheme://host:port``.

    Raises
    ------
    ParameterError("scheduler") : neither form, or a scheduler file without an address.
    """
    text = str(text).strip()
    if "://" not in text and Path(text).is_file():
        try:
            address = json.loads(Path(text).read_text(encoding="utf-8"))["address"]
        except (OSError, ValueError, KeyError, TypeError) as err:
            raise ParameterError(
                "scheduler", f"{text!r} is not a scheduler file holding an address: {err!r}"
            ) from err
        return scheduler_address(str(address))
    scheme, sep, rest = text.partition("://")
    if not sep:
        scheme, rest = "tcp", text
    if scheme not in SCHEMES:
        problem = f"unknown scheme {scheme!r} (one of {', '.join(SCHEMES)})"
    elif scheme == "inproc":
        return text if rest else _bad_address(text, "no address after inproc://")
    else:
        host, port = _host_port(rest)
        if not host:
            problem = "no host"
        elif port is None:
            problem = "no port number"
        elif not 0 < port < 65536:
            problem = f"port {port} is not in 1..65535"
        else:
            return f"{scheme}://{rest}"
    return _bad_address(text, problem)


def _bad_address(text: str, problem: str) -> NoReturn:
    raise ParameterError(
        "scheduler",
        f"{text!r} is not a Dask scheduler address: {problem}; write tcp://host:port or the "
        "path of a scheduler file",
    )


def _host_port(rest: str) -> tuple[str, int | None]:
    """(host, port or None) of ``host:port`` or ``[ipv6]:port``."""
    if rest.startswith("["):
        host, _, tail = rest[1:].partition("]")
        port = tail[1:] if tail.startswith(":") else ""
    else:
        host, _, port = rest.rpartition(":") if ":" in rest else (rest, "", "")
    if "/" in host or " " in host:
        return "", None
    return host, int(port) if port.isdigit() else None


def _probe(address: str) -> None:
    """Raise ParameterError("scheduler") within about :data:`PROBE_TIMEOUT` seconds unless
    a Dask server answers at ``address``: a plain TCP connection first (refused at once),
    then Dask's handshake under a hard deadline (a server that accepts and never speaks
    would otherwise hold the client's start for ever)."""
    scheme, _, rest = address.partition("://")
    if scheme not in ("tcp", "tls", "ws", "wss"):
        return
    host, port = _host_port(rest)
    try:
        socket.create_connection((host, port or 0), timeout=PROBE_TIMEOUT).close()
        with ThreadPoolExecutor(1) as thread:  # its own event loop, whatever the caller's
            thread.submit(asyncio.run, _handshake(address)).result()
    except TimeoutError as err:
        raise ParameterError(
            "scheduler",
            f"nothing answered as a Dask scheduler at {address!r} within {PROBE_TIMEOUT:g} s",
        ) from err
    except OSError as err:
        reason = err.strerror or str(err) or type(err).__name__
        raise ParameterError(
            "scheduler", f"cannot reach the Dask scheduler at {address!r}: {reason}"
        ) from err


async def _handshake(address: str) -> None:
    from distributed.comm import connect

    async def hello() -> None:
        comm = await connect(address, timeout=PROBE_TIMEOUT)
        await comm.close()

    await asyncio.wait_for(hello(), PROBE_TIMEOUT)


def dask_cluster(
    fn: RunFunction, campaign: Any, seed: int, indices: Sequence[int], address: str
) -> Iterator[Any]:
    """The runs on the Dask cluster whose scheduler is at ``address`` (tcp://host:port, or
    a scheduler file: :func:`scheduler_address`).

    Raises
    ------
    ParameterError("scheduler") : a malformed address, dask.distributed is not installed,
        or the scheduler at ``address`` cannot be reached.
    """
    address = scheduler_address(address)
    try:
        from distributed import Client, as_completed
    except ImportError as err:
        raise ParameterError(
            "scheduler",
            "running on a Dask cluster needs dask.distributed: "
            "pip install 'lightcraft_opt[distributed]'",
        ) from err
    _probe(address)

    class _Client(Client):
        """A client that closes itself when it fails to connect: else its ``__del__``
        tries to close it at exit and hangs for twice the timeout."""

        def start(self, **kwargs: Any) -> None:
            try:
                super().start(**kwargs)
            except BaseException:
                with contextlib.suppress(Exception):
                    self.close(timeout=PROBE_TIMEOUT)
                self.status = "closed"
                raise

    try:
        client = _Client(address, timeout=CONNECT_TIMEOUT, set_as_default=False)
    except (OSError, TimeoutError, ValueError) as err:
        raise ParameterError(
            "scheduler", f"cannot reach the Dask scheduler at {address!r}: {err}"
        ) from err
    try:
        if not indices:
            return
        spec = client.scatter(campaign, broadcast=True, hash=False)
        futures = [client.submit(fn, spec, seed, i, pure=False) for i in indices]
        try:
            for fut in as_completed(futures, loop=client.loop):
                yield fut.result()
        finally:
            client.cancel(futures)
    finally:
        client.close()
