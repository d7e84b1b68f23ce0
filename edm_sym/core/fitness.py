"""The paper's eq. 8, written once: the weighted RMS of a residual.

``fitness(residual, weights) = sqrt(mean(Lambda * residual**2))``, the mean
over every sample (zero-weight ones included). The genetic algorithm, the
LuGre identification, the report, the pipeline's evaluation and the plant's
statistics all call these two functions.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

__all__ = ["fitness", "rms"]


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
