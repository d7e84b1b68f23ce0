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

from edm_sym.core.elements import libm

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


class NumpyOps:
    """Vectorised implementation over numpy arrays.

    The transcendental functions are the C library's (:mod:`~edm_sym.core.elements.libm`),
    as the generated C and Python call them, not numpy's own vectorised ones: the
    same bits on any processor.
    """

    pi = math.pi

    @staticmethod
    def sin(x: Any) -> Any:
        return libm.sin(x)

    @staticmethod
    def atan(x: Any) -> Any:
        return libm.atan(x)

    @staticmethod
    def tanh(x: Any) -> Any:
        return libm.tanh(x)

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
        return np.sign(x) * libm.log1p(np.minimum(np.abs(x) / a, LOG_QUOTIENT_LIMIT))

    @staticmethod
    def sym_pow(x: Any, a: float) -> Any:
        """Signed power: ``sign(x) min(|x|, POW_INPUT_LIMIT) ** a``."""
        return np.sign(x) * libm.pow(np.minimum(np.abs(x), POW_INPUT_LIMIT), a)

    @staticmethod
    def tan(x: Any) -> Any:
        """Guarded tangent: ``tan(x)``; where ``|tan x| >= TAN_LIMIT``, that limit signed as ``sin x``."""
        t = libm.tan(x)
        return np.where(np.abs(t) >= TAN_LIMIT, np.where(libm.sin(x) < 0, -TAN_LIMIT, TAN_LIMIT), t)

    @staticmethod
    def asin(x: Any) -> Any:
        """Guarded arcsine: the input is first limited to [-1, 1]."""
        return libm.asin(np.clip(x, -1.0, 1.0))

    @staticmethod
    def acos(x: Any) -> Any:
        """Guarded arccosine: the input is first limited to [-1, 1]."""
        return libm.acos(np.clip(x, -1.0, 1.0))


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
