"""Symbolic decoding: row expressions, bounded simplification, python-control forms."""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp
from conftest import TS, smooth_signal

import edm_sym
from edm_sym.core.elements import element
from edm_sym.core.matrix import Compensator, make_matrix
from edm_sym.engines.simulate import simulate_row
from edm_sym.engines.symbolic import (
    LTI,
    Delay,
    Relay,
    SimplifyOptions,
    decode,
    simplify_expression,
    simulate_system,
    to_tf,
)
from edm_sym.engines.symbolic.functions import NUMPY_FUNCTIONS, GTan, Sat
from edm_sym.engines.symbolic.lti import z_polynomials
from edm_sym.engines.symbolic.operators import s
from edm_sym.engines.symbolic.simplify import minreal
from edm_sym.outputs.printing.latex import latex

OMEGA = sp.Symbol("omega", real=True)
THETA_W = sp.Symbol("theta_w", real=True)


def enc(name: str, value: float) -> float:
    """The p that decodes to ``value`` with the element's default range."""
    return element(name).param.default(TS, 20.0).encode(value)


def comp_of(rows, inputs=("theta_w", "omega", "alpha")) -> Compensator:
    return Compensator(make_matrix(list(inputs), rows), TS, {}, 20.0)


def a(k: int) -> sp.Symbol:
    return sp.Symbol(f"a_{k}", real=True)


def assert_tf(G: sp.Expr, num: list[float], den: list[float]) -> None:
    """G(s) has these coefficients (descending powers of s, den monic) to 1e-9."""
    tf = to_tf(G)
    n, d = tf.num[0][0], tf.den[0][0]
    np.testing.assert_allclose(n / d[0], num, rtol=1e-9)
    np.testing.assert_allclose(d / d[0], den, rtol=1e-9)


def lam(expr: sp.Expr, sym: sp.Symbol):
    f = sp.lambdify(sym, expr, modules=[NUMPY_FUNCTIONS, "numpy"])
    return lambda x: np.asarray(f(x), dtype=float) * np.ones_like(x)


# -- hand-built matrices decode to the expected expressions -----------------------


def test_coulomb_viscous_initial_model(coulomb_viscous: Compensator) -> None:
    model = decode(coulomb_viscous)
    r0, r1 = model.rows
    # Row 0: sign, gain (a_2), through -> a_2 sgn(omega); row 1: power gain a_4.
    assert r0.expr_raw == a(2) * sp.sign(OMEGA)
    assert r0.expr == a(2) * sp.sign(OMEGA)
    assert r1.expr == a(4) * OMEGA
    c0, f0 = r0.expr_numeric.as_coeff_Mul()
    assert f0 == sp.sign(OMEGA) and abs(float(c0) - 0.93) < 1e-9
    c1, f1 = r1.expr_numeric.as_coeff_Mul()
    assert f1 == OMEGA and abs(float(c1) - 0.007) < 1e-9
    assert model.total(numeric=False) == a(2) * sp.sign(OMEGA) + a(4) * OMEGA
    assert [p.symbol for p in model.params] == [a(2), a(4)]


def test_velocity_derivative_through_low_pass() -> None:
    comp = comp_of([("omega", [("derivative", enc("derivative", 0.02)),
                               ("lpf", enc("lpf", 150.0)), ("through", 0)])])
    row = decode(comp).rows[0]
    assert row.expr_raw == LTI(LTI(OMEGA, a(1) * s), a(2) / (s + a(2)))
    assert row.expr == LTI(OMEGA, a(1) * a(2) * s / (s + a(2)))
    assert isinstance(row.expr_numeric, LTI) and row.expr_numeric.args[0] == OMEGA
    assert_tf(row.expr_numeric.args[1], [0.02 * 150.0, 0.0], [1.0, 150.0])


def test_spatial_sine_of_wrapped_angle() -> None:
    comp = comp_of([("theta_w", [("gain", enc("gain", 4.0)), ("sin_phase", enc("sin_phase", 0.3)),
                                 ("sin_amp", enc("sin_amp", 0.05))])])
    row = decode(comp).rows[0]
    assert row.expr_raw == a(3) * sp.sin(sp.sin(a(1) * THETA_W + a(2)))
    num = row.expr_numeric
    assert isinstance(num, sp.Mul) and abs(float(num.as_coeff_Mul()[0]) - 0.05) < 1e-9


def test_unclassifiable_chain_decodes_to_its_composition() -> None:
    comp = comp_of([("omega", [("tan_amp", enc("tan_amp", 1.5)), ("log", enc("log", 0.2)),
                               ("acos", 0), ("power", enc("power", 2.0))])])
    row = decode(comp).rows[0]
    from edm_sym.engines.symbolic.functions import GAcos, SymLog, SymPow
    assert row.expr == SymPow(GAcos(SymLog(a(1) * GTan(OMEGA), a(2))), a(4))


# -- the bounded rewrite passes ----------------------------------------------------


def simp(expr: sp.Expr, numeric: bool = True, **kw) -> sp.Expr:
    return simplify_expression(expr, [OMEGA, THETA_W], numeric=numeric, **kw)


def test_gains_offsets_inversions_and_throughs_fold() -> None:
    comp = comp_of([("omega", [("through", 0), ("gain", enc("gain", 2.0)), ("invert", 0),
                               ("offset", enc("offset", 1.0)), ("gain", enc("gain", 3.0)),
                               ("offset", enc("offset", -0.5))])])
    row = decode(comp).rows[0]
    assert row.expr == -a(2) * a(5) * OMEGA + a(4) * a(5) + a(6)
    x = np.linspace(-3, 3, 11)
    np.testing.assert_allclose(lam(row.expr_numeric, OMEGA)(x), -6 * x + 3 - 0.5, atol=1e-12)
    assert len(row.expr_numeric.args) == 2  # c omega + d


def test_sign_rules() -> None:
    x = OMEGA
    assert simp(sp.sign(sp.sign(x))) == sp.sign(x)
    assert simp(sp.sign(2.5 * x)) == sp.sign(x)
    assert simp(sp.sign(sp.tanh(3.0 * x))) == sp.sign(x)
    assert simp(sp.sign(Sat(x, -0.2, 0.2))) == sp.sign(x)
    pos = a(7)
    assert simp(sp.sign(pos * x), numeric=False, signs={pos: 1}) == sp.sign(x)
    assert simp(sp.sign(pos * x), numeric=False) == sp.sign(pos * x)  # sign unknown: kept


def test_odd_functions_of_a_sign_factor_out() -> None:
    x = OMEGA
    assert simp(sp.tanh(2.0 * sp.sign(x))) == sp.Float(np.tanh(2.0)) * sp.sign(x)
    out = simp(sp.atan(0.5 * sp.sign(x)))
    assert out.as_coeff_Mul()[1] == sp.sign(x)
    assert abs(float(out.as_coeff_Mul()[0]) - np.arctan(0.5)) < 1e-15


def test_guards_vanish_when_the_argument_stays_inside() -> None:
    x = OMEGA
    assert simp(Sat(sp.tanh(x), -2.0, 2.0)) == sp.tanh(x)
    assert simp(Sat(Sat(x, -1.0, 1.0), -0.5, 0.5)) == Sat(x, -0.5, 0.5)
    assert simp(Sat(sp.sign(x), -3.0, 3.0)) == sp.sign(x)
    assert simp(Sat(sp.sign(x), -0.3, 0.3)) == sp.Float(0.3) * sp.sign(x)
    from edm_sym.engines.symbolic.functions import GAsin
    assert simp(GAsin(sp.sin(x))) == sp.asin(sp.sin(x))
    assert simp(GTan(sp.atan(2.0 * x))) == Sat(2.0 * x, -1e6, 1e6)


def test_linear_blocks_merge_and_gains_fold_into_them() -> None:
    G1, G2 = 10.0 / (s + 10.0), s / (s + 3.0)
    out = simp(2.0 * LTI(3.0 * LTI(OMEGA, G1), G2))
    assert isinstance(out, LTI) and out.args[0] == OMEGA
    assert_tf(out.args[1], [60.0, 0.0], [1.0, 13.0, 30.0])


def test_pole_zero_cancellation_and_constant_tf() -> None:
    # A lead followed by a lag with the same corner is the identity in continuous time.
    comp = comp_of([("omega", [("lead", enc("lead", 5.0)), ("gain", enc("gain", 2.0)),
                               ("lag", enc("lag", 5.0))])])
    row = decode(comp).rows[0]
    c, rest = row.expr_numeric.as_coeff_Mul()
    assert rest == OMEGA and abs(float(c) - 2.0) < 1e-9
    n, d = minreal([1.0, 3.0], [1.0, 3.0 + 1e-9])
    assert list(n) == pytest.approx([1.0]) and list(d) == pytest.approx([1.0])
    n, d = minreal([1.0, 3.0], [1.0, 3.1])
    assert len(d) == 2  # 3 %: not cancelled


def test_delays_merge_and_move_out() -> None:
    comp = comp_of([("omega", [("dead_time", enc("dead_time", 0.01)), ("sign", 0),
                               ("shift", enc("shift", 3.0)), ("gain", enc("gain", 0.5))])])
    row = decode(comp).rows[0]
    out = row.expr_numeric
    assert isinstance(out, Delay)
    assert abs(float(out.args[1]) - 0.013) < 1e-12
    c, rest = out.args[0].as_coeff_Mul()
    assert rest == sp.sign(OMEGA) and abs(float(c) - 0.5) < 1e-9
    assert row.expr == Delay(a(4) * sp.sign(OMEGA), a(1) + sp.Float(TS, 17) * a(3))


def test_relay_absorbs_a_gain() -> None:
    out = simp(Relay(-4.0 * OMEGA, 0.2))
    assert out == -Relay(OMEGA, sp.Float(0.05))


def test_passes_are_bounded() -> None:
    with pytest.raises(ValueError, match="passes"):
        SimplifyOptions(passes=0)
    one = simp(sp.sign(sp.sign(sp.tanh(sp.sign(OMEGA)))), options=SimplifyOptions(passes=1))
    assert isinstance(one, sp.Expr)


def test_latex_of_the_operators() -> None:
    # The project's LaTeX printer is the one place that knows LaTeX (the operators have no _latex).
    assert latex(LTI(OMEGA, a(1) / (s + a(1)))) == (
        r"\left\{\frac{a_{1}}{a_{1} + s}\right\}\left[\omega\right]")
    assert latex(Delay(OMEGA, a(2))) == r"\left[\omega\right]_{t - a_{2}}"
    assert latex(Relay(OMEGA, a(3))) == r"\operatorname{relay}_{a_{3}}\left(\omega\right)"


def test_existing_fields_are_kept(coulomb_viscous: Compensator) -> None:
    from edm_sym.engines.symbolic import build_model
    base = build_model(coulomb_viscous)
    full = edm_sym.decode(coulomb_viscous)
    for rb, rf in zip(base.rows, full.rows, strict=True):
        assert rb.stages == rf.stages and rb.input_symbol == rf.input_symbol
        assert rb.expr is None and rf.expr is not None
    assert base.params == full.params
    with pytest.raises(ValueError, match="build_model"):
        base.total()


# -- python-control --------------------------------------------------------------

DYNAMIC_ROWS = [
    ("omega", [("derivative", enc("derivative", 0.05)), ("lpf", enc("lpf", 80.0)),
               ("hpf", enc("hpf", 2.0)), ("integral", enc("integral", 3.0)),
               ("lead", enc("lead", 20.0))]),
    ("omega", [("lag", enc("lag", 10.0)), ("phase", enc("phase", 30.0)),
               ("notch", enc("notch", 60.0)), ("dead_time", enc("dead_time", 0.012)),
               ("shift", enc("shift", 4.0))]),
    ("theta_w", [("gain", enc("gain", 3.0)), ("hysteresis", enc("hysteresis", 0.4)),
                 ("lpf", enc("lpf", 40.0)), ("tanh", enc("tanh", 2.0)),
                 ("shift", enc("shift", 2.0))]),
    ("omega", [("sin_phase", 0.3), ("saturation", enc("saturation", 0.5)), ("integral", 0.5),
               ("sign", 0), ("notch", 0.4)]),
]


def test_row_systems_equal_the_reference_simulator() -> None:
    comp = comp_of(DYNAMIC_ROWS)
    model = decode(comp)
    x = {"theta_w": 2.0 * smooth_signal(seed=1), "omega": 1.5 * smooth_signal(seed=2),
         "alpha": smooth_signal(seed=3)}
    for row, mrow in zip(model.rows, comp.matrix.rows, strict=True):
        u = x[row.input]
        assert u.size == 20_000
        ref = simulate_row(comp, mrow, u)
        got = simulate_system(row.system, u)
        assert np.max(np.abs(ref)) > 1e-3  # the row does something
        np.testing.assert_allclose(got, ref, rtol=0, atol=1e-9)
        assert row.system.dt == TS and row.system.nstates == sum(
            st.element.state_size(st.value, TS) for st in row.stages)


def test_discrete_transfer_functions_hold_the_simulator_coefficients() -> None:
    import control as ct
    from scipy import signal

    model = decode(comp_of(DYNAMIC_ROWS))
    x = smooth_signal(2000, seed=4)
    n_parts = 0
    for row in model.rows:
        stages = {st.col: st for st in row.stages}
        for part in row.linear_parts:
            st = stages[part.col]
            n_parts += 1
            assert part.discrete.dt == TS
            if st.kind == "delay":
                continue
            num, den = z_polynomials(st.b, st.a)
            np.testing.assert_array_equal(part.discrete.num[0][0], np.trim_zeros(num, "f"))
            # python-control's own simulation of H(z) equals lfilter with Stage.b, Stage.a.
            y = ct.forced_response(part.discrete, np.arange(x.size) * TS, x).outputs
            np.testing.assert_allclose(y, signal.lfilter(st.b, st.a, x), atol=1e-9)
            if st.method == "bilinear":  # independent oracle: python-control's Tustin
                tustin = ct.sample_system(part.continuous, TS, method="tustin")
                np.testing.assert_allclose(
                    ct.forced_response(tustin, np.arange(x.size) * TS, x).outputs,
                    y, rtol=1e-7, atol=1e-9)
    assert n_parts == 14


def test_to_tf_of_a_simplified_row() -> None:
    comp = comp_of([("omega", [("derivative", enc("derivative", 0.02)),
                               ("lpf", enc("lpf", 150.0))])])
    G = decode(comp).rows[0].expr_numeric.args[1]
    tf = to_tf(G)
    assert abs(tf(1j * 150.0) - 0.02 * 150.0 * 150j / (150j + 150.0)) < 1e-9


# -- decoding robustness --------------------------------------------------------

NASTY_CHAIN = ["sin_phase", "tan_amp", "asin", "power", "log", "tan_phase", "acos", "sin_amp"]


def nasty_matrix() -> Compensator:
    rows = []
    for j in range(6):
        chain = NASTY_CHAIN[j:] + NASTY_CHAIN[:j]
        rows.append(("omega" if j % 2 else "theta_w",
                     [(name, (0.13 + 0.11 * i + 0.07 * j) % 1.0) for i, name in enumerate(chain)]))
    return comp_of(rows)


def test_nasty_matrix_decodes() -> None:
    model = decode(nasty_matrix())
    assert len(model.rows) == 6 and len(model.params) > 30
    x = 0.3 * smooth_signal(500)
    for row, mrow in zip(model.rows, model.compensator.matrix.rows, strict=True):
        assert row.expr is not None and row.terms is not None
        np.testing.assert_allclose(lam(row.expr_raw_numeric, row.input_symbol)(x),
                                   simulate_row(model.compensator, mrow, x), rtol=1e-9,
                                   atol=1e-9)


def test_decode_of_a_result_through_the_package_api(coulomb_viscous: Compensator,
                                                      tmp_path) -> None:
    from edm_sym.core.result import EdmResult, load_result, save_result

    prov = {"seed": 3, "package_version": "0.1.0", "data_sha256": "0" * 64}
    path = save_result(EdmResult(coulomb_viscous, "tau_ext", (), prov), tmp_path / "result.json")
    result = load_result(path)
    model = edm_sym.decode(result, roles={"omega": None})
    assert model.target == "tau_ext" and model.source_sha256 == result.sha256
    assert model.roles["omega"] is None
    assert model.rows[0].expr == a(2) * sp.sign(OMEGA)
    assert all(t.kind == "unclassified" for r in model.rows for t in r.terms)
