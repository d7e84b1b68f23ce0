"""Lanes: where the evaluator's chunks run, one lane per worker.

A lane runs one task at a time in a worker that keeps its state between
tasks (the run's data, its caches), so the evaluator sends each lane the
individuals whose rows that worker most likely holds.

* :class:`LocalLane` -- this process, synchronously.
* :class:`PoolLane` -- a single-process pool (forked after the shared row
  store was made, or spawned).
* :class:`DaskLane` -- one worker of a ``dask.distributed`` cluster, by its
  address (``Client.submit(..., workers=[address])``).
* :class:`ExecutorLane` -- any :class:`concurrent.futures.Executor`; tasks go
  wherever the executor puts them, so it is not pinned.
"""

from __future__ import annotations

from collections.abc import Callable
from concurrent.futures import Executor, Future
from typing import Any


class LocalLane:
    """This process: the task runs when submitted."""

    pinned = True
    local = True

    def submit(self, fn: Callable[..., Any], *args: Any) -> Future:
        """Run ``fn(*args)`` now; a finished future."""
        f: Future = Future()
        try:
            f.set_result(fn(*args))
        except BaseException as exc:  # noqa: BLE001 (handed to the caller by result())
            f.set_exception(exc)
        return f


class PoolLane:
    """One single-process :class:`~concurrent.futures.ProcessPoolExecutor`."""

    pinned = True
    local = False

    def __init__(self, pool: Executor):
        self.pool = pool

    def submit(self, fn: Callable[..., Any], *args: Any) -> Future:
        """Submit to the pool's one process."""
        return self.pool.submit(fn, *args)


class ExecutorLane:
    """A share of any executor's workers (not pinned to one)."""

    pinned = False
    local = False

    def __init__(self, executor: Executor):
        self.executor = executor

    def submit(self, fn: Callable[..., Any], *args: Any) -> Future:
        """Submit to the executor."""
        return self.executor.submit(fn, *args)


class DaskLane:
    """One worker of a dask.distributed cluster.

    Parameters
    ----------
    client : distributed.Client
        A connected client.
    address : str
        The worker's address (a key of ``client.scheduler_info()["workers"]``).
    """

    pinned = True
    local = False

    def __init__(self, client: Any, address: str):
        self.client = client
        self.address = address

    def submit(self, fn: Callable[..., Any], *args: Any) -> Any:
        """Submit to this worker only (``pure=False``: every task runs)."""
        return self.client.submit(fn, *args, workers=[self.address],
                                  allow_other_workers=False, pure=False)


def dask_lanes(client: Any) -> list[DaskLane]:
    """One lane per worker of ``client``'s cluster, by address.

    Raises
    ------
    RuntimeError
        When the cluster has no worker.
    """
    workers = sorted(client.scheduler_info()["workers"])
    if not workers:
        raise RuntimeError("the dask cluster has no worker")
    return [DaskLane(client, address) for address in workers]
