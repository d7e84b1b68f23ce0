"""Row expressions: a row's stages composed into one sympy expression of its input.

Each stage becomes a function of the expression before it, left to right:
static stages substitute that expression for :data:`~edm_sym.symbolic.model.X`,
dynamic stages wrap it in an operator of :mod:`edm_sym.symbolic.operators`.
Two forms are built: with the named parameters ``a_k`` (the paper's Table II)
and with the numbers the simulator uses (the realised delay in whole samples,
the relay threshold, the parameter values as 17-digit floats).
"""

from __future__ import annotations

import sympy as sp

from edm_sym.symbolic.model import RowModel, Stage, X
from edm_sym.symbolic.operators import LTI, Delay, Relay, rational


def _value(stage: Stage) -> sp.Float:
    return sp.Float(stage.param.value, 17)


def stage_operator(stage: Stage, x: sp.Expr, *, ts: float, numeric: bool) -> sp.Expr:
    """The output of one stage driven by the expression ``x``.

    Parameters
    ----------
    stage : Stage
        The decoded element.
    x : sympy.Expr
        Its input.
    ts : float
        The sample time [s] (delays are realised in whole samples of it).
    numeric : bool
        Substitute the parameter values for the ``a_k`` symbols.

    Returns
    -------
    sympy.Expr
    """
    if stage.kind == "static":
        body = stage.numeric_expr() if numeric else stage.expr
        return body.xreplace({X: x})
    if stage.kind == "linear":
        num, den = stage.tf
        if numeric and stage.param is not None:
            sub = {stage.param.symbol: _value(stage)}
            num = [sp.sympify(c).xreplace(sub) for c in num]
            den = [sp.sympify(c).xreplace(sub) for c in den]
        return LTI(x, rational(num, den))
    if stage.kind == "delay":
        if numeric or stage.param is None:
            return Delay(x, sp.Float(stage.delay * ts, 17))
        # The parameter is a time for the dead time and a count for the shift.
        unit_is_time = stage.param.unit == "s"
        T = stage.param.symbol if unit_is_time else stage.param.symbol * sp.Float(ts, 17)
        return Delay(x, T)
    if stage.kind == "relay":
        a = sp.Float(stage.threshold, 17) if numeric or stage.param is None else stage.param.symbol
        return Relay(x, a)
    raise TypeError(f"stage {stage.col} ({stage.element.name}): unknown kind {stage.kind!r}")


def row_expression(row: RowModel, *, ts: float, numeric: bool = False) -> sp.Expr:
    """The raw output expression of a row, in its input symbol (no simplification).

    Parameters
    ----------
    row : RowModel
    ts : float
        Sample time [s].
    numeric : bool, default False
        Numbers instead of the ``a_k`` symbols.

    Returns
    -------
    sympy.Expr
    """
    expr: sp.Expr = row.input_symbol
    for stage in row.stages:
        expr = stage_operator(stage, expr, ts=ts, numeric=numeric)
    return expr
