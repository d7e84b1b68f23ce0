"""What the report's TikZ pictures show, laid out here so the templates only loop.

* :func:`matrix_diagram` -- the element matrix as a grid of boxes (the paper's
  Fig. 21): the input of each row on the left, each element's code and name
  above its parameter, the rows' outputs summed on the right.
* :func:`chain_diagram` -- one row's simplified block diagram (Fig. 22): the
  blocks of :func:`edm_sym.outputs.report.blocks.row_chain`, left to right.

Positions are in centimetres, printed with fixed precision, so equal models
give equal pictures. Labels come from the LaTeX printer.
"""

from __future__ import annotations

from typing import Any

from edm_sym.engines.symbolic.model import RowModel, SymbolicModel
from edm_sym.outputs.printing.latex import EdmLatexPrinter
from edm_sym.outputs.report.blocks import PLACEHOLDER, Block, BlockKind, row_chain

#: Grid geometry [cm]: box width, horizontal gap, row pitch, input column, bus offset.
BOX_WIDTH = 2.0
GAP = 0.55
ROW_PITCH = 1.45
INPUT_X = 0.0
FIRST_X = INPUT_X + 0.45 + BOX_WIDTH / 2

#: TikZ style of each block kind of a row's chain (the template's style keys).
BLOCK_STYLES = {
    BlockKind.GAIN: "edmgain", BlockKind.OFFSET: "edmblock", BlockKind.FUNCTION: "edmblock",
    BlockKind.LTI: "edmlti", BlockKind.DELAY: "edmlti", BlockKind.RELAY: "edmblock",
    BlockKind.CONSTANT: "edmblock",
}


def _cm(v: float) -> str:
    return f"{v:.2f}"


def matrix_diagram(model: SymbolicModel, printer: EdmLatexPrinter) -> dict[str, Any]:
    """The element matrix as a grid (paper, Fig. 21).

    Parameters
    ----------
    model : SymbolicModel
    printer : EdmLatexPrinter
        Prints the labels; 3 significant digits read best in the boxes.

    Returns
    -------
    dict
        ``rows`` (each: ``number``, ``y``, ``input``, ``output``, ``last``,
        ``cells``: ``id``, ``prev``, ``x``, ``style``, ``code``, ``name``,
        ``param``), ``bus_x``, ``sum_x``, ``sum_y``, ``out_x``.
    """
    n = model.compensator.matrix.n_elements
    rows = []
    for row in model.rows:
        j = row.index + 1
        y = -ROW_PITCH * row.index
        cells = []
        prev = f"in{j}"
        for st in row.stages:
            cid = f"r{j}c{st.col + 1}"
            if st.param is None:
                param = "--"
            else:
                param = printer.math(f"{printer._print(st.param.symbol)} = "
                                     f"{printer.number(st.param.value)}")
            cells.append({
                "id": cid, "prev": prev, "x": _cm(FIRST_X + st.col * (BOX_WIDTH + GAP)),
                "style": "edmthrough" if st.element.is_identity else "edmcell",
                "code": str(st.element.code), "name": printer.text(st.element.name),
                "param": param,
            })
            prev = cid
        rows.append({"number": str(j), "y": _cm(y), "input": printer.math(printer._print(row.input_symbol)),
                     "output": printer.math(printer.signal("y", j)), "last": prev, "cells": cells})
    right = FIRST_X + (n - 1) * (BOX_WIDTH + GAP) + BOX_WIDTH / 2
    sum_y = -ROW_PITCH * (len(model.rows) - 1) / 2
    return {"rows": rows, "input_x": _cm(INPUT_X), "bus_x": _cm(right + 1.1),
            "sum_x": _cm(right + 1.9), "sum_y": _cm(sum_y), "out_x": _cm(right + 3.3),
            "box_width": _cm(BOX_WIDTH)}


def block_label(block: Block, printer: EdmLatexPrinter) -> str:
    """The math-mode label of one block."""
    if block.kind is BlockKind.OFFSET:
        c = block.expr
        if c.could_extract_minus_sign():
            return rf"-\,{printer.doprint(-c)}"
        return rf"+\,{printer.doprint(c)}"
    if block.kind is BlockKind.DELAY:
        return rf"e^{{-{printer.parenthesize(block.expr, 1000)} s}}"
    if block.kind is BlockKind.RELAY:
        return rf"\operatorname{{relay}}_{{{printer.doprint(block.expr)}}}(\cdot)"
    return printer.doprint(block.expr)


def chain_diagram(row: RowModel, printer: EdmLatexPrinter, *, numeric: bool = False
                  ) -> dict[str, Any]:
    """One row's simplified block diagram (paper, Fig. 22).

    Parameters
    ----------
    row : RowModel
        A decoded row.
    printer : EdmLatexPrinter
        Must print :data:`~edm_sym.outputs.report.blocks.PLACEHOLDER` as a dot
        (``symbol_names``), as :func:`chain_printer` sets up.
    numeric : bool
        Draw the numeric form instead of the named one.

    Returns
    -------
    dict
        ``input``, ``output``, ``blocks`` (each: ``id``, ``prev``, ``style``,
        ``label``), ``last``.
    """
    expr = row.expr_numeric if numeric else row.expr
    blocks = []
    prev = "u"
    for k, b in enumerate(row_chain(expr, row.input_symbol), 1):
        bid = f"b{k}"
        blocks.append({"id": bid, "prev": prev, "style": BLOCK_STYLES[b.kind],
                       "label": printer.math(r"\displaystyle " + block_label(b, printer))})
        prev = bid
    return {"input": printer.math(printer._print(row.input_symbol)),
            "output": printer.math(printer.signal("y", row.index + 1)),
            "blocks": blocks, "last": prev}


def chain_printer(digits: int = 4) -> EdmLatexPrinter:
    """A printer that shows a block's input as a dot."""
    return EdmLatexPrinter({"digits": digits, "symbol_names": {PLACEHOLDER: r"\cdot"}})
