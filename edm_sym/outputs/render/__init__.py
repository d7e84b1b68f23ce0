"""Rendering: the compensator as code (C for drive firmware, standalone Python).

The only layer that imports jinja2. :func:`render` takes the symbolic model
(made once by the caller, or here from the result's stages), builds each
target's validated context (:mod:`edm_sym.outputs.render.context`) and renders the
templates the fixed table :data:`~edm_sym.outputs.render.writer.TARGETS` names;
:func:`~edm_sym.outputs.render.writer.write_files` writes them atomically. Equal inputs
give byte-identical files (no timestamps, fixed float formats). The LaTeX
report (:mod:`edm_sym.outputs.report`) uses this package's environment and writer;
:func:`edm_sym.application.exporting.export` puts code and report together.
"""

from __future__ import annotations

from typing import Any

from edm_sym.outputs.render.context import source_of, validate_prefix, validate_real
from edm_sym.outputs.render.writer import ALL, TARGETS, OutputError, render_target, write_files

__all__ = ["ALL", "TARGETS", "OutputError", "render", "target_names", "write_files"]

#: The target written by :mod:`edm_sym.outputs.report` rather than by a code template.
REPORT = "latex"
#: The values ``target`` accepts.
TARGET_NAMES = ("c", "python", "latex", "test", "all")


def target_names(target: str) -> list[str]:
    """The targets ``target`` stands for (``"all"`` is every one), or ValueError."""
    if target not in TARGET_NAMES:
        raise ValueError(f"target: expected one of {', '.join(TARGET_NAMES)}, found {target!r}")
    return list(ALL) if target == "all" else [target]


def render(result: Any, target: str, *, prefix: str = "edm_comp",
           real: str = "double", model: Any = None,
           options: dict[str, Any] | None = None) -> dict[str, str]:
    """Render the code of ``result`` for ``target`` in memory.

    Parameters
    ----------
    result : EdmResult
    target : {"c", "python", "latex", "test", "all"}
    prefix : str
        A C identifier naming the files and every exported symbol.
    real : {"float", "double", "q31", "q15"}
        The C real type, or a fixed-point build.
    options : dict, optional
        The fixed-point options: ``build`` (a checked
        :class:`~edm_sym.engines.fixedpoint.Build`, made here when missing) and
        ``input_range`` (input name -> (lo, hi), over the recorded ranges).
    model : SymbolicModel, optional
        The result's model when the caller has made it (every target reads
        the same one); else its stages are built here.

    Returns
    -------
    dict of str to str
        File name -> text, in the order the files are written. The LaTeX
        report is not among them: :mod:`edm_sym.outputs.report` writes it.

    Raises
    ------
    ValueError
        On a bad ``target``, ``prefix`` or ``real``, or a ``model`` of another
        axis than the result's (one-line message).
    """
    validate_prefix(prefix)
    validate_real(real)
    names = target_names(target)
    source = source_of(result)
    if model is None:
        from edm_sym.engines.symbolic.model import build_model  # sympy only when rendering

        model = build_model(result.compensator, sha256=source.sha256, target=result.target,
                            axis=source.axis)
    elif model.axis != source.axis:  # the comments would print one axis's units for the other's
        raise ValueError(f"model: axis: expected {source.axis!r} as in {source.name}, found "
                         f"{model.axis!r}; hint: build the model with axis=result.axis")
    files: dict[str, str] = {}
    for name in names:
        if name in TARGETS:  # the report (latex) is written by edm_sym.outputs.report
            files.update(render_target(name, model, source, prefix=prefix, real=real,
                                       options=options))
    return files
