"""edm_sym: Element Description Method compensators for reaction torque observers.

The public API (CONTRACT.md section 7)::

    import edm_sym
    result = edm_sym.load_result("result.json")
    data = edm_sym.load_data("log.csv")
    sim = edm_sym.simulate(result, data)      # sim.rows (m, N), sim.total (N,)
    model = edm_sym.decode(result)            # sympy + python-control per row
    edm_sym.export(result, "c", "out/")
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from edm_sym.data import DataLog, load_data
from edm_sym.errors import (
    ConfigError,
    DataFormatError,
    EdmError,
    NumericsWarning,
    ResultFormatError,
)
from edm_sym.matrix import Compensator, ElementMatrix, Gene, Row, make_matrix
from edm_sym.result import EdmResult, load_result, save_result
from edm_sym.simulate import Simulation, simulate
from edm_sym.version import __version__

__all__ = [
    "Compensator",
    "ConfigError",
    "DataFormatError",
    "DataLog",
    "EdmError",
    "EdmResult",
    "ElementMatrix",
    "Gene",
    "NumericsWarning",
    "ResultFormatError",
    "Row",
    "Simulation",
    "__version__",
    "decode",
    "export",
    "load_data",
    "load_result",
    "make_matrix",
    "save_result",
    "simulate",
]


def decode(result: EdmResult | Compensator, **options: Any) -> Any:
    """Decode a result into its symbolic model (sympy and python-control per row).

    Parameters
    ----------
    result : EdmResult or Compensator
        The model to decode.
    **options
        Passed to :func:`edm_sym.symbolic.decode`.

    Returns
    -------
    edm_sym.symbolic.SymbolicModel
    """
    from edm_sym.symbolic import decode as _decode  # sympy is imported only here

    return _decode(result, **options)


def export(result: EdmResult, target: str, out_dir: str | Path, **options: Any) -> list[Path]:
    """Render a result as C, Python, LaTeX or all of them into ``out_dir``.

    Parameters
    ----------
    result : EdmResult
        The model to export.
    target : {"c", "python", "latex", "all"}
        What to write.
    out_dir : path-like
        The output folder.
    **options
        ``prefix``, ``real`` and the report's options; see
        :func:`edm_sym.exporting.export`.

    Returns
    -------
    list of pathlib.Path
        The files written.
    """
    from edm_sym.exporting import export as _export  # jinja2 is imported only here

    return _export(result, target, out_dir, **options)
