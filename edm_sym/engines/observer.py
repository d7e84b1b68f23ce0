"""The reaction-torque-observer view of a measured axis log.

A drive log gives position and motor force (or torque); the observer's
free-motion estimate of the external force is ``F - M_n qdd`` for a nominal
mass (inertia) ``M_n``. Velocity and acceleration come from the position
through a zero-phase Butterworth low-pass filter and central differences, as
in the usual inverse-dynamics identification of such axes (e.g. the EMPS
benchmark). The result is an ordinary :class:`~edm_sym.core.data.DataLog` that
``edm abstract`` and ``edm lugre`` read.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import signal

from edm_sym.core.data import DataLog
from edm_sym.core.errors import DataFormatError


@dataclass(frozen=True)
class ObserverOptions:
    """How to build the observer view.

    Parameters
    ----------
    position : str
        Position column [m or rad].
    force : str
        Force (torque) command column, or a controller output to scale.
    force_gain : float or str
        Multiplies ``force``: a number, or the name of a scalar stored in the
        log (the EMPS drive gain ``gtau``). Default 1.
    nominal_inertia : float
        M_n [kg or kg m^2]; the observer subtracts ``M_n qdd``.
    cutoff_hz : float
        Corner of the zero-phase Butterworth filter on the position [Hz].
    order : int
        Its order.
    """

    position: str
    force: str
    nominal_inertia: float
    force_gain: float | str = 1.0
    cutoff_hz: float = 100.0
    order: int = 4

    def __post_init__(self) -> None:
        if not np.isfinite(self.nominal_inertia) or self.nominal_inertia < 0:
            raise ValueError(f"nominal_inertia: expected a number >= 0, found {self.nominal_inertia}")
        if not (np.isfinite(self.cutoff_hz) and self.cutoff_hz > 0):
            raise ValueError(f"cutoff_hz: expected a positive frequency, found {self.cutoff_hz}")
        if not isinstance(self.force_gain, str) and not np.isfinite(self.force_gain):
            raise ValueError(f"force_gain: expected a finite number or a scalar's name, "
                             f"found {self.force_gain}")


#: The lowest filter corner, as a fraction of the Nyquist frequency: below it the
#: Butterworth filter's transfer-function coefficients lose its DC gain (1e-6 at 1e-3 of
#: Nyquist, 1 % at 1e-4, unstable below 3e-5 for order 4).
MIN_CORNER = 1e-3


def observer_view(data: DataLog, options: ObserverOptions) -> DataLog:
    """Derive ``q, qd, qdd, force, tau_ext`` from a measured log.

    Parameters
    ----------
    data : DataLog
        The measured log (e.g. ``load_data("DATA_EMPS.mat")``).
    options : ObserverOptions

    Returns
    -------
    DataLog
        Columns ``t, q, qd, qdd, force, tau_ext`` with ``tau_ext = force - M_n qdd``.

    Raises
    ------
    DataFormatError
        A missing column or scalar, or a filter corner above the Nyquist frequency.
    """
    if options.position == data.time_column:
        raise DataFormatError(f"{data.source}: column {options.position!r}",
                              "expected the measured position, found the log's time column")
    q = data.column(options.position, role="position column")
    raw = data.column(options.force, role="force column")
    gain = options.force_gain
    if isinstance(gain, str):
        if gain not in data.scalars:
            have = ", ".join(data.scalars) or "none"
            raise DataFormatError(f"{data.source}: scalar {gain!r}",
                                  f"expected a stored scalar named {gain!r}, found: {have}")
        gain = data.scalars[gain]
        if not np.isfinite(gain):
            raise DataFormatError(f"{data.source}: scalar {options.force_gain!r}",
                                  f"expected a finite gain, found {gain}")
    nyquist = 0.5 / data.ts
    if options.cutoff_hz >= nyquist:
        raise DataFormatError(f"{data.source}: cutoff",
                              f"expected a corner below Nyquist ({nyquist:g} Hz), "
                              f"found {options.cutoff_hz:g}")
    if options.cutoff_hz < MIN_CORNER * nyquist:
        raise DataFormatError(f"{data.source}: cutoff",
                              f"expected a corner of at least {MIN_CORNER:g} of Nyquist "
                              f"({MIN_CORNER * nyquist:g} Hz: below it the order-{options.order} "
                              f"filter's coefficients lose its gain), found "
                              f"{options.cutoff_hz:g}")
    b, a = signal.butter(options.order, options.cutoff_hz / nyquist)
    need = 3 * max(len(a), len(b)) + 1  # filtfilt's padding, plus one sample
    if len(q) < need:
        raise DataFormatError(f"{data.source}: column {options.position!r}",
                              f"expected at least {need} samples for the order-{options.order} "
                              f"zero-phase filter, found {len(q)}")
    qf = signal.filtfilt(b, a, q)
    qd = np.gradient(qf, data.ts)
    qdd = np.gradient(qd, data.ts)
    with np.errstate(over="ignore", invalid="ignore"):
        force = float(gain) * raw
        tau = force - options.nominal_inertia * qdd
    for col, what in ((force, f"force gain {gain:g}"),
                      (tau, f"nominal inertia {options.nominal_inertia:g}")):
        bad = np.flatnonzero(~np.isfinite(col))
        if bad.size:
            raise DataFormatError(f"{data.source}: row {bad[0] + 1}, column {options.force!r}",
                                  f"expected a force a double holds with the {what}, "
                                  f"found {col[bad[0]]}")
    cols = {data.time_column or "t": data.times, "q": q, "qd": qd, "qdd": qdd, "force": force,
            "tau_ext": tau}
    return DataLog(cols, data.ts, data.source, data.sha256, dict(data.scalars))


def relative_error(force: np.ndarray, residual: np.ndarray) -> float:
    """The EMPS figure of merit: ``100 ||residual|| / ||force||`` [%]."""
    return float(100.0 * np.linalg.norm(residual) / np.linalg.norm(force))


def fit_reference_model(qd: np.ndarray, qdd: np.ndarray, force: np.ndarray) -> np.ndarray:
    """Least-squares inverse-dynamics model ``F = M qdd + Fv qd + Fc sgn(qd) + offset``.

    Returns
    -------
    numpy.ndarray
        ``[M, Fv, Fc, offset]``.
    """
    design = np.column_stack([qdd, qd, np.sign(qd), np.ones_like(qd)])
    coef, *_ = np.linalg.lstsq(design, force, rcond=None)
    return coef


def reference_model(coef: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> np.ndarray:
    """Evaluate the model of :func:`fit_reference_model`."""
    m, fv, fc, off = coef
    return m * qdd + fv * qd + fc * np.sign(qd) + off
