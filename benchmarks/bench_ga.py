"""Benchmark of the abstraction's genetic algorithm: evaluation speed and scaling.

Prints, with ratios measured in the same run rather than verdicts:

1. the batched, cached evaluation of a population of random 4x5 matrices in
   one process (the numba row kernel when installed), against the plain
   per-sample Python loop and the generated C (gcc -O2), per element-sample;
2. scaling on the auger schedule (``examples/auger/abstraction.toml`` on
   ``plant:auger/abstraction``, 20 000 samples): the same first
   ``--generations`` generations with one worker, with ``--workers N``, on a
   ``dask.distributed.LocalCluster`` (``--dask-local K``) and on an existing
   dask scheduler (``--scheduler ADDRESS``); for each, evaluations per
   second, speed-up and parallel efficiency against one worker, row cache
   hit rate, the share of wall time the GA spends outside evaluation, and
   the peak resident memory of each worker process; with ``--bound``, also
   N independent one-worker runs at once: the speed-up this machine allows
   the same work when nothing is serial and nothing is shared;
3. with ``--searches K``, K independent searches of the auger schedule
   (``edm abstract --searches K``): one worker running them one after
   another against ``--workers N`` side by side, a LocalCluster and a
   scheduler (a task each), on the same evaluations;
4. optionally (``--plant``) the default schedule on the auger preset under a
   time limit and the RMSE of the result on the evaluation log.

Run ``python benchmarks/bench_ga.py [--workers N] [--scheduler ADDRESS]
[--dask-local K] [--generations G] [--repeat R] [--bound] [--searches K] [--skip-batched]
[--plant]``
(``--repeat``: the scaling comparison R times, then each figure as median
[min-max]). The machine's
load (``os.getloadavg``) is printed with the figures: on a shared machine
the parallel figures are noisy.
"""

from __future__ import annotations

import argparse
import contextlib
import functools
import multiprocessing
import os
import resource
import time
from pathlib import Path

import numpy as np

from edm_sym.core.data import DataLog
from edm_sym.core.elements import default_ranges
from edm_sym.core.matrix import Compensator
from edm_sym.core.result import EdmResult
from edm_sym.engines.abstraction import Evaluator, GenerationInfo, Parallel, abstract
from edm_sym.engines.abstraction.ga import Operators
from edm_sym.engines.abstraction.schedule import GaSettings
from edm_sym.engines.kernel import NUMBA
from edm_sym.engines.simulate import fitness, plain_loop, simulate

TS = 1e-3


def synthetic_log(n: int = 20_000, seed: int = 0) -> DataLog:
    """Steps then a chirp of velocity; target = Coulomb 1.0 + viscous 0.01 + noise."""
    t = np.arange(n) * TS
    half = t[-1] / 2
    levels = np.array([5, -5, 15, -15, 30, -30, 50, -50, 2, -2.0])
    k = np.minimum((t / (half / len(levels))).astype(int), len(levels) - 1)
    tc = t - half
    chirp = 20 * np.pi * np.sin(np.pi * (10.0 / (t[-1] - half)) * tc**2)
    omega = np.where(t < half, levels[k], chirp)
    alpha = np.gradient(omega, TS)
    theta = np.cumsum(omega) * TS
    rng = np.random.default_rng(seed)
    tau = np.sign(omega) + 0.01 * omega + 0.05 * rng.standard_normal(n)
    cols = {"t": t, "theta": theta, "omega": omega, "alpha": alpha, "tau_ext": tau}
    return DataLog(cols, TS, "synthetic")


def bench_batched(log: DataLog, workers: int = 1, repeat: int = 5) -> None:
    """Batched evaluation of random 4x5 matrices against the plain loop and the C."""
    inputs = ["theta", "omega", "alpha"]
    x = log.stack(inputs)
    y = log.columns["tau_ext"]
    n = len(y)
    ranges = default_ranges(TS, n * TS)
    ops = Operators(GaSettings(through_rate=0.0), len(inputs))
    pop = ops.random_population(np.random.default_rng(1), 64, 5, 4)
    cold, warm_s, samples = _cold_batch(x, y, ranges, pop, workers, repeat)
    batched = samples / cold
    # The plain loop is slow: time it on one matrix over a tenth of the log.
    short = {name: x[i, : n // 10] for i, name in enumerate(inputs)}
    comp = Compensator(pop.matrix(0, inputs), TS, ranges, n * TS)
    t0 = time.perf_counter()
    plain_loop(comp, short)
    plain = 4 * 5 * (n // 10) / (time.perf_counter() - t0)

    print(f"== batched evaluation: 64 random 4x5 matrices, N = {n}, workers = {workers}, "
          f"row kernel: {'numba' if NUMBA else 'reference realisations (numba not installed)'}")
    print(f"cold batch      {cold:8.3f} s   {batched:12.4g} element-samples/s (best of {repeat})")
    print(f"repeated batch  {warm_s:8.3f} s   (every row from the cache)")
    print(f"plain loop      {plain:12.4g} element-samples/s")
    print(f"ratio batched / plain loop: {batched / plain:.1f}")
    c_bins = _generated_c(pop, inputs, ranges, x, count=C_MATRICES)
    if c_bins is not None:
        # The same matrices both ways: the first C_MATRICES of the population.
        part = pop.take(np.arange(C_MATRICES))
        cold_part, _, samples_part = _cold_batch(x, y, ranges, part, workers, repeat)
        mine = samples_part / cold_part
        # The C and the row kernel in turns, the best of each: a shared machine's load
        # changes within seconds, and both should meet the same moments.
        # Each matrix's best time both ways (the C harness times a matrix at a time too).
        c_ns = np.full(C_MATRICES, np.inf)
        kernel_s = np.full(C_MATRICES, np.inf)
        for _ in range(repeat):
            c_ns = np.minimum(c_ns, [_c_step().run_c(b, x.shape[1], 5) for b in c_bins])
            if NUMBA:
                kernel_s = np.minimum(kernel_s, _kernel_seconds(pop, inputs, ranges, x, 5))
        c_ns = float(np.mean(c_ns))
        c_rate = 4 * 5 / (1e-9 * c_ns)
        print(f"generated C     {c_rate:12.4g} element-samples/s (gcc -O2, double, each "
              f"matrix's best of {5 * repeat} CPU times)")
        print(f"evaluator       {mine:12.4g} element-samples/s (the same {C_MATRICES} matrices, "
              f"rows and prefixes stored)")
        print(f"time per element-sample, evaluator / generated C: {c_rate / mine:.2f}")
        if NUMBA:
            rows = C_MATRICES * 5 * 4 * x.shape[1] / float(np.sum(kernel_s))
            print(f"row kernel      {rows:12.4g} element-samples/s (the same matrices, each's "
                  f"best of {5 * repeat}: kernel.simulate_rows, its rows together into a reused "
                  f"array)")
            print(f"time per element-sample, batched rows / generated C: {c_rate / rows:.2f} "
                  f"(aim: <= 1.2)")


def _kernel_seconds(pop, inputs, ranges, x, repeat: int) -> np.ndarray:  # noqa: ANN001
    """Best CPU seconds of kernel.simulate_rows on each of the first C_MATRICES.

    Each matrix's rows go into one output array, reused (as the GA's row
    stores and the C harness's state are): a new array per call would also
    time the kernel's page faults on fresh memory, not the simulation.
    """
    from edm_sym.engines import kernel

    comps = [Compensator(pop.matrix(k, inputs), TS, ranges, x.shape[1] * TS)
             for k in range(C_MATRICES)]
    out = np.empty((len(comps[0].matrix.rows), x.shape[1]))
    best = np.full(len(comps), np.inf)
    for _ in range(repeat):
        for k, comp in enumerate(comps):
            t0 = time.process_time()
            kernel.simulate_rows(comp, comp.matrix.rows, x, out)
            best[k] = min(best[k], time.process_time() - t0)
    return best


C_MATRICES = 16


def _cold_batch(x, y, ranges, pop, workers: int, repeat: int  # noqa: ANN001
                ) -> tuple[float, float, int]:
    """Best time of evaluating ``pop`` with nothing cached, then again (all cached).

    CPU time of this process with one worker (as the C harness measures), else wall time.
    """
    clock = time.process_time if workers == 1 else time.perf_counter
    ops = Operators(GaSettings(through_rate=0.0), x.shape[0])
    warm = ops.random_population(np.random.default_rng(2), 1, 1, 4)
    cold = float("inf")
    for _ in range(repeat):
        # A new evaluator each time (no row cached); its stores made before the clock starts.
        with Evaluator(x, y, TS, ranges, workers=workers) as ev:
            ev.start()
            ev.evaluate(warm.inputs, warm.codes, warm.ps)
            before = ev.stats.element_samples
            t0 = clock()
            ev.evaluate(pop.inputs, pop.codes, pop.ps)
            cold = min(cold, clock() - t0)
            samples = ev.stats.element_samples - before
            t0 = clock()
            ev.evaluate(pop.inputs, pop.codes, pop.ps)
            again = clock() - t0
    return cold, again, samples


def _generated_c(pop, inputs, ranges, x, count: int = 8) -> list[Path] | None:  # noqa: ANN001
    """The generated C of the first matrices, compiled with its harness (None without gcc).

    The binaries live in a temporary folder removed at exit.
    """
    import atexit
    import shutil
    import tempfile

    if not shutil.which("gcc"):
        return None
    n = x.shape[1]
    log = {name: x[i] for i, name in enumerate(inputs)}
    tmp = tempfile.TemporaryDirectory()
    atexit.register(tmp.cleanup)
    bins = []
    for k in range(count):
        comp = Compensator(pop.matrix(k, inputs), TS, ranges, n * TS)
        d = Path(tmp.name) / f"m{k}"
        d.mkdir()
        bins.append(_c_step().build_c(EdmResult(comp, "tau_ext"), log, d))
    return bins


@functools.cache
def _c_step():  # noqa: ANN202
    """benchmarks/bench_c_step.py (its C harness), loaded once."""
    import importlib.util

    spec = importlib.util.spec_from_file_location(
        "edm_bench_c_step", Path(__file__).with_name("bench_c_step.py"))
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _keep(store: dict):  # noqa: ANN202
    def keep(info: GenerationInfo) -> None:
        store["stats"] = info.stats

    return keep


def bench_ga(log: DataLog, workers: int) -> None:
    """The default schedule on the synthetic log: throughput and cache figures."""
    store: dict = {}
    t0 = time.perf_counter()
    res = abstract(log, target="tau_ext", inputs=["theta", "omega", "alpha"], seed=0,
                   parallel=Parallel(workers=workers), callback=_keep(store))
    wall = time.perf_counter() - t0
    rmse = fitness(log.columns["tau_ext"] - simulate(res, log).total)
    _print_run("GA, default schedule, Coulomb + viscous log", res, wall, store.get("stats"))
    print(f"rmse {rmse:.6g} (noise floor 0.05)")


def _print_run(title: str, res, wall: float, ev) -> None:  # noqa: ANN001
    evals = sum(s.evaluations for s in res.steps)
    print(f"== {title}")
    print(f"wall            {wall:8.2f} s   stop: {res.provenance['stop_reason']}")
    print(f"evaluations     {evals:8d}     {evals / wall:10.1f} evaluations/s")
    if ev is not None:
        print(f"row requests    {ev.row_requests:8d}     cache hit rate {ev.hit_rate:.3f}")
        print(f"rows simulated  {ev.rows_simulated:8d}     "
              f"{ev.element_samples / max(ev.sim_seconds, 1e-9):10.4g} element-samples/s "
              f"(in simulation, {ev.sim_seconds:.1f} s)")
    for s in res.steps:
        print(f"  step {s.step} {s.matrix.shape:>4}  generations {s.generations:5d}  "
              f"fitness {s.fitness:.6g}")


AUGER_INPUTS = ("theta_w", "theta_uw", "omega", "alpha")
#: Generations of the untimed run that warms a configuration before it is timed.
WARM_UP = 10


@functools.cache
def _auger():  # noqa: ANN202
    """The auger preset's abstraction log and the shipped config (made once per process)."""
    from edm_sym.engines.abstraction import load_config
    from edm_sym.engines.sources import load_data

    return (load_data("plant:auger/abstraction", require=[*AUGER_INPUTS, "tau_ext"]),
            load_config(Path(__file__).resolve().parent.parent / "examples/auger/abstraction.toml"))


def _auger_run(generations: int, **kwargs) -> dict:  # noqa: ANN003  (the Parallel settings)
    """The auger schedule's first ``generations`` generations; the figures at the last one."""
    log, cfg = _auger()
    seen: dict = {"count": 0}

    def stop(info: GenerationInfo) -> bool:
        seen["count"] += 1
        seen["info"] = info
        return seen["count"] >= generations

    abstract(log, target="tau_ext", inputs=AUGER_INPUTS, config=cfg, seed=1, callback=stop,
             parallel=Parallel(**kwargs))
    info = seen["info"]
    st = info.stats
    main_rss = int(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss) * 1024
    return {"samples": len(log), "generations": seen["count"], "elapsed": info.elapsed,
            "evaluations": st.individuals, "rate": st.individuals / info.elapsed,
            "hit_rate": st.hit_rate, "own_share": 1.0 - st.eval_seconds / info.elapsed,
            "sim_seconds": st.sim_seconds, "task_seconds": st.task_seconds,
            # This process alone: outside its batches' spans on other lanes.
            "alone_seconds": info.elapsed - st.spread_seconds, "wait_seconds": st.wait_seconds,
            "idle_seconds": st.idle_seconds,
            "rows": st.rows_simulated, "elements": st.elements_simulated,
            "peak_rss": dict(st.peak_rss), "main_rss": main_rss}


def _print_scaling(title: str, run: dict, lanes: int, base: dict | None,
                   limit: float | None = None) -> None:
    mib = 2.0**20
    line = (f"{title:34s} {run['rate']:8.1f} evaluations/s  "
            f"({run['evaluations']} in {run['elapsed']:.1f} s)")
    if base is not None:
        speed = run["rate"] / base["rate"]
        line += f"  speed-up {speed:.2f}  efficiency {speed / lanes:.2f}"
    print(line)
    workers = ", ".join(f"{v / mib:.0f}" for _, v in sorted(run["peak_rss"].items()))
    print(f"{'':34s} cache hit rate {run['hit_rate']:.3f}   GA outside evaluation "
          f"{100 * run['own_share']:.1f} %   peak memory per worker [MiB]: {workers} "
          f"(this process {run['main_rss'] / mib:.0f})")
    print(f"{'':34s} rows simulated {run['rows']}, elements run {run['elements']}; summed over "
          f"workers: simulating {run['sim_seconds']:.1f} s, in tasks {run['task_seconds']:.1f} s")
    if base is not None:
        alone = run["alone_seconds"]
        print(f"{'':34s} this process alone {alone:.1f} s ({100 * alone / run['elapsed']:.0f} %: "
              f"GA, planning, single evaluations), waiting for the others "
              f"{run['wait_seconds']:.1f} s; tasks "
              f"{100 * (run['task_seconds'] / base['task_seconds'] - 1):+.0f} % over one worker; "
              f"ceiling with this alone time {ceiling(run, base, lanes):.2f}x")
        if run["idle_seconds"]:
            print(f"{'':34s} lanes idle at a batch's end while another still worked (the "
                  f"imbalance of the cut), summed over lanes: {run['idle_seconds']:.1f} s "
                  f"({idle_share(run, lanes):.0f} % of {lanes} lanes' wall time)")
        if limit is not None:
            print(f"{'':34s} on this machine (--bound {limit:.2f}x): at most "
                  f"{machine_ceiling(run, base, limit):.2f}x with this alone time, "
                  f"{serial_free(run, base, lanes, limit):.2f}x with no serial work at all "
                  f"and this imbalance")


def ceiling(run: dict, base: dict, lanes: int) -> float:
    """The speed-up ``run`` could reach with its serial time and one worker's tasks split evenly.

    ``run``'s wall time outside its batches' parallel spans (this process
    alone: the GA, each batch's planning, single evaluations) plus one
    worker's task time over ``lanes``: Amdahl's bound for this run, with no
    waiting and no task slower than on one worker.
    """
    return base["elapsed"] / (run["alone_seconds"] + base["task_seconds"] / lanes)


def machine_ceiling(run: dict, base: dict, limit: float) -> float:
    """:func:`ceiling` with one worker's tasks at the pace the machine allows (``limit``).

    ``limit`` is :func:`machine_bound`'s speed-up of independent runs: the
    lanes' tasks can go no faster than ``limit`` times one worker's, whatever
    the code does, and this process's alone time comes on top.
    """
    return base["elapsed"] / (run["alone_seconds"] + base["task_seconds"] / limit)


def serial_free(run: dict, base: dict, lanes: int, limit: float) -> float:
    """The speed-up left if this process's serial work took no time, in either run.

    The lanes then run only batches: one worker's tasks at the machine's
    pace (``limit``), plus ``run``'s measured idle time at the batches' ends
    (the imbalance left by the lanes' speeds varying from batch to batch),
    against one worker's tasks alone.
    """
    work = lanes * base["task_seconds"] / limit
    return lanes * base["task_seconds"] / (work + run["idle_seconds"])


def idle_share(run: dict, lanes: int) -> float:
    """The lanes' idle time at batches' ends, in % of ``lanes`` times the run's wall time."""
    return 100 * run["idle_seconds"] / (lanes * run["elapsed"])


def _spread(values: list[float], fmt: str = ".2f") -> str:
    """``median [min-max]``."""
    return (f"{np.median(values):{fmt}} [{min(values):{fmt}}-{max(values):{fmt}}]"
            if len(values) > 1 else f"{values[0]:{fmt}}")


def _alone(generations: int) -> float:
    """Wall time of a one-worker run (in a process of its own)."""
    return _auger_run(generations, workers=1)["elapsed"]


def machine_bound(generations: int, copies: int, alone: float) -> tuple[float, list[float]]:
    """The speed-up ``copies`` cores allow this workload: that many independent runs at once.

    Each of ``copies`` one-worker runs of the same generations runs in a
    process of its own, all at the same time; they share nothing but the
    machine (its memory bandwidth, caches and whatever else the cores share).
    ``copies * alone / mean(their times)`` bounds the speed-up of any parallel
    evaluation of the same work: no serial part, no waiting, no transfer.
    """
    with multiprocessing.get_context("fork").Pool(copies) as pool:
        times = pool.map(_alone, [generations] * copies)
    return copies * alone / float(np.mean(times)), times


def bench_scaling(generations: int, workers: int, scheduler: str | None, dask_local: int,
                  repeat: int = 1, bound: bool = False) -> None:
    """One worker against ``workers``, a LocalCluster and a scheduler, on the same generations.

    With ``repeat`` > 1 the whole comparison runs again, and a summary gives
    each figure as median [min-max] over the repeats. With ``bound`` each
    comparison also measures what the machine allows (:func:`machine_bound`).
    """
    figures: dict[str, dict[str, list[float]]] = {}

    def keep(title: str, run: dict, one: dict, lanes: int = 1,
             limit: float | None = None) -> None:
        fig = figures.setdefault(title, {})
        fig.setdefault("rate", []).append(run["rate"])
        fig.setdefault("speed-up", []).append(run["rate"] / one["rate"])
        fig.setdefault("outside %", []).append(100 * run["own_share"])
        fig.setdefault("elements", []).append(run["elements"])
        if run is not one:
            fig.setdefault("ceiling", []).append(ceiling(run, one, lanes))
            if limit is not None:
                fig.setdefault("on this machine", []).append(machine_ceiling(run, one, limit))
                fig.setdefault("serial-free", []).append(serial_free(run, one, lanes, limit))
        if run["idle_seconds"]:
            fig.setdefault("idle %", []).append(idle_share(run, lanes))

    # Every configuration is timed warm: this process once here (its row kernel loaded,
    # its first batches run), a dask cluster by a short run on it before its timed run
    # (its workers are new processes; the forked pool inherits this process's state).
    _auger_run(WARM_UP, workers=1)
    for k in range(repeat):
        print(f"== scaling: auger schedule, seed 1, its first {generations} generations "
              f"(load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores)"
              + (f", run {k + 1} of {repeat}" if repeat > 1 else ""))
        one = _auger_run(generations, workers=1)
        limit = None  # what the machine allows `workers` lanes (--bound)
        print(f"log of {one['samples']} samples")
        _print_scaling("1 worker (this process)", one, 1, None)
        keep("1 worker", one, one)
        if bound and workers > 1:
            limit, times = machine_bound(generations, workers, one["elapsed"])
            print(f"{workers} independent 1-worker runs at once  "
                  f"{', '.join(f'{t:.1f}' for t in times)} s each (alone {one['elapsed']:.1f} s):"
                  f" the machine allows at most {limit:.2f}x")
            figures.setdefault("machine bound", {}).setdefault("bound", []).append(limit)
        if workers > 1:
            run = _auger_run(generations, workers=workers)
            _print_scaling(f"{workers} workers (this process + {workers - 1} forked)", run,
                           workers, one, limit)
            keep(f"{workers} workers", run, one, workers, limit)
        if dask_local:
            import distributed

            # One single-threaded worker process per core, as docs/abstraction.md says.
            with distributed.LocalCluster(n_workers=dask_local, threads_per_worker=1,
                                          processes=True, dashboard_address=None) as cluster, \
                    distributed.Client(cluster) as client:
                _auger_run(WARM_UP, scheduler=client)
                run = _auger_run(generations, scheduler=client)
            # The bound holds for as many lanes as it ran copies.
            same = limit if dask_local == workers else None
            _print_scaling(f"dask LocalCluster, {dask_local} workers", run, dask_local, one, same)
            keep(f"dask LocalCluster {dask_local}", run, one, dask_local, same)
        if scheduler:
            import distributed

            with distributed.Client(scheduler) as client:
                count = len(client.scheduler_info()["workers"])
                _auger_run(WARM_UP, scheduler=client)
                run = _auger_run(generations, scheduler=client)
            _print_scaling(f"dask scheduler {scheduler}, {count} workers", run, count, one)
            keep(f"dask scheduler, {count} workers", run, one, count)
    if repeat > 1:
        print(f"== summary over {repeat} runs: median [min-max]")
        for title, fig in figures.items():
            if title == "machine bound":
                print(f"{title:28s} {workers} independent runs at once allow "
                      f"{_spread(fig['bound'])}x")
                continue
            print(f"{title:28s} evaluations/s {_spread(fig['rate'], '.0f')}  speed-up "
                  f"{_spread(fig['speed-up'])}  GA outside evaluation "
                  f"{_spread(fig['outside %'], '.1f')} %  elements run "
                  f"{_spread(fig['elements'], '.0f')}"
                  + (f"  ceiling {_spread(fig['ceiling'])}x" if "ceiling" in fig else "")
                  + (f"  lanes idle {_spread(fig['idle %'], '.1f')} %" if "idle %" in fig
                     else "")
                  + (f"  on this machine at most {_spread(fig['on this machine'])}x, with no "
                     f"serial work {_spread(fig['serial-free'])}x" if "serial-free" in fig
                     else ""))


def _auger_searches(evaluations: int, searches: int, seed: int = 1, **kwargs) -> dict:  # noqa: ANN003
    """``searches`` independent searches of the auger schedule, each until ``evaluations``.

    Each search's figures are those of its first report at or past the
    budget (on a cluster a search reports about every 0.5 s, so that report
    may come a little past it; what it ran by then is what is counted, and
    what it runs until every search is there is not). The rate is every
    search's evaluations over the longest search's wall time.
    """
    log, cfg = _auger()
    last: dict[int, GenerationInfo] = {}

    def stop(info: GenerationInfo) -> bool:
        if info.search not in last or last[info.search].stats.individuals < evaluations:
            last[info.search] = info
        return (len(last) == searches
                and min(i.stats.individuals for i in last.values()) >= evaluations)

    abstract(log, target="tau_ext", inputs=AUGER_INPUTS, config=cfg, seed=seed, callback=stop,
             searches=searches, parallel=Parallel(**kwargs))
    done = sum(i.stats.individuals for i in last.values())
    wall = max(i.elapsed for i in last.values())
    peak: dict = {}
    for i in last.values():
        peak.update(i.stats.peak_rss)
    return {"evaluations": done, "elapsed": wall, "rate": done / wall,
            "hit_rate": float(np.mean([i.stats.hit_rate for i in last.values()])),
            "own_share": float(np.mean([1.0 - i.stats.eval_seconds / i.elapsed
                                        for i in last.values()])),
            "peak_rss": peak, "searches": len(last)}


def bench_searches(generations: int, searches: int, workers: int, dask_local: int,
                   scheduler: str | None, repeat: int = 1) -> None:
    """Independent searches side by side against the same searches one after another.

    The work: ``searches`` searches of the auger schedule (seeds drawn from
    seed 1, as ``edm abstract --seed 1 --searches K`` makes them), each
    until the evaluations of the first ``generations`` generations of seed 1.
    One worker runs them one after another (each alone, in this process);
    ``--workers N`` side by side, a process each; a LocalCluster
    (``--dask-local K``) and a scheduler a task each.
    """
    from edm_sym.engines.abstraction.searches import search_seeds

    figures: dict[str, list[float]] = {}
    budget = _auger_run(generations, workers=1)["evaluations"]
    seeds = search_seeds(1, searches)
    mib = 2.0**20

    def show(title: str, run: dict, base: dict | None, lanes: int) -> None:
        line = (f"{title:34s} {run['rate']:8.1f} evaluations/s  ({run['evaluations']} in "
                f"{run['elapsed']:.1f} s)")
        if base is not None:
            speed = run["rate"] / base["rate"]
            figures.setdefault(title, []).append(speed)
            line += f"  speed-up {speed:.2f}  efficiency {speed / lanes:.2f}"
        print(line)
        workers_mib = ", ".join(f"{v / mib:.0f}" for _, v in sorted(run["peak_rss"].items()))
        print(f"{'':34s} cache hit rate {run['hit_rate']:.3f}   GA outside evaluation "
              f"{100 * run['own_share']:.1f} %   peak memory per worker [MiB]: {workers_mib}")

    for k in range(repeat):
        print(f"== independent searches: {searches} searches of the auger schedule (seeds "
              f"{', '.join(map(str, seeds))}), {budget} evaluations each (load average "
              f"{os.getloadavg()[0]:.1f} on {os.cpu_count()} cores)"
              + (f", run {k + 1} of {repeat}" if repeat > 1 else ""))
        alone = [_auger_searches(budget, 1, seed=s, workers=1) for s in seeds]
        one = {"evaluations": sum(r["evaluations"] for r in alone),
               "elapsed": sum(r["elapsed"] for r in alone),
               "hit_rate": float(np.mean([r["hit_rate"] for r in alone])),
               "own_share": float(np.mean([r["own_share"] for r in alone])),
               "peak_rss": alone[-1]["peak_rss"]}
        one["rate"] = one["evaluations"] / one["elapsed"]
        show("1 worker, one after another", one, None, 1)
        if workers > 1:
            run = _auger_searches(budget, searches, workers=workers)
            show(f"{workers} workers, side by side", run, one, workers)
        for title, address, count in (("dask LocalCluster", None, dask_local),
                                      ("dask scheduler", scheduler, 0)):
            if not (address or count):
                continue
            import distributed

            with contextlib.ExitStack() as stack:
                if address is None:
                    cluster = stack.enter_context(distributed.LocalCluster(
                        n_workers=count, threads_per_worker=1, processes=True,
                        dashboard_address=None))
                    address = cluster.scheduler_address
                client = stack.enter_context(distributed.Client(address))
                lanes = len(client.scheduler_info()["workers"])
                _auger_searches(500, searches, scheduler=client)  # warms every worker
                run = _auger_searches(budget, searches, scheduler=client)
            show(f"{title}, {lanes} workers", run, one, lanes)
    if repeat > 1:
        print(f"== summary over {repeat} runs: speed-up of the searches, median [min-max]")
        for title, values in figures.items():
            print(f"{title:34s} {_spread(values)}")


def bench_plant(time_limit: float, workers: int) -> None:
    """The default schedule on the auger preset, judged on the evaluation log."""
    try:
        from edm_sym.engines.plant import simulate_plant
    except ImportError:
        print("== plant: edm_sym.engines.plant is not available; skipped")
        return
    logs = {}
    for kind in ("abstraction", "evaluation"):
        p = simulate_plant("auger", kind, seed=0)
        logs[kind] = DataLog(dict(p.columns), p.ts, f"auger_{kind}")
    inputs = ["theta_w", "theta_uw", "omega", "alpha"]
    store: dict = {}
    t0 = time.perf_counter()
    res = abstract(logs["abstraction"], target="tau_ext", inputs=inputs, seed=0,
                   time_limit=time_limit, parallel=Parallel(workers=workers),
                   callback=_keep(store))
    wall = time.perf_counter() - t0
    _print_run(f"default schedule on auger (time limit {time_limit:g} s)", res, wall,
               store.get("stats"))
    for kind, log in logs.items():
        tau = log.columns["tau_ext"]
        rmse = fitness(tau - simulate(res, log).total)
        print(f"rmse on the {kind} log {rmse:.6g} N m (uncompensated {fitness(tau):.6g})")


def main() -> None:
    """Run the benchmarks."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--workers", type=int, default=None,
                    help="processes for the scaling run (default: all cores)")
    ap.add_argument("--scheduler", default=None, metavar="ADDRESS",
                    help="also run on the workers of this dask scheduler")
    ap.add_argument("--dask-local", type=int, default=0, metavar="K",
                    help="also run on a dask LocalCluster of K worker processes")
    ap.add_argument("--generations", type=int, default=300,
                    help="generations of the auger schedule per scaling run (default 300)")
    ap.add_argument("--repeat", type=int, default=1,
                    help="run the scaling comparison this many times; a median [min-max] summary")
    ap.add_argument("--bound", action="store_true",
                    help="also run --workers independent 1-worker runs at once: the speed-up "
                         "this machine allows the workload")
    ap.add_argument("--searches", type=int, default=0, metavar="K",
                    help="also K independent searches: one worker one after another against "
                         "--workers side by side, --dask-local and --scheduler a task each")
    ap.add_argument("--skip-batched", action="store_true", help="no batched-evaluation figures")
    ap.add_argument("--skip-scaling", action="store_true", help="no scaling runs")
    ap.add_argument("--synthetic", action="store_true",
                    help="also the default schedule on the synthetic Coulomb + viscous log")
    ap.add_argument("--plant", action="store_true",
                    help="also the default schedule on the auger preset under --time-limit")
    ap.add_argument("--time-limit", type=float, default=120.0,
                    help="seconds for the --plant run (default 120)")
    args = ap.parse_args()
    from edm_sym.engines.abstraction.evaluator import default_workers

    workers = args.workers or default_workers()
    log = synthetic_log()
    if not args.skip_batched:
        bench_batched(log)
    if not args.skip_scaling:
        bench_scaling(args.generations, workers, args.scheduler, args.dask_local, args.repeat,
                      args.bound)
    if args.searches > 1:
        bench_searches(args.generations, args.searches, workers, args.dask_local, args.scheduler,
                       args.repeat)
    if args.synthetic:
        bench_ga(log, workers)
    if args.plant:
        bench_plant(args.time_limit, workers)


if __name__ == "__main__":
    main()
