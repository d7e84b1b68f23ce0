"""The velocity terms of several rows judged as one friction curve (edm_sym.engines.symbolic.joint)."""

from __future__ import annotations

import math

import pytest
import sympy as sp

from edm_sym.engines.symbolic.classify import ClassifyOptions, classify_expression
from edm_sym.engines.symbolic.joint import joint_velocity_terms, velocity_part
from edm_sym.engines.symbolic.operators import LTI, Relay, s

W = sp.Symbol("omega", real=True)
Q = sp.Symbol("theta_uw", real=True)
DATA = ClassifyOptions(velocity_range=60.0)  # the velocities a servo log reaches


def _parts(*rows: tuple[sp.Expr, sp.Symbol, str]):  # noqa: ANN202
    out = []
    for expr, u, role in rows:
        for t in classify_expression(expr, u, role, options=DATA):
            p = velocity_part(t, u, role)
            assert p is not None, t
            out.append(p)
    return out


def _kinds(terms) -> dict:  # noqa: ANN001
    return {t.kind: t.parameters for t in terms}


def test_a_cancelling_pair_is_judged_by_its_sum() -> None:
    # 4 sgn(v) + 0.01 v in one row, -3.6 tanh(20 v) in another: 0.4 N m Coulomb at speed.
    terms = joint_velocity_terms(_parts((4.0 * sp.sign(W) + 0.01 * W, W, "velocity"),
                                        (-3.6 * sp.tanh(20 * W), W, "velocity")), DATA)
    k = _kinds(terms)
    assert sorted(k) == ["coulomb", "viscous"]
    assert k["coulomb"]["level"][0] == pytest.approx(0.4, rel=1e-3)
    assert k["viscous"]["coefficient"][0] == pytest.approx(0.01, rel=1e-3)


def test_a_gentle_saturation_is_coulomb_over_the_data_range() -> None:
    # Over +-10 rad/s 0.2 tanh(0.147 v) looks like a slope; up to 60 rad/s it is a level.
    terms = joint_velocity_terms(_parts((0.1 * sp.sign(W), W, "velocity"),
                                        (0.4 * sp.tanh(0.147 * W), W, "velocity")), DATA)
    k = _kinds(terms)
    assert "stribeck" not in k
    assert k["coulomb"]["level"][0] == pytest.approx(0.5, rel=0.05)
    # Half the level where 0.1 + 0.4 tanh(0.147 v) reaches it (2.7 rad/s for 0.5 N m).
    half = 0.5 * k["coulomb"]["level"][0]
    assert k["coulomb"]["transition_velocity"][0] == pytest.approx(
        math.atanh((half - 0.1) / 0.4) / 0.147, abs=0.05)
    # A step that reaches half its level at once has no transition velocity.
    sharp = _kinds(joint_velocity_terms(_parts((0.3 * sp.sign(W), W, "velocity"),
                                               (0.2 * sp.tanh(0.147 * W), W, "velocity")), DATA))
    assert "transition_velocity" not in sharp["coulomb"]
    assert abs(k.get("viscous", {"coefficient": (0.0,)})["coefficient"][0]) * 60 < 0.05


def test_a_relay_holding_the_breakaway_level_is_stribeck() -> None:
    # 0.6 sgn(v) and a relay of -0.2 switching at +-3 rad/s: 0.8 N m after each reversal
    # until 3 rad/s, 0.4 N m beyond. The angle's derivative counts as the velocity.
    hp = LTI(Q, s / (s + 1000))  # theta' / 1000
    terms = joint_velocity_terms(_parts((0.6 * sp.sign(W), W, "velocity"),
                                        (-0.2 * Relay(hp, 0.003), Q, "angle"),
                                        (0.01 * W, W, "velocity")), DATA)
    k = _kinds(terms)
    assert sorted(k) == ["coulomb", "stribeck", "viscous"]
    assert k["coulomb"]["level"][0] == pytest.approx(0.4, rel=0.03)
    assert k["viscous"]["coefficient"][0] == pytest.approx(0.01, rel=0.05)
    assert 0.2 < k["stribeck"]["peak"][0] < 0.6
    assert 1.0 < k["stribeck"]["stribeck_velocity"][0] < 4.0


def test_what_is_not_a_friction_curve_keeps_its_names() -> None:
    # An even function of velocity (a parabola) is no Coulomb + viscous + Stribeck curve.
    terms = classify_expression(0.01 * W**2, W, "velocity", options=DATA)
    parts = [p for t in terms if (p := velocity_part(t, W, "velocity")) is not None]
    parts += _parts((0.3 * sp.sign(W), W, "velocity"))
    assert joint_velocity_terms(parts, DATA) is None
    # A term of the wrapped angle or of the acceleration is not a velocity part.
    (t,) = classify_expression(0.1 * sp.sin(3 * Q), Q, "angle_wrapped")
    assert velocity_part(t, Q, "angle_wrapped") is None


def test_a_sawtooth_of_the_wrap_is_not_spatial() -> None:
    qw = sp.Symbol("theta_w", real=True)
    (t,) = classify_expression(0.05 * sp.Max(3.9, qw), qw, "angle_wrapped")
    assert t.kind == "unclassified"
    assert abs(t.parameters["wrap_jump"][0]) == pytest.approx(0.05 * (2 * math.pi - 3.9), rel=1e-3)
    assert "wrap" in t.description
    # A ripple that jumps a little at the wrap (not a whole number of cycles) stays spatial.
    (r,) = classify_expression(0.05 * sp.sin(sp.Max(0.7, qw) + 0.35), qw, "angle_wrapped")
    assert r.kind == "spatial"
