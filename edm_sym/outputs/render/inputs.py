"""What the exports say about each input and each guard, in plain text.

Each input of a compensator is documented in the C header and the Python
module with its role and SI unit (from the role and the result's axis,
:func:`edm_sym.core.units.axis_units`), its expected range (the smallest and
largest value of its column in the abstraction log, when the result records
them: result.json ``logs[].columns[].min``/``max``), and the rows that read
it. An input no row reads is never read by the generated step function.

The guards are the elements' own (``Element.guard``): what an input outside an
element's mathematical domain does. No input is clamped to its expected range.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from edm_sym.core.elements.base import Element
from edm_sym.core.units import axis_units
from edm_sym.engines.symbolic.roles import input_roles

#: What each input role (:data:`edm_sym.engines.symbolic.roles.ROLES`) measures,
#: and which unit of :class:`~edm_sym.core.units.AxisUnits` it is in.
ROLE_QUANTITY: dict[str, tuple[str, str]] = {
    "angle": ("position", "position"),
    "angle_wrapped": ("position wrapped to one revolution", "position"),
    "velocity": ("velocity", "velocity"),
    "acceleration": ("acceleration", "acceleration"),
}

#: What the exports say about an input outside its expected range.
OUTSIDE_RANGE = ("No input is clamped: outside its expected range the compensator computes "
                 "the same formulas, so it extrapolates what it learnt there; only the element "
                 "guards below limit anything.")

#: Said when no element of the model has a guard.
NO_GUARDS = "none: every element is defined and finite for every finite input"


@dataclass(frozen=True)
class InputDoc:
    """One input as the exports document it.

    Attributes
    ----------
    name : str
    index : int
        Its index in ``u`` (the result's input order).
    role : str or None
        Its physical role (:data:`edm_sym.engines.symbolic.roles.ROLES`), None when unknown.
    unit : str or None
        Its SI unit on the result's axis, None when its role is unknown.
    range : tuple of float, or None
        The smallest and largest value of its column in the abstraction log,
        None when the result does not record them.
    log : str or None
        The abstraction log's file name (where the range comes from).
    rows : tuple of int
        The rows (from 1) that read it; empty when no row does.
    """

    name: str
    index: int
    role: str | None
    unit: str | None
    range: tuple[float, float] | None
    log: str | None
    rows: tuple[int, ...]

    @property
    def used(self) -> bool:
        """Whether any row reads this input."""
        return bool(self.rows)

    def text(self) -> str:
        """``"omega: velocity [rad/s], expected -12 .. 15 (its range in abs.csv); rows 3, 4"``."""
        what = (f"{ROLE_QUANTITY[self.role][0]} [{self.unit}]" if self.role in ROLE_QUANTITY
                else "no physical role, in the unit of its log column")
        if self.range is None:
            span = "range not recorded"
        else:
            span = f"expected {_fmt(self.range[0])} .. {_fmt(self.range[1])} (its range in {self.log})"
        if not self.used:
            return (f"{self.name}: {what}, {span}; read by no row, so its value is never used "
                    "(any value, e.g. 0, will do)")
        rows = ", ".join(str(r) for r in self.rows)
        return f"{self.name}: {what}, {span}; read by row{'s' if len(self.rows) > 1 else ''} {rows}"


def _fmt(v: float) -> str:
    return format(v, ".6g")


def input_docs(model: Any, *, axis: str, roles: Mapping[str, str | None],
               ranges: Mapping[str, tuple[float, float]], log: str | None) -> tuple[InputDoc, ...]:
    """Every input of ``model`` (a SymbolicModel) as the exports document it.

    Parameters
    ----------
    model : SymbolicModel
    axis : str
        The result's axis (its units).
    roles : mapping of str to str or None
        The roles the result records; the others follow the input names
        (:func:`~edm_sym.engines.symbolic.roles.input_roles`). A decoded
        model's own roles win.
    ranges : mapping of str to (float, float)
        Recorded (min, max) per column.
    log : str or None
        The abstraction log's file name.
    """
    units = axis_units(axis)
    role_of = dict(model.roles) if model.roles else input_roles(model.inputs, roles)
    out = []
    for k, name in enumerate(model.inputs):
        role = role_of.get(name)
        unit = getattr(units, ROLE_QUANTITY[role][1]) if role in ROLE_QUANTITY else None
        rows = tuple(r.index + 1 for r in model.rows if r.input == name)
        out.append(InputDoc(name, k, role, unit, ranges.get(name),
                            log if name in ranges else None, rows))
    return tuple(out)


def guard_notes(rows: Any) -> list[str]:
    """One line per stage whose element has a guard: where it is and what the guard does.

    ``rows`` are the plan's rows (:func:`edm_sym.outputs.render.context.plan`).
    """
    out = []
    for row in rows:
        for sp in row.stages:
            guard = sp.stage.element.guard
            if guard != Element.guard:
                out.append(f"row {row.index + 1}, element {sp.col + 1}, {sp.label}: {guard}")
    return out
