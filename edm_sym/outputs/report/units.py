"""Each parameter's SI unit, traced along its row (the report's parameter table).

An element declares its parameter's unit relative to the signal it sees
("unit of the input", "output unit per input unit", ...) and how its output's
unit follows from its input's (``Element.unit_out``). A row starts in its
input's unit (its role on the result's axis) and ends in the target's (N m or
N, the rows are summed into it), so the unit of every signal between two
elements follows forwards from the input and backwards from the output, and
with it the parameter's: a gain after a velocity input is in N m s/rad, a
gain before a sine in rad per unit of the input (``Element.unit_in``).

Where neither direction reaches (an input without a physical role, a power,
two scaling elements in one row, a gain whose output only feeds a sign), the
table keeps the relative unit and says why.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass
from typing import Any

from edm_sym.core.units import AxisUnits, axis_units
from edm_sym.outputs.render.inputs import ROLE_QUANTITY

#: The order base units are written in ("N m s/rad", "N s/m", "kg m^2").
ORDER = ("N", "kg", "m", "s", "rad")


def parse_unit(text: str) -> Counter:
    """``"N m s/rad"`` -> ``{N: 1, m: 1, s: 1, rad: -1}``; ``"1"`` -> ``{}``."""
    num, _, den = text.partition("/")
    out: Counter = Counter()
    for sign, part in ((1, num), (-1, den.strip().strip("()"))):
        for token in part.split():
            base, _, power = token.partition("^")
            if base != "1":
                out[base] += sign * int(power or 1)
    return Counter({k: v for k, v in out.items() if v})


def format_unit(unit: Counter) -> str:
    """The inverse of :func:`parse_unit`; ``"1"`` for a dimensionless unit."""
    def side(items: list[tuple[str, int]]) -> str:
        return " ".join(b if p == 1 else f"{b}^{p}" for b, p in items)

    keys = sorted(unit, key=lambda b: (ORDER.index(b) if b in ORDER else len(ORDER), b))
    num = side([(b, unit[b]) for b in keys if unit[b] > 0])
    den = side([(b, -unit[b]) for b in keys if unit[b] < 0])
    if not den:
        return num or "1"
    return f"{num or '1'}/{den}" if " " not in den else f"{num or '1'}/({den})"


def _named(unit: Counter, units: AxisUnits) -> str:
    """The axis's own name of a unit when it has one (force per acceleration: kg m^2)."""
    force = parse_unit(units.force)
    if unit == _quotient(force, parse_unit(units.velocity)):
        return units.viscous
    if unit == _quotient(force, parse_unit(units.acceleration)):
        return units.inertia
    return format_unit(unit)


def _quotient(a: Counter, b: Counter) -> Counter:
    out = Counter(a)
    out.subtract(b)
    return Counter({k: v for k, v in out.items() if v})


@dataclass(frozen=True)
class ParamUnit:
    """A parameter's unit: ``si`` when traced, else ``relative`` and ``why`` not."""

    si: str | None
    relative: str
    why: str = ""


def row_units(row: Any, units: AxisUnits) -> dict[int, ParamUnit]:
    """The unit of each parameter of ``row`` (a decoded RowModel), by column.

    Parameters
    ----------
    row : RowModel
    units : AxisUnits
    """
    stages = list(row.stages)
    n = len(stages)
    fwd: list[Counter | None] = [None] * (n + 1)
    fwhy = [""] * (n + 1)
    if row.role in ROLE_QUANTITY:
        fwd[0] = parse_unit(getattr(units, ROLE_QUANTITY[row.role][1]))
    else:
        fwhy[0] = f"{row.input} has no physical role"
    for j, st in enumerate(stages):
        kind = st.element.unit_out
        sym = st.param.symbol if st.param is not None else st.element.name
        if kind == "one":
            fwd[j + 1] = Counter()
        elif kind == "input":
            fwd[j + 1], fwhy[j + 1] = fwd[j], fwhy[j]
        elif kind == "power":
            fwd[j + 1] = Counter() if fwd[j] == Counter() else None
            fwhy[j + 1] = f"after the power {sym}, not an SI unit"
        else:  # scaled: the output's unit comes from what follows
            fwhy[j + 1] = f"set by {sym}"
    bwd: list[Counter | None] = [None] * (n + 1)
    bwhy = [""] * (n + 1)
    bwd[n] = parse_unit(units.force)
    for j in range(n - 1, -1, -1):
        st = stages[j]
        if st.element.unit_in is not None:  # an angle for sin and tan, whatever follows
            bwd[j], bwhy[j] = parse_unit(st.element.unit_in), ""
        elif st.element.unit_out == "input" and bwd[j + 1] is not None:
            bwd[j], bwhy[j] = bwd[j + 1], ""
        elif st.element.unit_out == "input":
            bwhy[j] = bwhy[j + 1]
        elif st.element.unit_out == "scaled":
            sym = st.param.symbol if st.param is not None else st.element.name
            bwhy[j] = f"{sym} after it scales the output too; only the product has a unit"
        else:
            bwhy[j] = f"it feeds {st.element.name}, whose output is dimensionless"

    def at(k: int) -> tuple[Counter | None, str]:
        if fwd[k] is not None:
            return fwd[k], ""
        if bwd[k] is not None:
            return bwd[k], ""
        return None, (bwhy[k] if fwhy[k].startswith("set by") and bwhy[k] else fwhy[k])

    out = {}
    for j, st in enumerate(stages):
        if st.param is None:
            continue
        rel = st.param.unit
        x, xwhy = at(j)
        y, ywhy = (bwd[j + 1], bwhy[j + 1]) if st.element.unit_out == "scaled" else at(j + 1)
        if rel == "unit of the input":
            u, why = (x, xwhy)
        elif rel == "1 / unit of the input":
            u, why = (None if x is None else _quotient(Counter(), x)), xwhy
        elif rel == "unit of the output":
            u, why = y, ywhy
        elif rel == "output unit per input unit":
            u = None if x is None or y is None else _quotient(y, x)
            why = xwhy if x is None else ywhy
        else:  # an absolute unit: rad/s, s, samples, rad, 1
            out[st.col] = ParamUnit(rel, rel)
            continue
        out[st.col] = (ParamUnit(_named(u, units), rel) if u is not None
                       else ParamUnit(None, rel, why))
    return out


def param_units(model: Any) -> dict[tuple[int, int], ParamUnit]:
    """Every parameter's :class:`ParamUnit` of a decoded model, by (row, column) from 0."""
    units = axis_units(model.axis)
    return {(row.index, col): u for row in model.rows for col, u in row_units(row, units).items()}

