"""``write_report``: the LaTeX model report of a result, with its figures and PDF."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from edm_sym.outputs.report import figures as fg
from edm_sym.outputs.report.context import ReportInputs, package_versions, report_context
from edm_sym.outputs.report.flags import report_classify
from edm_sym.outputs.report.front import FIGURE as FRONT
from edm_sym.outputs.report.front import front_figure
from edm_sym.outputs.report.logs import number_runs
from edm_sym.outputs.report.runs import LogRun, SteadyState, load_log, load_lugre_ref, run_log, steady_state

#: The template of the report (in the templates folder).
TEMPLATE = "report.tex.j2"


def _default_velocity(axis: str) -> float:
    """Velocity range of the friction characteristic without a data log, in the axis's unit.

    The classification's default velocity range of the axis (10 rad/s rotary,
    0.5 m/s linear: ``ClassifyOptions.for_axis``).
    """
    from edm_sym.engines.symbolic.classify import ClassifyOptions

    return ClassifyOptions.for_axis(axis).velocity_range


def figure_name(prefix: str, key: str) -> str:
    """The file name of a figure: ``<prefix>_fig_<key>.pdf``."""
    return f"{prefix}_fig_{key}.pdf"


def draw_figures(result: Any, runs: list[LogRun], out_dir: Path, prefix: str,
                 steady: SteadyState | None = None) -> dict[str, Path]:
    """Draw every figure the inputs allow; return figure key -> path.

    Parameters
    ----------
    result : EdmResult
    runs : list of LogRun
        The compensator on every abstraction and evaluation log (each drawn).
    out_dir : pathlib.Path
    prefix : str
    steady : SteadyState, optional
        The friction characteristic.
    """
    out: dict[str, Path] = {}
    units = result.units  # every figure's units follow the result's axis

    def path(key: str) -> Path:
        return out_dir / figure_name(prefix, key)

    if steady is not None and steady.rows:
        curves = [(f"$y_{{{j + 1}}}$", y) for j, y in zip(steady.rows, steady.torque, strict=True)]
        out["friction"] = fg.friction_curve(steady.velocity, curves, path("friction"),
                                            lugre=steady.lugre, units=units)
    if result.steps:
        hist = [(f"Step {s.step} ({s.matrix.n_elements}x{s.matrix.n_rows})", s.history)
                for s in result.steps]
        out["fitness"] = fg.fitness_history(hist, path("fitness"), units=units)
    if getattr(result, "parsimony", None):
        out[FRONT] = front_figure(result, path(FRONT))
    for r in runs:
        labels = [f"$y_{{{k + 1}}}$" for k in range(len(r.rows))]
        c = r.contributions
        out[f"contributions_{r.key}"] = fg.contributions(
            labels, c.rms, c.rmse_cumulative, path(f"contributions_{r.key}"),
            baseline=c.rmse_none, units=units)
        out[f"rows_{r.key}"] = fg.row_outputs(r.t, r.rows, path(f"rows_{r.key}"),
                                              labels=labels)
        others = [("LuGre (conventional)", r.lugre)] if r.lugre is not None else []
        title = f"{r.label} log" + ("" if r.of == 1 else f" {r.number} of {r.of}: {r.name}")
        out[f"time_{r.key}"] = fg.time_series(r.t, r.target, r.total, path(f"time_{r.key}"),
                                              title=title, others=others, units=units)
        window = fg.zoom_window(r.t, r.residual)
        out[f"zoom_{r.key}"] = fg.time_series(
            r.t, r.target, r.total, path(f"zoom_{r.key}"), others=others, window=window,
            title=f"{window[0]:.3g} s to {window[1]:.3g} s", units=units)
    return out


def render_report(inputs: ReportInputs) -> str:
    """The report's LaTeX text (no files written).

    Parameters
    ----------
    inputs : ReportInputs

    Returns
    -------
    str
    """
    from edm_sym.outputs.render.environment import environment

    return environment().get_template(TEMPLATE).render(report_context(inputs))


def write_report(result: Any, out_dir: str | Path, *, prefix: str = "edm_comp", model: Any = None,
                 data: str | Path | Sequence[str | Path] | None = None,
                 eval_data: str | Path | Sequence[str | Path] | None = None,
                 lugre: str | Path | None = None, ts: float | None = None,
                 pdf: bool = False) -> list[Path]:
    """Write the LaTeX model report of ``result`` (and compile it with ``pdf=True``).

    Parameters
    ----------
    result : EdmResult
        The compensator (``edm_sym.load_result``).
    out_dir : path-like
        The output folder; created when missing.
    prefix : str
        File prefix: ``<prefix>_report.tex``, ``<prefix>_fig_*.pdf``, ``<prefix>_report.pdf``.
    model : SymbolicModel, optional
        ``edm_sym.decode(result)`` when the caller has it already.
    data : path-like or list of them, optional
        The abstraction log: RMSE, row contributions, time responses. With
        several logs each is simulated from rest and gets its own
        contributions and time responses, and the fit is given on each and
        over all of them.
    eval_data : path-like or list of them, optional
        An evaluation log (or several): the same on new data.
    lugre : path-like, optional
        A LUGRE.json: the comparison with the LuGre model (on the evaluation
        log, else on the abstraction log).
    ts : float, optional
        Sample time of logs without a ``t`` column.
    pdf : bool
        Also compile ``<prefix>_report.pdf`` with latexmk.

    Returns
    -------
    list of pathlib.Path
        The .tex, the figures and (with ``pdf``) the PDF, in that order.

    Raises
    ------
    ValueError
        On a bad prefix (one line); nothing is written.
    ResultFormatError, DataFormatError
        On a bad LuGre file or data log; nothing is written.
    ToolMissingError
        With ``pdf=True`` and no latexmk; raised after the .tex and figures are written.
    LatexError
        When LaTeX fails on the report.
    """
    from edm_sym.outputs.render.context import source_of, validate_prefix
    from edm_sym.outputs.render.writer import write_files

    validate_prefix(prefix)
    out = Path(out_dir)
    ref = load_lugre_ref(lugre) if lugre is not None else None
    every: list[LogRun] = []  # each log simulated from rest on its own
    v_max = 0.0
    for label, given in (("abstraction", data), ("evaluation", eval_data)):
        paths = [] if given is None else [given] if isinstance(given, (str, Path)) else list(given)
        every += [run_log(result, load_log(path, result, ts=ts, lugre=ref), label=label,
                          lugre=ref) for path in paths]
    every = number_runs(every)
    runs = {r.label: r for r in every if r.number == 1}  # the first of each kind
    more = [r for r in every if r.number > 1]
    # Decoded and judged as `edm describe` does on the same log (the last one), so both
    # name the rows alike.
    classify = report_classify(result, list(runs.values()))
    if model is None:
        from edm_sym.engines.symbolic import decode

        model = decode(result, classify=classify) if classify is not None else decode(result)
    roles = [row.role for row in model.rows]
    for run in every:
        for j, role in enumerate(roles):
            if role == "velocity":
                signal = run.inputs[result.compensator.matrix.rows[j].input]
                v_max = max(v_max, float(np.max(np.abs(signal))))
    steady = steady_state(result, roles, v_max or _default_velocity(result.axis), lugre=ref)
    source = source_of(result)
    # Render before writing anything, so a failure leaves no file behind.
    inputs = ReportInputs(result, model, source.name, source.sha256, prefix,
                          runs.get("abstraction"), runs.get("evaluation"), ref,
                          {k: figure_name(prefix, k) for k in _figure_keys(result, every, steady)},
                          package_versions(), ts, steady, classify, tuple(more))
    text = render_report(inputs)
    tex_name = f"{prefix}_report.tex"
    written = write_files(out, {tex_name: text})
    drawn = draw_figures(result, every, out, prefix, steady)
    if set(drawn) != set(inputs.figures):  # the context names exactly the drawn figures
        raise RuntimeError(f"report figures: drew {sorted(drawn)}, the report names "
                           f"{sorted(inputs.figures)}")
    written += [drawn[k] for k in sorted(drawn)]
    if pdf:
        from edm_sym.outputs.report.pdf import compile_pdf

        pdf_path, _ = compile_pdf(written[0])
        written.append(pdf_path)
    return written


def _figure_keys(result: Any, runs: list[LogRun], steady: SteadyState | None) -> list[str]:
    keys = ["friction"] if steady is not None and steady.rows else []
    keys += ["fitness"] if result.steps else []
    keys += [FRONT] if getattr(result, "parsimony", None) else []
    for r in runs:
        keys += [f"{k}_{r.key}" for k in ("contributions", "rows", "time", "zoom")]
    return keys
