"""C99 printing of the symbolic model: expressions, guard helpers and stage statements.

:class:`EdmC99Printer` is SymPy's :class:`~sympy.printing.c.C99CodePrinter`
with one real type (``float`` or ``double``) throughout: literals carry the
type's suffix, math functions the type's name (``sinf`` for float), and the
project's own functions (:mod:`edm_sym.engines.symbolic.functions`) print as calls of
small pure ``static inline`` helpers whose bodies repeat the simulator's guards
(:mod:`edm_sym.core.elements.ops`) operation for operation.

Besides expressions, the printer writes the few statements a stage needs
(direct form II transposed filters, ring buffers, the relay) from plain
numbers and names, so no other module spells C.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable, Sequence
from typing import Any

import numpy as np
import sympy as sp
from sympy.codegen.ast import float32, float64, real
from sympy.printing.c import C99CodePrinter

from edm_sym.core.elements.ops import LOG_QUOTIENT_LIMIT, POW_INPUT_LIMIT, TAN_LIMIT
from edm_sym.outputs.printing.helpers import HelperCalls, StageLines

#: The real types a compensator can be printed in.
REALS = ("float", "double")

#: Significant digits that make a literal read back as the same value.
DIGITS = {"double": 17, "float": 9}

#: C89/C99 keywords: a prefix may not be one of them.
C_KEYWORDS = frozenset(
    "auto break case char const continue default do double else enum extern float for goto "
    "if inline int long register restrict return short signed sizeof static struct switch "
    "typedef union unsigned void volatile while _Bool _Complex _Imaginary".split()
)

_IDENTIFIER = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")

# Guard helpers: name -> (helpers it calls, parameter list, body lines). In them
# {R} is the real type, {P} the prefix, {f} the math-function suffix and the
# other fields real literals; every body mirrors edm_sym.core.elements.ops.ScalarOps.
_HELPERS: dict[str, tuple[tuple[str, ...], str, tuple[str, ...]]] = {
    "sign": ((), "{R} x", (
        "return (x > {zero}) ? {one} : ((x < {zero}) ? {m1} : {zero});",
    )),
    "sat": ((), "{R} x, {R} lo, {R} hi", (
        "return (x < lo) ? lo : ((x > hi) ? hi : x);",
    )),
    "dead_zone": ((), "{R} x, {R} a", (
        "return (x > a) ? (x - a) : ((x < -a) ? (x + a) : {zero});",
    )),
    "sym_log": (("sign",), "{R} x, {R} a", (
        "const {R} q = fabs{f}(x) / a;",
        "return {P}_sign(x) * log1p{f}((q < {log_limit}) ? q : {log_limit});",
    )),
    "sym_pow": (("sign",), "{R} x, {R} a", (
        "const {R} m = fabs{f}(x);",
        "return {P}_sign(x) * pow{f}((m < {pow_limit}) ? m : {pow_limit}, a);",
    )),
    # At a pole the sign of sin x decides, not the side pi/2 rounds to (ops.TAN_LIMIT).
    "tan": ((), "{R} x", (
        "const {R} t = tan{f}(x);",
        "return (fabs{f}(t) >= {tan_limit}) ? ((sin{f}(x) < {zero}) ? {m_tan_limit} : {tan_limit}) : t;",
    )),
    "asin": (("sat",), "{R} x", (
        "return asin{f}({P}_sat(x, {m1}, {one}));",
    )),
    "acos": (("sat",), "{R} x", (
        "return acos{f}({P}_sat(x, {m1}, {one}));",
    )),
}


def is_c_identifier(name: str) -> bool:
    """True when ``name`` is a C identifier and not a keyword."""
    return bool(_IDENTIFIER.match(name)) and name not in C_KEYWORDS


def c_comment_text(text: str) -> str:
    """``text`` made safe inside a ``/* ... */`` comment (one line)."""
    text = str(text).replace("*/", "* /").replace("/*", "/ *")
    return re.sub(r"\s", " ", text).rstrip()


class EdmC99Printer(HelperCalls, StageLines, C99CodePrinter):
    """C99 printer for edm_sym expressions in one real type.

    Parameters
    ----------
    settings : dict, optional
        SymPy printer settings plus ``real`` (``"float"`` or ``"double"``,
        default ``"double"``) and ``prefix`` (the C identifier that names the
        guard helpers, default ``"edm_comp"``).

    Attributes
    ----------
    helpers_used : set of str
        The guard helpers (``"sat"``, ``"sign"``, ...) printed so far; see
        :meth:`helper_definitions`.

    Examples
    --------
    >>> import sympy as sp
    >>> x = sp.Symbol("x")
    >>> EdmC99Printer({"real": "float"}).doprint(sp.Float(0.5) * sp.sin(x))
    '0.5f*sinf(x)'
    """

    _default_settings: dict[str, Any] = dict(
        C99CodePrinter._default_settings, real="double", prefix="edm_comp"
    )

    def __init__(self, settings: dict[str, Any] | None = None):
        settings = dict(settings or {})
        kind = settings.get("real", "double")
        if kind not in REALS:
            raise ValueError(f"real: expected one of {', '.join(REALS)}, found {kind!r}")
        prefix = settings.get("prefix", "edm_comp")
        if not is_c_identifier(prefix):
            raise ValueError(f"prefix: expected a C identifier, found {prefix!r}")
        settings["type_aliases"] = {real: float32 if kind == "float" else float64}
        super().__init__(settings)
        self.real = kind
        self.prefix = prefix
        self.helpers_used: set[str] = set()

    # -- numbers ---------------------------------------------------------------
    @property
    def real_t(self) -> str:
        """The name of the compensator's real typedef (``edm_comp_real_t``)."""
        return f"{self.prefix}_real_t"

    @property
    def func_suffix(self) -> str:
        """``"f"`` for float (``sinf``), empty for double."""
        return "f" if self.real == "float" else ""

    def literal(self, value: float) -> str:
        """A real literal that reads back as ``value`` in the printer's type.

        Doubles get 17 significant digits, floats the nearest float's 9 digits
        and the ``f`` suffix, so the compiler sees exactly the value intended.
        """
        v = float(value)
        if not math.isfinite(v):
            raise ValueError(f"a C literal: expected a finite number, found {v!r}")
        if self.real == "float":
            v = float(np.float32(v))
        text = format(v, f".{DIGITS[self.real]}g")
        if not any(c in text for c in ".en"):
            text += ".0"
        return text + ("f" if self.real == "float" else "")

    def operand(self, value: float) -> str:
        """:meth:`literal`, parenthesised when negative (an operand of ``*`` or ``-``)."""
        text = self.literal(value)
        return f"({text})" if text.startswith("-") else text

    def _print_Float(self, expr: sp.Float) -> str:
        return self.literal(float(expr))

    def _print_Integer(self, expr: sp.Integer) -> str:
        return self.literal(float(expr))

    def _print_Rational(self, expr: sp.Rational) -> str:
        return self.literal(float(expr))

    # -- the project's functions ----------------------------------------------
    def helper_symbol(self, name: str) -> str:
        return f"{self.prefix}_{name}"

    def _fold(self, function: str, expr: sp.Expr) -> str:
        args = [self._print(a) for a in expr.args]
        out = args[0]
        for a in args[1:]:
            out = f"{function}{self.func_suffix}({out}, {a})"
        return out

    def _print_Max(self, expr: sp.Expr) -> str:
        # fmax(a, b) equals numpy.maximum for every non-NaN pair.
        return self._fold("fmax", expr)

    def _print_Min(self, expr: sp.Expr) -> str:
        return self._fold("fmin", expr)

    # -- helper definitions ----------------------------------------------------
    def helper_definitions(self, names: Iterable[str] | None = None) -> list[str]:
        """The ``static inline`` definitions of the guard helpers ``names``.

        Parameters
        ----------
        names : iterable of str, optional
            Helper names; default :attr:`helpers_used`. Helpers they call are
            added, and the definitions come in a fixed order (callees first).

        Returns
        -------
        list of str
            One multi-line C definition per helper.
        """
        wanted = self.helpers_wanted(names, _HELPERS)
        fmt = {
            "R": self.real_t, "P": self.prefix, "f": self.func_suffix,
            "zero": self.literal(0.0), "one": self.literal(1.0), "m1": self.literal(-1.0),
            "tan_limit": self.literal(TAN_LIMIT), "m_tan_limit": self.literal(-TAN_LIMIT),
            "pow_limit": self.literal(POW_INPUT_LIMIT), "log_limit": self.literal(LOG_QUOTIENT_LIMIT),
        }
        out = []
        for name, (_, params, body) in _HELPERS.items():
            if name in wanted:
                lines = [f"static inline {self.real_t} {self.prefix}_{name}({params.format(**fmt)})",
                         "{", *(f"    {b.format(**fmt)}" for b in body), "}"]
                out.append("\n".join(lines))
        return out

    # -- statements ------------------------------------------------------------
    def assign(self, var: str, expr: sp.Expr) -> list[str]:
        """``var = expr;``, or nothing when ``expr`` is ``var`` itself."""
        text = self.doprint(expr)
        return [] if text == var else [f"{var} = {text};"]

    def linear_lines(self, b: Sequence[float], a: Sequence[float], z: str,
                     x: str = "x") -> list[str]:
        """One sample of a direct form II transposed filter, as scipy's lfilter runs it.

        ``y = b0 x + z0``; ``z_i = z_{i+1} + x b_{i+1} - y a_{i+1}``;
        ``z_{n-1} = x b_n - y a_n``, with ``a[0] == 1``. The lines open a
        block that ends with ``x = y;``.

        Parameters
        ----------
        b, a : sequence of float
            The discrete coefficients (z^-1 powers), padded to one length.
        z : str
            The C lvalue of the state array (``s->r1_e2_z``).
        x : str
            The variable holding the input, which receives the output.
        """
        n = len(a) - 1
        if len(b) != len(a) or n < 1:
            raise ValueError(f"filter: expected b and a of one length >= 2, found {len(b)}, {len(a)}")
        lit, op = self.literal, self.operand
        lines = ["{", f"    const {self.real_t} y = {lit(b[0])} * {x} + {z}[0];"]
        for i in range(n - 1):
            lines.append(f"    {z}[{i}] = {z}[{i + 1}] + {x} * {op(b[i + 1])} - y * {op(a[i + 1])};")
        lines.append(f"    {z}[{n - 1}] = {x} * {op(b[n])} - y * {op(a[n])};")
        lines += [f"    {x} = y;", "}"]
        return lines

    def delay_lines(self, samples: int, buf: str, pos: str | None, x: str = "x") -> list[str]:
        """One sample of a ring-buffer delay of ``samples`` samples (oldest value out).

        ``pos`` is the C lvalue of the read/write index; None when
        ``samples == 1`` (a single cell needs none).
        """
        if samples < 1:
            raise ValueError(f"delay: expected at least 1 sample, found {samples}")
        if samples == 1:
            return ["{", f"    const {self.real_t} y = {buf}[0];", f"    {buf}[0] = {x};",
                    f"    {x} = y;", "}"]
        if pos is None:
            raise ValueError("delay: a ring buffer longer than 1 needs an index")
        return ["{", f"    const {self.real_t} y = {buf}[{pos}];", f"    {buf}[{pos}] = {x};",
                f"    {pos} = ({pos} + 1u < {samples}u) ? {pos} + 1u : 0u;",
                f"    {x} = y;", "}"]

    def relay_lines(self, threshold: float, out: str, x: str = "x") -> list[str]:
        """Relay with hysteresis: +1 once ``x >= a``, -1 once ``x <= -a``, else held."""
        return [f"if ({x} >= {self.literal(threshold)}) {{",
                f"    {out} = {self.literal(1.0)};",
                f"}} else if ({x} <= {self.literal(-threshold)}) {{",
                f"    {out} = {self.literal(-1.0)};",
                "}", f"{x} = {out};"]

    # -- declarations ----------------------------------------------------------
    def state_ref(self, name: str) -> str:
        """The lvalue of state member ``name`` inside init and step (``s->name``)."""
        return f"s->{name}"

    def declare_placeholder(self, comment: str) -> str:
        """The member of a state struct with nothing to hold (C99 has no empty structs)."""
        return f"uint8_t unused;  /* {c_comment_text(comment)} */"

    def zero_placeholder(self) -> list[str]:
        """Init's line for :meth:`declare_placeholder`."""
        return [f"{self.state_ref('unused')} = 0u;"]

    def loop_index(self) -> list[str]:
        """Declaration of the index :meth:`zero_real_array` loops use."""
        return ["size_t i;"]

    def state_unused(self) -> list[str]:
        """Marks the state argument of a stateless step as deliberately unused."""
        return ["(void)s;"]

    def declare_real_array(self, name: str, size: int, comment: str) -> str:
        """A struct member line for ``size`` reals."""
        return f"{self.real_t} {name}[{size}];  /* {c_comment_text(comment)} */"

    def declare_index(self, name: str, comment: str) -> str:
        """A struct member line for a ring-buffer index."""
        return f"size_t {name};  /* {c_comment_text(comment)} */"

    def zero_real_array(self, lvalue: str, size: int) -> list[str]:
        """Lines setting ``size`` reals to zero (a loop over index ``i``)."""
        if size == 1:
            return [f"{lvalue}[0] = {self.literal(0.0)};"]
        return [f"for (i = 0u; i < {size}u; ++i) {{", f"    {lvalue}[i] = {self.literal(0.0)};",
                "}"]

    def zero_index(self, lvalue: str) -> list[str]:
        """A line setting a ring-buffer index to zero."""
        return [f"{lvalue} = 0u;"]
