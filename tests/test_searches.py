"""Independent searches (``searches`` > 1): seeds, determinism, the choice, stops and resumes."""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest
from helpers import SMALL, run

from edm_sym.core.data import DataLog
from edm_sym.core.errors import ConfigError
from edm_sym.core.result import dumps, load_result, save_result
from edm_sym.engines.abstraction import GenerationInfo
from edm_sym.engines.abstraction.parallel import Parallel
from edm_sym.engines.abstraction.searches import search_seeds

TWO = {**SMALL, "searches": 2}


@pytest.fixture(scope="module")
def two_one_worker(friction_data: DataLog) -> str:
    return dumps(run(friction_data, TWO, seed=5, parallel=Parallel(workers=1)))


def test_search_0_has_the_runs_seed_and_the_others_distinct_safe_integers() -> None:
    seeds = search_seeds(7, 5)
    assert seeds[0] == 7
    assert len(set(seeds)) == 5
    assert all(0 <= s < 2**53 for s in seeds)
    assert search_seeds(7, 5) == seeds
    assert search_seeds(7, 3) == seeds[:3]  # more searches keep the first ones
    assert search_seeds(8, 5)[1:] != seeds[1:]


def test_two_searches_give_the_same_bytes_with_one_worker_and_two(friction_data: DataLog,
                                                                  two_one_worker: str) -> None:
    assert dumps(run(friction_data, TWO, seed=5, parallel=Parallel(workers=2))) == two_one_worker


def test_searches_one_after_another_on_an_executor_give_the_same_bytes(
    friction_data: DataLog, two_one_worker: str
) -> None:
    with ThreadPoolExecutor(2) as ex:
        assert dumps(run(friction_data, TWO, seed=5, parallel=Parallel(executor=ex))) == two_one_worker


def test_search_0_is_the_one_search_run_and_the_model_comes_from_the_pooled_candidates(
    friction_data: DataLog, tmp_path: Path
) -> None:
    one = run(friction_data, SMALL, seed=5, parallel=Parallel(workers=1))
    res = run(friction_data, TWO, seed=5, parallel=Parallel(workers=2))
    found = res.provenance["searches"]
    assert [s["seed"] for s in found] == search_seeds(5, 2)
    # Search 0 is exactly the run with one search: more searches never lose its model.
    assert found[0]["step_fitness"] == [s.fitness for s in one.steps]
    assert found[0]["evaluations"] == sum(s.evaluations for s in one.steps)
    assert found[1]["step_fitness"] != found[0]["step_fitness"]
    assert all(s["stop_reason"] == "completed" for s in found)
    (chosen,) = [s for s in found if s["chosen"]]
    assert [s.fitness for s in res.steps] == chosen["step_fitness"]
    cands = res.parsimony["start_candidates"]
    assert {c["search"] for c in cands} == {0, 1}
    # Every step best of both searches is a candidate, with its refit when that helped.
    assert sum(not c["refitted"] for c in cands) == len(one.steps) + len(found[1]["step_fitness"])
    (pick,) = [c for c in cands if c["chosen"]]
    assert pick["search"] == chosen["search"]
    low = min(c["whole_rmse"][0] for c in cands)
    tied = [c for c in cands if c["whole_rmse"][0] <= low * (1 + res.parsimony["start_tie"])]
    assert pick["held_out_rmse"][0] == min(c["held_out_rmse"][0] for c in tied)
    # The one search's candidates are among them, scored alike.
    mine = [(c["step"], c["refitted"], c["whole_rmse"][0])
            for c in one.parsimony["start_candidates"]]
    assert mine == [(c["step"], c["refitted"], c["whole_rmse"][0]) for c in cands
                    if c["search"] == 0]
    # The file says all of it, and the schema takes it.
    save_result(res, tmp_path / "r.json")
    again = load_result(tmp_path / "r.json")
    assert again.provenance["searches"] == found


def test_each_search_reports_and_a_callback_stop_ends_them_all(friction_data: DataLog) -> None:
    seen: list[GenerationInfo] = []

    def hook(info: GenerationInfo) -> bool:
        seen.append(info)
        return sum(1 for i in seen if i.search == 1) >= 3

    res = run(friction_data, TWO, seed=5, parallel=Parallel(workers=2), callback=hook)
    assert {i.search for i in seen} == {0, 1}
    assert all(i.searches == 2 for i in seen)
    assert res.provenance["stop_reason"] == "stopped"
    assert any(s["stop_reason"] == "stopped" for s in res.provenance["searches"])


def test_a_stopped_run_of_two_searches_resumes_to_the_uninterrupted_bytes(
    friction_data: DataLog, tmp_path: Path, two_one_worker: str
) -> None:
    ckpt = tmp_path / "r.json.checkpoint"
    count = [0]

    def hook(info: GenerationInfo) -> bool:
        count[0] += 1
        return count[0] >= 6

    part = run(friction_data, TWO, seed=5, parallel=Parallel(workers=1), checkpoint=ckpt, callback=hook)
    assert part.provenance["stop_reason"] == "stopped"
    # One after another on one worker: search 0 stopped, search 1 never began.
    assert [s["stop_reason"] for s in part.provenance["searches"]] == ["stopped", "stopped"]
    assert part.provenance["searches"][1]["step_fitness"] == []
    files = [tmp_path / f"r.json.checkpoint.search{k}" for k in range(2)]
    assert files[0].exists() and not ckpt.exists()
    again = run(friction_data, TWO, seed=5, parallel=Parallel(workers=2), checkpoint=ckpt, resume=True)
    assert dumps(again) == two_one_worker
    assert not any(f.exists() for f in files)


@pytest.mark.parametrize("value, expect", [
    (0, "expected an integer from 1 to 64, found integer 0"),
    (65, "expected an integer from 1 to 64, found integer 65"),
    (True, "expected an integer from 1 to 64, found boolean true"),
    ("2", "expected an integer from 1 to 64, found string '2'"),
])
def test_a_bad_number_of_searches_is_refused_naming_the_key(friction_data: DataLog, value: object,
                                                           expect: str) -> None:
    with pytest.raises(ConfigError) as err:
        run(friction_data, {**SMALL, "searches": value}, seed=1, parallel=Parallel(workers=1))
    assert err.value.where == "test.toml: searches" and expect in err.value.problem
    with pytest.raises(ConfigError) as err:
        run(friction_data, SMALL, seed=1, parallel=Parallel(workers=1), searches=value)
    assert err.value.where == "searches"


def test_searches_on_a_dask_cluster_run_one_worker_each_and_give_the_same_bytes(
    friction_data: DataLog, two_one_worker: str
) -> None:
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        seen: list[GenerationInfo] = []
        res = run(friction_data, TWO, seed=5, parallel=Parallel(scheduler=client), callback=seen.append)
        assert dumps(res) == two_one_worker
        # Each search was a task of its own: both report, from the workers' processes.
        assert {i.search for i in seen} == {0, 1}
        # A stop from this process reaches the searches on the workers (at their next
        # report, within about 0.5 s): each would run 400 generations.
        long = {**TWO, "ga": {**TWO["ga"], "generations": 400, "patience": 0},
                "step": TWO["step"][:1]}
        stopped = run(friction_data, long, seed=5, parallel=Parallel(scheduler=client),
                      callback=lambda info: True)
        assert [s["stop_reason"] for s in stopped.provenance["searches"]] == ["stopped"] * 2
        assert all(s.generations < 400 for s in stopped.steps)


def test_with_the_last_step_rule_the_search_of_the_lowest_last_step_fitness_is_taken(
    friction_data: DataLog
) -> None:
    doc = {**TWO, "parsimony": {"start": "last-step"}}
    res = run(friction_data, doc, seed=5, parallel=Parallel(workers=2))
    found = res.provenance["searches"]
    last = [s["step_fitness"][-1] for s in found]
    (chosen,) = [s for s in found if s["chosen"]]
    assert chosen["search"] == min(range(2), key=lambda k: (last[k], k))
    assert [s.fitness for s in res.steps] == chosen["step_fitness"]
    assert "start_candidates" not in res.parsimony


@pytest.mark.parametrize("workers", [1, 2])
def test_an_error_in_a_search_ends_the_run_with_that_error(friction_data: DataLog, workers: int) -> None:
    # A weighting that is zero on every sample is found when a search starts its step.
    doc = {**TWO, "step": [{"n_rows": 2, "n_elements": 3,
                            "weighting": {"windows": [[900.0, 901.0, 1.0]], "otherwise": 0.0}}]}
    with pytest.raises(ConfigError) as err:
        run(friction_data, doc, seed=5, parallel=Parallel(workers=workers))
    assert "weighting" in err.value.where and "all zero" in err.value.problem
