"""Discrete-time realisations: the one place continuous forms become difference equations.

The simulator, the genetic algorithm, the python-control systems, the
generated C and Python and the report all read the coefficients made here;
there is no second path.

The method is a substitution for s, made directly in the polynomials (no
state-space round trip, so it is cheap enough for the genetic algorithm, which
discretises a new filter for almost every row it simulates)::

    bilinear       s = (2/Ts) (1 - w) / (1 + w)      (Tustin)
    backward_diff  s = (1 - w) / Ts

with w = z^-1. Multiplying numerator and denominator by the substitution's
denominator raised to the order gives two polynomials in w; dividing both by
the constant term of the denominator makes ``a[0] == 1``. The tests check the
result against :func:`scipy.signal.cont2discrete` as an independent oracle.
"""

from __future__ import annotations

from collections.abc import Sequence
from functools import lru_cache

import numpy as np

#: Discretisation methods, with the text the documentation and headers print.
METHODS = {
    "bilinear": "Tustin (bilinear), s = (2/Ts) (z - 1)/(z + 1)",
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
        ``"bilinear"`` is Tustin's substitution (proper functions);
        ``"backward_diff"`` substitutes s = (1 - z^-1)/Ts, which also realises
        improper forms such as a pure derivative.

    Returns
    -------
    b, a : numpy.ndarray
        Coefficients in ascending powers of z^-1 with ``a[0] == 1``, both of
        length ``max(len(num), len(den))`` (read-only: they are cached).

    Raises
    ------
    ValueError
        On an unknown method.
    """
    return _discretize(tuple(map(float, num)), tuple(map(float, den)), float(ts), method)


@lru_cache(maxsize=65536)
def _discretize(
    num: tuple[float, ...], den: tuple[float, ...], ts: float, method: str
) -> tuple[np.ndarray, np.ndarray]:
    if method == "bilinear":
        c = 2.0 / ts
        s_num, s_den = [c, -c], [1.0, 1.0]
    elif method == "backward_diff":
        s_num, s_den = [1.0 / ts, -1.0 / ts], [1.0]
    else:
        raise ValueError(f"method: expected one of {sorted(METHODS)}, found {method!r}")
    order = max(len(num), len(den)) - 1
    b = _substitute(num, order, s_num, s_den)
    d = _substitute(den, order, s_num, s_den)
    a0 = d[0]
    b_arr, a_arr = np.array(b) / a0, np.array(d) / a0
    b_arr.setflags(write=False)
    a_arr.setflags(write=False)
    return b_arr, a_arr


def _poly_mul(p: list[float], q: list[float]) -> list[float]:
    out = [0.0] * (len(p) + len(q) - 1)
    for i, a in enumerate(p):
        for j, b in enumerate(q):
            out[i + j] += a * b
    return out


def _poly_pow(p: list[float], k: int) -> list[float]:
    out = [1.0]
    for _ in range(k):
        out = _poly_mul(out, p)
    return out


def _substitute(coeffs: tuple[float, ...], order: int, num_w: list[float],
                den_w: list[float]) -> list[float]:
    """``sum c_i s^d_i`` with s = num_w(w) / den_w(w), times den_w^order, in powers of w."""
    out = [0.0] * (order + 1)
    deg = len(coeffs) - 1
    for i, c in enumerate(coeffs):
        d = deg - i
        if c == 0.0:
            continue
        for k, t in enumerate(_term(tuple(num_w), tuple(den_w), order, d)):
            out[k] += c * t
    return out


@lru_cache(maxsize=256)
def _term(num_w: tuple[float, ...], den_w: tuple[float, ...], order: int, d: int
          ) -> tuple[float, ...]:
    # num_w^d den_w^(order - d): the same for every parameter value (the GA's misses).
    return tuple(_poly_mul(_poly_pow(list(num_w), d), _poly_pow(list(den_w), order - d)))
