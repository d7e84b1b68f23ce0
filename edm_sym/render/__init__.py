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

from edm_sym.errors import ToolMissingError
from edm_sym.render.context import source_of, validate_prefix, validate_real
from edm_sym.render.writer import ALL, TARGETS, OutputError, render_target, write_files

__all__ = ["ALL", "TARGETS", "OutputError", "export", "render"]

#: The values ``target`` accepts.
TARGET_NAMES = ("c", "python", "latex", "all")


def _targets(target: str) -> list[str]:
    if target not in TARGET_NAMES:
        raise ValueError(f"--target: expected one of {', '.join(TARGET_NAMES)}, found {target!r}")
    if target == "all":
        return [t for t in ALL if t in TARGETS]
    if target not in TARGETS:
        raise ToolMissingError(f"--target {target}: the LaTeX report is not available yet "
                               "(use --target c or --target python)")
    return [target]


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
    return write_files(out_dir, files)
