"""Physical classification of rows, input roles and row contributions."""

from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import TS, smooth_signal

from edm_sym.elements import element
from edm_sym.matrix import Compensator, make_matrix
from edm_sym.simulate import simulate
from edm_sym.symbolic import (
    ClassifyOptions,
    PhysicalTerm,
    contributions,
    decode,
    input_roles,
)
from edm_sym.symbolic.classify import KINDS

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
    with pytest.raises(ValueError, match="not an input"):
        input_roles(["omega"], {"nope": "velocity"})


def test_every_kind_is_known(coulomb_viscous: Compensator) -> None:
    for row in decode(coulomb_viscous).rows:
        assert all(t.kind in KINDS for t in row.terms)


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
