"""Clocks: one-way angles, and the rows that read time from them.

docs/abstraction.md#clocks-rows-that-read-time-from-the-angle
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from helpers import TS

from edm_sym.core.data import DataLog, join_logs
from edm_sym.core.elements import default_ranges
from edm_sym.core.matrix import Compensator, make_matrix
from edm_sym.engines.abstraction.clocks import RETREAT, clock_shifts, is_clock, passengers
from edm_sym.engines.abstraction.finish import without_passengers
from edm_sym.engines.abstraction.holdout import Scorer, ValidationSettings, plan_holdout
from edm_sym.engines.abstraction.weighting import Weighting
from edm_sym.engines.simulate import simulate_row

INPUTS = ("theta_uw", "omega")
N = 3000  # one run of 3 s


def compensator(rows: list, n_samples: int = N) -> Compensator:
    """A matrix from rows of (input, [(element, value a or None), ...])."""
    ranges = default_ranges(TS, n_samples * TS)
    enc = [(inp, [(name, 0.0 if a is None else ranges[name].encode(a)) for name, a in genes])
           for inp, genes in rows]
    return Compensator(make_matrix(INPUTS, enc), TS, ranges, n_samples * TS)


def one_way_run(speed: float, n: int = N) -> tuple[np.ndarray, np.ndarray]:
    """A run from rest to ``speed`` [rad/s] in 0.3 s, one way: angle and velocity."""
    t = np.arange(n) * TS
    omega = speed * np.clip(t / 0.3, 0.0, 1.0)
    theta = np.concatenate([[0.0], np.cumsum(omega[:-1]) * TS])
    return theta, omega


RIPPLE = ("theta_uw", [("gain", 7.0), ("sin_amp", 0.05), ("lpf", 200.0)])
VELOCITY_FROM_ANGLE = ("theta_uw", [("derivative", 1.0), ("tanh", 5.0), ("sin_amp", 0.3)])
DIRECTION = ("theta_uw", [("tanh", 100.0), ("gain", 0.2), ("through", None)])
RAMP = ("theta_uw", [("gain", 0.01), ("lpf", 50.0), ("through", None)])
START = ("theta_uw", [("atan", 0.5), ("sin_phase", math.pi / 2), ("gain", 0.2)])  # cos(atan)
COULOMB = ("omega", [("tanh", 100.0), ("gain", 0.3), ("through", None)])


def test_a_one_way_angle_is_a_clock_despite_jitter_at_the_start() -> None:
    theta, _ = one_way_run(-5.0)
    assert is_clock(theta)
    jitter = theta.copy()
    jitter[5:8] += [1e-5, -1e-5, 2e-5]  # encoder counts back and forth at the start
    assert is_clock(jitter)
    back = np.concatenate([theta, theta[::-1]])  # there and back
    assert not is_clock(back)
    assert not is_clock(theta + 1.0 * (np.arange(N) > N // 2) * (theta[-1] - theta[0]) * -2 * RETREAT)
    assert not is_clock(np.zeros(N))
    _, omega = one_way_run(-8.0)
    noisy = omega + 1e-3 * np.random.default_rng(0).standard_normal(N)
    assert not is_clock(noisy)  # steps to a level and holds it: no clock
    assert is_clock(np.arange(N) * TS)  # the time column is one


def test_only_an_angle_that_is_a_clock_of_some_log_is_tested_and_by_one_turn() -> None:
    a, wa = one_way_run(8.0)
    b = np.sin(np.arange(N) * TS) * 3.0  # back and forth
    x = np.array([np.concatenate([b, a]), np.concatenate([np.cos(b), wa])])
    shifts = clock_shifts(x, (N,), ["angle", "velocity"], "rotary")
    assert list(shifts) == [0]
    span = float(np.ptp(x[0]))
    assert shifts[0] == pytest.approx(2 * math.pi)  # one revolution
    assert clock_shifts(x, (N,), ["angle", "velocity"], "linear") == {0: pytest.approx(span)}
    assert clock_shifts(x[:, :N], (), ["angle", "velocity"], "rotary") == {}  # no one-way log
    assert clock_shifts(x, (N,), ["angle_wrapped", "velocity"], "rotary") == {}


def test_rows_that_read_time_from_the_angle_are_passengers_and_physics_is_not() -> None:
    runs = [one_way_run(s) for s in (4.0, -6.0, 10.0)]
    x = np.array([np.concatenate([r[0] for r in runs]), np.concatenate([r[1] for r in runs])])
    starts = (N, 2 * N)
    comp = compensator([RIPPLE, VELOCITY_FROM_ANGLE, DIRECTION, RAMP, COULOMB])
    shifts = clock_shifts(x, starts, ["angle", "velocity"], "rotary")
    found = passengers(comp, comp.matrix, x, starts, shifts, slice(None), target_rms=0.3)
    assert [p.row for p in found] == [2, 3]
    assert all(p.change >= 0.01 for p in found)
    assert passengers(comp, comp.matrix, x, starts, {}, slice(None), target_rms=0.3) == []


def _log(runs: list[tuple[np.ndarray, np.ndarray]], tau: list[np.ndarray], k: int) -> DataLog:
    theta, omega = runs[k]
    return DataLog({"theta_uw": theta, "omega": omega, "tau_ext": tau[k]}, TS, f"run{k}.csv",
                   f"{k:064x}")


def test_a_passenger_leaves_the_model_and_the_gains_take_its_share() -> None:
    """A direction-of-travel row stands in for part of the Coulomb level of one-way runs: it
    goes, and the Coulomb row's gain is refitted to the whole level."""
    speeds = (4.0, -6.0, 10.0, -3.0)
    runs = [one_way_run(s) for s in speeds]
    tau = [0.5 * np.tanh(100.0 * w) for _, w in runs]
    x = np.array([np.concatenate([r[0] for r in runs]), np.concatenate([r[1] for r in runs])])
    logs = [_log(runs, tau, k) for k in range(len(runs))]
    data = join_logs(logs, ["tau_ext", *INPUTS])
    hold = plan_holdout(data, target="tau_ext", inputs=INPUTS,
                        settings=ValidationSettings(layout="end"), logs=logs)
    scorer = Scorer(hold, Weighting())
    comp = compensator([DIRECTION, COULOMB])
    shifts = clock_shifts(x, hold.training.starts, ["angle", "velocity"], "rotary")
    clean, found = without_passengers(comp, scorer, shifts)
    assert [p.row for p in found] == [0]
    assert [comp.matrix.inputs[r.input] for r in clean.matrix.rows] == ["omega"]
    gain = clean.value(clean.matrix.rows[0].genes[1])
    assert gain == pytest.approx(0.5, rel=0.02)
    # Nothing but passengers: the model stays as it is.
    only, none = without_passengers(compensator([DIRECTION]), scorer, shifts)
    assert none == [] and len(only.matrix.rows) == 1


def test_the_search_model_and_its_record_lose_the_clock_rows() -> None:
    """finish(): a row of the start from rest through the angle fits every run, held-out
    blocks included, so pruning keeps it; as a clock row it goes, and result.json and the
    closing summary say which row went and why."""
    import json
    from importlib import resources

    import jsonschema

    from edm_sym.application.abstract_cli import clock_line
    from edm_sym.core.result import StepRecord
    from edm_sym.engines.abstraction import parse_config
    from edm_sym.engines.abstraction.finish import finish

    speeds = (4.0, -6.0, 10.0, -3.0)
    runs = [one_way_run(s) for s in speeds]
    comp = compensator([START, ("omega", [("tanh", 100.0), ("gain", 0.5), ("through", None)])])
    tau = [simulate_row(comp, comp.matrix.rows[0], th) + simulate_row(comp, comp.matrix.rows[1], w)
           for th, w in runs]  # the planted model is the truth
    logs = [_log(runs, tau, k) for k in range(len(runs))]
    data = join_logs(logs, ["tau_ext", *INPUTS])
    cfg = parse_config({"ga": {"population": 16, "generations": 4, "continue": "no"},
                        "step": [{"n_rows": 2, "n_elements": 3}],
                        "parsimony": {"refit": 0}}, "test.toml")
    cfg = replace(cfg, validation=replace(cfg.validation, unit="N m"))
    hold = plan_holdout(data, target="tau_ext", inputs=INPUTS, settings=cfg.validation, logs=logs)
    steps = [StepRecord(1, comp.matrix, 0.0, ())]
    shifts = clock_shifts(hold.training.x, hold.training.starts, ["angle", "velocity"], "rotary")
    out, record, _ = finish(steps, comp, hold, cfg, clocks=shifts)
    assert [out.matrix.inputs[r.input] for r in out.matrix.rows] == ["omega"]
    (gone,) = record["clock_rows"]
    assert gone["row"]["input"] == "theta_uw"
    assert gone["shift"] == pytest.approx(shifts[0]) and gone["change"] > 0.01
    schema = json.loads(resources.files("edm_sym.schema").joinpath("result.schema.json")
                        .read_text("utf-8"))
    jsonschema.validate(record, {**schema["properties"]["parsimony"], "$defs": schema["$defs"]})
    line = clock_line(record)
    assert line.startswith("clock rows: 1 of 1 candidates for the search's model lost 1 row(s) in all; "
                           "the chosen one lost 1 on theta_uw")
    assert record["start_candidates"][0]["clock_rows"] == 1
    # Judged by the held-out blocks alone, the start from rest earns its row.
    same, plain, _ = finish(steps, comp, hold, cfg)
    assert "clock_rows" not in plain and clock_line(plain) is None
    assert [same.matrix.inputs[r.input] for r in same.matrix.rows] == ["theta_uw", "omega"]


def test_without_pruning_the_search_model_keeps_its_clock_rows() -> None:
    from edm_sym.core.result import StepRecord
    from edm_sym.engines.abstraction import parse_config
    from edm_sym.engines.abstraction.finish import finish

    runs = [one_way_run(s) for s in (4.0, -6.0)]
    tau = [0.5 * np.tanh(100.0 * w) for _, w in runs]
    logs = [_log(runs, tau, k) for k in range(len(runs))]
    data = join_logs(logs, ["tau_ext", *INPUTS])
    cfg = parse_config({"ga": {"population": 16, "generations": 4, "continue": "no"},
                        "step": [{"n_rows": 2, "n_elements": 3}],
                        "parsimony": {"refit": 0, "prune": False}}, "test.toml")
    hold = plan_holdout(data, target="tau_ext", inputs=INPUTS, settings=cfg.validation, logs=logs)
    comp = compensator([DIRECTION, COULOMB])
    shifts = clock_shifts(hold.training.x, hold.training.starts, ["angle", "velocity"], "rotary")
    assert shifts
    out, record, _ = finish([StepRecord(1, comp.matrix, 0.0, ())], comp, hold, cfg, clocks=shifts)
    assert out.matrix == comp.matrix and record == {}


def test_a_ripple_found_a_little_off_a_whole_number_of_cycles_is_no_passenger() -> None:
    runs = [one_way_run(s) for s in (20.0, -30.0)]  # 9 and 13 revolutions
    x = np.array([np.concatenate([r[0] for r in runs]), np.concatenate([r[1] for r in runs])])
    comp = compensator([("theta_uw", [("gain", 7.0002), ("sin_amp", 0.1), ("through", None)])])
    shifts = clock_shifts(x, (N,), ["angle", "velocity"], "rotary")
    assert passengers(comp, comp.matrix, x, (N,), shifts, slice(None), target_rms=0.1) == []


def test_the_operators_never_draw_a_barred_input_and_draw_as_before_without() -> None:
    from edm_sym.engines.abstraction.ga import Operators
    from edm_sym.engines.abstraction.schedule import GaSettings

    ga = GaSettings(input_mutation_rate=0.5)
    plain, barred = Operators(ga, 4), Operators(ga, 4, barred=(1,))
    pop = barred.random_population(np.random.default_rng(1), 200, 4, 3)
    assert set(np.unique(pop.inputs)) == {0, 2, 3}
    barred.mutate(np.random.default_rng(2), pop)
    assert 1 not in pop.inputs
    a = plain.random_population(np.random.default_rng(3), 50, 3, 2)
    b = Operators(ga, 4, barred=()).random_population(np.random.default_rng(3), 50, 3, 2)
    c = np.random.default_rng(3).integers(4, size=150)
    np.testing.assert_array_equal(a.inputs, b.inputs)
    np.testing.assert_array_equal(a.inputs.ravel(), c)


def test_an_angle_that_is_a_clock_of_every_log_is_barred_when_a_velocity_is_there() -> None:
    from edm_sym.engines.abstraction.clocks import barred_inputs

    runs = [one_way_run(s) for s in (4.0, -6.0)]
    theta = np.concatenate([r[0] for r in runs])
    omega = np.concatenate([r[1] for r in runs])
    x = np.array([np.mod(theta, 2 * np.pi), theta, omega])
    full = ["angle_wrapped", "angle", "velocity"]
    assert barred_inputs(x, (N,), full) == (1,)
    assert barred_inputs(x, (N,), ["angle_wrapped", "angle", None]) == ()  # no velocity
    assert barred_inputs(x[1:], (N,), full[1:]) == (0,)  # no wrapped angle: on either axis
    two_way = x.copy()
    two_way[1, :N] = np.sin(np.arange(N) * TS)  # the first log goes there and back
    assert barred_inputs(two_way, (N,), full) == ()


def test_abstract_leaves_a_clock_of_every_run_out_of_the_search_rows(tmp_path) -> None:
    import warnings

    from edm_sym.core.errors import ClockWarning
    from edm_sym.core.result import load_result, save_result
    from edm_sym.engines.abstraction import abstract, parse_config

    logs = []
    for k, speed in enumerate((4.0, -6.0, 10.0)):
        theta, omega = one_way_run(speed, 1500)
        tau = 0.3 * np.tanh(50.0 * omega) + 0.01 * omega + 0.05 * np.sin(3 * theta)
        logs.append(DataLog({"theta_w": np.mod(theta, 2 * np.pi), "theta_uw": theta,
                             "omega": omega, "tau_ext": tau}, TS, f"run{k}.csv", f"{k:064x}"))
    cfg = parse_config({"ga": {"population": 16, "generations": 3, "continue": "no"},
                        "step": [{"n_rows": 2, "n_elements": 2}, {"n_rows": 3, "n_elements": 2}]},
                       "test.toml")
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        res = abstract(logs, target="tau_ext", inputs=["theta_w", "theta_uw", "omega"], config=cfg,
                       seed=1)
    barred = [str(w.message) for w in seen if issubclass(w.category, ClockWarning)
              and "leave it out" in str(w.message)]
    assert len(barred) == 1 and "'theta_uw'" in barred[0]
    assert res.provenance["clock_inputs"] == ["theta_uw"]
    save_result(res, tmp_path / "r.json")  # valid against the schema
    assert load_result(tmp_path / "r.json").provenance["clock_inputs"] == ["theta_uw"]
    for step in res.steps:
        assert {res.inputs[r.input] for r in step.matrix.rows} <= {"theta_w", "omega"}
