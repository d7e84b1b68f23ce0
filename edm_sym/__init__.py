"""edm_sym: Element Description Method compensators for reaction torque observers.

The public API (docs/api.md#python-api)::

    import edm_sym
    result = edm_sym.load_result("result.json")
    data = edm_sym.load_data("log.csv")
    sim = edm_sym.simulate(result, data)      # sim.rows (m, N), sim.total (N,)
    print(edm_sym.describe(result, data).table())  # terms, contributions, flags
    model = edm_sym.decode(result)            # sympy + python-control per row
    edm_sym.export(result, "c", "out/")

``edm_sym.EDMRegressor`` (docs/estimator.md) needs the optional extra
``edm_sym[sklearn]``; it is imported on first access, so ``import edm_sym``
never imports scikit-learn.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

from edm_sym.core import display as _display  # no dependencies: safe before Ctrl-C handling

# Nothing heavy is imported here: `edm` and `edm-export` import this package first, and
# they must be able to catch Ctrl-C and SIGTERM before numpy and scipy load (docs/cli.md).
# The public names resolve on first access (__getattr__ below).
if TYPE_CHECKING:
    from edm_sym.core.data import ColumnRoles, DataLog
    from edm_sym.core.errors import ConfigError, DataFormatError, EdmError, NumericsWarning, ResultFormatError
    from edm_sym.core.matrix import Compensator, ElementMatrix, Gene, Row, make_matrix
    from edm_sym.core.result import EdmResult, load_result, save_result
    from edm_sym.core.version import __version__
    from edm_sym.engines.description import Description
    from edm_sym.engines.simulate import Simulation, simulate
    from edm_sym.engines.sources import load_data
    from edm_sym.engines.symbolic.classify import ClassifyOptions
    from edm_sym.engines.symbolic.model import SymbolicModel
    from edm_sym.engines.symbolic.significance import SignificanceOptions
    from edm_sym.engines.symbolic.simplify import SimplifyOptions

__all__ = [
    "ColumnRoles",
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
    "describe",
    "export",
    "load_data",
    "load_result",
    "make_matrix",
    "save_result",
    "simulate",
]


# The three functions below only import their implementation on first call, so they
# repeat its signature (tests/test_api_bad_input.py checks that the two agree).


def decode(
    result: EdmResult | Compensator,
    *,
    roles: Mapping[str, str | None] | None = None,
    simplify: SimplifyOptions | None = None,
    classify: ClassifyOptions | bool | None = None,
    systems: bool = True,
    axis: str | None = None,
) -> SymbolicModel:
    """Decode a result into its symbolic model (sympy and python-control per row).

    Parameters
    ----------
    result : EdmResult or Compensator
        The model to decode.
    roles, simplify, classify, systems, axis
        The input roles over the recorded ones, the simplification passes, the
        classifier's thresholds (False: no physical terms), whether to build the
        python-control systems, the axis's units; see
        :func:`edm_sym.engines.symbolic.decode`.

    Returns
    -------
    edm_sym.engines.symbolic.SymbolicModel
    """
    from edm_sym.engines.symbolic import decode as _decode  # sympy is imported only here

    return _decode(result, roles=roles, simplify=simplify, classify=classify, systems=systems,
                   axis=axis)


def describe(
    result: EdmResult | str | Path,
    data: DataLog | str | Path | None = None,
    *,
    ts: float | None = None,
    options: SignificanceOptions | None = None,
    roles: Mapping[str, str | None] | None = None,
    axis: str | None = None,
    columns: ColumnRoles | None = None,
    resample: bool = False,
    observer_bandwidth: float | None = None,
) -> Description:
    """What a model found, row by row: physical terms, contribution, flags (``edm describe``).

    Parameters
    ----------
    result : EdmResult or path-like
        The result (a path is loaded).
    data : DataLog, path-like or str, optional
        The log the contributions are measured on; default: the data the
        result records (``report_inputs.data``), else none.
    ts, options, roles, axis, columns, resample, observer_bandwidth
        A sample time for a log without a time column, the thresholds (a
        ``SignificanceOptions``), input roles, the axis, the log's column
        roles, resampling a log onto the result's grid, the observer's
        bandwidth; see :func:`edm_sym.engines.description.describe`.

    Returns
    -------
    edm_sym.engines.description.Description
        ``.table()`` for people, ``.to_json()`` for the shape of docs/describe.md.
    """
    from edm_sym.engines.description import describe as _describe  # sympy is imported only here

    return _describe(result, data, ts=ts, options=options, roles=roles, axis=axis,
                     columns=columns, resample=resample, observer_bandwidth=observer_bandwidth)


def export(
    result: EdmResult,
    target: str,
    out_dir: str | Path,
    *,
    prefix: str = "edm_comp",
    real: str = "double",
    pdf: bool = False,
    data: Any = None,
    eval_data: Any = None,
    lugre: Any = None,
    ts: float | None = None,
    input_range: Mapping[str, tuple[float, float]] | None = None,
) -> list[Path]:
    """Render a result as C, Python, LaTeX or all of them into ``out_dir``.

    Parameters
    ----------
    result : EdmResult
        The model to export.
    target : {"c", "python", "latex", "test", "all"}
        What to write.
    out_dir : path-like
        The output folder.
    prefix, real, pdf, data, eval_data, lugre, ts, input_range
        The file and symbol prefix, the C real type (or a fixed-point build),
        and the report's options; see :func:`edm_sym.application.exporting.export`.

    Returns
    -------
    list of pathlib.Path
        The files written.
    """
    from edm_sym.application.exporting import export as _export  # jinja2 is imported only here

    return _export(result, target, out_dir, prefix=prefix, real=real, pdf=pdf, data=data,
                   eval_data=eval_data, lugre=lugre, ts=ts, input_range=input_range)


def _model_latex(model: Any) -> str:
    from edm_sym.outputs.printing.latex import model_latex  # the one place that writes LaTeX

    return model_latex(model)


def _result_latex(result: EdmResult) -> str:
    return _model_latex(decode(result, classify=False, systems=False))


# Jupyter's rich display of results and models: core and engines know no LaTeX, so the
# package face (which may import every layer) hands them the printer's renderers.
_display.register_latex("model", _model_latex)
_display.register_latex("result", _result_latex)

#: Names resolved on first access: name -> module.
_LAZY = {
    "DataLog": "edm_sym.core.data", "ColumnRoles": "edm_sym.core.data",
    "ConfigError": "edm_sym.core.errors", "DataFormatError": "edm_sym.core.errors",
    "EdmError": "edm_sym.core.errors", "NumericsWarning": "edm_sym.core.errors",
    "ResultFormatError": "edm_sym.core.errors",
    "Compensator": "edm_sym.core.matrix", "ElementMatrix": "edm_sym.core.matrix",
    "Gene": "edm_sym.core.matrix", "Row": "edm_sym.core.matrix", "make_matrix": "edm_sym.core.matrix",
    "EdmResult": "edm_sym.core.result", "load_result": "edm_sym.core.result",
    "save_result": "edm_sym.core.result",
    "__version__": "edm_sym.core.version",
    "Simulation": "edm_sym.engines.simulate", "simulate": "edm_sym.engines.simulate",
    "load_data": "edm_sym.engines.sources",
    # needs scikit-learn (the extra edm_sym[sklearn])
    "EDMRegressor": "edm_sym.application.estimator",
}


def __getattr__(name: str) -> Any:
    """The public names, imported on first use (``EDMRegressor`` needs scikit-learn)."""
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 'edm_sym' has no attribute {name!r}")
    import importlib

    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY))
