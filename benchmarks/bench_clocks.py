"""One-way runs from rest: the rows that read time from the angle, and the physics without them.

A lab identifies an axis from runs that each start from rest and turn one
way (velocity steps at a few levels, both directions). Within each run the
unwrapped angle is a clock (docs/abstraction.md#clocks-rows-that-read-time-from-the-angle).
For every family draw D (docs/plant.md#a-family-of-plants-with-known-truth)
and seed S, as a user runs it (the default schedule, no config):

    edm abstract run0.csv ... run7.csv --target tau_ext \\
        --inputs theta_w,theta_uw,omega,alpha --seed S -o RESULT.json
    edm describe RESULT.json --data run8.csv --json
    edm simulate RESULT.json run8.csv / run9.csv

Runs 0-7 (training) step to 2, -3, 5, -8, 12, -20, 30 and -3.5 rad/s in
0.3 s and hold for 2.7 s; runs 8 and 9 (evaluation) to 6 and -12 rad/s.
Each run's current noise has its own seed (from D, S and the run).

Per run it reports: the rows the candidates for the search's model lost as
clock rows (result.json ``parsimony``), the rows on ``theta_uw`` the exported
model keeps, the named physics against the draw's truth
(``bench_naming.compare``: the same tolerances), and the RMSE on the two
evaluation runs. ``--root DIR`` runs another checkout's ``edm`` (the one
before a change, say) on the same runs.

    python benchmarks/bench_clocks.py [--draws 900-905] [--seeds 1,2] [--workers 2]
        [--inputs theta_w,theta_uw,omega,alpha] [--root DIR] [--keep DIR] [--out bench_clocks.json]

Each run takes 1-3 minutes on 2 workers.
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
from bench_naming import _ints, compare, named_physics

ROOT = Path(__file__).resolve().parent.parent
INPUTS = "theta_w,theta_uw,omega,alpha"
TRAINING = (2.0, -3.0, 5.0, -8.0, 12.0, -20.0, 30.0, -3.5)
EVALUATION = (6.0, -12.0)
RAMP, DURATION = 0.3, 3.0


def write_runs(draw: int, seed: int, folder: Path) -> list[Path]:
    """The training and evaluation runs of draw ``draw`` as CSV files in ``folder``."""
    from edm_sym.core.data import write_csv
    from edm_sym.engines.plant.family import draw_plant
    from edm_sym.engines.plant.servo import simulate_axis

    preset = draw_plant(draw).preset
    files = []
    for k, speed in enumerate(TRAINING + EVALUATION):
        def command(t: np.ndarray, w: float = speed) -> np.ndarray:
            return w * np.clip(t / RAMP, 0.0, 1.0)

        log = simulate_axis(preset, command, duration=DURATION, seed=1000 * seed + 10 * draw + k)
        path = folder / f"run{k}.csv"
        write_csv(path, log.columns)
        files.append(path)
    return files


def _edm(root: Path, *args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "edm_sym", *args], capture_output=True,
                          text=True, check=False, cwd=root)


def _rms(x: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.square(x))))


def run_one(draw: int, seed: int, work: Path, root: Path, workers: int, inputs: str = INPUTS
            ) -> dict:
    """One run: the runs written, abstract, describe, simulate."""
    from edm_sym.engines.plant.family import draw_plant
    from edm_sym.engines.sources import load_data

    folder = work / f"family-{draw}_seed{seed}"
    folder.mkdir(parents=True, exist_ok=True)
    files = write_runs(draw, seed, folder)
    train, evaluation = files[:len(TRAINING)], files[len(TRAINING):]
    result = folder / "result.json"
    done = _edm(root, "abstract", *map(str, train), "--target", "tau_ext", "--inputs", inputs,
                "--seed", str(seed), "--workers", str(workers), "--quiet", "-o", str(result))
    if done.returncode != 0:
        return {"draw": draw, "seed": seed, "error": done.stderr.strip()[-2000:]}
    described = _edm(root, "describe", str(result), "--data", str(evaluation[0]), "--json")
    if described.returncode != 0:
        return {"draw": draw, "seed": seed, "error": described.stderr.strip()[-2000:]}
    rmse = []
    for k, path in enumerate(evaluation):
        sim = folder / f"sim{k}.csv"
        if _edm(root, "simulate", str(result), str(path), "-o", str(sim)).returncode != 0:
            return {"draw": draw, "seed": seed, "error": f"edm simulate on {path.name} failed"}
        model = np.asarray(load_data(str(sim)).column("tau_cmp"), dtype=float)
        rmse.append(_rms(np.asarray(load_data(str(path)).column("tau_ext"), dtype=float) - model))
    doc = json.loads(result.read_text("utf-8"))
    par = doc.get("parsimony") or {}
    truth = {k: dict(v) for k, v in draw_plant(draw).truth.items()}
    named = named_physics(json.loads(described.stdout))
    return {"draw": draw, "seed": seed, "truth": truth, "named": named, **compare(named, truth),
            "clock_rows_chosen": len(par.get("clock_rows", [])),
            "clock_rows_candidates": sum(c.get("clock_rows", 0)
                                         for c in par.get("start_candidates", [])),
            "theta_uw_rows": sum(r["input"] == "theta_uw" for r in doc["matrix"]["rows"]),
            "rows": len(doc["matrix"]["rows"]), "rmse": rmse}


def _spread(values: list[float]) -> str:
    if not values:
        return "--"
    return f"{statistics.median(values):.4g} [{min(values):.4g}-{max(values):.4g}]"


def summary(runs: list[dict]) -> None:
    ok = [r for r in runs if "error" not in r]
    print(f"{len(ok)} runs ({len(runs) - len(ok)} failed)")
    print(f"  named physics within tolerance: {sum(r['pass'] for r in ok)}/{len(ok)}")
    print(f"  runs whose candidates lost clock rows: "
          f"{sum(r['clock_rows_candidates'] > 0 for r in ok)}/{len(ok)}; "
          f"the chosen one lost rows: {sum(r['clock_rows_chosen'] > 0 for r in ok)}/{len(ok)}")
    print(f"  exported models with a row on theta_uw: {sum(r['theta_uw_rows'] > 0 for r in ok)}"
          f"/{len(ok)}")
    print(f"  RMSE on the evaluation runs [N m]: "
          f"{_spread([e for r in ok for e in r['rmse']])}")
    errors: dict[str, list[float]] = {}
    for r in ok:
        for name, e in r["errors"].items():
            if e is not None:
                errors.setdefault(name, []).append(abs(e))
    for name in sorted(errors):
        print(f"  |relative error| {name}: {_spread(errors[name])}")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--draws", default="900-905")
    ap.add_argument("--seeds", default="1,2")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--inputs", default=INPUTS, help="edm abstract --inputs (without theta_w: the "
                    "search keeps theta_uw, and the rule after it acts)")
    ap.add_argument("--root", default=str(ROOT), help="the checkout whose edm runs")
    ap.add_argument("--keep", help="folder for the runs and results (default: a temporary one)")
    ap.add_argument("--out", default="bench_clocks.json")
    args = ap.parse_args(argv)
    work = Path(args.keep or tempfile.mkdtemp(prefix="bench_clocks_"))
    runs = []
    for draw in _ints(args.draws):
        for seed in _ints(args.seeds):
            r = run_one(draw, seed, work, Path(args.root).resolve(), args.workers, args.inputs)
            runs.append(r)
            if "error" in r:
                print(f"family-{draw} seed {seed}: error {r['error'][-300:]}", flush=True)
                continue
            print(f"family-{draw} seed {seed}: {'pass' if r['pass'] else 'FAIL: '}"
                  f"{'; '.join(r['failures'])} | clock rows lost: chosen "
                  f"{r['clock_rows_chosen']}, candidates {r['clock_rows_candidates']} | "
                  f"theta_uw rows kept {r['theta_uw_rows']} of {r['rows']} | RMSE "
                  f"{', '.join(f'{e:.4g}' for e in r['rmse'])} N m", flush=True)
    Path(args.out).write_text(json.dumps(runs, indent=1), encoding="utf-8")
    summary(runs)
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
