"""Sizes that cannot fit: refused up front with exit 2 and the figure (docs/cli.md#sizes-that-cannot-fit)."""

from __future__ import annotations

import json
import re
import warnings
from pathlib import Path

import numpy as np
import pytest
from helpers import SMALL, friction_log, run

from edm_sym.application.cli import main
from edm_sym.core import budget
from edm_sym.core.budget import (
    STATE_LIMIT_BYTES,
    TIME_LIMIT_SECONDS,
    StepSize,
    abstraction_estimate,
    check,
    check_state,
    format_bytes,
    format_seconds,
)
from edm_sym.core.errors import BudgetError, BudgetWarning
from edm_sym.core.result import load_result
from edm_sym.engines.abstraction import Parallel
from edm_sym.engines.abstraction.run import check_budget
from edm_sym.engines.abstraction.schedule import parse_config

EXAMPLE = Path(__file__).resolve().parent.parent / "examples" / "auger" / "result.json"


def _err(capsys: pytest.CaptureFixture) -> str:
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "Traceback" not in err, err
    return err


# -- the estimator -------------------------------------------------------------------

def test_figures_are_formatted_for_people() -> None:
    assert format_bytes(10 * 2**30 * 7.45) == "74.5 GiB"
    assert format_bytes(512) == "512 B"
    assert format_seconds(3 * 86400) == "3 days"
    assert format_seconds(12) == "12 s"


def test_memory_grows_with_the_population_the_matrix_and_the_log() -> None:
    def mem(p: int, m: int, n: int, samples: int) -> int:
        return abstraction_estimate([StepSize(p, m, n, 10)], n_samples=samples, n_inputs=2,
                                    cache_bytes=2**20, workers=1, time_limit=None).memory

    base = mem(64, 4, 4, 10_000)
    assert mem(640, 4, 4, 10_000) > 5 * base
    assert mem(64, 40, 4, 10_000) > 5 * base
    assert mem(64, 4, 4, 100_000) > 5 * base
    # A generation's rows dominate: three copies of population x rows x samples reals.
    assert mem(10**6, 5, 4, 16_000) >= 3 * 8 * 5 * 10**6 * 16_000


def test_time_counts_the_least_generations_and_a_time_limit_leaves_the_first() -> None:
    steps = [StepSize(64, 2, 4, 40), StepSize(64, 5, 4, 40)]
    full = abstraction_estimate(steps, n_samples=16_000, n_inputs=3, cache_bytes=0, workers=1,
                                time_limit=None)
    per_gen = [64 * 2 * 4 * 16_000, 64 * 5 * 4 * 16_000]
    assert full.seconds == pytest.approx(41 * sum(per_gen) / budget.ELEMENT_SAMPLES_PER_SECOND)
    limited = abstraction_estimate(steps, n_samples=16_000, n_inputs=3, cache_bytes=0,
                                   workers=1, time_limit=10.0)
    assert limited.seconds == pytest.approx(per_gen[0] / budget.ELEMENT_SAMPLES_PER_SECOND)


def test_check_names_the_place_the_figure_and_the_limit() -> None:
    est = budget.Estimate(3 * 2**30, 0.0, "population 9")
    with pytest.raises(BudgetError, match=r"cfg.toml: needs about 3 GiB of memory \(population 9\), "
                                          r"more than the 1 GiB this machine has available; less"):
        check(est, "cfg.toml", "less", memory=2**30)
    check(est, "cfg.toml", "less", memory=4 * 2**30)  # fits
    check(est, "cfg.toml", "less", memory=None)  # unknown memory: not refused for memory
    slow = budget.Estimate(1, 2 * TIME_LIMIT_SECONDS, "d")
    with pytest.raises(BudgetError, match=r"14 days of CPU time .*limit of 7 days; faster"):
        check(slow, "cfg.toml", "less", time_hint="faster", memory=None)


def test_the_default_schedule_on_the_auger_log_fits() -> None:
    # 20 000 samples, 4 inputs: the paper's experiment must never be refused.
    cfg = parse_config({})
    check_budget(cfg, 20_000, 4, workers=2)


# -- edm abstract, edm pipeline, EDMRegressor ------------------------------------------

@pytest.mark.parametrize("toml, figure", [
    ("[ga]\npopulation = 1000000000\n", r"needs about [\d.]+ TiB of memory \(step\[3\]: "
                                         r"population 1000000000 x 5 rows"),
    ("[[step]]\nn_rows = 100000\nn_elements = 100000\n", r"needs about [\d.]+ TiB of memory "
                                                          r"\(step\[0\]: population 64 x 100000 rows"),
    ("[ga]\ngenerations = 10000000\npatience = 0\n", r"needs at least about [\d.]+ (days|years) "
                                                     r"of CPU time"),
])
def test_abstract_refuses_absurd_sizes_before_any_work(friction_csv: Path, tmp_path: Path, capsys,
                                                       toml: str, figure: str) -> None:
    cfg = tmp_path / "big.toml"
    cfg.write_text(toml)
    out = tmp_path / "r.json"
    rc = main(["abstract", str(friction_csv), "--target", "tau_ext", "--inputs", "omega",
               "--config", str(cfg), "-o", str(out), "--quiet"])
    err = _err(capsys)
    assert rc == 2
    assert err.startswith("edm: big.toml: ") and re.search(figure, err), err
    assert not out.exists() and not (tmp_path / "r.json.checkpoint").exists()


def test_a_time_limit_bounds_the_time_estimate(friction_csv: Path) -> None:
    cfg = parse_config({"ga": {"generations": 10**7, "patience": 0}})
    with pytest.raises(BudgetError, match="CPU time"):
        check_budget(cfg, 800, 1, workers=1)
    check_budget(cfg, 800, 1, workers=1, time_limit=60.0)


def test_pipeline_refuses_before_the_lugre_identification(tmp_path: Path, capsys) -> None:
    (tmp_path / "big.toml").write_text("[ga]\npopulation = 1000000000\n")
    p = tmp_path / "pipeline.toml"
    p.write_text('[data]\nabstraction = "plant:lugre/abstraction"\n'
                 '[abstraction]\nconfig = "big.toml"\ntarget = "tau_ext"\ninputs = ["omega"]\n'
                 '[lugre]\nvelocity = "omega"\n[export]\ntarget = "c"\nout_dir = "gen"\n')
    assert main(["pipeline", str(p), "--quiet"]) == 2
    assert "big.toml: needs about" in _err(capsys)
    assert sorted(f.name for f in tmp_path.iterdir()) == ["big.toml", "pipeline.toml"]


def test_the_estimator_refuses_with_a_value_error() -> None:
    pytest.importorskip("sklearn")
    from edm_sym.application.estimator import EDMRegressor
    from edm_sym.engines.abstraction.schedule import AbstractionConfig, GaSettings, StepConfig

    cfg = AbstractionConfig((StepConfig(3, 3, ga=GaSettings(population=10**9)),),
                            source="estimator config")
    x = np.random.default_rng(0).normal(size=(500, 1))
    with pytest.raises(ValueError, match="estimator config: needs about .* of memory"):
        EDMRegressor(sample_time=1e-3, config=cfg).fit(x, x[:, 0])


# -- export: the state of a compensator ---------------------------------------------------

def _with_dead_time(tmp_path: Path, high: float, name: str) -> Path:
    doc = json.loads(EXAMPLE.read_text())
    doc["parameter_ranges"]["dead_time"] = {"low": 0.001, "high": high, "scaling": "log"}
    doc["matrix"]["rows"][0]["elements"][0] = {"code": 13, "name": "dead_time", "p": 1.0}
    path = tmp_path / name
    path.write_text(json.dumps(doc))
    return path


@pytest.mark.parametrize("target", ["c", "python", "latex"])
def test_export_refuses_a_state_of_74_gib(tmp_path: Path, capsys, target: str) -> None:
    huge = _with_dead_time(tmp_path, 1e7, "huge.json")  # 1e10 samples at Ts = 1 ms
    out = tmp_path / "gen"
    assert main(["export", str(huge), "--target", target, "-o", str(out)]) == 2
    err = _err(capsys)
    assert "huge.json: the compensator's state needs 74.5 GiB in double" in err
    assert "10000000000 samples" in err and "limit of 256 MiB" in err
    assert not out.exists() or not any(out.iterdir())


def test_export_warns_about_a_state_larger_than_a_microcontroller(tmp_path: Path, capsys) -> None:
    mid = _with_dead_time(tmp_path, 300.0, "mid.json")  # 300 000 samples
    assert main(["export", str(mid), "--target", "c", "--real", "float",
                 "-o", str(tmp_path / "gen")]) == 0
    assert ("edm: warning: mid.json: the compensator's state needs 1.14 MiB in float (the longest "
            "delay line holds 300000 samples)") in capsys.readouterr().err
    header = (tmp_path / "gen" / "edm_comp.h").read_text()
    assert "r1_e1_buf[300000]" in header
    comp = __import__("edm_sym").load_result(mid).compensator
    with pytest.warns(BudgetWarning, match="1.14 MiB in float"):
        check_state([g.element.state_size(comp.value(g), comp.sample_time)
                     for r in comp.matrix.rows for g in r.genes], "float", "mid.json")


def test_the_shipped_example_exports_without_a_word_about_size(tmp_path: Path) -> None:
    from edm_sym import load_result

    comp = load_result(EXAMPLE).compensator
    sizes = [g.element.state_size(comp.value(g), comp.sample_time)
             for r in comp.matrix.rows for g in r.genes]
    with warnings.catch_warnings():
        warnings.simplefilter("error", BudgetWarning)
        assert 0 < check_state(sizes, "double", "result.json") < 1024
    assert STATE_LIMIT_BYTES == 256 * 2**20


# -- edm simulate ------------------------------------------------------------------------------

def test_simulate_refuses_rows_that_do_not_fit(monkeypatch, tmp_path: Path, capsys) -> None:
    monkeypatch.setattr(budget, "available_memory", lambda: 4096)
    out = tmp_path / "sim.csv"
    assert main(["simulate", str(EXAMPLE), "plant:auger/evaluation", "-o", str(out)]) == 2
    err = _err(capsys)
    rows = len(load_result(EXAMPLE).matrix.rows)
    assert re.search(rf"plant:auger/evaluation: needs about [\d.]+ MiB of memory \({rows} rows x \d+ "
                     r"samples\), more than the 4 KiB", err), err
    assert not out.exists()


def test_restarts_count_in_the_time_estimate() -> None:
    # Each restart runs the step again: 10**6 of them were left out of the estimate.
    check_budget(parse_config({"ga": {"restarts": 1}}), 800, 1, workers=1)
    with pytest.raises(BudgetError, match="CPU time"):
        check_budget(parse_config({"ga": {"restarts": 10**6}}), 800, 1, workers=1)


# -- a run of multi fidelity (docs/abstraction.md#multi-fidelity-evaluation) -------------------

def test_a_long_log_is_estimated_at_multi_fidelity() -> None:
    # auto runs multi above AUTO_SAMPLES: two evaluators, the whole log's on a few individuals,
    # the windows' on short rows, so less memory and less time than the same run at full.
    from edm_sym.engines.abstraction.fidelity import AUTO_SAMPLES

    n = 8 * AUTO_SAMPLES
    auto = check_budget(parse_config({}), n, 4, workers=2, ts=1e-3)
    full = check_budget(parse_config({"fidelity": "full"}), n, 4, workers=2, ts=1e-3)
    forced = check_budget(parse_config({"fidelity": "multi"}), n, 4, workers=2, ts=1e-3)
    assert auto == forced
    assert auto.memory < full.memory and auto.seconds < full.seconds
    assert "multi fidelity" in auto.detail and "multi" not in full.detail
    # Longer windows (more samples, longer warm-ups) cost more; at most as much as the log.
    longer = check_budget(parse_config({"multi_fidelity": {"samples": 64_000}}), n, 4,
                          workers=2, ts=1e-3)
    assert auto.memory < longer.memory
    # Not past AUTO_SAMPLES: auto is full fidelity, estimated as before.
    short = AUTO_SAMPLES
    assert (check_budget(parse_config({}), short, 4, workers=2, ts=1e-3)
            == check_budget(parse_config({"fidelity": "full"}), short, 4, workers=2, ts=1e-3))


def test_a_run_refused_at_full_fidelity_fits_at_multi(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(budget, "available_memory", lambda: None)  # the figures first
    n = 400_000
    full = check_budget(parse_config({"fidelity": "full"}), n, 4, workers=2, ts=1e-3)
    multi = check_budget(parse_config({"fidelity": "auto"}), n, 4, workers=2, ts=1e-3)
    between = (full.memory + multi.memory) // 2
    monkeypatch.setattr(budget, "available_memory", lambda: between)
    with pytest.raises(BudgetError, match="of memory"):
        check_budget(parse_config({"fidelity": "full"}), n, 4, workers=2, ts=1e-3)
    check_budget(parse_config({"fidelity": "auto"}), n, 4, workers=2, ts=1e-3)


def test_abstract_checks_the_fidelity_it_runs(monkeypatch: pytest.MonkeyPatch) -> None:
    # Through abstract(): the same config and log, refused up front at full fidelity and run
    # at multi fidelity, with the log's sample time and its training samples.
    log, _ = friction_log(4.0)
    base = {**SMALL, "validation": {"share": 0.0}}  # the GA fits all 4 000 samples
    full = {**base, "fidelity": "full"}
    multi = {**base, "fidelity": "multi",
             "multi_fidelity": {"samples": 800, "windows": 4, "warm_up": 0.05}}
    monkeypatch.setattr(budget, "available_memory", lambda: None)
    sizes = [check_budget(parse_config(d), len(log), 2, workers=1, ts=log.ts)
             for d in (full, multi)]
    assert sizes[1].memory < sizes[0].memory
    monkeypatch.setattr(budget, "available_memory",
                        lambda: (sizes[0].memory + sizes[1].memory) // 2)
    with pytest.raises(BudgetError, match="test.toml: needs about .* of memory"):
        run(log, full, seed=1, parallel=Parallel(workers=1))
    res = run(log, multi, seed=1, parallel=Parallel(workers=1))
    assert res.provenance["fidelity"]["mode"] == "multi"
