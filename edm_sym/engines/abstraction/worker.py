"""Where individuals are evaluated: in this process or in a worker, one chunk at a time.

Rows travel as a canonical gene table (:func:`row_table`), one float64 line
``[input, c_1..c_n, p_1..p_n]`` per row. A worker keeps, per run, a
:class:`Worker`: the input signals and the target (sent once per worker), a
decoder from codes to element classes and ranges, the current weighting (sent
once per step), a store of whole rows, and a store of row prefixes (the
signal after the first k elements), so a row that differs from an earlier one
only in its later elements starts where they part
(:mod:`~edm_sym.engines.abstraction.rows`). Both stores are fixed blocks of
slots, bounded by the config's ``cache_mb``: the worker's own, or the main
process's shared ones (the chunk then says where each row and prefix goes).

A task (:func:`evaluate_chunk`) gets a :class:`Chunk`: a batch of individuals
as indices into a table of their distinct rows. The worker simulates the rows
its store lacks (with the numba row kernel, :mod:`edm_sym.engines.kernel`,
when it is installed, else the reference realisations) and returns each
individual's eq. 8 and, on request, the gain fit's least-squares row scales
and the eq. 8 of the candidate made with them, with the genes it changes
(:class:`ChunkResult`): a few numbers per individual, never a row.

Every number returned is a pure function of the genes, the data and the
weighting, whichever worker computes it and whatever its caches hold.
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
from typing import Any

import numpy as np
from threadpoolctl import threadpool_limits

from edm_sym.core.elements import REGISTRY, Element, ParamRange, libm
from edm_sym.core.elements.realisation import StaticMap
from edm_sym.engines import kernel
from edm_sym.engines.abstraction.cache import SlotStore
from edm_sym.engines.abstraction.ga import Population
from edm_sym.engines.abstraction.gain_fit import gain_fit, row_scales, scale_places
from edm_sym.engines.abstraction.prefixes import ChunkPrefixes, prefix_key
from edm_sym.engines.abstraction.rows import simulate_into
from edm_sym.engines.simulate import segments

#: Codes of the elements that use their parameter (others ignore p).
HAS_PARAM = np.array([c in REGISTRY and REGISTRY[c].param is not None
                      for c in range(max(REGISTRY) + 1)], dtype=bool)

#: What a task answers when this process lacks the run's context or the weighting.
NEED_CONTEXT = "need-context"
NEED_WEIGHTS = "need-weights"


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
    """What a worker needs for a run: the input signals, the target, Ts, the ranges.

    ``row_bytes`` bounds a worker's own row store (a worker sharing the main
    process's store has none), ``prefix_bytes`` its cache of row prefixes.
    """

    inputs: np.ndarray
    ts: float
    ranges: Mapping[str, ParamRange]
    prefix_bytes: int = 128 * 2**20
    target: np.ndarray | None = None
    row_bytes: int = 128 * 2**20
    #: Where further logs begin in the signals (several logs: each simulated from rest).
    starts: tuple[int, ...] = ()

    def bounds(self) -> np.ndarray:
        """The row kernel's log bounds: each log's first sample, then the length."""
        return kernel.log_bounds(self.inputs.shape[1], self.starts)

    def decoder(self) -> dict[int, tuple[type[Element], ParamRange | None]]:
        """Element class and range by element code."""
        return {c: (cls, self.ranges[cls.name] if cls.param is not None else None)
                for c, cls in REGISTRY.items()}


@dataclass(frozen=True)
class Chunk:
    """A batch of individuals for one task.

    Attributes
    ----------
    table : numpy.ndarray
        Shape (R, 1 + 2 n): the distinct rows of the individuals.
    members : numpy.ndarray
        Shape (P, m) int64: each individual's rows, as lines of ``table``.
    score : numpy.ndarray
        Shape (P,) bool: whose eq. 8 is wanted (the others only need their rows).
    free : numpy.ndarray or None
        Shape (P, m) bool: the rows whose scale the gain fit may change; when
        given, each scored individual also gets its least-squares scales
        (:func:`~edm_sym.engines.abstraction.gain_fit.row_scales`).
    slots : numpy.ndarray or None
        Shape (R,): where each row is in the shared store (the main process
        manages it); None: the worker finds them in its own store.
    simulate : numpy.ndarray or None
        Shape (R,) bool, with ``slots``: the rows this task must simulate
        into their slots (the others are there already).
    prefix_start, prefix_slots : numpy.ndarray or None
        With a shared prefix store: the table's lines of the batch's
        :class:`~edm_sym.engines.abstraction.prefixes.PrefixPlan` (where each
        row starts, where its new prefixes go).
    gain_allowed : bool or None
        With ``free``: also evaluate each scored individual's gain-fit
        candidate (:func:`~edm_sym.engines.abstraction.gain_fit.gain_fit`;
        the value says whether a ``through`` may become a ``gain``). None: no
        candidates.
    spare : numpy.ndarray or None
        With ``slots`` and ``gain_allowed``: free slots of the shared store for
        the candidates' new rows (one per free row of a scored individual).
    fit_start, fit_slots : numpy.ndarray or None
        With ``spare``: per line, the longest prefix stored before the batch
        that the line's candidates share (its length, 0: none; its slot).
    """

    table: np.ndarray
    members: np.ndarray
    score: np.ndarray
    free: np.ndarray | None = None
    slots: np.ndarray | None = None
    simulate: np.ndarray | None = None
    prefix_start: np.ndarray | None = None
    prefix_slots: np.ndarray | None = None
    gain_allowed: bool | None = None
    spare: np.ndarray | None = None
    fit_start: np.ndarray | None = None
    fit_slots: np.ndarray | None = None


@dataclass
class ChunkResult:
    """What a task sends back: a few numbers per individual.

    Attributes
    ----------
    fitness : numpy.ndarray
        Shape (P,) eq. 8 (NaN where not scored, inf for non-finite outputs).
    scales : list or None
        With ``Chunk.free``: per individual its :func:`row_scales` (None where
        not scored or nothing to fit).
    slots : numpy.ndarray
        Where the table's rows are in the store the task used.
    simulated : int
        Rows simulated.
    sim_seconds : float
        Seconds spent simulating them.
    seconds : float
        Seconds of the whole task.
    pid : int
        The process that ran it.
    peak_rss : int
        That process's peak resident memory [bytes] (0 where unknown).
    elements : int
        Elements run over the signal (a row from a stored prefix runs only the rest).
    prefixes : numpy.ndarray or None
        With a shared prefix store: the slots of the new prefixes written.
    finished : float
        ``time.monotonic()`` when the task ended (one clock for the processes of
        one machine, so the main process can time a lane from its send).
    fitted : numpy.ndarray or None
        With ``Chunk.gain_allowed``: shape (P,) eq. 8 of each individual's
        gain-fit candidate (NaN: it has none).
    fit_genes : numpy.ndarray or None
        With ``fitted``: shape (K, 5), the genes the candidates change, one
        per line ``[individual, row, element, code, p]``.
    fit_lines, fit_slots : numpy.ndarray or None
        With ``Chunk.spare``: the candidates' new rows (gene-table lines) and
        the spare slots they were written to.
    """

    fitness: np.ndarray
    scales: list | None
    slots: np.ndarray
    simulated: int
    sim_seconds: float
    seconds: float
    pid: int
    peak_rss: int
    elements: int = 0
    prefixes: np.ndarray | None = None
    finished: float = 0.0
    fitted: np.ndarray | None = None
    fit_genes: np.ndarray | None = None
    fit_lines: np.ndarray | None = None
    fit_slots: np.ndarray | None = None


@dataclass(frozen=True)
class Segmented:
    """A stage with state run over several logs laid end to end, each from rest
    (the reference realisations; the row kernel restarts its states itself)."""

    stage: Any
    starts: tuple[int, ...]

    def run(self, x: np.ndarray) -> np.ndarray:
        """The stage over each log on its own (:func:`edm_sym.engines.simulate.segments`)."""
        return np.concatenate([self.stage.run(x[a:b]) for a, b in segments(len(x), self.starts)])


@dataclass
class Worker:
    """A process's state for one run: context, decoder, stores, weighting.

    ``rows`` is the shared store's rows when the main process manages the
    slots; otherwise the worker keeps its own :class:`SlotStore` (``own``).
    Row prefixes go into the shared prefix store (``prefix_rows``, its slots
    planned by the main process) or into a store of this process
    (:meth:`prefix_store`); slots are reused in place, so simulating a row
    allocates no memory.
    ``trig`` holds sin and cos of each input signal: a sine element reading an
    input directly (the paper's position-dependent friction; its class
    declares ``from_sin_cos``) then costs two multiply-adds instead of a sine
    per sample. ``use_kernel``: simulate with the numba row kernel (default
    when numba is installed), else with the reference realisations. Several
    logs laid end to end (``ctx.starts``) run either way, each from rest.
    """

    ctx: SimContext
    decoder: dict
    rows: np.ndarray | None = field(default=None)
    own: SlotStore | None = field(default=None)
    trig: dict = field(default_factory=dict)
    weights: np.ndarray | None = field(default=None)
    wtoken: str | None = field(default=None)
    dots: dict = field(default_factory=dict)
    use_kernel: bool = field(default=kernel.NUMBA)
    stages: dict = field(default_factory=dict)
    encoders: dict = field(default_factory=dict)
    lock: threading.Lock = field(default_factory=threading.Lock)
    pool: SlotStore | None = field(default=None)
    work: np.ndarray | None = field(default=None)
    pool_pid: int = field(default=0)
    prefix_rows: np.ndarray | None = field(default=None)
    log_bounds: np.ndarray | None = field(default=None)

    def bounds(self) -> np.ndarray:
        """The row kernel's log bounds of this run's signals (computed once)."""
        if self.log_bounds is None:
            self.log_bounds = self.ctx.bounds()
        return self.log_bounds

    def sin_cos(self, k: int) -> tuple[np.ndarray, np.ndarray]:
        """sin and cos of input ``k`` (computed once)."""
        hit = self.trig.get(k)
        if hit is None:
            x = self.ctx.inputs[k]
            hit = self.trig[k] = (libm.sin(x), libm.cos(x))
        return hit

    def stage(self, code: int, p: float) -> Any:
        """Gene ``(code, p)`` as the kernel's steps, or as its realisation (remembered)."""
        key = (code, p)
        hit = self.stages.get(key)
        if hit is None:
            cls, rng = self.decoder[code]
            a = rng.decode(p) if rng is not None else None
            if self.use_kernel:
                make = self.encoders.get(code)
                if make is None:
                    probe = rng.decode(0.5) if rng is not None else None
                    make = self.encoders[code] = kernel.gene_encoder(cls, self.ctx.ts, probe)
                hit = make(a)
            else:
                hit = cls.realise(a, self.ctx.ts)
                if self.ctx.starts and not isinstance(hit, StaticMap):
                    hit = Segmented(hit, self.ctx.starts)
            if len(self.stages) > 100_000:
                self.stages.clear()
            self.stages[key] = hit
        return hit

    def scratch(self) -> np.ndarray:
        """A signal-sized array to compute in (this process's, reused)."""
        if self.work is None or self.work.shape[0] != self.ctx.inputs.shape[1]:
            self.work = np.empty(self.ctx.inputs.shape[1])
        return self.work

    def prefix_store(self) -> SlotStore:
        """This process's store of row prefixes (made on first use, in this process)."""
        if self.pool is None or self.pool_pid != os.getpid():
            n = self.ctx.inputs.shape[1]
            # At least a row's worth of prefixes; the rest as the bound allows.
            self.pool = SlotStore(max(self.ctx.prefix_bytes // (8 * n), 8), n)
            self.pool_pid = os.getpid()
        return self.pool

    def store_for(self, count: int) -> SlotStore:
        """This worker's own row store, with room for ``count`` rows at once."""
        n = self.ctx.inputs.shape[1]
        if self.own is None or self.own.slots < count + 16:
            slots = max(self.ctx.row_bytes // (8 * n), 2 * count + 16)
            self.own = SlotStore(slots, n)
        return self.own

    def set_weights(self, token: str, weights: np.ndarray) -> None:
        """The step's weighting (shape (N,) or (1,)); forgets the inner products."""
        self.weights = np.ascontiguousarray(weights, dtype=float)
        self.wtoken = token
        self.dots.clear()


_WORKERS: OrderedDict[str, Worker] = OrderedDict()
_LOCK = threading.Lock()  # executors may run tasks in threads (dask, thread pools)


def worker_for(token: str, blob: bytes | None = None, ctx: SimContext | None = None,
               rows: np.ndarray | None = None, prefix_rows: np.ndarray | None = None
               ) -> Worker | None:
    """This process's :class:`Worker` of run ``token`` (made from ``ctx`` or ``blob``).

    None when it has none and neither ``ctx`` nor ``blob`` is given.
    """
    with _LOCK:
        hit = _WORKERS.get(token)
        if hit is not None:
            _WORKERS.move_to_end(token)
            return hit
        if ctx is None:
            if blob is None:
                return None
            ctx = pickle.loads(blob)  # noqa: S301 (bytes pickled by the evaluator)
        # Several logs: the row kernel restarts every state at each log's first sample.
        hit = Worker(ctx, ctx.decoder(), rows, prefix_rows=prefix_rows)
        _WORKERS[token] = hit
        while len(_WORKERS) > 4:
            _WORKERS.popitem(last=False)
        return hit


def attach(token: str, blob: bytes, rows: tuple[str, int], prefixes: tuple[str, int], n: int
           ) -> bool:
    """Executor task: share the main process's named stores (same machine) for run ``token``.

    ``rows`` and ``prefixes`` are each a store's path and slot count. False
    when this process cannot open them (another machine): it keeps its own.
    """
    worker = worker_for(token, blob)
    try:
        shared = SlotStore.attach(*rows, n), SlotStore.attach(*prefixes, n)
    except OSError:
        return False
    worker.rows, worker.prefix_rows = shared
    return True


def forget(token: str) -> None:
    """Drop this process's state of run ``token``."""
    with _LOCK:
        _WORKERS.pop(token, None)


def _gram(worker: Worker, rows: list[np.ndarray], keys: list[bytes], target: np.ndarray
          ) -> tuple[np.ndarray, np.ndarray]:
    """Weighted inner products of rows (remembered by their keys) and with the target."""
    m = len(keys)
    gram, gy = np.empty((m, m)), np.empty(m)
    w, memo = worker.weights, worker.dots
    if len(memo) > 100_000:
        memo.clear()
    for i in range(m):
        key = keys[i] + b"|target"
        v = memo.get(key)
        if v is None:
            v = memo[key] = kernel.dot(rows[i], target, w)
        gy[i] = v
        for j in range(i + 1):
            # Canonical order, so the sum is the same bits whichever pair asks.
            a, b = (i, j) if keys[i] <= keys[j] else (j, i)
            key = keys[a] + b"|" + keys[b]
            v = memo.get(key)
            if v is None:
                v = memo[key] = kernel.dot(rows[a], rows[b], w)
            gram[i, j] = gram[j, i] = v
    return gram, gy


def run_chunk(worker: Worker, chunk: Chunk) -> ChunkResult:
    """Evaluate a chunk in ``worker`` (see :class:`Chunk` and :class:`ChunkResult`)."""
    t0 = time.perf_counter()
    table = chunk.table
    keys = [line.tobytes() for line in table]
    sim_seconds, simulated = 0.0, 0
    if chunk.slots is not None:
        store_rows, slots = worker.rows, np.asarray(chunk.slots, dtype=np.int64)
        todo = np.flatnonzero(chunk.simulate)
    else:
        extra = 0 if chunk.gain_allowed is None else int(chunk.free[chunk.score].sum())
        store = worker.store_for(len(table) + extra)  # room for the candidates' rows too
        slots = np.empty(len(table), dtype=np.int64)
        todo_list = []
        for r, key in enumerate(keys):
            slot = store.lookup(key)
            if slot is None:
                todo_list.append(r)
            else:
                slots[r] = slot
        if todo_list:
            fresh = store.allocate(len(todo_list), set(keys))
            for r, slot in zip(todo_list, fresh, strict=True):
                slots[r] = slot
        store_rows, todo = store.rows, np.array(todo_list, dtype=np.intp)
    elements, written, pool = 0, None, None
    if len(todo):
        s0 = time.perf_counter()
        if chunk.prefix_start is not None:
            pool = ChunkPrefixes(worker.prefix_rows, table[todo], chunk.prefix_start[todo],
                                 chunk.prefix_slots[todo], worker.prefix_rows.shape[0])
        elements = simulate_into(worker, table[todo], store_rows, slots[todo], pool)
        if pool is not None:
            written = np.array(pool.written, dtype=np.int64)
        sim_seconds, simulated = time.perf_counter() - s0, len(todo)
        if chunk.slots is None:
            for r in todo:
                worker.own.commit(keys[r], int(slots[r]))
    target = worker.ctx.target
    p = chunk.members.shape[0]
    fitness = np.full(p, np.nan)
    scales: list | None = [None] * p if chunk.free is not None else None
    for k in np.flatnonzero(chunk.score):
        mine = slots[chunk.members[k]]
        f = fitness[k] = kernel.score(store_rows, mine, target, worker.weights, worker.scratch())
        if scales is not None and chunk.free[k].any() and np.isfinite(f) and f != 0.0:
            gram, gy = _gram(worker, [store_rows[s] for s in mine],
                             [keys[r] for r in chunk.members[k]], target)
            scales[k] = row_scales(gram, gy, chunk.free[k], f, target.shape[0])
    fit: tuple = ()
    if chunk.gain_allowed is not None and scales is not None:
        s0 = time.perf_counter()
        *fit, more, ran = _candidates(worker, chunk, keys, slots, store_rows, scales, pool)
        sim_seconds += time.perf_counter() - s0
        simulated += more
        elements += ran
    return ChunkResult(fitness, scales, slots, simulated, sim_seconds,
                       time.perf_counter() - t0, os.getpid(), peak_rss(), elements, written,
                       time.monotonic(), *fit)


def _candidates(worker: Worker, chunk: Chunk, keys: list[bytes], slots: np.ndarray,
                store_rows: np.ndarray, scales: list, pool: ChunkPrefixes | None
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray | None, np.ndarray | None, int, int]:
    """Evaluate the gain-fit candidates of a chunk's scored individuals, where their rows are.

    The candidates are made as the main process would make them
    (:func:`~edm_sym.engines.abstraction.gain_fit.gain_fit` on the same genes),
    their new rows simulated from the prefixes they share with their
    individuals' rows, and scored: the generation needs no second batch.

    Returns
    -------
    fitted : numpy.ndarray
        Shape (P,) eq. 8 of each candidate (NaN: none).
    genes : numpy.ndarray
        Shape (K, 5): the genes each candidate changes, one per line
        ``[individual, row, element, code, p]``.
    lines, spare : numpy.ndarray or None
        With a shared store: the new rows and the spare slots they went to.
    simulated, elements : int
        Rows simulated and elements run.
    """
    table, members = chunk.table, chunk.members
    n = (table.shape[1] - 1) // 2
    fitted = np.full(members.shape[0], np.nan)
    none = (fitted, np.zeros((0, 5)), None, None, 0, 0)
    todo = [k for k, sc in enumerate(scales) if sc is not None]
    if not todo:
        return none
    sub = members[todo]
    pop = Population(table[sub, 0].astype(np.int64), table[sub, 1:1 + n].astype(np.int64),
                     table[sub, 1 + n:].copy())
    places = scale_places(pop.codes, chunk.gain_allowed)
    idx, cand = gain_fit(pop, [scales[k] for k in todo], places, worker.ctx.ranges)
    if not len(idx):
        return none
    # What each candidate changes (a ``through`` made a gain changes its code).
    old_codes, old_ps = pop.codes[idx], pop.ps[idx]
    q, j, i = np.nonzero((cand.codes != old_codes) | (cand.ps != old_ps))
    owner = np.asarray(todo)[idx[q]]
    genes = np.stack([owner, j, i, cand.codes[q, j, i], cand.ps[q, j, i]], axis=1).astype(float)
    c, m = cand.codes.shape[:2]
    lines = row_table(cand.inputs.reshape(-1), cand.codes.reshape(-1, n), cand.ps.reshape(-1, n))
    at = {key: int(s) for key, s in zip(keys, slots.tolist(), strict=True)}
    new: list[int] = []  # lines of the candidates' new rows
    lkeys = line_keys(lines)
    shared = chunk.spare is not None
    for r, key in enumerate(lkeys):
        if key not in at:
            # A row of this worker's own store serves; the shared store's index is the
            # main process's (a row found there again is simply not kept twice).
            slot = None if shared else worker.own.lookup(key)
            at[key] = -1 if slot is None else slot
            if slot is None:
                new.append(r)
    if shared:
        dest = np.asarray(chunk.spare[:len(new)], dtype=np.int64)
        rows = store_rows
        known = {}
        for r in np.flatnonzero(chunk.fit_start > 0).tolist():
            known[prefix_key(table[r], n, int(chunk.fit_start[r]))] = int(chunk.fit_slots[r])
        view = (ChunkPrefixes.reader(worker.prefix_rows, known) if pool is None
                else pool.reading(known))
    else:
        store = worker.own
        dest = np.array(store.allocate(len(new), set(keys) | set(lkeys)),
                        dtype=np.int64)
        rows, view = store.rows, None
    elements = simulate_into(worker, lines[new], rows, dest, view) if new else 0
    for a, r in enumerate(new):
        at[lkeys[r]] = int(dest[a])
        if not shared:
            worker.own.commit(lkeys[r], int(dest[a]))
    target = worker.ctx.target
    for k in range(c):
        mine = np.array([at[key] for key in lkeys[k * m:(k + 1) * m]], dtype=np.int64)
        fitted[todo[int(idx[k])]] = kernel.score(rows, mine, target, worker.weights,
                                                 worker.scratch())
    if shared:
        return fitted, genes, lines[new], dest, len(new), elements
    return fitted, genes, None, None, len(new), elements


def line_keys(table: np.ndarray) -> list[bytes]:
    """The bytes of each line of a 2-d float64 array (at once): the lines' keys."""
    lines = np.ascontiguousarray(table)
    return lines.view(np.dtype((np.void, lines.shape[1] * 8))).ravel().tolist()


def evaluate_chunk(token: str, blob: bytes | None, wtoken: str, wblob: bytes | None,
                   chunk: Chunk) -> ChunkResult | str:
    """Executor task: evaluate a chunk of individuals.

    Parameters
    ----------
    token : str
        The run (a digest of its pickled :class:`SimContext`).
    blob : bytes or None
        The pickled context, sent once per worker: without it a worker that
        lacks the run answers :data:`NEED_CONTEXT`.
    wtoken : str
        The weighting.
    wblob : bytes or None
        The pickled weights, sent once per worker and step (else
        :data:`NEED_WEIGHTS`).
    chunk : Chunk
        The individuals.

    Returns
    -------
    ChunkResult or str
    """
    worker = worker_for(token, blob)
    if worker is None:
        return NEED_CONTEXT
    if worker.wtoken != wtoken:
        if wblob is None:
            return NEED_WEIGHTS
        worker.set_weights(wtoken, pickle.loads(wblob))  # noqa: S301 (from the evaluator)
    with worker.lock:  # an executor may run two tasks of one process in threads
        return run_chunk(worker, chunk)


def peak_rss() -> int:
    """Peak resident memory of this process [bytes] (0 where unknown)."""
    try:
        import resource
    except ImportError:  # pragma: no cover (not POSIX)
        return 0
    return int(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss) * 1024


def warm_up() -> None:
    """Load (or compile, the first time on a machine) the row kernel before any fork.

    A small batch runs every compiled function the GA calls: a group of
    filters, stored prefixes, inputs read in place and the numpy steps' guards.
    """
    if not kernel.NUMBA:
        return
    libm.make_all()
    from edm_sym.core.elements import REGISTRY

    by_name = {cls.name: cls for cls in REGISTRY.values()}
    x = np.linspace(-30.0, 30.0, 8)
    rows = [[("lpf", 10.0), ("tanh", 1.0), ("tan_amp", 1.0), ("asin", None)],
            [("lpf", 20.0), ("log", 0.5), ("power", 1.5)]]
    programs = [kernel.compile_row([by_name[name].realise(a, 1e-3) for name, a in row],
                                   store=True)[0] for row in rows]
    inter = np.empty((sum(p.stores for p in programs), x.shape[0]))
    kernel.run_rows(programs, [0, x], np.empty((2, x.shape[0])), np.arange(2, dtype=np.int64),
                    inter, [range(0, 3), range(3, 5)], sources=x.reshape(1, -1).copy())
    kernel.score(np.zeros((1, 8)), np.zeros(1, dtype=np.int64), x, np.ones(1))
    kernel.dot(x, x, np.ones(1))


def worker_init(parent: int) -> None:
    """Pool initializer: leave Ctrl-C to the main process, and end with it.

    The main process ends a run cleanly on Ctrl-C; a worker finishes its chunk.
    Should the main process be killed outright, a watchdog thread ends the
    worker too instead of leaving it orphaned.
    """
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    # One BLAS thread per lane: N lanes then use N cores, not N times BLAS's own
    # threads spinning on the same cores (docs/abstraction.md#speed-design).
    threadpool_limits(1)

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
