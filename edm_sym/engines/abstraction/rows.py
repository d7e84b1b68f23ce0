"""Simulating the rows of a gene table, each from its longest stored prefix.

A row's output is computed from the longest of its prefixes (the signal
after its first k elements) that the prefix store holds, and the prefixes
it computes go into that store (a process's own
:class:`~edm_sym.engines.abstraction.cache.SlotStore`, or a chunk's view of
the shared one, :class:`~edm_sym.engines.abstraction.prefixes.ChunkPrefixes`).
With numba the row kernel (:mod:`edm_sym.engines.kernel`) runs the rows in
batches; without it the reference realisations run, row after row. Either
way several logs laid end to end (``ctx.starts``) run each from rest.
"""

from __future__ import annotations

from typing import Any, Protocol

import numpy as np

from edm_sym.engines import kernel
from edm_sym.engines.abstraction.cache import SlotStore
from edm_sym.engines.abstraction.prefixes import ChunkPrefixes, prefix_key


class WorkerView(Protocol):
    """What the row simulation reads of a worker: its data (``ctx``), gene decoder,
    stores and stages (:class:`~edm_sym.engines.abstraction.worker.Worker`, which
    imports this module)."""

    ctx: Any
    decoder: dict
    use_kernel: bool

    def sin_cos(self, k: int) -> tuple[np.ndarray, np.ndarray]:
        """The cached sine and cosine of input ``k``."""

    def stage(self, code: int, p: float) -> Any:
        """The realisation of element ``code`` at normalised parameter ``p``."""

    def prefix_store(self) -> SlotStore:
        """This process's prefix store."""

    def bounds(self) -> np.ndarray:
        """The row kernel's log bounds (each log's first sample, then the length)."""


def simulate_table(worker: WorkerView, table: np.ndarray,
                   outs: list[np.ndarray] | np.ndarray | None = None) -> list[np.ndarray]:
    """Simulate the rows of a canonical gene table (see :func:`simulate_into`).

    Parameters
    ----------
    worker : WorkerView
        Context, decoder and prefix store of this process.
    table : numpy.ndarray
        Shape (R, 1 + 2 n).
    outs : sequence of numpy.ndarray, optional
        Where each row's output goes (shape (N,) each, or one (R, N) array);
        new arrays when None.

    Returns
    -------
    list of numpy.ndarray
        The R row outputs (``outs`` when given).
    """
    count, length = len(table), worker.ctx.inputs.shape[1]
    order = np.arange(count, dtype=np.int64)
    if outs is None or (isinstance(outs, np.ndarray) and outs.ndim == 2):
        store = np.empty((count, length)) if outs is None else outs
        simulate_into(worker, table, store, order)
        return list(store)
    store = np.empty((count, length))
    simulate_into(worker, table, store, order)
    for out, row in zip(outs, store, strict=True):
        out[:] = row
    return list(outs)


#: The most rows the row kernel runs together (one schedule, their filters overlapped).
BATCH_ROWS = 64


def simulate_into(worker: WorkerView, table: np.ndarray, store: np.ndarray, dest: np.ndarray,
                  pool: SlotStore | ChunkPrefixes | None = None) -> int:
    """Simulate the rows of a canonical gene table into ``store[dest[r]]``.

    Each row starts from the longest prefix found in the prefix store
    (``pool``, default the worker's own); each prefix it computes goes into
    that store, when the store has room for all of them. With numba the row
    kernel runs the rows in batches (:func:`edm_sym.engines.kernel.run_rows`,
    writing the prefixes straight into their slots); a row whose longest
    prefix another row of the batch computes waits for the next batch, so it
    starts there as it would have one after the other. Without numba the
    realisations run, one numpy call per element, row after row.

    Parameters
    ----------
    worker : WorkerView
        Context, decoder and prefix store of this process.
    table : numpy.ndarray
        Shape (R, 1 + 2 n).
    store : numpy.ndarray
        Shape (S, N): row r's output goes to ``store[dest[r]]``.
    dest : numpy.ndarray
        int64, shape (R,), distinct.
    pool : SlotStore or ChunkPrefixes, optional
        The prefix store (default: :meth:`Worker.prefix_store`).

    Returns
    -------
    int
        Elements run over the signal.
    """
    if pool is None:
        pool = worker.prefix_store()
    if not worker.use_kernel:
        return sum(_simulate_reference(worker, pool, line, store[dest[r]])
                   for r, line in enumerate(table))
    ctx, decoder = worker.ctx, worker.decoder
    n = (table.shape[1] - 1) // 2
    sources = ctx.inputs
    if not (sources.flags.c_contiguous and sources.dtype == np.float64):
        sources = np.ascontiguousarray(sources, dtype=np.float64)
    # A batch's prefixes all need a slot at once: at most half the prefix store.
    cap = max(1, min(BATCH_ROWS, pool.slots // (2 * max(1, n - 1))))
    todo = list(range(len(table)))
    elements = 0
    while todo:
        batch, later, produced, used = [], [], set(), set()
        for r in todo:
            line = table[r]
            if len(batch) >= cap:
                later.append(r)
                continue
            start, begin, wait = 0, None, False
            for k in range(n - 1, 0, -1):
                key = prefix_key(line, n, k)
                if key in produced:  # a row of this batch computes it: start there next time
                    wait = True
                    break
                slot = pool.lookup(key)
                if slot is not None:
                    start, begin = k, -1 - slot  # the prefix, read in place
                    used.add(key)
                    break
            if wait:
                later.append(r)
                continue
            found, keep, stages = start, None, []
            if begin is None:
                begin = int(line[0])  # the input, read in place
            for i in range(start, n):
                code, p = int(line[1 + i]), float(line[1 + n + i])
                cls, rng = decoder[code]
                if i == 0 and cls.from_sin_cos is not None:
                    a = rng.decode(p) if rng is not None else None
                    begin = cls.from_sin_cos(*worker.sin_cos(int(line[0])), a)
                    start = 1
                    keep = begin if n > 1 else None
                    continue
                stages.append(worker.stage(code, p))
            new = [prefix_key(line, n, k) for k in range(found + 1, n)]
            storing = pool.storing(new)
            program, stored = kernel.compile_steps(stages, store=storing)
            batch.append((r, line, program, stored, start, begin, keep if storing else None))
            elements += n - found
            if storing:
                produced.update(new)
        _run_batch(pool, batch, n, store, dest, sources, used, worker.bounds())
        todo = later
    return elements


def _run_batch(pool: SlotStore | ChunkPrefixes, batch: list, n: int, store: np.ndarray,
               dest: np.ndarray, sources: np.ndarray, used: set[bytes], bounds: np.ndarray
               ) -> None:
    """Run a batch of rows in the kernel (each log from rest: ``bounds``); record their prefixes.

    The prefixes rows start from (``used``) keep their slots during the batch.
    """
    keys = [prefix_key(line, n, start + count)
            for _, line, _, stored, start, _, _ in batch for count in stored]
    slots = pool.place(keys, used)
    row_slots, at = [], 0
    for b in batch:
        row_slots.append(slots[at:at + len(b[3])])
        at += len(b[3])
    kernel.run_rows([b[2] for b in batch], [b[5] for b in batch], store,
                    np.array([dest[b[0]] for b in batch], dtype=np.int64), pool.rows, row_slots,
                    sources=sources, bounds=bounds)
    for key, slot in zip(keys, slots, strict=True):
        pool.commit(key, slot)
    for _, line, _, _, _, _, keep in batch:
        if keep is not None:
            _keep(pool, prefix_key(line, n, 1), keep)


def _simulate_reference(worker: WorkerView, pool: SlotStore | ChunkPrefixes, line: np.ndarray,
                        out: np.ndarray) -> int:
    """One row with the realisations, from its longest stored prefix (storing the others).

    Returns the number of elements run.
    """
    ctx, decoder = worker.ctx, worker.decoder
    n = (line.shape[0] - 1) // 2
    y, start = None, 0
    for k in range(n - 1, 0, -1):
        y = pool.get(prefix_key(line, n, k))
        if y is not None:
            start = k
            break
    if y is None:
        y = ctx.inputs[int(line[0])]
    for i in range(start, n):
        code, p = int(line[1 + i]), float(line[1 + n + i])
        cls, rng = decoder[code]
        if i == 0 and cls.from_sin_cos is not None:
            a = rng.decode(p) if rng is not None else None
            y = cls.from_sin_cos(*worker.sin_cos(int(line[0])), a)
        else:
            prev, y = y, worker.stage(code, p).run(y)
            if y is prev:
                continue
        if i + 1 < n:
            _keep(pool, prefix_key(line, n, i + 1), y)
    out[:] = y
    return n - start


def _keep(pool: SlotStore | ChunkPrefixes, key: bytes, y: np.ndarray) -> None:
    """Copy a prefix into the pool (unless it is there, or the pool has no room planned)."""
    if pool.lookup(key) is None and pool.storing([key]):
        slot = pool.place([key], ())[0]
        pool.rows[slot] = y
        pool.commit(key, slot)
