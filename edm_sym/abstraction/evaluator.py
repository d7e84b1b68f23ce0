"""Batched fitness evaluation: a row-output cache and any concurrent.futures executor.

The fitness of an individual is eq. 8 on ``target - sum(rows)``, and a row's
output depends only on its genes (input code, element codes, parameters). So
every row output is cached under a canonical key of its genes, and a
generation only simulates the rows that no earlier generation has seen.

The rows to simulate are sorted by their genes (rows sharing a prefix of
elements then sit next to each other and share the prefix's intermediate
signals), cut into chunks and sent to an executor: a
:class:`~concurrent.futures.ProcessPoolExecutor` over every core by default,
or any :class:`~concurrent.futures.Executor` the caller passes (a
``dask.distributed`` client's ``get_executor()`` spreads a run over a
cluster). Results are collected in submission order and each row's output is
a pure function of its genes, so the outcome never depends on the number of
workers or on which task finishes first.
"""

from __future__ import annotations

import hashlib
import os
import pickle
import signal
import time
from collections import OrderedDict
from collections.abc import Mapping, Sequence
from concurrent.futures import Executor, ProcessPoolExecutor
from dataclasses import dataclass

import numpy as np

from edm_sym.elements import REGISTRY, Element, ParamRange
from edm_sym.simulate import fitness, simulate_element_fast

#: Codes of the elements that use their parameter (others ignore p).
_MAX_CODE = max(REGISTRY) + 1
HAS_PARAM = np.array([c in REGISTRY and REGISTRY[c].param is not None
                      for c in range(_MAX_CODE)], dtype=bool)


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


class RowCache:
    """Least-recently-used row outputs, bounded by memory.

    Parameters
    ----------
    max_bytes : int
        Upper bound on the bytes of cached arrays (at least one row is kept).
    """

    def __init__(self, max_bytes: int):
        self.max_bytes = int(max_bytes)
        self.nbytes = 0
        self._data: OrderedDict[bytes, np.ndarray] = OrderedDict()
        self.hits = 0
        self.misses = 0

    def __len__(self) -> int:
        return len(self._data)

    def get(self, key: bytes) -> np.ndarray | None:
        """The cached output of ``key`` (refreshing it), or None."""
        arr = self._data.get(key)
        if arr is None:
            self.misses += 1
            return None
        self._data.move_to_end(key)
        self.hits += 1
        return arr

    def put(self, key: bytes, arr: np.ndarray) -> None:
        """Store ``arr`` under ``key``, evicting the least recently used rows."""
        if key in self._data:
            self._data.move_to_end(key)
            return
        self._data[key] = arr
        self.nbytes += arr.nbytes
        while self.nbytes > self.max_bytes and len(self._data) > 1:
            _, old = self._data.popitem(last=False)
            self.nbytes -= old.nbytes

    def clear(self) -> None:
        """Drop every row."""
        self._data.clear()
        self.nbytes = 0


# -- worker side ------------------------------------------------------------------

@dataclass(frozen=True)
class SimContext:
    """What a worker needs to simulate rows: the input signals, Ts and the ranges."""

    inputs: np.ndarray
    ts: float
    ranges: Mapping[str, ParamRange]

    def decoder(self) -> dict[int, tuple[type[Element], ParamRange | None]]:
        """Element class and range by element code."""
        return {c: (cls, self.ranges[cls.name] if cls.param is not None else None)
                for c, cls in REGISTRY.items()}


_CONTEXTS: OrderedDict[str, tuple[SimContext, dict]] = OrderedDict()


def _context(token: str, blob: bytes | None, local: SimContext | None = None
             ) -> tuple[SimContext, dict]:
    hit = _CONTEXTS.get(token)
    if hit is not None:
        _CONTEXTS.move_to_end(token)
        return hit
    ctx = local if local is not None else pickle.loads(blob)  # noqa: S301 (our own bytes)
    hit = (ctx, ctx.decoder())
    _CONTEXTS[token] = hit
    while len(_CONTEXTS) > 4:
        _CONTEXTS.popitem(last=False)
    return hit


def simulate_table(ctx: SimContext, decoder: Mapping[int, tuple], table: np.ndarray
                   ) -> np.ndarray:
    """Simulate rows given as a canonical gene table (see :func:`row_table`).

    Consecutive rows that share their input and first elements reuse the
    shared prefix's signals, so sort the table first.

    Parameters
    ----------
    ctx : SimContext
        Input signals, Ts, ranges.
    decoder : mapping
        ``ctx.decoder()``.
    table : numpy.ndarray
        Shape (R, 1 + 2 n).

    Returns
    -------
    numpy.ndarray
        Shape (R, N) row outputs.
    """
    n = (table.shape[1] - 1) // 2
    out = np.empty((table.shape[0], ctx.inputs.shape[1]))
    stack: list[np.ndarray] = []
    prev: np.ndarray | None = None
    for r, line in enumerate(table):
        k = 0
        if prev is not None and prev[0] == line[0]:
            while k < n and prev[1 + k] == line[1 + k] and prev[1 + n + k] == line[1 + n + k]:
                k += 1
        del stack[k:]
        y = stack[-1] if stack else ctx.inputs[int(line[0])]
        for i in range(k, n):
            cls, rng = decoder[int(line[1 + i])]
            a = rng.decode(float(line[1 + n + i])) if rng is not None else None
            y = simulate_element_fast(cls, y, a, ctx.ts)
            stack.append(y)
        out[r] = y
        prev = line
    return out


def simulate_chunk(token: str, blob: bytes, table: np.ndarray) -> np.ndarray:
    """Executor task: simulate the rows of ``table`` (the context travels as ``blob``).

    Parameters
    ----------
    token : str
        Digest of ``blob``; a worker unpickles each context once.
    blob : bytes
        The pickled :class:`SimContext`.
    table : numpy.ndarray
        Canonical gene table, sorted.

    Returns
    -------
    numpy.ndarray
        Shape (R, N) row outputs.
    """
    ctx, decoder = _context(token, blob)
    return simulate_table(ctx, decoder, table)


def _ignore_sigint() -> None:
    # Ctrl-C is for the main process, which ends the run cleanly; workers
    # finish their chunk and are shut down.
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def default_workers() -> int:
    """Usable cores of this process."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover (not Linux)
        return max(1, os.cpu_count() or 1)


# -- main side --------------------------------------------------------------------

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
        Where to simulate rows. None: a process pool of ``workers``
        processes, started on first need (``workers=1``: in this process).
    workers : int, optional
        Process count of the default pool (default: every usable core); with
        an ``executor``, a hint for how many chunks to cut a batch into.
    cache_bytes : int
        Memory bound of the row cache.
    """

    #: Batches with fewer rows than this are simulated in this process.
    MIN_PARALLEL_ROWS = 8

    def __init__(self, inputs: np.ndarray, target: np.ndarray, ts: float,
                 ranges: Mapping[str, ParamRange], *, executor: Executor | None = None,
                 workers: int | None = None, cache_bytes: int = 512 * 2**20):
        self.inputs = np.ascontiguousarray(inputs, dtype=float)
        self.target = np.ascontiguousarray(target, dtype=float)
        self.ctx = SimContext(self.inputs, float(ts), dict(ranges))
        self._blob = pickle.dumps(self.ctx, protocol=pickle.HIGHEST_PROTOCOL)
        self._token = hashlib.sha256(self._blob).hexdigest()
        self.executor = executor
        self._own_pool = executor is None
        self.workers = int(workers) if workers else default_workers()
        self.cache = RowCache(cache_bytes)
        self.stats = EvalStats()
        self._weights: np.ndarray | float = 1.0
        self._memo: dict[bytes, float] = {}

    # -- configuration --------------------------------------------------------
    def set_weights(self, weights: np.ndarray | float) -> None:
        """Set Lambda(q) for the following evaluations."""
        self._weights = weights if np.isscalar(weights) else np.asarray(weights, dtype=float)
        self._memo.clear()

    def close(self) -> None:
        """Shut down the process pool this evaluator started (not a caller's executor)."""
        if self._own_pool and self.executor is not None:
            self.executor.shutdown(wait=True, cancel_futures=True)
            self.executor = None

    def abort(self) -> None:
        """Shut down an own pool without waiting (after an interrupt)."""
        if self._own_pool and self.executor is not None:
            self.executor.shutdown(wait=False, cancel_futures=True)
            self.executor = None

    def __enter__(self) -> Evaluator:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # -- evaluation -----------------------------------------------------------
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
            When given, filled with one entry per individual: its m row
            outputs, or None when its fitness came from the memo of
            individuals already evaluated under the current weighting.

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
        todo = []
        for k in range(p):
            ikey = b"".join(keys[k * m:(k + 1) * m])
            f = self._memo.get(ikey)
            if f is None:
                todo.append((k, ikey))
            else:
                out[k] = f
        need = {keys[k * m + j] for k, _ in todo for j in range(m)}
        rows: dict[bytes, np.ndarray] = {}
        missing: list[int] = []
        seen: set[bytes] = set()
        for idx, key in enumerate(keys):
            if key not in need or key in seen:
                continue
            seen.add(key)
            arr = self.cache.get(key)
            if arr is None:
                missing.append(idx)
            else:
                rows[key] = arr
        self.stats.rows_missed += len(missing)
        if missing:
            sub = table[missing]
            order = np.lexsort(sub.T[::-1])
            sub = sub[order]
            outputs = self._simulate(sub)
            for r, line in enumerate(sub):
                key = line.tobytes()
                row = outputs[r].copy()  # own memory, so the cache's byte count is true
                rows[key] = row
                self.cache.put(key, row)
        if rows_out is not None:
            rows_out[:] = [None] * p
        for k, ikey in todo:
            mine = [rows[keys[k * m + j]] for j in range(m)]
            if rows_out is not None:
                rows_out[k] = mine
            f = self._fitness(mine)
            out[k] = f
            if len(self._memo) > 200_000:
                self._memo.clear()
            self._memo[ikey] = f
        return out

    @property
    def weights(self) -> np.ndarray | float:
        """The current Lambda(q)."""
        return self._weights

    def _fitness(self, rows: Sequence[np.ndarray]) -> float:
        total = rows[0].copy()
        for r in rows[1:]:
            total += r
        with np.errstate(over="ignore", invalid="ignore"):
            f = fitness(self.target - total, self._weights)
        return f if np.isfinite(f) else float("inf")

    def simulate_rows(self, table: np.ndarray) -> np.ndarray:
        """Simulate rows of a canonical gene table (no cache), in table order."""
        order = np.lexsort(table.T[::-1])
        out = np.empty((table.shape[0], self.inputs.shape[1]))
        out[order] = self._simulate(table[order])
        return out

    def _simulate(self, table: np.ndarray) -> np.ndarray:
        t0 = time.perf_counter()
        rows = table.shape[0]
        n = (table.shape[1] - 1) // 2
        if rows < self.MIN_PARALLEL_ROWS or (self._own_pool and self.workers <= 1):
            ctx, decoder = _context(self._token, None, self.ctx)
            out = simulate_table(ctx, decoder, table)
        else:
            executor = self._pool()
            chunks = min(rows, 2 * self.workers)
            bounds = np.linspace(0, rows, chunks + 1).astype(int)
            futures = [executor.submit(simulate_chunk, self._token, self._blob,
                                       table[bounds[c]:bounds[c + 1]])
                       for c in range(chunks)]
            # In submission order, never in completion order.
            out = np.concatenate([f.result() for f in futures], axis=0)
        self.stats.rows_simulated += rows
        self.stats.element_samples += rows * n * self.inputs.shape[1]
        self.stats.sim_seconds += time.perf_counter() - t0
        return out

    def _pool(self) -> Executor:
        if self.executor is None:
            # Python's default start method (fork on Linux up to 3.13): workers
            # need no copy of the data from a re-imported main module.
            self.executor = ProcessPoolExecutor(self.workers, initializer=_ignore_sigint)
        return self.executor

    def start(self) -> None:
        """Start the default process pool now (before any thread is started)."""
        if self._own_pool and self.workers > 1:
            self._pool()
