"""Lanes: where the evaluator's chunks run, one lane per worker.

A lane runs one task at a time in a worker that keeps its state between
tasks (the run's data, its caches), so the evaluator sends each lane the
individuals whose rows that worker most likely holds.

* :class:`LocalLane` -- this process, synchronously.
* :class:`PoolLane` -- a single-process pool (forked after the shared row
  store was made, or spawned).
* :class:`DaskLane` -- one worker of a ``dask.distributed`` cluster, through
  a :class:`LaneActor` made on it: the calls go to the worker directly, not
  through the scheduler (a round trip of a few ms instead of tens).
* :class:`ExecutorLane` -- any :class:`concurrent.futures.Executor`; tasks go
  wherever the executor puts them, so it is not pinned.

A dask cluster's workers on this machine share the run's row and prefix
stores with this process, as a forked pool does (:func:`share_stores`).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from concurrent.futures import Executor, Future
from typing import Any

from edm_sym.engines.abstraction.cache import SlotStore
from edm_sym.engines.abstraction.rowsim import attach, forget


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


class LaneActor:
    """A dask actor on one worker: runs the tasks sent to it, one at a time.

    dask starts its workers with ``MALLOC_TRIM_THRESHOLD_`` set, which turns
    off glibc's adaptive mmap threshold: every signal-sized temporary (160 kB
    for 20 000 samples) would then be a fresh mapping, page-faulted page by
    page. The actor sets the threshold above such temporaries in its process.
    """

    def __init__(self) -> None:
        try:
            import ctypes

            libc = ctypes.CDLL("libc.so.6")
            libc.mallopt(-3, 32 * 2**20)  # M_MMAP_THRESHOLD
        except (OSError, AttributeError):  # pragma: no cover (not glibc)
            pass

    def call(self, fn: Callable[..., Any], *args: Any) -> Any:
        """``fn(*args)`` in the worker's process."""
        return fn(*args)


class DaskLane:
    """One worker of a dask.distributed cluster, through an actor on it.

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
        # The future keeps the actor alive: the scheduler forgets a task nobody holds.
        self._future = client.submit(LaneActor, actor=True, workers=[address],
                                     allow_other_workers=False, pure=False)
        self.actor = self._future.result()

    def submit(self, fn: Callable[..., Any], *args: Any) -> Any:
        """Run ``fn(*args)`` on this worker; a future with ``result()``."""
        return self.actor.call(fn, *args)


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


def share_stores(lanes: Sequence[Any], token: str, blob: bytes, slots: tuple[int, int], n: int
                 ) -> tuple[SlotStore, SlotStore] | None:
    """Named row and prefix stores that every lane maps, when its workers are on this machine.

    A dask cluster's workers are not forked from this process, but those of a
    LocalCluster (or started here with ``dask worker``) can open a store in
    ``/dev/shm`` and then share rows and prefixes as the forked pool does.
    Each lane also gets the run's context (``blob``) with the stores.

    Parameters
    ----------
    lanes : sequence
        The lanes (each with ``submit``).
    token, blob : str, bytes
        The run and its pickled context.
    slots : tuple of int
        Slots of the row store and of the prefix store.
    n : int
        Samples per row.

    Returns
    -------
    tuple of SlotStore or None
        The row and prefix stores; None when a lane cannot open them (another
        machine: every lane keeps its own), or this machine has no ``/dev/shm``.
    """
    stores = [SlotStore.named(count, n) for count in slots]
    if None in stores:  # pragma: no cover (no /dev/shm, or no room in it)
        return None
    try:
        futures = [lane.submit(attach, token, blob, *((st.path, st.slots) for st in stores), n)
                   for lane in lanes]
        ok = [f.result() for f in futures]
    finally:
        for st in stores:
            st.unlink()  # every lane has it mapped by now, or never will
    if all(ok):
        return stores[0], stores[1]
    for lane, yes in zip(lanes, ok, strict=True):  # pragma: no cover (a remote worker)
        if yes:
            lane.submit(forget, token).result()
    return None
