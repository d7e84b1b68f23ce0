"""Honest names in the report: which rows it may name as physics, and their flags.

The rows are judged (:func:`edm_sym.engines.symbolic.significance.judge_rows`) on the
report's last data log (the evaluation log when there is one: data the
search did not fit), so the report names rows exactly as ``edm describe``
does on that log. Every string returned here is finished LaTeX.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from edm_sym.core.bounds import bound_flags
from edm_sym.core.terms import TermKind
from edm_sym.engines.description import classify_on
from edm_sym.engines.symbolic.classify import ClassifyOptions
from edm_sym.engines.symbolic.inertia import rows_inertia
from edm_sym.engines.symbolic.model import SymbolicModel
from edm_sym.engines.symbolic.significance import JudgedRow, judge_rows
from edm_sym.outputs.printing.latex import EdmLatexPrinter
from edm_sym.outputs.report.runs import LogRun


def report_classify(result: Any, runs: Sequence[LogRun]) -> ClassifyOptions | None:
    """The classifier's options ``edm describe`` uses on the last log of ``runs`` (None: no log)."""
    if not runs or runs[-1].inputs is None:
        return None
    return classify_on(result, runs[-1].inputs)


def judge_report_rows(model: SymbolicModel, runs: Sequence[LogRun],
                      classify: ClassifyOptions | None = None) -> tuple[JudgedRow, ...]:
    """The rows judged on the last log of ``runs`` (none: nothing is measured).

    Parameters
    ----------
    model : SymbolicModel
        Decoded with ``classify``.
    runs : sequence of LogRun
    classify : ClassifyOptions, optional
        :func:`report_classify`'s, as ``edm describe`` judges.

    Returns
    -------
    tuple of JudgedRow
    """
    if not runs:
        return judge_rows(model)
    run = runs[-1]
    inputs = (None if run.inputs is None
              else [run.inputs[row.input] for row in model.compensator.matrix.rows])
    inertia = None if inputs is None else rows_inertia(
        [row.role for row in model.rows], run.rows, inputs, run.ts, run.observer_bandwidth)
    return judge_rows(model, run.rows, run.target, inputs, classify=classify, inertia=inertia)


def row_flags(p: EdmLatexPrinter, judged: JudgedRow) -> list[str]:
    """The row's flags (and its terms'), one LaTeX line each; ``unmeasured`` is left out."""
    out = []
    for f in judged.flags:
        if f.code != "unmeasured":
            out.append(rf"\textbf{{{p.text(f.code.replace('_', ' '))}}}: {p.breakable(f.message)}")
    return out


def judged_titles(judged: JudgedRow, titles: Mapping[TermKind, str]) -> list[str]:
    """What the row is called: its judged terms' titles, or ``negligible``."""
    if judged.negligible:
        return ["negligible"]
    return [titles.get(jt.term.kind, jt.term.kind.value) for jt in judged.terms]


def bounds_fact(p: EdmLatexPrinter, model: SymbolicModel) -> tuple[str, str]:
    """The report's fact line: the parameters at their range bounds, or none."""
    flags = bound_flags(model.compensator)
    text = "; ".join(f.message() for f in flags) if flags else "none"
    return ("Parameters at a range bound", p.breakable(text))



def negligible_fact(p: EdmLatexPrinter, judged: Sequence[JudgedRow], measured: bool) -> tuple[str, str]:
    """The report's fact line: the negligible (or cancelling) rows and terms, or none.

    Parameters
    ----------
    p : EdmLatexPrinter
    judged : sequence of JudgedRow
    measured : bool
        Whether a log was given (without one, nothing is measured).
    """
    if not measured:
        return ("Negligible rows and terms", "not measured (no data log given)")
    found = [f"row {j.index + 1}: {f.message}" for j in judged for f in j.flags
             if f.code in ("negligible", "cancels")]
    return ("Negligible rows and terms", p.breakable("; ".join(found)) if found else
            "none (every row and term contributes at least the threshold)")
