"""Friction of the servo axis: LuGre bristles, viscous friction, position ripple.

The LuGre model (paper eqs. 10-12)::

    tau = sigma_0 z + sigma_1 dz/dt + sigma_2 v
    dz/dt = v - |v| z / g(v)
    g(v) = (tau_c + (tau_s - tau_c) exp(-(v/v_s)^2)) / sigma_0

is stiff: in sliding z relaxes over a *distance* g(v) (tens of micro-radians)
whatever the speed. Written per unit of travel, ``dz/dtheta = sgn(v) - z/g``, the
relaxation is exact for a known displacement, which is what
:func:`solve_substep` uses; the integrator never resolves the fast time scale.

The ground truth splits ``sigma_0 z`` exactly into a Coulomb and a Stribeck part:
with ``zeta = sigma_0 z / (tau_c + (tau_s - tau_c) exp(-(v/v_s)^2))`` (which is
``sgn(v)`` in steady sliding), ``coulomb = tau_c zeta`` and
``stribeck = (tau_s - tau_c) exp(-(v/v_s)^2) zeta``; ``bristle = sigma_1 dz/dt``
(zero in steady sliding).
"""

from __future__ import annotations

import math

import numpy as np

from edm_sym.engines.plant.presets import PlantPreset

__all__ = [
    "FRICTION_COMPONENTS",
    "friction_components",
    "ripple_torque",
    "solve_substep",
    "stribeck_level",
]

#: Keys of :func:`friction_components`, in the order they are summed.
FRICTION_COMPONENTS: tuple[str, ...] = ("coulomb", "stribeck", "bristle", "viscous", "ripple")


def stribeck_level(preset: PlantPreset, omega: np.ndarray | float) -> np.ndarray | float:
    """Steady-state LuGre friction magnitude ``sigma_0 g(v)`` [N m] (eq. 12 times sigma_0).

    Parameters
    ----------
    preset : PlantPreset
        The plant.
    omega : float or array_like
        Velocity [rad/s].

    Returns
    -------
    float or numpy.ndarray
        ``tau_c + (tau_s - tau_c) exp(-(omega/v_s)^2)``.
    """
    x = np.asarray(omega, dtype=float) / preset.stribeck_velocity
    level = preset.coulomb + (preset.stiction - preset.coulomb) * np.exp(-x * x)
    return level if np.ndim(level) else float(level)


def ripple_torque(preset: PlantPreset, theta: np.ndarray | float) -> np.ndarray | float:
    """Position-dependent torque ripple [N m], periodic in the wrapped angle.

    Parameters
    ----------
    preset : PlantPreset
        The plant.
    theta : float or array_like
        Angle [rad] (wrapped or not: the result is the same).

    Returns
    -------
    float or numpy.ndarray
        ``sum(A_i sin(k_i theta + phi_i))``.
    """
    theta = np.asarray(theta, dtype=float)
    out = np.zeros_like(theta)
    for h in preset.ripple:
        out = out + h.amplitude * np.sin(h.cycles * theta + h.phase)
    return out if np.ndim(out) else float(out)


def friction_components(
    preset: PlantPreset, theta: np.ndarray, omega: np.ndarray, z: np.ndarray
) -> dict[str, np.ndarray]:
    """True friction torques at given states, split into physical components.

    Parameters
    ----------
    preset : PlantPreset
        The plant.
    theta, omega, z : array_like
        True angle [rad], velocity [rad/s] and bristle deflection [rad].

    Returns
    -------
    dict of str to numpy.ndarray
        Keys :data:`FRICTION_COMPONENTS` [N m]; their sum is the friction torque.
    """
    theta = np.asarray(theta, dtype=float)
    omega = np.asarray(omega, dtype=float)
    z = np.asarray(z, dtype=float)
    zero = np.zeros_like(omega)
    out = {
        "coulomb": zero,
        "stribeck": zero.copy(),
        "bristle": zero.copy(),
        "viscous": preset.viscous * omega,
        "ripple": np.asarray(ripple_torque(preset, theta), dtype=float) + zero,
    }
    if preset.has_lugre:
        level = np.asarray(stribeck_level(preset, omega))
        zeta = preset.bristle_stiffness * z / level
        out["coulomb"] = preset.coulomb * zeta
        out["stribeck"] = (level - preset.coulomb) * zeta
        dz = omega - np.abs(omega) * zeta
        out["bristle"] = preset.bristle_damping * dz
    return out


def solve_substep(k: float, b: float, c: float, z0: float, g: float) -> tuple[float, float]:
    """Solve one implicit step of the mechanics with LuGre bristles.

    Finds the displacement d of ``k d + b Z(d) = c``, where ``Z(d)`` is the exact
    bristle state after a travel d at a frozen ``g``::

        Z(d) = sgn(d) g + (z0 - sgn(d) g) exp(-|d| / g)

    ``Z`` is monotone in d, so the root is unique; each branch is convex or
    concave and Newton's method started on the right side of the root converges
    monotonically.

    Parameters
    ----------
    k : float
        ``2 J / h + sigma_2`` (> 0).
    b : float
        ``h sigma_0 / 2 + sigma_1`` (>= 0).
    c : float
        Right-hand side (impulses and momentum).
    z0 : float
        Bristle deflection at the start of the step [rad].
    g : float
        ``g(v)`` of eq. 12 [rad] (> 0).

    Returns
    -------
    d, z1 : float
        Displacement over the step [rad] and bristle deflection at its end [rad].
    """
    f0 = b * z0 - c
    if f0 < 0.0:
        return _forward(k, b, c, z0, g)
    if f0 > 0.0:
        d, z1 = _forward(k, b, -c, -z0, g)
        return -d, -z1
    return 0.0, z0


def _forward(k: float, b: float, c: float, z0: float, g: float) -> tuple[float, float]:
    # Root of phi(d) = k d + beta exp(-d/g) - gamma on d > 0, knowing phi(0) < 0.
    beta = b * (z0 - g)
    gamma = c - b * g
    # Start at the fully relaxed solution (z = g): left of the root when phi is
    # concave (beta <= 0), right of it when convex; either way Newton is monotone.
    d = gamma / k
    if d < 0.0:
        d = 0.0
    exp = math.exp
    for _ in range(200):
        e = exp(-d / g)
        step = (k * d + beta * e - gamma) / (k - beta * e / g)
        d -= step
        if abs(step) <= 1e-15 * (d + g):
            break
    return d, g + (z0 - g) * exp(-d / g)
