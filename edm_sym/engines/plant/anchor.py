"""The engineer's anchor: friction, inertia and ripple by linear least squares on a log.

What an engineer fits to a reaction-torque-observer log before trusting any
search: ``tau_ext ~ Q(s)[Fc sgn(omega) + Fs sgn(omega) exp(-(omega/v_s)^2)
+ D omega + dJ alpha + c0 + sum_k (a_k cos k theta + b_k sin k theta)]``,
each regressor passed through the observer's low-pass ``Q(s) = g/(s + g)``
(:func:`edm_sym.engines.plant.filters.lowpass`), so the observer's lag is in
the model, not in the parameters. The Stribeck velocity ``v_s`` makes the fit
nonlinear; it is given, or scanned over candidates (the one with the least
residual wins). Velocity and acceleration are central differences of the
encoder angle, at the instant the observer's torque balance is centred on.
The rows fitted are those in steady sliding: a reversal (``|omega|`` below
``min_speed``, 0.5 rad/s by default) and the ``settle`` observer time
constants after it are left out, since there the friction is the LuGre
bristles' presliding, which no static law describes. On the family's draws
(:mod:`edm_sym.engines.plant.family`) it recovers the truth's parameters
within a few percent (``tests/test_family.py``).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from edm_sym.core.terms import TermKind
from edm_sym.engines.plant.filters import lowpass, sliding_rows

__all__ = ["AnchorFit", "centred_motion", "fit_anchor", "law_torque"]

#: The angle harmonics fitted by default: 1 to 8 cycles per revolution.
DEFAULT_HARMONICS = tuple(range(1, 9))


@dataclass(frozen=True)
class AnchorFit:
    """The least-squares parameters of one log.

    Parameters
    ----------
    coulomb : float
        Fc [N m].
    viscous : float
        D [N m s/rad].
    inertia : float
        dJ [kg m^2], the inertia ``tau_ext`` sees beyond the nominal one.
    offset : float
        c0 [N m].
    stribeck_peak : float
        Fs [N m], the excess over Coulomb at rest (0 when no ``v_s`` was used).
    stribeck_velocity : float or None
        The v_s used [rad/s], None without a Stribeck regressor.
    harmonics : mapping of int to (float, float)
        Cycles per revolution to (amplitude [N m], phase [rad]) of
        ``amplitude sin(k theta + phase)``.
    rmse : float
        RMS of the residual over the rows fitted [N m].
    """

    coulomb: float
    viscous: float
    inertia: float
    offset: float
    stribeck_peak: float
    stribeck_velocity: float | None
    harmonics: Mapping[int, tuple[float, float]]
    rmse: float

    def physics(self) -> dict[str, dict[str, float]]:
        """The fit in the shape of a family plant's truth (kind to parameters).

        Every kind is listed; ``spatial`` is the harmonic of largest
        amplitude, ``stribeck`` only when a Stribeck velocity was used.

        Returns
        -------
        dict of str to dict of str to float
        """
        out: dict[str, dict[str, float]] = {
            TermKind.COULOMB: {"level": self.coulomb},
            TermKind.VISCOUS: {"coefficient": self.viscous},
            TermKind.ACCELERATION: {"inertia": self.inertia},
            TermKind.OFFSET: {"level": self.offset},
        }
        if self.stribeck_velocity is not None:
            out[TermKind.STRIBECK] = {"peak": self.stribeck_peak,
                                      "stribeck_velocity": self.stribeck_velocity}
        if self.harmonics:
            k, (amplitude, phase) = max(self.harmonics.items(), key=lambda kv: kv[1][0])
            out[TermKind.SPATIAL] = {"cycles_per_revolution": float(k), "amplitude": amplitude,
                                     "phase": phase}
        return out


def centred_motion(theta_uw: np.ndarray, ts: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Angle, velocity and acceleration at ``t_{k-1}``, from the encoder angle up to sample k.

    The torque balance of sample k, which ``tau_ext[k]`` low-passes, is the
    disturbance around ``t_{k-1}`` (docs/plant.md, step 3); the central
    differences ``(theta[k] - theta[k-2]) / 2 ts`` and ``(theta[k] -
    2 theta[k-1] + theta[k-2]) / ts^2`` are the motion at that instant. The
    logged ``omega`` and ``alpha`` lag it by their filters (about 0.7 and 1.7
    samples), and on a 10 Hz chirp such a lag moves a few percent of the
    viscous torque into the inertia and back.

    Parameters
    ----------
    theta_uw : numpy.ndarray
        Unwrapped encoder angle [rad].
    ts : float
        Sample time [s].

    Returns
    -------
    theta, omega, alpha : numpy.ndarray
        Each as long as ``theta_uw``, [rad], [rad/s], [rad/s^2]; the axis is
        at rest before the first sample.
    """
    before = np.concatenate([[theta_uw[0], theta_uw[0]], theta_uw])
    theta = before[1:-1]
    omega = (before[2:] - before[:-2]) / (2.0 * ts)
    alpha = (before[2:] - 2.0 * before[1:-1] + before[:-2]) / ts**2
    return theta, omega, alpha


def fit_anchor(
    columns: Mapping[str, np.ndarray], *, g_rtob: float, ts: float,
    stribeck_velocity: float | Sequence[float] | None = None,
    harmonics: Sequence[int] = DEFAULT_HARMONICS, min_speed: float = 0.5, settle: float = 6.0,
) -> AnchorFit:
    """Fit friction, inertia error, offset and angle harmonics to ``tau_ext``.

    Parameters
    ----------
    columns : mapping of str to numpy.ndarray
        The log columns ``theta_uw`` and ``tau_ext`` (``PlantLog.columns``,
        or a data log's); velocity and acceleration come from the angle
        (:func:`centred_motion`).
    g_rtob : float
        The observer's cut-off [rad/s].
    ts : float
        Sample time [s].
    stribeck_velocity : float or sequence of float, optional
        v_s [rad/s] of the Stribeck regressor; a sequence is scanned. None:
        no Stribeck regressor.
    harmonics : sequence of int, optional
        The cycles per revolution fitted (default 1-8; empty for none).
    min_speed : float, optional
        Rows with ``|omega| < min_speed`` [rad/s] are left out, and so are
        the rows within ``settle`` time constants ``1/g_rtob`` after them
        (0 fits every row).
    settle : float, optional
        How many observer time constants after a slow sample stay out.

    Returns
    -------
    AnchorFit
    """
    theta, omega, alpha = centred_motion(np.asarray(columns["theta_uw"], dtype=float), ts)
    target = np.asarray(columns["tau_ext"], dtype=float)
    sign = np.sign(omega)
    base = [sign, omega, alpha, np.ones_like(omega)]
    for k in harmonics:
        base += [np.cos(k * theta), np.sin(k * theta)]
    design = np.column_stack([lowpass(x, g_rtob, ts) for x in base])
    rows = sliding_rows(omega, min_speed, int(math.ceil(settle / (g_rtob * ts))))
    design, target = design[rows], target[rows]
    if stribeck_velocity is None:
        candidates: list[float | None] = [None]
    elif isinstance(stribeck_velocity, int | float):
        candidates = [float(stribeck_velocity)]
    else:
        candidates = [float(v) for v in stribeck_velocity]
    best: tuple[float, np.ndarray, float | None] | None = None
    for vs in candidates:
        matrix = design
        if vs is not None:
            hump = lowpass(sign * np.exp(-(omega / vs) ** 2), g_rtob, ts)[rows]
            matrix = np.column_stack([design, hump])
        coef, *_ = np.linalg.lstsq(matrix, target, rcond=None)
        rmse = float(np.sqrt(np.mean((target - matrix @ coef) ** 2)))
        if best is None or rmse < best[0]:
            best = (rmse, coef, vs)
    assert best is not None
    rmse, coef, vs = best
    fc, d, dj, c0 = (float(c) for c in coef[:4])
    found = {}
    for i, k in enumerate(harmonics):
        a, b = float(coef[4 + 2 * i]), float(coef[5 + 2 * i])
        found[int(k)] = (math.hypot(a, b), math.atan2(a, b))
    peak = float(coef[-1]) if vs is not None else 0.0
    return AnchorFit(fc, d, dj, c0, peak, vs, found, rmse)


def law_torque(
    columns: Mapping[str, np.ndarray], physics: Mapping[str, Mapping[str, float]], *,
    g_rtob: float, ts: float,
) -> np.ndarray:
    """The documented static laws with given parameters, on a log, as the observer sees them.

    ``Q(s)[Fc sgn(omega) + Fs sgn(omega) exp(-(omega/v_s)^2) + D omega + dJ alpha
    + c0 + A sin(k theta + phi)]`` with the motion of :func:`centred_motion`:
    what the model :func:`fit_anchor` fits predicts with these parameters. With
    a family plant's truth it is the plant's law without its presliding
    dynamics and noise.

    Parameters
    ----------
    columns : mapping of str to numpy.ndarray
        The log columns (``theta_uw`` is used).
    physics : mapping of str to mapping of str to float
        Kind to parameters, as :attr:`FamilyPlant.truth
        <edm_sym.engines.plant.family.FamilyPlant.truth>` or
        :meth:`AnchorFit.physics` give them; kinds not listed are zero.
    g_rtob, ts : float
        The observer's cut-off [rad/s] and the sample time [s].

    Returns
    -------
    numpy.ndarray
        The predicted ``tau_ext`` [N m].
    """
    theta, omega, alpha = centred_motion(np.asarray(columns["theta_uw"], dtype=float), ts)
    sign = np.sign(omega)
    law = np.zeros_like(omega)
    if TermKind.COULOMB in physics:
        law += physics[TermKind.COULOMB]["level"] * sign
    if TermKind.STRIBECK in physics:
        st = physics[TermKind.STRIBECK]
        law += st["peak"] * sign * np.exp(-(omega / st["stribeck_velocity"]) ** 2)
    if TermKind.VISCOUS in physics:
        law += physics[TermKind.VISCOUS]["coefficient"] * omega
    if TermKind.ACCELERATION in physics:
        law += physics[TermKind.ACCELERATION]["inertia"] * alpha
    if TermKind.OFFSET in physics:
        law += physics[TermKind.OFFSET]["level"]
    if TermKind.SPATIAL in physics:
        sp = physics[TermKind.SPATIAL]
        law += sp["amplitude"] * np.sin(sp["cycles_per_revolution"] * theta + sp.get("phase", 0.0))
    return lowpass(law, g_rtob, ts)
