"""Held-out validation: what the GA never fits, and both scores."""

from __future__ import annotations

import hashlib
import json
from dataclasses import replace
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from helpers import TS, friction_log

from edm_sym.application.cli import main
from edm_sym.core.data import DataLog, write_csv
from edm_sym.core.errors import ConfigError, DataFormatError
from edm_sym.core.result import dumps, load_result, matrix_to_json, parse_result, save_result
from edm_sym.engines.abstraction import abstract, parse_config
from edm_sym.engines.abstraction.holdout import ValidationSettings, parse_validation
from edm_sym.engines.abstraction.parallel import Parallel
from edm_sym.engines.simulate import plain_loop

ROOT = Path(__file__).resolve().parents[1]
# A rough search (4 generations a step, no restarts) leaves step bests a refit improves.
TINY = {"ga": {"population": 16, "generations": 4, "continue": "no", "restarts": 0},
        "step": [{"n_rows": 2, "n_elements": 3},
                 {"n_rows": 3, "n_elements": 3,
                  "weighting": {"threshold": 0.5, "above": 4.0, "below": 1.0}}]}


def run(data: DataLog, doc: dict = TINY, **kw) -> object:
    kw.setdefault("seed", 2)
    kw.setdefault("parallel", Parallel(workers=1))
    return abstract(data, target="tau_ext", inputs=["omega", "alpha"],
                    config=parse_config(doc, "test.toml"), **kw)


def corrupted(log: DataLog, start: int) -> DataLog:
    """The same log with its target from ``start`` on replaced by a large unrelated signal."""
    cols = dict(log.columns)
    tau = cols["tau_ext"].copy()
    tau[start:] = 50.0 * np.cos(np.arange(len(tau) - start) * 0.37) + 20.0
    cols["tau_ext"] = tau
    return DataLog(cols, log.ts, "corrupted")


def corrupted_blocks(log: DataLog) -> DataLog:
    """The same log with its target replaced by a large unrelated signal in the held-out blocks."""
    cols = dict(log.columns)
    tau = cols["tau_ext"].copy()
    tau[HELD] = 50.0 * np.cos(HELD * 0.37) + 20.0
    cols["tau_ext"] = tau
    return DataLog(cols, log.ts, "corrupted")


@pytest.fixture(scope="module")
def log() -> DataLog:
    return friction_log(1.5)[0]


BLOCKS = [[150 * j + 60, 150 * j + 90] for j in range(10)]
HELD = np.concatenate([np.arange(a, b) for a, b in BLOCKS])
TRAIN = np.setdiff1d(np.arange(1500), HELD)
END = {**TINY, "validation": {"layout": "end"}}


def test_ten_blocks_spread_over_the_log_are_held_out_by_default_and_recorded(
        log: DataLog) -> None:
    res = run(log)
    held = res.validation["held_out"]
    # 20 % of 1500 samples in 10 blocks of 30, each at the end of its tenth of the log.
    assert held == {"kind": "blocks", "share": 0.2, "count": 10, "blocks": BLOCKS,
                    "times": [[pytest.approx(a * TS), pytest.approx((b - 1) * TS)]
                              for a, b in BLOCKS]}
    assert res.validation["training"]["samples"] == 1200
    assert res.validation["validation"]["samples"] == 300
    assert res.validation["training"]["fitness"][1] == "N m"
    assert res.validation["weighting"] == {"constant": 1.0, "threshold": 0.5, "above": 4.0,
                                           "below": 1.0}


def test_the_last_fifth_is_held_out_with_the_end_layout(log: DataLog) -> None:
    res = run(log, END)
    held = res.validation["held_out"]
    assert held == {"kind": "segment", "end": "last", "share": 0.2, "rows": [1200, 1500],
                    "t": [pytest.approx(1.2), pytest.approx(1.499)]}
    assert res.validation["training"]["samples"] == 1200
    assert res.validation["validation"]["samples"] == 300


NO_PRUNE = {**TINY, "parsimony": {"prune": False}}


def corrupted_at(log: DataLog, index: np.ndarray) -> DataLog:
    """The same log with its target at ``index`` replaced by a large unrelated signal."""
    cols = dict(log.columns)
    tau = cols["tau_ext"].copy()
    tau[index] = 50.0 * np.cos(np.arange(len(index)) * 0.37) + 20.0
    cols["tau_ext"] = tau
    return DataLog(cols, log.ts, "corrupted")


def test_the_held_out_blocks_never_enter_the_ga(log: DataLog) -> None:
    # Without the pruning pass, which scores simplifications on the held-out part on purpose.
    clean = run(log, NO_PRUNE)
    bad = run(corrupted_at(log, HELD), NO_PRUNE)
    # Every step, every history value and the final matrix are the same bytes ...
    assert [matrix_to_json(s.matrix) for s in bad.steps] == [
        matrix_to_json(s.matrix) for s in clean.steps]
    assert [s.history for s in bad.steps] == [s.history for s in clean.steps]
    assert bad.fitness == clean.fitness
    assert bad.validation["training"] == clean.validation["training"]
    # ... but the held-out score sees the corruption.
    assert bad.validation["validation"]["rmse"][0] > 10 * clean.validation["validation"]["rmse"][0]
    # Corrupting one training sample between two blocks changes the fit: the check can fail.
    assert dumps(run(corrupted_at(log, np.array([200])), NO_PRUNE)) != dumps(clean)


def test_the_held_out_segment_never_enters_the_ga(log: DataLog) -> None:
    end = {**NO_PRUNE, "validation": {"layout": "end"}}
    clean = run(log, end)
    bad = run(corrupted(log, 1200), end)
    assert [matrix_to_json(s.matrix) for s in bad.steps] == [
        matrix_to_json(s.matrix) for s in clean.steps]
    assert [s.history for s in bad.steps] == [s.history for s in clean.steps]
    assert bad.validation["training"] == clean.validation["training"]
    assert bad.validation["validation"]["rmse"][0] > 10 * clean.validation["validation"]["rmse"][0]
    assert dumps(run(corrupted(log, 1199), end)) != dumps(bad)


@pytest.mark.parametrize(("doc", "parts"), [
    (TINY, (("training", TRAIN), ("validation", HELD))),
    (END, (("training", slice(0, 1200)), ("validation", slice(1200, None)))),
])
def test_both_scores_match_an_independent_recomputation(log: DataLog, doc: dict,
                                                        parts: tuple) -> None:
    res = run(log, doc)
    # The per-sample loop (a firmware-like realisation) over the whole log, from rest.
    total = plain_loop(res.compensator, log).sum(axis=0)
    e = log.columns["tau_ext"] - total
    lam = np.where(np.abs(log.columns["tau_ext"]) >= 0.5, 4.0, 1.0)
    for part, sl in parts:
        score = res.validation[part]
        assert score["fitness"][0] == pytest.approx(np.sqrt(np.mean(lam[sl] * e[sl] ** 2)),
                                                    rel=1e-9)
        assert score["rmse"][0] == pytest.approx(np.sqrt(np.mean(e[sl] ** 2)), rel=1e-9)
    # The result's fitness is the exported model's training eq. 8 ...
    assert res.fitness == pytest.approx(res.validation["training"]["fitness"][0], rel=1e-12)
    # ... which, without pruning, is the last step's, as the GA ranked it.
    plain = run(log, {**doc, "parsimony": {"prune": False}})
    assert plain.steps[-1].fitness == pytest.approx(plain.fitness, rel=1e-9)
    assert plain.validation["training"]["fitness"][0] == pytest.approx(plain.fitness, rel=1e-9)


def test_a_share_from_the_config_or_the_call(log: DataLog) -> None:
    res = run(log, {**TINY, "validation": {"share": 0.4, "unit": "N", "layout": "end"}})
    assert res.validation["held_out"]["rows"] == [900, 1500]
    assert res.validation["training"]["rmse"][1] == "N"
    res = run(log, {**TINY, "validation": {"share": 0.4, "blocks": 3}})
    assert res.validation["held_out"]["blocks"] == [[150, 350], [650, 850], [1150, 1350]]
    res = run(log, {**TINY, "validation": {"share": 0.4}}, validation_share=0.0)
    assert res.validation["held_out"] == {"kind": "none"}
    assert res.validation["validation"] is None
    assert res.validation["training"]["samples"] == 1500


def test_a_second_log_is_held_out_whole(log: DataLog, tmp_path: Path) -> None:
    other, _ = friction_log(1.0, seed=9)
    path = write_csv(tmp_path / "val.csv", other.columns)
    from edm_sym.core.data import load_data

    val = load_data(path)
    res = run(log, validate=val)
    held = res.validation["held_out"]
    assert held == {"kind": "file", "file": "val.csv",
                    "sha256": hashlib.sha256(path.read_bytes()).hexdigest(), "samples": 1000}
    assert res.validation["training"]["samples"] == 1500
    e = val.columns["tau_ext"] - plain_loop(res.compensator, val).sum(axis=0)
    assert res.validation["validation"]["rmse"][0] == pytest.approx(np.sqrt(np.mean(e**2)),
                                                                    rel=1e-9)


def test_results_round_trip_and_old_files_still_load(log: DataLog, tmp_path: Path) -> None:
    res = run(log)
    back = load_result(save_result(res, tmp_path / "r.json"))
    assert back.validation == res.validation
    old = load_result(ROOT / "tests/golden/legacy_auger_result.json")
    assert old.validation == {}
    assert "validation" not in json.loads(dumps(old))


@pytest.mark.parametrize(("path", "value", "message"), [
    (["validation", "training", "rmse"], [1.0], "validation.training.rmse: expected at least 2"),
    (["validation", "held_out", "kind"], "middle", "validation.held_out.kind: expected one of"),
    (["validation", "validation"], 3, "validation.validation: expected null or an object"),
])
def test_a_bad_validation_entry_is_refused(log: DataLog, path: list, value: object,
                                           message: str) -> None:
    doc = json.loads(dumps(run(log)))
    node = doc
    for key in path[:-1]:
        node = node[key]
    node[path[-1]] = value
    with pytest.raises(ValueError, match=message.replace(".", r"\.")):
        parse_result(doc, "r.json")


def test_settings_are_checked() -> None:
    with pytest.raises(ConfigError, match=r"c.toml: validation.share: expected a number in \[0, 0.9\]"):
        parse_validation("c.toml: validation", {"share": 0.95})
    with pytest.raises(ConfigError, match="c.toml: validation.fraction: unknown key"):
        parse_validation("c.toml: validation", {"fraction": 0.2})
    assert ValidationSettings().share == 0.2
    assert (ValidationSettings().layout, ValidationSettings().blocks) == ("blocks", 10)
    with pytest.raises(ConfigError, match="validation.layout: expected one of blocks, end, found"):
        parse_validation("c.toml: validation", {"layout": "middle"})
    with pytest.raises(ConfigError, match="validation.blocks: expected an integer >= 1, found 0"):
        parse_validation("c.toml: validation", {"blocks": 0})
    three = DataLog({"omega": np.ones(3), "alpha": np.zeros(3), "tau_ext": np.ones(3)}, TS,
                    "three.csv")
    # Named by where the share came from (the argument, else the config file's key), and
    # the log it does not fit (found by a fuzz pass: neither was named).
    with pytest.raises(ConfigError, match="expected a share that leaves samples on both sides "
                                          "of the 3 samples of three.csv") as err:
        run(three, validation_share=0.1)
    assert err.value.where == "validation_share"
    with pytest.raises(ConfigError, match="of the 3 samples of three.csv") as err:
        run(three, {**TINY, "validation": {"share": 1e-320}})
    assert err.value.where == "test.toml: validation.share"


def test_a_target_whose_square_overflows_is_refused_before_the_search() -> None:
    # 1e160 ran the whole search with every fitness inf, then failed in the JSON writer
    # ("Out of range float values are not JSON compliant: inf"), naming nothing.
    log, _ = friction_log(2.0, seed=1)
    cols = {**log.columns, "tau_ext": 1e160 * log.columns["tau_ext"]}
    with pytest.raises(DataFormatError, match="largest magnitude is from 1e-150") as err:
        run(DataLog(cols, log.ts, "huge.csv"))
    assert err.value.where == "huge.csv: column 'tau_ext'"


# -- the command line ----------------------------------------------------------------

QUICK = """
[ga]
population = 12
generations = 2
continue = "no"

[[step]]
n_rows = 2
n_elements = 2
"""


@pytest.fixture(scope="module")
def files(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path, Path]:
    d = tmp_path_factory.mktemp("v")
    data = write_csv(d / "log.csv", friction_log(1.0)[0].columns)
    other = friction_log(0.5, seed=4)[0].columns
    val = write_csv(d / "val.csv", other)
    bad = write_csv(d / "bad.csv", {k: v for k, v in other.items() if k != "alpha"})
    (d / "cfg.toml").write_text(QUICK)
    return data, val, bad


def _abstract(files: tuple[Path, Path, Path], out: Path, *extra: str) -> int:
    return main(["abstract", str(files[0]), "--target", "tau_ext", "--inputs", "omega,alpha",
                 "--config", str(files[0].parent / "cfg.toml"), "-o", str(out),
                 "--workers", "1", "--quiet", *extra])


def test_cli_validation_share_and_validate(files: tuple[Path, Path, Path], tmp_path: Path,
                                           capsys: pytest.CaptureFixture) -> None:
    assert _abstract(files, tmp_path / "a.json", "--validation-share", "0.5") == 0
    held = load_result(tmp_path / "a.json").validation["held_out"]
    assert (held["kind"], held["share"], len(held["blocks"])) == ("blocks", 0.5, 10)
    assert _abstract(files, tmp_path / "b.json", "--validate", str(files[1])) == 0
    out = capsys.readouterr().out
    assert "held out: val.csv (500 samples)" in out
    assert load_result(tmp_path / "b.json").validation["held_out"]["kind"] == "file"


@pytest.mark.parametrize(("extra", "message"), [
    (["--validation-share", "1.5"], "edm: --validation-share: expected a number in [0, 0.9], "
                                    "found 1.5"),
    (["--validation-share", "0.2", "--validate", "VAL"], "edm: --validation-share: expected no "
                                                          "share with --validate"),
    (["--validate", "BAD"], "edm: bad.csv: column 'alpha': expected a column named 'alpha', "
                            "found only: t, omega, tau_ext"),
])
def test_cli_bad_validation_options_exit_2_with_one_line(
    files: tuple[Path, Path, Path], tmp_path: Path, capsys: pytest.CaptureFixture,
    extra: list[str], message: str,
) -> None:
    extra = [str(files[1]) if a == "VAL" else str(files[2]) if a == "BAD" else a for a in extra]
    out = tmp_path / "r.json"
    assert _abstract(files, out, *extra) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(message), err
    assert not out.exists()


def test_cli_bad_validation_table_names_file_and_key(files: tuple[Path, Path, Path],
                                                     tmp_path: Path,
                                                     capsys: pytest.CaptureFixture) -> None:
    cfg = tmp_path / "v.toml"
    cfg.write_text(QUICK + '\n[validation]\nshare = "a fifth"\n')
    out = tmp_path / "r.json"
    rc = main(["abstract", str(files[0]), "--target", "tau_ext", "--inputs", "omega,alpha",
               "--config", str(cfg), "-o", str(out), "--workers", "1", "--quiet"])
    assert rc == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("edm: v.toml: validation.share: expected a number in [0, 0.9], "
                          "found 'a fifth'")
    assert not out.exists()


def _whole_rmse(res: object, log: DataLog, matrix: object) -> float:
    from dataclasses import replace

    comp = replace(res.compensator, matrix=matrix)
    e = log.columns["tau_ext"] - plain_loop(comp, log).sum(axis=0)
    return float(np.sqrt(np.mean(e ** 2)))


NO_REFIT = {**TINY, "parsimony": {"refit": 0}}


def test_pruning_starts_from_the_step_best_of_the_lowest_whole_log_rmse(log: DataLog) -> None:
    res = run(log, {**TINY, "parsimony": {"refit": 0, "tie": 0.0}})
    rmse = [_whole_rmse(res, log, s.matrix) for s in res.steps]
    best = min(range(len(rmse)), key=lambda q: (rmse[q], -q))
    assert res.parsimony["start_step"] == res.steps[best].step
    assert res.parsimony["criterion"] == "validation.rmse+training"
    first = res.parsimony["front"][-1]
    assert first["change"].startswith(f"search (step {res.steps[best].step} best)")
    assert res.parsimony["refit"] == 0 and res.parsimony["refitted"] is False
    assert _start_matrix(res) == res.steps[best].matrix
    _guarded_criterion(res, log, "rmse")


def test_step_bests_tied_on_the_whole_log_are_told_apart_by_the_held_out_blocks() -> None:
    """Step 2 is 1 % better over the whole log (80 % fitted) and far worse held out."""
    from edm_sym.core.matrix import Compensator, ElementMatrix, Gene, Row
    from edm_sym.core.result import StepRecord
    from edm_sym.engines.abstraction.finish import finish
    from edm_sym.engines.abstraction.holdout import plan_holdout

    t = np.arange(1500) * TS
    omega, s = np.sin(2 * np.pi * 0.7 * t), np.cos(2 * np.pi * 3.1 * t)
    # A disturbance s on the fitted samples only: step 1 leaves it, step 2 models k s with
    # k chosen so that its mean square over the whole log is 0.98 times step 1's.
    tau = np.sign(omega) + s
    tau[HELD] = np.sign(omega[HELD])
    fit, held = np.sum(s[TRAIN] ** 2), np.sum(s[HELD] ** 2)
    k = max(np.roots([fit + held, -2.0 * fit, 0.02 * fit]).real)
    data = DataLog({"t": t, "omega": omega, "s": s, "tau_ext": tau}, TS, "made.csv")
    through = Gene(0, 0.0)
    coulomb = Row(0, (Gene(19, 0.0), through, through))
    one = ElementMatrix(("omega", "s"), (coulomb,))
    two = ElementMatrix(("omega", "s"), (coulomb, Row(1, (Gene(3, k / 2), through, through))))
    steps = [StepRecord(q, m, 0.0, ()) for q, m in ((1, one), (2, two))]

    def start(tie: float) -> dict:
        cfg = parse_config({**TINY, "parsimony": {"refit": 0, "tie": tie},
                            "ranges": {"gain": {"low": 0.0, "high": 2.0}}}, "test.toml")
        cfg = replace(cfg, validation=replace(cfg.validation, unit="N m"))
        hold = plan_holdout(data, target="tau_ext", inputs=["omega", "s"],
                            settings=cfg.validation)
        ranges = cfg.resolve_ranges(TS, 1.5)
        whole = [_whole_rmse(SimpleNamespace(compensator=Compensator(m, TS, ranges, 1.5)),
                             data, m) for m in (one, two)]
        assert 0.985 * whole[0] < whole[1] < 0.995 * whole[0]  # 1 % better over the whole log
        return finish(steps, Compensator(two, TS, ranges, 1.5), hold, cfg)[1]

    record = start(0.02)  # the default
    assert record["start_step"] == 1
    assert record["front"][-1]["change"] == "search (step 1 best)"
    assert [(c["step"], c["tied"], c["chosen"]) for c in record["start_candidates"]] == [
        (1, True, True), (2, True, False)]
    held_out = [c["held_out_rmse"][0] for c in record["start_candidates"]]
    assert held_out[0] < 1e-12 < 1.0 < held_out[1]
    assert record["start_tie"] == 0.02
    # Not tied: the whole log alone chooses step 2.
    record = start(0.005)
    assert record["start_step"] == 2
    assert [(c["tied"], c["chosen"]) for c in record["start_candidates"]] == [
        (False, False), (True, True)]


def _start_matrix(res: object) -> object:
    """The search's model, which pruning started from."""
    from edm_sym.core.result import _matrix_from_json

    return _matrix_from_json("result", "search_matrix", res.parsimony["search_matrix"], res.inputs)


def test_step_bests_refitted_on_the_whole_training_part_are_candidates(log: DataLog) -> None:
    res = run(log, NARROW_LAST)
    rec = res.parsimony
    assert rec["refit"] == 600
    # The last step fitted the first 0.15 s only: refitted on the whole training part, its
    # best is the search's model, better over the whole log than every step best as the GA
    # left it.
    assert rec["refitted"] is True
    start = _start_matrix(res)
    assert start not in [s.matrix for s in res.steps]
    assert [(r.input, [g.code for g in r.genes]) for r in start.rows] == [
        (r.input, [g.code for g in r.genes]) for r in res.steps[rec["start_step"] - 1].matrix.rows]
    assert _whole_rmse(res, log, start) < min(_whole_rmse(res, log, s.matrix) for s in res.steps)


def test_the_refit_never_sees_the_held_out_blocks(log: DataLog) -> None:
    from edm_sym.engines.abstraction.holdout import plan_holdout
    from edm_sym.engines.abstraction.local_search import step_candidates

    res = run(log, NO_REFIT)
    settings = ValidationSettings()

    def refit(data: DataLog) -> list:
        hold = plan_holdout(data, target="tau_ext", inputs=["omega", "alpha"], settings=settings)
        assert np.array_equal(np.flatnonzero(hold.mask == 0), HELD)
        return step_candidates(res.steps, res.compensator, hold, max_evaluations=200)

    clean = refit(log)
    assert any(c.refitted for c in clean)
    assert [(c.matrix, c.step) for c in clean if not c.refitted] == [(s.matrix, s.step)
                                                                     for s in res.steps]
    assert refit(corrupted_blocks(log)) == clean


def _guarded_criterion(res: object, log: DataLog, kind: str) -> None:
    """Every member's criterion: v0 * max(v / v0, t / t0) against the search's model."""
    from dataclasses import replace

    comp = replace(res.compensator, matrix=res.steps[res.parsimony["start_step"] - 1].matrix)
    e = log.columns["tau_ext"] - plain_loop(comp, log).sum(axis=0)
    lam = np.where(np.abs(log.columns["tau_ext"]) >= 0.5, 4.0, 1.0) if kind == "fitness" else 1.0
    lam = np.broadcast_to(lam, e.shape)
    v0 = np.sqrt(np.mean(lam[HELD] * e[HELD] ** 2))
    t0 = np.sqrt(np.mean(lam[TRAIN] * e[TRAIN] ** 2))
    for member in res.parsimony["front"]:
        v, t = member["validation"][kind][0], member["training"][kind][0]
        assert member["criterion"][0] == pytest.approx(v0 * max(v / v0, t / t0), rel=1e-9)
    # Guarded: the selected member keeps the training part within the tolerance too.
    chosen = res.parsimony["front"][res.parsimony["selected"] - 1]
    assert chosen["training"][kind][0] <= t0 * (1 + res.parsimony["tolerance"]) * (1 + 1e-9)


#: A last step that fits only the first 0.15 s: worse on the held-out blocks than step 1.
NARROW_LAST = {**TINY, "step": [TINY["step"][0], {
    "n_rows": 3, "n_elements": 3, "weighting": {"windows": [[0.0, 0.15, 1.0]], "otherwise": 0.0}}]}


def test_an_earlier_step_best_is_exported_when_the_last_one_fits_a_narrow_window(
        log: DataLog) -> None:
    res = run(log, {**NARROW_LAST, "parsimony": {"refit": 0}})
    assert res.parsimony["start_step"] == 1
    last = run(log, {**NARROW_LAST, "parsimony": {"start": "last-step"}})
    assert last.parsimony["start_step"] == 2
    assert res.validation["validation"]["rmse"][0] < last.validation["validation"]["rmse"][0]


def test_the_paper_s_last_step_and_eq8_criterion_on_request(log: DataLog) -> None:
    res = run(log, {**TINY, "parsimony": {"start": "last-step", "criterion": "fitness"}})
    assert res.parsimony["start_step"] == res.steps[-1].step
    assert res.parsimony["criterion"] == "validation.fitness+training"
    _guarded_criterion(res, log, "fitness")


@pytest.mark.parametrize(("doc", "message"), [
    ({"criterion": "mse"}, "parsimony.criterion: expected one of rmse, fitness, found 'mse'"),
    ({"start": "first"}, "parsimony.start: expected one of best-step, last-step, found 'first'"),
    ({"refit": -1}, "parsimony.refit: expected an integer >= 0, found -1"),
    ({"refit": 2.5}, "parsimony.refit: expected an integer >= 0, found 2.5"),
])
def test_parsimony_criterion_and_start_are_checked(doc: dict, message: str) -> None:
    from edm_sym.engines.abstraction.parsimony import parse_parsimony

    with pytest.raises(ConfigError, match=message):
        parse_parsimony("c.toml: parsimony", doc)
