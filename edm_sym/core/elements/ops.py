"""The small math interface that static elements are written against.

A static element's function ``f(m, x, a)`` only calls the methods below, so
one definition runs on numpy arrays (:data:`NUMPY`, the simulator), on Python
floats (:data:`SCALAR`, the plain per-sample loop) and on sympy symbols (the
symbolic layer supplies its own implementation with the same names). The
domain guards live here, so every backend applies the same ones.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

#: |tan| is limited to this value, so the tangent's poles give a finite output. Where
#: |tan x| reaches it (within about 1e-6 rad of a pole), the output is this value with the
#: sign of sin x: the same on both sides of the pole, so a phase that lands on the pole
#: (tan_phase at p = 0 or 1 is tan(-+pi/2)) gives one answer in double and in float,
#: although pi/2 rounds to either side of the pole in the two precisions.
TAN_LIMIT = 1.0e6
#: |x| is limited to this value before a power, so no power overflows.
POW_INPUT_LIMIT = 1.0e6
#: The largest exponent of a power (of any range): 1e6 ** 48 = 1e288, which a gain of up
#: to 1e12 keeps finite. A negative exponent is infinite at x = 0, so the smallest is 0.
POW_EXPONENT_LIMIT = 48.0
#: |x| / a is limited to this value before the guarded logarithm, so the quotient of a
#: large input by a small scale never overflows (in float it would above 3.4e38).
LOG_QUOTIENT_LIMIT = 1.0e30


def libm_tanh(x: Any, out: np.ndarray | None = None) -> Any:
    """tanh as the C library computes it (fdlibm's ``s_tanh.c``), over arrays, to the bit.

    numpy's own float64 tanh is a vectorised approximation that differs from the
    C library's in the last bit on about a quarter of the arguments. The
    generated C and the Python module call the C library's tanh; a chain that
    amplifies a last bit (``tanh`` then ``acos`` near 1, a sharp notch) made
    them differ from the simulator by 1.5e-8. This is fdlibm's algorithm on
    ``numpy.expm1`` (the C library's expm1): ``1 - 2 / (expm1(2|x|) + 2)`` from
    |x| = 1, ``-t / (t + 2)`` with ``t = expm1(-2|x|)`` below, ``x (1 + x)``
    below 2**-55, exactly 1 from 22, with the sign of x. tests/test_elements.py
    checks it against ``math.tanh`` on millions of arguments.
    """
    x = np.asarray(x, dtype=float)
    ax = np.abs(x)
    big = ax >= 1.0
    with np.errstate(over="ignore", invalid="ignore"):
        t = np.expm1(np.where(big, 2.0 * ax, -2.0 * ax))
        z = np.where(big, 1.0 - 2.0 / (t + 2.0), -t / (t + 2.0))
        z = np.where(ax < 2.0**-55, ax * (1.0 + ax), z)
    z = np.where(ax >= 22.0, 1.0, z)
    return np.copysign(z, x, out=out)


class NumpyOps:
    """Vectorised implementation over numpy arrays."""

    pi = math.pi

    @staticmethod
    def sin(x: Any) -> Any:
        return np.sin(x)

    @staticmethod
    def atan(x: Any) -> Any:
        return np.arctan(x)

    @staticmethod
    def tanh(x: Any) -> Any:
        return libm_tanh(x)

    @staticmethod
    def sign(x: Any) -> Any:
        return np.sign(x)

    @staticmethod
    def sat(x: Any, lo: float, hi: float) -> Any:
        """Saturation: ``x`` limited to [lo, hi]."""
        return np.clip(x, lo, hi)

    @staticmethod
    def lower_limit(x: Any, lo: float) -> Any:
        """One-sided limiter: ``max(x, lo)``."""
        return np.maximum(x, lo)

    @staticmethod
    def dead_zone(x: Any, a: float) -> Any:
        """0 inside [-a, a], ``x -+ a`` outside (continuous)."""
        return np.where(x > a, x - a, np.where(x < -a, x + a, 0.0))

    @staticmethod
    def sym_log(x: Any, a: float) -> Any:
        """Guarded logarithm: ``sign(x) ln(1 + min(|x| / a, LOG_QUOTIENT_LIMIT))``, odd and finite."""
        return np.sign(x) * np.log1p(np.minimum(np.abs(x) / a, LOG_QUOTIENT_LIMIT))

    @staticmethod
    def sym_pow(x: Any, a: float) -> Any:
        """Signed power: ``sign(x) min(|x|, POW_INPUT_LIMIT) ** a``."""
        return np.sign(x) * np.minimum(np.abs(x), POW_INPUT_LIMIT) ** a

    @staticmethod
    def tan(x: Any) -> Any:
        """Guarded tangent: ``tan(x)``; where ``|tan x| >= TAN_LIMIT``, that limit signed as ``sin x``."""
        t = np.tan(x)
        return np.where(np.abs(t) >= TAN_LIMIT, np.where(np.sin(x) < 0, -TAN_LIMIT, TAN_LIMIT), t)

    @staticmethod
    def asin(x: Any) -> Any:
        """Guarded arcsine: the input is first limited to [-1, 1]."""
        return np.arcsin(np.clip(x, -1.0, 1.0))

    @staticmethod
    def acos(x: Any) -> Any:
        """Guarded arccosine: the input is first limited to [-1, 1]."""
        return np.arccos(np.clip(x, -1.0, 1.0))


def _sign(x: float) -> float:
    return 1.0 if x > 0 else (-1.0 if x < 0 else 0.0)


def _clip(x: float, lo: float, hi: float) -> float:
    return lo if x < lo else (hi if x > hi else x)


class ScalarOps:
    """Per-sample implementation over Python floats (the plain loop)."""

    pi = math.pi
    sin = staticmethod(math.sin)
    atan = staticmethod(math.atan)
    tanh = staticmethod(math.tanh)
    sign = staticmethod(_sign)
    sat = staticmethod(_clip)

    @staticmethod
    def lower_limit(x: float, lo: float) -> float:
        return x if x > lo else lo

    @staticmethod
    def dead_zone(x: float, a: float) -> float:
        return x - a if x > a else (x + a if x < -a else 0.0)

    @staticmethod
    def sym_log(x: float, a: float) -> float:
        return _sign(x) * math.log1p(min(abs(x) / a, LOG_QUOTIENT_LIMIT))

    @staticmethod
    def sym_pow(x: float, a: float) -> float:
        return _sign(x) * min(abs(x), POW_INPUT_LIMIT) ** a

    @staticmethod
    def tan(x: float) -> float:
        t = math.tan(x)
        if abs(t) >= TAN_LIMIT:
            return -TAN_LIMIT if math.sin(x) < 0 else TAN_LIMIT
        return t

    @staticmethod
    def asin(x: float) -> float:
        return math.asin(_clip(x, -1.0, 1.0))

    @staticmethod
    def acos(x: float) -> float:
        return math.acos(_clip(x, -1.0, 1.0))


NUMPY = NumpyOps()
SCALAR = ScalarOps()
