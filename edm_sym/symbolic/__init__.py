"""Symbolic decoding: the element matrix as sympy expressions and python-control systems."""

from __future__ import annotations

from typing import Any

from edm_sym.matrix import Compensator
from edm_sym.symbolic.model import (
    ParamInfo,
    RowModel,
    Stage,
    SymbolicModel,
    X,
    build_model,
    s,
)

__all__ = ["ParamInfo", "RowModel", "Stage", "SymbolicModel", "X", "build_model", "decode", "s"]


def decode(result: Any) -> SymbolicModel:
    """Decode a result (or a bare compensator) into its symbolic model.

    Parameters
    ----------
    result : EdmResult or Compensator

    Returns
    -------
    SymbolicModel
    """
    if isinstance(result, Compensator):
        return build_model(result)
    return build_model(result.compensator, sha256=result.sha256, target=result.target)
