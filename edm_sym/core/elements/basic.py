"""Basic elements (paper, Fig. 3): through, invert, offset."""

from __future__ import annotations

from typing import Any

from edm_sym.core.elements.base import Param, ParamRange, StaticElement


class Through(StaticElement):
    name = "through"
    cost = 0.0
    code = 0
    title = "Through"
    category = "basic"
    homogeneous = True
    is_identity = True
    formula = "y = x"

    @staticmethod
    def f(m: Any, x: Any, a: Any) -> Any:
        return x


class Invert(StaticElement):
    name = "invert"
    code = 1
    title = "Invert"
    category = "basic"
    homogeneous = True
    formula = "y = -x"

    @staticmethod
    def f(m: Any, x: Any, a: Any) -> Any:
        return -x


class Offset(StaticElement):
    name = "offset"
    code = 2
    title = "Offset"
    category = "basic"
    formula = "y = x + a"
    param = Param("constant added to the input", "unit of the input",
                  lambda ts, t_sum: ParamRange(-5.0, 5.0, "linear"), "-5 .. 5 (linear)")

    @staticmethod
    def f(m: Any, x: Any, a: Any) -> Any:
        return x + a
