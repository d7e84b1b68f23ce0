"""Batched fitness evaluation: chunks of individuals to workers, rows cached where they run.

The fitness of an individual is eq. 8 on ``target - sum(rows)``, and a row's
output depends only on its genes (input code, element codes, parameters). So
every row is kept under a canonical key of its genes, a generation only
simulates the rows no earlier generation has left in a store, and an
individual seen before (an elite) is not evaluated again until the weighting
changes.

A batch of individuals is cut into chunks for the lanes
(:mod:`edm_sym.engines.abstraction.lanes`); a worker simulates the rows it
lacks and sends back a few numbers per individual (eq. 8 and, for the gain
fit, the least-squares scales of its rows and the eq. 8 of the candidate it
made with them: :mod:`~edm_sym.engines.abstraction.candidates`), never a
row. The run's data goes to each worker once, the weighting once per step.

Where the rows are simulated and kept:

* ``workers=1``: in this process, in its own stores.
* default (``executor=None``, ``workers=W > 1``): this process and W - 1
  single-process pools forked after two shared memory maps of slots (rows,
  row prefixes) were made. This process manages the slots; a worker writes
  the rows and prefixes it simulates into theirs and reads any from the
  maps, so a row or prefix simulated once serves every worker (a few
  prefixes shared across pieces are computed by each: see ``balance.groups``).
  The batch goes out in one piece per lane, sized by the lanes' measured speeds
  (:mod:`~edm_sym.engines.abstraction.balance`).
* ``client=`` (a ``dask.distributed.Client``): one lane per cluster worker.
  Workers on this machine open the same two maps (named, in ``/dev/shm``) and
  run as the pool does; otherwise each keeps its own stores, and individuals
  go to the worker that holds most of their rows.
* ``executor=`` (any :class:`~concurrent.futures.Executor`): ``workers``
  unpinned lanes with their own stores.

Results are pure functions of the genes, gathered by individual, so a run's
outcome never depends on the number of workers or on which task finishes first.
"""
from __future__ import annotations

import hashlib
import math
import multiprocessing
import os
import pickle
import time
import warnings
from collections import OrderedDict
from collections.abc import Callable, Mapping, Sequence
from concurrent.futures import Executor, ProcessPoolExecutor
from dataclasses import dataclass
from typing import Any

import numpy as np

from edm_sym.core.elements import REGISTRY, ParamRange
from edm_sym.engines import kernel
from edm_sym.engines.abstraction.balance import (
    Feeder,
    Speeds,
    by_affinity,
    element_costs,
    feed,
    group_costs,
    groups,
    scoring_costs,
)
from edm_sym.engines.abstraction.cache import SlotStore
from edm_sym.engines.abstraction.candidates import CandidatePlan
from edm_sym.engines.abstraction.lanes import (
    DaskLane,
    ExecutorLane,
    LocalLane,
    PipeLane,
    PoolLane,
    SocketLane,
    dask_lanes,
    share_stores,
    socket_lanes,
)
from edm_sym.engines.abstraction.poles import (
    SEARCH_GRID,
    may_have_pole,
    prefix_has_pole,
    with_tangent,
)
from edm_sym.engines.abstraction.prefixes import PrefixPlan, plan_prefixes
from edm_sym.engines.abstraction.stats import EvalStats
from edm_sym.engines.abstraction.worker import (
    NEED_CONTEXT,
    NEED_WEIGHTS,
    Chunk,
    ChunkResult,
    SimContext,
    default_workers,
    evaluate_chunk,
    forget,
    line_keys,
    ping,
    row_table,
    run_chunk,
    warm_up,
    worker_for,
    worker_init,
)

__all__ = ["EvalStats", "Evaluator", "row_table"]

#: How long [s] the worker processes together get to end when a run closes; a
#: straggler (a busy machine, a long chunk) is then killed: it holds no output.
SHUTDOWN_SECONDS = 3.0


@dataclass(frozen=True)
class Evaluation:
    """What :meth:`Evaluator.evaluation` found for a batch of P individuals."""

    #: Shape (P,) eq. 8 values (inf for non-finite outputs, and with ``reject_poles`` for a
    #: row with a tangent pole in the data's range).
    fitness: np.ndarray
    #: With ``rows``: per individual its m row keys and m row outputs (valid until the next
    #: call).
    rows: list[tuple[list[bytes], list[np.ndarray]]] | None = None
    #: With ``free``: per individual its
    #: :func:`~edm_sym.engines.abstraction.gain_fit.row_scales` (or None).
    scales: list | None = None
    #: With ``gain_allowed``: per individual ``(eq. 8, genes)``, its gain-fit candidate's
    #: eq. 8 (NaN: it has none) and the genes it changes, shape (K, 4) ``[row, element,
    #: code, p]``. A candidate's rows have a tangent pole where its individual's rows have
    #: one (the gain fit scales a row after its tangents), so a candidate with a finite
    #: eq. 8 needs no other check.
    fitted: list | None = None


@dataclass(frozen=True)
class Dispatched:
    """What :meth:`Evaluator._dispatch` found for a batch of individuals, whose rows are
    the lines of a table."""

    #: Shape (count,): each individual's eq. 8 (read where it was to be scored).
    fitness: np.ndarray
    #: Per individual its row scales (None without ``free``).
    scales: list
    #: With ``local``: per table line its row outputs; else None.
    rows: list[np.ndarray] | None
    #: Per individual ``(eq. 8, genes)`` of its gain-fit candidate (NaN: it has none).
    fitted: list


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
        Where to evaluate chunks (it is not shut down here): ``workers``
        unpinned lanes.
    workers : int, optional
        Lanes (default: every usable core; ``1``: this process only). Without
        an executor or a client: this process plus ``workers - 1`` processes.
    cache_bytes : int
        Memory bound of a process's row store (at least room for two batches);
        each process's prefix cache gets half as much.
    max_batch_rows : int
        The most distinct rows one batch can hold (sizes the shared store).
    client : distributed.Client, optional
        A dask client: one lane per worker of its cluster (``workers`` is
        then ignored).
    reject_poles : bool
        Give an individual an infinite fitness when one of its rows has a
        tangent pole inside its input's range in the data (see
        :mod:`edm_sym.engines.abstraction.poles`); settable per step
        (:meth:`set_reject_poles`).
    starts : sequence of int
        Where further logs begin in the signals: several logs laid end to
        end, each simulated from rest (the row kernel restarts every state at
        each log's first sample).
    spans : sequence of (float, float), optional
        Per input the range the tangent-pole check reads (``reject_poles``);
        default the range each input takes in ``inputs``. An evaluator of a
        part of the log is given the whole log's.
    full_log : bool
        Whether ``inputs`` is the whole training log (counted in
        :attr:`EvalStats.full_log`); False for a low-fidelity part
        (:mod:`~edm_sym.engines.abstraction.fidelity`).
    """

    #: Batches with fewer individuals to evaluate than this run in this process.
    MIN_PARALLEL = 4
    #: A group joined by shared new prefixes stays within 1 / (SPLIT * lanes) of a batch's
    #: estimated cost (past it, each lane computes the prefix itself: see ``balance.groups``).
    SPLIT = 4

    def __init__(self, inputs: np.ndarray, target: np.ndarray, ts: float,
                 ranges: Mapping[str, ParamRange], *, executor: Executor | None = None,
                 workers: int | None = None, cache_bytes: int = 256 * 2**20,
                 max_batch_rows: int = 1024, client: Any = None, reject_poles: bool = False,
                 starts: Sequence[int] = (), spans: Sequence[tuple[float, float]] | None = None,
                 full_log: bool = True):
        self.inputs = np.ascontiguousarray(inputs, dtype=float)
        self.ranges = dict(ranges)
        self.ts = float(ts)
        with np.errstate(all="ignore"):
            finite = np.where(np.isfinite(self.inputs), self.inputs, np.nan)
            self._span = [(float(np.nanmin(r)), float(np.nanmax(r))) if np.isfinite(r).any()
                          else (math.nan, math.nan) for r in finite]
        if spans is not None:
            self._span = [(float(lo), float(hi)) for lo, hi in spans]
        self.full_log = bool(full_log)
        self.reject_poles = bool(reject_poles)
        self._poles: dict[bytes, bool] = {}
        self.target = np.ascontiguousarray(target, dtype=float)
        n = self.target.shape[0]
        self.n_samples = n
        self.ctx = SimContext(self.inputs, float(ts), dict(ranges), max(1, cache_bytes // 2),
                              self.target, int(cache_bytes), tuple(int(k) for k in starts))
        self._blob = pickle.dumps(self.ctx, protocol=pickle.HIGHEST_PROTOCOL)
        self._token = hashlib.sha256(self._blob).hexdigest() + f"-{os.getpid()}-{id(self):x}"
        self.executor = executor
        self.client = client
        self.workers = int(workers) if workers else default_workers()
        self.shared = (executor is None and client is None and self.workers > 1
                       and "fork" in multiprocessing.get_all_start_methods())
        self.store: SlotStore | None = None
        self.prefixes: SlotStore | None = None
        self._slots = (max(cache_bytes // (8 * n), 2 * max_batch_rows + 16),
                       max(self.ctx.prefix_bytes // (8 * n), 8))
        if self.shared:
            self.store, self.prefixes = SlotStore(self._slots[0], n), SlotStore(self._slots[1], n)
        # Made before any fork, so forked workers inherit it (and the stores).
        self._local = worker_for(self._token, ctx=self.ctx,
                                 rows=self.store.rows if self.shared else None,
                                 prefix_rows=self.prefixes.rows if self.shared else None)
        self.lanes: list = [LocalLane()]
        self._pools: list[ProcessPoolExecutor | PipeLane] = []
        self._started = False
        self._sent_ctx: list[bool] = []
        self._sent_w: list[str | None] = []
        self._mirror: list[OrderedDict] = []
        self.stats = EvalStats()
        self._weights: np.ndarray | float = 1.0
        self._wtoken = ""
        self._wblob = b""
        # Individual key -> (eq. 8, gain-fit scales, whether asked for, its candidate:
        # (eq. 8, changed genes) or None when not asked for).
        self._memo: dict[bytes, tuple[float, Any, bool, tuple | None]] = {}
        self._dots: dict[bytes, float] = {}
        self.set_weights(1.0)

    # -- life cycle -------------------------------------------------------------
    def start(self) -> None:
        """Make the lanes: fork the pool now, before any other thread exists."""
        if self._started:
            return
        self._started = True
        warm_up()  # the row kernel, loaded once before the fork
        if self.client is not None:
            self.lanes = dask_lanes(self.client)
            stores = share_stores(self.lanes, self._token, self._blob, self._slots, self.n_samples)
            if stores is not None:
                self.shared = True
                self.store, self.prefixes = stores
                self._local.rows, self._local.prefix_rows = self.store.rows, self.prefixes.rows
                self.lanes = socket_lanes(self.lanes)
        elif self.executor is not None:
            self.lanes = [ExecutorLane(self.executor) for _ in range(self.workers)]
        elif self.workers > 1:
            with warnings.catch_warnings():
                # Forking is safe here: the pool starts before the run makes threads.
                warnings.simplefilter("ignore", DeprecationWarning)
                if self.shared:
                    ctx = multiprocessing.get_context("fork")
                    self._pools = [PipeLane(ctx, worker_init, (os.getpid(),))
                                   for _ in range(self.workers - 1)]
                    others = list(self._pools)
                else:
                    self._pools = [ProcessPoolExecutor(1, initializer=worker_init,
                                                       initargs=(os.getpid(),))
                                   for _ in range(self.workers - 1)]
                    others = [PoolLane(p) for p in self._pools]
                for f in [lane.submit(ping) for lane in others]:
                    f.result()
            # This process is a lane too: it works while the others do.
            self.lanes = [LocalLane(), *others]
        count = len(self.lanes)
        self._sent_ctx = [lane.local or self.shared for lane in self.lanes]
        self._sent_w = [None] * count
        self._speed = Speeds(count)
        self._mirror = [OrderedDict() for _ in range(count)]

    def close(self) -> None:
        """Free the run's state in every worker; shut down the processes this evaluator started."""
        for lane in self.lanes:
            if isinstance(lane, SocketLane):
                lane.hang_up()
                lane = lane.via
            if isinstance(lane, DaskLane):
                # A cluster's workers outlive the run: drop its data and stores there.
                try:
                    lane.submit(forget, self._token).result()
                except Exception:  # noqa: BLE001 (a worker gone is as good as one cleared)
                    pass
        self._shutdown(wait=True)
        forget(self._token)

    def abort(self) -> None:
        """Shut down own processes without waiting (after an interrupt)."""
        self._shutdown(wait=False)

    def _shutdown(self, wait: bool) -> None:
        for lane in self.lanes:
            if isinstance(lane, SocketLane):
                lane.hang_up()
        pools, self._pools = self._pools, []
        # Every process is told first, then waited for together: N lanes take one
        # timeout at most, not N of them; a straggler (a busy machine) is killed.
        for pool in pools:
            if isinstance(pool, PipeLane):
                pool.stop()
            else:
                pool.shutdown(wait=False, cancel_futures=True)
        deadline = time.monotonic() + SHUTDOWN_SECONDS
        for pool in pools:
            if isinstance(pool, PipeLane):
                pool.shutdown(wait=wait, timeout=max(0.0, deadline - time.monotonic()))
            else:
                pool.shutdown(wait=wait, cancel_futures=True)
        self.lanes = [LocalLane()]

    def __enter__(self) -> Evaluator:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    @property
    def spans(self) -> list[tuple[float, float]]:
        """Per input the range the tangent-pole check reads."""
        return list(self._span)

    # -- weighting ----------------------------------------------------------------
    @property
    def weights(self) -> np.ndarray | float:
        """The current Lambda(q)."""
        return self._weights

    def set_weights(self, weights: np.ndarray | float) -> None:
        """Set Lambda(q) for the following evaluations."""
        self._weights = weights if np.isscalar(weights) else np.asarray(weights, dtype=float)
        arr = np.ascontiguousarray(np.atleast_1d(np.asarray(weights, dtype=float)))
        self._wtoken = hashlib.sha256(arr.tobytes()).hexdigest()[:24]
        self._wblob = pickle.dumps(arr, protocol=pickle.HIGHEST_PROTOCOL)
        self._local.set_weights(self._wtoken, arr)
        self._memo.clear()
        self._dots.clear()

    def set_reject_poles(self, reject: bool) -> None:
        """Reject individuals with a tangent pole in the data's range from now on, or not."""
        if bool(reject) != self.reject_poles:
            self.reject_poles = bool(reject)
            self._memo.clear()

    def has_pole(self, key: bytes, line: np.ndarray) -> bool:
        """Whether the row of a table line has a tangent pole in its input's range (cached)."""
        hit = self._poles.get(key)
        if hit is None:
            n = (line.shape[0] - 1) // 2
            codes = line[1:1 + n].astype(np.int64).tolist()
            hit = False
            if may_have_pole(codes):
                lo, hi = self._span[int(line[0])]
                els = [(REGISTRY[c], self.ranges[REGISTRY[c].name].decode(float(p))
                        if REGISTRY[c].param is not None else None)
                       for c, p in zip(codes, line[1 + n:], strict=True)]
                hit = prefix_has_pole(lo, hi, els, self.ts, SEARCH_GRID)
            if len(self._poles) > 200_000:
                self._poles.clear()
            self._poles[key] = hit
        return hit

    def pole_rows(self, table: np.ndarray, keys: Sequence[bytes]) -> np.ndarray:
        """Which lines of a gene table have a tangent pole in their input's range (cached)."""
        n = (table.shape[1] - 1) // 2
        pole = np.zeros(len(keys), dtype=bool)
        for r in np.flatnonzero(with_tangent(table[:, 1:1 + n])).tolist():
            pole[r] = self.has_pole(keys[r], table[r])
        return pole

    def gram(self, keys: Sequence[bytes], rows: Sequence[np.ndarray]
             ) -> tuple[np.ndarray, np.ndarray]:
        """Weighted inner products of rows (as the workers compute them for the gain fit).

        Parameters
        ----------
        keys, rows : sequence
            Row keys and outputs (as :attr:`Evaluation.rows` gives them).

        Returns
        -------
        gram : numpy.ndarray
            ``G[i, j] = sum(Lambda * r_i * r_j)``, shape (m, m).
        gy : numpy.ndarray
            ``sum(Lambda * r_i * target)``, shape (m,).
        """
        from edm_sym.engines.abstraction.worker import _gram

        return _gram(self._local, [np.asarray(r) for r in rows], list(keys), self.target)

    # -- evaluation -----------------------------------------------------------------
    def individual_keys(self, inputs: np.ndarray, codes: np.ndarray, ps: np.ndarray
                        ) -> list[bytes]:
        """Canonical key of each individual (equal keys: equal compensators)."""
        p, m, n = codes.shape
        table = row_table(inputs.reshape(-1), codes.reshape(-1, n), ps.reshape(-1, n))
        return [table[k * m:(k + 1) * m].tobytes() for k in range(p)]

    def remember(self, inputs: np.ndarray, codes: np.ndarray, ps: np.ndarray,
                 fitness: np.ndarray) -> None:
        """Keep the eq. 8 of individuals evaluated elsewhere (gain-fit candidates)."""
        if len(self._memo) > 50_000:
            self._memo.clear()
        for key, f in zip(self.individual_keys(inputs, codes, ps), fitness.tolist(), strict=True):
            self._memo.setdefault(key, (f, None, False, None))

    def evaluate(self, inputs: np.ndarray, codes: np.ndarray, ps: np.ndarray) -> np.ndarray:
        """Fitness of each individual: :meth:`evaluation`'s ``fitness``.

        Parameters
        ----------
        inputs : numpy.ndarray
            Shape (P, m) input codes.
        codes : numpy.ndarray
            Shape (P, m, n) element codes.
        ps : numpy.ndarray
            Shape (P, m, n) normalised parameters.

        Returns
        -------
        numpy.ndarray
            Shape (P,) eq. 8 values (inf for non-finite outputs, and with
            ``reject_poles`` for a row with a tangent pole in the data's range).
        """
        return self.evaluation(inputs, codes, ps).fitness

    def evaluation(self, inputs: np.ndarray, codes: np.ndarray, ps: np.ndarray, *,
                   rows: bool = False, free: np.ndarray | None = None,
                   gain_allowed: bool | None = None) -> Evaluation:
        """Fitness of each individual, and what the local searches need of it.

        Parameters
        ----------
        inputs, codes, ps : numpy.ndarray
            The individuals, as for :meth:`evaluate`.
        rows : bool
            Also each individual's row keys and row outputs
            (:attr:`Evaluation.rows`). Without shared stores the batch then
            runs in this process.
        free : numpy.ndarray, optional
            Shape (P, m) bool: the rows whose scale the gain fit may change
            (:func:`~edm_sym.engines.abstraction.gain_fit.scale_places`); also
            each individual's scales (:attr:`Evaluation.scales`).
        gain_allowed : bool, optional
            With ``free``: evaluate each individual's gain-fit candidate too,
            in the worker that fits it (:attr:`Evaluation.fitted`; the value
            says whether a ``through`` may become a ``gain``, as for
            :func:`~edm_sym.engines.abstraction.gain_fit.scale_places`).

        Returns
        -------
        Evaluation
        """
        t0 = time.perf_counter()
        if not self._started:
            self.start()
        p, m, n = codes.shape
        table = row_table(inputs.reshape(-1), codes.reshape(-1, n), ps.reshape(-1, n))
        keys = line_keys(table)
        self.stats.individuals += p
        self.stats.row_requests += p * m
        want_scales = free is not None
        gains = gain_allowed if want_scales else None
        out = np.empty(p)
        scales: list = [None] * p
        fitted: list = [None] * p
        ikeys = line_keys(table.reshape(p, -1))
        need = []
        for k in range(p):
            hit = self._memo.get(ikeys[k])
            if hit is not None and (not want_scales or hit[2]) and (
                    gains is None or hit[3] is not None):
                out[k], scales[k], fitted[k] = hit[0], hit[1], hit[3]
            else:
                need.append(k)
        self.stats.scored += len(need)
        if self.full_log:
            self.stats.full_log += len(need)
        row_outputs: list | None = [] if rows else None
        send = list(range(p)) if rows else need
        if send:
            index: dict[bytes, int] = {}
            flat = [k * m + j for k in send for j in range(m)]
            at = [index.setdefault(keys[i], len(index)) for i in flat]
            members = np.array(at, dtype=np.int64).reshape(len(send), m)
            first = np.empty(len(index), dtype=np.int64)
            first[members.reshape(-1)] = flat  # any line of a key: they are equal
            needed = set(need)
            score = np.array([k in needed for k in send], dtype=bool)
            utab = table[first]
            ukeys = list(index)
            sub_free = free[send] if want_scales else None
            poles: list[np.ndarray] = []

            def aside() -> None:  # this process's share of the work while the lanes run
                if self.reject_poles:
                    poles.append(self.pole_rows(utab, ukeys))

            done = self._dispatch(utab, ukeys, members, score, sub_free, rows, aside, gains)
            fit, fits = done.fitness, done.fitted
            if poles:
                pole = poles[0][members].any(axis=1)
                fit = np.where(pole, np.inf, fit)
                for a in np.flatnonzero(pole).tolist():
                    # Its candidate scales rows after their tangents: it has the same poles.
                    if not math.isnan(fits[a][0]):
                        fits[a] = (math.inf, fits[a][1])
            if len(self._memo) > 50_000:
                self._memo.clear()
            for a, k in enumerate(send):
                if score[a]:
                    out[k] = fit[a]
                    scales[k] = done.scales[a] if want_scales else None
                    fitted[k] = None if gains is None else fits[a]
                    self._memo[ikeys[k]] = (out[k], scales[k], want_scales, fitted[k])
            if rows:
                row_outputs = [(keys[k * m:(k + 1) * m],
                                [done.rows[members[a, j]] for j in range(m)])
                               for a, k in enumerate(send)]
        if gains is not None:
            # The candidates count as individuals evaluated, their rows as rows asked for.
            made = sum(1 for f in fitted if f is not None and not math.isnan(f[0]))
            self.stats.individuals += made
            self.stats.row_requests += made * m
            self.stats.scored += made
            if self.full_log:
                self.stats.full_log += made
        self.stats.eval_seconds += time.perf_counter() - t0
        return Evaluation(out, row_outputs, scales if want_scales else None,
                          fitted if gains is not None else None)

    # -- dispatch -------------------------------------------------------------------
    def _dispatch(self, table: np.ndarray, keys: list[bytes], members: np.ndarray,
                  score: np.ndarray, free: np.ndarray | None, local: bool,
                  aside: Callable[[], None] = lambda: None, gains: bool | None = None
                  ) -> Dispatched:
        """Evaluate individuals given as rows of ``table``; their fitness, scales, rows (local)
        (a :class:`Dispatched`).

        ``aside()`` is work of this process that needs no result: it runs
        while the other lanes work (once their pieces are sent). With
        ``gains`` (and ``free``) the lanes also evaluate the gain-fit
        candidates; :attr:`Dispatched.fitted` holds, per individual, its
        candidate's eq. 8 (NaN: none) and the genes it changes.

        With shared stores every lane reads every row, so ``local`` (rows
        wanted back) does not keep the batch in this process.

        About 100 lines on purpose: the hot path of every generation, whose
        slots, prefix and candidate plans the ``settle`` closure records as each
        lane's piece comes in.
        """
        count = len(members)
        alone = (local and not self.shared) or len(self.lanes) == 1 or (
            int(score.sum()) < self.MIN_PARALLEL)
        lanes = [0] if alone else list(range(len(self.lanes)))
        if lanes == [0] and not self.lanes[0].local:
            lanes = []  # no local lane among a client's or an executor's: run here
        slots = missing = plan = None
        keep = set(keys)
        if self.shared:
            slots = np.array(self.store.lookup_many(keys), dtype=np.int64)
            missing = slots < 0
            miss = np.flatnonzero(missing)
            if len(miss):
                slots[miss] = self.store.allocate(len(miss), keep)
        costs = element_costs(table) if self.shared else None
        cplan = CandidatePlan(table, members, score, free, gains,
                              self.store if self.shared else None,
                              self.prefixes if self.shared else None, keep, costs)
        if self.shared:
            plan = plan_prefixes(self.prefixes, table, missing, costs, cplan.reads)
        fitness = np.full(count, np.nan)
        scales: list = [None] * count
        fitted: list = [(math.nan, _NO_GENES)] * count
        new_row = missing.tolist() if self.shared else None
        slot_of = slots.tolist() if self.shared else None

        def settle(idx: list[int], lines: list[int], res: ChunkResult) -> None:
            # A piece's answers, and what it wrote into the shared stores, recorded as
            # soon as it is in (on the shared stores: this process's own piece while the
            # other lanes still work, each other piece as it arrives).
            for a, i in enumerate(idx):
                fitness[i] = res.fitness[a]
                if res.scales is not None:
                    scales[i] = res.scales[a]
            if res.fitted is not None:
                # Each candidate's genes, in the order the lane listed them.
                owner = res.fit_genes[:, 0].astype(np.int64)
                order = np.argsort(owner, kind="stable")
                bounds = np.searchsorted(owner[order], np.arange(len(idx) + 1)).tolist()
                genes = res.fit_genes[order, 1:]
                for a in np.flatnonzero(~np.isnan(res.fitted)).tolist():
                    fitted[idx[a]] = (float(res.fitted[a]), genes[bounds[a]:bounds[a + 1]])
            self._account(res, table.shape[1])
            if self.shared:
                for r in lines:
                    if new_row[r]:
                        self.store.commit(keys[r], slot_of[r])
                if res.prefixes is not None:
                    plan.record(self.prefixes, res.prefixes)
                cplan.record(res)

        if self.shared and len(lanes) > 1:
            results = self._feed(table, members, score, free, slots, missing, plan, lanes, aside,
                                 cplan, settle)  # each piece settled as it comes in
        else:
            aside()
            if len(lanes) > 1:
                parts = by_affinity(keys, members, lanes, self._mirror,
                                    max(64, self.ctx.row_bytes // (8 * self.n_samples)))
            else:
                parts = [(lanes[0] if lanes else 0, list(range(count)))]
            pending = []
            for lane, idx in parts:
                if idx:
                    chunk, lines = self._chunk(table, members, score, free, slots, missing, plan,
                                               idx, cplan)
                    pending.append((lane, idx, lines, chunk))
            if lanes:
                results = self._gather(pending)
            else:
                results = [(idx, lines, run_chunk(self._local, chunk))
                           for _, idx, lines, chunk in pending]
            for idx, lines, res in results:
                settle(idx, lines, res)
        rows = None
        if self.shared:
            plan.release(self.prefixes)
            cplan.release()
            if local:
                rows = [self.store.rows[s] for s in slots.tolist()]
        elif local:
            _, lines, res = results[0]
            rows = [None] * len(keys)
            for line, s in zip(lines, res.slots, strict=True):
                rows[line] = self._local.own.rows[s]
        return Dispatched(fitness, scales, rows, fitted)

    def _chunk(self, table: np.ndarray, members: np.ndarray, score: np.ndarray,
               free: np.ndarray | None, slots: np.ndarray | None, missing: np.ndarray | None,
               plan: PrefixPlan | None, idx: list[int], cplan: CandidatePlan
               ) -> tuple[Chunk, list[int]]:
        """The chunk of individuals ``idx``: their rows, renumbered; which table lines they are."""
        sub = members[idx]
        lines, inverse = np.unique(sub.reshape(-1), return_inverse=True)
        chunk = Chunk(table[lines], inverse.reshape(sub.shape).astype(np.int64), score[idx],
                      None if free is None else free[idx],
                      None if slots is None else slots[lines],
                      None if missing is None else missing[lines],
                      None if plan is None else plan.start[lines],
                      None if plan is None else plan.slots[lines],
                      cplan.gains, *cplan.of(idx, lines))
        return chunk, lines.tolist()

    def _feed(self, table: np.ndarray, members: np.ndarray, score: np.ndarray,
              free: np.ndarray | None, slots: np.ndarray, missing: np.ndarray, plan: PrefixPlan,
              lanes: list[int], aside: Callable[[], None], cplan: CandidatePlan,
              settle: Callable[[list[int], list[int], ChunkResult], None]) -> list:
        """Run a batch on the shared-store lanes, a piece each in proportion to their speeds.

        A lane's speed is the estimated cost it gets through per second,
        averaged over its earlier pieces, so a lane slowed by anything (its
        round trips, another program) gets less (:class:`Feeder`, :func:`feed`).
        Each piece is settled (``settle``) as soon as it is in: this process's own
        before it waits for the others.
        """
        per = scoring_costs(members, score, free) + cplan.cost
        total = float(plan.cost[missing].sum() + per.sum())
        parts = groups(members, plan, missing, per, total / (self.SPLIT * len(lanes)))
        feeder = Feeder(parts, group_costs(parts, members, plan, per), self._speed.of(lanes))
        cost = {lane: load for lane, load in zip(lanes, feeder.loads, strict=True)}
        chunks: dict[int, tuple[Chunk, list[int]]] = {}

        sent_at: dict[int, float] = {}
        ends: list[float] = []  # when each lane ended its piece (this machine's clock)
        begun = time.monotonic()

        def send(lane: int, idx: list[int], again: bool = False) -> Any:
            if not again:
                chunks[lane] = self._chunk(table, members, score, free, slots, missing, plan, idx,
                                           cplan)
            sent_at[lane] = time.monotonic()
            # The weighting goes with every piece until the lane confirms it has it.
            wblob = None if self._sent_w[lane] == self._wtoken and not again else self._wblob
            return self.lanes[lane].submit(evaluate_chunk, self._token,
                                           self._blob if again else None, self._wtoken, wblob,
                                           chunks[lane][0])

        def receive(lane: int, idx: list[int], future: Any) -> tuple:
            t0 = time.perf_counter()
            res = future.result()
            self.stats.wait_seconds += time.perf_counter() - t0
            if res in (NEED_CONTEXT, NEED_WEIGHTS):  # a restarted worker, or a call overtaken
                res = send(lane, idx, again=True).result()
            self._sent_w[lane] = self._wtoken
            seconds = res.seconds
            if self.lanes[lane].same_clock:
                # From send to end, on this machine's clock: the piece's transfer and
                # the worker's start count against the lane too.
                took = res.finished - sent_at[lane]
                if seconds <= took < 10.0 * seconds + 1.0:
                    seconds = took
            self._speed.timed(lane, cost[lane], seconds)
            if self.lanes[lane].same_clock:
                ends.append(res.finished)
            settle(idx, chunks[lane][1], res)
            return idx, chunks[lane][1], res

        def run(idx: list[int]) -> tuple:
            chunk, lines = self._chunk(table, members, score, free, slots, missing, plan, idx,
                                       cplan)
            res = run_chunk(self._local, chunk)
            # From the first send, as the other lanes are timed: the sends and the work
            # aside count against this lane, so its piece leaves room for them.
            ended = time.monotonic()
            self._speed.timed(lanes[here], cost[lanes[here]], ended - min(sent_at.values(),
                                                                         default=begun))
            ends.append(ended)
            settle(idx, lines, res)
            return idx, lines, res

        local = [k for k, lane in enumerate(lanes) if self.lanes[lane].local]
        here = local[0] if local else None
        results = feed(feeder.pieces, lanes, here, send, receive, run, aside)
        if sent_at:
            self.stats.spread_seconds += time.monotonic() - min(sent_at.values())
        if len(ends) == len(results) > 1:
            self.stats.idle_seconds += sum(max(ends) - end for end in ends)
        return results

    def _gather(self, pending: list) -> list:
        """Submit every chunk (this process's last), then collect in submission order.

        A worker that lacks the run's data or the step's weighting says so and
        gets the chunk again with them; a pinned lane gets them with its first
        chunk, so that round trip happens only on unpinned executors.
        """
        out: list = [None] * len(pending)
        todo = list(range(len(pending)))
        first = None  # when the first piece went to another lane
        for attempt in range(3):
            futures = {}
            order = sorted(todo, key=lambda i: self.lanes[pending[i][0]].local)
            for i in order:
                lane, _, _, chunk = pending[i]
                ln = self.lanes[lane]
                blob = None if (self._sent_ctx[lane] and attempt == 0) else self._blob
                if attempt > 0 and ln.local:
                    blob = None
                wblob = (None if self._sent_w[lane] == self._wtoken and attempt == 0
                         else self._wblob)
                if not ln.pinned and attempt == 0:
                    blob = wblob = None
                if first is None and not ln.local:
                    first = time.monotonic()
                futures[i] = ln.submit(evaluate_chunk, self._token, blob, self._wtoken, wblob,
                                       chunk)
            todo = []
            for i in sorted(futures):
                lane, idx, lines, _ = pending[i]
                t0 = time.perf_counter()
                res = futures[i].result()
                if not self.lanes[lane].local:
                    self.stats.wait_seconds += time.perf_counter() - t0
                if res in (NEED_CONTEXT, NEED_WEIGHTS):
                    todo.append(i)
                    continue
                if self.lanes[lane].pinned:
                    self._sent_ctx[lane] = True
                    self._sent_w[lane] = self._wtoken
                out[i] = (idx, lines, res)
            if not todo:
                if first is not None:
                    self.stats.spread_seconds += time.monotonic() - first
                return out
        raise RuntimeError("a worker did not take the run's data")

    def _account(self, res: ChunkResult, width: int) -> None:
        n = (width - 1) // 2
        st = self.stats
        st.rows_missed += res.simulated
        st.rows_simulated += res.simulated
        st.elements_simulated += res.elements
        st.element_samples += res.simulated * n * self.n_samples
        st.sim_seconds += res.sim_seconds
        st.task_seconds += res.seconds
        st.tasks += 1
        if res.peak_rss:
            st.peak_rss[res.pid] = max(st.peak_rss.get(res.pid, 0), res.peak_rss)


#: No genes changed (an individual without a gain-fit candidate).
_NO_GENES = np.zeros((0, 4))


def kernel_in_use() -> bool:
    """Whether rows are simulated by the numba row kernel (else the reference realisations)."""
    return kernel.NUMBA
