"""Symbolic decoding: the element matrix as sympy expressions and python-control systems.

``decode(result)`` returns the frozen :class:`SymbolicModel`: per row the
stages (what the exporters print), the raw and simplified row expressions
(named ``a_k`` parameters and numbers), the python-control transfer functions
and row system, and the physical terms. See ``docs/symbolic.md``.
"""

from __future__ import annotations

from edm_sym.engines.symbolic.classify import ClassifyOptions, PhysicalTerm, classify_expression
from edm_sym.engines.symbolic.contributions import Contributions, contributions
from edm_sym.engines.symbolic.decoding import decode, decode_row
from edm_sym.engines.symbolic.lti import LinearPart, row_system, simulate_system, to_tf
from edm_sym.engines.symbolic.model import (
    ParamInfo,
    RowModel,
    Stage,
    SymbolicModel,
    X,
    build_model,
    s,
)
from edm_sym.engines.symbolic.operators import LTI, Delay, Relay
from edm_sym.engines.symbolic.roles import DEFAULT_ROLES, ROLES, input_roles
from edm_sym.engines.symbolic.simplify import SimplifyOptions, simplify_expression

__all__ = [
    "DEFAULT_ROLES",
    "LTI",
    "ROLES",
    "ClassifyOptions",
    "Contributions",
    "Delay",
    "LinearPart",
    "ParamInfo",
    "PhysicalTerm",
    "Relay",
    "RowModel",
    "SimplifyOptions",
    "Stage",
    "SymbolicModel",
    "X",
    "build_model",
    "classify_expression",
    "contributions",
    "decode",
    "decode_row",
    "input_roles",
    "row_system",
    "s",
    "simplify_expression",
    "simulate_system",
    "to_tf",
]
