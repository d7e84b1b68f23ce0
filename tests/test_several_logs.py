"""Several logs, one model: each log simulated from rest on its own, eq. 8 over all of them."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from conftest import TS

from edm_sym.application.cli import main
from edm_sym.core.data import DataLog, join_logs, write_csv
from edm_sym.core.errors import DataFormatError
from edm_sym.core.matrix import Compensator
from edm_sym.engines.abstraction import AbstractionConfig, GaSettings, StepConfig, abstract
from edm_sym.engines.abstraction.evaluator import Evaluator
from edm_sym.engines.abstraction.ga import Operators
from edm_sym.engines.abstraction.parallel import Parallel
from edm_sym.engines.abstraction.schedule import default_ranges
from edm_sym.engines.simulate import simulate_row

CONFIG = """
[ga]
population = 16
generations = 3

[[step]]
n_rows = 2
n_elements = 3

[validation]
blocks = 2
"""


def _columns(seed: int, n: int) -> dict[str, np.ndarray]:
    rng = np.random.default_rng(seed)
    t = np.arange(n) * TS
    omega = np.sin(2 * np.pi * (2 + seed) * t) + 0.05 * rng.standard_normal(n)
    # A lagged friction torque: a row needs a filter (state) to fit it.
    tau = np.convolve(0.3 * np.tanh(20 * omega) + 0.05 * omega, np.full(5, 0.2))[:n]
    return {"t": t, "omega": omega, "tau": tau + 0.01 * rng.standard_normal(n)}


def _log(seed: int, n: int) -> DataLog:
    return DataLog(_columns(seed, n), TS, f"log{seed}.csv", f"{seed:064x}")


def _population(seed: int = 3, size: int = 24):
    ga = GaSettings(population=size, elements=("gain", "lpf", "dead_time", "hysteresis", "sign",
                                                "integral", "through"))
    return Operators(ga, 1).random_population(np.random.default_rng(seed), size, 2, 3)


def test_a_row_runs_each_log_from_rest() -> None:
    from edm_sym.core.matrix import ElementMatrix

    a, b = _log(1, 300), _log(2, 200)
    pop = _population()
    ranges = default_ranges(TS, 300 * TS)
    for k in range(len(pop)):
        m: ElementMatrix = pop.matrix(k, ("omega",))
        comp = Compensator(m, TS, ranges, 300 * TS)
        for row in m.rows:
            x = np.concatenate([a.columns["omega"], b.columns["omega"]])
            got = simulate_row(comp, row, x, starts=(300,))
            want = np.concatenate([simulate_row(comp, row, a.columns["omega"]),
                                   simulate_row(comp, row, b.columns["omega"])])
            np.testing.assert_array_equal(got, want)


def test_the_fitness_over_two_logs_is_their_length_weighted_sum() -> None:
    # Eq. 8 over both logs, each simulated on its own: the mean square error over all
    # their samples, i.e. each log's weighted by its length.
    a, b = _log(1, 300), _log(2, 200)
    ranges = default_ranges(TS, 300 * TS)
    pop = _population()
    joined = join_logs([a, b], ["tau", "omega"])

    def fit(log: DataLog, starts=()) -> np.ndarray:
        with Evaluator(log.stack(["omega"]), log.columns["tau"], TS, ranges, workers=1,
                       starts=starts) as ev:
            return ev.evaluate(pop.inputs, pop.codes, pop.ps)

    both = fit(joined, (300,))
    fa, fb = fit(a), fit(b)
    ok = np.isfinite(both)
    assert ok.sum() > len(pop) // 2
    np.testing.assert_allclose(both[ok], np.sqrt((300 * fa**2 + 200 * fb**2) / 500)[ok],
                               rtol=1e-9)
    # Laid end to end without the restart, a filter's state would cross into the next
    # log: some individuals (those with state) score otherwise.
    crossed = fit(joined)
    assert not np.allclose(crossed[ok], both[ok], rtol=1e-9)


def test_several_logs_run_on_the_row_kernel_as_the_reference_runs_them() -> None:
    # The fitness over two logs on the row kernel (each state restarting at the second
    # log's first sample) equals the reference realisations' (each log from rest).
    from edm_sym.engines import kernel

    a, b = _log(1, 300), _log(2, 200)
    ranges = default_ranges(TS, 300 * TS)
    pop = _population(seed=5, size=32)
    joined = join_logs([a, b], ["tau", "omega"])
    scores = []
    for use_kernel in (True, False):
        with Evaluator(joined.stack(["omega"]), joined.columns["tau"], TS, ranges, workers=1,
                       starts=(300,)) as ev:
            assert ev._local.use_kernel is kernel.NUMBA
            ev._local.use_kernel = use_kernel
            scores.append(ev.evaluate(pop.inputs, pop.codes, pop.ps))
    fast, reference = scores
    np.testing.assert_array_equal(np.isfinite(fast), np.isfinite(reference))
    ok = np.isfinite(reference)
    assert ok.sum() > len(pop) // 2
    np.testing.assert_allclose(fast[ok], reference[ok], rtol=1e-9)


def test_two_logs_give_the_model_of_their_summed_fitness() -> None:
    a, b = _log(1, 400), _log(2, 300)
    cfg = AbstractionConfig(steps=(StepConfig(n_rows=2, n_elements=3,
                                              ga=GaSettings(population=16, generations=3)),))
    res = abstract([a, b], target="tau", inputs=["omega"], config=cfg, seed=2, parallel=Parallel(workers=1))
    # The exported model's training score, recomputed log by log from rest.
    comp = res.compensator
    held = res.validation["held_out"]
    assert held["kind"] == "blocks"
    assert [lg["file"] for lg in held["logs"]] == ["log1.csv", "log2.csv"]
    assert held["logs"][1]["rows"] == [400, 700]
    # Held-out blocks in every log.
    assert any(s[1] <= 400 for s in held["blocks"]) and any(s[0] >= 400 for s in held["blocks"])
    mask = np.zeros(700, dtype=bool)
    for s0, s1 in held["blocks"]:
        mask[s0:s1] = True
    e = []
    for log in (a, b):
        out = sum(simulate_row(comp, row, log.columns["omega"]) for row in comp.matrix.rows)
        e.append(log.columns["tau"] - out)
    e = np.concatenate(e)
    rmse = float(np.sqrt(np.mean(e[~mask] ** 2)))
    assert res.validation["training"]["rmse"][0] == pytest.approx(rmse, rel=1e-9)
    assert [lg["file"] for lg in res.logs] == ["log1.csv", "log2.csv"]
    assert [lg["rows"] for lg in res.logs] == [400, 300]
    # The same seed, the same result; the order of the logs is part of the data.
    again = abstract([a, b], target="tau", inputs=["omega"], config=cfg, seed=2, parallel=Parallel(workers=1))
    assert again.compensator.matrix == comp.matrix


def test_logs_of_another_sample_time_or_role_are_refused_naming_the_file() -> None:
    a = _log(1, 300)
    b = DataLog(_columns(2, 200), 2 * TS, "slow.csv", "0" * 64)
    with pytest.raises(DataFormatError) as info:
        join_logs([a, b], ["tau", "omega"])
    assert info.value.where == "slow.csv: sample time"
    c = DataLog(_columns(2, 200), TS, "roles.csv", "0" * 64, roles={"omega": "velocity"})
    with pytest.raises(DataFormatError) as info:
        join_logs([a, c], ["tau", "omega"])
    assert info.value.where == "roles.csv: column 'omega'"
    assert info.value.problem == "expected the role None as in log1.csv, found 'velocity'"


def _write(tmp_path: Path, name: str, seed: int, n: int, ts: float = TS) -> Path:
    cols = _columns(seed, n)
    cols["t"] = np.arange(n) * ts
    return write_csv(tmp_path / name, cols)


def test_edm_abstract_takes_several_logs(tmp_path: Path, capsys) -> None:
    cfg = tmp_path / "cfg.toml"
    cfg.write_text(CONFIG)
    a, b = _write(tmp_path, "a.csv", 1, 400), _write(tmp_path, "b.csv", 2, 300)
    out = tmp_path / "r.json"
    args = ["abstract", str(a), str(b), "--target", "tau", "--inputs", "omega", "--config",
            str(cfg), "--quiet", "--workers", "1", "-o", str(out)]
    assert main(args) == 0
    doc = json.loads(out.read_text())
    assert [lg["file"] for lg in doc["logs"]] == ["a.csv", "b.csv"]
    assert all(lg["use"] == "abstraction" for lg in doc["logs"])
    # The config's data list, relative to the config file.
    cfg.write_text('data = ["a.csv", "b.csv"]\n' + CONFIG)
    out2 = tmp_path / "r2.json"
    assert main([*args[:1], *args[3:-1], str(out2)]) == 0
    assert json.loads(out2.read_text())["matrix"] == doc["matrix"]
    # Another sample time: exit 2, one line naming the file.
    c = _write(tmp_path, "c.csv", 3, 300, ts=2 * TS)
    capsys.readouterr()
    assert main([args[0], str(a), str(c), *args[3:]]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "c.csv: sample time" in err[0]


def test_the_estimator_fits_several_logs_by_groups_or_a_list() -> None:
    pytest.importorskip("sklearn")
    from edm_sym import EDMRegressor

    a, b = _columns(1, 400), _columns(2, 300)
    cfg = AbstractionConfig(steps=(StepConfig(n_rows=2, n_elements=3,
                                              ga=GaSettings(population=16, generations=3)),))
    X = np.concatenate([a["omega"], b["omega"]])[:, None]
    y = np.concatenate([a["tau"], b["tau"]])
    groups = np.r_[np.zeros(400), np.ones(300)]
    est = EDMRegressor(sample_time=TS, config=cfg, seed=2, workers=1, target_name="tau")
    est.fit(X, y, feature_names=["omega"], groups=groups)
    by_list = EDMRegressor(sample_time=TS, config=cfg, seed=2, workers=1, target_name="tau")
    by_list.fit([X[:400], X[400:]], [y[:400], y[400:]], feature_names=["omega"])
    assert by_list.result_.compensator.matrix == est.result_.compensator.matrix
    assert [lg["rows"] for lg in est.result_.logs] == [400, 300]
    pred = est.predict(X, groups=groups)
    np.testing.assert_array_equal(pred[400:], est.predict(X[400:]))
    with pytest.raises(ValueError, match="expected each log as one run of samples"):
        est.fit(X, y, feature_names=["omega"], groups=np.r_[np.zeros(200), np.ones(300),
                                                             np.zeros(200)])


def test_simulate_describe_and_export_take_several_logs(tmp_path: Path, capsys) -> None:
    cfg = tmp_path / "cfg.toml"
    cfg.write_text(CONFIG)
    a, b = _write(tmp_path, "a.csv", 1, 400), _write(tmp_path, "b.csv", 2, 300)
    res = tmp_path / "r.json"
    assert main(["abstract", str(a), str(b), "--target", "tau", "--inputs", "omega", "--config",
                 str(cfg), "--quiet", "--workers", "1", "-o", str(res)]) == 0
    capsys.readouterr()
    out = tmp_path / "sims"
    out.mkdir()
    assert main(["simulate", str(res), str(a), str(b), "-o", str(out)]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert sorted(p.name for p in out.iterdir()) == ["a_sim.csv", "b_sim.csv"]
    assert lines[-1].endswith("N m (over all 2 logs with the target, by their samples)")
    per = [float(line.split()[1]) for line in lines if line.startswith("rmse") and "(a.csv)" in line
           or "(b.csv)" in line]
    overall = float(lines[-1].split()[1])
    assert overall == pytest.approx(np.sqrt((400 * per[0] ** 2 + 300 * per[1] ** 2) / 700))
    # Each log from rest: b's simulation alone gives the same file.
    assert main(["simulate", str(res), str(b), "-o", str(tmp_path / "b_alone.csv")]) == 0
    assert (tmp_path / "b_alone.csv").read_text() == (out / "b_sim.csv").read_text()
    capsys.readouterr()
    assert main(["describe", str(res), "--data", str(a), str(b)]) == 0
    text = capsys.readouterr().out
    assert f"== {a} (1 of 2) ==" in text and f"== {b} (2 of 2) ==" in text
    assert main(["describe", str(res), "--data", str(a), str(b), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert [d["data"] for d in doc["logs"]] == [str(a), str(b)]
    assert main(["export", str(res), "--target", "python", "-o", str(tmp_path / "gen"),
                 "--data", str(a), str(b)]) == 0
    err = capsys.readouterr().err
    assert "over all 2 logs" in err and "on a.csv" in err and "on b.csv" in err
