"""Benchmark of the abstraction's genetic algorithm (issue 7).

Prints, with ratios rather than verdicts:

1. the batched, cached evaluation of a population of random 4x5 matrices
   against the plain per-sample Python loop (:func:`edm_sym.engines.simulate.plain_loop`)
   in element-samples per second;
2. a GA run on a synthetic Coulomb + viscous log: evaluations, evaluations per
   second, cache hit rate, element-samples per second;
3. when the plant simulator is available, the default schedule on the
   ``auger`` preset's abstraction log under a time limit, and the RMSE of the
   result on the evaluation log.

Run ``python benchmarks/bench_ga.py [--time-limit S] [--workers W]``.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from edm_sym.core.data import DataLog
from edm_sym.core.elements import default_ranges
from edm_sym.core.matrix import Compensator
from edm_sym.core.result import EdmResult
from edm_sym.engines.abstraction import Evaluator, GenerationInfo, abstract
from edm_sym.engines.abstraction.ga import Operators
from edm_sym.engines.abstraction.schedule import GaSettings
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


def bench_batched(log: DataLog, workers: int) -> None:
    """Batched evaluation of random 4x5 matrices against the plain loop."""
    inputs = ["theta", "omega", "alpha"]
    x = log.stack(inputs)
    y = log.columns["tau_ext"]
    n = len(y)
    ranges = default_ranges(TS, n * TS)
    ops = Operators(GaSettings(through_rate=0.0), len(inputs))
    pop = ops.random_population(np.random.default_rng(1), 64, 5, 4)
    with Evaluator(x, y, TS, ranges, workers=workers) as ev:
        ev.start()
        t0 = time.perf_counter()
        ev.evaluate(pop.inputs, pop.codes, pop.ps)
        cold = time.perf_counter() - t0
        t0 = time.perf_counter()
        ev.evaluate(pop.inputs, pop.codes, pop.ps)
        warm = time.perf_counter() - t0
        samples = ev.stats.element_samples
    batched = samples / cold
    # The plain loop is slow: time it on one matrix over a tenth of the log.
    short = {name: x[i, : n // 10] for i, name in enumerate(inputs)}
    comp = Compensator(pop.matrix(0, inputs), TS, ranges, n * TS)
    t0 = time.perf_counter()
    plain_loop(comp, short)
    plain = 4 * 5 * (n // 10) / (time.perf_counter() - t0)
    print(f"== batched evaluation: 64 random 4x5 matrices, N = {n}, workers = {workers}")
    print(f"cold batch      {cold:8.3f} s   {batched:12.4g} element-samples/s")
    print(f"repeated batch  {warm:8.3f} s   (every row from the cache)")
    print(f"plain loop      {plain:12.4g} element-samples/s")
    print(f"ratio batched / plain loop: {batched / plain:.1f}")
    c_rate = _generated_c_rate(pop, inputs, ranges, x)
    if c_rate is not None:
        print(f"generated C     {c_rate:12.4g} element-samples/s (gcc -O2, double, 8 of the matrices)")
        print(f"ratio generated C / batched: {c_rate / batched:.2f} (aim: within 2)")


def _generated_c_rate(pop, inputs, ranges, x) -> float | None:  # noqa: ANN001
    """Element-samples per second of the generated C of the first 8 matrices (None without gcc)."""
    import importlib.util
    import shutil

    if not shutil.which("gcc"):
        return None
    spec = importlib.util.spec_from_file_location(
        "edm_bench_c_step", Path(__file__).with_name("bench_c_step.py"))
    bench_c = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(bench_c)
    n = x.shape[1]
    log = {name: x[i] for i, name in enumerate(inputs)}
    ns = []
    for k in range(8):
        comp = Compensator(pop.matrix(k, inputs), TS, ranges, n * TS)
        result = EdmResult(comp, "tau_ext")
        ns.append(bench_c.c_ns_per_sample(result, log, repeat=5))
    return 4 * 5 / (1e-9 * float(np.mean(ns)))


def _keep(store: dict):  # noqa: ANN202
    def keep(info: GenerationInfo) -> None:
        store["stats"] = info.stats

    return keep


def bench_ga(log: DataLog, workers: int) -> None:
    """The default schedule on the synthetic log: throughput and cache figures."""
    store: dict = {}
    t0 = time.perf_counter()
    res = abstract(log, target="tau_ext", inputs=["theta", "omega", "alpha"], seed=0,
                   workers=workers, callback=_keep(store))
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
                   time_limit=time_limit, workers=workers, callback=_keep(store))
    wall = time.perf_counter() - t0
    _print_run(f"default schedule on auger (time limit {time_limit:g} s)", res, wall,
               store.get("stats"))
    for kind, log in logs.items():
        tau = log.columns["tau_ext"]
        rmse = fitness(tau - simulate(res, log).total)
        print(f"rmse on the {kind} log {rmse:.6g} N m (uncompensated {fitness(tau):.6g})")


def main() -> None:
    """Run the three benchmarks."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--time-limit", type=float, default=120.0,
                    help="seconds for the plant run (default 120)")
    ap.add_argument("--workers", type=int, default=None, help="processes (default: all cores)")
    ap.add_argument("--skip-plant", action="store_true")
    args = ap.parse_args()
    from edm_sym.engines.abstraction.evaluator import default_workers

    workers = args.workers or default_workers()
    log = synthetic_log()
    bench_batched(log, workers)
    bench_ga(log, workers)
    if not args.skip_plant:
        bench_plant(args.time_limit, workers)


if __name__ == "__main__":
    main()
