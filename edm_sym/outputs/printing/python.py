"""Python printing of the symbolic model for the standalone module (standard library only).

:class:`EdmPythonPrinter` is SymPy's :class:`~sympy.printing.pycode.PythonCodePrinter`
with the project's own functions printed as calls of small module-level
helpers (``_sat``, ``_sym_log``, ...) whose bodies are those of
:class:`edm_sym.core.elements.ops.ScalarOps`, so the generated module applies the
simulator's guards. Floats print as their shortest exact ``repr``. Like the C
printer, it also writes the statements of the dynamic stages.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from typing import Any

import sympy as sp
from sympy.printing.pycode import PythonCodePrinter

from edm_sym.core.elements.ops import LOG_QUOTIENT_LIMIT, POW_INPUT_LIMIT, TAN_LIMIT
from edm_sym.outputs.printing.helpers import HelperCalls, StageLines

# name -> (helpers it calls, parameters, body lines); bodies are ScalarOps'.
_HELPERS: dict[str, tuple[tuple[str, ...], str, tuple[str, ...]]] = {
    "sign": ((), "x", ("return 1.0 if x > 0 else (-1.0 if x < 0 else 0.0)",)),
    "sat": ((), "x, lo, hi", ("return lo if x < lo else (hi if x > hi else x)",)),
    "dead_zone": ((), "x, a", ("return x - a if x > a else (x + a if x < -a else 0.0)",)),
    "sym_log": (("sign",), "x, a", ("return _sign(x) * math.log1p(min(abs(x) / a, _LOG_QUOTIENT_LIMIT))",)),
    "sym_pow": (("sign",), "x, a", ("return _sign(x) * min(abs(x), _POW_INPUT_LIMIT) ** a",)),
    "tan": ((), "x", ("t = math.tan(x)",
                      "if abs(t) >= _TAN_LIMIT:",
                      "    return -_TAN_LIMIT if math.sin(x) < 0 else _TAN_LIMIT",
                      "return t")),
    "asin": (("sat",), "x", ("return math.asin(_sat(x, -1.0, 1.0))",)),
    "acos": (("sat",), "x", ("return math.acos(_sat(x, -1.0, 1.0))",)),
}

#: Module constants the helpers read: name -> value.
HELPER_CONSTANTS = {"_TAN_LIMIT": TAN_LIMIT, "_POW_INPUT_LIMIT": POW_INPUT_LIMIT,
                    "_LOG_QUOTIENT_LIMIT": LOG_QUOTIENT_LIMIT}


def py_literal(value: float) -> str:
    """The shortest Python literal that reads back as ``value`` exactly."""
    v = float(value)
    if not math.isfinite(v):
        raise ValueError(f"a Python literal: expected a finite number, found {v!r}")
    return repr(v)


class EdmPythonPrinter(HelperCalls, StageLines, PythonCodePrinter):
    """Python printer for edm_sym expressions using only the ``math`` module.

    Attributes
    ----------
    helpers_used : set of str
        The guard helpers printed so far; see :meth:`helper_definitions`.

    Examples
    --------
    >>> import sympy as sp
    >>> from edm_sym.engines.symbolic.functions import Sat
    >>> x = sp.Symbol("x")
    >>> EdmPythonPrinter().doprint(Sat(x, -0.5, 0.5))
    '_sat(x, -0.5, 0.5)'
    """

    def __init__(self, settings: dict[str, Any] | None = None):
        super().__init__(dict(settings or {}, standard="python3"))
        self.helpers_used: set[str] = set()

    def literal(self, value: float) -> str:
        """See :func:`py_literal`."""
        return py_literal(value)

    def operand(self, value: float) -> str:
        """:meth:`literal`, parenthesised when negative."""
        text = py_literal(value)
        return f"({text})" if text.startswith("-") else text

    def _print_Float(self, expr: sp.Float) -> str:
        return py_literal(float(expr))

    def _print_Rational(self, expr: sp.Rational) -> str:
        return py_literal(float(expr))

    # -- the project's functions ----------------------------------------------
    def helper_symbol(self, name: str) -> str:
        return f"_{name}"

    def _print_Max(self, expr: sp.Expr) -> str:
        return f"max({', '.join(self._print(a) for a in expr.args)})"

    def _print_Min(self, expr: sp.Expr) -> str:
        return f"min({', '.join(self._print(a) for a in expr.args)})"

    # -- helpers ----------------------------------------------------------------
    def helper_definitions(self, names: Iterable[str] | None = None) -> list[str]:
        """The module-level ``def`` of each guard helper in ``names`` (default: those used).

        Helpers they call are added; the order is fixed (callees first).
        """
        wanted = self.helpers_wanted(names, _HELPERS)
        return ["\n".join([f"def _{name}({params}):", *(f"    {b}" for b in body)])
                for name, (_, params, body) in _HELPERS.items() if name in wanted]

    def helper_constants(self, definitions: Sequence[str]) -> list[str]:
        """``NAME = value`` lines for the constants the helper ``definitions`` read."""
        text = "\n".join(definitions)
        return [f"{k} = {py_literal(v)}" for k, v in HELPER_CONSTANTS.items() if k in text]

    def uses_math(self, code: Iterable[str]) -> bool:
        """True when any of the ``code`` strings calls the ``math`` module."""
        return any("math." in c for c in code)

    # -- statements ------------------------------------------------------------
    def assign(self, var: str, expr: sp.Expr) -> list[str]:
        """``var = expr``, or nothing when ``expr`` is ``var`` itself."""
        text = self.doprint(expr)
        return [] if text == var else [f"{var} = {text}"]

    def linear_lines(self, b: Sequence[float], a: Sequence[float], z: str,
                     x: str = "x") -> list[str]:
        """One sample of a direct form II transposed filter, as scipy's lfilter runs it.

        ``z`` is the attribute holding the state list (``self._r1_e2_z``).
        """
        n = len(a) - 1
        if len(b) != len(a) or n < 1:
            raise ValueError(f"filter: expected b and a of one length >= 2, found {len(b)}, {len(a)}")
        op = self.operand
        lines = [f"z = {z}", f"y = {py_literal(b[0])} * {x} + z[0]"]
        for i in range(n - 1):
            lines.append(f"z[{i}] = z[{i + 1}] + {x} * {op(b[i + 1])} - y * {op(a[i + 1])}")
        lines += [f"z[{n - 1}] = {x} * {op(b[n])} - y * {op(a[n])}", f"{x} = y"]
        return lines

    def delay_lines(self, samples: int, buf: str, pos: str | None, x: str = "x") -> list[str]:
        """One sample of a ring-buffer delay (``pos`` None when ``samples == 1``)."""
        if samples < 1:
            raise ValueError(f"delay: expected at least 1 sample, found {samples}")
        if samples == 1:
            return [f"buf = {buf}", f"{x}, buf[0] = buf[0], {x}"]
        if pos is None:
            raise ValueError("delay: a ring buffer longer than 1 needs an index")
        return [f"buf = {buf}", f"k = {pos}", f"{x}, buf[k] = buf[k], {x}",
                f"{pos} = k + 1 if k + 1 < {samples} else 0"]

    def relay_lines(self, threshold: float, out: str, x: str = "x") -> list[str]:
        """Relay with hysteresis: +1 once ``x >= a``, -1 once ``x <= -a``, else held."""
        return [f"if {x} >= {py_literal(threshold)}:", f"    {out} = 1.0",
                f"elif {x} <= {py_literal(-threshold)}:", f"    {out} = -1.0",
                f"{x} = {out}"]

    def state_ref(self, name: str) -> str:
        """The attribute holding state member ``name`` (``self._name``)."""
        return f"self._{name}"

    def empty_body(self) -> list[str]:
        """The body of a method with nothing to do."""
        return ["pass"]

    def zero_state(self, attr: str, size: int | None) -> str:
        """``attr = [0.0] * size`` (a list of reals) or ``attr = 0`` (an index, size None)."""
        return f"{attr} = 0" if size is None else f"{attr} = [0.0] * {size}"

    def string(self, text: str) -> str:
        """A Python string literal of ``text``."""
        return repr(str(text))

    def tuple_of(self, items: Sequence[str]) -> str:
        """A tuple display of already printed ``items``: ``(a, b)``, ``(a,)`` or ``()``."""
        if len(items) == 1:
            return f"({items[0]},)"
        return f"({', '.join(items)})"
