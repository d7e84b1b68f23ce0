"""The report's context: everything the LaTeX template shows, computed and validated here.

:func:`report_context` reads the decoded model, the runs on the data logs and
the names of the figures, and returns nested dicts and lists whose leaves are
all strings of finished LaTeX (from :class:`~edm_sym.outputs.printing.latex.EdmLatexPrinter`).
Optional parts (a data log, the fitness history, the LuGre comparison) are
lists of zero or one item, so the template needs nothing but loops.
:func:`check_report_context` refuses a context the template could not render.
"""

from __future__ import annotations

import shlex
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from edm_sym.core.units import AxisUnits, axis_units
from edm_sym.engines.fixedpoint.switching import SWITCH_LSB
from edm_sym.engines.symbolic.model import SymbolicModel
from edm_sym.outputs.printing.latex import EdmLatexPrinter
from edm_sym.outputs.report.diagrams import matrix_diagram
from edm_sym.outputs.report.fixed import fixed_context
from edm_sym.outputs.report.flags import (
    bounds_fact,
    judge_report_rows,
    judged_titles,
    negligible_fact,
)
from edm_sym.outputs.report.front import front_context
from edm_sym.outputs.report.logs import (
    contribution_tables,
    figure_entry,
    log_facts,
    log_kinds,
    log_rmse,
    time_figures,
)
from edm_sym.outputs.report.rows import (
    KIND_TITLES,
    equation_lines,
    role_title,
    row_context,
)
from edm_sym.outputs.report.runs import LogRun, LuGreRef, SteadyState
from edm_sym.outputs.report.units import param_units

#: Packages whose versions the report names.
VERSION_PACKAGES = ("edm_sym", "numpy", "scipy", "sympy", "control", "jinja2", "matplotlib")


@dataclass(frozen=True)
class ReportInputs:
    """What a report is made from.

    Attributes
    ----------
    result : EdmResult
    model : SymbolicModel
        ``edm_sym.decode(result)``.
    source_name, source_sha256 : str
        The result file's name and digest.
    prefix : str
    abstraction, evaluation : LogRun or None
        The compensator on the abstraction and evaluation logs.
    lugre : LuGreRef or None
    figures : mapping of str to str
        Figure key -> file name, for the figures that were drawn.
    versions : sequence of (str, str)
        Package name -> version.
    ts : float or None
        The ``--ts`` option the logs were read with.
    steady : SteadyState or None
        The friction characteristic of the velocity rows.
    classify : ClassifyOptions or None
        The options ``model`` was decoded and its rows are judged with
        (:func:`edm_sym.outputs.report.flags.report_classify`; None: the axis's defaults).
    more : sequence of LogRun
        Further logs of either kind after the first (``abstraction`` and
        ``evaluation`` are the first of each), numbered among their kind
        (:func:`edm_sym.outputs.report.logs.number_runs`).
    """

    result: Any
    model: SymbolicModel
    source_name: str
    source_sha256: str
    prefix: str
    abstraction: LogRun | None = None
    evaluation: LogRun | None = None
    lugre: LuGreRef | None = None
    figures: Mapping[str, str] = field(default_factory=dict)
    versions: Sequence[tuple[str, str]] = ()
    ts: float | None = None
    steady: SteadyState | None = None
    classify: Any = None
    more: Sequence[LogRun] = ()

    @property
    def logs(self) -> list[LogRun]:
        """Every log: the abstraction logs, then the evaluation logs, each in the order given."""
        return [r for first in (self.abstraction, self.evaluation) if first is not None
                for r in (first, *(m for m in self.more if m.label == first.label))]


def package_versions() -> tuple[tuple[str, str], ...]:
    """The versions of edm_sym and its main dependencies (importlib.metadata).

    Returns
    -------
    tuple of (str, str)
        ``(name, version)``, ``"not installed"`` for a missing package.
    """
    import sys
    from importlib import metadata

    out = [("python", sys.version.split()[0])]
    for name in VERSION_PACKAGES:
        try:
            out.append((name, metadata.version(name)))
        except metadata.PackageNotFoundError:
            out.append((name, "not installed"))
    return tuple(out)


# -- pieces ----------------------------------------------------------------------

def _recorded(p: EdmLatexPrinter, v: Any) -> str:
    return "not recorded" if v is None else p.text(str(v))


def _params(model: SymbolicModel) -> list[dict[str, str]]:
    p6 = EdmLatexPrinter({"digits": 6})
    p4 = EdmLatexPrinter()
    traced = param_units(model)  # SI units along each row (edm_sym.outputs.report.units)
    out = []
    for info in model.params:
        unit = traced.get((info.row, info.col))
        if unit is None or unit.si is not None:
            shown = p6.unit(unit.si if unit is not None else info.unit)
        else:
            shown = p6.text(f"{unit.relative} (no SI unit: {unit.why})")
        out.append({
            "symbol": p6.math(p6._print(info.symbol)),
            "where": p6.text(f"{info.row + 1}, {info.col + 1}"),
            "element": p6.text(info.element),
            "meaning": p6.text(info.meaning),
            "value": p6.math(p6.number(info.value)),
            "p": p6.math(p6.number(info.p)),
            "range": p4.math(p4.interval(info.range.low, info.range.high)),
            "scaling": p6.text(info.range.scaling),
            "unit": shown,
        })
    return out


#: Rows per part of the parameter table: a part never outgrows a page (no longtable,
#: whose page breaks fight the floats).
PARAM_ROWS_PER_TABLE = 22


def _chunks(p: EdmLatexPrinter, rows: list[dict[str, str]]) -> list[dict[str, Any]]:
    if not rows:  # the table stays, so every reference to it holds
        rows = [{"symbol": "--", "where": "", "element": "none",
                 "meaning": "every element is parameter-free", "value": "", "p": "",
                 "range": "", "scaling": "", "unit": ""}]
    out = []
    for k in range(0, len(rows), PARAM_ROWS_PER_TABLE):
        first = k == 0
        out.append({"caption": "Parameters of the element matrix" + ("." if first else
                                                                      " (continued)."),
                    "label": r"\label{tab:params}" if first else "",
                    "rows": rows[k:k + PARAM_ROWS_PER_TABLE]})
    return out


def _friction(p: EdmLatexPrinter, st: SteadyState | None, figures: Mapping[str, str],
              has_data: bool, units: AxisUnits) -> dict[str, list[str]]:
    """The friction characteristic's figure and what it shows, as sentences (in ``units``)."""
    if st is None:
        return {"figures": [], "notes": ["No row has a velocity input, so the compensator has "
                                         "no friction characteristic."]}
    rows = ", ".join(p.math(p.signal("y", j + 1)) for j in st.rows)
    span = p.math(rf"\pm {p.number(st.velocity[-1])}")
    where = "the largest velocity of the data logs" if has_data else "no data log was given"
    notes = []
    if st.rows:
        notes.append(f"The rows with a velocity input ({rows}) held at each constant velocity "
                     f"for {p.math(p.number(st.settle))}~s, over {span}~{p.unit_text(units.velocity)} "
                     f"({where}): the "
                     "friction the compensator predicts in steady state, to check against the "
                     "axis's friction curve (Coulomb level, viscous slope, Stribeck hump).")
    if st.unsettled:
        un = ", ".join(p.math(p.signal("y", j + 1)) for j in st.unsettled)
        notes.append(f"Not shown: {un}, whose output is still changing after "
                     f"{p.math(p.number(st.settle))}~s at constant velocity (a slow filter or "
                     "an integral).")
    caption = (f"Steady-state {units.effort} of the velocity rows against constant velocity"
               + (", with the LuGre model's (eq.~14)" if st.lugre is not None else "") + ".")
    fig = figure_entry(figures, "friction", caption, 0.95)
    return {"figures": [fig] if fig else [], "notes": notes}


def _physics(p: EdmLatexPrinter, model: SymbolicModel, result: Any,
             runs: Sequence[LogRun]) -> dict[str, Any]:
    """The laws of the whole model by behaviour (:mod:`edm_sym.engines.physics`), as
    ``edm describe`` names them on the report's last log (else over the recorded ranges)."""
    from edm_sym.engines.physics import model_physics, physics_on_log, ranges_from_result

    comp = model.compensator
    roles = [model.roles.get(n) for n in comp.matrix.inputs]
    recorded = ranges_from_result(result, dict(zip(comp.matrix.inputs, roles, strict=True)))
    phys = None
    try:
        run = runs[-1] if runs else None
        if run is not None and run.inputs is not None:
            phys = physics_on_log(comp, roles, x=run.inputs, rows=run.rows, target=run.target,
                                  ts=run.ts, source=run.name, axis=model.axis,
                                  bandwidth=run.observer_bandwidth, fallback=recorded)
        elif recorded is not None:
            phys = model_physics(comp, roles, recorded, axis=model.axis)
    except (ValueError, np.linalg.LinAlgError):
        phys = None
    if phys is None:
        return {"tables": [], "notes": [p.text("the physics could not be named by behaviour: no "
                                               "data log and no recorded ranges")], "source": ""}
    laws = []
    for t in phys.terms:
        params = ", ".join(f"{p.text(k.replace('_', ' '))} {p.math(p.number(v))}"
                           + ("" if u == "1" else f"~{p.unit(u)}")
                           for k, (v, u) in t.parameters.items() if k != "harmonics")
        rows = ", ".join(rf"{j + 1}: {p.math(p.number(round(100 * sh, 1)))}\,\%"
                         for j, sh in enumerate(t.rows) if abs(sh) >= 0.1)
        laws.append({"kind": p.text(KIND_TITLES.get(t.kind, t.kind.value)), "params": params,
                     "share": p.math(p.number(round(100 * t.share, 3))) + r"\,\%", "rows": rows})
    notes = [p.text(f"not named: {k.value}: {why}") for k, why in phys.left_out]
    notes.append(p.text(f"the laws explain {100 * phys.explained:.4g} % of what the model does "
                        f"on the probes"))
    notes += [p.text(f"row {b.index} unclassified: {b.reason}") for b in phys.rows if b.reason]
    notes += [p.text(n) for n in phys.notes]
    # Optional parts are lists of zero or one item (the templates hold no conditions).
    return {"tables": [{"laws": laws}] if laws else [], "notes": notes,
            "source": p.text(phys.ranges.source)}


def _steps(p: EdmLatexPrinter, result: Any) -> list[dict[str, str]]:
    return [{
        "step": str(s.step), "size": p.math(f"{s.matrix.n_elements} \\times {s.matrix.n_rows}"),
        "generations": str(s.generations), "evaluations": str(s.evaluations),
        "fitness": p.math(p.number(s.fitness)),
        "weighting": p.math(p.weighting(s.weighting)) if s.weighting else "--",
    } for s in result.steps]


#: The method's paper. /work/shared/paper holds its text, whose title this is; the
#: copy has no author line, venue or year, so none is printed rather than guessed.
PAPER = {"title": "Hierarchical Abstraction of Compensator for Reaction Torque Observer "
                  "Based on Element Description Method",
         "authors": None, "venue": None, "year": None}


def _citation(p: EdmLatexPrinter) -> str:
    """The bibliography entry of the method's paper, from the fields :data:`PAPER` has."""
    parts = [p.text(PAPER["authors"])] if PAPER["authors"] else []
    parts.append(r"\emph{" + p.text(PAPER["title"]) + "}")
    parts += [p.text(str(PAPER[k])) for k in ("venue", "year") if PAPER[k]]
    return ", ".join(parts) + "."


def _units(result: Any) -> AxisUnits:
    """The SI units of the axis the result belongs to (rotary until it records one)."""
    return axis_units(getattr(result, "axis", None) or "rotary")


def _units_context(p: EdmLatexPrinter, u: AxisUnits) -> dict[str, str]:
    """The axis's units in running text, for the template's headers and sentences."""
    return {"force": p.unit_text(u.force), "velocity": p.unit_text(u.velocity),
            "position": p.unit_text(u.position),
            "note": p.text(f"{u.effort.capitalize()}s are in ") + p.unit_text(u.force)
            + p.text(f", {u.motion}s in ") + p.unit_text(u.position)
            + ", velocities in " + p.unit_text(u.velocity) + "."}


def _lugre(p: EdmLatexPrinter, ref: LuGreRef, run: LogRun, u: AxisUnits) -> dict[str, Any]:
    """The LuGre comparison, in the units of the result's axis (the LuGre file records none)."""
    from edm_sym.engines.lugre import PARAMETER_NAMES

    units = {"v_s": u.velocity, "tau_c": u.force, "tau_s": u.force, "z0": u.position,
             "sigma0": f"{u.force}/{u.position}", "sigma1": u.viscous, "sigma2": u.viscous}
    symbols = {"v_s": r"\dot\nu_s", "tau_c": r"\tau_c", "tau_s": r"\tau_s", "z0": "z_0",
               "sigma0": r"\sigma_0", "sigma1": r"\sigma_1", "sigma2": r"\sigma_2"}
    lr = ref.result
    params = [{"symbol": p.math(symbols.get(n, p.text(n))), "name": p.text(n),
               "value": p.math(EdmLatexPrinter({"digits": 5}).number(getattr(lr.params, n))),
               "unit": p.unit(units[n])}
              for n in PARAMETER_NAMES]
    return {
        "name": p.mono(ref.name), "log": p.text(run.label), "log_name": p.mono(run.name),
        "method": p.text(lr.method), "fitness": p.math(p.number(lr.rmse)),
        "fitness_unit": p.unit_text(u.force),
        "params": params,
        "rmse": [{"method": "LuGre (conventional)", "value": p.math(p.number(run.lugre_rmse)),
                  "unit": p.unit(u.force)},
                 {"method": "EDM (this compensator)", "value": p.math(p.number(run.rmse)),
                  "unit": p.unit(u.force)}],
        "ratio": p.math(p.number(run.rmse / run.lugre_rmse if run.lugre_rmse else float("nan"))),
    }


def _commands(p: EdmLatexPrinter, inp: ReportInputs) -> list[str]:
    """The shell commands that regenerate the report and check its numbers."""
    q = shlex.quote
    name = q(inp.source_name)
    export = [f"edm-export {name} --target latex --prefix {inp.prefix}"]
    for flag, run in (("--data", inp.abstraction), ("--eval-data", inp.evaluation)):
        if run is not None:
            further = "".join(f" {q(r.name)}" for r in inp.more if r.label == run.label)
            export.append(f"    {flag} {q(run.name)}{further}")
    if inp.lugre is not None:
        export.append(f"    --lugre {q(inp.lugre.name)}")
    if inp.ts is not None:
        export.append(f"    --ts {inp.ts!r}")
    export.append("    --pdf -o DIR")
    lines = [line + " \\" for line in export[:-1]] + export[-1:]
    for run in (inp.abstraction, inp.evaluation):
        if run is not None:
            ts = f" --ts {inp.ts!r}" if inp.ts is not None else ""
            lines.append(f"edm simulate {name} {q(run.name)}{ts}   # prints rmse")
    lines.append(f"edm-export {name} --target all --prefix {inp.prefix} -o DIR")
    text = "\n".join(lines)
    if "\\end{Verbatim}" in text:
        raise ValueError(f"commands: a file name holds '\\end{{Verbatim}}': {text!r}")
    return text.split("\n")


def report_context(inp: ReportInputs) -> dict[str, Any]:
    """The validated context of ``templates/report.tex.j2``.

    Long on purpose: one literal of the template's context, key by key, in the
    order the report reads; each value comes from a named helper.

    Parameters
    ----------
    inp : ReportInputs

    Returns
    -------
    dict
        Nested dicts and lists of finished LaTeX strings; optional parts are
        lists of zero or one item.

    Raises
    ------
    ValueError
        When the context is incomplete (a defect of this module, not of the input).
    """
    p = EdmLatexPrinter()
    model, result = inp.model, inp.result
    units = _units(result)
    runs = [r for r in (inp.abstraction, inp.evaluation) if r is not None]
    mat = model.compensator.matrix
    roles = [f"{p.mono(n)} ({p.text(role_title(model.roles.get(n), model.axis))})"
             for n in model.inputs]
    facts = [
        ("Result file", p.mono(inp.source_name)),
        ("sha256 of the result", p.digest(inp.source_sha256)),
        (f"Target (estimated {units.effort})", p.mono(result.target)),
        ("Inputs", ", ".join(roles)),
        ("Sample time", p.math(f"T_s = {p.number(model.sample_time)}") + r"~s"),
        ("Element matrix", p.math(f"{mat.n_elements} \\times {mat.n_rows}")
         + f" ({mat.n_elements} elements per row, {mat.n_rows} rows)"),
        ("Hierarchical steps", str(len(result.steps)) if result.steps
         else "none recorded (hand-written or imported model)"),
        ("Weighted fitness (eq. 8)",
         p.math(r"\Gamma = " + p.number(result.fitness)) + "~" + p.unit(units.force)
         if result.fitness is not None else "not recorded"),
    ]
    facts += log_facts(p, inp.logs, p.unit(units.force))
    if inp.lugre is not None:
        facts.append(("LuGre baseline", p.mono(inp.lugre.name)))
    facts.append(bounds_fact(p, model))
    judged = judge_report_rows(model, runs, inp.classify)  # honest names (edm_sym.outputs.report.flags)
    facts.append(negligible_fact(p, judged, bool(runs)))
    kinds = log_kinds(inp.logs)
    rms_on = [(k.phrase(p), k.contributions.rms) for k in kinds]
    rows = [row_context(p, model, row, rms_on, j) for row, j in zip(model.rows, judged, strict=True)]
    overview = [{"number": r["number"], "section": p.ref(f"sec:row{r['number']}"),
                 "input": p.math(p._print(row.input_symbol)),
                 "terms": p.text(", ".join(judged_titles(j, KIND_TITLES))
                                 or "none (identically 0)"),
                 "rms": [x["value"] for x in r["rms"]]}
                for r, row, j in zip(rows, model.rows, judged, strict=True)]
    total = [(row.expr_numeric, f"row {row.index + 1}") for row in model.rows]
    compare = runs[-1] if runs else None
    lugre = ([_lugre(p, inp.lugre, compare, units)]
             if inp.lugre is not None and compare is not None and compare.lugre is not None else [])
    fig = inp.figures
    prov = result.provenance
    fixed, fixed_refused = fixed_context(p, model, result, runs, units.force)
    ctx: dict[str, Any] = {
        "title": p.text(f"EDM compensator {inp.prefix}: model report"),
        "subtitle": p.mono(inp.source_name),
        "facts": [{"label": p.text(k), "value": v} for k, v in facts],
        "equation": equation_lines(p, r"\tau_{\mathrm{cmp}}(t)", total),
        "overview": overview,
        "physics": _physics(p, model, result, runs),
        "log_labels": [p.text(f"{k.label} log" if len(k.runs) == 1
                              else f"{len(k.runs)} {k.label} logs") for k in kinds],
        "no_data": [] if runs else ["no data log was given (edm-export --data LOG)"],
        "matrix": matrix_diagram(model, EdmLatexPrinter({"digits": 3})),
        "matrix_size": p.math(f"{mat.n_elements} \\times {mat.n_rows}"),
        "rows": rows,
        "friction": _friction(p, inp.steady, fig, bool(runs), units),
        "param_chunks": _chunks(p, _params(model)),
        "no_params": [] if model.params else ["every element of the matrix is parameter-free"],
        "contributions": contribution_tables(p, inp.logs, fig),
        "fitness": [f for f in [figure_entry(fig, "fitness", "Best fitness per generation of each "
                                        "hierarchical step (weighted RMSE, eq.~8).", 1.0)] if f],
        "steps": _steps(p, result),
        "no_steps": [] if result.steps else ["the result records no hierarchical steps"],
        "time": time_figures(p, inp.logs, fig, units.effort),
        "log_rmse": log_rmse(p, inp.logs, inp.lugre is not None
                             and all(r.lugre is not None for r in inp.logs)),
        "lugre": lugre,
        "fixed": fixed,
        "fixed_refused": fixed_refused,
        "fixed_switch_lsb": str(SWITCH_LSB),
        "fixed_log": [p.mono(r.name) for r in runs[:1]],
        "fixed_no_log": [] if runs else ["no log"],
        "no_lugre": [] if lugre else ["no LuGre result was given (edm-export --lugre LUGRE.json)"],
        "provenance": [
            {"label": p.text("sha256 of the result"), "value": p.digest(inp.source_sha256)},
            {"label": p.text("seed"), "value": _recorded(p, prov.get("seed"))},
            {"label": p.text("data sha256 (in the result)"),
             "value": p.digest(prov["data_sha256"]) if prov.get("data_sha256")
             else "not recorded"},
            {"label": p.text("written by edm_sym"), "value": _recorded(p, prov.get("package_version"))},
        ] + [{"label": p.text(str(k).replace("_", " ")), "value": p.text(str(v))}
             for k, v in sorted(prov.items())
             if k not in ("seed", "data_sha256", "package_version")],
        "versions": [{"name": p.text(n), "version": p.text(v)} for n, v in inp.versions],
        "commands": _commands(p, inp),
        "sample_time": p.math(f"T_s = {p.number(model.sample_time)}") + r"~s",
        "force_unit": p.unit(units.force),
        "effort": p.text(units.effort),
        "observer": p.text("reaction torque observer (RTOB)" if units.axis == "rotary"
                           else "reaction force observer (RFOB)"),
        "viscous_unit": p.unit(units.viscous),
        "units": _units_context(p, units),
        "paper": _citation(p),
        **front_context(p, result, fig),
    }
    return check_report_context(ctx)


#: Keys every report context holds.
REPORT_KEYS = ("title", "facts", "equation", "overview", "matrix", "rows", "friction", "param_chunks",
               "contributions",
               "fitness", "units", "steps", "time", "lugre", "provenance", "versions", "commands",
               "effort", "observer")


def check_report_context(ctx: dict[str, Any]) -> dict[str, Any]:
    """Check a report context: every key present, every leaf a string.

    Strings are finished LaTeX, so the template formats nothing; only the
    verbatim ``commands`` may hold no ``\\end{Verbatim}``, and no other
    string a line break.

    Raises
    ------
    ValueError
        Naming the key at fault.
    """
    for k in REPORT_KEYS:
        if k not in ctx:
            raise ValueError(f"report context: expected the key {k!r}, found it missing")

    def walk(v: Any, where: str) -> None:
        if isinstance(v, str):
            if "\n" in v:
                raise ValueError(f"report context: {where} holds a line break")
            return
        if isinstance(v, Mapping):
            for k, x in v.items():
                walk(x, f"{where}.{k}")
            return
        if isinstance(v, (list, tuple)):
            for i, x in enumerate(v):
                walk(x, f"{where}[{i}]")
            return
        raise ValueError(f"report context: {where} is a {type(v).__name__}, expected finished text")

    walk(ctx, "context")
    if not ctx["rows"]:
        raise ValueError("report context: expected at least one row, found 0")
    return ctx
