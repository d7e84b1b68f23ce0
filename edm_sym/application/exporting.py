"""Export: a result as code and report, from one symbolic model (the application layer).

:func:`export` (and :func:`export_files`, which also returns what a fixed-point
build states about its deviation) checks the options, makes the stages of the result's symbolic
model the code needs and hands them to the code renderer
(:mod:`edm_sym.outputs.render`); the report (:mod:`edm_sym.outputs.report`)
decodes the whole model itself, with the classifier options of the data it
is judged on, as ``edm describe`` does. ``edm_sym.export`` and ``edm export``
call it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from edm_sym.core.budget import check_state
from edm_sym.core.data import is_plant_spec
from edm_sym.core.errors import ExternalToolError, ToolMissingError
from edm_sym.outputs.render import REPORT, render, target_names, write_files
from edm_sym.outputs.render.context import FIXED_REALS, source_of, validate_prefix, validate_real

__all__ = ["Exported", "export", "export_files", "recorded_log", "report_inputs"]


@dataclass(frozen=True)
class Exported:
    """What :func:`export_files` wrote, and what it states beside the files.

    Attributes
    ----------
    files : list of pathlib.Path
        The files written, in order.
    notes : tuple of str
        The lines a fixed-point build states about its deviation (``"q31: ..."``).
    """

    files: list[Path]
    notes: tuple[str, ...] = ()


def export(result: Any, target: str, out_dir: str | Path, *, prefix: str = "edm_comp",
           real: str = "double", pdf: bool = False, data: Any = None, eval_data: Any = None,
           lugre: Any = None, ts: float | None = None, input_range: Any = None) -> list[Path]:
    """Render ``result`` as C, Python, the LaTeX report or all of them into ``out_dir``.

    Parameters
    ----------
    result : EdmResult
        The model to export (``edm_sym.load_result``).
    target : {"c", "python", "latex", "all"}
        ``"c"`` writes ``<prefix>.h`` and ``<prefix>.c``; ``"python"`` writes
        ``<prefix>.py``; ``"latex"`` writes the report ``<prefix>_report.tex``
        and its figures; ``"all"`` writes every target from one decoding.
    out_dir : path-like
        The output folder; created when missing.
    prefix : str
        A C identifier; default ``"edm_comp"``.
    real : {"float", "double", "q31", "q15"}
        The C real type, or an integer-only fixed-point build; default ``"double"``.
    pdf, data, eval_data, lugre, ts
        Options of the LaTeX report (see :func:`edm_sym.outputs.report.write_report`).
        ``data`` (else ``eval_data``, else the result's stored logs) also sizes a
        fixed-point build and gives the kit's vectors (:func:`recorded_log`).
    input_range : mapping of str to (float, float), optional
        Input ranges over those the result records (fixed-point builds and the kit).

    Returns
    -------
    list of pathlib.Path
        The files written, in order (:func:`export_files` also gives what a
        fixed-point build states about its deviation).

    Raises
    ------
    ValueError
        On a bad ``target``, ``prefix`` or ``real``; nothing is written.
    BudgetError
        When the compensator's state exceeds the limit of
        :data:`edm_sym.core.budget.STATE_LIMIT_BYTES` (256 MiB); above 1 MiB
        a :class:`~edm_sym.core.errors.BudgetWarning` gives the figure.
    ToolMissingError
        With ``pdf=True`` and no latexmk; the .tex, figures and code are written.
    OutputError
        When ``out_dir`` or a file in it cannot be written.
    """
    return export_files(result, target, out_dir, prefix=prefix, real=real, pdf=pdf, data=data,
                        eval_data=eval_data, lugre=lugre, ts=ts, input_range=input_range).files


def export_files(result: Any, target: str, out_dir: str | Path, *, prefix: str = "edm_comp",
                 real: str = "double", pdf: bool = False, data: Any = None, eval_data: Any = None,
                 lugre: Any = None, ts: float | None = None, input_range: Any = None) -> Exported:
    """:func:`export`, and also what a fixed-point build states about its deviation.

    Parameters
    ----------
    result, target, out_dir, prefix, real, pdf, data, eval_data, lugre, ts, input_range
        As for :func:`export`.

    Returns
    -------
    Exported
        The files written, in order, and the lines a fixed-point build states.
    """
    validate_prefix(prefix)
    validate_real(real)
    names = target_names(target)
    # The state a compensator keeps is sized before anything is decoded or written.
    comp = result.compensator
    check_state([g.element.state_size(comp.value(g), comp.sample_time)
                 for row in comp.matrix.rows for g in row.genes],
                real if "c" in names else "double", source_of(result).name)
    from edm_sym.engines.symbolic import build_model  # sympy only when exporting

    source = source_of(result)
    # The axis given explicitly: the model's units (N or N m in the header's and module's
    # comments) are the result's, never a default. The report decodes its own model,
    # judged on its data as `edm describe` does.
    model = build_model(result.compensator, sha256=source.sha256, target=result.target,
                        axis=source.axis)
    options: dict[str, Any] = {"input_range": input_range}
    notes: tuple[str, ...] = ()
    if "test" in names or (real in FIXED_REALS and "c" in names):
        options["log"] = recorded_log(result, data=data, eval_data=eval_data)
    if real in FIXED_REALS and ({"c", "test"} & set(names)):
        from edm_sym.core.units import axis_units
        from edm_sym.outputs.render.fixed_context import accuracy_lines, fixed_build

        options["build"] = fixed_build(model, source, real, input_range, options["log"])
        notes = tuple(f"{real}: {line}" for line in accuracy_lines(
            options["build"], axis_units(source.axis).force))
    files = render(result, target, prefix=prefix, real=real, model=model, options=options)
    if REPORT not in names:
        return Exported(write_files(out_dir, files), notes)
    from edm_sym.outputs.report import write_report

    inputs = report_inputs(result, data=data, eval_data=eval_data, lugre=lugre)
    # The report validates its inputs before writing anything, so it goes first. Each
    # target is written on its own: a PDF that fails (latexmk missing, LaTeX stopping)
    # leaves the .tex, the figures and the C and Python in place, and says so.
    try:
        # The report decodes the model itself, judged on its data as `edm describe` does.
        written = write_report(result, out_dir, prefix=prefix, ts=ts, pdf=pdf, **inputs)
    except (ToolMissingError, ExternalToolError) as exc:
        code = write_files(out_dir, files)
        if not code:
            raise
        landed = ", ".join(p.name for p in code)
        raise type(exc)(f"target latex (PDF): {exc}; the other targets were written ({landed})") \
            from None
    return Exported(write_files(out_dir, files) + written, notes)


def report_inputs(result: Any, *, data: Any = None, eval_data: Any = None,
                  lugre: Any = None) -> dict[str, Any]:
    """The report's logs and LuGre file: the options given, else the result's ``report_inputs``.

    Paths stored in the result are relative to the folder holding it; a
    ``plant:...`` data spec is used as it is.

    Parameters
    ----------
    result : EdmResult
    data, eval_data : path-like or str, or a list of several, optional
    lugre : path-like or str, optional
        Override the stored abstraction log, evaluation log and LuGre file.

    Returns
    -------
    dict
        ``data``, ``eval_data`` and ``lugre``, each a path, a plant spec or None.
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


def recorded_log(result: Any, *, data: Any = None, eval_data: Any = None
                 ) -> tuple[Any, str] | None:
    """The recorded log a fixed-point build is sized on and the kit's vectors come from.

    ``data`` (else ``eval_data``) when given, else the result's stored
    ``report_inputs`` (``data``, then ``eval_data``; a ``plant:`` spec, or a
    file relative to the result). A stored log that cannot be read, lacks an
    input or has another sample time is passed over (the synthetic excitation
    stands in); a given one is refused.

    Returns
    -------
    tuple of (numpy.ndarray, str) or None
        The model's inputs, shape (n_inputs, N), and the log's name; None when
        no log is at hand.

    Raises
    ------
    DataFormatError
        When a given log cannot be read, lacks an input or has another sample time.
    """
    import numpy as np

    from edm_sym.core.errors import DataFormatError, EdmError
    from edm_sym.engines.sources import load_data

    given = [s for s in (data, eval_data) if s is not None]
    stored = report_inputs(result)
    specs = [(s, True) for s in given] or [(stored[k], False) for k in ("data", "eval_data")
                                            if stored[k] is not None]
    ts = result.compensator.sample_time
    inputs = tuple(result.compensator.matrix.inputs)
    for spec, strict in specs:
        try:
            log = load_data(spec, default_ts=ts, require=list(inputs))
            if not math.isclose(log.ts, ts, rel_tol=1e-6):
                raise DataFormatError(f"{spec}: sample time", f"expected {ts:g} s as the "
                                      f"result's, found {log.ts:g} s")
            x = np.vstack([np.asarray(log.column(n), dtype=float) for n in inputs])
        except (EdmError, OSError):
            if strict:
                raise
            continue
        return x, str(spec)
    return None
