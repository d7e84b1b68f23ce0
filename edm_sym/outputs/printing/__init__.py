"""Printers: the only modules that know C and Python syntax.

:class:`EdmC99Printer` and :class:`EdmPythonPrinter` subclass SymPy's code
printers and add a ``_print_<Function>`` method for each of the project's own
functions (:mod:`edm_sym.engines.symbolic.functions`).
"""

from __future__ import annotations

from edm_sym.outputs.printing.c import REALS, EdmC99Printer, c_comment_text, is_c_identifier
from edm_sym.outputs.printing.python import EdmPythonPrinter, py_literal

__all__ = [
    "REALS",
    "EdmC99Printer",
    "EdmPythonPrinter",
    "c_comment_text",
    "is_c_identifier",
    "py_literal",
]
