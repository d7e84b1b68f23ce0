"""LaTeX printing for the model report: expressions, numbers, units and text.

:class:`EdmLatexPrinter` is SymPy's ``LatexPrinter`` with the project's own
functions (saturation, dead zone, guarded log and power, ...), the operators
with memory (``LTI``, ``Delay``, ``Relay``), a fixed number of significant
digits, and the small pieces of LaTeX the report needs besides expressions:
numbers for tables, SI units, escaped text and difference equations. Nothing
else in edm_sym writes LaTeX syntax.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping, Sequence
from typing import Any

import sympy as sp
from sympy.printing.latex import LatexPrinter

#: Characters LaTeX treats specially in text, with their escaped forms.
_TEXT_ESCAPES = {
    "\\": r"\textbackslash{}", "&": r"\&", "%": r"\%", "$": r"\$", "#": r"\#", "_": r"\_",
    "{": r"\{", "}": r"\}", "~": r"\textasciitilde{}", "^": r"\textasciicircum{}",
    "<": r"\textless{}", ">": r"\textgreater{}",
}
_TEXT_RE = re.compile("|".join(re.escape(k) for k in _TEXT_ESCAPES))
_PLAIN_NAME = re.compile(r"[A-Za-z][A-Za-z0-9_]*")


def escape_text(text: str) -> str:
    """``text`` with every LaTeX special character escaped (for text mode).

    Parameters
    ----------
    text : str

    Returns
    -------
    str
    """
    return _TEXT_RE.sub(lambda m: _TEXT_ESCAPES[m.group(0)], str(text))


def format_number(value: float, digits: int = 4) -> str:
    """A number in LaTeX math: ``digits`` significant digits, ``m \\times 10^{e}`` when large or small.

    Parameters
    ----------
    value : float
    digits : int
        Significant digits (trailing zeros dropped).

    Returns
    -------
    str
        Math-mode LaTeX (``-0.95``, ``1.211 \\times 10^{3}``).
    """
    v = float(value)
    if math.isnan(v):
        return r"\mathrm{NaN}"
    if math.isinf(v):
        return r"\infty" if v > 0 else r"-\infty"
    text = f"{v:.{digits}g}"
    if "e" in text:
        mant, exp = text.split("e")
        return rf"{mant} \times 10^{{{int(exp)}}}"
    return text


class EdmLatexPrinter(LatexPrinter):
    """SymPy's LaTeX printer with the project's functions and operators.

    Parameters
    ----------
    settings : dict, optional
        SymPy printer settings, plus ``digits`` (significant digits of floats,
        default 4: equations read best that way; tables give more).
    """

    _default_settings: dict[str, Any] = {**LatexPrinter._default_settings, "digits": 4}

    def __init__(self, settings: dict[str, Any] | None = None):
        merged = {"full_prec": False, "min": -3, "max": 3}
        merged.update(settings or {})
        super().__init__(merged)

    # -- symbols and numbers -----------------------------------------------------
    def _print_Symbol(self, expr: Any, style: str = "plain") -> str:
        # Names beyond letters, digits and "_" (a log's column "tau%ext") would be LaTeX syntax.
        if expr in self._settings["symbol_names"] or _PLAIN_NAME.fullmatch(expr.name):
            return super()._print_Symbol(expr, style=style)
        return rf"\mathrm{{{escape_text(expr.name)}}}"

    def _print_Float(self, expr: Any) -> str:
        return format_number(float(expr), self._settings["digits"])

    def number(self, value: float) -> str:
        """``value`` as math-mode LaTeX with this printer's significant digits."""
        return format_number(value, self._settings["digits"])

    # -- the project's functions ------------------------------------------------
    def _fn(self, name: str, *args: Any) -> str:
        return rf"\operatorname{{{name}}}\left({', '.join(self._print(a) for a in args)}\right)"

    def _print_Sat(self, expr: Any) -> str:
        x, lo, hi = expr.args
        return self._fn("sat", x, lo, hi)

    def _print_DeadZone(self, expr: Any) -> str:
        return self._fn("dz", *expr.args)

    def _print_SymLog(self, expr: Any) -> str:
        x, a = expr.args
        return (rf"\operatorname{{sgn}}\left({self._print(x)}\right)"
                rf"\ln\left(1 + \frac{{\left|{self._print(x)}\right|}}{{{self._print(a)}}}\right)")

    def _print_SymPow(self, expr: Any) -> str:
        x, a = expr.args
        return (rf"\operatorname{{sgn}}\left({self._print(x)}\right)"
                rf"\left|{self._print(x)}\right|^{{{self._print(a)}}}")

    def _print_GTan(self, expr: Any) -> str:
        return rf"\tan\left({self._print(expr.args[0])}\right)"

    def _print_GAsin(self, expr: Any) -> str:
        return rf"\arcsin\left({self._print(expr.args[0])}\right)"

    def _print_GAcos(self, expr: Any) -> str:
        return rf"\arccos\left({self._print(expr.args[0])}\right)"

    def _print_sign(self, expr: Any) -> str:
        return rf"\operatorname{{sgn}}\left({self._print(expr.args[0])}\right)"

    # -- operators with memory ----------------------------------------------------
    def _print_LTI(self, expr: Any) -> str:
        x, G = expr.args  # noqa: N806
        return rf"\left\{{{self._print(G)}\right\}}\left[{self._print(x)}\right]"

    def _print_Delay(self, expr: Any) -> str:
        x, T = expr.args  # noqa: N806
        return rf"\left[{self._print(x)}\right]_{{t - {self._print(T)}}}"

    def _print_Relay(self, expr: Any) -> str:
        x, a = expr.args
        return rf"\operatorname{{relay}}_{{{self._print(a)}}}\left({self._print(x)}\right)"

    # -- pieces of the report -------------------------------------------------------
    def signed_terms(self, expr: sp.Expr) -> list[tuple[str, str]]:
        """The additive terms of ``expr`` as (sign, LaTeX of the term without its sign).

        The order is sympy's printing order, so the terms read as ``latex(expr)``.
        """
        expr = sp.sympify(expr)
        terms = list(self._as_ordered_terms(expr, order=None)) if expr.is_Add else [expr]
        out = []
        for t in terms:
            if t.could_extract_minus_sign():
                out.append(("-", self._print(-t)))
            else:
                out.append(("+", self._print(t)))
        return out

    def difference_equation(self, out: str, inp: str, b: Sequence[float],
                            a: Sequence[float]) -> str:
        """``out[k] = sum b_i inp[k-i] - sum a_i out[k-i]`` (``a[0] == 1``), zero terms left out.

        Parameters
        ----------
        out, inp : str
            LaTeX names of the output and input signals (without ``[k]``).
        b, a : sequence of float
            Coefficients in ascending powers of ``z^-1``.

        Returns
        -------
        str
            The right-hand side, math-mode LaTeX.
        """
        parts: list[tuple[float, str]] = []
        parts += [(float(c), rf"{inp}{_index(i)}") for i, c in enumerate(b)]
        parts += [(-float(c), rf"{out}{_index(i)}") for i, c in enumerate(a) if i > 0]
        parts = [(c, s) for c, s in parts if c != 0.0]
        if not parts:
            return "0"
        text = ""
        for c, sig in parts:
            sign = "-" if c < 0 else "+"
            mag = abs(c)
            coeff = "" if mag == 1.0 else self.number(mag) + r"\,"
            text += (f" {sign} " if text else ("-" if sign == "-" else "")) + coeff + sig
        return text

    def unit(self, unit: str) -> str:
        """An SI unit (``"N m s/rad"``, ``"kg m^2"``) in LaTeX math (``\\mathrm{N\\,m\\,s/rad}``).

        Dimensionless (``"1"`` or empty) gives ``"--"`` in text mode.
        """
        unit = unit.strip()
        if unit in ("", "1"):
            return "--"
        parts = [re.sub(r"\^(-?\d+)", r"}^{\1}\\mathrm{", p) for p in unit.split()]
        body = r"\,".join(parts)
        return rf"$\mathrm{{{body}}}$".replace(r"\mathrm{}", "")

    @staticmethod
    def unit_text(unit: str) -> str:
        """An SI unit in running text: ``"N m"`` -> ``N\\,m``, ``"kg m^2"`` -> ``kg\\,m\\textsuperscript{2}``.

        For headers and sentences, where :meth:`unit`'s math would change the type;
        dimensionless (``"1"`` or empty) gives ``"--"``.
        """
        unit = unit.strip()
        if unit in ("", "1"):
            return "--"
        parts = [re.sub(r"\\textasciicircum\{\}(-?\d+)", r"\\textsuperscript{\1}", escape_text(p))
                 for p in unit.split()]
        return r"\,".join(parts)

    def relay_equation(self, out: str, inp: str, threshold: float) -> str:
        """The relay's update as a ``cases`` right-hand side (held output, starting at 0)."""
        a = self.number(threshold)
        return (rf"\begin{{cases}} 1 & {inp}[k] \ge {a} \\ -1 & {inp}[k] \le -{a} \\ "
                rf"{out}[k - 1] & \text{{otherwise}} \end{{cases}}")

    @staticmethod
    def delayed(inp: str, samples: int) -> str:
        """``inp[k - N]``."""
        return f"{inp}{_index(int(samples))}"

    @staticmethod
    def signal(base: str, *index: int) -> str:
        """A signal name with a subscript: ``signal("y", 1) == "y_{1}"``, ``x_{3,2}``."""
        return f"{base}_{{{','.join(str(i) for i in index)}}}" if index else base

    @staticmethod
    def math(text: str) -> str:
        """Inline math: ``$text$``."""
        return f"${text}$"

    @staticmethod
    def text(text: str) -> str:
        """Escaped text (:func:`escape_text`)."""
        return escape_text(text)

    @staticmethod
    def breakable(text: str) -> str:
        """Escaped text that may break after ``(``, ``,``, ``*`` and ``=`` (long formulas in prose).

        A power written with a caret (``kg m^2``, ``rad/s^-2``) is set as a superscript.
        """
        text = re.sub(r"([(,*=])", r"\1\\allowbreak{}", escape_text(text))
        return re.sub(r"\\textasciicircum\{\}(-?\d+)", r"\\textsuperscript{\1}", text)

    @staticmethod
    def mono(text: str) -> str:
        """Escaped typewriter text (file names, digests)."""
        return rf"\texttt{{{escape_text(text)}}}"

    @staticmethod
    def ref(label: str) -> str:
        """A cross-reference to ``label``."""
        return rf"\ref{{{label}}}"

    @staticmethod
    def digest(text: str) -> str:
        """A hex digest in small typewriter type (fits a table cell)."""
        return rf"{{\small\texttt{{{escape_text(text)}}}}}"

    @staticmethod
    def math_text(text: str) -> str:
        """Text inside math (``\text{...}``), escaped."""
        return rf"\text{{{escape_text(text)}}}"

    def interval(self, low: float, high: float) -> str:
        """``[low, high]`` in math."""
        return rf"[{self.number(low)},\ {self.number(high)}]"

    def weighting(self, doc: Mapping[str, Any]) -> str:
        """A step's weighting Lambda (paper, eqs. 15-16) as one line of math.

        Parameters
        ----------
        doc : mapping
            The weighting as recorded in result.json (``constant``, ``windows``,
            ``otherwise``, ``threshold``, ``above``, ``below``; all optional).
        """
        parts = []
        c = doc.get("constant", 1.0)
        if c != 1.0 or not (doc.get("windows") or doc.get("threshold") is not None):
            parts.append(self.number(c))
        if doc.get("windows"):
            cases = [rf"{self.number(w)} & {self.number(t0)} \le t < {self.number(t1)}"
                     for t0, t1, w in doc["windows"]]
            cases.append(rf"{self.number(doc.get('otherwise', 0.0))} & \text{{otherwise}}")
            parts.append(r"\begin{cases}" + r" \\ ".join(cases) + r"\end{cases}")
        if doc.get("threshold") is not None:
            thr = self.number(doc["threshold"])
            parts.append(rf"\begin{{cases}} {self.number(doc.get('above', 1.0))} & "
                         rf"|\hat\tau| \ge {thr} \\ {self.number(doc.get('below', 1.0))} & "
                         r"\text{otherwise} \end{cases}")
        return r"\Lambda = " + r" \cdot ".join(parts)


def _index(i: int) -> str:
    return "[k]" if i == 0 else f"[k - {i}]"


def latex(expr: Any, **settings: Any) -> str:
    """LaTeX text of ``expr`` with the project's functions.

    Parameters
    ----------
    expr : sympy.Basic
    **settings
        SymPy LaTeX printer settings (and ``digits``).
    """
    return EdmLatexPrinter(settings).doprint(expr)


def model_latex(model: Any) -> str:
    """A decoded model as display math: one aligned line per row, then their sum.

    Parameters
    ----------
    model : SymbolicModel
        Rows with expressions (:func:`edm_sym.engines.symbolic.decode`); a
        model from ``build_model`` shows its rows as the stages compose them.

    Returns
    -------
    str
        ``$$\\begin{aligned} y_{1} &= ... \\\\ \\tau_{cmp} &= y_{1} + ... \\end{aligned}$$``
        with 4 significant digits.
    """
    from edm_sym.engines.symbolic.rowexpr import row_expression

    p = EdmLatexPrinter({"digits": 4})
    lines = []
    for row in model.rows:
        expr = row.expr_numeric
        if expr is None:
            expr = row_expression(row, ts=model.sample_time, numeric=True)
        lines.append(rf"y_{{{row.index + 1}}} &= {p.doprint(expr)} && \text{{row {row.index + 1}, "
                     rf"{escape_text(row.input)}}}")
    total = " + ".join(f"y_{{{row.index + 1}}}" for row in model.rows) or "0"
    lines.append(rf"\tau_{{\mathrm{{cmp}}}} &= {total}")
    return "$$\\begin{aligned}" + r" \\ ".join(lines) + r"\end{aligned}$$"
