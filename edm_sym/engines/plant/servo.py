"""Servo axis with DOB-based acceleration control and a reaction torque observer.

Block diagram (paper Fig. 9), per sample k at t_k = k ts:

1. The encoder counts the true angle: ``theta_m[k] = floor(theta / q) q``.
2. ``omega_d[k] = (theta_m[k] - theta_m[k-1]) / ts`` (backward difference).
3. Torque balance ``u[k] = K_tn (I_ref[k-1] + I_ref[k-2]) / 2 - J_n (omega_d[k] -
   omega_d[k-1]) / ts``: everything that is not ``J_n alpha``.
4. DOB ``tau_dis_hat = LPF_g_dob(u)`` and RTOB ``tau_ext_hat = Q(u)``, Q = LPF_g_rtob.
5. Velocity loop: ``alpha_ref = (omega_cmd[k+1] - omega_cmd[k]) / ts + K_v e + K_i sum(e ts)``
   with ``e = (omega_cmd[k-1] + omega_cmd[k]) / 2 - omega_d[k]`` (the reference is
   averaged over the same interval as the encoder difference).
6. ``I_ref[k] = (J_n alpha_ref + tau_dis_hat) / K_tn``; the current loop is ideal
   but regulates the *measured* current, so the motor carries ``I_ref - n`` with
   n the current-sensor noise.
7. The continuous plant ``J domega/dt = K_t I - tau_fric - tau_env`` runs over
   [t_k, t_{k+1}) in ``substeps`` implicit trapezoidal steps, with the LuGre
   bristles relaxed exactly along the travel (see :mod:`edm_sym.engines.plant.friction`).

The log holds what the drive measures: the encoder angle, the low-passed
differences for omega and alpha, and the RTOB output; the ground truth is kept
beside it.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, replace
from types import MappingProxyType

import numpy as np

from edm_sym.core.errors import ConfigError
from edm_sym.core.fitness import rms
from edm_sym.engines.plant import filters
from edm_sym.engines.plant.excitation import get_excitation
from edm_sym.engines.plant.friction import (
    FRICTION_COMPONENTS,
    friction_components,
    solve_substep,
)
from edm_sym.engines.plant.presets import PlantPreset, get_preset

__all__ = [
    "COLUMNS",
    "MAX_SUBSTEP",
    "TRUTH_KEYS",
    "PlantLog",
    "default_substeps",
    "simulate_axis",
    "simulate_plant",
]

#: Log columns, in order (docs/cli.md#plant-log-columns).
COLUMNS: tuple[str, ...] = ("t", "theta_w", "theta_uw", "omega", "alpha", "tau_ext")
#: Keys of :attr:`PlantLog.truth`.
TRUTH_KEYS: tuple[str, ...] = (
    *FRICTION_COMPONENTS,
    "friction",
    "environment",
    "inertia_mismatch",
    "torque_constant_mismatch",
    "current_noise",
    "total",
)
#: Longest internal integration step used when ``substeps`` is not given [s].
MAX_SUBSTEP = 1.0e-4

_TWO_PI = 2.0 * math.pi


def _readonly(x: np.ndarray) -> np.ndarray:
    x = np.ascontiguousarray(x, dtype=float)
    x.setflags(write=False)
    return x


@dataclass(frozen=True, eq=False)
class PlantLog:
    """A free-motion log of the servo axis, with its ground truth.

    Parameters
    ----------
    preset : PlantPreset
        The plant that made the log.
    excitation : str
        Name of the velocity command (``"custom"`` for :func:`simulate_axis`).
    ts : float
        Sample time [s].
    seed : int
        Seed of the current-sensor noise.
    substeps : int
        Integration steps per sample.
    t, theta_w, theta_uw, omega, alpha, tau_ext : numpy.ndarray
        The logged columns (see :attr:`columns`).
    omega_cmd : numpy.ndarray
        Velocity command at each sample [rad/s].
    truth : mapping of str to numpy.ndarray
        Ground truth per sample [N m], keys :data:`TRUTH_KEYS`: the friction
        components (coulomb, stribeck, bristle, viscous, ripple) and their sum
        ``friction``; ``environment`` (external torque); ``inertia_mismatch``
        ``(J - J_n) alpha``; ``torque_constant_mismatch``
        ``(K_tn/K_t - 1)(J alpha + friction + environment)``; ``current_noise``
        ``K_tn n``; ``total`` = their sum = ``K_tn I_ref - J_n alpha``, the
        torque the RTOB estimates before its low-pass. Values are instantaneous
        at t_k, with alpha the true acceleration just after the current of
        sample k is applied.
    state : mapping of str to numpy.ndarray
        True states and drive signals per sample: ``theta`` [rad], ``omega``
        [rad/s], ``alpha`` [rad/s^2], ``z`` [rad] (bristle deflection),
        ``i_ref`` [A], ``tau_dob`` [N m] (DOB estimate), ``balance`` [N m]
        (torque balance fed to the DOB and the RTOB).
    """

    preset: PlantPreset
    excitation: str
    ts: float
    seed: int
    substeps: int
    t: np.ndarray
    theta_w: np.ndarray
    theta_uw: np.ndarray
    omega: np.ndarray
    alpha: np.ndarray
    tau_ext: np.ndarray
    omega_cmd: np.ndarray
    truth: Mapping[str, np.ndarray] = field(default_factory=dict)
    state: Mapping[str, np.ndarray] = field(default_factory=dict)

    @property
    def columns(self) -> dict[str, np.ndarray]:
        """dict of str to numpy.ndarray: the log columns, in the order of :data:`COLUMNS`."""
        return {name: getattr(self, name) for name in COLUMNS}

    def statistics(self) -> dict[str, dict[str, float]]:
        """Mean, RMS, minimum and maximum of every log column.

        Returns
        -------
        dict
            ``{column: {"mean": ..., "rms": ..., "min": ..., "max": ...}}`` in
            the order of :data:`COLUMNS`.
        """
        return {
            name: {
                "mean": float(np.mean(x)),
                "rms": rms(x),
                "min": float(np.min(x)),
                "max": float(np.max(x)),
            }
            for name, x in self.columns.items()
        }

    def tracking_error_rms(self) -> float:
        """RMS of ``omega_cmd - omega`` over the log (logged, i.e. measured, omega).

        Returns
        -------
        float
            [rad/s]
        """
        return rms(self.omega_cmd - self.omega)


def default_substeps(ts: float) -> int:
    """Integration steps per sample used when none is given.

    Parameters
    ----------
    ts : float
        Sample time [s].

    Returns
    -------
    int
        ``ceil(ts / MAX_SUBSTEP)``, at least 1.
    """
    return max(1, math.ceil(ts / MAX_SUBSTEP - 1e-9))


def simulate_plant(
    preset: str | PlantPreset,
    excitation: str,
    *,
    ts: float = 1e-3,
    duration: float = 20.0,
    seed: int = 0,
    substeps: int | None = None,
) -> PlantLog:
    """Simulate a preset servo axis in free motion under a named excitation.

    Parameters
    ----------
    preset : str or PlantPreset
        A key of :data:`edm_sym.engines.plant.PRESETS`, or a custom preset.
    excitation : {"abstraction", "evaluation"}
        The velocity command (paper section IV-A, eqs. 9 and 17).
    ts : float, optional
        Sample time of the drive and of the log [s].
    duration : float, optional
        Length of the log [s]; ``round(duration / ts)`` samples from t = 0.
    seed : int, optional
        Seed of the current-sensor noise; equal seeds give equal logs.
    substeps : int, optional
        Integration steps per sample; default :func:`default_substeps`.

    Returns
    -------
    PlantLog

    Raises
    ------
    ConfigError
        (a ``ValueError``) for an unknown preset or excitation, or a bad option.
    """
    plant = get_preset(preset)
    command = get_excitation(excitation, plant.staircase)
    log = simulate_axis(plant, command, ts=ts, duration=duration, seed=seed, substeps=substeps)
    return replace(log, excitation=excitation)


def _check_options(ts: float, duration: float, seed: int, substeps: int | None) -> int:
    if not (isinstance(ts, int | float) and math.isfinite(ts) and ts > 0.0):
        raise ConfigError("ts", f"expected a sample time > 0 [s], found {ts!r}")
    if not (isinstance(duration, int | float) and math.isfinite(duration) and duration >= ts):
        raise ConfigError("duration", f"expected a duration >= ts = {ts} [s], found {duration!r}")
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer) or seed < 0:
        raise ConfigError("seed", f"expected an integer >= 0, found {seed!r}")
    if substeps is None:
        return default_substeps(ts)
    if isinstance(substeps, bool) or not isinstance(substeps, int | np.integer) or substeps < 1:
        raise ConfigError("substeps", f"expected an integer >= 1, found {substeps!r}")
    return int(substeps)


def simulate_axis(
    preset: str | PlantPreset,
    command: Callable[[np.ndarray], np.ndarray],
    *,
    ts: float = 1e-3,
    duration: float = 20.0,
    seed: int = 0,
    substeps: int | None = None,
    tau_env: Callable[[np.ndarray], np.ndarray] | None = None,
) -> PlantLog:
    """Simulate the servo axis under any velocity command and external torque.

    Parameters
    ----------
    preset : str or PlantPreset
        The plant.
    command : callable
        Vectorised ``t -> omega_cmd`` [rad/s]; evaluated from t = -ts (the axis
        is at rest before t = 0) to t = duration.
    ts, duration, seed, substeps
        As in :func:`simulate_plant`.
    tau_env : callable, optional
        Vectorised ``t -> external torque`` [N m] opposing the motor like
        friction (so the RTOB sees it with a plus sign); evaluated at the
        midpoint of every integration step and at the samples.

    Returns
    -------
    PlantLog
        With ``excitation="custom"``.
    """
    p = get_preset(preset)
    steps = _check_options(ts, duration, seed, substeps)
    ts = float(ts)
    n = int(round(duration / ts))
    h = ts / steps
    t = np.arange(n) * ts
    cmd = np.asarray(command(np.arange(-1, n + 1) * ts), dtype=float)
    if cmd.shape != (n + 2,) or not np.all(np.isfinite(cmd)):
        raise ConfigError("command", f"expected {n + 2} finite speeds, found shape {cmd.shape}")
    if tau_env is None:
        env_mid = None
        env_samples = np.zeros(n)
    else:
        mids = (np.arange(n * steps) + 0.5) * h
        env_mid = np.asarray(tau_env(mids), dtype=float).tolist()
        env_samples = np.asarray(tau_env(t), dtype=float)
    noise = p.current_noise * np.random.default_rng(int(seed)).standard_normal(n)

    rec = _run_loop(p, cmd.tolist(), noise.tolist(), env_mid, n, steps, ts)
    theta, omega, z, i_ref, tau_dob, balance, theta_m = (np.asarray(r) for r in rec)

    # Wrap in integer counts so theta_w is exactly in [0, 2 pi) and consistent
    # with theta_uw (a float modulo can round up to 2 pi).
    if p.encoder_counts:
        counts = np.rint(theta_m / (_TWO_PI / p.encoder_counts)).astype(np.int64)
        theta_w = np.mod(counts, p.encoder_counts) * (_TWO_PI / p.encoder_counts)
    else:
        theta_w = np.mod(theta_m, _TWO_PI)
        theta_w[theta_w >= _TWO_PI] = 0.0
    omega_log = filters.velocity_from_angle(theta_m, ts, p.g_velocity)
    alpha_log = filters.acceleration_from_velocity(omega_log, ts, p.g_acceleration)
    tau_ext = filters.lowpass(balance, p.g_rtob, ts)

    truth, alpha_true = _ground_truth(p, theta, omega, z, i_ref, noise, env_samples)
    state = {
        "theta": theta,
        "omega": omega,
        "alpha": alpha_true,
        "z": z,
        "i_ref": i_ref,
        "tau_dob": tau_dob,
        "balance": balance,
    }
    return PlantLog(
        preset=p,
        excitation="custom",
        ts=ts,
        seed=int(seed),
        substeps=steps,
        t=_readonly(t),
        theta_w=_readonly(theta_w),
        theta_uw=_readonly(theta_m),
        omega=_readonly(omega_log),
        alpha=_readonly(alpha_log),
        tau_ext=_readonly(tau_ext),
        omega_cmd=_readonly(cmd[1:-1]),
        truth=MappingProxyType({k: _readonly(v) for k, v in truth.items()}),
        state=MappingProxyType({k: _readonly(v) for k, v in state.items()}),
    )


def _ground_truth(
    p: PlantPreset,
    theta: np.ndarray,
    omega: np.ndarray,
    z: np.ndarray,
    i_ref: np.ndarray,
    noise: np.ndarray,
    env: np.ndarray,
) -> tuple[dict[str, np.ndarray], np.ndarray]:
    parts = friction_components(p, theta, omega, z)
    friction = sum(parts[k] for k in FRICTION_COMPONENTS)
    motor = p.torque_constant * (i_ref - noise)
    alpha = (motor - friction - env) / p.inertia
    ratio = p.torque_constant_nominal / p.torque_constant
    truth = dict(parts)
    truth["friction"] = friction
    truth["environment"] = env.copy()
    truth["inertia_mismatch"] = (p.inertia - p.inertia_nominal) * alpha
    truth["torque_constant_mismatch"] = (ratio - 1.0) * (p.inertia * alpha + friction + env)
    truth["current_noise"] = p.torque_constant_nominal * noise
    truth["total"] = (
        friction
        + env
        + truth["inertia_mismatch"]
        + truth["torque_constant_mismatch"]
        + truth["current_noise"]
    )
    return truth, alpha


def _run_loop(
    p: PlantPreset,
    cmd: list[float],
    noise: list[float],
    env_mid: list[float] | None,
    n: int,
    steps: int,
    ts: float,
) -> tuple[list[float], ...]:
    # The per-sample loop is sequential (feedback), so it runs on Python floats;
    # numpy scalars would be several times slower here.
    h = ts / steps
    jn, ktn, kt, jj = p.inertia_nominal, p.torque_constant_nominal, p.torque_constant, p.inertia
    kv, ki = p.velocity_gain, p.velocity_integral
    a_dob, b_dob = filters.lowpass_coefficients(p.g_dob, ts)
    quantum = _TWO_PI / p.encoder_counts if p.encoder_counts else 0.0
    lugre = p.has_lugre
    s0, s1, s2 = p.bristle_stiffness, p.bristle_damping, p.viscous
    tc, dts = p.coulomb, p.stiction - p.coulomb
    inv_vs2 = 1.0 / p.stribeck_velocity**2
    k_lin = 2.0 * jj / h + s2
    b_lin = h * s0 / 2.0 + s1 if lugre else 0.0
    z_coef = s1 - h * s0 / 2.0
    ripple = [(float(r.cycles), r.amplitude, r.phase) for r in p.ripple]
    floor, exp, sin = math.floor, math.exp, math.sin

    theta = omega = z = 0.0
    acc = 0.0  # acceleration of the last substep, to predict mid-step speed
    theta_m_prev = 0.0
    omega_d_prev = 0.0
    i1 = i2 = 0.0  # I_ref[k-1], I_ref[k-2]
    dob = 0.0
    integral = 0.0
    out_theta, out_omega, out_z = [0.0] * n, [0.0] * n, [0.0] * n
    out_i, out_dob, out_bal, out_thm = [0.0] * n, [0.0] * n, [0.0] * n, [0.0] * n
    for k in range(n):
        theta_m = floor(theta / quantum) * quantum if quantum else theta
        if k == 0:
            theta_m_prev = theta_m  # at rest before t = 0
        omega_d = (theta_m - theta_m_prev) / ts
        balance = ktn * 0.5 * (i1 + i2) - jn * (omega_d - omega_d_prev) / ts
        dob = a_dob * dob + b_dob * balance
        error = 0.5 * (cmd[k] + cmd[k + 1]) - omega_d  # cmd[j] is omega_cmd(t_{j-1})
        integral += ts * error
        alpha_ref = (cmd[k + 2] - cmd[k + 1]) / ts + kv * error + ki * integral
        i_ref = (jn * alpha_ref + dob) / ktn

        out_theta[k], out_omega[k], out_z[k] = theta, omega, z
        out_i[k], out_dob[k], out_bal[k], out_thm[k] = i_ref, dob, balance, theta_m
        theta_m_prev, omega_d_prev = theta_m, omega_d
        i2, i1 = i1, i_ref

        torque = kt * (i_ref - noise[k])
        base = k * steps
        for j in range(steps):
            force = torque
            if env_mid is not None:
                force -= env_mid[base + j]
            if ripple:
                th = theta + 0.5 * h * omega
                for cyc, amp, ph in ripple:
                    force -= amp * sin(cyc * th + ph)
            rhs = h * force + 2.0 * jj * omega
            if lugre:
                v_mid = omega + 0.5 * h * acc
                g = (tc + dts * exp(-v_mid * v_mid * inv_vs2)) / s0
                d, z = solve_substep(k_lin, b_lin, rhs + z_coef * z, z, g)
            else:
                d = rhs / k_lin
            omega_new = 2.0 * d / h - omega
            acc = (omega_new - omega) / h
            omega = omega_new
            theta += d
    return out_theta, out_omega, out_z, out_i, out_dob, out_bal, out_thm
