"""Row simulation where it runs: in this process or in a worker.

Rows travel as a canonical gene table (:func:`row_table`), one float64 line
``[input, c_1..c_n, p_1..p_n]`` per row. A worker keeps, per run, the input
signals, a decoder from codes to element classes and ranges, and a cache of
row prefixes (the signal after the first k elements), so a row that differs
from an earlier one only in its later elements starts where they part. A
row's output is a pure function of its genes, whatever any cache holds.
"""

from __future__ import annotations

import os
import pickle
import signal
import threading
import time
from collections import OrderedDict
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from edm_sym.core.elements import REGISTRY, Element, ParamRange
from edm_sym.engines.abstraction.cache import RowCache

#: Codes of the elements that use their parameter (others ignore p).
HAS_PARAM = np.array([c in REGISTRY and REGISTRY[c].param is not None
                      for c in range(max(REGISTRY) + 1)], dtype=bool)


def row_table(inputs: np.ndarray, codes: np.ndarray, ps: np.ndarray) -> np.ndarray:
    """Canonical gene table of rows: one float64 line ``[input, codes..., p...]`` per row.

    ``p`` of parameter-free elements is set to 0, since it changes nothing.

    Parameters
    ----------
    inputs : numpy.ndarray
        Shape (R,) input codes.
    codes : numpy.ndarray
        Shape (R, n) element codes.
    ps : numpy.ndarray
        Shape (R, n) normalised parameters.

    Returns
    -------
    numpy.ndarray
        Shape (R, 1 + 2 n).
    """
    r, n = codes.shape
    out = np.empty((r, 1 + 2 * n))
    out[:, 0] = inputs
    out[:, 1:1 + n] = codes
    out[:, 1 + n:] = np.where(HAS_PARAM[codes], ps, 0.0)
    return out


@dataclass(frozen=True)
class SimContext:
    """What a worker needs to simulate rows: the input signals, Ts, the ranges.

    ``prefix_bytes`` bounds the worker's cache of row prefixes.
    """

    inputs: np.ndarray
    ts: float
    ranges: Mapping[str, ParamRange]
    prefix_bytes: int = 128 * 2**20

    def decoder(self) -> dict[int, tuple[type[Element], ParamRange | None]]:
        """Element class and range by element code."""
        return {c: (cls, self.ranges[cls.name] if cls.param is not None else None)
                for c, cls in REGISTRY.items()}


@dataclass
class Worker:
    """A process's state for one run: context, decoder, prefix cache, shared rows.

    ``trig`` holds sin and cos of each input signal: a sine element reading an
    input directly (the paper's position-dependent friction; its class
    declares ``from_sin_cos``) then costs two multiply-adds instead of a sine
    per sample.
    """

    ctx: SimContext
    decoder: dict
    prefixes: RowCache
    store: np.ndarray | None = field(default=None)
    trig: dict = field(default_factory=dict)

    def sin_cos(self, k: int) -> tuple[np.ndarray, np.ndarray]:
        """sin and cos of input ``k`` (computed once)."""
        hit = self.trig.get(k)
        if hit is None:
            x = self.ctx.inputs[k]
            hit = self.trig[k] = (np.sin(x), np.cos(x))
        return hit


_WORKERS: OrderedDict[str, Worker] = OrderedDict()
_LOCK = threading.Lock()  # executors may run tasks in threads (dask, thread pools)


def worker_for(token: str, blob: bytes | None = None, ctx: SimContext | None = None,
               store: np.ndarray | None = None) -> Worker:
    """This process's :class:`Worker` of run ``token`` (made from ``ctx`` or ``blob``)."""
    with _LOCK:
        hit = _WORKERS.get(token)
        if hit is not None:
            _WORKERS.move_to_end(token)
            return hit
        if ctx is None:
            ctx = pickle.loads(blob)  # noqa: S301 (bytes pickled by the evaluator)
        hit = Worker(ctx, ctx.decoder(), RowCache(ctx.prefix_bytes), store)
        _WORKERS[token] = hit
        while len(_WORKERS) > 8:
            _WORKERS.popitem(last=False)
        return hit


def forget(token: str) -> None:
    """Drop this process's state of run ``token``."""
    with _LOCK:
        _WORKERS.pop(token, None)


def prefix_key(line: np.ndarray, n: int, k: int) -> bytes:
    """Key of the first ``k`` elements of a gene-table line (the row key of that prefix)."""
    return line[:1 + k].tobytes() + line[1 + n:1 + n + k].tobytes()


def simulate_table(worker: Worker, table: np.ndarray) -> list[np.ndarray]:
    """Simulate the rows of a canonical gene table.

    Each row starts from the longest prefix found in the worker's prefix
    cache; each prefix it computes goes into that cache.

    Parameters
    ----------
    worker : Worker
        Context, decoder and prefix cache of this process.
    table : numpy.ndarray
        Shape (R, 1 + 2 n).

    Returns
    -------
    list of numpy.ndarray
        R row outputs of shape (N,) (read-only use: they may be shared).
    """
    ctx, decoder, cache = worker.ctx, worker.decoder, worker.prefixes
    n = (table.shape[1] - 1) // 2
    out = []
    for line in table:
        y, start = None, 0
        for k in range(n - 1, 0, -1):
            y = cache.get(prefix_key(line, n, k))
            if y is not None:
                start = k
                break
        if y is None:
            y = ctx.inputs[int(line[0])]
        for i in range(start, n):
            code = int(line[1 + i])
            cls, rng = decoder[code]
            a = rng.decode(float(line[1 + n + i])) if rng is not None else None
            fast = cls.from_sin_cos if i == 0 else None
            prev, y = y, (cls.realise(a, ctx.ts).run(y) if fast is None
                          else fast(*worker.sin_cos(int(line[0])), a))
            if i < n - 1 and y is not prev:
                cache.put(prefix_key(line, n, i + 1), y)
        out.append(y)
    return out


def simulate_chunk(token: str, blob: bytes, table: np.ndarray) -> list[np.ndarray]:
    """Executor task: simulate rows and send their outputs back.

    Parameters
    ----------
    token : str
        Digest of ``blob``; a worker unpickles each run's context once.
    blob : bytes
        The pickled :class:`SimContext`.
    table : numpy.ndarray
        Canonical gene table.

    Returns
    -------
    list of numpy.ndarray
        The row outputs, in table order.
    """
    return simulate_table(worker_for(token, blob), table)


def fill_slots(token: str, table: np.ndarray, slots: list[int]) -> int:
    """Executor task of a forked pool: simulate rows into the shared row store.

    Parameters
    ----------
    token : str
        The run; its :class:`Worker` (with the store) was made before the fork.
    table : numpy.ndarray
        Canonical gene table.
    slots : list of int
        Store slot of each row.

    Returns
    -------
    int
        The number of rows written.
    """
    worker = _WORKERS[token]
    for slot, y in zip(slots, simulate_table(worker, table), strict=True):
        worker.store[slot] = y
    return len(slots)


def worker_init(parent: int) -> None:
    """Pool initializer: leave Ctrl-C to the main process, and end with it.

    The main process ends a run cleanly on Ctrl-C; a worker finishes its chunk.
    Should the main process be killed outright, a watchdog thread ends the
    worker too instead of leaving it orphaned.
    """
    signal.signal(signal.SIGINT, signal.SIG_IGN)

    def watch() -> None:
        while os.getppid() == parent:
            time.sleep(0.5)
        os._exit(0)

    threading.Thread(target=watch, daemon=True).start()


def ping() -> int:
    """A no-op task that makes a pool start its processes."""
    return os.getpid()


def default_workers() -> int:
    """Usable cores of this process."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover (not Linux)
        return max(1, os.cpu_count() or 1)
