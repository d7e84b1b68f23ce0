"""Multi-fidelity evaluation (``fidelity``): full stays bit for bit, multi scores elites on all data."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from helpers import SMALL, friction_log, run

from edm_sym.core.errors import ConfigError
from edm_sym.core.result import dumps
from edm_sym.engines.abstraction import GenerationInfo, Parallel, parse_config
from edm_sym.engines.abstraction import fidelity as fidelity_module
from edm_sym.engines.abstraction.fidelity import (
    FidelitySettings,
    plan_windows,
    promoted,
    rank_multi,
)
from edm_sym.engines.simulate import fitness, simulate_rows

#: A small multi-fidelity part for the tests' logs: 8 windows of 250 samples, 50 ms warm-ups.
MULTI = {"samples": 2000, "windows": 8, "warm_up": 0.05}
#: Nothing held out: the training part is the whole log, so eq. 8 is easy to recompute.
WHOLE = {**SMALL, "validation": {"share": 0.0}, "parsimony": {"refit": 60}}


@pytest.fixture(scope="module")
def long_log():  # noqa: ANN201
    return friction_log(8.0, seed=5)[0]


def _stats(data, doc: dict, **kw):  # noqa: ANN001, ANN202
    last: list[GenerationInfo] = []
    res = run(data, doc, callback=last.append, **kw)
    return res, last[-1].stats


# -- the config key ----------------------------------------------------------------------------

def test_full_gives_the_result_of_a_run_without_the_key(friction_data) -> None:  # noqa: ANN001
    plain = dumps(run(friction_data, SMALL, seed=4, parallel=Parallel(workers=1)))
    full = {**SMALL, "fidelity": "full"}
    assert dumps(run(friction_data, full, seed=4, parallel=Parallel(workers=1))) == plain
    # auto on a short log is full, whatever the multi-fidelity settings say
    auto = {**SMALL, "fidelity": "auto", "multi_fidelity": MULTI}
    assert dumps(run(friction_data, auto, seed=4, parallel=Parallel(workers=1))) == plain
    assert "fidelity" not in json.loads(plain)["provenance"]


@pytest.mark.parametrize(("doc", "expect"), [
    ({"fidelity": "fast"}, "test.toml: fidelity: expected one of 'auto', 'full', 'multi', "
                           "found string 'fast'"),
    ({"fidelity": 1}, "test.toml: fidelity: expected one of 'auto', 'full', 'multi', found integer 1"),
    ({"multi_fidelity": {"windows": 0}}, "test.toml: multi_fidelity.windows: expected an integer >= 1"),
    ({"multi_fidelity": {"margin": -0.1}}, "test.toml: multi_fidelity.margin: expected a number >= 0"),
    ({"multi_fidelity": {"promte": 3}}, "test.toml: multi_fidelity.promte: unknown key (known: "
                                        "samples, windows, warm_up, margin, promote)"),
    ({"multi_fidelity": "multi"}, "test.toml: multi_fidelity: expected a table"),
])
def test_a_bad_fidelity_is_refused_by_name(doc: dict, expect: str) -> None:
    with pytest.raises(ConfigError) as err:
        parse_config(doc, "test.toml")
    assert str(err.value).startswith(expect)


def test_auto_runs_multi_above_the_documented_size(long_log, monkeypatch) -> None:  # noqa: ANN001
    doc = {**WHOLE, "multi_fidelity": MULTI}
    res = run(long_log, doc, seed=2, parallel=Parallel(workers=1))
    assert "fidelity" not in res.provenance  # 8 000 samples <= AUTO_SAMPLES: full
    monkeypatch.setattr(fidelity_module, "AUTO_SAMPLES", 6_000)
    res = run(long_log, doc, seed=2, parallel=Parallel(workers=1))
    assert res.provenance["fidelity"] == {"mode": "multi", "config": "auto", "samples": 2000,
                                          "windows": 8, "warm_up": 0.05, "margin": 0.02,
                                          "promote": 4}


# -- multi-fidelity runs -------------------------------------------------------------------------

def _whole_log_fitness(comp, matrix, data) -> float:  # noqa: ANN001
    """Eq. 8 of ``matrix`` with Lambda = 1 over every sample, by the reference simulator."""
    rows = simulate_rows(replace(comp, matrix=matrix), matrix.rows, data.stack(["omega", "alpha"]))
    return float(fitness(data.columns["tau_ext"] - rows.sum(axis=0), 1.0))


def test_multi_reports_whole_log_fitness_deterministically_with_fewer_whole_log_evaluations(
        long_log) -> None:  # noqa: ANN001
    multi = {**WHOLE, "fidelity": "multi", "multi_fidelity": MULTI}
    res, stats = _stats(long_log, multi, seed=3, parallel=Parallel(workers=2))
    assert res.provenance["fidelity"]["mode"] == "multi"
    # The reported fitness is eq. 8 on every training sample, recomputed independently.
    comp = res.compensator
    assert res.fitness == pytest.approx(_whole_log_fitness(comp, comp.matrix, long_log), rel=1e-9)
    for step in res.steps:
        # A step best's fitness is its whole-log eq. 8, which its history ends with.
        assert step.history[-1] == pytest.approx(step.fitness, rel=1e-9)
        assert step.fitness == pytest.approx(_whole_log_fitness(comp, step.matrix, long_log),
                                             rel=1e-9)
        assert all(b <= a for a, b in zip(step.history, step.history[1:], strict=False))
    # The same seed gives the same bytes, with another number of workers too.
    again, _ = _stats(long_log, multi, seed=3, parallel=Parallel(workers=1))
    assert dumps(again) == dumps(res)
    # Fewer individuals scored on the whole log than a run of full fidelity scores.
    _, full = _stats(long_log, {**WHOLE, "fidelity": "full"}, seed=3, parallel=Parallel(workers=1))
    assert full.full_log == full.scored > 0
    assert 0 < stats.full_log < stats.scored
    assert stats.full_log < full.full_log / 4


def test_multi_resumes_to_the_uninterrupted_result(long_log, tmp_path: Path) -> None:  # noqa: ANN001
    multi = {**WHOLE, "fidelity": "multi", "multi_fidelity": MULTI}
    want = dumps(run(long_log, multi, seed=6, parallel=Parallel(workers=1)))
    ckpt = tmp_path / "r.json.checkpoint"
    count = [0]

    def hook(info: GenerationInfo) -> bool:
        count[0] += 1
        return count[0] >= 5

    part = run(long_log, multi, seed=6, parallel=Parallel(workers=1), checkpoint=ckpt, callback=hook)
    assert part.provenance["stop_reason"] == "stopped" and ckpt.exists()
    again = run(long_log, multi, seed=6, parallel=Parallel(workers=1), checkpoint=ckpt,
                resume=True)
    assert dumps(again) == want


# -- the rule's parts ---------------------------------------------------------------------------

def test_windows_start_at_the_log_and_spread_over_the_fitted_samples() -> None:
    s = FidelitySettings(samples=400, windows=4, warm_up=0.01, margin=0.0, promote=1)
    n = 10_000
    plan = plan_windows(1.0, n, 1e-3, s)
    scored = plan.index[plan.scored]
    # The first window is the log's start (from rest, as the log); the last ends with the log.
    assert plan.index[0] == 0 and plan.scored[0] and scored[-1] == n - 1
    assert len(scored) == 400 and len(plan.index) == 400 + 3 * 10
    assert np.all(np.diff(plan.index) > 0)
    starts = scored[np.flatnonzero(np.diff(scored) > 1) + 1]
    assert starts.tolist() == [3300, 6600, 9900]
    # Each later window follows 10 warm-up samples of the log, which weigh 0.
    warm = plan.index[~plan.scored]
    assert warm.tolist() == [i for s0 in (3300, 6600, 9900) for i in range(s0 - 10, s0)]
    w = plan.weights(1.0)
    assert np.all(w[~plan.scored] == 0) and np.allclose(w[plan.scored], 430 / 400)
    # Held-out samples (Lambda 0) are never a window's start; windows lie on the fitted ones.
    lam = np.ones(n)
    lam[:5000] = 0.0
    lam[-300:] = 0.5
    lam[-100:] = 0.0
    plan = plan_windows(lam, n, 1e-3, s)
    assert plan.index[plan.scored].min() == 5000 and plan.index.max() == n - 101
    w = plan.weights(lam)
    scale = len(plan.index) / np.count_nonzero(plan.scored)
    assert np.array_equal(w, np.where(plan.scored, lam[plan.index] * scale, 0.0))


def test_elites_are_ranked_by_whole_log_and_the_rest_by_low_fidelity() -> None:
    full = np.array([np.inf, 0.5, np.inf, 0.4, 0.6])
    low = np.array([0.1, 0.55, 0.2, 0.45, 0.3])
    keys = [b"a", b"b", b"c", b"d", b"e"]
    assert rank_multi(full, low, keys, 2).tolist() == [3, 1, 0, 2, 4]
    # A repeated genome goes after every distinct one.
    low[4] = 0.05
    assert rank_multi(full, low, keys, 2).tolist() == [3, 1, 4, 0, 2]
    assert rank_multi(full, low, [b"a", b"b", b"c", b"d", b"d"], 2).tolist() == [3, 1, 0, 2, 4]
    assert rank_multi(full, low, [b"a", b"b", b"b", b"d", b"e"], 2).tolist() == [3, 1, 4, 0, 2]


def test_promotion_takes_the_lowest_within_the_margin() -> None:
    s = FidelitySettings(samples=400, windows=4, margin=0.1, promote=2)
    low = np.array([1.2, 0.9, 1.05, np.inf, 1.09, 0.5])
    assert promoted(low, 1.0, s) == [1, 5]
    assert promoted(low, 0.4, s) == []
    assert promoted(low, 0.4, s, always=(0,)) == [0]
    assert promoted(low, None, s, least=3) == [1, 2, 5]
