"""The element registry: every element of the paper's Figs. 3-5, by code and by name.

Adding an element means writing one class in one of the modules imported below;
defining it registers it (a duplicate code or name is an error).
"""

from __future__ import annotations

from edm_sym.core.elements import basic, calculation, nonlinear  # noqa: F401  (registers)
from edm_sym.core.elements.base import (
    BY_NAME,
    REGISTRY,
    DelayElement,
    Element,
    LinearElement,
    Param,
    ParamRange,
    RelayElement,
    StaticElement,
)

__all__ = [
    "BY_NAME",
    "REGISTRY",
    "DelayElement",
    "Element",
    "LinearElement",
    "Param",
    "ParamRange",
    "RelayElement",
    "StaticElement",
    "all_elements",
    "check_range",
    "default_ranges",
    "element",
]


def element(code_or_name: int | str) -> type[Element]:
    """Look an element class up by its integer code or its name.

    Raises
    ------
    KeyError
        With the known codes or names in the message.
    """
    table = BY_NAME if isinstance(code_or_name, str) else REGISTRY
    try:
        return table[code_or_name]
    except KeyError:
        known = f"{min(REGISTRY)}-{max(REGISTRY)}" if table is REGISTRY else ", ".join(BY_NAME)
        raise KeyError(f"{code_or_name!r} is not a known element (known: {known})") from None


def check_range(name: str, rng: ParamRange) -> ParamRange:
    """Refuse a range of element ``name`` that passes its parameter's limits (:class:`Param`).

    Raises
    ------
    ValueError
        ``"range: expected ... found [low, high]"``; names unknown to the registry pass.
    """
    el = BY_NAME.get(name)
    if el is not None and el.param is not None:
        el.param.check(rng)
    return rng


def all_elements() -> list[type[Element]]:
    """Every registered element class, ordered by code."""
    return [REGISTRY[c] for c in sorted(REGISTRY)]


def default_ranges(ts: float, t_sum: float) -> dict[str, ParamRange]:
    """Default parameter ranges (eqs. 6-7) for a log of sample time ``ts`` and length ``t_sum``."""
    return {e.name: e.param.default(ts, t_sum) for e in all_elements() if e.param is not None}
