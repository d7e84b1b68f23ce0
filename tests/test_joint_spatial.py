"""The angle terms of several rows judged as one ripple (edm_sym.engines.symbolic.joint_spatial)."""

from __future__ import annotations

import pytest
import sympy as sp

from edm_sym.engines.symbolic.classify import ClassifyOptions, classify_expression
from edm_sym.engines.symbolic.joint_spatial import joint_spatial_term, overlapping, spatial_part

QW = sp.Symbol("theta_w", real=True)
QU = sp.Symbol("theta_uw", real=True)
OPTIONS = ClassifyOptions.for_axis("rotary")


def _parts(*rows: tuple[sp.Expr, sp.Symbol, str]):  # noqa: ANN202
    out = []
    for expr, u, role in rows:
        for t in classify_expression(expr, u, role, options=OPTIONS):
            p = spatial_part(t, u, role)
            assert p is not None, t
            out.append(p)
    return out


def test_a_ripple_written_as_a_difference_is_named_by_its_sum() -> None:
    # sin(2.5 sin q) has harmonics 1, 3, 5 ...; minus its fundamental on the wrapped
    # angle, what is left is a 3-cycle ripple. One by one: two 1-cycle ripples.
    a1 = 2 * sp.besselj(1, 2.5).evalf()
    parts = _parts((0.1 * sp.sin(2.5 * sp.sin(QU)), QU, "angle"),
                   (-0.1 * a1 * sp.sin(QW), QW, "angle_wrapped"))
    assert [p.term.parameters["cycles_per_revolution"][0] for p in parts] == [1.0, 1.0]
    assert overlapping(parts)
    t = joint_spatial_term(parts, OPTIONS, "rows 3, 5")
    assert t.kind == "spatial"
    assert t.parameters["dominant_cycles"][0] == 3.0
    a3 = 2 * 0.1 * abs(float(sp.besselj(3, 2.5).evalf()))
    assert t.parameters["dominant_amplitude"][0] == pytest.approx(a3, rel=1e-3)
    assert t.parameters["fundamental_amplitude"][0] < 1e-6
    assert "rows 3, 5" in t.description


def test_wrap_jumps_that_cancel_make_a_ripple() -> None:
    # Each row a sawtooth of the wrap (unclassified alone); together 0.05 sin(3 q).
    parts = _parts((0.05 * sp.Max(QW, 1.0) + 0.05 * sp.sin(3 * QW), QW, "angle_wrapped"),
                   (-0.05 * sp.Max(QW, 1.0), QW, "angle_wrapped"))
    assert "unclassified" in {p.term.kind for p in parts}
    assert overlapping(parts)
    t = joint_spatial_term(parts, OPTIONS)
    assert t.parameters["cycles_per_revolution"][0] == 3.0
    assert t.parameters["amplitude"][0] == pytest.approx(0.05, rel=1e-3)
    assert t.parameters["mean"][0] == pytest.approx(0.0, abs=1e-9)
    # Without the row that cancels its jump, the sum jumps at the wrap: no ripple.
    alone = [p for p in parts if p.term.kind == "unclassified"][:1] + [
        p for p in parts if p.term.kind == "spatial"]
    assert joint_spatial_term(alone, OPTIONS) is None


def test_separate_harmonics_keep_their_names() -> None:
    # A 3-cycle and a 5-cycle ripple on two rows share no harmonic: nothing to join.
    parts = _parts((0.1 * sp.sin(3 * QW), QW, "angle_wrapped"),
                   (0.05 * sp.sin(5 * QU + 0.3), QU, "angle"))
    assert not overlapping(parts)


def test_what_is_not_a_ripple_of_the_revolution_is_no_part() -> None:
    # 2.13 cycles per revolution of the unwrapped angle does not repeat every revolution.
    (t,) = classify_expression(0.1 * sp.sin(2.13 * QU), QU, "angle")
    assert spatial_part(t, QU, "angle") is None
    # A velocity term is no part either.
    w = sp.Symbol("omega", real=True)
    (v,) = classify_expression(0.3 * sp.sign(w), w, "velocity")
    assert spatial_part(v, w, "velocity") is None
