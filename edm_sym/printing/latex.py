"""LaTeX printing of the project's own functions, for the model report."""

from __future__ import annotations

from typing import Any

from sympy.printing.latex import LatexPrinter


class EdmLatexPrinter(LatexPrinter):
    """SymPy's LaTeX printer with the guarded and piecewise elements.

    Parameters
    ----------
    settings : dict, optional
        SymPy printer settings; floats default to 4 significant digits.
    """

    def __init__(self, settings: dict[str, Any] | None = None):
        merged = {"full_prec": False, "min": -3, "max": 3}
        merged.update(settings or {})
        super().__init__(merged)

    def _print_Float(self, expr: Any) -> str:
        # Four significant digits read best in equations; tables give full values.
        text = f"{float(expr):.4g}"
        if "e" in text:
            mant, exp = text.split("e")
            return rf"{mant} \cdot 10^{{{int(exp)}}}"
        return text

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


def latex(expr: Any, **settings: Any) -> str:
    """LaTeX text of ``expr`` with the project's functions.

    Parameters
    ----------
    expr : sympy.Basic
    **settings
        SymPy LaTeX printer settings.
    """
    return EdmLatexPrinter(settings).doprint(expr)
