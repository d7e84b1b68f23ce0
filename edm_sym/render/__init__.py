"""Rendering: the compensator as files (C for drive firmware, standalone Python).

The only layer that imports jinja2. :func:`export` decodes a result into the
symbolic model once, builds each target's validated context
(:mod:`edm_sym.render.context`), renders the templates the fixed table
:data:`~edm_sym.render.writer.TARGETS` names, and writes the files atomically.
Equal inputs give byte-identical files (no timestamps, fixed float formats).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from edm_sym.data import is_plant_spec
from edm_sym.errors import ToolMissingError
from edm_sym.render.context import source_of, validate_prefix, validate_real
from edm_sym.render.writer import ALL, TARGETS, OutputError, render_target, write_files

__all__ = ["ALL", "TARGETS", "OutputError", "export", "render"]

#: The target written by :mod:`edm_sym.report` rather than by a code template.
REPORT = "latex"
#: The values ``target`` accepts.
TARGET_NAMES = ("c", "python", "latex", "all")


def _targets(target: str) -> list[str]:
    if target not in TARGET_NAMES:
        raise ValueError(f"--target: expected one of {', '.join(TARGET_NAMES)}, found {target!r}")
    return list(ALL) if target == "all" else [target]


def render(result: Any, target: str, *, prefix: str = "edm_comp",
           real: str = "double") -> dict[str, str]:
    """Render ``result`` for ``target`` in memory.

    Parameters
    ----------
    result : EdmResult
    target : {"c", "python", "latex", "all"}
    prefix : str
        A C identifier naming the files and every exported symbol.
    real : {"float", "double"}
        The C real type.

    Returns
    -------
    dict of str to str
        File name -> text, in the order the files are written.

    Raises
    ------
    ValueError
        On a bad ``target``, ``prefix`` or ``real`` (one-line message).
    ToolMissingError
        For ``target="latex"``, which is not available yet.
    """
    validate_prefix(prefix)
    validate_real(real)
    names = _targets(target)
    from edm_sym.symbolic.model import build_model  # sympy only when rendering

    source = source_of(result)
    model = build_model(result.compensator, sha256=source.sha256, target=result.target)
    files: dict[str, str] = {}
    for name in names:
        if name in TARGETS:  # the report (latex) is written by edm_sym.report
            files.update(render_target(name, model, source, prefix=prefix, real=real))
    return files


def export(result: Any, target: str, out_dir: str | Path, *, prefix: str = "edm_comp",
           real: str = "double", pdf: bool = False, data: Any = None, eval_data: Any = None,
           lugre: Any = None, ts: float | None = None) -> list[Path]:
    """Render ``result`` as C, Python (or, later, LaTeX) files into ``out_dir``.

    Parameters
    ----------
    result : EdmResult
        The model to export (``edm_sym.load_result``).
    target : {"c", "python", "latex", "all"}
        ``"c"`` writes ``<prefix>.h`` and ``<prefix>.c``; ``"python"`` writes
        ``<prefix>.py``; ``"all"`` writes every available target.
    out_dir : path-like
        The output folder; created when missing.
    prefix : str
        A C identifier; default ``"edm_comp"``.
    real : {"float", "double"}
        The C real type; default ``"double"``.
    pdf, data, eval_data, lugre, ts
        Options of the LaTeX report; unused by the C and Python targets.

    Returns
    -------
    list of pathlib.Path
        The files written, in order.

    Raises
    ------
    ValueError
        On a bad ``target``, ``prefix`` or ``real``; nothing is written.
    ToolMissingError
        For ``target="latex"`` (not available yet); nothing is written.
    OutputError
        When ``out_dir`` or a file in it cannot be written.
    """
    files = render(result, target, prefix=prefix, real=real)
    if REPORT not in _targets(target):
        return write_files(out_dir, files)
    from edm_sym.report import write_report

    inputs = report_inputs(result, data=data, eval_data=eval_data, lugre=lugre)
    # The report validates its inputs before writing anything, so it goes first;
    # a missing latexmk (raised after the .tex is written) still lets the code land.
    try:
        written = write_report(result, out_dir, prefix=prefix, ts=ts, pdf=pdf, **inputs)
    except ToolMissingError:
        write_files(out_dir, files)
        raise
    return write_files(out_dir, files) + written


def report_inputs(result: Any, *, data: Any = None, eval_data: Any = None,
                  lugre: Any = None) -> dict[str, Any]:
    """The report's logs and LuGre file: the options given, else the result's ``report_inputs``.

    Paths stored in the result are relative to the folder holding it; a
    ``plant:...`` data spec is used as it is.
    """
    given = {"data": data, "eval_data": eval_data, "lugre": lugre}
    stored = getattr(result, "report_inputs", None) or {}
    base = Path(result.source).parent if getattr(result, "source", None) else Path(".")
    out = {}
    for key, value in given.items():
        if value is None and key in stored:
            spec = stored[key]
            value = spec if is_plant_spec(spec) else base / spec
        out[key] = value
    return out
