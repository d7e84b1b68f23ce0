"""The physics of a whole model, named by its behaviour on probe motions (edm_sym.engines.physics).

Hand-written models with known laws, written the ways the search writes them
(one row a law, a cancelling pair, velocity built from the integral of the
acceleration), must be named with their parameters; what the model lacks
must not be named. The shipped EMPS result, without its data, must agree with
the engineer's least squares on the measured log (docs/describe.md#physics-named-by-behaviour).
"""

from __future__ import annotations

import math
import re
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import edm_sym
from edm_sym.core.elements import default_ranges
from edm_sym.core.matrix import Compensator, make_matrix
from edm_sym.engines.physics import (
    HELD_BAND,
    Law,
    MotionRange,
    Physics,
    PhysicsOptions,
    RowBehaviour,
    TermKind,
    held_speed,
    held_time,
    inertia_on_data,
    model_physics,
    probe_runs,
    ranges_from_data,
    ranges_from_result,
)
from edm_sym.engines.plant.anchor import centred_motion

ROOT = Path(__file__).resolve().parents[1]
TS = 1e-3
INPUTS = ("theta_w", "theta_uw", "omega", "alpha")
ROLES = ("angle_wrapped", "angle", "velocity", "acceleration")
RANGE = MotionRange(velocity=20.0, slowest=0.5, acceleration=400.0, position=(0.0, 60.0),
                    source="test ranges")


def _comp(rows: list[tuple[str, list[tuple[str, float]]]], inputs=INPUTS) -> Compensator:  # noqa: ANN001
    """A compensator from decoded parameter values (encoded with the default ranges)."""
    ranges = default_ranges(TS, 20.0)
    width = max(len(genes) for _, genes in rows)  # rows of one length, padded with `through`
    rows = [(inp, [*genes, *[("through", 0.0)] * (width - len(genes))]) for inp, genes in rows]
    enc = [(inp, [(name, ranges[name].encode(a) if name in ranges else 0.0) for name, a in genes])
           for inp, genes in rows]
    return Compensator(make_matrix(inputs, enc), TS, {})


def _named(phys) -> dict:  # noqa: ANN001
    return phys.named()


def test_one_row_per_law_is_named_with_its_parameters() -> None:
    comp = _comp([("omega", [("sign", 0), ("gain", 0.5)]),
                  ("omega", [("gain", 0.01)]),
                  ("alpha", [("gain", 0.002)]),
                  ("theta_w", [("gain", 3.0), ("sin_amp", 0.07)])])
    phys = model_physics(comp, ROLES, RANGE)
    named = _named(phys)
    assert set(named) == {"coulomb", "viscous", "acceleration", "spatial"}
    assert named["coulomb"]["level"] == pytest.approx(0.5, rel=0.01)
    assert named["viscous"]["coefficient"] == pytest.approx(0.01, rel=0.02)
    assert named["acceleration"]["inertia"] == pytest.approx(0.002, rel=0.02)
    assert named["spatial"]["cycles_per_revolution"] == 3
    assert named["spatial"]["amplitude"] == pytest.approx(0.07, rel=0.02)
    assert phys.explained > 0.999
    # each law is carried by its own row
    shares = {t.kind: t.rows for t in phys.terms}
    assert shares[TermKind.COULOMB][0] == pytest.approx(1.0, abs=0.01)
    assert shares[TermKind.SPATIAL][3] == pytest.approx(1.0, abs=0.01)
    assert not any(b.reason for b in phys.rows)


def test_a_cancelling_pair_is_named_as_the_law_it_makes_together() -> None:
    comp = _comp([("omega", [("sign", 0), ("gain", 0.3)]),
                  ("omega", [("gain", 2.0)]),
                  ("omega", [("gain", -1.99)])])
    phys = model_physics(comp, ROLES, RANGE)
    named = _named(phys)
    assert named["viscous"]["coefficient"] == pytest.approx(0.01, rel=0.02)
    rows = next(t.rows for t in phys.terms if t.kind is TermKind.VISCOUS)
    assert rows[1] == pytest.approx(200.0, rel=0.02) and rows[2] == pytest.approx(-199.0, rel=0.02)
    # the pair's viscous law is not named as anything else
    assert set(named) == {"coulomb", "viscous"}


def test_velocity_built_from_the_integral_of_the_acceleration_is_viscous() -> None:
    comp = _comp([("omega", [("sign", 0), ("gain", 0.4)]),
                  ("alpha", [("integral", 1.0), ("gain", 0.02)])])
    named = _named(model_physics(comp, ROLES, RANGE))
    assert named["viscous"]["coefficient"] == pytest.approx(0.02, rel=0.03)
    assert named["coulomb"]["level"] == pytest.approx(0.4, rel=0.02)
    assert "acceleration" not in named


def test_what_the_model_lacks_is_not_named_and_a_wrong_sign_is_said() -> None:
    comp = _comp([("omega", [("sign", 0), ("gain", -0.5)]),
                  ("omega", [("gain", 0.02)])])
    phys = model_physics(comp, ROLES, RANGE)
    assert set(phys.named()) == {"viscous"}
    left = dict(phys.left_out)
    assert "negative Coulomb" in left[TermKind.COULOMB]
    assert "below" in left[TermKind.OFFSET]


def test_a_row_no_law_explains_says_how_much_of_the_probe_behaviour_it_leaves() -> None:
    """Without data the shares are of the model on the probes: the reason names that once."""
    comp = _comp([("omega", [("sign", 0), ("gain", 0.5)]),
                  ("omega", [("gain", 3.0), ("sin_amp", 0.2)])])
    phys = model_physics(comp, ROLES, RANGE)
    reason = phys.rows[1].reason
    assert re.fullmatch(r"[0-9.]+ % of the model on the probes that no law explains", reason)


def test_a_tiny_law_is_left_out_below_the_threshold() -> None:
    comp = _comp([("omega", [("sign", 0), ("gain", 0.5)]),
                  ("omega", [("gain", 1e-5)])])
    phys = model_physics(comp, ROLES, RANGE, options=PhysicsOptions(threshold=0.01))
    assert set(phys.named()) == {"coulomb"}
    assert any(k is TermKind.VISCOUS for k, _ in phys.left_out)


def test_a_law_that_hangs_on_one_probe_speed_is_flagged_uncertain() -> None:
    """A friction curve that bends between the probe speeds (Coulomb, viscous and a
    wobble 0.06 sin(0.5 v), as a search's free curve can hold) gets a viscous slope
    that depends on which speeds are probed: its relative error is the jackknife
    over the speeds (14 %; as independent samples, 0.4 %), and it is flagged.
    A curve that is the law has errors near zero and no flag."""
    clean = _comp([("omega", [("sign", 0), ("gain", 0.3)]), ("omega", [("gain", 0.01)])])
    wobbly = _comp([("omega", [("sign", 0), ("gain", 0.3)]), ("omega", [("gain", 0.01)]),
                    ("omega", [("gain", 0.5), ("sin_amp", 0.06)])])
    law = {t.kind: t for t in model_physics(clean, ROLES, RANGE).terms}
    assert law[TermKind.VISCOUS].errors["coefficient"] < 1e-6
    assert not any(t.flags for t in law.values())
    law = {t.kind: t for t in model_physics(wobbly, ROLES, RANGE).terms}
    viscous = law[TermKind.VISCOUS]
    assert viscous.parameters["coefficient"][0] == pytest.approx(0.0067, rel=0.05)
    assert viscous.errors["coefficient"] > PhysicsOptions().uncertain
    assert [code for code, _ in viscous.flags] == ["uncertain"]


def test_observer_lag_is_taken_out_before_the_inertia_is_named() -> None:
    # A viscous law seen through the observer's low-pass g/(s+g) lags: without the
    # bandwidth it reads as an inertia of -D/g, with it as none.
    g = 100.0
    comp = _comp([("omega", [("gain", 0.05), ("lpf", g)]),
                  ("omega", [("sign", 0), ("gain", 0.5), ("lpf", g)])])
    with_g = model_physics(comp, ROLES, RANGE, bandwidth=g).named()
    assert "acceleration" not in with_g
    assert with_g["viscous"]["coefficient"] == pytest.approx(0.05, rel=0.03)
    without = model_physics(comp, ROLES, RANGE, options=PhysicsOptions(threshold=0.001))
    # -D/g to first order; the Coulomb step at each reversal, through the same
    # low-pass, adds its tail inside the ramps (about a quarter more here).
    assert without.named()["acceleration"]["inertia"] == pytest.approx(-0.05 / g, rel=0.3)
    assert any(c == "lag_included" for t in without.terms for c, _ in t.flags)


def test_probes_stay_in_the_velocity_range_and_start_from_rest() -> None:
    runs = probe_runs(RANGE, TS, 0.05, rotary=True, options=PhysicsOptions())
    for run in runs:
        assert run.velocity[0] == 0.0
        assert np.max(np.abs(run.velocity)) <= RANGE.velocity * (1 + 1e-9)
        assert np.max(np.abs(run.acceleration[run.steady])) <= RANGE.acceleration * (1 + 1e-6)
        assert run.steady.any()
    # the constant-velocity runs hold speeds from the slowest to the fastest, each
    # reached as a sweep down from the fastest in its direction
    constant = [r for r in runs if r.speed >= 0]
    held = sorted(float(np.abs(r.velocity[r.steady]).mean()) for r in constant)
    assert held[0] == pytest.approx(RANGE.slowest, rel=1e-6)
    assert held[-1] == pytest.approx(RANGE.velocity, rel=1e-6)
    for r in constant:
        assert np.max(np.abs(r.velocity)) == pytest.approx(RANGE.velocity, rel=1e-9)
        assert np.ptp(r.velocity[r.steady]) == 0.0


def test_ranges_from_data_are_the_motion_the_log_reaches() -> None:
    t = np.arange(20000) * TS
    v = 5.0 * np.sin(t)
    r = ranges_from_data(v, 5.0 * np.cos(t), np.cumsum(v) * TS, "log")
    assert r.velocity == pytest.approx(5.0, rel=0.01)
    assert 0 < r.slowest < r.velocity
    assert r.acceleration == pytest.approx(5.0, rel=0.01)


def _staircase_and_chirp(slow: float) -> np.ndarray:
    """A velocity: 1 s plateaus at +-slow, +-6 and +-30 rad/s, then a 10 s chirp to 60."""
    t = np.arange(10000) * TS
    stairs = np.repeat([slow, 6.0, 30.0, -slow, -6.0, -30.0], 1000)
    chirp = 60.0 * np.sin(2 * np.pi * 0.5 * t ** 2)
    return np.concatenate([np.zeros(2000), stairs, np.zeros(2000), chirp])


def test_the_probes_go_down_to_the_slowest_speed_a_log_holds() -> None:
    # A plateau at 0.8 rad/s (2 s of 20) is held; the chirp's passages through every speed
    # are not. Probes go down to a fiftieth of the fastest, and lower to a held speed down
    # to a two-hundredth; a plateau below that is not followed.
    rng = np.random.default_rng(0)
    for slow, expected in ((0.8, 0.8), (3.0, None), (0.1, None)):
        v = _staircase_and_chirp(slow) + rng.normal(0.0, 0.01, 20000)
        r = ranges_from_data(v, np.gradient(v, TS), np.cumsum(v) * TS, "log")
        if expected is None:
            assert r.slowest == pytest.approx(r.velocity / 50.0)
        else:
            assert r.slowest == pytest.approx(expected, rel=HELD_BAND)
    chirp = _staircase_and_chirp(0.8)[10000:]
    assert held_speed(chirp, 0.3, 1.2) is None
    assert held_speed(np.zeros(100), 0.3, 1.2) is None


def test_describe_probes_as_slow_as_the_abstraction_log_held() -> None:
    # result.json's physics records the slowest speed its abstraction log held; describe
    # on another log (a chirp) probes down to it, with data or without.
    from edm_sym.engines.physics import physics_on_log
    from edm_sym.engines.simulate import simulate_rows

    comp = _comp([("omega", [("sign", 0), ("gain", 0.5)]), ("omega", [("gain", 0.01)])],
                 inputs=("theta_uw", "omega", "alpha"))
    v = _staircase_and_chirp(0.8)[10000:]
    x = np.vstack([np.cumsum(v) * TS, v, np.gradient(v, TS)])
    rows = simulate_rows(comp, comp.matrix.rows, x)
    target = rows.sum(axis=0)
    roles = ("angle", "velocity", "acceleration")
    alone = physics_on_log(comp, roles, x=x, rows=rows, target=target, ts=TS, source="c.csv")
    assert alone.ranges.slowest == pytest.approx(alone.ranges.velocity / 50.0)

    class Result:  # what ranges_from_result reads of a result
        logs = ({"use": "abstraction", "columns": [{"name": "omega", "min": -60.0, "max": 60.0}]},)
        physics = {"ranges": {"slowest": 0.8}}
        source = "r.json"

    recorded = ranges_from_result(Result(), {"omega": "velocity"})
    assert recorded.slowest == 0.8
    given = physics_on_log(comp, roles, x=x, rows=rows, target=target, ts=TS, source="c.csv",
                           fallback=recorded)
    assert given.ranges.slowest == 0.8
    assert given.named()["coulomb"]["level"] == pytest.approx(0.5, rel=0.01)
    Result.physics = {"ranges": {"slowest": 0.01}}  # at least a two-hundredth of the fastest
    assert ranges_from_result(Result(), {"omega": "velocity"}).slowest == pytest.approx(0.3)
    Result.physics = {}  # an older result: a fiftieth
    assert ranges_from_result(Result(), {"omega": "velocity"}).slowest == pytest.approx(1.2)


def test_the_longest_hold_of_a_log_is_its_longest_plateau() -> None:
    # 1 s plateaus (noise of 0.01 rad/s) hold about 1 s; a chirp's passages do not hold;
    # rest is no hold.
    rng = np.random.default_rng(0)
    v = _staircase_and_chirp(0.8) + rng.normal(0.0, 0.01, 20000)
    assert 0.9 <= held_time(v, TS, 0.3) <= 1.0
    assert held_time(v[10000:], TS, 0.3) < 0.3
    assert held_time(np.zeros(100), TS, 0.1) is None
    r = ranges_from_data(v, np.gradient(v, TS), np.cumsum(v) * TS, "log", TS)
    assert r.hold == held_time(v, TS, r.velocity / 200.0)
    assert ranges_from_data(v, np.gradient(v, TS), None, "log").hold is None  # no sample time


def test_the_probes_wait_no_longer_than_the_fitted_log_holds_a_speed() -> None:
    """A pole at 0.75 rad/s on an acceleration row (as a search puts one, draw 1402)
    is a viscous term of -0.0025 that fades over 1.3 s after each change of speed: the
    log's 0.9 s plateaus saw it, a 3 s wait does not. With the hold recorded the probes
    wait 0.9 s and read the viscous slope nearer what the log's time scales show (the
    chirp's 0.0075, the 1 s plateaus' 0.0094) than the DC gain 0.01, with the difference
    from the settled reading in its error; a model whose filters settle within the hold
    reads the same either way."""
    from edm_sym.engines.physics import physics_on_log
    from edm_sym.engines.simulate import simulate_rows

    slow = _comp([("omega", [("sign", 0), ("gain", 0.3)]), ("omega", [("gain", 0.01)]),
                  ("alpha", [("lpf", 0.75), ("gain", -0.0025 / 0.75)])])
    before = model_physics(slow, ROLES, RANGE)
    held = model_physics(slow, ROLES, replace(RANGE, hold=0.9))
    assert any("waited 3 s" in n for n in before.notes)
    assert any("waited 0.9 s" in n and "time scales" in n for n in held.notes)
    d_before = before.named()["viscous"]["coefficient"]
    d_held = held.named()["viscous"]["coefficient"]
    assert d_held < 0.95 * d_before and d_held > 0.0075
    # How far the reading hangs on the wait is part of its error (8 % here: no flag).
    viscous = next(t for t in held.terms if t.kind is TermKind.VISCOUS)
    assert viscous.errors["coefficient"] >= abs(d_before - d_held) / d_held > 0.05
    assert not viscous.flags
    assert next(t for t in before.terms if t.kind is TermKind.VISCOUS).errors["coefficient"] < 0.05
    assert held.named()["coulomb"]["level"] == pytest.approx(0.3, rel=0.01)
    fast = _comp([("omega", [("sign", 0), ("gain", 0.3)]), ("omega", [("gain", 0.01)]),
                  ("alpha", [("lpf", 50.0), ("gain", 0.002)])])
    assert model_physics(fast, ROLES, replace(RANGE, hold=0.9)).named() == \
        model_physics(fast, ROLES, RANGE).named()
    # On data the hold is the fitted log's, which result.json records (a chirp holds
    # 0.2 s); a result written before records none, and the probes wait as then.
    v = _staircase_and_chirp(0.8)[10000:]
    x = np.vstack([np.mod(np.cumsum(v) * TS, 2 * np.pi), np.cumsum(v) * TS, v, np.gradient(v, TS)])
    rows = simulate_rows(slow, slow.matrix.rows, x)

    class Result:  # what ranges_from_result reads of a result
        logs = ({"use": "abstraction", "columns": [{"name": "omega", "min": -60.0, "max": 60.0}]},)
        physics = {"ranges": {"slowest": 0.8, "hold": 0.9}}
        source = "r.json"

    for recorded, wait in ((0.9, "0.9 s"), (None, "3 s")):
        Result.physics = {"ranges": {"slowest": 0.8, **({} if recorded is None else {"hold": recorded})}}
        fallback = ranges_from_result(Result(), dict(zip(INPUTS, ROLES, strict=True)))
        assert fallback.hold == recorded
        phys = physics_on_log(slow, ROLES, x=x, rows=rows, target=rows.sum(axis=0), ts=TS,
                              source="c.csv", fallback=fallback)
        assert phys.ranges.hold == recorded
        assert any(f"waited {wait}" in n for n in phys.notes)
        assert ("hold" in phys.to_json()["ranges"]) == (recorded is not None)
    # Without a record only the log the model was fitted on (edm abstract's summary) sets it.
    kw = {"x": x, "rows": rows, "target": rows.sum(axis=0), "ts": TS, "source": "c.csv"}
    assert physics_on_log(slow, ROLES, **kw).ranges.hold is None
    own = physics_on_log(slow, ROLES, **kw, fitted=True)
    assert own.ranges.hold == held_time(v, TS, own.ranges.velocity / 200.0) < 0.3


def test_linear_axis_units_and_a_position_profile() -> None:
    comp = _comp([("qd", [("sign", 0), ("gain", 8.0)]),
                  ("qd", [("gain", 9.0)]),
                  ("q", [("gain", 9.0), ("sin_amp", 2.0)])], inputs=("q", "qd", "qdd"))
    rng = MotionRange(0.2, 0.01, 2.0, (0.0, 0.5), "test")
    phys = model_physics(comp, ("angle", "velocity", None), rng, axis="linear")
    terms = {t.kind.value: t.parameters for t in phys.terms}
    assert terms["coulomb"]["level"][1] == "N"
    assert terms["coulomb"]["level"][0] == pytest.approx(8.0, rel=0.02)
    assert terms["viscous"]["coefficient"] == (pytest.approx(9.0, rel=0.05), "N s/m")
    assert terms["spatial"]["amplitude"][0] == pytest.approx(2.0, rel=0.1)
    assert any("held at zero" in n for n in phys.notes)


# The engineer's least squares on the measured EMPS log (sgn v, v, a, 1), whole log:
# Fc 20.32 N, Fv 204.3 N s/m, mass error 5.07 kg (benchmarks/bench_emps.py's regressors).
EMPS_LS = {"coulomb": ("level", 20.32), "viscous": ("coefficient", 204.3),
           "acceleration": ("inertia", 5.07)}


def test_emps_without_data_agrees_with_least_squares_over_the_recorded_ranges() -> None:
    desc = edm_sym.describe(ROOT / "examples" / "emps" / "result.json")
    doc = desc.to_json()
    phys = doc["physics"]
    assert "records" in phys["ranges"]["source"]
    assert phys["ranges"]["velocity"] == pytest.approx(0.1278, rel=0.01)
    named = {t["kind"]: t["parameters"] for t in phys["terms"]}
    for kind, (param, value) in EMPS_LS.items():
        assert named[kind][param][0] == pytest.approx(value, rel=0.15), kind
    assert phys["reference"] == "probes"
    assert not math.isnan(phys["explained"]) and phys["explained"] > 0.95


def test_describe_json_physics_reads_the_data_when_given(tmp_path: Path) -> None:
    doc = edm_sym.describe(ROOT / "examples" / "auger" / "result.json",
                           "plant:auger/evaluation").to_json()
    named = {t["kind"]: t["parameters"] for t in doc["physics"]["terms"]}
    # the auger plant (docs/plant.md): Coulomb 0.95 N m, viscous 0.005, inertia error
    # 2e-4 kg m^2, a 1-cycle ripple of 0.06 N m
    assert named["coulomb"]["level"][0] == pytest.approx(0.95, rel=0.05)
    assert named["viscous"]["coefficient"][0] == pytest.approx(0.005, rel=0.1)
    assert named["acceleration"]["inertia"][0] == pytest.approx(2e-4, rel=0.2)
    assert named["spatial"]["cycles_per_revolution"][0] == 1
    assert named["spatial"]["amplitude"][0] == pytest.approx(0.06, rel=0.2)
    assert "offset" not in named and "stribeck" not in named
    assert doc["physics"]["observer_bandwidth"] == 150.0


def test_an_input_that_only_rises_over_the_log_is_said_to_be_a_clock() -> None:
    import warnings

    from edm_sym.core.data import DataLog
    from edm_sym.core.errors import ClockWarning
    from edm_sym.engines.abstraction.run import check_data, clock_inputs

    t = np.arange(4000) * TS
    omega = 2.0 + np.sin(3 * t)  # one way: the angle only rises
    theta = np.cumsum(omega) * TS
    log = DataLog({"t": t, "theta_uw": theta, "theta_w": np.mod(theta, 2 * np.pi),
                   "omega": omega, "tau": 0.3 * np.sign(omega) + 0.01 * omega}, TS, "oneway.csv")
    assert [c[0] for c in clock_inputs(log, ["theta_w", "theta_uw", "omega"])] == ["theta_uw"]
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        check_data(log, "tau", ["theta_uw", "omega"])
    clocks = [w for w in seen if issubclass(w.category, ClockWarning)]
    assert len(clocks) == 1 and "'theta_uw' only rises" in str(clocks[0].message)
    # both ways: no clock
    back = DataLog({"t": t, "theta_uw": np.sin(t), "omega": np.cos(t), "tau": np.cos(t)}, TS, "x")
    assert clock_inputs(back, ["theta_uw", "omega"]) == []


@pytest.fixture(scope="module")
def emps_with_data(tmp_path_factory: pytest.TempPathFactory) -> tuple[dict, np.ndarray]:
    """describe's physics of the shipped EMPS result on its measured log, and least squares
    on that log (sgn v, v, a, 1)."""
    from conftest import emps_path

    from edm_sym.application.cli import main

    view = tmp_path_factory.mktemp("emps") / "emps_view.csv"
    assert main(["observe", str(emps_path()), "--position", "qm", "--force", "vir",
                 "--force-gain", "gtau", "--nominal-inertia", "90", "--axis", "linear",
                 "-o", str(view)]) == 0
    log = edm_sym.load_data(view)
    v, a, y = log.column("qd"), log.column("qdd"), log.column("tau_ext")
    ls, *_ = np.linalg.lstsq(np.column_stack([np.sign(v), v, a, np.ones_like(v)]), y, rcond=None)
    doc = edm_sym.describe(ROOT / "examples" / "emps" / "result.json", view).to_json()
    assert doc["physics"]["reference"] == "target"
    return {t["kind"]: t["parameters"] for t in doc["physics"]["terms"]}, ls


@pytest.mark.parametrize("kind, param, column", [
    ("coulomb", "level", 0), ("viscous", "coefficient", 1), ("acceleration", "inertia", 2),
])
def test_emps_with_its_data_agrees_with_least_squares_on_the_log(
        emps_with_data: tuple[dict, np.ndarray], kind: str, param: str, column: int) -> None:
    named, ls = emps_with_data
    assert named[kind][param][0] == pytest.approx(ls[column], rel=0.15), kind


def test_with_data_the_inertia_is_measured_on_the_logs_motion(
        emps_with_data: tuple[dict, np.ndarray]) -> None:
    # The probes' triangle waves name 5.89 kg for the EMPS model (least squares on the log:
    # 5.07 kg); on the log's own motion the model holds what the log needs.
    named, _ = emps_with_data
    doc = edm_sym.describe(ROOT / "examples" / "emps" / "result.json").to_json()
    law = next(t for t in doc["physics"]["terms"] if t["kind"] == "acceleration")
    assert not any(f["code"] == "on_data" for f in law["flags"])  # no data: the probes
    probes = law["parameters"]["inertia"][0]
    assert abs(named["acceleration"]["inertia"][0] - probes) > 0.05 * probes


def _reversing_log(n: int = 8000) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A motion that reverses: angle, velocity and acceleration (no lag, no noise)."""
    t = np.arange(n) * TS
    omega = 12.0 * np.sin(2 * np.pi * 0.4 * t) + 4.0 * np.sin(2 * np.pi * 1.3 * t)
    alpha = np.gradient(omega, TS)
    theta = np.cumsum(omega) * TS
    return theta, omega, alpha


@pytest.mark.parametrize("plant_has_inertia", [True, False])
def test_a_law_the_data_does_not_need_is_not_named(plant_has_inertia: bool) -> None:
    from edm_sym.engines.physics import physics_on_log
    from edm_sym.engines.simulate import simulate_rows

    # The model: Coulomb 0.5 and an inertia of 3e-4 kg m^2 (its term about 2 % of the target).
    comp = _comp([("omega", [("sign", 0), ("gain", 0.5)]), ("alpha", [("gain", 3e-4)])],
                 inputs=("theta_uw", "omega", "alpha"))
    theta, omega, alpha = _reversing_log()
    x = np.vstack([theta, omega, alpha])
    rows = simulate_rows(comp, comp.matrix.rows, x)
    rng = np.random.default_rng(3)
    target = 0.5 * np.sign(omega) + rng.normal(0.0, 0.01, omega.size)
    if plant_has_inertia:
        target = target + 3e-4 * alpha
    phys = physics_on_log(comp, ("angle", "velocity", "acceleration"), x=x, rows=rows,
                          target=target, ts=TS, source="test.csv")
    named = phys.named()
    assert named["coulomb"]["level"] == pytest.approx(0.5, rel=0.01)
    if plant_has_inertia:
        assert named["acceleration"]["inertia"] == pytest.approx(3e-4, rel=0.02)
        law = next(t for t in phys.terms if t.kind is TermKind.ACCELERATION)
        assert "on_data" in [c for c, _ in law.flags]  # measured on the log's motion
    else:
        assert "acceleration" not in named
        why = dict(phys.left_out)[TermKind.ACCELERATION]
        assert why.startswith("the data does not support it: without its term the model fits "
                              "the target better")
    # Without the data the same model's inertia is named (nothing says the plant lacks it).
    assert "acceleration" in model_physics(comp, ("angle", "velocity", "acceleration"),
                                           RANGE).named()



@pytest.mark.parametrize("draw, hump", [(1809, 0.29), (1801, 0.0)])
def test_the_datas_support_of_a_stribeck_hump_is_judged_where_the_axis_slides(
        draw: int, hump: float) -> None:
    """At a reversal the plant's friction follows its bristles (presliding), not the
    static laws, and a chirp passes the hump's speeds only there: on family draw 1809's
    evaluation log the plant's own Stribeck term, through Q(s), fits the target worse
    over every sample (RMSE 0.122 N m with it, 0.099 without) and far better where the
    axis slides. A model holding the plant's laws names the hump; the same hump put
    into a model of draw 1801, which has none, is left out."""
    from edm_sym.engines.physics import physics_on_log
    from edm_sym.engines.plant import simulate_plant
    from edm_sym.engines.plant.family import draw_plant
    from edm_sym.engines.simulate import simulate_rows

    fp = draw_plant(draw)
    truth = {k.value: dict(v) for k, v in fp.truth.items()}
    g = fp.preset.g_rtob
    fc, d = truth["coulomb"]["level"], truth["viscous"]["coefficient"]
    # sign(v) (Fc + Fs) - Fs tanh(0.29 v): Coulomb and a hump of Fs falling to e^-1 near
    # 2.6 rad/s (draw 1809's v_s 2.58 rad/s); the observer's low-pass in every row.
    fs = 0.29
    law_rows = [("omega", [("sign", 0), ("lpf", g), ("gain", fc + fs)]),
                ("omega", [("tanh", 0.29), ("lpf", g), ("gain", -fs)]),
                ("omega", [("lpf", g), ("gain", d)])]
    if "spatial" in truth:
        sp = truth["spatial"]
        law_rows.append(("theta_w", [("gain", sp["cycles_per_revolution"]),
                                     ("sin_amp", sp["amplitude"]), ("lpf", g)]))
    comp = _comp(law_rows, inputs=("theta_w", "theta_uw", "omega", "alpha"))
    log = simulate_plant(fp.preset, "evaluation", seed=0)
    x = np.vstack([log.columns[c] for c in ("theta_w", "theta_uw", "omega", "alpha")])
    rows = simulate_rows(comp, comp.matrix.rows, x)
    phys = physics_on_log(comp, ROLES, x=x, rows=rows, target=log.tau_ext, ts=log.ts,
                          source=f"plant:family-{draw}/evaluation", bandwidth=g)
    named = phys.named()
    assert named["coulomb"]["level"] == pytest.approx(fc, rel=0.1)
    if hump:  # named; its peak is the law's exponential fitted to tanh's shape
        assert named["stribeck"]["peak"] == pytest.approx(hump, rel=0.5)
    else:
        assert "stribeck" not in named
        why = dict(phys.left_out)[TermKind.STRIBECK]
        assert why.startswith("the data does not support it: without its term the model fits "
                              "the target better where the axis slides")


def test_the_constant_speeds_are_swept_down_to_so_a_relay_is_in_its_sliding_state() -> None:
    """A relay with a band of +-1 rad/s holds its starting state (0) at slower speeds
    reached from rest: a Coulomb level carried by it would vanish at the slowest probes.
    Each constant speed is reached from the fastest one in its direction, where sliding
    that way has set the relay."""
    comp = _comp([("omega", [("hysteresis", 1.0), ("gain", 0.5)]),
                  ("omega", [("gain", 0.01)])])
    phys = model_physics(comp, ROLES, RANGE)  # probes from 0.5 rad/s
    named = _named(phys)
    assert set(named) == {"coulomb", "viscous"}
    assert named["coulomb"]["level"] == pytest.approx(0.5, rel=0.01)
    assert named["viscous"]["coefficient"] == pytest.approx(0.01, rel=0.02)
    assert phys.explained > 0.999


def test_an_inertia_too_small_on_the_log_is_left_out() -> None:
    """The probes' constant accelerations can give a row on the acceleration a gain the
    log's motion does not. Measured on the log, the inertia's share is rescaled; under
    the threshold it is not named (left out with both values) and no row lists it; above
    it the law stays named with the log's value."""
    angle = np.asarray(edm_sym.load_data("plant:auger/evaluation").column("theta_uw"), dtype=float)
    _, omega, alpha = centred_motion(angle, TS)
    friction = 0.5 * np.sign(omega) + 0.01 * omega
    ranges = MotionRange(float(np.max(np.abs(omega))), 1.0, float(np.max(np.abs(alpha))), None,
                         "test")
    # On the probes: 1e-4 kg m^2, 5 % of the reference.
    law = Law(TermKind.ACCELERATION, {"inertia": (1e-4, "kg m^2")}, 0.05, rows=(0.0, 1.0))
    rows = (RowBehaviour(1, {"coulomb": 1.0}, 0.0), RowBehaviour(2, {"acceleration": 1.0}, 0.0))
    phys = Physics((law,), (), 1.0, rows, ranges, None)
    assert PhysicsOptions().threshold == 0.01

    kept = inertia_on_data(phys, angle, friction + 6e-5 * alpha, TS)  # 3 %: named
    assert [x.kind for x in kept.terms] == [TermKind.ACCELERATION]
    # The log's least squares reads the 6e-5 the output holds.
    on_log = kept.terms[0].parameters["inertia"][0]
    assert on_log == pytest.approx(6e-5, rel=0.02)
    assert kept.terms[0].share == pytest.approx(0.05 * on_log / 1e-4)
    assert kept.rows == rows and kept.left_out == ()

    small = inertia_on_data(phys, angle, friction + 1e-5 * alpha, TS)  # 0.5 %: left out
    assert small.terms == ()
    ((kind, why),) = small.left_out
    assert kind is TermKind.ACCELERATION
    assert "below the 1 % threshold" in why and "on the probes 0.0001 kg m^2" in why
    assert [r.laws for r in small.rows] == [{"coulomb": 1.0}, {}]
