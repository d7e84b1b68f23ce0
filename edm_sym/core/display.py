"""How results and models show themselves: one line per row, and LaTeX for notebooks.

``repr(result)`` and ``repr(model)`` give a header line and one line per row
(the row's input and its elements with their values), never the dataclass
dump of every field. ``_repr_latex_`` (Jupyter's rich display) needs the LaTeX
printer, which lives in a layer above (``edm_sym.outputs.printing``): the
package face registers the renderers here with :func:`register_latex`, so the
core and the engines know no LaTeX syntax and import nothing upward.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

__all__ = ["latex_repr", "matrix_lines", "register_latex"]

#: Renderers by kind (``"result"``, ``"model"``): object -> LaTeX text (with ``$`` delimiters).
_LATEX: dict[str, Callable[[Any], str]] = {}


def register_latex(kind: str, render: Callable[[Any], str]) -> None:
    """Install the LaTeX renderer of ``kind`` (``"result"`` or ``"model"``).

    Parameters
    ----------
    kind : str
    render : callable
        Takes the object, returns LaTeX math with its delimiters.
    """
    _LATEX[kind] = render


def latex_repr(kind: str, obj: Any) -> str | None:
    """The LaTeX display of ``obj``, or None (no renderer installed: the text repr shows).

    Parameters
    ----------
    kind : str
    obj : object

    Returns
    -------
    str or None
    """
    render = _LATEX.get(kind)
    return None if render is None else render(obj)


def _value(x: float) -> str:
    return f"{x:.4g}"


def matrix_lines(comp: Any) -> list[str]:
    """One line per row: ``row 1: alpha -> phase(0.3142 rad/s) -> gain(-8.167e-05)``.

    ``through`` elements are left out; a parameter is shown with its SI unit
    (none when dimensionless or relative to the row's signals).

    Parameters
    ----------
    comp : Compensator

    Returns
    -------
    list of str
    """
    out = []
    for j, row in enumerate(comp.matrix.rows):
        parts = [comp.matrix.inputs[row.input]]
        for gene in row.genes:
            el = gene.element
            if el.is_identity:
                continue
            if el.param is None:
                parts.append(el.name)
                continue
            unit = el.param.unit
            # Relative units ("unit of the input") are for the docs, not for one line.
            plain = unit not in ("", "1", "-") and "unit" not in unit
            shown = _value(float(comp.value(gene))) + (f" {unit}" if plain else "")
            parts.append(f"{el.name}({shown})")
        out.append(f"row {j + 1}: " + " -> ".join(parts))
    return out
