"""The project's own sympy functions: the guarded and piecewise elements.

Each is a :class:`sympy.Function` so printers can give it a ``_print_<Name>``
method (C, Python, LaTeX), and each evaluates on numbers exactly as the
simulator's guard in :mod:`edm_sym.core.elements.ops` does. :data:`SYMPY_OPS`
implements the elements' math interface over sympy expressions.
"""

from __future__ import annotations

import math
from typing import Any

import sympy as sp

from edm_sym.core.elements.ops import LOG_QUOTIENT_LIMIT, POW_INPUT_LIMIT, SCALAR, TAN_LIMIT


class _Numeric(sp.Function):
    """Evaluates to a Float when every argument is a number."""

    _scalar: Any = None

    @classmethod
    def eval(cls, *args: Any) -> Any:
        if all(a.is_number and a.is_real for a in args) and not any(
            isinstance(a, sp.Symbol) for a in args
        ):
            if all(isinstance(a, (sp.Float, sp.Integer, sp.Rational)) for a in args):
                return sp.Float(cls._scalar(*(float(a) for a in args)))
        return None


class Sat(_Numeric):
    """Saturation ``Sat(x, lo, hi) = min(max(x, lo), hi)``."""

    nargs = 3
    _scalar = staticmethod(SCALAR.sat)


class DeadZone(_Numeric):
    """Dead zone ``DeadZone(x, a)``: 0 on [-a, a], ``x -+ a`` outside."""

    nargs = 2
    _scalar = staticmethod(SCALAR.dead_zone)


class SymLog(_Numeric):
    """Guarded logarithm ``SymLog(x, a) = sign(x) ln(1 + min(|x|/a, LOG_QUOTIENT_LIMIT))``."""

    nargs = 2
    _scalar = staticmethod(SCALAR.sym_log)


class SymPow(_Numeric):
    """Signed power ``SymPow(x, a) = sign(x) min(|x|, POW_INPUT_LIMIT)^a``."""

    nargs = 2
    _scalar = staticmethod(SCALAR.sym_pow)


class GTan(_Numeric):
    """Guarded tangent: ``tan(x)``; ``+-TAN_LIMIT`` with the sign of ``sin x`` where it reaches that."""

    nargs = 1
    _scalar = staticmethod(SCALAR.tan)


class GAsin(_Numeric):
    """Guarded arcsine: ``asin(Sat(x, -1, 1))``."""

    nargs = 1
    _scalar = staticmethod(SCALAR.asin)


class GAcos(_Numeric):
    """Guarded arccosine: ``acos(Sat(x, -1, 1))``."""

    nargs = 1
    _scalar = staticmethod(SCALAR.acos)


class SympyOps:
    """The elements' math interface over sympy expressions."""

    pi = sp.pi
    sin = staticmethod(sp.sin)
    atan = staticmethod(sp.atan)
    tanh = staticmethod(sp.tanh)
    sign = staticmethod(sp.sign)
    tan = staticmethod(GTan)
    asin = staticmethod(GAsin)
    acos = staticmethod(GAcos)
    dead_zone = staticmethod(DeadZone)
    sym_log = staticmethod(SymLog)
    sym_pow = staticmethod(SymPow)

    @staticmethod
    def sat(x: Any, lo: Any, hi: Any) -> Any:
        return Sat(x, lo, hi)

    @staticmethod
    def lower_limit(x: Any, lo: Any) -> Any:
        return sp.Max(x, lo)


SYMPY_OPS = SympyOps()

#: numpy implementations, for ``sympy.lambdify(..., modules=[NUMPY_FUNCTIONS, "numpy"])``:
#: the simulator's, and its transcendental functions (the C library's, not numpy's own:
#: :mod:`edm_sym.core.elements.libm`), so an expression gives the simulator's bits.
NUMPY_FUNCTIONS: dict[str, Any] = {}


def _numpy_functions() -> dict[str, Any]:
    from edm_sym.core.elements import libm
    from edm_sym.core.elements.ops import NUMPY

    return {
        "Sat": NUMPY.sat, "DeadZone": NUMPY.dead_zone, "SymLog": NUMPY.sym_log,
        "SymPow": NUMPY.sym_pow, "GTan": NUMPY.tan, "GAsin": NUMPY.asin, "GAcos": NUMPY.acos,
        "sin": libm.sin, "cos": libm.cos, "tan": libm.tan, "asin": libm.asin,
        "acos": libm.acos, "atan": libm.atan, "tanh": libm.tanh, "log1p": libm.log1p,
    }


NUMPY_FUNCTIONS.update(_numpy_functions())
GUARD_CONSTANTS = {"TAN_LIMIT": TAN_LIMIT, "POW_INPUT_LIMIT": POW_INPUT_LIMIT,
                   "LOG_QUOTIENT_LIMIT": LOG_QUOTIENT_LIMIT, "pi": math.pi}
