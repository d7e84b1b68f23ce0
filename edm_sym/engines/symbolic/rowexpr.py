"""Row expressions: a row's stages composed into one sympy expression of its input.

Each stage becomes a function of the expression before it, left to right:
static stages substitute that expression for :data:`~edm_sym.engines.symbolic.model.X`,
dynamic stages wrap it in an operator of :mod:`edm_sym.engines.symbolic.operators`.
Two forms are built: with the named parameters ``a_k`` (the paper's Table II)
and with the numbers the simulator uses (the realised delay in whole samples,
the relay threshold, the parameter values as 17-digit floats).
"""

from __future__ import annotations

import sympy as sp

from edm_sym.core.elements.realisation import DelayLine, LinearFilter, StaticMap
from edm_sym.core.elements.realisation import Relay as RelayLine
from edm_sym.engines.symbolic.model import RowModel, Stage, X
from edm_sym.engines.symbolic.operators import LTI, Delay, Relay, rational


def _static(stage: Stage, x: sp.Expr, ts: float, numeric: bool) -> sp.Expr:
    body = stage.numeric_expr() if numeric else stage.expr
    return body.xreplace({X: x})


def _linear(stage: Stage, x: sp.Expr, ts: float, numeric: bool) -> sp.Expr:
    num, den = stage.numeric_tf() if numeric else stage.tf
    return LTI(x, rational(num, den))


def _delay(stage: Stage, x: sp.Expr, ts: float, numeric: bool) -> sp.Expr:
    if numeric or stage.param is None:
        return Delay(x, sp.Float(stage.realisation.samples * ts, 17))
    # The parameter is a time for the dead time and a count for the shift.
    unit_is_time = stage.param.unit == "s"
    T = stage.param.symbol if unit_is_time else stage.param.symbol * sp.Float(ts, 17)  # noqa: N806
    return Delay(x, T)


def _relay(stage: Stage, x: sp.Expr, ts: float, numeric: bool) -> sp.Expr:
    thr = stage.realisation.threshold
    return Relay(x, sp.Float(thr, 17) if numeric or stage.param is None else stage.param.symbol)


#: The operator of each realisation type.
OPERATORS = {StaticMap: _static, LinearFilter: _linear, DelayLine: _delay, RelayLine: _relay}


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
    return OPERATORS[type(stage.realisation)](stage, x, ts, numeric)


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
