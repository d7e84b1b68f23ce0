"""Named physics against the truth on the family of plants with known truth.

The family: docs/plant.md#a-family-of-plants-with-known-truth.

For every draw D and seed S, as a user runs it (the default schedule, no config):

    edm abstract plant:family-D/abstraction@S --target tau_ext \\
        --inputs theta_w,theta_uw,omega,alpha --seed S -o RESULT.json
    edm describe RESULT.json --data plant:family-D/evaluation --json
    edm simulate RESULT.json plant:family-D/evaluation -o SIM.csv

then the named physics (:func:`named_physics`) is compared with the draw's
truth: Coulomb level within 10 %, Stribeck peak (the excess over Coulomb at
rest) within 20 % where the plant has one (stiction >= 1.2 Coulomb), viscous
within 20 %, inertia error within 20 %, ripple order exact and amplitude
within 20 %, and no kind the plant lacks (an offset or an unclassified term
that describe lists counts as one). A run passes when every one holds.

The fit: the RMSE of the model's output (``edm simulate``) on the evaluation
log, divided by

* ``truth``: the RMSE of the true disturbance through Q(s)
  (:func:`edm_sym.engines.plant.family.true_law`, the noise floor: a few
  mN m);
* ``static``: the RMSE of the documented static laws with the true parameters
  through Q(s) (:func:`edm_sym.engines.plant.anchor.law_torque`: what an
  engineer who knew the parameters would predict; the presliding at
  reversals is outside it). Where the static laws are within
  :data:`ABOVE_FLOOR` of the noise floor, 0.75 of them is below the floor:
  the summary gives the share at or below them and its median also over the
  other runs.

Whether the excitation identifies a Stribeck hump at all: the engineer's
least squares on the run's own training log with the Stribeck velocity
scanned, not given (:func:`anchor_stribeck`). On a plant that sticks and
slips at the staircase's slow plateaus it misses the peak too; the summary
gives the pass share over the other runs beside the share over all of them
(the pass criterion is the same for every run). It also counts the Stribeck
peaks within tolerance apart for humps at most :data:`LOW_HUMP` times the
presets' slowest plateau (pi/2 rad/s) and above it (:func:`stribeck_by_speed`).

Draws 0-3 are the tuning draws (rules may be tuned on them), draws 100-111 the
measured ones; the summary gives each set separately: the share of runs with
all physics within tolerance, per parameter the relative error median
[min-max], and the RMSE ratios median [min-max].

    python benchmarks/bench_naming.py [--draws 0-3,100-111] [--seeds 1,2,3]
        [--jobs 2] [--workers 1] [--time-limit S] [--generations G | --max-blocks B]
        [--out bench_naming.json] [--keep DIR] [--reuse] [--by {behaviour,rows}]

The full run (16 draws x 3 seeds under the default schedule) takes hours on
2 cores. A quick check of the machinery, one draw and one seed, 5
generations a step:

    python benchmarks/bench_naming.py --draws 0 --seeds 1 --generations 5 --jobs 1
"""

from __future__ import annotations

import argparse
import csv
import json
import statistics
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from edm_sym.engines.plant.family import FamilyPlant

ROOT = Path(__file__).resolve().parent.parent
INPUTS = "theta_w,theta_uw,omega,alpha"
TUNING = tuple(range(0, 4))
MEASURED = tuple(range(100, 112))
#: (kind, parameter, relative tolerance) compared with the truth.
STRIBECK_TOLERANCE = 0.20
TOLERANCES = (("coulomb", "level", 0.10), ("stribeck", "peak", STRIBECK_TOLERANCE),
              ("viscous", "coefficient", 0.20), ("acceleration", "inertia", 0.20),
              ("spatial", "amplitude", 0.20))
#: The Stribeck velocities [rad/s] the engineer's least squares scans (:func:`anchor_stribeck`).
STRIBECK_SCAN = tuple(float(v) for v in np.geomspace(0.3, 30.0, 80))
#: A hump whose true Stribeck velocity is at most this many times the presets' staircase's
#: slowest plateau (pi/2 rad/s) is a low one (:func:`stribeck_by_speed`).
LOW_HUMP = 1.3
#: A run's static laws are above its noise floor when their RMSE on the evaluation log is
#: at least this many times the true disturbance's: only then is 0.75 times the static laws'
#: RMSE (the goal's median) above the floor, where a model can reach it (:func:`summary`).
ABOVE_FLOOR = 4.0 / 3.0
#: Parameters that add up when several terms name the same kind.
ADDITIVE = {"level", "coefficient", "inertia", "peak"}


def named_physics(describe_json: dict) -> dict[str, dict[str, float]]:
    """The physics a describe JSON names, by kind: ``{kind: {parameter: value}}``.

    Reads ``doc["physics"]["terms"]`` (the whole model's naming) when the key
    exists, else every row's ``terms``. Terms of one kind are summed (levels,
    coefficients, inertias, Stribeck peaks); for ``spatial`` the term of the
    largest amplitude is kept, its order its ``dominant_cycles`` when given;
    ``stribeck`` keeps the Stribeck velocity of its largest peak. Every other
    kind (``offset``, ``unclassified``) is listed with a ``count``.
    """
    physics = describe_json.get("physics")
    if isinstance(physics, dict) and "terms" in physics:
        terms = physics["terms"]
    else:
        terms = [t for row in describe_json.get("rows", []) for t in row.get("terms", [])]
    out: dict[str, dict[str, float]] = {}
    for term in terms:
        kind = term["kind"]
        params = {k: float(v[0]) for k, v in term.get("parameters", {}).items()
                  if isinstance(v, list | tuple) and isinstance(v[0], int | float)}
        have = out.setdefault(kind, {"count": 0.0})
        have["count"] += 1
        if kind == "spatial":
            if "dominant_cycles" in params:
                params["cycles_per_revolution"] = params["dominant_cycles"]
            if "amplitude" not in have or abs(params.get("amplitude", 0.0)) > abs(have["amplitude"]):
                have.update({k: v for k, v in params.items() if k != "count"})
            continue
        biggest = abs(params.get("peak", 0.0)) >= abs(have.get("peak", 0.0))
        for key, value in params.items():
            if key in ADDITIVE:
                have[key] = have.get(key, 0.0) + value
            elif key not in have or biggest:
                have[key] = value
    return out


def compare(named: dict[str, dict[str, float]], truth: dict[str, dict[str, float]]) -> dict:
    """Relative errors per parameter, missing and extra kinds, and whether the run passes."""
    errors: dict[str, float | None] = {}
    failures: list[str] = []
    for kind, key, tol in TOLERANCES:
        if kind not in truth:
            continue
        want = truth[kind][key]
        got = named.get(kind, {}).get(key)
        name = f"{kind}.{key}"
        errors[name] = None if got is None else got / want - 1.0
        if got is None:
            failures.append(f"{kind} missing")
        elif abs(got / want - 1.0) > tol:
            failures.append(f"{name} {got:.4g} vs {want:.4g}")
    if "spatial" in truth and "spatial" in named:
        k = named["spatial"].get("cycles_per_revolution", float("nan"))
        want = truth["spatial"]["cycles_per_revolution"]
        if not abs(k - want) <= 0.01:
            failures.append(f"ripple order {k:.3g} vs {want:g}")
    extra = sorted(set(named) - set(truth))
    failures += [f"extra {kind}" for kind in extra]
    return {"errors": errors, "extra": extra, "failures": failures, "pass": not failures}


def _edm(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "edm_sym", *args], capture_output=True,
                          text=True, check=False, cwd=ROOT)


def _rms(x: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.square(x))))


def run_one(draw: int, seed: int, work: str, opts: dict) -> dict:
    """One run: abstract, describe, simulate; the comparison and the RMSE ratios."""
    from edm_sym.engines.plant import simulate_plant
    from edm_sym.engines.plant.anchor import law_torque
    from edm_sym.engines.plant.family import draw_plant, true_law

    folder = Path(work) / f"family-{draw}_seed{seed}"
    folder.mkdir(parents=True, exist_ok=True)
    result, sim = folder / "result.json", folder / "sim.csv"
    data = f"plant:family-{draw}/abstraction@{seed}"
    evaluation = f"plant:family-{draw}/evaluation"
    args = ["abstract", data, "--target", "tau_ext", "--inputs", INPUTS, "--seed", str(seed),
            "--workers", str(opts["workers"]), "--quiet", "-o", str(result)]
    if opts.get("time_limit"):
        args += ["--time-limit", str(opts["time_limit"])]
    if opts.get("config"):
        cfg = folder / "budget.toml"
        cfg.write_text(opts["config"], encoding="utf-8")
        args += ["--config", str(cfg)]
    start = time.perf_counter()
    if not (opts.get("reuse") and result.is_file()):
        done = _edm(*args)
        if done.returncode != 0:
            return {"draw": draw, "seed": seed, "error": done.stderr.strip()[-2000:]}
    seconds = time.perf_counter() - start
    described = _edm("describe", str(result), "--data", evaluation, "--json")
    if described.returncode != 0:
        return {"draw": draw, "seed": seed, "error": described.stderr.strip()[-2000:]}
    doc = json.loads(described.stdout)
    if opts.get("by") == "rows":  # the row-by-row names, as describe gave them before the physics
        doc.pop("physics", None)
    simulated = _edm("simulate", str(result), evaluation, "-o", str(sim))
    if simulated.returncode != 0:
        return {"draw": draw, "seed": seed, "error": simulated.stderr.strip()[-2000:]}
    with sim.open(newline="", encoding="utf-8") as fh:
        rows = list(csv.reader(fh))
    header = rows[0]
    values = np.array(rows[1:], dtype=float)
    model = values[:, header.index("tau_cmp")]  # the compensation torque (docs/cli.md)

    fp = draw_plant(draw)
    truth = {k: dict(v) for k, v in fp.truth.items()}
    log = simulate_plant(fp.preset, "evaluation", seed=0)
    edm_rmse = _rms(log.tau_ext - model)
    truth_rmse = _rms(log.tau_ext - true_law(log))
    static_rmse = _rms(log.tau_ext - law_torque(log.columns, truth, g_rtob=fp.preset.g_rtob,
                                                 ts=log.ts))
    named = named_physics(doc)
    return {"draw": draw, "seed": seed, "seconds": seconds, "truth": truth, "named": named,
            **compare(named, truth), "rmse": edm_rmse, "rmse_truth": truth_rmse,
            "rmse_static": static_rmse, "ratio_truth": edm_rmse / truth_rmse,
            "ratio_static": edm_rmse / static_rmse,
            "anchor_stribeck": anchor_stribeck(fp, seed)}


def anchor_stribeck(fp: FamilyPlant, seed: int) -> float | None:
    """The engineer's Stribeck peak error on the run's own training log, v_s scanned.

    :func:`~edm_sym.engines.plant.anchor.fit_anchor` with the Stribeck
    velocity scanned over :data:`STRIBECK_SCAN` (not given): whether the
    abstraction excitation identifies the hump at all. The draws' staircase
    (:data:`~edm_sym.engines.plant.family.STAIRCASE`) holds plateaus at pi/4
    and pi/2 rad/s, below the slowest Stribeck velocity drawn; a plant that
    sticks and slips there never slides steadily at low speed, and least
    squares with the right regressors misses its peak too. The family draws
    no such hump any more (docs/plant.md, "A hump the drive holds"; draws 607
    and 804 did before). None when the plant has no Stribeck hump.
    """
    from edm_sym.engines.plant import simulate_plant
    from edm_sym.engines.plant.anchor import fit_anchor

    if "stribeck" not in fp.truth:
        return None
    log = simulate_plant(fp.preset, "abstraction", seed=seed)
    fit = fit_anchor(log.columns, g_rtob=fp.preset.g_rtob, ts=log.ts,
                     stribeck_velocity=STRIBECK_SCAN)
    return fit.stribeck_peak / fp.truth["stribeck"]["peak"] - 1.0


def _spread(values: list[float]) -> str:
    if not values:
        return "-"
    return f"{statistics.median(values):.3g} [{min(values):.3g}-{max(values):.3g}]"


def stribeck_by_speed(runs: list[dict]) -> tuple[str, str, float]:
    """The Stribeck peak within tolerance, counted apart for low and other humps.

    Over the runs whose plant has a hump: ``(low, high, bound)``, each count
    as ``"passed/runs"``, where a low hump's true Stribeck velocity is at most
    ``bound`` = :data:`LOW_HUMP` times the presets' staircase's slowest plateau
    (pi/2 rad/s, :data:`~edm_sym.engines.plant.excitation.STAIRCASE_LEVELS`):
    the humps the draws' logs saw only on their flank before the draws had a
    staircase of their own; the bound stays, so releases compare. A missing
    peak counts as outside the tolerance.
    """
    from edm_sym.engines.plant.excitation import STAIRCASE_LEVELS

    bound = LOW_HUMP * min(abs(v) for v in STAIRCASE_LEVELS if v)
    low: list[bool] = []
    high: list[bool] = []
    for r in runs:
        hump = r.get("truth", {}).get("stribeck")
        if "error" in r or not hump:
            continue
        err = r["errors"].get("stribeck.peak")
        within = err is not None and abs(err) <= STRIBECK_TOLERANCE
        (low if hump["stribeck_velocity"] <= bound else high).append(within)
    return f"{sum(low)}/{len(low)}", f"{sum(high)}/{len(high)}", bound


def summary(runs: list[dict], label: str) -> dict:
    """Pass share, per-parameter relative errors and RMSE ratios over a set of runs."""
    ok = [r for r in runs if "error" not in r]
    errors: dict[str, list[float]] = {}
    for r in ok:
        for name, value in r["errors"].items():
            if value is not None:
                errors.setdefault(name, []).append(abs(value))
    out = {"label": label, "runs": len(runs), "failed_to_run": len(runs) - len(ok),
           "pass": sum(r["pass"] for r in ok),
           "errors": {k: _spread(v) for k, v in sorted(errors.items())},
           "ratio_truth": _spread([r["ratio_truth"] for r in ok]),
           "ratio_static": _spread([r["ratio_static"] for r in ok])}
    # Humps the excitation does not identify: least squares with v_s scanned misses them too.
    seen = [r for r in ok if abs(r.get("anchor_stribeck") or 0.0) <= STRIBECK_TOLERANCE]
    hidden = len(ok) - len(seen)
    out["unidentified_stribeck"] = hidden
    out["pass_identified"] = f"{sum(r['pass'] for r in seen)}/{len(seen)}"
    low, high, bound = stribeck_by_speed(ok)
    out["stribeck_low"], out["stribeck_high"] = low, high
    out["at_or_below_static"] = f"{sum(r['ratio_static'] <= 1.0 for r in ok)}/{len(ok)}"
    # Where the static laws sit at the noise floor no model gets much below them.
    above = [r for r in ok if r["rmse_static"] >= ABOVE_FLOOR * r["rmse_truth"]]
    out["above_floor"] = {"runs": len(above),
                          "at_or_below_static": sum(r["ratio_static"] <= 1.0 for r in above),
                          "ratio_static": _spread([r["ratio_static"] for r in above])}
    print(f"{label}: {out['pass']}/{len(runs)} runs with all physics within tolerance"
          + (f" ({out['failed_to_run']} did not run)" if out["failed_to_run"] else ""))
    print(f"  Stribeck humps the least squares with v_s scanned misses by over "
          f"{STRIBECK_TOLERANCE:.0%} too: {hidden} runs; the others: "
          f"{out['pass_identified']} pass")
    print(f"  Stribeck peak within {STRIBECK_TOLERANCE:.0%}: {low} runs with a hump at v_s <= "
          f"{bound:.3g} rad/s ({LOW_HUMP:g}x the slowest plateau), {high} above")
    for name, text in out["errors"].items():
        print(f"  |relative error| {name}: {text}")
    print(f"  RMSE / true law (noise floor): {out['ratio_truth']}")
    print(f"  RMSE / static laws with the true parameters: {out['ratio_static']}, "
          f"at or below them {out['at_or_below_static']}")
    fl = out["above_floor"]
    print(f"  runs whose static laws are at least {ABOVE_FLOOR:.3g}x the noise floor: "
          f"{fl['runs']}, at or below them {fl['at_or_below_static']}, RMSE / static laws "
          f"{fl['ratio_static']}")
    return out


def _line(r: dict) -> str:
    if "error" in r:
        return f"family-{r['draw']} seed {r['seed']}: ERROR {r['error'].splitlines()[-1:]}"
    verdict = "pass" if r["pass"] else "FAIL: " + "; ".join(r["failures"])
    if r.get("anchor_stribeck") is not None:
        verdict += f" (least squares, v_s scanned: Stribeck peak {r['anchor_stribeck']:+.1%})"
    errs = " ".join(f"{k}={v:+.1%}" for k, v in r["errors"].items() if v is not None)
    return (f"family-{r['draw']} seed {r['seed']}: {verdict} | {errs} | RMSE {r['rmse']:.4g} N m, "
            f"x{r['ratio_truth']:.3g} truth, x{r['ratio_static']:.3g} static | {r['seconds']:.0f} s")


def _ints(text: str) -> list[int]:
    out: list[int] = []
    for part in text.split(","):
        lo, _, hi = part.partition("-")
        out += list(range(int(lo), int(hi) + 1)) if hi else [int(lo)]
    return out


def main(argv: list[str] | None = None) -> int:
    """Run the benchmark; print a line per run and the summaries; write the JSON."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--draws", default="0-3,100-111", help="draws, e.g. 0-3,100-111")
    ap.add_argument("--seeds", default="1,2,3")
    ap.add_argument("--jobs", type=int, default=1, help="runs side by side")
    ap.add_argument("--workers", type=int, default=1, help="edm abstract --workers per run")
    ap.add_argument("--time-limit", type=float, help="edm abstract --time-limit per run [s]")
    budget = ap.add_mutually_exclusive_group()
    budget.add_argument("--generations", type=int,
                        help="quick mode: G generations a step, one block ([ga] generations)")
    budget.add_argument("--max-blocks", type=int, help="[ga] max_blocks: blocks of 50 a step")
    ap.add_argument("--out", default="bench_naming.json", help="the JSON of every run")
    ap.add_argument("--keep", help="folder for the results (default: a temporary one)")
    ap.add_argument("--reuse", action="store_true",
                    help="with --keep: describe the result.json a run left there instead of "
                         "searching again (to measure a change of the naming alone)")
    ap.add_argument("--by", choices=["behaviour", "rows"], default="behaviour",
                    help="the physics describe names by behaviour (default), or its rows' terms")
    args = ap.parse_args(argv)

    config = None
    if args.generations:
        config = f'[ga]\ngenerations = {args.generations}\ncontinue = "no"\n'
    elif args.max_blocks:
        config = f"[ga]\nmax_blocks = {args.max_blocks}\n"
    opts = {"workers": args.workers, "time_limit": args.time_limit, "config": config,
            "reuse": args.reuse, "by": args.by}
    jobs = [(d, s) for d in _ints(args.draws) for s in _ints(args.seeds)]
    with tempfile.TemporaryDirectory() as tmp:
        work = args.keep or tmp
        runs = []
        with ProcessPoolExecutor(max_workers=max(1, args.jobs)) as pool:
            futures = [pool.submit(run_one, d, s, work, opts) for d, s in jobs]
            for future in futures:
                run = future.result()
                print(_line(run), flush=True)
                runs.append(run)
    sets = [("tuning draws", [r for r in runs if r["draw"] in TUNING]),
            ("measured draws", [r for r in runs if r["draw"] not in TUNING])]
    summaries = [summary(rs, label) for label, rs in sets if rs]
    doc = {"command": " ".join(sys.argv), "options": opts, "runs": runs, "summaries": summaries}
    Path(args.out).write_text(json.dumps(doc, indent=1, sort_keys=True), encoding="utf-8")
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
