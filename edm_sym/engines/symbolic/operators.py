"""Dynamic stages as sympy operators: ``LTI(x, G)``, ``Delay(x, T)``, ``Relay(x, a)``.

A row expression is a composition of its stages applied to the row's input.
Static stages are ordinary sympy functions; the stages with memory are these
operators applied to their input expression:

* ``LTI(x, G)`` -- the linear time-invariant system with continuous transfer
  function ``G(s)`` (a rational expression in :data:`s`) driven by ``x`` from rest;
* ``Delay(x, T)`` -- ``x`` delayed by ``T`` seconds (the buffer starts at zero);
* ``Relay(x, a)`` -- the relay with hysteresis of half width ``a`` (starts at 0).

They are sympy ``Function`` subclasses, so rewrite rules match them by type and
every printer gives them a ``_print_<Operator>`` method (LaTeX:
:class:`edm_sym.outputs.printing.latex.EdmLatexPrinter`). They cannot be
lambdified: their numeric form is the python-control system of
:mod:`edm_sym.engines.symbolic.lti`.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import sympy as sp

#: The Laplace variable (the same symbol as :data:`edm_sym.engines.symbolic.model.s`).
s = sp.Symbol("s")


class _Operator(sp.Function):
    """An operator on a signal: its first argument is the input expression."""

    def _eval_is_real(self) -> bool | None:
        return self.args[0].is_real

    @property
    def signal(self) -> sp.Expr:
        """The input expression."""
        return self.args[0]


class LTI(_Operator):
    """``LTI(x, G)``: the signal ``x`` through the transfer function ``G(s)``, from rest.

    ``G`` free of ``s`` is a plain gain, so ``LTI(x, c)`` evaluates to ``c x``.
    """

    nargs = 2

    @classmethod
    def eval(cls, x: sp.Expr, G: sp.Expr) -> sp.Expr | None:  # noqa: N803  (G is the name)
        if x.is_zero or G.is_zero:
            return sp.S.Zero
        if s not in G.free_symbols:
            return G * x
        return None

    @property
    def transfer_function(self) -> sp.Expr:
        """``G(s)``."""
        return self.args[1]


class Delay(_Operator):
    """``Delay(x, T)``: ``x`` delayed by ``T`` seconds, the buffer starting at zero."""

    nargs = 2

    @classmethod
    def eval(cls, x: sp.Expr, T: sp.Expr) -> sp.Expr | None:  # noqa: N803
        if x.is_zero or T.is_zero:
            return x
        return None

    @property
    def time(self) -> sp.Expr:
        """The delay ``T`` [s]."""
        return self.args[1]


class Relay(_Operator):
    """``Relay(x, a)``: +1 once ``x >= a``, -1 once ``x <= -a``, else held; starts at 0."""

    nargs = 2

    @classmethod
    def eval(cls, x: sp.Expr, a: sp.Expr) -> sp.Expr | None:
        if x.is_zero and a.is_positive:
            return sp.S.Zero  # the input never leaves the band: the output stays 0
        return None

    def _eval_is_real(self) -> bool:
        return True  # +-1 or 0, whatever the input

    @property
    def threshold(self) -> sp.Expr:
        """The half width ``a`` of the hysteresis band."""
        return self.args[1]


#: The operators with memory, for ``isinstance`` checks.
DYNAMIC = (LTI, Delay, Relay)


def rational(num: Sequence[Any], den: Sequence[Any]) -> sp.Expr:
    """``num(s) / den(s)`` from coefficient lists in descending powers of s."""
    def poly(c: Sequence[Any]) -> sp.Expr:
        n = len(c) - 1
        return sp.Add(*(sp.sympify(v) * s ** (n - i) for i, v in enumerate(c)))

    return poly(num) / poly(den)


def coefficients(G: sp.Expr) -> tuple[list[sp.Expr], list[sp.Expr]]:  # noqa: N803
    """Numerator and denominator coefficients of ``G(s)``, descending powers of s.

    The denominator is scaled to a leading coefficient 1.
    """
    num, den = sp.fraction(sp.cancel(sp.together(G), s))
    pn, pd = sp.Poly(num, s), sp.Poly(den, s)
    lead = pd.LC()
    return ([sp.cancel(c / lead) for c in pn.all_coeffs()],
            [sp.cancel(c / lead) for c in pd.all_coeffs()])
