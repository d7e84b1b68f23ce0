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
    # The first window (the log's first 100 samples, simulated as the log does) weighs as in
    # the log; the 300 samples of the later windows stand for the other 9 900.
    assert plan.start == 100 and plan.n == n
    first = plan.index < 100
    assert np.all(w[~plan.scored] == 0) and np.allclose(w[first], 430 / n)
    assert np.allclose(w[plan.scored & ~first], 430 / n * 9_900 / 300)
    # Held-out samples (Lambda 0) are never a window's start; windows lie on the fitted ones.
    lam = np.ones(n)
    lam[:5000] = 0.0
    lam[-300:] = 0.5
    lam[-100:] = 0.0
    plan = plan_windows(lam, n, 1e-3, s)
    assert plan.index[plan.scored].min() == 5000 and plan.index.max() == n - 101
    assert plan.start == 0  # the log's start is held out: no window starts there
    w = plan.weights(lam)
    scale = len(plan.index) / n * lam.sum() / lam[plan.index[plan.scored]].sum()
    assert np.allclose(w, np.where(plan.scored, lam[plan.index] * scale, 0.0))


def test_the_windows_estimate_the_whole_log_and_its_start_as_it_weighs() -> None:
    # A residual with a start-from-rest transient: the windows' eq. 8 is the whole log's
    # when the rest is stationary, with or without held-out blocks; weighing the first
    # window as one in four would count the transient 25 times over.
    s = FidelitySettings(samples=400, windows=4, warm_up=0.01, margin=0.0, promote=1)
    n = 10_000
    residual = np.full(n, 0.1)
    residual[:50] = 3.0
    lam = np.ones(n)
    lam[2_000:3_000] = 0.0
    for weights in (1.0, lam):
        plan = plan_windows(weights, n, 1e-3, s)
        low = fitness(residual[plan.index], plan.weights(weights))
        assert low == pytest.approx(fitness(residual, weights), rel=1e-12)
        uniform = np.where(plan.scored, 1.0, 0.0) * len(plan.index) / np.count_nonzero(plan.scored)
        assert fitness(residual[plan.index], uniform) > 2 * fitness(residual, weights)


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


# -- multi fidelity with dask, an interrupt, a weighting that moves the windows --------------------

MULTI_RUN = {**WHOLE, "fidelity": "multi", "multi_fidelity": MULTI}


def test_multi_on_a_dask_cluster_gives_the_bytes_of_one_process(long_log) -> None:  # noqa: ANN001
    # docs/abstraction.md#multi-fidelity-evaluation: "a seed gives the same result.json
    # whatever the workers", a dask cluster's among them; both evaluators use the cluster.
    distributed = pytest.importorskip("distributed")
    want = dumps(run(long_log, MULTI_RUN, seed=7, parallel=Parallel(workers=1)))
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        held: list[int] = []

        def look(info: GenerationInfo) -> None:
            if info.generation == 1 and not held:
                # Each cluster worker holds the run's data: the whole log's and the windows'.
                counts = client.run(lambda: len(__import__(
                    "edm_sym.engines.abstraction.worker", fromlist=["_WORKERS"])._WORKERS))
                held.extend(sorted(counts.values()))

        res = run(long_log, MULTI_RUN, seed=7, parallel=Parallel(scheduler=client), callback=look)
        assert res.provenance["fidelity"]["mode"] == "multi"
        assert dumps(res) == want
        assert held == [2, 2]
        # Any executor (unpinned lanes): the same bytes again.
        res = run(long_log, MULTI_RUN, seed=7,
                  parallel=Parallel(executor=client.get_executor(), workers=2))
        assert dumps(res) == want


def test_an_interrupt_of_multi_returns_whole_log_scores_and_resumes(long_log,  # noqa: ANN001
                                                                   tmp_path: Path) -> None:
    # As at full fidelity (tests/test_abstraction.py): Ctrl-C in a callback ends the run at
    # the generation boundary with the best so far, and --resume gives the uninterrupted bytes.
    want = dumps(run(long_log, MULTI_RUN, seed=4, parallel=Parallel(workers=1)))
    ckpt = tmp_path / "c"
    count = [0]

    def hook(info: GenerationInfo) -> None:
        count[0] += 1
        if count[0] == 10:  # step 2 (7 boundaries a step), generation 2
            raise KeyboardInterrupt

    # Two workers: the interrupt shuts both evaluators' processes down.
    part = run(long_log, MULTI_RUN, seed=4, parallel=Parallel(workers=2), checkpoint=ckpt,
               callback=hook)
    assert part.provenance["stop_reason"] == "interrupted" and ckpt.exists()
    assert [s.step for s in part.steps] == [1, 2] and part.steps[-1].generations == 2
    # The step in progress reports its best by the whole log, not by the windows.
    comp = part.compensator
    for step in part.steps:
        assert step.history[-1] == pytest.approx(step.fitness, rel=1e-9)
        assert step.fitness == pytest.approx(_whole_log_fitness(comp, step.matrix, long_log),
                                             rel=1e-9)
    again = run(long_log, MULTI_RUN, seed=4, parallel=Parallel(workers=1), checkpoint=ckpt,
                resume=True)
    assert dumps(again) == want and not ckpt.exists()


#: Step 1 fits the velocity steps (0-4 s), step 2 the whole log, the chirp (4-8 s) four
#: times as much: the second step's windows are not the first's.
MOVING = {**MULTI_RUN, "step": [
    {"n_rows": 2, "n_elements": 3, "weighting": {"windows": [[0.0, 4.0, 1.0]], "otherwise": 0.0}},
    {"n_rows": 3, "n_elements": 3, "weighting": {"windows": [[4.0, 8.0, 1.0]],
                                                  "otherwise": 0.25}}]}


def test_a_weighting_that_moves_the_windows_scores_each_step_with_its_own(
        long_log, monkeypatch: pytest.MonkeyPatch) -> None:  # noqa: ANN001
    from edm_sym.engines.abstraction.ga import Population
    from edm_sym.engines.abstraction.multi import MultiSteps

    cfg = parse_config(MOVING, "test.toml")
    t, y = long_log.columns["t"], long_log.columns["tau_ext"]
    x = long_log.stack(["omega", "alpha"])
    lams = [np.broadcast_to(s.weighting.weights(t, y), y.shape) for s in cfg.steps]
    plans = [plan_windows(lam, len(y), long_log.ts, FidelitySettings(**MULTI)) for lam in lams]
    assert plans[0] != plans[1]
    assert np.all(t[plans[0].index[plans[0].scored]] < 4.0)
    # Every individual judged, as the windows' evaluator left it (gain-fitted), and its scores.
    judged: list = []
    real = MultiSteps.judge

    def judge(self, pop, ops, reference, **kw):  # noqa: ANN001, ANN202
        full, low, made = real(self, pop, ops, reference, **kw)
        judged.append((self.fid.plan, pop.take(np.arange(len(pop))), low.copy(), full.copy()))
        return full, low, made

    monkeypatch.setattr(MultiSteps, "judge", judge)
    res = run(long_log, MOVING, seed=5, parallel=Parallel(workers=1))
    assert res.provenance["stop_reason"] == "completed"
    # Each step judges on its own windows: step 1's first, then step 2's.
    k = [plans.index(p) for p, *_ in judged]
    assert k == sorted(k) and set(k) == {0, 1}
    comp = res.compensator

    def eq8(pop: Population, i: int, xs: np.ndarray, ys: np.ndarray, lam) -> float:  # noqa: ANN001
        matrix = pop.matrix(i, ["omega", "alpha"])
        rows = simulate_rows(replace(comp, matrix=matrix), matrix.rows, xs)
        return float(fitness(ys - rows.sum(axis=0), lam))

    checked = [0, 0]
    for plan, pop, low, full in judged[::4]:
        s = plans.index(plan)
        w = plan.weights(lams[s])
        idx = plan.index
        for i in np.flatnonzero(np.isfinite(low))[:3].tolist():
            # The windows' eq. 8 is the step's Lambda on the windows (step 2's: not Lambda = 1).
            assert low[i] == pytest.approx(eq8(pop, i, x[:, idx], y[idx], w), rel=1e-7)
            if s == 1:
                assert low[i] != pytest.approx(eq8(pop, i, x[:, idx], y[idx],
                                                   plan.weights(1.0)), rel=1e-3)
            checked[s] += 1
        for i in np.flatnonzero(np.isfinite(full))[:2].tolist():
            assert full[i] == pytest.approx(eq8(pop, i, x, y, lams[s]), rel=1e-7)
    assert min(checked) > 0
    # A step best's fitness is its whole-log eq. 8 with the step's own weighting.
    for step, lam in zip(res.steps, lams, strict=True):
        assert step.history[-1] == pytest.approx(step.fitness, rel=1e-9)
        matrix = step.matrix
        rows = simulate_rows(replace(comp, matrix=matrix), matrix.rows, x)
        assert step.fitness == pytest.approx(float(fitness(y - rows.sum(axis=0), lam)), rel=1e-9)
    # Deterministic: the same seed gives the same bytes (with two workers too).
    monkeypatch.undo()
    assert dumps(run(long_log, MOVING, seed=5, parallel=Parallel(workers=2))) == dumps(res)
