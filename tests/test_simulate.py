"""The reference simulator: matrix semantics and the finite-output property."""

from __future__ import annotations

import numpy as np
from conftest import TS, smooth_signal
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from edm_sym.core.elements import REGISTRY
from edm_sym.core.matrix import Compensator, ElementMatrix, Gene, Row
from edm_sym.engines.simulate import fitness, plain_loop, simulate, simulate_row


def test_rows_run_left_to_right_and_sum(coulomb_viscous: Compensator) -> None:
    omega = 5 * smooth_signal()
    data = {"theta_w": np.zeros_like(omega), "omega": omega}
    sim = simulate(coulomb_viscous, data)
    np.testing.assert_allclose(sim.rows[0], 0.93 * np.sign(omega), rtol=1e-12)
    np.testing.assert_allclose(sim.rows[1], 0.007 * omega, rtol=1e-12)
    np.testing.assert_allclose(sim.total, sim.rows.sum(0), rtol=0, atol=0)
    assert fitness(sim.residual(sim.total)) == 0.0


def test_order_matters_within_a_row() -> None:
    x = smooth_signal()
    ab = ElementMatrix(("x",), (Row(0, (Gene(7, 0.4), Gene(19, 0.0))),))  # lpf then sign
    ba = ElementMatrix(("x",), (Row(0, (Gene(19, 0.0), Gene(7, 0.4))),))  # sign then lpf
    ya = simulate(Compensator(ab, TS, {}, 20.0), {"x": x}).total
    yb = simulate(Compensator(ba, TS, {}, 20.0), {"x": x}).total
    assert set(np.unique(ya)) <= {-1.0, 0.0, 1.0}
    assert len(np.unique(yb)) > 100


def test_fitness_is_eq_8() -> None:
    r = np.array([1.0, -2.0, 3.0])
    lam = np.array([1.0, 0.0, 2.0])
    assert fitness(r, lam) == np.sqrt((1 + 0 + 18) / 3)


def test_plain_loop_equals_vectorised(coulomb_viscous: Compensator) -> None:
    x = 3 * smooth_signal(2000)
    data = {"theta_w": np.mod(x, 2 * np.pi), "omega": x}
    np.testing.assert_allclose(plain_loop(coulomb_viscous, data),
                               simulate(coulomb_viscous, data).rows, rtol=1e-12, atol=1e-12)


@st.composite
def matrices(draw, max_n: int = 8, max_m: int = 6, n_inputs: int = 3) -> ElementMatrix:
    n = draw(st.integers(1, max_n))
    m = draw(st.integers(1, max_m))
    codes = st.sampled_from(sorted(REGISTRY))
    ps = st.floats(0.0, 1.0, allow_nan=False)
    rows = tuple(
        Row(draw(st.integers(0, n_inputs - 1)),
            tuple(Gene(draw(codes), draw(ps)) for _ in range(n)))
        for _ in range(m)
    )
    return ElementMatrix(("u0", "u1", "u2"), rows)


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(matrix=matrices(), seed=st.integers(0, 2**32 - 1), scale=st.sampled_from([1e-3, 1.0, 1e4]))
def test_any_valid_matrix_simulates_to_finite_outputs(matrix, seed, scale) -> None:
    rng = np.random.default_rng(seed)
    n = 1500
    data = {f"u{k}": rng.uniform(-scale, scale, n) for k in range(3)}
    comp = Compensator(matrix, TS, {}, n * TS)
    sim = simulate(comp, data)
    assert sim.rows.shape == (matrix.n_rows, n)
    assert np.all(np.isfinite(sim.rows)) and np.all(np.isfinite(sim.total))


@settings(max_examples=40, deadline=None)
@given(matrix=matrices(max_n=4, max_m=3), seed=st.integers(0, 1000))
def test_vectorised_rows_equal_the_plain_loop(matrix, seed) -> None:
    rng = np.random.default_rng(seed)
    data = {f"u{k}": rng.uniform(-2, 2, 300) for k in range(3)}
    comp = Compensator(matrix, TS, {}, 20.0)
    want = plain_loop(comp, data)
    got = np.vstack([simulate_row(comp, r, data[f"u{r.input}"]) for r in matrix.rows])
    np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-9 * (1 + np.abs(want).max()))
