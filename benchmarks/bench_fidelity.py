"""Long logs at the speed of short ones: multi-fidelity evaluation against full fidelity.

The same excitation (the plant's abstraction command, 20 s at 1 kHz) is
repeated to longer logs of one simulated plant (the axis keeps moving from
one repetition into the next: one simulation of the repeated command), and
the default schedule abstracts each, with ``fidelity = "full"`` and
``"multi"`` (docs/abstraction.md#multi-fidelity-evaluation), one child
process per run. Per run it prints the wall time of the search and the CPU
time of the process tree (the run's process and the workers it forked;
CPU ratios are robust on a shared machine), their ratios against the first
20 000-sample run of the same seed, individuals scored per second, the
share of them scored on the whole training log, the peak resident memory
of every process that evaluated (the workers), and the held-out RMSE with
its ratio to the full-fidelity run of the same seed and length; then, per
run type, median [min-max] over seeds (the held-out RMSE itself as well as
its ratio: single searches spread widely, and the medians of the two
fidelities compare them apart from which seed went well).

    python benchmarks/bench_fidelity.py [--seeds 1,2,3] [--workers 2]
        [--runs 20000:full,80000:full,80000:multi,320000:full,320000:multi]
        [--preset auger] [--generations G] [--time-limit S] [--tell-observer]
        [--keep DIR] [--out bench_fidelity.json] [--reuse EARLIER.json]

``--runs`` lists ``SAMPLES:FIDELITY`` pairs, run in that order for every
seed (``auto`` is allowed); the ratios are against the first 20 000-sample
run. ``--reuse`` takes earlier runs (another sitting's ``--out``) as done:
they are not run again and serve as references. ``--generations G`` caps
every step at G generations (one block, no patience): a cheaper mode that
measures the cost per generation, not a search to its end; say so beside
its figures. ``--tell-observer`` tells the search the preset's observer
bandwidth, as a ``plant:`` log records it (``edm abstract
--observer-bandwidth`` for a CSV): the static laws' block is then offered
before pruning (the search itself does not read it). The goal: the 320 000-sample multi-fidelity run
within 3x the 20 000-sample time, its held-out RMSE within 5 % of the
full-fidelity run, median over 3 seeds, and at most 1 GiB peak memory per
worker.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
INPUTS = ["theta_w", "theta_uw", "omega", "alpha"]
PERIOD = 20.0  # [s], the abstraction excitation's length


def repeated_log(preset: str, samples: int, seed: int, path: Path) -> Path:
    """The plant's abstraction command repeated to ``samples`` samples at 1 kHz, as a CSV."""
    from edm_sym.engines.plant.excitation import abstraction_command
    from edm_sym.engines.plant.servo import simulate_axis

    def command(t: np.ndarray) -> np.ndarray:
        return np.where(t < 0.0, 0.0, abstraction_command(np.mod(t, PERIOD)))

    log = simulate_axis(preset, command, ts=1e-3, duration=samples * 1e-3, seed=seed)
    cols = {"t": log.t, "theta_w": log.theta_w, "theta_uw": log.theta_uw, "omega": log.omega,
            "alpha": log.alpha, "tau_ext": log.tau_ext}
    np.savetxt(path, np.column_stack(list(cols.values())), delimiter=",",
               header=",".join(cols), comments="", fmt="%.17g")
    return path


def _cpu() -> float:
    own, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + kids.ru_utime + kids.ru_stime


def child(spec: dict) -> None:
    """One run, in this process: prints its figures as one JSON line."""
    from edm_sym import load_data
    from edm_sym.core.result import save_result
    from edm_sym.engines.abstraction import Parallel, abstract
    from edm_sym.engines.abstraction.schedule import parse_config

    doc: dict = {"fidelity": spec["fidelity"]}
    if spec.get("generations"):
        doc["ga"] = {"generations": spec["generations"], "max_blocks": 1, "patience": 0}
    cfg = parse_config(doc, "bench_fidelity")
    data = load_data(spec["log"])
    if spec.get("observer"):
        # As a plant: log records it and edm abstract --observer-bandwidth takes it.
        data = replace(data, scalars={**data.scalars, "observer_bandwidth": spec["observer"]})
    last: dict = {}
    cpu0, wall0 = _cpu(), time.monotonic()
    result = abstract(data, target="tau_ext", inputs=INPUTS, config=cfg, seed=spec["seed"],
                      parallel=Parallel(workers=spec["workers"]), time_limit=spec.get("time_limit"),
                      callback=lambda info: last.update(info=info))
    wall, cpu = time.monotonic() - wall0, _cpu() - cpu0
    save_result(result, spec["result"])
    st, info = last["info"].stats, last["info"]
    print(json.dumps({
        "wall": wall, "cpu": cpu, "search_seconds": info.elapsed,
        "scored": st.scored, "full_log": st.full_log, "rows_simulated": st.rows_simulated,
        "peak_rss": sorted(st.peak_rss.values()),
        "held_out_rmse": result.validation["validation"]["rmse"][0],
        "training_rmse": result.validation["training"]["rmse"][0],
        "fitness": result.fitness, "stop_reason": result.provenance["stop_reason"],
        "mode": (result.provenance.get("fidelity") or {}).get("mode", "full"),
        "generations": [s.generations for s in result.steps]}))


def run(spec: dict) -> dict:
    out = subprocess.run([sys.executable, __file__, "--child", json.dumps(spec)],
                         capture_output=True, text=True, check=False)
    if out.returncode:
        raise SystemExit(f"run {spec} failed:\n{out.stderr[-3000:]}")
    return json.loads(out.stdout.strip().splitlines()[-1])


def _ratios(row: dict, table: list[dict]) -> None:
    """``row``'s wall and CPU ratios to the 20 000-sample run of its seed, and its held-out
    RMSE's ratio to the full-fidelity run of its seed and length, from ``table``."""
    seed, samples = row["seed"], row["samples"]
    base = next((r for r in table if r["seed"] == seed and r["samples"] == 20000), None)
    ref = next((r for r in table if r["seed"] == seed and r["samples"] == samples
                and r["mode"] == "full"), None)
    row["wall_ratio"] = row["wall"] / base["wall"] if base else 1.0
    row["cpu_ratio"] = row["cpu"] / base["cpu"] if base else 1.0
    row["rmse_ratio"] = row["held_out_rmse"] / ref["held_out_rmse"] if ref else None


def _spread(values: list[float]) -> str:
    if not values:
        return "-"
    if len(values) == 1:
        return f"{values[0]:.3g}"
    return f"{statistics.median(values):.3g} [{min(values):.3g}-{max(values):.3g}]"


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--child", help=argparse.SUPPRESS)
    ap.add_argument("--seeds", default="1,2,3")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--runs", default="20000:full,80000:full,80000:multi,320000:full,320000:multi")
    ap.add_argument("--preset", default="auger")
    ap.add_argument("--generations", type=int, default=None)
    ap.add_argument("--time-limit", type=float, default=None)
    ap.add_argument("--tell-observer", action="store_true",
                    help="tell edm abstract the preset's observer bandwidth (g_rtob), as a plant: "
                         "log records it: the static laws' block is offered before pruning")
    ap.add_argument("--keep", default=None, help="keep the logs and results in this directory")
    ap.add_argument("--out", default=None, help="write every run's figures to this JSON file")
    ap.add_argument("--reuse", default=None,
                    help="a JSON file of earlier runs (--out): runs found there are not run again, "
                         "and serve as references of the ratios")
    args = ap.parse_args(argv)
    if args.child:
        child(json.loads(args.child))
        return
    seeds = [int(s) for s in args.seeds.split(",")]
    observer = None
    if args.tell_observer:
        from edm_sym.engines.plant.presets import get_preset

        observer = float(get_preset(args.preset).g_rtob)
    runs = [(int(a), b) for a, b in (r.split(":") for r in args.runs.split(","))]
    work = Path(args.keep or tempfile.mkdtemp(prefix="bench_fidelity-"))
    work.mkdir(parents=True, exist_ok=True)
    print(f"# {args.preset}, default schedule, {args.workers} workers, seeds {args.seeds}"
          + (f", --generations {args.generations}" if args.generations else "")
          + (f", --time-limit {args.time_limit:g}" if args.time_limit else "")
          + (f", observer bandwidth told ({observer:g} rad/s)" if observer else "")
          + f"; load average {os.getloadavg()[0]:.2f}", flush=True)
    table: list[dict] = json.loads(Path(args.reuse).read_text("utf-8")) if args.reuse else []
    # A reused run counts only when it was told the observer as this sitting is.
    table = [r for r in table if r.get("observer") == observer]
    for seed in seeds:
        for samples, fidelity in runs:
            if any(r["seed"] == seed and r["samples"] == samples and r["fidelity"] == fidelity
                   for r in table):
                continue
            log = work / f"{args.preset}-{samples}-s{seed}.csv"
            if not log.exists():
                repeated_log(args.preset, samples, seed, log)
            spec = {"log": str(log), "seed": seed, "workers": args.workers, "fidelity": fidelity,
                    "generations": args.generations, "time_limit": args.time_limit,
                    "observer": observer,
                    "result": str(work / f"result-{samples}-{fidelity}-s{seed}.json")}
            row = {"seed": seed, "samples": samples, "fidelity": fidelity, "observer": observer,
                   **run(spec)}
            _ratios(row, table)
            table.append(row)
            peak = max(row["peak_rss"]) / 2**30 if row["peak_rss"] else float("nan")
            print(f"seed {seed} {samples:>7} {fidelity:>5} ({row['mode']}): wall {row['wall']:7.1f} s "
                  f"(x{row['wall_ratio']:.2f}; search {row['search_seconds']:.1f} s), "
                  f"CPU {row['cpu']:7.1f} s (x{row['cpu_ratio']:.2f}), "
                  f"{row['scored'] / row['search_seconds']:6.1f} scored/s, full-log share "
                  f"{row['full_log'] / max(1, row['scored']):.3f}, peak RSS {peak:.2f} GiB, "
                  f"held-out RMSE {row['held_out_rmse']:.4g}"
                  + (f" (x{row['rmse_ratio']:.3f} of full)" if row["rmse_ratio"] else "")
                  + f", generations {row['generations']}", flush=True)
    print("# median [min-max] over seeds")
    for row in table:  # reused runs too: against the references this table now holds
        _ratios(row, table)
    for samples, fidelity in runs:
        rows = [r for r in table if r["samples"] == samples and r["fidelity"] == fidelity
                and r["seed"] in seeds]
        print(f"{samples:>7} {fidelity:>5}: wall x{_spread([r['wall_ratio'] for r in rows])}, "
              f"CPU x{_spread([r['cpu_ratio'] for r in rows])}, full-log share "
              f"{_spread([r['full_log'] / max(1, r['scored']) for r in rows])}, held-out RMSE "
              f"{_spread([r['held_out_rmse'] for r in rows])} "
              f"(x{_spread([r['rmse_ratio'] for r in rows if r['rmse_ratio']])} of full), peak RSS "
              f"{_spread([max(r['peak_rss']) / 2**30 for r in rows if r['peak_rss']])} GiB")
    if args.out:
        Path(args.out).write_text(json.dumps(table, indent=1) + "\n", encoding="utf-8")


if __name__ == "__main__":
    main()
