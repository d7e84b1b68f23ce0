"""Lanes: where the evaluator's chunks run, one lane per worker.

A lane runs one task at a time in a worker that keeps its state between
tasks (the run's data, its caches), so the evaluator sends each lane the
individuals whose rows that worker most likely holds.

* :class:`LocalLane` -- this process, synchronously.
* :class:`PipeLane` -- a process forked after the shared stores were made,
  fed through a pipe by the main thread itself.
* :class:`PoolLane` -- a single-process pool (spawned, where there is no fork).
* :class:`DaskLane` -- one worker of a ``dask.distributed`` cluster, through
  a :class:`LaneActor` made on it: the calls go to the worker directly, not
  through the scheduler (a round trip of a few ms instead of tens).
* :class:`ExecutorLane` -- any :class:`concurrent.futures.Executor`; tasks go
  wherever the executor puts them, so it is not pinned.

A dask cluster's workers on this machine share the run's row and prefix
stores with this process, as a forked pool does (:func:`share_stores`).
"""

from __future__ import annotations

import contextlib
import os
import tempfile
import threading
from collections import deque
from collections.abc import Callable, Sequence
from concurrent.futures import Executor, Future
from multiprocessing.connection import Client, Listener
from typing import Any

from edm_sym.engines.abstraction.cache import SlotStore
from edm_sym.engines.abstraction.worker import attach, forget


class LocalLane:
    """This process: the task runs when submitted."""

    pinned = True
    local = True
    same_clock = True

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
    same_clock = False

    def __init__(self, pool: Executor):
        self.pool = pool

    def submit(self, fn: Callable[..., Any], *args: Any) -> Future:
        """Submit to the pool's one process."""
        return self.pool.submit(fn, *args)


class ConnectionLane:
    """A process that runs the tasks sent over a connection (a pipe, a socket), in order.

    The main thread writes each task to the connection itself and reads each
    result when it asks for it, so no thread of this process has to win the
    GIL for a task to start or end (a
    :class:`~concurrent.futures.ProcessPoolExecutor` hands a task through two
    threads: about 2 ms from submit to start on the auger schedule, measured;
    a dask actor call goes through the client's event loop and the worker's).
    """

    pinned = True
    local = False
    #: A process of this machine: its ``time.monotonic()`` is this process's.
    same_clock = True

    def __init__(self, conn: Any):
        self._conn = conn
        self._waiting: deque[_PipeFuture] = deque()

    def submit(self, fn: Callable[..., Any], *args: Any) -> _PipeFuture:
        """Send ``fn(*args)``; a future with ``done()`` and ``result()``."""
        self._conn.send((fn, args))
        future = _PipeFuture(self)
        self._waiting.append(future)
        return future

    def _receive(self, block: bool) -> None:
        """Read the next result (waiting for it if ``block``) into the oldest future."""
        if self._waiting and (block or self._conn.poll()):
            ok, value = self._conn.recv()
            self._waiting.popleft()._set(ok, value)

    def hang_up(self) -> None:
        """Tell the other end to stop serving, and close the connection."""
        with contextlib.suppress(OSError):
            self._conn.send(None)
        self._conn.close()


class PipeLane(ConnectionLane):
    """One forked process that runs the tasks sent down a pipe.

    Parameters
    ----------
    context : multiprocessing context
        A ``fork`` context (the process inherits this one's state).
    init : callable
        Run first in the process (with ``init_args``).
    init_args : tuple
        Its arguments.
    """

    def __init__(self, context: Any, init: Callable[..., Any], init_args: tuple = ()):
        conn, child = context.Pipe()
        self._process = context.Process(target=_serve, args=(child, init, init_args),
                                        daemon=True)
        self._process.start()
        child.close()
        super().__init__(conn)

    def stop(self) -> None:
        """Ask the process to end after its tasks (without waiting for it)."""
        if self._process.is_alive():
            with contextlib.suppress(OSError):
                self._conn.send(None)

    def shutdown(self, wait: bool = True, timeout: float = 10.0) -> None:
        """End the process: after its tasks (``wait``, at most ``timeout`` seconds), or now."""
        if wait and self._process.is_alive():
            self.stop()
            self._process.join(timeout=timeout)
        if self._process.is_alive():
            self._process.kill()
            self._process.join()
        self._conn.close()


class SocketLane(ConnectionLane):
    """A dask worker on this machine, through a socket that a thread of the worker serves.

    ``via`` is the worker's :class:`DaskLane` (for the calls that stay dask's).
    """

    def __init__(self, conn: Any, via: DaskLane):
        super().__init__(conn)
        self.via = via


class _PipeFuture:
    """The result of a :class:`PipeLane` task."""

    def __init__(self, lane: PipeLane):
        self._lane = lane
        self._done = False
        self._ok = True
        self._value: Any = None

    def _set(self, ok: bool, value: Any) -> None:
        self._done, self._ok, self._value = True, ok, value

    def done(self) -> bool:
        """Whether the result is in (reading what has arrived)."""
        while not self._done and self._lane._waiting and self._lane._conn.poll():
            self._lane._receive(block=False)
        return self._done

    def result(self) -> Any:
        """The task's value (waiting for it); the task's exception is raised here."""
        while not self._done:
            if not self._lane._waiting:  # pragma: no cover (the lane was shut down)
                raise RuntimeError("the worker process ended before answering")
            self._lane._receive(block=True)
        if not self._ok:
            raise self._value
        return self._value


def _serve(conn: Any, init: Callable[..., Any] | None = None, init_args: tuple = ()) -> None:
    """A :class:`ConnectionLane`'s other end: run each task received, send back its value or error."""
    if init is not None:
        init(*init_args)
    while True:
        try:
            task = conn.recv()
        except (EOFError, OSError):  # the main process is gone
            return
        if task is None:
            return
        fn, args = task
        try:
            out = (True, fn(*args))
        except BaseException as exc:  # noqa: BLE001 (sent to the main process)
            out = (False, exc)
        try:
            conn.send(out)
        except OSError:  # pragma: no cover (the main process is gone)
            return


class ExecutorLane:
    """A share of any executor's workers (not pinned to one)."""

    pinned = False
    local = False
    same_clock = False

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
        tune_malloc()

    def call(self, fn: Callable[..., Any], *args: Any) -> Any:
        """``fn(*args)`` in the worker's process."""
        return fn(*args)


def tune_malloc() -> None:
    """Keep signal-sized temporaries out of fresh mappings in a dask worker (see :class:`LaneActor`)."""
    try:
        import ctypes

        libc = ctypes.CDLL("libc.so.6")
        libc.mallopt(-3, 32 * 2**20)  # M_MMAP_THRESHOLD
    except (OSError, AttributeError):  # pragma: no cover (not glibc)
        pass


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
    same_clock = False  # perhaps another machine

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


def socket_lanes(lanes: Sequence[DaskLane]) -> list[ConnectionLane | DaskLane]:
    """The lanes of dask workers on this machine, each through a socket of its own.

    Each worker connects to a Unix socket of this process (in a private
    folder) and serves the tasks sent over it in a thread
    (:func:`serve_socket`); the lanes stay dask's where that fails.
    """
    folder = tempfile.mkdtemp(prefix="edm_sym-", dir="/dev/shm" if os.path.isdir("/dev/shm")
                              else None)
    address = os.path.join(folder, "lanes")
    try:
        with Listener(address, family="AF_UNIX", backlog=len(lanes)) as listener:
            ok = [f.result() for f in [lane.submit(serve_socket, address, k)
                                       for k, lane in enumerate(lanes)]]
            if not all(ok):  # pragma: no cover (a worker on another machine)
                return list(lanes)
            conns: dict[int, Any] = {}
            for _ in lanes:
                conn = listener.accept()
                conns[conn.recv()] = conn
    finally:
        with contextlib.suppress(OSError):
            os.unlink(address)
        with contextlib.suppress(OSError):
            os.rmdir(folder)
    return [SocketLane(conns[k], lane) for k, lane in enumerate(lanes)]


def serve_socket(address: str, index: int) -> bool:
    """Task for a dask worker: connect to ``address`` and serve tasks from it in a thread.

    False when there is no such socket here (another machine).
    """
    try:
        conn = Client(address, family="AF_UNIX")
    except OSError:
        return False
    conn.send(index)
    threading.Thread(target=_serve, args=(conn,), daemon=True, name="edm_sym-lane").start()
    return True
