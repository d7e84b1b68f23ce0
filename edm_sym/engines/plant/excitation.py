"""Velocity commands for free-motion experiments (paper section IV-A).

``"abstraction"``: 0-10 s a staircase of speed plateaus in both directions,
each step a quintic (minimum-jerk shaped) ramp, so acceleration is continuous;
10-20 s the chirp of eq. (9). ``"evaluation"``: the chirp of eq. (17).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from functools import partial

import numpy as np

from edm_sym.core.errors import ConfigError

__all__ = [
    "EXCITATIONS",
    "RAMP_TIME",
    "STAIRCASE_LEVELS",
    "abstraction_command",
    "evaluation_command",
    "excitation_command",
    "get_excitation",
]

#: Names accepted by :func:`excitation_command` and ``simulate_plant``.
EXCITATIONS: tuple[str, ...] = ("abstraction", "evaluation")

#: Plateau speeds of the abstraction staircase [rad/s]; plateau i starts at t = i s.
STAIRCASE_LEVELS: tuple[float, ...] = tuple(
    math.pi * k for k in (0.5, 2.0, 6.0, 12.0, 2.0, -0.5, -2.0, -6.0, -12.0, -2.0)
)
#: Duration of every speed change of the staircase [s].
RAMP_TIME = 0.2
# The staircase returns to rest over the last ramp so the chirp of eq. (9),
# which starts from zero speed at t = 10 s, follows without a jump.
_STAIRCASE_END = 10.0


def _smoothstep(x: np.ndarray) -> np.ndarray:
    # Quintic 6x^5 - 15x^4 + 10x^3: zero slope and curvature at both ends, so the
    # commanded acceleration is continuous and peaks at 1.875 * step / RAMP_TIME.
    x = np.clip(x, 0.0, 1.0)
    return x * x * x * (x * (6.0 * x - 15.0) + 10.0)


def abstraction_command(
    t: np.ndarray, levels: Sequence[float] = STAIRCASE_LEVELS
) -> np.ndarray:
    """Velocity command of the abstraction experiment.

    Parameters
    ----------
    t : array_like
        Time [s].
    levels : sequence of float, optional
        The staircase's ten plateau speeds [rad/s], plateau i from t = i s;
        default :data:`STAIRCASE_LEVELS`.

    Returns
    -------
    numpy.ndarray
        omega_cmd [rad/s]: the staircase for t < 10 s, then eq. (9),
        ``20 pi sin(2 pi 0.5 (t - 10)^2)``.
    """
    t = np.asarray(t, dtype=float)
    omega = np.zeros_like(t)
    previous = 0.0
    starts = [float(i) for i in range(len(levels))] + [_STAIRCASE_END - RAMP_TIME]
    for start, level in zip(starts, [*levels, 0.0], strict=True):
        # A sum of smooth steps: each ramp moves from the previous level to the next.
        omega += (level - previous) * _smoothstep((t - start) / RAMP_TIME)
        previous = level
    tc = t - _STAIRCASE_END
    chirp = 20.0 * np.pi * np.sin(2.0 * np.pi * 0.5 * tc**2)
    return np.where(t >= _STAIRCASE_END, chirp, omega)


def evaluation_command(t: np.ndarray) -> np.ndarray:
    """Velocity command of the evaluation experiment, eq. (17).

    Parameters
    ----------
    t : array_like
        Time [s].

    Returns
    -------
    numpy.ndarray
        omega_cmd = ``20 pi sin(2 pi 0.1 t^2)`` [rad/s].
    """
    t = np.asarray(t, dtype=float)
    return 20.0 * np.pi * np.sin(2.0 * np.pi * 0.1 * t**2)


_COMMANDS: dict[str, Callable[[np.ndarray], np.ndarray]] = {
    "abstraction": abstraction_command,
    "evaluation": evaluation_command,
}


def get_excitation(
    name: str, staircase: Sequence[float] | None = None
) -> Callable[[np.ndarray], np.ndarray]:
    """Return the command function of a named excitation.

    Parameters
    ----------
    name : str
        One of :data:`EXCITATIONS`.
    staircase : sequence of float, optional
        The abstraction staircase's plateau speeds [rad/s] (a preset's
        ``staircase``); default :data:`STAIRCASE_LEVELS`.

    Returns
    -------
    callable
        ``t -> omega_cmd`` (vectorised).

    Raises
    ------
    ConfigError
        (a ``ValueError``) when the name is unknown.
    """
    if isinstance(name, str) and name in _COMMANDS:
        if name == "abstraction" and staircase is not None:
            return partial(abstraction_command, levels=tuple(staircase))
        return _COMMANDS[name]
    raise ConfigError(
        "excitation", f"expected one of {', '.join(EXCITATIONS)}, found {name!r}"
    )


def excitation_command(name: str, t: np.ndarray) -> np.ndarray:
    """Evaluate a named velocity command.

    Parameters
    ----------
    name : str
        One of :data:`EXCITATIONS`.
    t : array_like
        Time [s].

    Returns
    -------
    numpy.ndarray
        omega_cmd [rad/s].
    """
    return get_excitation(name)(t)
