"""The simulated servo axis with DOB, velocity loop and RTOB (the data source)."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from edm_sym.plant import PRESETS, PlantLog, simulate_axis, simulate_plant

STATS = Path(__file__).with_name("data") / "plant_stats.json"
#: Velocity-tracking error RMS per preset and excitation [rad/s] (documented in docs/plant.md).
TRACKING_BOUND = 1.0


def frictionless(name: str = "auger"):
    """The preset with no friction and exact nominal values (J_n = J, K_tn = K_t)."""
    p = PRESETS[name]
    return replace(p, name="frictionless", coulomb=0.0, stiction=0.0, viscous=0.0, ripple=(),
                   inertia_nominal=p.inertia, torque_constant_nominal=p.torque_constant)


def ramp_to(speed: float, t_ramp: float = 0.5):
    return lambda t: speed * np.clip(t / t_ramp, 0.0, 1.0)


def test_no_friction_and_exact_inertia_gives_zero_within_noise() -> None:
    p = frictionless()
    log = simulate_axis(p, ramp_to(10.0), duration=3.0)
    tau = log.tau_ext[log.t > 1.0]
    # The observer sees only the current-sensor noise (K_t * i_noise), low-pass filtered.
    noise = p.torque_constant * p.current_noise
    assert abs(tau.mean()) < 0.2 * noise
    assert np.sqrt(np.mean(tau**2)) < noise
    quiet = simulate_axis(replace(p, current_noise=0.0), ramp_to(10.0), duration=3.0)
    assert np.max(np.abs(quiet.tau_ext[quiet.t > 1.0])) < 1e-3  # only encoder quantisation left


@pytest.mark.parametrize("speed", [-20.0, 5.0, 30.0])
def test_pure_coulomb_at_constant_speed(speed: float) -> None:
    p = replace(frictionless(), coulomb=1.0, stiction=1.0, current_noise=0.0)
    log = simulate_axis(p, ramp_to(speed), duration=3.0)
    level = log.tau_ext[log.t > 1.5].mean()
    assert level == pytest.approx(np.sign(speed) * 1.0, rel=0.01)


def test_rtob_low_pass_step_response() -> None:
    """A step of external torque appears through Q(s) = g/(s + g): 1 - exp(-g t)."""
    p = replace(frictionless(), current_noise=0.0)
    step, t0 = 0.5, 1.0
    log = simulate_axis(p, ramp_to(5.0), duration=2.0,
                        tau_env=lambda t: np.where(t >= t0, step, 0.0))
    k = log.t >= t0
    after = log.t[k] - t0
    want = step * (1.0 - np.exp(-p.g_rtob * after))
    err = np.abs(log.tau_ext[k] - want)
    # one sample of timing slack (the observer is discrete), then a close match
    assert np.max(err[after > 2e-3]) < 0.03 * step
    assert log.tau_ext[k][-1] == pytest.approx(step, rel=1e-3)


def test_log_does_not_depend_on_the_integration_step() -> None:
    a = simulate_plant("auger", "abstraction")
    b = simulate_plant("auger", "abstraction", substeps=2 * a.substeps)
    for name, col in a.columns.items():
        diff = np.sqrt(np.mean((col - b.columns[name]) ** 2))
        assert diff < 0.01 * np.sqrt(np.mean(col**2)), name


@pytest.mark.parametrize("preset", sorted(PRESETS))
@pytest.mark.parametrize("excitation", ["abstraction", "evaluation"])
def test_log_is_consistent(preset: str, excitation: str) -> None:
    log = simulate_plant(preset, excitation)
    assert list(log.columns) == ["t", "theta_w", "theta_uw", "omega", "alpha", "tau_ext"]
    ts = log.ts
    assert log.tracking_error_rms() < TRACKING_BOUND
    # theta_w is theta_uw wrapped into [0, 2 pi) (to the encoder's resolution)
    assert np.all((log.theta_w >= 0) & (log.theta_w < 2 * np.pi))
    wrapped = np.mod(log.theta_uw, 2 * np.pi)
    gap = np.abs(np.angle(np.exp(1j * (log.theta_w - wrapped))))
    assert np.max(gap) < 2 * (2 * np.pi / PRESETS[preset].encoder_counts) + 1e-12
    # omega and alpha are the derivatives of the angle (what integrates back to it)
    span = np.ptp(log.theta_uw)
    assert np.max(np.abs(np.cumsum(log.omega) * ts - (log.theta_uw - log.theta_uw[0]))) < 0.01 * span
    vspan = np.ptp(log.omega)
    assert np.max(np.abs(np.cumsum(log.alpha) * ts - (log.omega - log.omega[0]))) < 0.02 * vspan


def test_excitations_follow_the_paper() -> None:
    ab = simulate_plant("auger", "abstraction")
    t, cmd = ab.t, ab.omega_cmd
    chirp = t >= 10.0
    np.testing.assert_allclose(cmd[chirp], 20 * np.pi * np.sin(2 * np.pi * 0.5 * (t[chirp] - 10) ** 2),
                               atol=1e-9)
    steps = cmd[~chirp]
    assert steps.max() > 0 and steps.min() < 0  # both directions
    ev = simulate_plant("auger", "evaluation")
    np.testing.assert_allclose(ev.omega_cmd, 20 * np.pi * np.sin(2 * np.pi * 0.1 * ev.t**2),
                               atol=1e-9)


def test_seed_gives_the_same_log_and_another_seed_other_noise() -> None:
    a = simulate_plant("ballscrew", "evaluation", seed=3)
    b = simulate_plant("ballscrew", "evaluation", seed=3)
    c = simulate_plant("ballscrew", "evaluation", seed=4)
    for name in a.columns:
        np.testing.assert_array_equal(a.columns[name], b.columns[name])
    assert not np.array_equal(a.tau_ext, c.tau_ext)


def test_unknown_preset_is_refused() -> None:
    with pytest.raises(ValueError, match="preset"):
        simulate_plant("nope", "abstraction")
    with pytest.raises(ValueError, match="excitation"):
        simulate_plant("auger", "nope")


def statistics(log: PlantLog) -> dict:
    return {name: {"mean": float(c.mean()), "rms": float(np.sqrt(np.mean(c**2))),
                   "min": float(c.min()), "max": float(c.max())}
            for name, c in log.columns.items()}


@pytest.mark.parametrize("preset", sorted(PRESETS))
@pytest.mark.parametrize("excitation", ["abstraction", "evaluation"])
def test_preset_statistics_are_pinned(preset: str, excitation: str) -> None:
    """Regression: update only with ``python tests/update_plant_stats.py`` (and review)."""
    pinned = json.loads(STATS.read_text())[f"{preset}/{excitation}"]
    got = statistics(simulate_plant(preset, excitation))
    for name, stats in pinned.items():
        for key, value in stats.items():
            assert got[name][key] == pytest.approx(value, rel=1e-6, abs=1e-9), (name, key)
