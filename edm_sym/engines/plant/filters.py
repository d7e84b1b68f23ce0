"""Discrete filters of the drive: observer low-passes and the logged derivatives.

All first-order low-passes ``g/(s + g)`` of the drive (DOB, RTOB's Q(s), the
velocity and acceleration filters of the log) are realised here, once, as the
zero-order-hold equivalent from :func:`scipy.signal.cont2discrete`
(``method="zoh"``)::

    y[k] = a y[k-1] + b x[k],    a = exp(-g ts),  b = 1 - a

``x[k]`` is the input *held over the interval that ends at sample k* (the
observers' torque balance and the encoder differences are interval averages of
that kind), so a step of x that starts at a sample instant gives exactly
``y(t_k) = 1 - exp(-g t_k)``, the continuous step response.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
from scipy import signal

__all__ = [
    "acceleration_from_velocity",
    "lowpass",
    "lowpass_coefficients",
    "sliding_rows",
    "velocity_from_angle",
]


def lowpass_coefficients(g: float, ts: float) -> tuple[float, float]:
    """ZOH-equivalent coefficients of the first-order low-pass ``g/(s + g)``.

    Parameters
    ----------
    g : float
        Cut-off [rad/s], > 0.
    ts : float
        Sample time [s], > 0.

    Returns
    -------
    a, b : float
        ``y[k] = a y[k-1] + b x[k]``, with ``a = exp(-g ts)`` and ``b = 1 - a``.
    """
    return _coefficients(float(g), float(ts))


@lru_cache(maxsize=256)
def _coefficients(g: float, ts: float) -> tuple[float, float]:
    if not (g > 0.0 and ts > 0.0):
        raise ValueError(f"lowpass: expected g > 0 and ts > 0, found g={g!r}, ts={ts!r}")
    num, den, _ = signal.cont2discrete(([g], [1.0, g]), ts, method="zoh")
    # cont2discrete returns b(z) = [0, 1 - a], a(z) = [1, -a]: the leading zero is
    # the one-sample delay that our interval-aligned input already accounts for.
    num = np.atleast_1d(np.squeeze(num))
    return float(-den[1]), float(num[1])


def lowpass(x: np.ndarray, g: float, ts: float) -> np.ndarray:
    """Run the ZOH first-order low-pass over a signal, starting from rest.

    Parameters
    ----------
    x : array_like
        Input samples, ``x[k]`` held over the interval ending at sample k.
    g : float
        Cut-off [rad/s].
    ts : float
        Sample time [s].

    Returns
    -------
    numpy.ndarray
        ``y[k] = a y[k-1] + b x[k]`` with ``y[-1] = 0``.
    """
    a, b = lowpass_coefficients(g, ts)
    return signal.lfilter([b], [1.0, -a], np.asarray(x, dtype=float))


def velocity_from_angle(theta: np.ndarray, ts: float, g: float) -> np.ndarray:
    """The logged velocity: low-passed backward differences of the encoder angle.

    Parameters
    ----------
    theta : array_like
        Measured (unwrapped) angle [rad]; the axis is taken at rest before ``theta[0]``.
    ts : float
        Sample time [s].
    g : float
        Cut-off of the low-pass [rad/s].

    Returns
    -------
    numpy.ndarray
        omega [rad/s].
    """
    theta = np.asarray(theta, dtype=float)
    return lowpass(np.diff(theta, prepend=theta[:1]) / ts, g, ts)


def acceleration_from_velocity(omega: np.ndarray, ts: float, g: float) -> np.ndarray:
    """The logged acceleration: low-passed backward differences of the logged velocity.

    Parameters
    ----------
    omega : array_like
        Logged velocity [rad/s]; zero before ``omega[0]``.
    ts, g : float
        As for :func:`velocity_from_angle`.

    Returns
    -------
    numpy.ndarray
        alpha [rad/s^2].
    """
    omega = np.asarray(omega, dtype=float)
    return lowpass(np.diff(omega, prepend=0.0) / ts, g, ts)



def sliding_rows(omega: np.ndarray, min_speed: float, memory: int) -> np.ndarray:
    """Samples where the axis slides: ``|omega| >= min_speed`` there and in the ``memory``
    samples before.

    The static friction laws hold while the axis slides; at a reversal and for
    a while after it (the bristles' presliding, the observer's lag) the target
    follows dynamics no static law describes. The engineer's least squares
    (:func:`edm_sym.engines.plant.anchor.fit_anchor`) and the data's support
    of a named law (docs/describe.md, "Honest names") read these samples.

    Parameters
    ----------
    omega : numpy.ndarray
        Velocity.
    min_speed : float
        The slowest speed that counts as sliding (> 0; 0 or less: every sample).
    memory : int
        Samples after a slower one that still do not count.

    Returns
    -------
    numpy.ndarray of bool
    """
    if min_speed <= 0.0:
        return np.ones(omega.size, dtype=bool)
    slow = (np.abs(omega) < min_speed).astype(float)
    recent = np.convolve(slow, np.ones(memory + 1))[: omega.size]
    return recent == 0.0
