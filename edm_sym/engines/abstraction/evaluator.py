"""Batched fitness evaluation: cached rows, any concurrent.futures executor.

The fitness of an individual is eq. 8 on ``target - sum(rows)``, and a row's
output depends only on its genes (input code, element codes, parameters). So
every row output is cached under a canonical key of its genes, and a
generation only simulates the rows no earlier generation has left in the
cache. The rows of a batch are sorted by their genes (so a chunk holds rows
with common prefixes) and cut into chunks for the workers.

Where the rows are simulated:

* ``workers=1``: in this process.
* default (``executor=None``): a :class:`~concurrent.futures.ProcessPoolExecutor`
  over every core, forked after a shared memory map of row slots was made.
  Workers write rows into their slots; nothing but gene tables and slot
  numbers is pickled, because sending a row back would cost more than
  simulating it.
* any other :class:`~concurrent.futures.Executor` (``executor=``, e.g. a
  ``dask.distributed`` client's ``get_executor()``): the context is sent with
  each chunk (unpickled once per worker) and the row outputs come back.

Results are gathered in submission order and are pure functions of the
genes, so a run's outcome never depends on the number of workers or on
which task finishes first.
"""

from __future__ import annotations

import hashlib
import multiprocessing
import os
import pickle
import time
import warnings
from collections import OrderedDict
from collections.abc import Mapping, Sequence
from concurrent.futures import Executor, ProcessPoolExecutor
from dataclasses import dataclass

import numpy as np

from edm_sym.core.elements import ParamRange
from edm_sym.engines.abstraction.cache import RowCache, SlotStore
from edm_sym.engines.abstraction.rowsim import (
    SimContext,
    default_workers,
    fill_slots,
    forget,
    ping,
    prefix_key,
    row_table,
    simulate_chunk,
    simulate_table,
    worker_for,
    worker_init,
)

__all__ = ["EvalStats", "Evaluator", "RowCache", "row_table"]


@dataclass
class EvalStats:
    """Counters of an evaluator (for progress lines and benchmarks)."""

    individuals: int = 0
    row_requests: int = 0
    rows_missed: int = 0
    rows_simulated: int = 0
    element_samples: int = 0
    sim_seconds: float = 0.0

    @property
    def cache_hits(self) -> int:
        """Row requests served without simulating (cache, memo or a twin in the batch)."""
        return self.row_requests - self.rows_missed

    @property
    def hit_rate(self) -> float:
        """Share of row requests served without simulating."""
        return self.cache_hits / self.row_requests if self.row_requests else 0.0


class Evaluator:
    """Fitness (eq. 8) of many individuals at once, with cached rows.

    Parameters
    ----------
    inputs : numpy.ndarray
        Shape (n_inputs, N) input signals.
    target : numpy.ndarray
        Shape (N,) the target column.
    ts : float
        Sample time [s].
    ranges : mapping of element name to ParamRange
        Decode ``p`` to ``a``.
    executor : concurrent.futures.Executor, optional
        Where to simulate rows (it is not shut down here). None: a process
        pool of ``workers`` processes (``workers=1``: this process).
    workers : int, optional
        Processes of the default pool (default: every usable core). A batch
        is cut into twice this many chunks (also for a caller's executor).
    cache_bytes : int
        Memory bound of the row cache; each process's prefix cache gets half.
    max_batch_rows : int
        The most distinct rows one batch can hold (sizes the shared store).
    """

    #: Batches with fewer new rows than this are simulated in this process.
    MIN_PARALLEL_ROWS = 8

    def __init__(self, inputs: np.ndarray, target: np.ndarray, ts: float,
                 ranges: Mapping[str, ParamRange], *, executor: Executor | None = None,
                 workers: int | None = None, cache_bytes: int = 256 * 2**20,
                 max_batch_rows: int = 1024):
        self.inputs = np.ascontiguousarray(inputs, dtype=float)
        self.target = np.ascontiguousarray(target, dtype=float)
        n = self.target.shape[0]
        self.ctx = SimContext(self.inputs, float(ts), dict(ranges), max(1, cache_bytes // 2))
        self._blob = pickle.dumps(self.ctx, protocol=pickle.HIGHEST_PROTOCOL)
        self._token = hashlib.sha256(self._blob).hexdigest() + f"-{id(self):x}"
        self.executor = executor
        self._own_pool = executor is None
        self.workers = int(workers) if workers else default_workers()
        self.shared = (self._own_pool and self.workers > 1
                       and "fork" in multiprocessing.get_all_start_methods())
        if self.shared:
            slots = max(cache_bytes // (8 * n), 2 * max_batch_rows + 16)
            self.cache: RowCache | SlotStore = SlotStore(slots, n)
            store = self.cache.rows
        else:
            self.cache = RowCache(cache_bytes)
            store = None
        # Made before any fork, so forked workers inherit it (and the store).
        self._local = worker_for(self._token, ctx=self.ctx, store=store)
        self._started = False
        self._pinned: list[ProcessPoolExecutor] = []
        self._owner: OrderedDict[bytes, int] = OrderedDict()
        self.stats = EvalStats()
        self._weights: np.ndarray | float = 1.0
        self._memo: dict[bytes, float] = {}
        self._dots: dict[bytes, float] = {}

    # -- life cycle -------------------------------------------------------------
    def start(self) -> None:
        """Start the default process pool now, before any other thread exists."""
        if not self._own_pool or self.workers <= 1 or self._started:
            return
        self._started = True
        with warnings.catch_warnings():
            # Forking is safe here: the pool starts before the run makes threads.
            warnings.simplefilter("ignore", DeprecationWarning)
            if self.shared:
                # One single-process pool per worker, so rows can be routed to the
                # worker whose prefix cache holds their first elements.
                ctx = multiprocessing.get_context("fork")
                self._pinned = [ProcessPoolExecutor(1, mp_context=ctx, initializer=worker_init,
                                                    initargs=(os.getpid(),))
                                for _ in range(self.workers)]
                pools = self._pinned
            else:
                self.executor = ProcessPoolExecutor(self.workers, initializer=worker_init,
                                                    initargs=(os.getpid(),))
                pools = [self.executor] * self.workers
            for f in [pool.submit(ping) for pool in pools]:
                f.result()

    def close(self) -> None:
        """Shut down the process pool this evaluator started (not a caller's executor)."""
        self._shutdown(wait=True)
        forget(self._token)

    def abort(self) -> None:
        """Shut down an own pool without waiting (after an interrupt)."""
        self._shutdown(wait=False)

    def _shutdown(self, wait: bool) -> None:
        if self._own_pool and self.executor is not None:
            self.executor.shutdown(wait=wait, cancel_futures=True)
            self.executor = None
        for pool in self._pinned:
            pool.shutdown(wait=wait, cancel_futures=True)
        self._pinned = []

    def __enter__(self) -> Evaluator:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # -- weighting ----------------------------------------------------------------
    @property
    def weights(self) -> np.ndarray | float:
        """The current Lambda(q)."""
        return self._weights

    def set_weights(self, weights: np.ndarray | float) -> None:
        """Set Lambda(q) for the following evaluations."""
        self._weights = weights if np.isscalar(weights) else np.asarray(weights, dtype=float)
        self._memo.clear()
        self._dots.clear()

    def gram(self, keys: Sequence[bytes], rows: Sequence[np.ndarray]
             ) -> tuple[np.ndarray, np.ndarray]:
        """Weighted inner products of rows, remembered by their keys.

        Parameters
        ----------
        keys, rows : sequence
            Row keys and outputs (as from ``evaluate(..., rows_out=...)``).

        Returns
        -------
        gram : numpy.ndarray
            ``G[i, j] = sum(Lambda * r_i * r_j)``, shape (m, m).
        gy : numpy.ndarray
            ``sum(Lambda * r_i * target)``, shape (m,).
        """
        m = len(keys)
        gram, gy = np.empty((m, m)), np.empty(m)
        if len(self._dots) > 500_000:
            self._dots.clear()
        for i in range(m):
            gy[i] = self._dot(keys[i], rows[i], b"target", self.target)
            for j in range(i + 1):
                gram[i, j] = gram[j, i] = self._dot(keys[i], rows[i], keys[j], rows[j])
        return gram, gy

    def _dot(self, ka: bytes, a: np.ndarray, kb: bytes, b: np.ndarray) -> float:
        key = ka + b"|" + kb if ka <= kb else kb + b"|" + ka
        v = self._dots.get(key)
        if v is None:
            w = self._weights
            # einsum's own loops, not BLAS: the same bits whatever the thread settings.
            with np.errstate(over="ignore", invalid="ignore"):
                v = float(np.einsum("i,i", a, b) * w if np.isscalar(w)
                          else np.einsum("i,i,i", w, a, b))
            self._dots[key] = v
        return v

    # -- evaluation -----------------------------------------------------------------
    def individual_keys(self, inputs: np.ndarray, codes: np.ndarray, ps: np.ndarray
                        ) -> list[bytes]:
        """Canonical key of each individual (equal keys: equal compensators)."""
        p, m, n = codes.shape
        table = row_table(inputs.reshape(-1), codes.reshape(-1, n), ps.reshape(-1, n))
        return [table[k * m:(k + 1) * m].tobytes() for k in range(p)]

    def evaluate(self, inputs: np.ndarray, codes: np.ndarray, ps: np.ndarray,
                 rows_out: list | None = None) -> np.ndarray:
        """Fitness of each individual.

        Parameters
        ----------
        inputs : numpy.ndarray
            Shape (P, m) input codes.
        codes : numpy.ndarray
            Shape (P, m, n) element codes.
        ps : numpy.ndarray
            Shape (P, m, n) normalised parameters.
        rows_out : list, optional
            When given, filled with one entry per individual: its m row keys
            and m row outputs (valid until the next call).

        Returns
        -------
        numpy.ndarray
            Shape (P,) eq. 8 values (inf for non-finite outputs).
        """
        p, m, n = codes.shape
        table = row_table(inputs.reshape(-1), codes.reshape(-1, n), ps.reshape(-1, n))
        keys = [line.tobytes() for line in table]
        self.stats.individuals += p
        self.stats.row_requests += len(keys)
        out = np.empty(p)
        todo, want = [], []
        for k in range(p):
            ikey = b"".join(keys[k * m:(k + 1) * m])
            f = self._memo.get(ikey)
            if f is None:
                todo.append((k, ikey))
            else:
                out[k] = f
            if f is None or rows_out is not None:
                want.append(k)
        rows: dict[bytes, np.ndarray] = {}
        missing: list[int] = []
        for k in want:
            for idx in range(k * m, (k + 1) * m):
                key = keys[idx]
                if key in rows:
                    continue
                arr = self.cache.get(key)
                if arr is None:
                    rows[key] = None  # placeholder: simulated below
                    missing.append(idx)
                else:
                    rows[key] = arr
        self.stats.rows_missed += len(missing)
        if missing:
            sub = table[missing]
            sub = sub[np.lexsort(sub.T[::-1])]
            for line, row in zip(sub, self._simulate(sub, keep=rows.keys()), strict=True):
                rows[line.tobytes()] = row
        if rows_out is not None:
            rows_out[:] = [(keys[k * m:(k + 1) * m], [rows[keys[k * m + j]] for j in range(m)])
                           for k in range(p)]
        for k, ikey in todo:
            f = self._fitness([rows[keys[k * m + j]] for j in range(m)])
            out[k] = f
            if len(self._memo) > 200_000:
                self._memo.clear()
            self._memo[ikey] = f
        return out

    def _fitness(self, rows: Sequence[np.ndarray]) -> float:
        # Eq. 8 in one pass over the residual (einsum's loops: no temporaries, no
        # BLAS); equal to edm_sym.engines.simulate.fitness to rounding.
        res = self.target - rows[0]
        for r in rows[1:]:
            res -= r
        w = self._weights
        with np.errstate(over="ignore", invalid="ignore"):
            sq = (np.einsum("i,i", res, res) * w if np.isscalar(w)
                  else np.einsum("i,i,i", w, res, res))
            f = float(np.sqrt(sq / res.shape[0]))
        return f if np.isfinite(f) else float("inf")

    def simulate_rows(self, table: np.ndarray) -> list[np.ndarray]:
        """Simulate the rows of a canonical gene table (bypassing the row cache).

        Returns copies, in table order.
        """
        if isinstance(self.cache, SlotStore):
            slots = self.cache.allocate(len(table), ())
            try:
                self._fill(table, slots)
                return [self.cache.rows[s].copy() for s in slots]
            finally:
                self.cache.release(slots)
        return [np.array(r) for r in self._simulate(table, keep=())]

    def _simulate(self, table: np.ndarray, keep: object) -> list[np.ndarray]:
        """Simulate rows and enter them in the cache; their outputs in table order."""
        t0 = time.perf_counter()
        rows = table.shape[0]
        if isinstance(self.cache, SlotStore):
            slots = self.cache.allocate(rows, keep)
            self._fill(table, slots)
            out = [self.cache.commit(line.tobytes(), s) for line, s in zip(table, slots,
                                                                           strict=True)]
        else:
            if rows < self.MIN_PARALLEL_ROWS or self.executor is None:
                out = simulate_table(self._local, table)
            else:
                futures = [self.executor.submit(simulate_chunk, self._token, self._blob, part)
                           for part in self._chunks(table)]
                # In submission order, never in completion order.
                out = [row for f in futures for row in f.result()]
            for line, row in zip(table, out, strict=True):
                self.cache.put(line.tobytes(), row)
        n = (table.shape[1] - 1) // 2
        self.stats.rows_simulated += rows
        self.stats.element_samples += rows * n * self.inputs.shape[1]
        self.stats.sim_seconds += time.perf_counter() - t0
        return out

    def _fill(self, table: np.ndarray, slots: list[int]) -> None:
        if len(table) < self.MIN_PARALLEL_ROWS or not self._pinned:
            fill_slots(self._token, table, slots)
            return
        parts = self._route(table)
        futures = [self._pinned[w].submit(fill_slots, self._token, table[idx],
                                          [slots[i] for i in idx])
                   for w, idx in enumerate(parts) if idx]
        for f in futures:
            f.result()

    def _route(self, table: np.ndarray) -> list[list[int]]:
        """Rows per worker: to the worker that computed their longest known prefix.

        A row goes where its prefix most likely sits in a prefix cache, unless
        that worker already has its share of the batch (then to the least
        loaded one). Routing changes only speed, never a result.
        """
        n = (table.shape[1] - 1) // 2
        cap = -(-len(table) * 5 // (4 * self.workers))  # a quarter over an even share
        parts: list[list[int]] = [[] for _ in range(self.workers)]
        for r, line in enumerate(table):
            keys = [prefix_key(line, n, k) for k in range(1, n)]
            owner = next((self._owner[k] for k in reversed(keys) if k in self._owner), None)
            if owner is None or len(parts[owner]) >= cap:
                owner = min(range(self.workers), key=lambda w: len(parts[w]))
            parts[owner].append(r)
            for k in keys:
                self._owner[k] = owner
                self._owner.move_to_end(k)
        while len(self._owner) > 200_000:
            self._owner.popitem(last=False)
        return parts

    def _chunks(self, table: np.ndarray) -> list[np.ndarray]:
        count = min(len(table), 2 * self.workers)
        bounds = np.linspace(0, len(table), count + 1).astype(int)
        return [table[bounds[c]:bounds[c + 1]] for c in range(count)]
