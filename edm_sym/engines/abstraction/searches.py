"""Independent searches side by side (``searches`` > 1): one process per search.

One search of the hierarchical schedule synchronises its workers every
generation (the GA ranks a whole generation before it breeds the next), and
on a small machine that synchronisation costs a share of every core
(docs/abstraction.md#measuring-it). K independent searches of the same
schedule, each from its own seed, share nothing until they end: each runs in
a process of its own, forked from this one, with its own row stores, and only
its generation reports and its step bests come back. The search's model is
then chosen among the step bests of all of them
(:func:`finish_searches`).

A search's outcome depends only on the data, the config and its seed
(:func:`search_seeds`), so the run's result does not depend on how many
searches ran at once, nor on which ended first.
"""

from __future__ import annotations

import functools
import multiprocessing
import os
import pickle
from collections.abc import Callable, Mapping, Sequence
from dataclasses import replace
from multiprocessing.connection import wait
from pathlib import Path
from typing import Any

import numpy as np

from edm_sym.core.matrix import Compensator
from edm_sym.core.result import StepRecord
from edm_sym.engines.abstraction.finish import finish
from edm_sym.engines.abstraction.holdout import Holdout
from edm_sym.engines.abstraction.local_search import Candidate, step_candidates
from edm_sym.engines.abstraction.parallel import Parallel
from edm_sym.engines.abstraction.schedule import AbstractionConfig
from edm_sym.engines.abstraction.worker import default_workers, warm_up

#: (search index, its time limit, its callback) -> the search's outcome.
SearchFn = Callable[[int, "float | None", "Callable[[Any], bool | None] | None"], Any]

# The job of the processes forked by side_by_side: set before the fork, so a
# child reads it from its copy of this process (nothing is pickled to start it).
_JOB: SearchFn | None = None
_STOP: Any = None
_INTERRUPT: Any = None


def search_seeds(seed: int, count: int) -> list[int]:
    """The seed of each search: search 0 has the run's own, search k > 0 one drawn from it.

    Drawn with :meth:`numpy.random.SeedSequence.spawn` (independent streams)
    and kept below 2**53, so a result.json reader in any language reads it
    exactly. Search 0 of a run with K searches is the run with one search:
    more searches never lose the model one search finds.
    """
    children = np.random.SeedSequence(int(seed)).spawn(count)
    return [int(seed)] + [int(c.generate_state(1, np.uint64)[0]) >> 11 for c in children[1:]]


def checkpoint_files(checkpoint: Path | None, count: int) -> list[Path | None]:
    """The checkpoint file of each search: ``checkpoint`` itself for one search,
    ``<checkpoint>.search<k>`` for each of several."""
    if checkpoint is None:
        return [None] * count
    if count == 1:
        return [checkpoint]
    return [checkpoint.with_name(f"{checkpoint.name}.search{k}") for k in range(count)]


def run_searches(job: Any, seeds: Sequence[int], files: Sequence[Path | None], resume: bool, *,
                 parallel: Parallel, time_limit: float | None,
                 callback: Callable[[Any], bool | None] | None) -> list[tuple]:
    """Every search of a run, where they run best; each one's outcome.

    Parameters
    ----------
    job : run._SearchJob
        What the searches share; ``job.run(seed, parallel, checkpoint, resume,
        time_limit, callback)`` runs one of them.
    seeds : sequence of int
        Each search's seed (:func:`search_seeds`); one seed: one search, here.
    files : sequence of pathlib.Path or None
        Each search's checkpoint (:func:`checkpoint_files`).
    resume : bool
        Continue each search from its checkpoint.
    parallel : Parallel
        The run's settings, its ``scheduler`` a connected client or None
        (:meth:`Parallel.connected`); each search gets its share of them.
    time_limit, callback
        As for :func:`edm_sym.engines.abstraction.abstract`.

    Returns
    -------
    list of tuple
        One search: ``[(steps, reason)]``. Several: per search ``(steps,
        reason, candidates)`` (:func:`search_candidates`); a search that never
        began has no steps and the reason ``"stopped"`` or ``"interrupted"``.
    """
    count, client, workers = len(seeds), parallel.scheduler, parallel.workers
    if count == 1:
        return [job.run(int(seeds[0]), parallel, files[0], resume, time_limit, callback)]
    if client is not None:
        # Each search a task of its own on the cluster, run by one worker alone.
        task = functools.partial(_one_search, job, seeds, files, resume,
                                 parallel=Parallel(workers=1))
        ended = on_cluster(client, count, task, callback, time_limit)
    else:
        # Side by side on this machine's cores (one process each, sharing nothing);
        # one after another with an executor, each search on all of it.
        lanes = 1 if parallel.executor is not None else (workers or default_workers())
        if lanes > 1:
            warm_up()  # the row kernel, loaded once before the searches are forked
        per = max(1, lanes // min(count, lanes)) if lanes > 1 else workers
        task = functools.partial(_one_search, job, seeds, files, resume,
                                 parallel=replace(parallel, workers=per))
        ended = side_by_side(count, lanes, task, callback, time_limit)
    outcomes: list[tuple] = []
    for value, error in ended:
        if error is not None and not isinstance(error, KeyboardInterrupt):
            raise error
        # Not run: the run was stopped (or interrupted) before this search began.
        outcomes.append(value if value is not None else
                        ([], "interrupted" if error is not None else "stopped", []))
    return outcomes


def _one_search(job: Any, seeds: Sequence[int], files: Sequence[Path | None], resume: bool,
                k: int, limit: float | None, report: Callable[[Any], bool | None], *,
                parallel: Parallel) -> tuple[list[StepRecord], str, list[Candidate]]:
    """Search ``k`` of a run with several, on ``parallel``, and its candidates for the
    search's model.

    The refits of its step bests are made where it ran, beside the other searches'.
    """
    steps, why = job.run(seeds[k], parallel, files[k], resume, limit, report)
    if not steps or why == "interrupted":  # an interrupted run exports no refit (see run.abstract)
        return steps, why, []
    comp = Compensator(steps[-1].matrix, job.ts, job.ranges, job.n * job.ts)
    return steps, why, search_candidates(steps, comp, job.hold, job.cfg)


def finish_searches(groups: Sequence[Sequence[StepRecord]], comp: Compensator, hold: Holdout,
                    cfg: AbstractionConfig, select: str | None = None,
                    cands: Sequence[Sequence[Candidate]] | None = None,
                    clocks: Mapping[int, float] | None = None,
                    laws: Mapping[str, int] | None = None, observer: float | None = None
                    ) -> tuple[Compensator, dict[str, Any], dict[str, Any], int]:
    """:func:`~edm_sym.engines.abstraction.finish.finish` over the step bests of one or several
    searches; also which search won.

    With ``[parsimony] start = "best-step"`` (the default) the step bests of
    every search are the candidates of one choice (each candidate names its
    search); otherwise, of the searches that ran the most steps, the one whose
    last step best has the lowest fitness (eq. 8 of that step's weighting) is
    finished alone. A search without any step (stopped before its first
    population) is passed over.
    ``cands``: each search's :func:`search_candidates`, when already made;
    ``clocks``, ``laws``, ``observer``: as :func:`~edm_sym.engines.abstraction.finish.finish` takes them.
    """
    ran = [k for k, g in enumerate(groups) if g]
    if len(groups) == 1 or not cfg.parsimony.from_step_bests:
        # The search that ran the most steps (a stopped one may not have reached the last).
        chosen = min(ran, key=lambda k: (-len(groups[k]), groups[k][-1].fitness, k))
        steps = groups[chosen]
        out = finish(steps, replace(comp, matrix=steps[-1].matrix), hold, cfg, select,
                     clocks=clocks, laws=laws, observer=observer)
        return (*out, chosen)
    pooled = [s for k in ran for s in groups[k]]
    made = [replace(c, search=k) for k in ran
            for c in (cands[k] if cands is not None else search_candidates(groups[k], comp, hold, cfg))]
    comp, parsimony, final = finish(pooled, comp, hold, cfg, select, candidates_in=made,
                                    clocks=clocks, laws=laws, observer=observer)
    chosen = next(c["search"] for c in parsimony["start_candidates"] if c["chosen"])
    return comp, parsimony, final, chosen


def search_candidates(steps: Sequence[StepRecord], comp: Compensator, hold: Holdout,
                      cfg: AbstractionConfig) -> list[Candidate]:
    """One search's candidates for the search's model: its step bests and their refits
    (:func:`~edm_sym.engines.abstraction.local_search.step_candidates`); made where the
    search ran, side by side with the other searches'."""
    if not (steps and cfg.parsimony.from_step_bests):
        return []
    return step_candidates(steps, replace(comp, matrix=steps[-1].matrix), hold,
                           max_evaluations=cfg.parsimony.refit,
                           reject_poles=cfg.steps[-1].ga.reject_poles)


def side_by_side(count: int, lanes: int, job: SearchFn,
                 callback: Callable[[Any], bool | None] | None,
                 time_limit: float | None) -> list[tuple[Any, BaseException | None]]:
    """Run ``job(k, limit, report)`` for each search k, at most ``lanes`` at a time.

    Parameters
    ----------
    count : int
        Searches.
    lanes : int
        How many run at once: 1 runs them one after another in this process;
        more fork a process per search (where the system can fork).
    job : callable
        One search: its index, its time limit (seconds or None) and the
        callback it reports each generation to (a true return value stops it).
    callback : callable, optional
        The run's callback: called in this process with each search's
        reports, tagged ``search=k`` and ``searches=count``; a true return
        value stops every search at its next generation.
    time_limit : float, optional
        The run's wall time: each search gets ``time_limit * lanes / count``
        (the searches run in ``count / lanes`` waves).

    Returns
    -------
    list of (outcome, exception)
        Per search, in order: its outcome and None, or None and what it
        raised (a search not started because the run was stopped first:
        ``(None, None)``; interrupted first: ``(None, KeyboardInterrupt())``).

    Raises
    ------
    KeyboardInterrupt
        When interrupted before any search evaluated its first population.
    """
    global _JOB, _STOP, _INTERRUPT
    lanes = max(1, min(int(lanes), count))
    limit = None if time_limit is None else time_limit * lanes / count
    if lanes == 1 or "fork" not in multiprocessing.get_all_start_methods():
        return _one_after_another(count, job, callback, limit)
    ctx = multiprocessing.get_context("fork")
    _JOB, _STOP, _INTERRUPT = job, ctx.Event(), ctx.Event()
    out: list[tuple[Any, BaseException | None]] = [(None, None)] * count
    running: dict[Any, tuple[int, Any]] = {}
    queued = list(range(count))
    interrupted = False
    try:
        while queued or running:
            while queued and len(running) < lanes and not _STOP.is_set():
                k = queued.pop(0)
                conn, child = ctx.Pipe(duplex=False)
                proc = ctx.Process(target=_child, args=(child, k, limit, os.getpid()),
                                   name=f"edm_sym-search-{k}")
                proc.start()
                child.close()
                running[conn] = (k, proc)
            if _STOP.is_set():
                queued.clear()
            try:
                ready = wait(list(running))
            except KeyboardInterrupt:
                # Each search saves its checkpoint and returns its best so far (a Ctrl-C
                # reaches them all at once; a SIGTERM to this process only, so they are told).
                interrupted = True
                _INTERRUPT.set()
                _STOP.set()
                continue
            for conn in ready:
                k, proc = running[conn]
                try:
                    kind, value = conn.recv()
                except (EOFError, OSError):
                    kind, value = "error", RuntimeError(f"search {k} ended without an answer "
                                                        f"(exit code {proc.exitcode})")
                except KeyboardInterrupt:
                    interrupted = True
                    _INTERRUPT.set()
                    _STOP.set()
                    continue
                if kind == "info":
                    if _tell(callback, value, k, count):
                        _STOP.set()
                    continue
                out[k] = (value, None) if kind == "done" else (None, value)
                if kind != "done" and not isinstance(value, KeyboardInterrupt):
                    _STOP.set()  # the run fails with this error: the others need not go on
                del running[conn]
                conn.close()
                proc.join()
    finally:
        for conn, (_, proc) in running.items():  # pragma: no cover (an error in this process)
            proc.kill()
            proc.join()
            conn.close()
        _JOB, _STOP, _INTERRUPT = None, None, None
    return _interrupted(out) if interrupted else out


def _tell(callback: Callable[[Any], bool | None] | None, info: Any, k: int, count: int) -> bool:
    """Hand search ``k``'s report to the run's callback, tagged; whether it asks to stop."""
    return callback is not None and bool(callback(replace(info, search=k, searches=count)))


def _interrupted(out: list[tuple[Any, BaseException | None]]
                 ) -> list[tuple[Any, BaseException | None]]:
    """The outcomes of an interrupted run: a search with none was interrupted too (not started,
    or stopped before its first population); with none at all, the interrupt goes on."""
    if all(v is None for v, _ in out):
        raise KeyboardInterrupt
    return [(v, KeyboardInterrupt() if v is None and e is None else e) for v, e in out]


def _one_after_another(count: int, job: SearchFn, callback: Callable[[Any], bool | None] | None,
                       limit: float | None) -> list[tuple[Any, BaseException | None]]:
    """The searches in this process, in order (a stop ends the one running and skips the rest;
    a search's error ends the run)."""
    stopped = False
    out: list[tuple[Any, BaseException | None]] = []
    for k in range(count):
        if stopped:
            out.append((None, None))
            continue

        def report(info: Any, k: int = k) -> bool:
            nonlocal stopped
            if _tell(callback, info, k, count):
                stopped = True
            return stopped

        try:
            out.append((job(k, limit, report), None))
        except KeyboardInterrupt as exc:
            if any(v is not None for v, _ in out):
                out.append((None, exc))
                stopped = True
                continue
            raise
    return out


def _child(conn: Any, k: int, limit: float | None, parent: int) -> None:
    """A forked search: run it, send each report and then its outcome (or its error)."""
    assert _JOB is not None and _STOP is not None and _INTERRUPT is not None
    stop, interrupt = _STOP, _INTERRUPT

    def report(info: Any) -> bool:
        if os.getppid() != parent:  # the run's process is gone: so is its result
            os._exit(1)
        if interrupt.is_set():
            raise KeyboardInterrupt  # the search saves its checkpoint: --resume continues it
        conn.send(("info", info))
        return stop.is_set()

    try:
        msg = ("done", _JOB(k, limit, report))
    except BaseException as exc:  # noqa: BLE001 (sent to the run's process)
        msg = ("error", exc)
    try:
        conn.send(msg)
    except Exception as exc:  # noqa: BLE001 (an outcome that does not pickle)
        conn.send(("error", RuntimeError(f"search {k}: {type(exc).__name__}: {exc}")))
    conn.close()


#: Seconds between two reports a search on a cluster sends (each is a scheduler round trip).
CLUSTER_REPORT_SECONDS = 0.5


def on_cluster(client: Any, count: int, task: Callable[[int, float | None, Callable], Any],
               callback: Callable[[Any], bool | None] | None,
               time_limit: float | None) -> list[tuple[Any, BaseException | None]]:
    """Each search a task of its own on a dask cluster: a worker runs it alone, start to end.

    ``task`` (picklable: it goes to the workers) runs one search as ``job``
    does in :func:`side_by_side`. Its reports come back through a
    ``distributed.Queue`` at most every :data:`CLUSTER_REPORT_SECONDS` (and
    at each step's end), pickled; a true return of ``callback`` sets a
    ``distributed.Event`` the searches look at as they report. Each search
    gets ``time_limit * workers / count`` seconds.

    Returns and raises as :func:`side_by_side`.
    """
    import time
    import uuid

    from distributed import Event, Queue

    name = f"edm_sym-searches-{uuid.uuid4().hex}"
    reports = Queue(name, client=client)
    stop, interrupt = Event(name, client=client), Event(name + "-interrupt", client=client)
    lanes = max(1, min(count, len(client.scheduler_info()["workers"])))
    limit = None if time_limit is None else time_limit * lanes / count
    futures = [client.submit(_cluster_search, task, k, limit, name, pure=False,
                             key=f"{name}-{k}") for k in range(count)]
    interrupted = False

    def forward() -> None:
        for blob in reports.get(batch=True):
            k, info = pickle.loads(blob)
            if _tell(callback, info, k, count):
                stop.set()

    try:
        while not all(f.done() for f in futures):
            try:
                time.sleep(0.1)
                forward()
            except KeyboardInterrupt:
                interrupted = True
                interrupt.set()
                stop.set()
        forward()
        out: list[tuple[Any, BaseException | None]] = []
        for f in futures:
            try:
                out.append((f.result(), None))
            except BaseException as exc:  # noqa: BLE001 (returned to the caller, who raises it)
                out.append((None, exc))
    finally:
        for f in futures:
            f.cancel()
        reports.close()
    return _interrupted(out) if interrupted else out


def _cluster_search(task: Callable[[int, float | None, Callable], Any], k: int,
                    limit: float | None, name: str) -> Any:
    """On a dask worker: run search ``k``, reporting through the run's queue."""
    import time

    from distributed import Event, Queue

    from edm_sym.engines.abstraction.lanes import tune_malloc

    tune_malloc()
    reports = Queue(name)
    stop, interrupt = Event(name), Event(name + "-interrupt")
    last = {"sent": -float("inf"), "step": 0, "stopped": False}

    def report(info: Any) -> bool:
        now = time.monotonic()
        if now - last["sent"] < CLUSTER_REPORT_SECONDS and info.step == last["step"]:
            return last["stopped"]
        last["sent"], last["step"] = now, info.step
        if interrupt.is_set():
            raise KeyboardInterrupt  # the search saves its checkpoint: --resume continues it
        reports.put(pickle.dumps((k, info), protocol=pickle.HIGHEST_PROTOCOL))
        last["stopped"] = stop.is_set()
        return last["stopped"]

    return task(k, limit, report)
