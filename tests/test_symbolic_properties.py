"""Properties of decoding: any valid matrix decodes, and its forms compute the simulator's numbers.

Where a row is ill-conditioned (a tangent near its pole, a sign near zero, a
power of a huge number), any two correct evaluations may differ by far more
than rounding. Those samples are recognised the honest way -- the simulator
itself moves there when the input or the parameters move by 1e-10 -- and only
the other samples are compared, to 1e-9.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import sympy as sp
from conftest import TS, smooth_signal
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from edm_sym.core.elements import REGISTRY, StaticElement
from edm_sym.core.matrix import Compensator, ElementMatrix, Gene, Row
from edm_sym.engines.simulate import simulate_row
from edm_sym.engines.symbolic import PhysicalTerm, decode, simulate_system
from edm_sym.engines.symbolic.classify import KINDS
from edm_sym.engines.symbolic.functions import NUMPY_FUNCTIONS

INPUTS = ("theta_w", "omega", "alpha")
STATIC = sorted(c for c, el in REGISTRY.items() if issubclass(el, StaticElement))
N = 400
SIGNALS = np.vstack([np.mod(6 * smooth_signal(N, seed=11), 2 * np.pi),
                     2 * smooth_signal(N, seed=12), 3 * smooth_signal(N, seed=13)])


@st.composite
def matrices(draw, codes: list[int], max_n: int = 6, max_m: int = 4) -> ElementMatrix:
    n = draw(st.integers(1, max_n))
    m = draw(st.integers(1, max_m))
    ps = st.floats(0.0, 1.0, allow_nan=False)
    rows = tuple(Row(draw(st.integers(0, len(INPUTS) - 1)),
                     tuple(Gene(draw(st.sampled_from(codes)), draw(ps)) for _ in range(n)))
                 for _ in range(m))
    return ElementMatrix(INPUTS, rows)


def _nudged(comp: Compensator, row: Row, dp: float) -> tuple[Compensator, Row]:
    genes = tuple(Gene(g.code, min(1.0, max(0.0, g.p + dp))) for g in row.genes)
    return comp, dataclasses.replace(row, genes=genes)


def well_conditioned(comp: Compensator, row: Row, x: np.ndarray, ref: np.ndarray) -> np.ndarray:
    """Samples where the simulator moves by < 1e-7 (relative) under 1e-10 nudges."""
    eps = 1e-10
    outs = [simulate_row(comp, row, x * (1 + eps) + eps),
            simulate_row(comp, row, x * (1 - eps) - eps)]
    for dp in (eps, -eps):
        c, r = _nudged(comp, row, dp)
        outs.append(simulate_row(c, r, x))
    ok = np.ones(x.shape, dtype=bool)
    for y in outs:
        ok &= np.abs(y - ref) <= 1e-7 * (1 + np.abs(ref))
    return ok


def evaluate(expr: sp.Expr, sym: sp.Symbol, x: np.ndarray) -> np.ndarray:
    f = sp.lambdify(sym, expr, modules=[NUMPY_FUNCTIONS, "numpy"])
    with np.errstate(all="ignore"):
        return np.asarray(f(x), dtype=float) * np.ones_like(x)


def assert_equal_where_conditioned(got: np.ndarray, ref: np.ndarray, ok: np.ndarray) -> None:
    np.testing.assert_allclose(got[ok], ref[ok], rtol=1e-9, atol=1e-9)


def check_decodes(matrix: ElementMatrix) -> None:
    """Decode ``matrix`` and check every row's forms against the simulator."""
    comp = Compensator(matrix, TS, {}, 20.0)
    model = decode(comp)
    assert len(model.rows) == matrix.n_rows
    for row, mrow in zip(model.rows, matrix.rows, strict=True):
        for e in (row.expr_raw, row.expr_raw_numeric, row.expr, row.expr_numeric):
            assert isinstance(e, sp.Expr)
        assert not (row.expr_numeric.free_symbols - {row.input_symbol, sp.Symbol("s")})
        assert all(isinstance(t, PhysicalTerm) and t.kind in KINDS for t in row.terms)
        assert row.system.nstates == sum(g.element.state_size(comp.value(g), TS)
                                         for g in mrow.genes)
        # The python-control row system computes the simulator's numbers.
        x = SIGNALS[mrow.input][:120]
        ref = simulate_row(comp, mrow, x)
        assert_equal_where_conditioned(simulate_system(row.system, x), ref,
                                       well_conditioned(comp, mrow, x, ref))


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(matrices(sorted(REGISTRY)))
def test_any_matrix_decodes(matrix: ElementMatrix) -> None:
    check_decodes(matrix)


@pytest.mark.slow
@settings(max_examples=400, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(matrices(sorted(REGISTRY)))
def test_any_matrix_decodes_many(matrix: ElementMatrix) -> None:
    check_decodes(matrix)


@settings(max_examples=100, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(matrices(STATIC))
def test_static_row_expressions_equal_the_simulator(matrix: ElementMatrix) -> None:
    comp = Compensator(matrix, TS, {}, 20.0)
    model = decode(comp, systems=False)
    for row, mrow in zip(model.rows, matrix.rows, strict=True):
        x = SIGNALS[mrow.input]
        ref = simulate_row(comp, mrow, x)
        ok = well_conditioned(comp, mrow, x, ref)
        # The raw form is the simulator's computation, sample for sample.
        assert_equal_where_conditioned(evaluate(row.expr_raw_numeric, row.input_symbol, x),
                                       ref, ok)
        # The simplified form is the same function.
        assert_equal_where_conditioned(evaluate(row.expr_numeric, row.input_symbol, x), ref, ok)
        # And so is the named form with the parameter values substituted.
        values = {p.symbol: sp.Float(p.value, 17) for p in model.params}
        assert_equal_where_conditioned(
            evaluate(row.expr.xreplace(values), row.input_symbol, x), ref, ok)
