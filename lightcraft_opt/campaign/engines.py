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
  never needs it.
"""

from __future__ import annotations

import multiprocessing
import os
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from typing import Any

from lightcraft_opt.errors import ParameterError

__all__ = ["RunFunction", "dask_cluster", "default_workers", "local_processes", "serial"]

#: ``fn(campaign, seed, index) -> outcome``.
RunFunction = Callable[[Any, int, int], Any]

#: Connecting to a scheduler gives up after this long [s].
CONNECT_TIMEOUT = 10.0


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


def _init_worker(fn: RunFunction, campaign: Any, seed: int) -> None:
    _WORKER.update(fn=fn, campaign=campaign, seed=seed)


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
        initargs=(fn, campaign, seed),
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


def dask_cluster(
    fn: RunFunction, campaign: Any, seed: int, indices: Sequence[int], address: str
) -> Iterator[Any]:
    """The runs on the Dask cluster whose scheduler is at ``address`` (tcp://host:port).

    Raises
    ------
    ParameterError("scheduler") : dask.distributed is not installed, or the scheduler
        at ``address`` cannot be reached.
    """
    try:
        from distributed import Client, as_completed
    except ImportError as err:
        raise ParameterError(
            "scheduler",
            "running on a Dask cluster needs dask.distributed: "
            "pip install 'lightcraft_opt[distributed]'",
        ) from err
    try:
        client = Client(address, timeout=CONNECT_TIMEOUT, set_as_default=False)
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
