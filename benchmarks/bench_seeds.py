"""Seed robustness of the abstraction: K seeds of one config on the auger preset.

Each seed is one run of ``abstract()`` on ``plant:auger/abstraction`` in its
own process with one core (``workers=1``), under the config's own generation
budget (no time limit, like the shipped example), so the CPU seconds of every
run are comparable with today's. Each result is judged on
``plant:auger/evaluation`` against the LuGre baseline (``examples/auger/lugre.json``,
identified on the abstraction log like ``examples/auger/pipeline.toml``).

Prints per seed EDM/LuGre on the evaluation log, the CPU seconds of the run
and the wall time at which EDM/LuGre first fell below ``--threshold`` (the
callback's own evaluation time is not counted as the run's CPU); then
min/median/max over the seeds. ``--json`` prints the same as one JSON object.

    python benchmarks/bench_seeds.py [--config FILE] [--seeds K] [--first-seed S]
                                     [--jobs J] [--workers W] [--searches N]
                                     [--threshold 0.45] [--json]

With ``--searches N`` each run makes N independent searches (``edm abstract
--searches N``); its search 0 is the one-search run of the same seed.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
INPUTS = ("theta_w", "theta_uw", "omega", "alpha")
TARGET = "tau_ext"


def _rmse(residual: np.ndarray) -> float:
    return float(np.sqrt(np.mean(residual**2)))


def _logs():  # noqa: ANN202
    from edm_sym.engines.sources import load_data

    return (load_data("plant:auger/abstraction", require=[*INPUTS, TARGET]),
            load_data("plant:auger/evaluation", require=[*INPUTS, TARGET]))


def lugre_rmse(lugre_file: Path, log) -> float:  # noqa: ANN001
    """RMSE of the LuGre compensator of ``lugre_file`` on ``log``."""
    from edm_sym.engines.lugre import load_lugre, simulate_lugre

    lugre = load_lugre(lugre_file)
    tau = simulate_lugre(lugre.params, log.columns[lugre.velocity_name], log.ts)
    return _rmse(log.columns[TARGET] - tau)


def _children_cpu() -> float:
    """CPU seconds of the ended child processes this process waited for."""
    t = os.times()
    return t.children_user + t.children_system


def run_seed(config: str, seed: int, lugre: float, threshold: float, workers: int,
             out_dir: str | None = None, until: bool = False, searches: int = 1) -> dict:
    """One run; returns its figures (executed in a worker process).

    With ``until`` the run stops at the generation its best first falls
    below ``threshold`` (its other figures are then those of that moment).
    """
    from edm_sym.core.matrix import Compensator
    from edm_sym.engines.abstraction import Parallel, abstract, load_config
    from edm_sym.engines.simulate import simulate

    abst, evl = _logs()
    cfg = load_config(config)
    ranges = cfg.resolve_ranges(abst.ts, len(abst) * abst.ts)
    y_eval = evl.columns[TARGET]
    track = {"first": None, "last": None, "cpu": 0.0, "wall": 0.0}

    def callback(info) -> bool:  # noqa: ANN001
        # Only a new best model is simulated (once per improvement, a few ms each), and
        # the callback's own time is left out of the run's CPU and of the crossing time.
        if track["first"] is not None or info.best_matrix is None:
            return until and track["first"] is not None
        if info.best_matrix == track["last"]:
            return False
        c0, w0 = time.process_time(), time.perf_counter()
        track["last"] = info.best_matrix
        comp = Compensator(info.best_matrix, abst.ts, ranges, len(abst) * abst.ts)
        with np.errstate(all="ignore"):
            ratio = _rmse(y_eval - simulate(comp, evl).total) / lugre
        if ratio < threshold:
            track["first"] = info.elapsed - track["wall"]
        track["cpu"] += time.process_time() - c0
        track["wall"] += time.perf_counter() - w0
        return until and track["first"] is not None

    c0, w0, k0 = time.process_time(), time.perf_counter(), _children_cpu()
    res = abstract(abst, target=TARGET, inputs=INPUTS, config=cfg, seed=seed,
                   parallel=Parallel(workers=workers), callback=callback, searches=searches)
    # With several workers or searches, the processes the run forked and joined count too.
    cpu = time.process_time() - c0 - track["cpu"] + _children_cpu() - k0
    wall = time.perf_counter() - w0
    edm = _rmse(y_eval - simulate(res, evl).total)
    if out_dir is not None:
        from edm_sym.core.result import save_result

        Path(out_dir).mkdir(parents=True, exist_ok=True)
        save_result(res, Path(out_dir) / f"result_seed{seed}.json")
    out = {"seed": seed, "edm": edm, "ratio": edm / lugre, "cpu_s": cpu, "wall_s": wall,
           "stopped_at_threshold": until and track["first"] is not None,
           "below_threshold_s": track["first"],
           "fitness": res.fitness, "step_fitness": [s.fitness for s in res.steps],
           "generations": [s.generations for s in res.steps],
           "evaluations": sum(s.evaluations for s in res.steps),
           "chosen_search": next((s["search"] for s in res.provenance.get("searches", ())
                                  if s["chosen"]), 0)}
    if out_dir is not None:
        (Path(out_dir) / f"seed{seed}.json").write_text(json.dumps(out, sort_keys=True) + "\n")
    return out


def main(argv: list[str] | None = None) -> dict:
    """Run the benchmark; returns the JSON summary."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--config", default=str(ROOT / "examples/auger/abstraction.toml"))
    ap.add_argument("--lugre", default=str(ROOT / "examples/auger/lugre.json"))
    ap.add_argument("--seeds", type=int, default=8, help="K, the number of seeds (default 8)")
    ap.add_argument("--first-seed", type=int, default=1, help="seeds S .. S+K-1 (default 1)")
    ap.add_argument("--jobs", type=int, default=2, help="runs in parallel (default 2)")
    ap.add_argument("--workers", type=int, default=1, help="processes per run (default 1)")
    ap.add_argument("--searches", type=int, default=1,
                    help="independent searches per run (edm abstract --searches; default 1)")
    ap.add_argument("--threshold", type=float, default=0.45,
                    help="EDM/LuGre whose first crossing time is reported (default 0.45)")
    ap.add_argument("--until-threshold", action="store_true",
                    help="stop each run once it falls below --threshold (time to quality only)")
    ap.add_argument("--out-dir", default=None, help="write each seed's result_seedS.json here")
    ap.add_argument("--json", action="store_true", help="print one JSON object")
    args = ap.parse_args(argv)

    _, evl = _logs()
    lugre = lugre_rmse(Path(args.lugre), evl)
    seeds = list(range(args.first_seed, args.first_seed + args.seeds))
    w0 = time.perf_counter()
    with ProcessPoolExecutor(max_workers=args.jobs) as pool:
        futures = [pool.submit(run_seed, args.config, s, lugre, args.threshold, args.workers,
                               args.out_dir, args.until_threshold, args.searches)
                   for s in seeds]
        runs = []
        for f in futures:
            runs.append(f.result())
            if not args.json:
                r = runs[-1]
                below = ("-" if r["below_threshold_s"] is None
                         else f"{r['below_threshold_s']:.0f} s")
                print(f"seed {r['seed']:3d}  EDM/LuGre {r['ratio']:.3f}  cpu {r['cpu_s']:6.0f} s"
                      f"  wall {r['wall_s']:6.0f} s  < {args.threshold:g} at {below}"
                      f"  generations {r['generations']}"
                      + (f"  from search {r['chosen_search']}" if args.searches > 1 else ""),
                      flush=True)
    ratios = [r["ratio"] for r in runs]
    cpus = [r["cpu_s"] for r in runs]
    below = [r["below_threshold_s"] for r in runs]
    summary = {
        "config": args.config, "lugre_rmse_eval": lugre, "seeds": seeds,
        "runs": runs,
        "ratio": {"min": min(ratios), "median": statistics.median(ratios), "max": max(ratios)},
        "cpu_s": {"min": min(cpus), "median": statistics.median(cpus), "max": max(cpus)},
        "below_threshold": {"threshold": args.threshold,
                            "reached": sum(b is not None for b in below),
                            "median_s": (statistics.median([b if b is not None else float("inf")
                                                            for b in below])),
                            "min_s": min((b for b in below if b is not None), default=None),
                            "max_s": (max(below) if all(b is not None for b in below)
                                      else float("inf"))},
        "wall_s": time.perf_counter() - w0,
    }
    if args.json:
        json.dump(summary, sys.stdout, indent=2, sort_keys=True)
        print()
    else:
        q = summary["ratio"]
        c = summary["cpu_s"]
        print(f"EDM/LuGre on the evaluation log over {len(seeds)} seeds: median {q['median']:.3f}"
              f" [{q['min']:.3f}-{q['max']:.3f}]")
        print(f"CPU per run: median {c['median']:.0f} s [{c['min']:.0f}-{c['max']:.0f}]")
        b = summary["below_threshold"]
        print(f"below {args.threshold:g}: {b['reached']}/{len(seeds)} runs, wall time to it "
              f"median {b['median_s']:.0f} s [{b['min_s'] or 0:.0f}-{b['max_s']:.0f}]"
              f" ({args.jobs} runs at a time, {args.workers} worker(s) each)")
        if args.until_threshold:
            print("(--until-threshold: each run stopped there, so EDM/LuGre and CPU are "
                  "those of that moment)")
        print(f"benchmark wall {summary['wall_s']:.0f} s with {args.jobs} jobs")
    return summary


if __name__ == "__main__":
    main()
