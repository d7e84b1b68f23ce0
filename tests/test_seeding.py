"""Seeds: a step that adds rows seeds the residual's strongest angle harmonics and Stribeck
humps (edm_sym.engines.abstraction.seeding, docs/abstraction.md#hierarchy-and-inheritance-figs-8-19)."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import TS
from scipy.signal import lfilter

from edm_sym.core.data import DataLog
from edm_sym.core.elements import BY_NAME, default_ranges
from edm_sym.core.matrix import Compensator, ElementMatrix, Gene, Row
from edm_sym.core.result import dumps
from edm_sym.engines.abstraction import Parallel, abstract, parse_config
from edm_sym.engines.abstraction.seeding import (
    LAG_CORNERS,
    angle_input,
    harmonic_rows,
    residual_harmonics,
    residual_stribeck,
    stribeck_rows,
    velocity_input,
)
from edm_sym.engines.simulate import simulate_rows


def test_the_strongest_harmonics_of_a_residual_are_found_with_their_phase() -> None:
    rng = np.random.default_rng(0)
    theta = np.cumsum(rng.uniform(0.0, 0.02, 20000))
    resid = (0.2 * np.sin(5 * theta + 0.7) + 0.05 * np.sin(2 * theta - 1.0)
             + 0.3 + rng.normal(0, 0.02, 20000))
    found = residual_harmonics(theta, resid, np.ones_like(theta), count=2)
    (k1, a1, p1, c1), (k2, a2, p2, c2) = found
    assert c1 is None and c2 is None  # no corners tried: no lag
    assert (k1, k2) == (5, 2)
    assert a1 == pytest.approx(0.2, rel=0.05) and p1 == pytest.approx(0.7, abs=0.05)
    assert a2 == pytest.approx(0.05, rel=0.2) and p2 == pytest.approx(-1.0, abs=0.2)


def test_held_out_samples_weigh_nothing() -> None:
    theta = np.linspace(0.0, 200.0, 10000)
    resid = np.where(np.arange(10000) < 5000, 0.1 * np.sin(3 * theta), 0.5 * np.sin(7 * theta))
    w = (np.arange(10000) < 5000).astype(float)
    assert residual_harmonics(theta, resid, w, count=1)[0][0] == 3
    assert residual_harmonics(theta, resid, np.ones(10000), count=1)[0][0] == 7


def test_a_seed_row_is_the_harmonic_it_was_made_from() -> None:
    ranges = default_ranges(TS, 10.0)
    allowed = {el.code for el in BY_NAME.values()}
    (codes, ps), = harmonic_rows([(4, 0.08, -2.5)], ranges, 4, allowed)
    row = Row(0, tuple(Gene(int(c), float(p)) for c, p in zip(codes, ps, strict=True)))
    comp = Compensator(ElementMatrix(("theta_w",), (row,)), TS, ranges, 10.0)
    theta = np.linspace(0.0, 2 * np.pi, 500)
    out = simulate_rows(comp, [row], theta[None, :])[0]
    np.testing.assert_allclose(out, 0.08 * np.sin(4 * theta - 2.5), atol=1e-12)
    # no room, no gain or no sine allowed, or a gain beyond its range: no row
    assert harmonic_rows([(4, 0.08, 0.0)], ranges, 2, allowed) == []
    assert harmonic_rows([(4, 0.08, 0.0)], ranges, 4, allowed - {BY_NAME["sin_phase"].code}) == []
    assert harmonic_rows([(40, 0.08, 0.0)], ranges, 4, allowed) == []


def test_a_ripple_seen_through_a_lag_is_found_with_its_corner() -> None:
    # A 7-cycle ripple at up to 60 rad/s reaches the target through g/(s+g), g = 250:
    # the plain fit loses much of it, the lagged one finds the amplitude and the corner.
    n = 20000
    t = np.arange(n) * TS
    omega = 60.0 * np.sin(2 * np.pi * 0.1 * t)
    theta = np.cumsum(omega) * TS
    ranges = default_ranges(TS, n * TS)
    ripple = 0.15 * np.sin(7 * theta + 0.9)
    b, a = BY_NAME["lpf"].coefficients(250.0, TS)
    resid = lfilter(b, a, ripple) + np.random.default_rng(4).normal(0.0, 0.005, n)
    corners = np.geomspace(ranges["lpf"].low, ranges["lpf"].high, LAG_CORNERS)
    plain, = residual_harmonics(theta, resid, np.ones(n), count=1)
    lagged, = residual_harmonics(theta, resid, np.ones(n), count=1, corners=corners, ts=TS)
    assert plain.order == lagged.order == 7 and plain.corner is None
    assert plain.amplitude < 0.9 * 0.15
    assert lagged.amplitude == pytest.approx(0.15, rel=0.05)
    assert lagged.corner == pytest.approx(250.0, rel=0.1)
    # the seed row with its low-pass is the lagged ripple
    (codes, ps), = harmonic_rows([lagged], ranges, 4, {el.code for el in BY_NAME.values()})
    assert BY_NAME["lpf"].code in codes.tolist()
    row = Row(0, tuple(Gene(int(c), float(p)) for c, p in zip(codes, ps, strict=True)))
    comp = Compensator(ElementMatrix(("theta_w",), (row,)), TS, ranges, n * TS)
    out = simulate_rows(comp, [row], theta[None, :])[0]
    assert np.sqrt(np.mean((out - resid) ** 2)) < 0.01
    # a residual without ripple (slow steps): no corner, though a slow low-pass of the
    # harmonics would fit the steps
    steps = (0.3 * np.sign(np.sin(2 * np.pi * 0.05 * t))
             + np.random.default_rng(5).normal(0.0, 0.005, n))
    slow, = residual_harmonics(theta, steps, np.ones(n), count=1, corners=corners, ts=TS)
    assert slow.corner is None and slow.amplitude < 0.03
    # no lag in the residual: no corner; three elements a row: the row without its low-pass
    assert residual_harmonics(theta, ripple, np.ones(n), count=1, corners=corners,
                              ts=TS)[0].corner is None
    (codes3, _), = harmonic_rows([lagged], ranges, 3, {el.code for el in BY_NAME.values()})
    assert BY_NAME["lpf"].code not in codes3.tolist()


def test_seeds_need_a_rotary_axis_and_an_angle() -> None:
    assert angle_input(["velocity", "angle", "angle_wrapped"], "rotary") == 2
    assert angle_input(["velocity", "angle"], "rotary") == 1
    assert angle_input(["velocity", "acceleration"], "rotary") is None
    assert angle_input(["angle_wrapped", "velocity"], "linear") is None


def _ripple_log() -> DataLog:
    n = 6000
    t = np.arange(n) * TS
    omega = 8.0 * np.sin(2 * np.pi * 0.3 * t) + 3.0
    theta = np.cumsum(omega) * TS
    rng = np.random.default_rng(1)
    tau = (0.6 * np.sign(omega) + 0.01 * omega + 0.15 * np.sin(6 * theta + 0.4)
           + rng.normal(0.0, 0.005, n))
    return DataLog({"t": t, "theta_w": np.mod(theta, 2 * np.pi), "omega": omega, "tau": tau},
                   TS, "ripple.csv")


DOC = {"ga": {"population": 16, "generations": 3, "continue": "no", "restarts": 0,
              "local_search": 0},
       "step": [{"n_rows": 1, "n_elements": 4}, {"n_rows": 2, "n_elements": 4}]}


def test_a_step_that_adds_a_row_meets_the_ripple_through_its_seed() -> None:
    log = _ripple_log()

    def run(seeds: int) -> object:
        doc = {**DOC, "ga": {**DOC["ga"], "harmonic_seeds": seeds}}
        return abstract(log, target="tau", inputs=["theta_w", "omega"],
                        config=parse_config(doc, "t.toml"), seed=5, parallel=Parallel(workers=1))

    seeded, plain = run(3), run(0)
    matrix = seeded.steps[-1].matrix
    ripple = [r for r in matrix.rows if r.input == 0]
    assert ripple, "the seeded harmonic row was bred out"
    gain = default_ranges(TS, len(log) * TS)["gain"]
    assert gain.decode(ripple[0].genes[0].p) == pytest.approx(6.0, abs=0.05)
    assert seeded.steps[-1].fitness < 0.5 * plain.steps[-1].fitness
    # a function of the seed: the same bytes again
    assert dumps(run(3)) == dumps(seeded)


def test_a_stribeck_hump_of_the_residual_is_found_at_its_velocity() -> None:
    rng = np.random.default_rng(2)
    v = rng.uniform(-12.0, 12.0, 20000)
    for vs in (0.8, 3.0):
        resid = 0.4 * np.exp(-(v / vs) ** 2) * np.sign(v) + rng.normal(0.0, 0.01, v.size)
        (k, c, drop), second = residual_stribeck(v, resid, np.ones_like(v), count=2)
        # 1 - tanh(|v| / a) matches exp(-(v / v_s)^2) best with a near 1.5 v_s
        assert 1.0 / k == pytest.approx(1.5 * vs, rel=0.35)
        assert c < 0 and drop > 0.95
        assert abs(np.log(second[0] / k)) >= np.log(2.0) - 1e-12
    # no hump: nothing the fit removes beyond the noise
    flat = rng.normal(0.0, 0.01, v.size)
    assert residual_stribeck(v, flat, np.ones_like(v), count=1)[0][2] < 0.01


def test_a_stribeck_seed_row_is_the_tanh_it_was_made_from() -> None:
    ranges = default_ranges(TS, 10.0)
    allowed = {el.code for el in BY_NAME.values()}
    (codes, ps), = stribeck_rows([(0.4, -0.3, 0.9)], ranges, 4, allowed)
    row = Row(0, tuple(Gene(int(c), float(p)) for c, p in zip(codes, ps, strict=True)))
    comp = Compensator(ElementMatrix(("omega",), (row,)), TS, ranges, 10.0)
    v = np.linspace(-10.0, 10.0, 500)
    out = simulate_rows(comp, [row], v[None, :])[0]
    np.testing.assert_allclose(out, -0.3 * np.tanh(0.4 * v), rtol=1e-9, atol=1e-12)
    assert stribeck_rows([(0.4, -0.3, 0.9)], ranges, 1, allowed) == []
    assert stribeck_rows([(0.4, -0.3, 0.9)], ranges, 4, allowed - {BY_NAME["tanh"].code}) == []
    assert stribeck_rows([(0.4, -30.0, 0.9)], ranges, 4, allowed) == []
    assert velocity_input(["angle", "velocity"]) == 1 and velocity_input(["angle"]) is None


def _stribeck_log() -> DataLog:
    n = 8000
    t = np.arange(n) * TS
    omega = 6.0 * np.sin(2 * np.pi * 0.25 * t) * np.abs(np.sin(2 * np.pi * 0.05 * t))
    rng = np.random.default_rng(3)
    tau = (0.3 * np.sign(omega) + 0.35 * np.exp(-(omega / 1.0) ** 2) * np.sign(omega)
           + 0.01 * omega + rng.normal(0.0, 0.005, n))
    return DataLog({"t": t, "omega": omega, "tau": tau}, TS, "stribeck.csv")


def test_a_step_that_adds_a_row_meets_the_stribeck_hump_through_its_seed() -> None:
    log = _stribeck_log()

    def run(seeds: int) -> object:
        doc = {**DOC, "ga": {**DOC["ga"], "stribeck_seeds": seeds}}
        return abstract(log, target="tau", inputs=["omega"],
                        config=parse_config(doc, "t.toml"), seed=5, parallel=Parallel(workers=1))

    seeded, plain = run(2), run(0)
    tanh = BY_NAME["tanh"].code
    assert any(g.code == tanh for r in seeded.steps[-1].matrix.rows for g in r.genes), \
        "the seeded tanh row was bred out"
    assert seeded.steps[-1].fitness < 0.7 * plain.steps[-1].fitness
    assert dumps(run(2)) == dumps(seeded)


def test_a_long_log_is_seeded_from_a_thinned_fit_in_bounded_memory(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """320 000 samples: the seeds fit every 8th training sample, the low-passed columns
    filtered over the whole log one at a time; the harmonic and its corner are those of
    the whole log, and the fit never holds the log's columns all at once."""
    import tracemalloc

    from edm_sym.engines.abstraction.seeding import SEED_SAMPLES, fitted_samples

    n = 320_000
    t = np.arange(n) * TS
    omega = 60.0 * np.sin(2 * np.pi * 0.1 * t)
    theta = np.cumsum(omega) * TS
    b, a = BY_NAME["lpf"].coefficients(250.0, TS)
    resid = (lfilter(b, a, 0.15 * np.sin(7 * theta + 0.9))
             + np.random.default_rng(6).normal(0.0, 0.005, n))
    weights = np.ones(n)
    weights[100_000:140_000] = 0.0  # held out
    chosen = fitted_samples(weights)
    assert chosen.size <= SEED_SAMPLES and np.all(weights[chosen] > 0)
    assert np.array_equal(fitted_samples(weights[:30_000]), np.arange(30_000))
    ranges = default_ranges(TS, n * TS)
    corners = np.geomspace(ranges["lpf"].low, ranges["lpf"].high, LAG_CORNERS)
    tracemalloc.start()
    try:
        lagged, = residual_harmonics(theta, resid, weights, count=1, corners=corners, ts=TS)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert lagged.order == 7 and lagged.amplitude == pytest.approx(0.15, rel=0.05)
    assert lagged.corner == pytest.approx(250.0, rel=0.1)
    # A few whole-log vectors (the angle's speed, one column and its filtered copy ...):
    # the whole-log fit held over a hundred at once (0.3 GB).
    assert peak < 20 * 8 * n
    hump = 0.1 * np.sign(omega) * np.exp(-(omega / 5.0) ** 2)
    (k, c, _), = residual_stribeck(omega, hump, weights, 1)
    # the same as the whole log's fits (every sample)
    from edm_sym.engines.abstraction import seeding

    monkeypatch.setattr(seeding, "SEED_SAMPLES", 10 * n)
    whole, = residual_harmonics(theta, resid, weights, count=1, corners=corners, ts=TS)
    assert whole.order == lagged.order and whole.corner == pytest.approx(lagged.corner, rel=0.02)
    assert whole.amplitude == pytest.approx(lagged.amplitude, rel=0.01)
    (k_all, c_all, _), = residual_stribeck(omega, hump, weights, 1)
    assert k == pytest.approx(k_all, rel=0.05) and c == pytest.approx(c_all, rel=0.02)
