"""The report's logs: contributions and time responses per log, the fit per log and over all.

Logs come in two kinds, ``abstraction`` and ``evaluation``, each one or
several (``--data A B``, ``--eval-data C D``). Every log is simulated from
rest on its own (:func:`edm_sym.outputs.report.runs.run_log`) and gets its own
contribution table, figures and time responses. A kind of several logs is
also summed up over all of them (:class:`LogKind`: the RMS and RMSE of the
concatenated residuals, weighted by each log's length), and a table gives the
RMSE of each log and of each kind over all. With one log of each kind the
words and figure names are those of a one-log report. Every string returned
here is finished LaTeX.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from edm_sym.engines.symbolic.contributions import Contributions
from edm_sym.outputs.printing.latex import EdmLatexPrinter
from edm_sym.outputs.report.runs import LogRun


def _pooled(values: Sequence[float], weights: Sequence[int]) -> float:
    """The RMS over concatenated signals from each one's RMS and length."""
    n = sum(weights)
    return math.sqrt(sum(w * v * v for v, w in zip(values, weights, strict=True)) / n)


@dataclass(frozen=True)
class LogKind:
    """The logs of one kind, in the order given, and their fit over all of them.

    Attributes
    ----------
    label : str
        ``"abstraction"`` or ``"evaluation"``.
    runs : tuple of LogRun
        Each log, simulated from rest on its own.
    """

    label: str
    runs: tuple[LogRun, ...]

    @property
    def samples(self) -> int:
        """The samples of all the logs."""
        return sum(len(r.t) for r in self.runs)

    @property
    def rmse(self) -> float:
        """The RMSE of the residuals of all the logs together."""
        return _pooled([r.rmse for r in self.runs], [len(r.t) for r in self.runs])

    @property
    def lugre_rmse(self) -> float | None:
        """The LuGre model's RMSE over all the logs (None when a log has none)."""
        if any(r.lugre_rmse is None for r in self.runs):
            return None
        return _pooled([r.lugre_rmse for r in self.runs], [len(r.t) for r in self.runs])

    @property
    def contributions(self) -> Contributions:
        """Row RMS and cumulative RMSE over all the logs (one log: its own)."""
        if len(self.runs) == 1:
            return self.runs[0].contributions
        w = [len(r.t) for r in self.runs]
        cs = [r.contributions for r in self.runs]
        return Contributions(
            tuple(_pooled(v, w) for v in zip(*(c.rms for c in cs), strict=True)),
            tuple(_pooled(v, w) for v in zip(*(c.rmse_cumulative for c in cs), strict=True)),
            _pooled([c.rmse_none for c in cs], w))

    def phrase(self, p: EdmLatexPrinter) -> str:
        """``the abstraction log``, or ``all 3 abstraction logs``."""
        n = len(self.runs)
        return p.text(f"the {self.label} log" if n == 1 else f"all {n} {self.label} logs")


def log_kinds(runs: Sequence[LogRun]) -> list[LogKind]:
    """The runs grouped by kind, abstraction first; kinds without a log left out."""
    return [LogKind(label, tuple(r for r in runs if r.label == label))
            for label in ("abstraction", "evaluation") if any(r.label == label for r in runs)]


def number_runs(runs: Sequence[LogRun]) -> list[LogRun]:
    """The runs with their place among the logs of their kind (``number`` of ``of``)."""
    from dataclasses import replace

    out = []
    for kind in log_kinds(runs):
        out += [replace(r, number=k + 1, of=len(kind.runs)) for k, r in enumerate(kind.runs)]
    return out


def log_phrase(p: EdmLatexPrinter, r: LogRun, *, named: bool = True) -> str:
    """``the abstraction log a.csv``; with several of a kind ``abstraction log 2 of 3, b.csv``."""
    if r.of == 1:
        return f"the {p.text(r.label)} log" + (f" {p.mono(r.name)}" if named else "")
    return f"{p.text(r.label)} log {r.number} of {r.of}, {p.mono(r.name)}"


def figure_entry(figures: Mapping[str, str], key: str, caption: str, width: float
                 ) -> dict[str, str] | None:
    """A drawn figure's file, caption, label and width (None when it was not drawn)."""
    if key not in figures:
        return None
    return {"file": figures[key], "caption": caption, "label": f"fig:{key.replace('_', '-')}",
            "width": f"{width:.2f}"}


def _contribution_table(p: EdmLatexPrinter, c: Contributions, title: str, where: str,
                        figures: list[dict[str, str]]) -> dict[str, Any]:
    rows = [{"row": p.math(p.signal("y", k + 1)), "rms": p.math(p.number(rms)),
             "rmse": p.math(p.number(e)), "drop": p.math(p.number(d))}
            for k, (rms, e, d) in enumerate(zip(c.rms, c.rmse_cumulative, c.improvement,
                                                strict=True))]
    worse = [k for k, d in enumerate(c.improvement) if d < 0]
    warn = []
    if worse:
        names = ", ".join(p.math(p.signal("y", k + 1)) for k in worse)
        warn.append(f"Adding {names} makes the fit on {where} worse (a negative drop): "
                    "check the sign and size of "
                    + ("that row" if len(worse) == 1 else "those rows") + ".")
    return {"title": title, "warnings": warn, "baseline": p.math(p.number(c.rmse_none)),
            "rows": rows, "figures": figures}


def contribution_tables(p: EdmLatexPrinter, runs: Sequence[LogRun],
                        figures: Mapping[str, str]) -> list[dict[str, Any]]:
    """Each log's contribution table and figures; a kind of several logs also over all."""
    out = []
    for kind in log_kinds(runs):
        for r in kind.runs:
            drawn = [f for f in (
                figure_entry(figures, f"contributions_{r.key}",
                        f"Row contributions on {log_phrase(p, r)}: RMS of each row's output "
                        "(left) and the RMSE as the rows are added one by one (right).", 0.95),
                figure_entry(figures, f"rows_{r.key}",
                        f"Output of each row on {log_phrase(p, r, named=r.of > 1)}, on a common "
                        "scale (signal flow of the element matrix).", 0.95)) if f]
            # A file name in typewriter type, plain in the PDF's bookmarks.
            title = (f"On the {p.text(r.label)} log" if r.of == 1
                     else f"On {p.text(r.label)} log {r.number} of {r.of}, "
                          rf"\texorpdfstring{{{p.mono(r.name)}}}{{{p.text(r.name)}}}")
            where = "this log" if r.of == 1 else log_phrase(p, r)
            out.append(_contribution_table(p, r.contributions, title, where, drawn))
        if len(kind.runs) > 1:
            out.append(_contribution_table(
                p, kind.contributions, f"Over {kind.phrase(p)}", kind.phrase(p), []))
    return out


def time_figures(p: EdmLatexPrinter, runs: Sequence[LogRun], figures: Mapping[str, str],
                 effort: str) -> list[dict[str, str]]:
    """The time responses of every log: over the whole log and enlarged."""
    out = []
    for kind in log_kinds(runs):
        for r in kind.runs:
            vs = ", the LuGre model's," if r.lugre is not None else ""
            for key, what in ((f"time_{r.key}", "over the whole log"),
                              (f"zoom_{r.key}", "enlarged where the EDM residual is largest")):
                f = figure_entry(figures, key, f"Target {effort}, EDM compensation {effort}{vs} and "
                            f"the residuals on {log_phrase(p, r)}, {what}.", 1.0)
                if f:
                    out.append(f)
    return out


def log_rmse(p: EdmLatexPrinter, runs: Sequence[LogRun], compared: bool) -> list[dict[str, Any]]:
    """The RMSE on each log and over all logs of a kind: one table when a kind has several.

    ``compared``: a LuGre file was given, so every log has the LuGre model's too.
    """
    kinds = log_kinds(runs)
    if all(len(k.runs) == 1 for k in kinds):
        return []

    def cells(label: str, name: str, samples: int, edm: float, lugre: float | None) -> dict:
        return {"log": p.text(label), "name": name, "samples": str(samples),
                "rmse": p.math(p.number(edm)),
                "lugre": [p.math(p.number(lugre))] if compared else []}

    rows = []
    for kind in kinds:
        rows += [cells(r.label, p.mono(r.name), len(r.t), r.rmse, r.lugre_rmse)
                 for r in kind.runs]
        if len(kind.runs) > 1:
            rows.append(cells(kind.label, p.text(f"over all {len(kind.runs)} logs"),
                              kind.samples, kind.rmse, kind.lugre_rmse))
    return [{"lugre_head": [p.text("LuGre")] if compared else [], "rows": rows}]


def log_facts(p: EdmLatexPrinter, runs: Sequence[LogRun], force_unit: str
              ) -> list[tuple[str, str]]:
    """The summary's lines on the logs: each log, its sha256 and RMSE, where the model
    extrapolates on it; a kind's RMSE over all."""
    facts = []
    for kind in log_kinds(runs):
        for r in kind.runs:
            # Short labels with several logs: the summary's first column is narrow.
            name, about = ((f"{r.label.capitalize()} log", f" the {r.label} log") if r.of == 1
                           else (f"{r.label.capitalize()} log {r.number} of {r.of}",
                                 f", {r.label} log {r.number}"))
            facts.append((name, f"{p.mono(r.name)}, {len(r.t)} samples, "
                                f"{p.math(p.number(r.duration))}~s"))
            if r.sha256:
                facts.append((f"sha256{' of' if r.of == 1 else ''}{about}", p.digest(r.sha256)))
            facts.append((f"RMSE{' on' if r.of == 1 else ''}{about}",
                          p.math(p.number(r.rmse)) + "~" + force_unit))
            # Where the model extrapolates on this log (the line of edm simulate).
            facts += [(f"Beyond the training range{',' if r.of == 1 else ''}{about}", p.text(line))
                      for line in r.beyond]
        if len(kind.runs) > 1:
            facts.append((f"RMSE, all {len(kind.runs)} {kind.label} logs",
                          p.math(p.number(kind.rmse)) + "~" + force_unit
                          + f" ({kind.samples} samples, each log simulated from rest)"))
    return facts
