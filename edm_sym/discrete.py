"""Discrete-time realisations: the one place continuous forms become difference equations.

The simulator, the python-control systems, the generated C and Python and the
report all read the coefficients made here.
"""

from __future__ import annotations

from collections.abc import Sequence
from functools import lru_cache

import numpy as np
from scipy import signal

#: Discretisation methods, with the text the documentation and headers print.
METHODS = {
    "bilinear": "Tustin (bilinear), s = (2/Ts) (z - 1)/(z + 1), via scipy.signal.cont2discrete",
    "backward_diff": "backward difference, s = (z - 1)/(Ts z)",
}


def discretize(
    num: Sequence[float], den: Sequence[float], ts: float, method: str
) -> tuple[np.ndarray, np.ndarray]:
    """Discretise ``num(s)/den(s)`` with sample time ``ts``.

    Parameters
    ----------
    num, den : sequence of float
        Coefficients in descending powers of s.
    ts : float
        Sample time [s].
    method : {"bilinear", "backward_diff"}
        ``"bilinear"`` uses :func:`scipy.signal.cont2discrete` (proper
        functions only); ``"backward_diff"`` substitutes s = (1 - z^-1)/Ts,
        which also realises improper forms such as a pure derivative.

    Returns
    -------
    b, a : numpy.ndarray
        Coefficients in ascending powers of z^-1 with ``a[0] == 1``.
    """
    return _discretize(tuple(map(float, num)), tuple(map(float, den)), float(ts), method)


@lru_cache(maxsize=65536)
def _discretize(
    num: tuple[float, ...], den: tuple[float, ...], ts: float, method: str
) -> tuple[np.ndarray, np.ndarray]:
    if method not in METHODS:
        raise ValueError(f"method: expected one of {sorted(METHODS)}, found {method!r}")
    if method == "bilinear":
        b, a, _ = signal.cont2discrete((np.array(num), np.array(den)), ts, method="bilinear")
        b = np.atleast_1d(np.squeeze(b))
        a = np.atleast_1d(np.squeeze(a))
    else:
        b, a = _backward_diff(num, den, ts)
    b, a = b / a[0], a / a[0]
    b.setflags(write=False)
    a.setflags(write=False)
    return b, a


def _backward_diff(
    num: tuple[float, ...], den: tuple[float, ...], ts: float
) -> tuple[np.ndarray, np.ndarray]:
    # s^k -> ((1 - w)/Ts)^k with w = z^-1; multiply through by nothing: both
    # polynomials become polynomials in w of degree max(deg num, deg den).
    order = max(len(num), len(den)) - 1
    base = np.array([1.0, -1.0]) / ts  # (1 - w)/Ts, ascending powers of w

    def poly(coeffs: tuple[float, ...]) -> np.ndarray:
        out = np.zeros(order + 1)
        deg = len(coeffs) - 1
        for i, c in enumerate(coeffs):
            term = np.array([1.0])
            for _ in range(deg - i):
                term = np.convolve(term, base)
            out[: len(term)] += c * term
        return out

    return poly(num), poly(den)
