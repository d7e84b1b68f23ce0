"""Hierarchical abstraction: recovery, determinism, resume, the result file."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from helpers import COULOMB, SMALL, TS, VISCOUS, friction_log, run
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from edm_sym.core.data import DataLog
from edm_sym.core.elements import BY_NAME, default_ranges
from edm_sym.core.matrix import Compensator, Gene
from edm_sym.core.result import dumps, load_result, matrix_to_json, save_result
from edm_sym.engines.abstraction import GenerationInfo, abstract, parse_config
from edm_sym.engines.abstraction.ga import Operators
from edm_sym.engines.abstraction.parallel import Parallel
from edm_sym.engines.simulate import fitness, simulate, simulate_row


def steady_state_friction(result, velocity: str = "omega", step: int | None = None
                          ) -> tuple[float, float, float]:
    """Read the friction curve of eq. 14 off the matrix: tau_ss = c sgn(v) + b v + d.

    Each row of the matrix is run on constant inputs (velocity v, every other
    input 0, i.e. no acceleration) until its filters settle, and the sum of
    the rows' final values is fitted by c sgn(v) + b v + d. This reads any
    way the GA writes the same physics: ``sign`` then ``gain 1.0``, or
    ``tanh`` of a large slope after ``sign`` times ``gain 1.0``. With
    ``step``, the best matrix of that step (1-based) is read.
    """
    comp = result.compensator
    if step is not None:
        comp = Compensator(result.steps[step - 1].matrix, comp.sample_time, comp.ranges,
                           comp.record_length)
    grid = np.array([0.5, 1, 2, 5, 10, 20, 40, 60.0])
    v = np.concatenate([grid, -grid])
    tau = []
    for vel in v:
        x = comp.matrix.inputs.index(velocity)
        const = np.full(20_000, vel)
        total = 0.0
        for row in comp.matrix.rows:
            sig = const if row.input == x else np.zeros_like(const)
            total += simulate_row(comp, row, sig)[-1]
        tau.append(total)
    a = np.column_stack([np.sign(v), v, np.ones_like(v)])
    (c, b, d), *_ = np.linalg.lstsq(a, np.array(tau), rcond=None)
    return float(c), float(b), float(d)


STEP_4X2 = {"step": [{"n_rows": 2, "n_elements": 4}]}
# -- acceptance: the GA finds Coulomb + viscous friction -------------------------

def test_ga_recovers_coulomb_and_viscous_friction() -> None:
    data, floor = friction_log(5.0)
    res = run(data, STEP_4X2, seed=0, parallel=Parallel(workers=1))
    rmse = fitness(data.columns["tau_ext"] - simulate(res, data).total)
    assert rmse <= 1.05 * floor, f"rmse {rmse} vs noise floor {floor}"
    c, b, d = steady_state_friction(res)
    assert abs(c / COULOMB - 1) <= 0.02, f"Coulomb level {c}"
    assert abs(b / VISCOUS - 1) <= 0.02, f"viscous coefficient {b}"
    assert abs(d) < 0.01


@pytest.mark.slow
@pytest.mark.parametrize("seed", range(1, 9))
def test_recovery_is_reliable_across_seeds(seed: int) -> None:
    data, floor = friction_log(5.0, seed=seed)
    res = run(data, STEP_4X2, seed=seed, parallel=Parallel(workers=1))
    assert fitness(data.columns["tau_ext"] - simulate(res, data).total) <= 1.05 * floor
    c, b, _ = steady_state_friction(res)
    assert abs(c / COULOMB - 1) <= 0.02 and abs(b / VISCOUS - 1) <= 0.02


@pytest.mark.slow
@pytest.mark.parametrize("seed", [1, 2, 3])
def test_default_schedule_recovers_friction_on_a_20_s_log(seed: int) -> None:
    data, floor = friction_log(20.0, seed=seed)
    res = abstract(data, target="tau_ext", inputs=["omega", "alpha"], seed=seed, parallel=Parallel(workers=1))
    assert [s.matrix.shape for s in res.steps] == ["4x2", "4x3", "4x4", "4x5"]
    rmse = fitness(data.columns["tau_ext"] - simulate(res, data).total)
    assert rmse <= 1.05 * floor
    # Step 1 (4x2) is the size of the true model; later rows only fit noise, in
    # any shape they like (an integral of velocity, say), so read step 1.
    c, b, _ = steady_state_friction(res, step=1)
    assert abs(c / COULOMB - 1) <= 0.02 and abs(b / VISCOUS - 1) <= 0.02
    assert all(s.fitness <= 1.01 * floor for s in res.steps)


# -- determinism -----------------------------------------------------------------

def test_same_seed_gives_byte_identical_results_with_any_worker_count(friction_data: DataLog) -> None:
    one = dumps(run(friction_data, SMALL, seed=5, parallel=Parallel(workers=1)))
    assert dumps(run(friction_data, SMALL, seed=5, parallel=Parallel(workers=1))) == one
    assert dumps(run(friction_data, SMALL, seed=5, parallel=Parallel(workers=2))) == one
    assert dumps(run(friction_data, SMALL, seed=6, parallel=Parallel(workers=1))) != one


def test_a_thread_pool_executor_gives_the_same_result(friction_data: DataLog) -> None:
    from concurrent.futures import ThreadPoolExecutor

    one = dumps(run(friction_data, SMALL, seed=5, parallel=Parallel(workers=1)))
    with ThreadPoolExecutor(2) as ex:
        assert dumps(run(friction_data, SMALL, seed=5, parallel=Parallel(executor=ex))) == one
        assert not ex._shutdown  # a caller's executor is left running


@pytest.mark.parametrize("stop_after", [1, 4, 7, 8, 11])
def test_resume_after_a_stop_gives_the_uninterrupted_result(
    friction_data: DataLog, tmp_path: Path, stop_after: int
) -> None:
    want = dumps(run(friction_data, SMALL, seed=2, parallel=Parallel(workers=1)))
    ckpt = tmp_path / "r.json.checkpoint"
    seen: list[GenerationInfo] = []

    def hook(info: GenerationInfo) -> bool:
        seen.append(info)
        return len(seen) >= stop_after

    part = run(friction_data, SMALL, seed=2, parallel=Parallel(workers=1), checkpoint=ckpt, callback=hook)
    assert part.provenance["stop_reason"] == "stopped"
    assert ckpt.exists()
    again = run(friction_data, SMALL, seed=2, parallel=Parallel(workers=2), checkpoint=ckpt, resume=True)
    assert dumps(again) == want
    assert not ckpt.exists()  # a completed run removes its checkpoint


@settings(max_examples=6, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(stop_after=st.integers(1, 14))
def test_a_stop_at_a_random_generation_resumes_to_the_same_bytes(
    friction_data: DataLog, tmp_path_factory: pytest.TempPathFactory, stop_after: int
) -> None:
    want = _uninterrupted(friction_data)
    ckpt = tmp_path_factory.mktemp("ck") / "c"
    count = [0]

    def hook(info: GenerationInfo) -> bool:
        count[0] += 1
        return count[0] >= stop_after

    run(friction_data, SMALL, seed=9, parallel=Parallel(workers=1), checkpoint=ckpt, callback=hook)
    assert dumps(run(friction_data, SMALL, seed=9, parallel=Parallel(workers=1), checkpoint=ckpt,
                     resume=True)) == want


_CACHE: dict = {}


def _uninterrupted(friction_data: DataLog) -> str:
    if "r" not in _CACHE:
        _CACHE["r"] = dumps(run(friction_data, SMALL, seed=9, parallel=Parallel(workers=1)))
    return _CACHE["r"]


def test_an_interrupt_returns_the_best_so_far_and_resumes(friction_data: DataLog, tmp_path: Path) -> None:
    want = dumps(run(friction_data, SMALL, seed=4, parallel=Parallel(workers=1)))
    ckpt = tmp_path / "c"
    count = [0]

    def hook(info: GenerationInfo) -> None:
        count[0] += 1
        if count[0] == 5:
            raise KeyboardInterrupt

    part = run(friction_data, SMALL, seed=4, parallel=Parallel(workers=1), checkpoint=ckpt, callback=hook)
    assert part.provenance["stop_reason"] == "interrupted"
    assert part.steps[-1].generations == 4
    again = run(friction_data, SMALL, seed=4, parallel=Parallel(workers=1), checkpoint=ckpt, resume=True)
    assert dumps(again) == want


def test_the_checkpoint_is_written_every_few_seconds_and_whenever_a_run_stops(
        friction_data: DataLog, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    # Writing it after every generation cost 3-6 % of a run; a stop still leaves the
    # state of the last generation, so --resume starts where the run ended.
    import edm_sym.engines.abstraction.run as runmod

    written: list[int] = []
    real = runmod.save_checkpoint

    def save(path, state):  # noqa: ANN001, ANN202
        written.append(state.current.generation if state.current else -1)
        return real(path, state)

    monkeypatch.setattr(runmod, "save_checkpoint", save)
    monkeypatch.setattr(runmod, "CHECKPOINT_SECONDS", 3600.0)
    ckpt = tmp_path / "c"
    seen: list[GenerationInfo] = []

    def hook(info: GenerationInfo) -> bool:
        seen.append(info)
        return len(seen) >= 9  # in the second step

    run(friction_data, SMALL, seed=3, parallel=Parallel(workers=1), checkpoint=ckpt, callback=hook)
    # The first state, the first step's end, the stop (not the 9 generations between).
    assert written == [0, -1, seen[-1].generation] and seen[-1].generation == 1
    doc = json.loads(ckpt.read_text())
    assert doc["current"]["generation"] == seen[-1].generation == written[-1]
    assert len(doc["finished"]) == 1


def test_a_checkpoint_of_another_run_is_refused(friction_data: DataLog, tmp_path: Path) -> None:
    from edm_sym.core.errors import ConfigError

    ckpt = tmp_path / "c"
    run(friction_data, SMALL, seed=1, parallel=Parallel(workers=1), checkpoint=ckpt,
        callback=lambda info: True)
    with pytest.raises(ConfigError, match=r"found one of another seed \(1; this run: 2\)"):
        run(friction_data, SMALL, seed=2, parallel=Parallel(workers=1), checkpoint=ckpt, resume=True)


@pytest.mark.parametrize("damage", ["rng_state", "codes", "fitness", "step", "ps"])
def test_a_damaged_checkpoint_is_refused_before_the_run(friction_data: DataLog, tmp_path: Path,
                                                        damage: str) -> None:
    # Each edit keeps valid JSON; resumed, they crashed the run (KeyError, IndexError,
    # "Initial guess is outside of provided bounds", exit 1 or a library message).
    from edm_sym.core.errors import ConfigError

    ckpt = tmp_path / "c"
    seen: list[GenerationInfo] = []
    run(friction_data, SMALL, seed=1, parallel=Parallel(workers=1), checkpoint=ckpt,
        callback=lambda info: seen.append(info) or len(seen) >= 3)
    doc = json.loads(ckpt.read_text())
    cur = doc["current"]
    if damage == "rng_state":
        del doc["rng_state"]["state"]
    elif damage == "codes":
        cur["population"]["codes"][0][0][0] = -1
    elif damage == "fitness":
        cur["fitness"] = None
    elif damage == "step":
        cur["step"] = 1e308
    else:
        cur["population"]["ps"][0][0][0] = -1.0
    ckpt.write_text(json.dumps(doc, sort_keys=True))
    with pytest.raises(ConfigError, match="damaged or edited") as err:
        run(friction_data, SMALL, seed=1, parallel=Parallel(workers=1), checkpoint=ckpt, resume=True)
    assert err.value.where == f"{ckpt}: sha256"


def test_time_limit_ends_at_a_generation_boundary_with_a_valid_result(
    friction_data: DataLog, tmp_path: Path
) -> None:
    res = run(friction_data, SMALL, seed=0, parallel=Parallel(workers=1), time_limit=1e-9)
    assert res.provenance["stop_reason"] == "time_limit"
    assert len(res.steps) == 1 and res.steps[0].generations == 0
    back = load_result(save_result(res, tmp_path / "r.json"))
    assert back.fitness == res.fitness


# -- the algorithm's guarantees ----------------------------------------------------

def test_the_best_never_gets_worse_and_steps_inherit(friction_data: DataLog) -> None:
    doc = {"ga": {"population": 24, "generations": 15, "continue": "no"},
           "step": [{"n_rows": 1, "n_elements": 3}, {"n_rows": 2, "n_elements": 4},
                    {"n_rows": 3, "n_elements": 4}]}
    res = run(friction_data, doc, seed=3, parallel=Parallel(workers=1))
    for s in res.steps:
        assert all(b <= a for a, b in zip(s.history, s.history[1:], strict=False))
        assert s.history[-1] == min(s.history)
        # The record holds the reference simulator's eq. 8, the GA's to rounding.
        assert s.fitness == pytest.approx(s.history[-1], rel=1e-12)
        assert len(s.history) == s.generations + 1
    for prev, cur in zip(res.steps, res.steps[1:], strict=False):
        # Same weighting: the inherited model (new rows at zero) is in the first population.
        assert cur.history[0] <= prev.history[-1]
        assert cur.matrix.n_rows == prev.matrix.n_rows + 1


def test_a_step_starts_from_the_previous_best_as_it_is(friction_data: DataLog) -> None:
    # No restarts: the second population drawn is the second step's.
    doc = {"ga": {"population": 12, "generations": 3, "continue": "no", "restarts": 0},
           "step": [{"n_rows": 1, "n_elements": 3}, {"n_rows": 2, "n_elements": 4}]}
    seen: list = []
    orig = Operators.random_population

    def spy(self, rng, p, m, n):  # noqa: ANN001, ANN202
        pop = orig(self, rng, p, m, n)
        seen.append(pop)
        return pop

    Operators.random_population = spy
    try:
        res = run(friction_data, doc, seed=1, parallel=Parallel(workers=1))
    finally:
        Operators.random_population = orig
    first = seen[1].matrix(0, ["omega", "alpha"])  # the second step's seed individual
    prev = res.steps[0].matrix.rows[0]
    assert first.rows[0].input == prev.input
    assert first.rows[0].genes == (*prev.genes, Gene(BY_NAME["through"].code, 0.0))
    zero_row = first.rows[1].genes  # the new row outputs 0: through, ..., gain 0
    assert [g.code for g in zero_row] == [BY_NAME["through"].code] * 3 + [BY_NAME["gain"].code]
    assert BY_NAME["gain"].param.default(TS, 2.0).decode(zero_row[-1].p) == 0.0


def fitted(res: object, n: int) -> np.ndarray:
    """The samples the GA fitted: all but the held-out blocks (or segment) of the result."""
    held = res.validation["held_out"]
    keep = np.ones(n, dtype=bool)
    if held["kind"] == "blocks":
        for a, b in held["blocks"]:
            keep[a:b] = False
    elif held["kind"] == "segment":
        keep[held["rows"][0]:] = False
    return keep


def test_a_human_model_seeds_the_first_step(friction_data: DataLog) -> None:
    doc = {"ga": {"population": 16, "generations": 2, "continue": "no"},
           "initial": {"rows": [{"input": "omega", "elements": [["sign"], ["gain", 1.0]]},
                                {"input": "omega", "elements": [["gain", 0.01]]}]},
           "step": [{"n_rows": 2, "n_elements": 4}]}
    res = run(friction_data, doc, seed=0, parallel=Parallel(workers=1))
    keep = fitted(res, len(friction_data))
    data_floor = fitness((friction_data.columns["tau_ext"] - np.sign(friction_data.columns["omega"])
                          - 0.01 * friction_data.columns["omega"])[keep])
    assert res.steps[0].history[0] <= data_floor * (1 + 1e-9)


def test_a_restricted_element_set_is_respected(friction_data: DataLog) -> None:
    names = ["through", "gain", "sign", "lpf"]
    doc = {"ga": {"population": 16, "generations": 5, "continue": "no", "elements": names},
           "step": [{"n_rows": 2, "n_elements": 3}]}
    res = run(friction_data, doc, seed=0, parallel=Parallel(workers=1))
    allowed = {BY_NAME[n].code for n in names}
    for s in res.steps:
        assert {g.code for r in s.matrix.rows for g in r.genes} <= allowed


def test_windows_weighting_ignores_the_masked_part(friction_data: DataLog) -> None:
    # Only the first 0.5 s count: the target there is explained by the data alone.
    doc = {"ga": {"population": 16, "generations": 3, "continue": "no"},
           "step": [{"n_rows": 2, "n_elements": 3,
                     "weighting": {"windows": [[0.0, 0.5, 1.0]]}}]}
    res = run(friction_data, doc, seed=0, parallel=Parallel(workers=1))
    sim = simulate(res, friction_data).total
    lam = (friction_data.columns["t"] < 0.5).astype(float)
    # The fitness is eq. 8 over the samples the GA fits (20 % are held out in blocks).
    keep = fitted(res, len(friction_data))
    assert np.count_nonzero(keep) == 1600
    assert res.fitness == pytest.approx(
        fitness((friction_data.columns["tau_ext"] - sim)[keep], lam[keep]), rel=1e-9)
    assert res.steps[0].weighting == {"constant": 1.0, "windows": [[0.0, 0.5, 1.0]],
                                      "otherwise": 0.0}


# -- the result file --------------------------------------------------------------

def test_the_result_records_steps_provenance_and_ranges(friction_data: DataLog, tmp_path: Path) -> None:
    doc = {**SMALL, "ranges": {"gain": {"low": -3.0, "high": 3.0}}}
    res = run(friction_data, doc, seed=7, parallel=Parallel(workers=1))
    path = save_result(res, tmp_path / "r.json")
    back = load_result(path)
    raw = json.loads(path.read_text())
    assert raw["provenance"]["seed"] == 7
    assert raw["provenance"]["data_sha256"] is None  # an in-memory log has no file
    assert raw["provenance"]["package_version"]
    assert [s["n_rows"] for s in raw["steps"]] == [2, 3]
    assert all(s["evaluations"] > 0 and len(s["history"]) == s["generations"] + 1
               for s in raw["steps"])
    ranges = default_ranges(TS, len(friction_data) * TS)
    ranges["gain"] = ranges["gain"].__class__(-3.0, 3.0, "linear")
    assert dict(back.compensator.ranges) == ranges
    assert back.compensator.record_length == pytest.approx(len(friction_data) * TS)
    # The recorded fitness is eq. 8 of the reference simulator on the training part.
    keep = fitted(back, len(friction_data))
    ref = fitness((friction_data.columns["tau_ext"] - simulate(back, friction_data).total)[keep])
    assert back.fitness == pytest.approx(ref, rel=1e-14)
    # The exported matrix is the selected member of the pruned front; without
    # pruning it is the last step's best.
    par = back.parsimony
    assert matrix_to_json(back.matrix) == par["front"][par["selected"] - 1]["matrix"]
    plain = run(friction_data, {**doc, "parsimony": {"prune": False}}, seed=7, parallel=Parallel(workers=1))
    assert plain.matrix == res.steps[-1].matrix and not plain.parsimony


def test_the_progress_bar_shows_step_generation_best_and_rate(
    friction_data: DataLog, capsys: pytest.CaptureFixture
) -> None:
    from edm_sym.application.progress import ProgressReporter

    with ProgressReporter("test", bar=True) as reporter:
        run(friction_data, SMALL, seed=0, parallel=Parallel(workers=1), callback=reporter.abstraction)
    err = capsys.readouterr().err
    assert "step 2/2 (3x3)" in err and "best" in err and "eval/s" in err and "gen 6" in err


@pytest.mark.parametrize("restarts", [0, 1])
def test_the_engine_prints_nothing_and_reports_the_generations_left(
    friction_data: DataLog, capsys: pytest.CaptureFixture, restarts: int
) -> None:
    seen = []
    doc = {**SMALL, "ga": {**SMALL["ga"], "restarts": restarts}}
    run(friction_data, doc, seed=0, parallel=Parallel(workers=1), callback=seen.append)
    assert capsys.readouterr() == ("", "")
    # continue = "no", 6 generations per step, each restart 6 more (its generations count
    # on): the fewest generations left count down to 0 over both steps.
    per = 6 * (1 + restarts)
    assert [(i.step, i.generation) for i in seen][:2] == [(1, 0), (1, 1)]
    assert [i.generations_left for i in seen] == [per - g + (per if s == 1 else 0)
                                                  for s, g in ((i.step, i.generation) for i in seen)]
    assert seen[-1].generations_left == 0 and seen[-1].shape == (3, 3) and seen[-1].steps == 2


def test_the_config_example_in_the_docs_is_valid() -> None:
    import re

    from edm_sym.core.fileio import tomllib

    text = (Path(__file__).resolve().parents[1] / "docs" / "abstraction.md").read_text()
    block = re.search(r"```toml\n(.*?)```", text, re.S).group(1)
    cfg = parse_config(tomllib.loads(block), "docs")
    assert [s.n_rows for s in cfg.steps] == [2, 3, 5] and cfg.steps[1].ga.population == 96
