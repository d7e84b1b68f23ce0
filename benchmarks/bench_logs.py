"""Several logs in the GA's fitness: the row kernel against the reference realisations.

Populations of random 4x5 matrices (the GA's own draw of elements) are
evaluated (rows simulated, eq. 8 per individual: ``Evaluator.evaluate`` in
this process) on ``--logs K`` synthetic logs laid end to end, each simulated
from rest, three ways:

1. the row kernel, every state restarting at each log's first sample (what
   ``edm abstract A B ...`` runs);
2. the reference realisations, each log's stages run on their own (what a
   run of several logs ran before the kernel took them);
3. the row kernel on one log of the same length (a single-log run).

Each way gets its own evaluator, warmed on a first population (stores
touched, kernel loaded); then each of ``--repeat`` new populations (the same
for the three) is evaluated cold (its rows are new) and timed in CPU seconds
of this process, the three in turns. Prints median [min-max] seconds and the
ratios reference / kernel and several logs / one log (figures to read, not
tests):

    python benchmarks/bench_logs.py [--logs 4] [--samples 20000] [--population 64]
                                    [--repeat 5] [--seed 1]
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

from edm_sym.core.elements import default_ranges
from edm_sym.engines.abstraction import Evaluator
from edm_sym.engines.abstraction.ga import Operators
from edm_sym.engines.abstraction.schedule import GaSettings
from edm_sym.engines.kernel import NUMBA

TS = 1e-3
INPUTS = ("theta", "omega", "alpha")
#: Each evaluator's row store (its prefix store gets half): room for two batches.
CACHE = 128 * 2**20


def synthetic_logs(count: int, samples: int, seed: int) -> tuple[np.ndarray, np.ndarray, tuple]:
    """``count`` logs of velocity steps and chirps, end to end: inputs, target, starts."""
    rng = np.random.default_rng(seed)
    cuts = np.linspace(0, samples, count + 1).astype(int)
    xs, ys = [], []
    for a, b in zip(cuts, cuts[1:], strict=False):
        t = np.arange(b - a) * TS
        omega = rng.uniform(5, 30) * np.sign(np.sin(2 * np.pi * rng.uniform(0.2, 1) * t)) \
            + 10 * np.sin(2 * np.pi * (0.5 + t) * t)
        theta = np.cumsum(omega) * TS
        alpha = np.gradient(omega, TS)
        xs.append(np.vstack([theta, omega, alpha]))
        ys.append(np.sign(omega) + 0.01 * omega + 0.05 * rng.standard_normal(b - a))
    return np.hstack(xs), np.concatenate(ys), tuple(int(k) for k in cuts[1:-1])


def evaluators(x: np.ndarray, y: np.ndarray, starts: tuple) -> dict[str, Evaluator]:
    """The three ways, each an evaluator of its own (one process)."""
    ranges = default_ranges(TS, x.shape[1] * TS)
    out = {"kernel": Evaluator(x, y, TS, ranges, workers=1, starts=starts, cache_bytes=CACHE),
           "reference": Evaluator(x, y, TS, ranges, workers=1, starts=starts, cache_bytes=CACHE),
           "one log": Evaluator(x, y, TS, ranges, workers=1, cache_bytes=CACHE)}
    out["reference"]._local.use_kernel = False  # the benchmark's switch; runs choose by numba
    return out


def cpu_seconds(ev: Evaluator, pop) -> float:  # noqa: ANN001
    """CPU seconds of this process evaluating ``pop``."""
    t0 = time.process_time()
    with np.errstate(all="ignore"):
        ev.evaluate(pop.inputs, pop.codes, pop.ps)
    return time.process_time() - t0


def _figure(values: list[float]) -> str:
    return f"{statistics.median(values):.3f} [{min(values):.3f}-{max(values):.3f}] s"


def main() -> None:
    """Run the comparison and print the figures."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--logs", type=int, default=4)
    ap.add_argument("--samples", type=int, default=20_000)
    ap.add_argument("--population", type=int, default=64)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args()
    if not NUMBA:
        raise SystemExit("numba is not installed: the row kernel cannot be compared")
    x, y, starts = synthetic_logs(args.logs, args.samples, args.seed)
    ops = Operators(GaSettings(), len(INPUTS))
    rng = np.random.default_rng(args.seed)
    pops = [ops.random_population(rng, args.population, 5, 4) for _ in range(args.repeat + 1)]
    ways = evaluators(x, y, starts)
    runs: dict[str, list[float]] = {name: [] for name in ways}
    try:
        for k, pop in enumerate(pops):
            for name, ev in ways.items():  # in turns: a shared machine's load meets all three
                seconds = cpu_seconds(ev, pop)
                if k:  # the first population warms the evaluator
                    runs[name].append(seconds)
    finally:
        for ev in ways.values():
            ev.close()
    print(f"== {args.population} random 4x5 matrices on {args.logs} logs end to end, "
          f"N = {args.samples} in all, one process, {args.repeat} cold batches each, CPU s")
    print(f"several logs, row kernel             {_figure(runs['kernel'])}")
    print(f"several logs, reference realisations {_figure(runs['reference'])}")
    print(f"one log, row kernel                  {_figure(runs['one log'])}")
    ratio = [r / k for r, k in zip(runs["reference"], runs["kernel"], strict=True)]
    cost = [k / o for k, o in zip(runs["kernel"], runs["one log"], strict=True)]
    print(f"ratio reference / kernel (several logs): {statistics.median(ratio):.2f} "
          f"[{min(ratio):.2f}-{max(ratio):.2f}]")
    print(f"ratio several logs / one log (kernel):   {statistics.median(cost):.2f} "
          f"[{min(cost):.2f}-{max(cost):.2f}]")


if __name__ == "__main__":
    main()
