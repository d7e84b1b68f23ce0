"""The inertia a model holds, with the observer's lag taken out.

A reaction torque observer estimates the disturbance through a low-pass,
``tau_ext = g / (s + g) tau``, so the target lags the torque it stands for by
about ``1/g``. A compensator fitted to it lags too, and the search writes
that lag, and often an inertia error with it, into the filters of velocity
rows: ``(0.15 s + 25.5)/(s + 1697)`` on the velocity holds 8e-5 kg m^2 of
``d(omega)/dt`` in its lead. Named row by row, no such row is an
acceleration term; and the lag itself, regressed on the acceleration, looks
like an inertia of ``-(d friction / d omega) / g`` (-6e-5 to -7e-5 kg m^2 on
the project's plants, whose inertia is exact).

:func:`model_inertia` undoes the lag on the model's total output and on each
row's, ``y + y' / g`` (``g`` the observer's bandwidth, which the log records
as the scalar ``observer_bandwidth``, or ``edm describe --observer-bandwidth``),
and regresses it over the data on ``sgn(v), v, a, 1``: Coulomb, viscous,
inertia and an offset, the first-order model of the friction. The ``a``
coefficient is the inertia the model holds; each row's coefficient is its
share (they add up to it). Without a bandwidth nothing is measured: the
lag cannot be told from an inertia.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from edm_sym.core.roles import motion_signals


@dataclass(frozen=True)
class ModelInertia:
    """The inertia the model's rows hold together.

    Attributes
    ----------
    inertia : float
        The ``a`` coefficient of the whole model's un-lagged output [kg m^2 or kg].
    rows : tuple of float
        Each row's coefficient (they sum to ``inertia``).
    rms : float
        RMS of ``inertia * a`` on the data [N m or N].
    bandwidth : float
        The observer's bandwidth ``g`` used [rad/s].
    """

    inertia: float
    rows: tuple[float, ...]
    rms: float
    bandwidth: float


def model_inertia(outputs: np.ndarray, velocity: np.ndarray, acceleration: np.ndarray,
                  ts: float, bandwidth: float, part: slice | np.ndarray = slice(None)
                  ) -> ModelInertia | None:
    """The inertia the rows hold, each row's output un-lagged and regressed on the data.

    Parameters
    ----------
    outputs : numpy.ndarray
        Shape (m, N): each row's output on one contiguous log.
    velocity, acceleration : numpy.ndarray
        Shape (N,): from :func:`motion_signals`.
    ts : float
        Sample time [s].
    bandwidth : float
        The observer's bandwidth ``g`` [rad/s].
    part : slice or numpy.ndarray
        The samples to regress on (the held-out rows of the log the search was
        fitted to); the derivatives are taken on the whole log first.

    Returns
    -------
    ModelInertia or None
        None when the regression is singular or not finite.
    """
    if not (bandwidth > 0 and np.isfinite(bandwidth)) or outputs.shape[1] < 3:
        return None
    unlagged = outputs + np.gradient(outputs, ts, axis=1) / bandwidth
    v, a = velocity[part], acceleration[part]
    basis = np.column_stack([np.sign(v), v, a, np.ones_like(v)])
    if not np.all(np.isfinite(basis)) or not np.all(np.isfinite(unlagged)):
        return None
    coef, _, rank, _ = np.linalg.lstsq(basis, unlagged[:, part].T, rcond=None)
    if rank < basis.shape[1]:
        return None
    rows = tuple(float(c) for c in coef[2])
    total = float(sum(rows))
    return ModelInertia(total, rows, abs(total) * float(np.sqrt(np.mean(a * a))), bandwidth)


def rows_inertia(roles: Sequence[str | None], outputs: np.ndarray, inputs: Sequence[np.ndarray],
                 ts: float, bandwidth: float | None,
                 part: slice | np.ndarray = slice(None)) -> ModelInertia | None:
    """:func:`model_inertia` of a model's rows on one contiguous log (None without a bandwidth).

    Parameters
    ----------
    roles : sequence of str or None
        Each row's input role (``SymbolicModel.rows[j].role``).
    outputs : numpy.ndarray
        Shape (m, N): each row's output.
    inputs : sequence of numpy.ndarray
        Each row's input signal.
    ts, bandwidth, part
        As for :func:`model_inertia`.
    """
    if bandwidth is None:
        return None
    motion = motion_signals(inputs, roles, ts)
    if motion is None:
        return None
    return model_inertia(np.asarray(outputs, dtype=float), *motion, ts, float(bandwidth), part)
