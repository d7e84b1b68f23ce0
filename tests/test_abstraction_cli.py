"""``edm abstract``: output, exit status, one-line errors, interrupt and resume."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import jsonschema
import pytest
from helpers import friction_log

from edm_sym.application.abstract_cli import checkpoint_path, start_line
from edm_sym.application.cli import main
from edm_sym.core.data import write_csv
from edm_sym.core.result import load_result
from edm_sym.engines.abstraction.parallel import Parallel

ROOT = Path(__file__).resolve().parents[1]

QUICK = """
[ga]
population = 16
generations = 4
continue = "no"

[[step]]
n_rows = 2
n_elements = 3
"""


def _config(tmp_path: Path, text: str = QUICK) -> Path:
    path = tmp_path / "cfg.toml"
    path.write_text(text)
    return path


def test_abstract_writes_the_result_and_prints_fitness_and_path(
    friction_csv: Path, tmp_path: Path, capsys: pytest.CaptureFixture
) -> None:
    out = tmp_path / "res.json"
    rc = main(["abstract", str(friction_csv), "--target", "tau_ext", "--inputs", "omega, alpha",
               "--config", str(_config(tmp_path)), "--seed", "3", "-o", str(out),
               "--workers", "1", "--quiet"])
    lines = capsys.readouterr().out.splitlines()
    assert rc == 0
    res = load_result(out)
    tr, va = res.validation["training"], res.validation["validation"]
    par = res.parsimony
    assert lines == [f"wrote {out}", f"fitness {res.fitness:.10g}",
                     "held out: 20 % of the log in 10 blocks, one in the middle of each 10 % "
                     "(rows 40-60, 140-160, ...)",
                     f"training: fitness (eq. 8) {tr['fitness'][0]:.6g} N m, "
                     f"rmse {tr['rmse'][0]:.6g} N m",
                     f"validation: fitness (eq. 8) {va['fitness'][0]:.6g} N m, "
                     f"rmse {va['rmse'][0]:.6g} N m",
                     f"parsimony: complexity {par['search_complexity']} -> "
                     f"{par['front'][par['selected'] - 1]['complexity']} (front member "
                     f"{par['selected']} of {len(par['front'])}, simplest-within=1)",
                     start_line(par), lines[-1]]
    (chosen,) = (c for c in par["start_candidates"] if c["chosen"])
    assert lines[-2].startswith(f"search's model: step {chosen['step']} best")
    assert f"whole-log RMSE {chosen['whole_rmse'][0]:.4g} N m" in lines[-2]
    # last, the physics by behaviour: this log's plant is Coulomb 1 N m + viscous 0.01 N m s/rad
    assert lines[-1] == ("physics (by behaviour, over log.csv): coulomb level 1 N m; "
                         "viscous coefficient 0.00999 N m s/rad")
    # ... and result.json keeps what it printed (the physics key, as edm describe --json has it)
    doc = json.loads(out.read_text())
    jsonschema.validate(doc, json.loads((ROOT / "edm_sym" / "schema" / "result.schema.json")
                                        .read_text()))
    named = {t["kind"]: t["parameters"] for t in doc["physics"]["terms"]}
    assert set(named) == {"coulomb", "viscous"}
    assert f"{named['coulomb']['level'][0]:.4g}" == "1"
    assert doc["physics"]["ranges"]["source"] == "log.csv"
    assert res.physics == doc["physics"]
    assert res.inputs == ("omega", "alpha") and res.target == "tau_ext"
    assert res.provenance["seed"] == 3 and len(res.provenance["data_sha256"]) == 64
    assert not checkpoint_path(out).exists()


def test_the_search_models_line_says_when_the_held_out_blocks_chose() -> None:
    cands = [{"step": 2, "refitted": True, "whole_rmse": [0.05029, "N m"],
              "held_out_rmse": [0.06072, "N m"], "tied": True, "chosen": True},
             {"step": 4, "refitted": True, "whole_rmse": [0.04958, "N m"],
              "held_out_rmse": [0.06651, "N m"], "tied": True, "chosen": False},
             {"step": 3, "refitted": False, "whole_rmse": [0.4487, "N m"],
              "held_out_rmse": [0.456, "N m"], "tied": False, "chosen": False}]
    assert start_line({"start_tie": 0.02, "start_candidates": cands}) == (
        "search's model: step 2 best, refitted (whole-log RMSE 0.05029 N m, held out "
        "0.06072 N m; tied within 2 % with 1 other candidate: the held-out RMSE chose)")
    alone = [{**cands[1], "chosen": True}, {**cands[2]}]
    assert start_line({"start_tie": 0.02, "start_candidates": alone}) == (
        "search's model: step 4 best, refitted (whole-log RMSE 0.04958 N m, held out "
        "0.06651 N m; the lowest whole-log RMSE of 2 candidates)")
    assert start_line({"front": []}) is None  # an older result, or --last-step


def test_prune_tolerance_keeps_the_configs_other_parsimony_keys(
    friction_csv: Path, tmp_path: Path
) -> None:
    out = tmp_path / "res.json"
    cfg = _config(tmp_path, QUICK + '\n[parsimony]\nstart = "last-step"\n')
    rc = main(["abstract", str(friction_csv), "--target", "tau_ext", "--inputs", "omega",
               "--config", str(cfg), "--prune-tolerance", "0.02", "-o", str(out),
               "--workers", "1", "--quiet"])
    assert rc == 0
    par = load_result(out).parsimony
    assert par["tolerance"] == 0.02
    # The last step's best, as the config asks: no candidates, no refit.
    assert par["start_step"] == 1 and par["refit"] == 0 and "start_candidates" not in par


def test_time_limit_exits_0_with_the_best_so_far(
    friction_csv: Path, tmp_path: Path, capsys: pytest.CaptureFixture
) -> None:
    out = tmp_path / "res.json"
    rc = main(["abstract", str(friction_csv), "--target", "tau_ext", "--inputs", "omega",
               "--config", str(_config(tmp_path)), "--time-limit", "1e-6", "-o", str(out),
               "--workers", "1"])
    assert rc == 0
    assert load_result(out).provenance["stop_reason"] == "time_limit"
    assert checkpoint_path(out).exists()  # --resume would continue it
    assert "time limit" in capsys.readouterr().err


@pytest.mark.parametrize("args, expect", [
    (["--config", "{bad}"], "cfg.toml: ga.populaton: unknown key"),
    (["--config", "{type}"], "cfg.toml: ga.population: expected an integer, found string"),
    (["--config", "{toml}"], "cfg.toml: expected TOML"),
    (["--config", "{missing}"], "nope.toml: cannot be read"),
    (["--target", "torque"], "log.csv: column 'torque': expected a target column"),
    (["--inputs", "omega,speed"], "log.csv: column 'speed': expected a input column"),
    (["--inputs", "omega,,alpha"], "--inputs: expected comma-separated column names"),
    (["--workers", "0"], "--workers: expected an integer >= 1"),
    (["--searches", "0"], "--searches: expected an integer from 1 to 64, found integer 0"),
    (["--config", "{searches}"], "cfg.toml: searches: expected an integer from 1 to 64, found string"),
    (["--config", "{fidelity}"],
     "cfg.toml: fidelity: expected one of 'auto', 'full', 'multi', found string 'fast'"),
    (["--config", "{multi}"], "cfg.toml: multi_fidelity.promote: expected an integer >= 1, found 0"),
    (["--seed", "-4"], "--seed: expected an integer >= 0"),
    # Nothing listens on the discard port: refused within the 10 s connect timeout.
    (["--scheduler", "tcp://127.0.0.1:9"],
     "--scheduler: expected a dask scheduler at tcp://127.0.0.1:9, found none"),
])
def test_bad_input_exits_2_with_one_line(
    friction_csv: Path, tmp_path: Path, capsys: pytest.CaptureFixture, args: list, expect: str
) -> None:
    texts = {"bad": "[ga]\npopulaton = 3\n", "type": "[ga]\npopulation = '64'\n",
             "toml": "[ga\n", "searches": "searches = '2'\n", "fidelity": "fidelity = 'fast'\n",
             "multi": "[multi_fidelity]\npromote = 0\n"}
    fixed = []
    for a in args:
        if a.startswith("{"):
            key = a.strip("{}")
            a = str(tmp_path / "nope.toml") if key == "missing" else str(
                _config(tmp_path, texts[key]))
        fixed.append(a)
    argv = ["abstract", str(friction_csv), "--target", "tau_ext", "--inputs", "omega",
            "-o", str(tmp_path / "r.json"), "--workers", "1"]
    for k in range(0, len(fixed), 2):
        flag = fixed[k]
        if flag in argv:
            argv[argv.index(flag) + 1] = fixed[k + 1]
        else:
            argv += fixed[k:k + 2]
    rc = main(argv)
    err = capsys.readouterr().err.strip()
    assert rc == 2
    assert len(err.splitlines()) == 1 and "Traceback" not in err
    assert expect in err
    assert not (tmp_path / "r.json").exists()


# -- --resume with a checkpoint it cannot continue ----------------------------------------


def _stopped_run(friction_csv: Path, cfg: Path, out: Path, *, searches: int = 1) -> None:
    """A run stopped after its first generation, leaving its checkpoint(s) beside ``out``."""
    from edm_sym.engines.abstraction import abstract, load_config
    from edm_sym.engines.sources import load_data

    abstract(load_data(friction_csv), target="tau_ext", inputs=["omega", "alpha"],
             config=load_config(cfg), seed=3, parallel=Parallel(workers=1), checkpoint=checkpoint_path(out),
             callback=lambda info: True, searches=searches)
    if searches > 1:  # the stop came before the second search began: it has the first's
        first = checkpoint_path(out).with_name(f"{out.name}.checkpoint.search0")
        first.with_name(f"{out.name}.checkpoint.search1").write_bytes(first.read_bytes())


def _set(ckpt: Path, **keys: object) -> None:
    """Change top-level keys of a checkpoint and seal it again (a digest that matches)."""
    from edm_sym.engines.abstraction.checkpoint import _digest

    doc = json.loads(ckpt.read_text())
    doc.update(keys)
    doc["sha256"] = _digest(doc)
    ckpt.write_text(json.dumps(doc, sort_keys=True) + "\n")


@pytest.mark.parametrize("change, args, expect", [
    ({"version": 3}, [], "version: expected checkpoint format version 2 (edm_sym "),
    ({"version": 1}, [], "found version 1 (a checkpoint of another edm_sym release)"),
    ({"format": "edm-result"}, [], "format: expected 'edm-abstraction-checkpoint' (version 2), "
                                   'found format "edm-result"'),
    ({}, ["--seed", "4"], "found one of another seed (3; this run: 4)"),
    ({}, ["--inputs", "omega"], 'another input set (["omega", "alpha"]; this run: ["omega"])'),
    ({}, ["--target", "alpha", "--inputs", "omega"],
     'another target ("tau_ext"; this run: "alpha")'),
    ({}, ["--config", "{other}"], "found one of another config (or --searches)"),
    ({}, ["--data", "{other}"], "found one of another data file"),
    ({}, ["--searches", "2"], "expected a checkpoint of this run of 2 searches "
                              "(r.json.checkpoint.search0), found one of a run of one search"),
], ids=["newer", "older", "format", "seed", "inputs", "target", "config", "data", "searches"])
def test_a_checkpoint_resume_cannot_continue_is_refused_and_left_as_it_was(
    friction_csv: Path, tmp_path: Path, capsys: pytest.CaptureFixture, change: dict, args: list,
    expect: str
) -> None:
    cfg = _config(tmp_path, QUICK.replace("generations = 4", "generations = 50"))
    out = tmp_path / "r.json"
    _stopped_run(friction_csv, cfg, out)
    ckpt = checkpoint_path(out)
    if change:
        _set(ckpt, **change)
    before = ckpt.read_bytes()
    argv = {"--data": str(friction_csv), "--target": "tau_ext", "--inputs": "omega,alpha",
            "--config": str(cfg), "--seed": "3"}
    for k in range(0, len(args), 2):
        argv[args[k]] = args[k + 1]
    if argv["--config"] == "{other}":
        (tmp_path / "o").mkdir()
        argv["--config"] = str(_config(tmp_path / "o", QUICK.replace("= 16", "= 18")))
    if argv["--data"] == "{other}":
        log, _ = friction_log(1.0, seed=5)
        argv["--data"] = str(write_csv(tmp_path / "other.csv", log.columns))
    data = argv.pop("--data")
    rc = main(["abstract", data, *[a for kv in argv.items() for a in kv], "-o", str(out),
               "--workers", "1", "--quiet", "--resume"])
    err = capsys.readouterr().err
    assert rc == 2
    assert len(err.strip().splitlines()) == 1, err
    assert err.startswith(f"edm: {ckpt}") and expect in err, err
    assert "the file is left as it was" in err
    assert ckpt.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir() if p.name.startswith("r.json")) == \
        ["r.json.checkpoint"]  # no result, no checkpoint of the refused run


def test_checkpoints_of_several_searches_are_refused_for_one(
    friction_csv: Path, tmp_path: Path, capsys: pytest.CaptureFixture
) -> None:
    cfg = _config(tmp_path, QUICK.replace("generations = 4", "generations = 50"))
    out = tmp_path / "r.json"
    _stopped_run(friction_csv, cfg, out, searches=2)
    files = sorted(tmp_path.glob("r.json.checkpoint.search*"))
    assert len(files) == 2
    before = [f.read_bytes() for f in files]
    rc = main(["abstract", str(friction_csv), "--target", "tau_ext", "--inputs", "omega,alpha",
               "--config", str(cfg), "--seed", "3", "-o", str(out), "--workers", "1",
               "--quiet", "--resume"])
    err = capsys.readouterr().err
    assert rc == 2 and len(err.strip().splitlines()) == 1, err
    assert "expected a checkpoint of this run of one search (r.json.checkpoint), found one of " \
           "a run of several searches" in err
    assert [f.read_bytes() for f in files] == before
    assert not out.exists() and not checkpoint_path(out).exists()


def test_a_second_search_of_another_version_is_refused_before_the_first_runs(
    friction_csv: Path, tmp_path: Path, capsys: pytest.CaptureFixture
) -> None:
    cfg = _config(tmp_path, QUICK.replace("generations = 4", "generations = 50"))
    out = tmp_path / "r.json"
    _stopped_run(friction_csv, cfg, out, searches=2)
    first, second = sorted(tmp_path.glob("r.json.checkpoint.search*"))
    _set(second, version=7)
    before = first.read_bytes(), second.read_bytes()
    rc = main(["abstract", str(friction_csv), "--target", "tau_ext", "--inputs", "omega,alpha",
               "--config", str(cfg), "--seed", "3", "-o", str(out), "--workers", "2",
               "--searches", "2", "--quiet", "--resume"])
    err = capsys.readouterr().err
    assert rc == 2 and f"{second}: version: " in err and "found version 7" in err, err
    assert (first.read_bytes(), second.read_bytes()) == before
    assert not out.exists()


# -- a real process, interrupted and resumed ---------------------------------------

# Long enough that a checkpoint (every CHECKPOINT_SECONDS, and at each step's end) shows a
# step in progress before the run ends: the interrupt must land mid-step (no patience: a
# step runs all its generations). The first step (about 1.5 s here) may end before the
# first checkpoint; the second, about 6 s, holds at least two.
LONG = """
[ga]
population = 32
generations = 400
patience = 0
continue = "no"

[[step]]
n_rows = 2
n_elements = 4

[[step]]
n_rows = 3
n_elements = 4
generations = 1600
"""


def _cmd(data: Path, cfg: Path, out: Path, *extra: str) -> list[str]:
    return [sys.executable, "-m", "edm_sym", "abstract", str(data), "--target", "tau_ext",
            "--inputs", "omega,alpha", "--config", str(cfg), "--seed", "11", "-o", str(out),
            "--quiet", *extra]


def _wait_for_generation(ckpt: Path, proc: subprocess.Popen, generation: int) -> None:
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and proc.poll() is None:
        try:
            cur = json.loads(ckpt.read_text())["current"]
            if cur is not None and (cur["step"] > 0 or cur["generation"] >= generation):
                return
        except (OSError, ValueError, KeyError):
            pass
        time.sleep(0.05)
    raise AssertionError("the run did not reach the generation in time")


@pytest.mark.slow
@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM, signal.SIGKILL],
                         ids=["SIGINT", "SIGTERM", "SIGKILL"])
def test_an_interrupted_process_resumes_to_the_uninterrupted_result(
    tmp_path: Path, sig: signal.Signals
) -> None:
    log, _ = friction_log(4.0)
    data = write_csv(tmp_path / "log.csv", log.columns)
    cfg = _config(tmp_path, LONG)
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    ref = tmp_path / "ref.json"
    subprocess.run(_cmd(data, cfg, ref), check=True, env=env, capture_output=True)

    out = tmp_path / "out.json"
    ckpt = checkpoint_path(out)
    proc = subprocess.Popen(_cmd(data, cfg, out), env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    try:
        _wait_for_generation(ckpt, proc, 6)
        proc.send_signal(sig)
        _, err = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    if sig in (signal.SIGINT, signal.SIGTERM):
        assert proc.returncode == 130  # interrupted (docs/cli.md#exit-status)
        assert "interrupted" in err and "Traceback" not in err
        part = load_result(out)  # the best so far was written
        assert part.provenance["stop_reason"] == "interrupted"
    else:
        assert proc.returncode == -signal.SIGKILL
        assert not out.exists()
    assert ckpt.exists()
    done = subprocess.run(_cmd(data, cfg, out, "--resume"), env=env, capture_output=True,
                          text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert out.read_bytes() == ref.read_bytes()
    assert not ckpt.exists()


@pytest.mark.slow
def test_an_interrupted_run_of_two_searches_resumes_on_one_worker_to_the_same_bytes(
    tmp_path: Path
) -> None:
    log, _ = friction_log(4.0)
    data = write_csv(tmp_path / "log.csv", log.columns)
    cfg = _config(tmp_path, LONG)
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    two = ("--searches", "2", "--workers", "2")
    ref = tmp_path / "ref.json"
    subprocess.run(_cmd(data, cfg, ref, *two), check=True, env=env, capture_output=True)

    out = tmp_path / "out.json"
    ckpts = [checkpoint_path(out).with_name(f"out.json.checkpoint.search{k}") for k in range(2)]
    proc = subprocess.Popen(_cmd(data, cfg, out, *two), env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    try:
        for ckpt in ckpts:  # both searches run at once, each with its own checkpoint
            _wait_for_generation(ckpt, proc, 6)
        proc.send_signal(signal.SIGTERM)  # to the run's process only: it tells the searches
        _, err = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == 130 and "Traceback" not in err
    part = load_result(out)
    assert [s["stop_reason"] for s in part.provenance["searches"]] == ["interrupted"] * 2
    assert all(c.exists() for c in ckpts)
    done = subprocess.run(_cmd(data, cfg, out, "--resume", "--searches", "2", "--workers", "1"),
                          env=env, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert out.read_bytes() == ref.read_bytes()
    assert not any(c.exists() for c in ckpts)
