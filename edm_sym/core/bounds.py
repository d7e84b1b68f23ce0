"""Parameters at their range bounds, and the complexity of a matrix (no sympy).

A parameter is stored normalised, ``p`` in [0, 1], and decoded into its range
(linear or logarithmic). A parameter at or within ``margin`` of a bound,
``p <= margin`` or ``p >= 1 - margin`` (default 1 %, in ``p``), is *at its
bound*: the search wanted a value the range may not allow, so the number is a
limit, not an estimate. A periodic parameter (a phase) whose range spans a
whole period reaches every value, and is never at a bound.

The complexity of a matrix is the number of active elements (every element
that is not ``through``) plus the size of the state of its discrete
realisation (filter states, delay buffers, relay bits): what a firmware
engineer pays for the compensator in code and memory.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from edm_sym.core.matrix import Compensator, ElementMatrix

#: Default margin to a range bound, in normalised ``p`` (1 %).
BOUND_MARGIN = 0.01


@dataclass(frozen=True)
class BoundFlag:
    """A parameter at (or within the margin of) one of its range bounds.

    Attributes
    ----------
    row, col : int
        Where the element sits (0-based).
    element : str
        The element's name.
    meaning, unit : str
        What the parameter is, and its unit.
    p : float
        The normalised parameter.
    value : float
        The decoded parameter.
    side : {"low", "high"}
        Which bound.
    bound : float
        That bound's value.
    """

    row: int
    col: int
    element: str
    meaning: str
    unit: str
    p: float
    value: float
    side: str
    bound: float

    def message(self) -> str:
        """One line: where, what, and the bound (4 significant digits, with the unit)."""
        return (f"row {self.row + 1} element {self.col + 1} ({self.element}, {self.meaning}) "
                f"= {_quantity(self.value, self.unit)} is at its {self.side} bound "
                f"{_quantity(self.bound, self.unit)} (p = {self.p:.4g})")

    def to_json(self) -> dict[str, Any]:
        """The entry of result.json's ``parameters_at_bound`` (row and element 1-based)."""
        return {"row": self.row + 1, "element": self.col + 1, "name": self.element,
                "p": self.p, "value": self.value, "unit": self.unit, "side": self.side,
                "bound": self.bound}


def _quantity(value: float, unit: str) -> str:
    """``0.3142 rad/s``; a dimensionless number (unit ``"1"``) without a unit."""
    return f"{value:.4g}" if unit.strip() in ("", "1") else f"{value:.4g} {unit}"


def bound_flags(comp: Compensator, *, margin: float = BOUND_MARGIN) -> tuple[BoundFlag, ...]:
    """Every parameter of the matrix that is at (or within ``margin`` of) a range bound.

    Parameters
    ----------
    comp : Compensator
        The matrix and its parameter ranges.
    margin : float, default 0.01
        In normalised ``p``: flagged when ``p <= margin`` or ``p >= 1 - margin``.

    Returns
    -------
    tuple of BoundFlag
        In row, then column order. Parameter-free elements (``p`` ignored) and
        periodic parameters whose range spans a period are never flagged.
    """
    if not 0 <= margin < 0.5:
        raise ValueError(f"margin: expected a number in [0, 0.5), found {margin!r}")
    out = []
    for j, row in enumerate(comp.matrix.rows):
        for i, gene in enumerate(row.genes):
            param = gene.element.param
            if param is None:
                continue
            rng = comp.ranges[gene.element.name]
            if param.period is not None and rng.high - rng.low >= param.period * (1 - 1e-9):
                continue
            if gene.p <= margin:
                side, bound = "low", rng.low
            elif gene.p >= 1 - margin:
                side, bound = "high", rng.high
            else:
                continue
            out.append(BoundFlag(j, i, gene.element.name, param.meaning, param.unit, gene.p,
                                 float(comp.value(gene)), side, bound))
    return tuple(out)


def complexity(comp: Compensator, matrix: ElementMatrix | None = None) -> int:
    """Rows + active (non-``through``) elements + state size of the discrete realisation.

    The one complexity count of the project: ``edm describe``, the report and
    the parsimony front (docs/abstraction.md#parsimony-pruning-and-the-complexity-vs-fitness-front)
    all use it.

    Parameters
    ----------
    comp : Compensator
        Its ranges and sample time decode the parameters.
    matrix : ElementMatrix, optional
        The matrix to count (default: ``comp.matrix``).

    Returns
    -------
    int
        E.g. Coulomb + viscous in two rows, ``sign -> gain`` and ``power_gain``:
        2 rows, 3 elements, no state: 5. A dead time of 183 samples adds 184.
    """
    ts = comp.sample_time
    total = 0
    for row in (matrix or comp.matrix).rows:
        total += 1
        for gene in row.genes:
            if gene.element.is_identity:
                continue
            total += 1 + int(gene.element.state_size(comp.value(gene), ts))
    return total


def bound_summary(comp: Compensator, *, margin: float = BOUND_MARGIN) -> list[str]:
    """One line per parameter at its range bound, for a command's closing summary.

    Parameters
    ----------
    comp : Compensator
    margin : float, default 0.01
        As for :func:`bound_flags`.

    Returns
    -------
    list of str
        Empty when no parameter is at a bound.
    """
    return [f"parameter at its range bound: {f.message()}; its value is a limit of the "
            "search, not an estimate (widen the range in the config)"
            for f in bound_flags(comp, margin=margin)]
