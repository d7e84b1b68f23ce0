"""Robust search: least-squares tuning of the elite, restarts of a stagnating step."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from helpers import SMALL, TS, friction_log

from edm_sym.core.data import DataLog
from edm_sym.core.elements import BY_NAME, default_ranges
from edm_sym.core.errors import ConfigError
from edm_sym.core.result import dumps
from edm_sym.engines.abstraction import GenerationInfo, abstract, parse_config
from edm_sym.engines.abstraction import run as run_module
from edm_sym.engines.abstraction.evaluator import Evaluator
from edm_sym.engines.abstraction.ga import Population
from edm_sym.engines.abstraction.local_search import free_parameters, tune_parameters
from edm_sym.engines.abstraction.parallel import Parallel


def run(data: DataLog, doc: dict, **kw) -> object:
    return abstract(data, target="tau_ext", inputs=["omega", "alpha"],
                    config=parse_config(doc, "test.toml"), **kw)


def _individual(ranges: dict, coulomb: float, viscous: float, cutoff: float) -> Population:
    """[sign, gain c, lpf f] on omega + [power_gain b, through, through] on omega."""
    code = {name: BY_NAME[name].code for name in ("sign", "gain", "lpf", "power_gain", "through")}
    return Population(
        np.array([[0, 0]]),
        np.array([[[code["sign"], code["gain"], code["lpf"]],
                   [code["power_gain"], code["through"], code["through"]]]]),
        np.array([[[0.0, ranges["gain"].encode(coulomb), ranges["lpf"].encode(cutoff)],
                   [ranges["power_gain"].encode(viscous), 0.0, 0.0]]]))


@pytest.fixture(scope="module")
def problem():  # noqa: ANN201
    data, floor = friction_log(2.0, seed=3)
    x = data.stack(["omega", "alpha"])
    y = data.columns["tau_ext"]
    ranges = default_ranges(TS, len(y) * TS)
    with Evaluator(x, y, TS, ranges, workers=1) as ev:
        ev.start()
        yield ev, ranges, floor


def test_free_parameters_are_the_genes_with_a_parameter(problem) -> None:  # noqa: ANN001
    _, ranges, _ = problem
    ind = _individual(ranges, 0.7, 0.02, 50.0)
    assert free_parameters(ind.codes[0]) == [(0, 1), (0, 2), (1, 0)]


def test_least_squares_tunes_a_detuned_elite_to_the_best_of_its_structure(problem) -> None:  # noqa: ANN001
    ev, ranges, _ = problem
    ev.set_weights(1.0)
    ind = _individual(ranges, 0.7, 0.02, 50.0)
    f0 = float(ev.evaluate(ind.inputs, ind.codes, ind.ps)[0])
    # The best this structure can do: the truth (1.0, 0.01) with the fastest filter.
    ideal = _individual(ranges, 1.0, 0.01, ranges["lpf"].high)
    f_ideal = float(ev.evaluate(ideal.inputs, ideal.codes, ideal.ps)[0])
    out, f, used = tune_parameters(ev, ind, f0, max_evaluations=200)
    assert 0 < used <= 200
    assert f <= 1.001 * f_ideal, f"{f} vs {f_ideal} (from {f0})"
    assert f == pytest.approx(float(ev.evaluate(out.inputs, out.codes, out.ps)[0]), rel=1e-12)
    assert np.array_equal(out.codes, ind.codes) and np.array_equal(out.inputs, ind.inputs)
    again = tune_parameters(ev, ind, f0, max_evaluations=200)
    assert again[1] == f and np.array_equal(again[0].ps, out.ps)  # deterministic


def test_least_squares_never_returns_a_worse_individual(problem) -> None:  # noqa: ANN001
    ev, ranges, _ = problem
    ev.set_weights(1.0)
    ind = _individual(ranges, 0.7, 0.02, 50.0)
    f0 = float(ev.evaluate(ind.inputs, ind.codes, ind.ps)[0])
    out, f, used = tune_parameters(ev, ind, f0, max_evaluations=2)  # too small to start
    assert (f, used) == (f0, 0) and np.array_equal(out.ps, ind.ps)
    out, f, used = tune_parameters(ev, ind, f0, max_evaluations=6)  # stops within budget
    assert used <= 6 and f <= f0


def test_a_relay_band_inside_the_noise_at_rest_is_widened_by_the_scan() -> None:
    """An axis at rest with velocity noise of 0.01 rad/s while the torque is still 0.

    A Coulomb relay whose band (0.004 rad/s) is inside the noise switches on it
    and holds the wrong level until the axis moves; the least squares' forward
    differences do not see the band's step, the scan does.
    """
    from edm_sym.engines.abstraction.local_search import scan_relay_bands

    t = np.arange(2000) * TS
    omega = np.sin(2 * np.pi * 1.3 * (t - 0.3)) * (t >= 0.3)
    rest = t < 0.3
    omega[rest] = 0.01 * np.sin(2 * np.pi * 37.0 * t[rest] + 1.0)  # noise of the axis at rest
    tau = np.where(rest, 0.0, np.sign(omega))
    ranges = default_ranges(TS, len(t) * TS)
    relay = BY_NAME["hysteresis"]
    ind = Population(np.array([[0]]), np.array([[[relay.code, BY_NAME["gain"].code]]]),
                     np.array([[[ranges["hysteresis"].encode(0.004),
                                 ranges["gain"].encode(1.0)]]]))
    with Evaluator(omega[None, :], tau, TS, ranges, workers=1) as ev:
        f0 = float(ev.evaluate(ind.inputs, ind.codes, ind.ps)[0])
        assert f0 > 0.3  # latched on the noise: a wrong level of 1 for most of 0.3 s of 2 s
        tuned, _, _ = tune_parameters(ev, ind, f0, max_evaluations=200)
        assert ranges["hysteresis"].decode(tuned.ps[0, 0, 0]) < 0.01  # still inside the noise
        out, f2, used = scan_relay_bands(ev, ind, f0, ranges)
        band = ranges["hysteresis"].decode(out.ps[0, 0, 0])
        # The narrowest band of the scan above the noise (0.004 * 2^(6/4)): it switches
        # once the axis moves, a sample late at each reversal.
        assert band == pytest.approx(0.004 * 2 ** 1.5, rel=1e-9) and used == 16
        assert f2 < 0.3 * f0
        assert f2 == pytest.approx(float(ev.evaluate(out.inputs, out.codes, out.ps)[0]),
                                   rel=1e-12)
        # Nothing to scan, or nothing better: the individual comes back unchanged.
        again, f3, _ = scan_relay_bands(ev, out, f2, ranges)
        assert f3 == f2 and np.array_equal(again.ps, out.ps)
        sign = Population(ind.inputs, np.array([[[BY_NAME["sign"].code, ind.codes[0, 0, 1]]]]),
                          ind.ps.copy())
        assert scan_relay_bands(ev, sign, 1.0, ranges)[1:] == (1.0, 0)


def test_a_step_stagnating_calls_the_local_search_unless_it_is_off(
        friction_data: DataLog, monkeypatch: pytest.MonkeyPatch) -> None:
    calls: list[float] = []
    orig = run_module.tune_parameters

    def spy(evaluator, best, fitness, **kw):  # noqa: ANN001, ANN003, ANN202
        calls.append(fitness)
        return orig(evaluator, best, fitness, **kw)

    monkeypatch.setattr(run_module, "tune_parameters", spy)
    doc = {**SMALL, "ga": {**SMALL["ga"], "local_search": 2}}
    run(friction_data, doc, seed=1, parallel=Parallel(workers=1))
    assert calls
    calls.clear()
    run(friction_data, {**SMALL, "ga": {**SMALL["ga"], "local_search": 0}}, seed=1,
        parallel=Parallel(workers=1))
    assert not calls


RESTART = {"ga": {"population": 16, "generations": 4, "continue": "improving", "max_blocks": 3,
                  "patience": 3, "local_search": 2},
           "step": [{"n_rows": 2, "n_elements": 3}, {"n_rows": 3, "n_elements": 3}]}


def _with(doc: dict, **ga) -> dict:
    return {**doc, "ga": {**doc["ga"], **ga}}


def test_restarts_continue_a_stagnating_step_and_never_lose_the_best(friction_data: DataLog) -> None:
    plain = run(friction_data, _with(RESTART, restarts=0), seed=3, parallel=Parallel(workers=1))
    again = run(friction_data, _with(RESTART, restarts=2), seed=3, parallel=Parallel(workers=1))
    for a, b in zip(plain.steps, again.steps, strict=True):
        assert b.generations > a.generations
        assert all(np.diff(b.history) <= 0)  # the elites survive a restart
    assert again.steps[0].fitness <= plain.steps[0].fitness


def test_restarts_are_deterministic_with_any_worker_count(friction_data: DataLog) -> None:
    doc = _with(RESTART, restarts=1)
    one = dumps(run(friction_data, doc, seed=4, parallel=Parallel(workers=1)))
    assert dumps(run(friction_data, doc, seed=4, parallel=Parallel(workers=2))) == one


@pytest.mark.parametrize("stop_after", [5, 9, 14])
def test_a_run_with_restarts_resumes_to_the_same_bytes(
        friction_data: DataLog, tmp_path: Path, stop_after: int) -> None:
    doc = _with(RESTART, restarts=1)
    want = dumps(run(friction_data, doc, seed=2, parallel=Parallel(workers=1)))
    ckpt = tmp_path / "c"
    count = [0]

    def hook(info: GenerationInfo) -> bool:
        count[0] += 1
        return count[0] >= stop_after

    run(friction_data, doc, seed=2, parallel=Parallel(workers=1), checkpoint=ckpt, callback=hook)
    assert dumps(run(friction_data, doc, seed=2, parallel=Parallel(workers=1), checkpoint=ckpt,
                     resume=True)) == want


@pytest.mark.parametrize(("key", "value"), [("restarts", -1), ("local_search", -1),
                                            ("local_search_evaluations", 0),
                                            ("restarts", 1.5)])
def test_bad_search_settings_are_refused(key: str, value: object) -> None:
    with pytest.raises(ConfigError, match=key):
        parse_config({"ga": {key: value}}, "cfg.toml")
