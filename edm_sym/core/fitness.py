"""The paper's eq. 8, written once: the weighted RMS of a residual.

``fitness(residual, weights) = sqrt(mean(Lambda * residual**2))``, the mean
over every sample (zero-weight ones included). The genetic algorithm, the
LuGre identification, the report, the pipeline's evaluation and the plant's
statistics all call these two functions.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

__all__ = ["MAGNITUDE", "fitness", "magnitude_problem", "rms"]

#: The largest magnitude a target (or a velocity) may reach: eq. 8 squares the error,
#: and eq. 12 the velocity; squared, it must stay a normal double.
MAGNITUDE = (1e-150, 1e150)


def magnitude_problem(x: ArrayLike) -> str | None:
    """Why the values ``x`` cannot be squared safely (None: they can, or are all zero)."""
    peak = float(np.max(np.abs(np.asarray(x, dtype=float))))
    if peak and not MAGNITUDE[0] <= peak <= MAGNITUDE[1]:
        return (f"expected values whose largest magnitude is from {MAGNITUDE[0]:g} to "
                f"{MAGNITUDE[1]:g} (their squares normal numbers), found {peak:g}")
    return None


def fitness(residual: ArrayLike, weights: ArrayLike | float = 1.0) -> float:
    """The paper's eq. 8: ``sqrt(mean(Lambda * residual**2))``.

    Parameters
    ----------
    residual : array_like
        ``target - tau_cmp`` per sample.
    weights : array_like or float, default 1.0
        The weighting function Lambda per sample (or one value for all).

    Returns
    -------
    float
    """
    r = np.asarray(residual, dtype=float)
    return float(np.sqrt(np.mean(np.asarray(weights, dtype=float) * r * r)))


def rms(x: ArrayLike) -> float:
    """The root mean square of ``x``: :func:`fitness` with Lambda = 1."""
    return fitness(x)
