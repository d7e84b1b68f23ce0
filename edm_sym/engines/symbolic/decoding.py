"""The full symbolic decoding of a compensator: expressions, systems, physical terms.

:func:`decode` starts from the stages of
:func:`~edm_sym.engines.symbolic.model.build_model` (what every exporter prints) and
makes, per row, a new frozen row with: the raw and the simplified expression,
with named parameters and with numbers; the python-control forms; the input's
role and the physical terms. It returns a new frozen
:class:`~edm_sym.engines.symbolic.model.SymbolicModel`; nothing is filled in later.
Exporters receive this one model (``edm_sym.application.exporting.export`` decodes once).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import sympy as sp

from edm_sym.core.matrix import Compensator
from edm_sym.engines.symbolic.classify import ClassifyOptions, classify_expression
from edm_sym.engines.symbolic.lti import row_system, stage_parts
from edm_sym.engines.symbolic.model import RowModel, SymbolicModel, build_model
from edm_sym.engines.symbolic.roles import input_roles
from edm_sym.engines.symbolic.rowexpr import row_expression
from edm_sym.engines.symbolic.simplify import SimplifyOptions, simplify_expression


def parameter_signs(model: SymbolicModel) -> dict[sp.Symbol, int]:
    """+1 / -1 for the parameters whose range is entirely positive / negative.

    Parameters
    ----------
    model : SymbolicModel

    Returns
    -------
    dict of sympy.Symbol to int
    """
    out = {}
    for p in model.params:
        if p.range.low > 0:
            out[p.symbol] = 1
        elif p.range.high < 0:
            out[p.symbol] = -1
    return out


def decode_row(
    model: SymbolicModel,
    row: RowModel,
    *,
    role: str | None,
    simplify: SimplifyOptions | None = None,
    classify: ClassifyOptions | bool | None = None,
    systems: bool = True,
    axis: str = "rotary",
) -> RowModel:
    """One row with its expressions, python-control forms and physical terms filled.

    Parameters
    ----------
    model : SymbolicModel
        The model the row belongs to (sample time, parameters, inputs).
    row : RowModel
    role : str or None
        The physical role of the row's input.
    simplify, classify, systems, axis
        As for :func:`decode`.

    Returns
    -------
    RowModel
    """
    ts = model.sample_time
    raw = row_expression(row, ts=ts)
    raw_n = row_expression(row, ts=ts, numeric=True)
    expr = simplify_expression(raw, model.input_symbols, numeric=False,
                               signs=parameter_signs(model), options=simplify)
    expr_n = simplify_expression(raw_n, model.input_symbols, numeric=True, options=simplify)
    # classify=False: no physical terms (a repr or a system needs none, and they cost sympy time).
    terms = () if classify is False else classify_expression(expr_n, row.input_symbol, role,
                                                              options=classify, axis=axis)
    return RowModel(row.index, row.input, row.input_symbol, row.stages, role=role,
                    expr_raw=raw, expr_raw_numeric=raw_n, expr=expr, expr_numeric=expr_n,
                    terms=terms, linear_parts=stage_parts(row, ts) if systems else (),
                    system=row_system(row, ts) if systems else None)


def decode(
    result: Any,
    *,
    roles: Mapping[str, str | None] | None = None,
    simplify: SimplifyOptions | None = None,
    classify: ClassifyOptions | bool | None = None,
    systems: bool = True,
    axis: str | None = None,
) -> SymbolicModel:
    """Decode a result (or a bare compensator) into its full symbolic model.

    Parameters
    ----------
    result : EdmResult or Compensator
    roles : mapping of str to str or None, optional
        Input name -> physical role (``"velocity"``, ``"acceleration"``,
        ``"angle"`` or ``"position"``, ``"angle_wrapped"`` or
        ``"position_wrapped"``, or None), over the roles the result records
        (``EdmResult.roles``) and the defaults of the input names
        (:mod:`edm_sym.engines.symbolic.roles`).
    simplify : SimplifyOptions, optional
        Number of rewrite passes and the pole-zero tolerance.
    classify : ClassifyOptions or False, optional
        Thresholds of the physical classification, in the axis's units
        (default: ``ClassifyOptions.for_axis(axis)``); False: no physical terms.
    systems : bool, default True
        Build the python-control transfer functions and row systems.
    axis : str, optional
        ``"rotary"`` or ``"linear"``, the SI units of the physical terms;
        default: the result's ``axis`` (rotary for a bare compensator).

    Returns
    -------
    SymbolicModel
        :func:`~edm_sym.engines.symbolic.model.build_model`'s model with every row's
        ``role``, ``expr_raw``, ``expr_raw_numeric``, ``expr``, ``expr_numeric``,
        ``terms``, ``linear_parts`` and ``system`` filled, and ``roles`` set.
    """
    if isinstance(result, Compensator):
        base = build_model(result)
    else:
        base = build_model(result.compensator, sha256=getattr(result, "sha256", None),
                           target=getattr(result, "target", None),
                           axis=getattr(result, "axis", "rotary"))
    # The roles the result records (given with --role), then the caller's.
    role_map = input_roles(base.inputs, {**getattr(result, "roles", {}), **(roles or {})})
    axis = axis or getattr(result, "axis", "rotary")
    if classify is None or classify is True:
        classify = ClassifyOptions.for_axis(axis)
    rows = tuple(decode_row(base, r, role=role_map[r.input], simplify=simplify,
                            classify=classify, systems=systems, axis=axis) for r in base.rows)
    return SymbolicModel(base.compensator, base.inputs, base.input_symbols, base.sample_time,
                         rows, base.params, base.source_sha256, base.target, role_map, axis)
