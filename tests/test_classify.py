"""Physical classification of rows, input roles and row contributions."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
import sympy as sp
from conftest import TS, smooth_signal

from edm_sym.core.elements import default_ranges, element
from edm_sym.core.matrix import Compensator, make_matrix
from edm_sym.core.terms import TermKind
from edm_sym.engines.simulate import simulate
from edm_sym.engines.symbolic import (
    LTI,
    ClassifyOptions,
    Delay,
    PhysicalTerm,
    RowModel,
    contributions,
    decode,
    input_roles,
    s,
)
from edm_sym.engines.symbolic.classify import KINDS
from edm_sym.engines.symbolic.functions import SymPow

INPUTS = ("theta_w", "theta_uw", "omega", "alpha", "x")


def enc(name: str, value: float) -> float:
    return element(name).param.default(TS, 20.0).encode(value)


def terms_of(genes, inp="omega", **kw) -> tuple[PhysicalTerm, ...]:
    comp = Compensator(make_matrix(INPUTS, [(inp, genes)]), TS, {}, 20.0)
    return decode(comp, systems=False, **kw).rows[0].terms


def one(terms, kind: str) -> PhysicalTerm:
    found = [t for t in terms if t.kind == kind]
    assert len(found) == 1, terms
    return found[0]


def close(term: PhysicalTerm, name: str, value: float, unit: str) -> None:
    got, got_unit = term.parameters[name]
    assert got_unit == unit
    assert abs(got - value) <= 1e-9 * max(1.0, abs(value)), (name, got, value)


def test_saturating_acceleration_term() -> None:
    # The paper's fifth row: 9.296 tanh(0.0998 * 2.059 * LPF(alpha)).
    t = one(terms_of([("lpf", enc("lpf", 451.6)), ("gain", enc("gain", 0.0998)),
                      ("tanh", enc("tanh", 2.059)), ("gain", enc("gain", 9.296))], inp="alpha"),
            "acceleration")
    close(t, "inertia", 9.296 * 0.0998 * 2.059, "kg m^2")
    close(t, "saturation_level", 9.296, "N m")
    close(t, "corner", 451.6, "rad/s")


def test_coulomb_and_viscous_initial_model(coulomb_viscous: Compensator) -> None:
    model = decode(coulomb_viscous)
    assert model.roles == {"theta_w": "angle_wrapped", "omega": "velocity"}
    c = one(model.rows[0].terms, "coulomb")
    close(c, "level", 0.93, "N m")
    v = one(model.rows[1].terms, "viscous")
    close(v, "coefficient", 0.007, "N m s/rad")
    assert all(len(r.terms) == 1 for r in model.rows)


def test_acceleration_from_velocity_derivative_through_low_pass() -> None:
    t = one(terms_of([("derivative", enc("derivative", 0.02)), ("gain", enc("gain", 0.5)),
                      ("lpf", enc("lpf", 150.0))]), "acceleration")
    close(t, "inertia", 0.01, "kg m^2")
    close(t, "corner", 150.0, "rad/s")


def test_a_filtered_acceleration_is_named_by_its_gain_where_the_motion_is() -> None:
    # EMPS seed 1's row 3: corners at 1.28 and 1472 rad/s and a zero in the right half
    # plane at 1.28 rad/s, so the filter's DC gain (-7.44) has the other sign than its
    # gain through the 0.2-20 Hz motion (+7.47 at 4 pi rad/s, shifted by 16 deg).
    from edm_sym.engines.symbolic import classify_expression
    from edm_sym.engines.symbolic.significance import _term_flags as term_flags

    a = sp.Symbol("alpha")
    G = (74.4 * s**2 + 1.086e4 * s - 1.399e4) / (s**2 + 1474.0 * s + 1881.0)  # noqa: N806
    t = one(classify_expression(LTI(a, G), a, "acceleration"), "acceleration")
    jw = 4j * math.pi
    g = (74.4 * jw**2 + 1.086e4 * jw - 1.399e4) / (jw**2 + 1474.0 * jw + 1881.0)
    assert t.parameters["inertia"][0] == pytest.approx(abs(g), rel=1e-6)
    assert t.parameters["filter_phase"][0] == pytest.approx(np.angle(g), rel=1e-6)
    assert not any(f.code == "derivative_like" for f in term_flags(t))
    # A low pass below that frequency: named there, and it acts mostly as an integral.
    t = one(classify_expression(LTI(a, 0.3 * 5 / (s + 5)), a, "acceleration"), "acceleration")
    assert t.parameters["inertia"][0] == pytest.approx(0.3 * 5 / abs(jw + 5), rel=1e-6)
    assert any(f.code == "derivative_like" for f in term_flags(t))
    # A low pass well above it shifts it by 7 deg: named with its DC gain, as before.
    t = one(classify_expression(LTI(a, 0.3 * 100 / (s + 100)), a, "acceleration"),
            "acceleration")
    close(t, "inertia", 0.3, "kg m^2")
    assert "filter_phase" not in t.parameters


def test_a_saturated_filtered_acceleration_takes_its_slope_where_the_motion_is() -> None:
    # c tanh(k H(s) a) with the EMPS row's filter: its slope for small accelerations is
    # c k H at 4 pi rad/s (+0.747), not c k H(0) (-0.744); the level keeps its sign rule.
    from edm_sym.engines.symbolic import classify_expression
    from edm_sym.engines.symbolic.significance import _term_flags as term_flags

    a, v = sp.Symbol("alpha"), sp.Symbol("omega")
    G = (74.4 * s**2 + 1.086e4 * s - 1.399e4) / (s**2 + 1474.0 * s + 1881.0)  # noqa: N806
    jw = 4j * math.pi
    g = (74.4 * jw**2 + 1.086e4 * jw - 1.399e4) / (jw**2 + 1474.0 * jw + 1881.0)
    t = one(classify_expression(2.0 * sp.tanh(0.05 * LTI(a, G)), a, "acceleration"),
            "acceleration")
    assert t.parameters["inertia"][0] == pytest.approx(2.0 * 0.05 * abs(g), rel=1e-6)
    assert t.parameters["saturation_level"] == (pytest.approx(2.0), "N m")
    assert t.parameters["filter_phase"][0] == pytest.approx(np.angle(g), rel=1e-6)
    assert not any(f.code == "derivative_like" for f in term_flags(t))
    # The velocity differentiated through a low pass below 4 pi: its gain there, derivative-like.
    t = one(classify_expression(2.0 * sp.atan(0.05 * LTI(v, 5 * s / (s + 5))), v, "velocity"),
            "acceleration")
    assert t.parameters["inertia"][0] == pytest.approx(2.0 * 0.05 * 5 / abs(jw + 5), rel=1e-6)
    assert any(f.code == "derivative_like" for f in term_flags(t))
    # A low pass well above it: the DC gain, as before.
    t = one(classify_expression(2.0 * sp.tanh(0.05 * LTI(a, 100 / (s + 100))), a,
                                "acceleration"), "acceleration")
    close(t, "inertia", 0.1, "kg m^2")
    assert "filter_phase" not in t.parameters


def test_acceleration_input() -> None:
    t = one(terms_of([("gain", enc("gain", -0.3))], inp="alpha"), "acceleration")
    close(t, "inertia", -0.3, "kg m^2")
    assert "corner" not in t.parameters


@pytest.mark.parametrize("cycles, phase, amp", [(4.0, 0.3, 0.05), (-3.0, -1.0, -0.2)])
def test_spatial_sine_of_wrapped_angle(cycles: float, phase: float, amp: float) -> None:
    t = one(terms_of([("gain", enc("gain", cycles)), ("sin_phase", enc("sin_phase", phase)),
                      ("gain", enc("gain", amp))], inp="theta_w"), "spatial")
    close(t, "cycles_per_revolution", abs(cycles), "1")
    close(t, "period", 2 * math.pi / abs(cycles), "rad")
    close(t, "amplitude", abs(amp), "N m")
    # The same wave: A sin(k q + phi) at a few angles.
    q = np.linspace(0, 2 * np.pi, 7)
    a_, k_, p_ = (t.parameters[n][0] for n in ("amplitude", "cycles_per_revolution", "phase"))
    np.testing.assert_allclose(a_ * np.sin(k_ * q + p_), amp * np.sin(cycles * q + phase),
                               atol=1e-9)
    assert "jumps" not in t.description


def test_spatial_with_fractional_cycles_warns_of_the_wrap() -> None:
    t = one(terms_of([("gain", enc("gain", 2.5)), ("sin_amp", enc("sin_amp", 0.1))],
                     inp="theta_w"), "spatial")
    assert "jumps at each wrap" in t.description


def test_non_sinusoidal_periodic_term() -> None:
    t = one(terms_of([("gain", enc("gain", 3.0)), ("sin_phase", enc("sin_phase", 0.0)),
                      ("sign", 0), ("gain", enc("gain", 0.4))], inp="theta_uw"), "spatial")
    close(t, "cycles_per_revolution", 3.0, "1")
    close(t, "amplitude", 0.4, "N m")
    assert "non-sinusoidal" in t.description
    # A sine of a sine of the angle: amplitude 0.05 sin(1) over the revolution.
    t = one(terms_of([("gain", enc("gain", 4.0)), ("sin_phase", enc("sin_phase", 0.3)),
                      ("sin_amp", enc("sin_amp", 0.05))], inp="theta_w"), "spatial")
    close(t, "cycles_per_revolution", 4.0, "1")
    assert abs(t.parameters["amplitude"][0] - 0.05 * math.sin(1.0)) < 1e-6


def test_coulomb_plus_offset_in_one_row() -> None:
    terms = terms_of([("sign", 0), ("gain", enc("gain", 0.6)), ("offset", enc("offset", -0.2))])
    close(one(terms, "coulomb"), "level", 0.6, "N m")
    close(one(terms, "offset"), "level", -0.2, "N m")


def test_steep_tanh_is_coulomb_and_gentle_tanh_is_not() -> None:
    t = one(terms_of([("tanh", enc("tanh", 1000.0)), ("gain", enc("gain", 0.8))]), "coulomb")
    close(t, "level", 0.8, "N m")
    close(t, "transition_velocity", 1e-3, "rad/s")
    u = one(terms_of([("tanh", enc("tanh", 2.0)), ("gain", enc("gain", 0.8))]), "unclassified")
    assert "transition velocity" in u.description
    # The threshold is an option.
    t2 = terms_of([("tanh", enc("tanh", 2.0)), ("gain", enc("gain", 0.8))],
                  classify=ClassifyOptions(coulomb_velocity=1.0))
    close(one(t2, "coulomb"), "transition_velocity", 0.5, "rad/s")


def test_saturation_and_atan_coulomb() -> None:
    t = one(terms_of([("power_gain", enc("power_gain", 500.0)), ("saturation",
                      enc("saturation", 2.0)), ("gain", enc("gain", 0.25))]), "coulomb")
    close(t, "level", 0.5, "N m")
    close(t, "transition_velocity", 2.0 / 500.0, "rad/s")
    t = one(terms_of([("atan", enc("atan", 400.0)), ("gain", enc("gain", 0.5))]), "coulomb")
    close(t, "level", 0.5 * math.pi / 2, "N m")


def test_relay_is_coulomb_with_hysteresis() -> None:
    t = one(terms_of([("gain", enc("gain", 2.0)), ("hysteresis", enc("hysteresis", 0.01)),
                      ("gain", enc("gain", -0.7))]), "coulomb")
    close(t, "level", -0.7, "N m")
    close(t, "hysteresis", 0.005, "rad/s")


def test_filtered_and_delayed_terms_keep_their_filter() -> None:
    c = one(terms_of([("lpf", enc("lpf", 50.0)), ("sign", 0), ("gain", enc("gain", 0.9))]),
            "coulomb")
    close(c, "level", 0.9, "N m")
    close(c, "corner", 50.0, "rad/s")
    v = one(terms_of([("dead_time", enc("dead_time", 0.004)), ("gain", enc("gain", 0.3))]),
            "viscous")
    close(v, "coefficient", 0.3, "N m s/rad")
    close(v, "delay", 0.004, "s")
    f = one(terms_of([("sign", 0), ("lpf", enc("lpf", 20.0)), ("gain", enc("gain", 0.9))]),
            "coulomb")
    close(f, "corner", 20.0, "rad/s")
    assert "filter" in f.description


def test_stribeck_like_hump() -> None:
    # 0.3 sin(2 atan(2 v)): odd, peaks at v = 0.5 rad/s, then falls.
    t = one(terms_of([("atan", enc("atan", 2.0)), ("gain", enc("gain", 2.0)),
                      ("sin_phase", enc("sin_phase", 0.0)), ("gain", enc("gain", 0.3))]),
            "stribeck")
    close(t, "peak", 0.3, "N m")
    assert abs(t.parameters["peak_velocity"][0] - 0.5) < 0.01


def test_dead_zone_fits_coulomb_plus_viscous() -> None:
    terms = terms_of([("dead_zone", enc("dead_zone", 1e-3)), ("gain", enc("gain", 2.0))])
    assert abs(one(terms, "coulomb").parameters["level"][0] + 2e-3) < 1e-9
    assert abs(one(terms, "viscous").parameters["coefficient"][0] - 2.0) < 1e-9


def test_unclassifiable_chain_says_why() -> None:
    t = one(terms_of([("tan_amp", enc("tan_amp", 1.5)), ("log", enc("log", 0.2)),
                      ("acos", 0), ("power", enc("power", 2.0))]), "unclassified")
    assert "velocity" in t.description and t.description


def test_linear_in_angle_is_reported_as_a_stiffness() -> None:
    t = one(terms_of([("gain", enc("gain", 0.4))], inp="theta_uw"), "unclassified")
    close(t, "stiffness", 0.4, "N m/rad")


def test_unknown_input_role_and_its_override() -> None:
    t = one(terms_of([("gain", enc("gain", 0.4))], inp="x"), "unclassified")
    assert "roles=" in t.description
    v = one(terms_of([("gain", enc("gain", 0.4))], inp="x", roles={"x": "velocity"}), "viscous")
    close(v, "coefficient", 0.4, "N m s/rad")


def test_role_defaults_and_validation() -> None:
    roles = input_roles(["theta_w", "theta_uw", "omega", "alpha", "qd_2", "q", "foo"])
    assert roles == {"theta_w": "angle_wrapped", "theta_uw": "angle", "omega": "velocity",
                     "alpha": "acceleration", "qd_2": "velocity", "q": "angle", "foo": None}
    assert input_roles(["omega"], {"omega": None}) == {"omega": None}
    with pytest.raises(ValueError, match="expected one of"):
        input_roles(["omega"], {"omega": "speedy"})
    with pytest.raises(ValueError, match="expected an input.s name"):
        input_roles(["omega"], {"nope": "velocity"})


def test_every_kind_is_known(coulomb_viscous: Compensator) -> None:
    for row in decode(coulomb_viscous).rows:
        assert all(isinstance(t.kind, TermKind) and t.kind in KINDS for t in row.terms)


def test_a_term_kind_is_an_enum_that_reads_as_its_name_in_text_and_json() -> None:
    # A string given is made a TermKind; files and messages keep the plain name.
    term = PhysicalTerm("viscous", {"coefficient": (0.5, "N m s/rad")})
    assert term.kind is TermKind.VISCOUS
    assert json.dumps({term.kind: term.kind}) == '{"viscous": "viscous"}'
    assert f"{term.kind}" == str(term.kind) == "viscous" and term.kind == "viscous"
    with pytest.raises(ValueError, match="'friction' is not a valid TermKind"):
        PhysicalTerm("friction")


# -- rows the genetic algorithm found on the auger plant ----------------------------

RANGES = default_ranges(TS, 20.0)
W_REP = 4 * math.pi  # ClassifyOptions().acceleration_frequency


def ga_row(inp: str, genes: list[tuple[str, float]], **kw) -> RowModel:
    """One decoded row; genes are (element name, parameter value), encoded by the ranges."""
    coded = [(name, RANGES[name].encode(v) if name in RANGES else 0.0) for name, v in genes]
    comp = Compensator(make_matrix(INPUTS, [(inp, coded)]), TS, {}, 20.0)
    return decode(comp, systems=False, **kw).rows[0]


def assert_same_expr(got: sp.Expr, want: sp.Expr, rtol: float = 1e-9) -> None:
    """The same expression tree, numbers equal to ``rtol``."""
    if want.is_Number:
        assert got.is_Number and abs(float(got) - float(want)) <= rtol * max(1.0, abs(
            float(want))), (got, want)
        return
    assert got.func == want.func and len(got.args) == len(want.args), (got, want)
    for a, b in zip(got.args, want.args, strict=True):
        assert_same_expr(a, b, rtol)


def test_ga_sine_through_a_lag_is_spatial() -> None:
    row = ga_row("theta_uw", [("sin_phase", 0.40328794296480153), ("through", 0),
                              ("lag", 121.14323491198216), ("sin_amp", 0.06645347507252275),
                              ("through", 0)])
    q = row.input_symbol
    a = 121.14323491198216
    assert_same_expr(row.expr_numeric, 0.06645347507252275 * sp.sin(
        LTI(sp.sin(q + 0.40328794296480153), (sp.Float(0.1) * s + a) / (s + a))))
    t = one(row.terms, "spatial")
    close(t, "cycles_per_revolution", 1.0, "1")
    close(t, "period", 2 * math.pi, "rad")
    # The lag's DC gain is 1: 0.0665 sin(sin(q + 0.403)), half peak-to-peak 0.0665 sin(1),
    # an odd function of sin(q + 0.403), so its fundamental keeps the phase 0.403.
    assert t.parameters["amplitude"][0] == pytest.approx(0.06645347507252275 * math.sin(1.0),
                                                         rel=1e-5)
    assert t.parameters["phase"][0] == pytest.approx(0.40328794296480153, abs=1e-9)
    assert t.parameters["corner"][0] == pytest.approx(a, rel=1e-9)
    assert "filtered" in t.description


def test_ga_sine_of_a_delayed_sine_is_spatial() -> None:
    row = ga_row("theta_uw", [("sin_amp", -5.0), ("dead_time", 0.003),
                              ("sin_phase", -1.5734016809073534),
                              ("gain", -0.022916475114039159), ("through", 0)])
    q = row.input_symbol
    assert_same_expr(row.expr_numeric, -0.022916475114039159 * sp.sin(
        Delay(-5.0 * sp.sin(q), 0.003) - 1.5734016809073534))
    t = one(row.terms, "spatial")
    close(t, "cycles_per_revolution", 1.0, "1")
    close(t, "delay", 0.003, "s")
    # -5 sin q - 1.573 sweeps past both +-pi/2: the outer sine reaches +-1.
    assert t.parameters["amplitude"][0] == pytest.approx(0.022916475114039159, rel=1e-4)
    # cos(5 sin q) = J0(5) + 2 J2(5) cos 2q + 2 J4(5) cos 4q + ...: J4(5) = 0.391 dominates.
    close(t, "dominant_cycles", 4.0, "1")
    assert t.parameters["dominant_amplitude"][0] == pytest.approx(
        0.022916475114039159 * 2 * 0.3912323604, rel=1e-3)
    assert "delayed" in t.description


@pytest.mark.parametrize("a_range", [1000.0, 100.0])
def test_ga_delayed_power_of_high_passed_acceleration(a_range: float) -> None:
    c, a, p = -8.4115104597159984e-5, 2.02949733251458, 0.93724133457915504
    row = ga_row("alpha", [("hpf", a), ("power", p), ("gain", c), ("dead_time", 0.005),
                           ("through", 0)],
                 classify=ClassifyOptions(acceleration_range=a_range))
    x = row.input_symbol
    assert_same_expr(row.expr_numeric, Delay(c * SymPow(LTI(x, s / (s + a)), p), 0.005))
    t = one(row.terms, "acceleration")
    # The high pass at 4 pi rad/s: |G| = w / sqrt(w^2 + a^2). The least-squares line
    # through c sgn(x) |G x|^p over [-A, A] has the slope c |G|^p 3 A^(p-1) / (p + 2).
    g = W_REP / math.hypot(W_REP, a)
    expected = c * g ** p * 3 * a_range ** (p - 1) / (p + 2)
    assert t.parameters["inertia"][0] == pytest.approx(expected, rel=0.01)
    assert t.parameters["inertia"][1] == "kg m^2"
    assert t.parameters["linearity_r2"][0] > 0.99
    close(t, "delay", 0.005, "s")
    assert t.parameters["corner"][0] == pytest.approx(a)
    assert t.parameters["band_low"][0] == pytest.approx(a, rel=0.05)
    assert "band_high" not in t.parameters
    assert t.description.startswith("acceleration-dependent term")


def test_ga_band_passed_acceleration() -> None:
    # alpha -> high pass -> notch -> gain: s^3 and s in the numerator, a cubic below.
    g, a1, a2 = 0.00035592640513115725, 601.0146164046411, 433.47251062996236
    row = ga_row("alpha", [("hpf", a1), ("notch", a2), ("gain", g), ("through", 0),
                           ("through", 0)])
    num = g * s ** 3 + 66.878008260586455 * s
    den = s ** 3 + 1034.4871270346034 * s ** 2 + 448421.73217006639 * s + 112929695.29987873
    assert_same_expr(row.expr_numeric, LTI(row.input_symbol, num / den), rtol=1e-7)
    t = one(row.terms, "acceleration")
    jw = 1j * W_REP
    G = g * jw / (jw + a1) * (jw ** 2 + a2 ** 2) / (jw ** 2 + a2 * jw + a2 ** 2)  # noqa: N806
    assert G.real > 0
    assert t.parameters["inertia"][0] == pytest.approx(abs(G), rel=1e-6)
    assert t.parameters["filter_phase"][0] == pytest.approx(np.angle(G), rel=1e-6)
    close(t, "frequency", W_REP, "rad/s")
    # Its pass band lies above the hpf and the notch; there the inertia is the gain.
    assert 601 < t.parameters["band_low"][0] < 2000
    assert t.parameters["inertia_in_band"][0] == pytest.approx(g, rel=0.01)
    assert "derivative" in t.description  # 87 deg of phase at 4 pi rad/s


def test_sign_of_high_passed_acceleration_is_nonlinear_acceleration() -> None:
    # 0.2 sgn(hpf(alpha)): the line through 0.2 sgn(x) over [-A, A] has the slope
    # 0.2 * 3 / (2 A) and R^2 = 3/4.
    t = one(terms_of([("hpf", enc("hpf", 1.0)), ("sign", 0), ("gain", enc("gain", 0.2))],
                     inp="alpha"), "acceleration")
    assert t.parameters["inertia"][0] == pytest.approx(0.2 * 1.5 / 1000.0, rel=0.01)
    assert t.parameters["linearity_r2"][0] == pytest.approx(0.75, abs=0.01)
    close(t, "peak", 0.2, "N m")
    assert t.description.startswith("nonlinear acceleration-dependent term")


def test_velocity_nonlinearity_then_derivative_is_acceleration() -> None:
    # 0.3 d/dt tanh(0.01 omega) = 0.3 * 0.01 (1 - tanh^2) alpha: at 100 rad/s^2 and
    # 4 pi rad/s the velocity swings +-8 rad/s, where tanh(0.08) is still nearly linear.
    genes = [("tanh", enc("tanh", 0.01)), ("derivative", enc("derivative", 0.3))]
    t = one(terms_of(genes, classify=ClassifyOptions(acceleration_range=100.0)),
            "acceleration")
    assert t.parameters["inertia"][0] == pytest.approx(0.3 * 0.01, rel=0.01)
    assert "corner" not in t.parameters
    # Over +-1000 rad/s^2 the velocity reaches +-80 rad/s and tanh bends: a smaller slope.
    t = one(terms_of(genes), "acceleration")
    assert 0.5 * 0.3 * 0.01 < t.parameters["inertia"][0] < 0.95 * 0.3 * 0.01


def test_wrapped_angle_rows_are_spatial_unless_they_follow_the_wrap() -> None:
    # 0.05 tanh(2 theta_w): one revolution rises from 0 to 0.05, then jumps back. The jump
    # (0.05) is twice the amplitude: the term follows the wrap, it is no position friction.
    row = ga_row("theta_w", [("gain", 1.0), ("tanh", 2.0), ("gain", 0.05)])
    t = one(row.terms, "unclassified")
    assert t.parameters["wrap_jump"][0] == pytest.approx(-0.05, rel=1e-6)
    assert t.parameters["amplitude"][0] == pytest.approx(0.025, rel=1e-6)
    assert "wrap" in t.description
    # Linear in the wrapped angle: a sawtooth of the wrap (jump 2 pi c, amplitude pi c).
    t = one(terms_of([("gain", enc("gain", 0.4))], inp="theta_w"), "unclassified")
    assert abs(t.parameters["wrap_jump"][0]) == pytest.approx(0.8 * math.pi, rel=1e-6)
    # A ripple of the wrapped angle that jumps less than its amplitude stays spatial.
    t = one(terms_of([("gain", enc("gain", 1.3)), ("sin_phase", enc("sin_phase", 0.0)),
                      ("gain", enc("gain", 0.1))], inp="theta_w"), "spatial")
    assert "jumps at each wrap" in t.description
    # A saw with four teeth per revolution: four cycles.
    t = one(terms_of([("gain", enc("gain", 4.0)), ("sin_phase", enc("sin_phase", 0.0)),
                      ("asin", 0), ("gain", enc("gain", 0.1))], inp="theta_w"), "spatial")
    close(t, "cycles_per_revolution", 4.0, "1")
    assert t.parameters["amplitude"][0] == pytest.approx(0.1 * math.pi / 2, rel=1e-5)


def test_periodicity_of_the_unwrapped_angle_needs_whole_harmonics() -> None:
    genes = [("gain", enc("gain", 2.003)), ("sin_phase", enc("sin_phase", 0.2)),
             ("lag", enc("lag", 30.0)), ("sin_amp", enc("sin_amp", 0.1))]
    close(one(terms_of(genes, inp="theta_uw"), "spatial"), "cycles_per_revolution", 2.0, "1")
    t = one(terms_of(genes, inp="theta_uw", classify=ClassifyOptions(harmonic_tolerance=1e-4)),
            "unclassified")
    assert "angle input" in t.description
    # Not periodic at all: a function of the angle itself.
    one(terms_of([("tanh", enc("tanh", 2.0)), ("lag", enc("lag", 30.0)),
                  ("sin_amp", enc("sin_amp", 0.1))], inp="theta_uw"), "unclassified")


def test_classify_options_are_validated() -> None:
    for name in ("acceleration_frequency", "acceleration_range", "harmonic_tolerance"):
        with pytest.raises(ValueError, match=name):
            ClassifyOptions(**{name: 0.0})
    with pytest.raises(ValueError, match="below 0.5"):
        ClassifyOptions(harmonic_tolerance=0.5)


# -- contributions ---------------------------------------------------------------


def test_contributions_add_rows_one_by_one(coulomb_viscous: Compensator) -> None:
    omega = 5 * smooth_signal(4000)
    data = {"theta_w": np.mod(omega, 2 * np.pi), "omega": omega}
    sim = simulate(coulomb_viscous, data)
    target = sim.total + 0.01 * np.sin(np.arange(omega.size))
    c = contributions(coulomb_viscous, data, target)
    np.testing.assert_allclose(c.rms, np.sqrt(np.mean(sim.rows ** 2, axis=1)), rtol=1e-12)
    assert c.rmse_none == pytest.approx(np.sqrt(np.mean(target ** 2)))
    assert c.rmse_cumulative[-1] == pytest.approx(0.01 / np.sqrt(2), rel=1e-2)
    assert c.rmse_cumulative[0] == pytest.approx(
        np.sqrt(np.mean((target - sim.rows[0]) ** 2)))
    assert all(d > 0 for d in c.improvement)
    # A decoded model and a column name work too.
    data["tau"] = target
    assert contributions(decode(coulomb_viscous, systems=False), data, "tau") == c
    assert "rmse" in c.table()
    with pytest.raises(ValueError, match="samples"):
        contributions(coulomb_viscous, data, target[:10])


# -- velocity terms measured on their static characteristic (eq. 14's shape) --------
def test_relay_of_a_log_of_velocity_is_coulomb() -> None:
    """What the GA found on the auger axis: omega -> log -> hysteresis -> gain -> lpf."""
    genes = [("log", enc("log", 0.01)), ("hysteresis", enc("hysteresis", 0.05)),
             ("gain", enc("gain", 0.96)), ("lpf", enc("lpf", 150.0))]
    t = one(terms_of(genes), "coulomb")
    level, unit = t.parameters["level"]
    assert unit == "N m" and abs(level - 0.96) < 0.01 * 0.96


def test_dead_zone_gain_of_velocity_is_viscous() -> None:
    """omega -> dead zone (0.2 rad/s) -> gain: viscous friction with a dead band."""
    genes = [("dead_zone", enc("dead_zone", 0.2)), ("power_gain", enc("power_gain", 0.004))]
    terms = terms_of(genes)
    coef, unit = one(terms, "viscous").parameters["coefficient"]
    # least squares of 0.004 * dz(v, 0.2) by c sgn(v) + b v over +-10 rad/s: b close to 0.004
    assert unit == "N m s/rad" and abs(coef - 0.004) < 0.05 * 0.004
    assert not [t for t in terms if t.kind in ("coulomb", "unclassified")]
