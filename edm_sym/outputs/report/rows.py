"""One row of the report: its equations (continuous and discrete time) and physical terms.

:func:`row_context` gives what the template shows for a row: the simplified
block diagram, the equation as composed from the elements, simplified and
with the values, the difference equations from the stages' own coefficients
(what the simulator and the generated code run), and the physical terms with
their parameters in SI units. Every string is finished LaTeX from the printer.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from typing import Any

import sympy as sp

from edm_sym.core.elements.realisation import DelayLine, LinearFilter, Relay, StaticMap
from edm_sym.core.terms import TermKind
from edm_sym.engines.symbolic.model import RowModel, SymbolicModel, X
from edm_sym.outputs.printing.latex import EdmLatexPrinter
from edm_sym.outputs.report.diagrams import chain_diagram, chain_printer
from edm_sym.outputs.report.flags import row_flags

#: Readable names of the physical term kinds.
KIND_TITLES: dict[TermKind, str] = {
    TermKind.COULOMB: "Coulomb friction",
    TermKind.VISCOUS: "viscous friction",
    TermKind.ACCELERATION: "acceleration-dependent term (inertia)",
    TermKind.SPATIAL: "position-dependent (spatial) friction",
    TermKind.STRIBECK: "Stribeck friction",
    TermKind.OFFSET: "constant offset",
    TermKind.UNCLASSIFIED: "unclassified term",
}

#: Readable names of the input roles (edm_sym.engines.symbolic.roles.ROLES).
ROLE_TITLES = {
    "velocity": "angular velocity",
    "acceleration": "angular acceleration",
    "angle": "unwrapped angle",
    "angle_wrapped": "wrapped angle",
    None: "no physical role",
}

#: The same on a linear axis (a position in m, not an angle).
LINEAR_ROLE_TITLES = {
    "velocity": "velocity",
    "acceleration": "acceleration",
    "angle": "position",
    "angle_wrapped": "wrapped position",
    None: "no physical role",
}


def role_title(role: str | None, axis: str = "rotary") -> str:
    """The readable name of an input role on ``axis`` (``"angular velocity"``, ``"velocity"``)."""
    titles = LINEAR_ROLE_TITLES if axis == "linear" else ROLE_TITLES
    return titles.get(role, str(role) if role is not None else "no physical role")

#: How each discretisation method is named in the report.
METHOD_TITLES = {"bilinear": "Tustin", "backward_diff": "backward difference"}


def rms_text(p: EdmLatexPrinter, v: float | None) -> str:
    """An RMS value in math, or ``--`` when there is none."""
    return "--" if v is None else p.math(p.number(v))


def equation_lines(p: EdmLatexPrinter, lhs: str, exprs: Sequence[tuple[sp.Expr, str]]
                    ) -> list[dict[str, str]]:
    """Lines of an ``align*``: each additive term on its own line, the tag on a group's first."""
    lines = []
    for expr, tag in exprs:
        terms = p.signed_terms(expr)
        for k, (sign, body) in enumerate(terms):
            first = not lines
            lines.append({
                "lhs": f"{lhs} ={{}}" if first else "",
                "sign": ("-" if sign == "-" else "") if first else sign,
                "body": body,
                "tag": p.math_text(tag) if k == 0 and tag else "",
                "end": r"\\",
            })
    if lines:
        lines[-1]["end"] = ""
    return lines


def _row_equations(p: EdmLatexPrinter, row: RowModel) -> list[dict[str, str]]:
    lhs = f"{p.signal('y', row.index + 1)}(t)"
    groups = []
    for expr, tag in ((row.expr_raw, "elements"), (row.expr, "simplified"),
                      (row.expr_numeric, "values")):
        if not groups or expr != groups[-1][0]:
            groups.append((expr, tag))
    lines = []
    for k, (expr, tag) in enumerate(groups):
        lines.append({"lhs": lhs if k == 0 else "", "body": p.doprint(expr),
                      "tag": p.math_text(tag), "end": r"\\"})
    lines[-1]["end"] = ""
    return lines


def _filter_equation(st: Any, p: EdmLatexPrinter, out: str, inp: str, ts: float
                     ) -> tuple[str, str]:
    r = st.realisation
    return (p.difference_equation(out, inp, r.b, r.a),
            f"{st.element.name}, {METHOD_TITLES.get(r.method, r.method)}")


def _delay_equation(st: Any, p: EdmLatexPrinter, out: str, inp: str, ts: float
                    ) -> tuple[str, str]:
    n = st.realisation.samples
    return p.delayed(inp, n), f"{st.element.name}, {n} sample(s) = {n * ts:.6g} s"


def _relay_equation(st: Any, p: EdmLatexPrinter, out: str, inp: str, ts: float
                    ) -> tuple[str, str]:
    return (p.relay_equation(out, inp, st.realisation.threshold),
            "hysteresis relay, starts at 0")


#: The difference equation (right-hand side, what it is) of each stage kind with memory.
_EQUATIONS = {LinearFilter: _filter_equation, DelayLine: _delay_equation, Relay: _relay_equation}


def _difference_equations(row: RowModel, ts: float, digits: int = 10
                          ) -> tuple[list[dict[str, str]], list[dict[str, str]]]:
    """The row in discrete time, from the stages' coefficients (the simulator's numbers).

    Consecutive static elements are composed into one signal; each filter,
    delay or relay gets its own. The last signal is the row output ``y_j``.

    Returns
    -------
    lines : list of dict
        ``lhs``, ``body``, ``end`` of each equation.
    signals : list of dict
        ``name`` and ``what`` of each signal.
    """
    j = row.index + 1
    # (first column, last column, data): data is (input dummy, expression) for
    # consecutive static maps composed into one signal, else the stage itself.
    segments: list[tuple[int, int, Any]] = []
    acc_sym = sp.Dummy("v", real=True)
    acc: sp.Expr = acc_sym
    first = 1
    for st in row.stages:
        if isinstance(st.realisation, StaticMap):
            acc = st.numeric_expr().xreplace({X: acc})
            continue
        if acc != acc_sym:
            segments.append((first, st.col, (acc_sym, acc)))
        segments.append((st.col + 1, st.col + 1, st))
        first = st.col + 2
        acc_sym = sp.Dummy("v", real=True)
        acc = acc_sym
    if acc != acc_sym or not segments:
        segments.append((first, len(row.stages), (acc_sym, acc)))
    base = EdmLatexPrinter()
    names = [base.signal("y", j) if k == len(segments) - 1 else base.signal("x", j, last)
             for k, (_, last, _) in enumerate(segments)]
    lines, signals = [], []
    prev = base._print(row.input_symbol)
    for k, (col0, col1, data) in enumerate(segments):
        out = names[k]
        where = f"element {col0}" if col0 == col1 else f"elements {col0}--{col1}"
        if isinstance(data, tuple):
            sym, expr = data
            pr = EdmLatexPrinter({"digits": digits, "symbol_names": {sym: f"{prev}[k]"}})
            rhs = pr.doprint(expr)
            what = f"{where}, static" if col0 <= col1 else "the input, passed through"
        else:
            equation = _EQUATIONS[type(data.realisation)]
            rhs, what = equation(data, EdmLatexPrinter({"digits": digits}), out, prev, ts)
            what = f"{where}, {what}"
        lines.append({"lhs": f"{out}[k]", "body": rhs, "end": r"\\"})
        signals.append({"name": base.math(out), "what": base.text(what)})
        prev = out
    lines[-1]["end"] = ""
    for sg in signals:
        sg["sep"] = "; "
    signals[-1]["sep"] = "."
    return lines, signals


def _term(p: EdmLatexPrinter, term: Any) -> dict[str, Any]:
    params = [{"name": p.text(name.replace("_", " ")), "value": p.math(p.number(v)),
               "unit": p.unit(unit)} for name, (v, unit) in term.parameters.items()]
    desc = term.description or ""
    notes = desc if term.kind is TermKind.UNCLASSIFIED else "; ".join(desc.split("; ")[1:])
    # The expression is printed above; the description's plain-text copy of it adds nothing.
    notes = re.sub(r"^no physical pattern for .* \((\w+) input\)", r"no physical pattern for "
                   r"this term (\1 input)", notes)
    notes = _drop_code(notes)
    return {
        "title": p.text(KIND_TITLES.get(term.kind, term.kind.value)),
        "expr": p.doprint(term.expr) if term.expr is not None else "",
        "params": params,
        "notes": [p.breakable(notes)] if notes else [],
    }


def _drop_code(text: str) -> str:
    """``text`` without parenthesised copies of sympy expressions (``(0.5*GAcos(x))``)."""
    out: list[str] = []
    i = 0
    while i < len(text):
        if text[i] == "(":
            depth, j = 0, i
            while j < len(text):
                depth += {"(": 1, ")": -1}.get(text[j], 0)
                if depth == 0:
                    break
                j += 1
            inner = text[i + 1:j]
            if len(inner) > 20 and ("*" in inner or "(" in inner):
                while out and out[-1] == " ":
                    out.pop()
                i = j + 1
                continue
        out.append(text[i])
        i += 1
    return "".join(out)


def _elements_text(p: EdmLatexPrinter, row: RowModel) -> str:
    parts = [p.text(row.input)]
    for st in row.stages:
        label = p.text(st.element.name)
        if st.param is not None:
            label += " (" + p.math(f"{p._print(st.param.symbol)} = {p.number(st.param.value)}") + ")"
        parts.append(label)
    return r" $\to$ ".join(parts)


def row_context(p: EdmLatexPrinter, model: SymbolicModel, row: RowModel,
                rms_on: Sequence[tuple[str, Sequence[float]]], judged: Any = None
                ) -> dict[str, Any]:
    """The template context of one row (see the module docstring).

    ``rms_on`` gives, per kind of log, where (finished LaTeX: ``the abstraction
    log``) and each row's RMS there. ``judged`` (a
    :class:`~edm_sym.engines.symbolic.significance.JudgedRow`) names the row
    honestly: only its judged terms, and its flags.
    """
    terms = row.terms if judged is None else tuple(jt.term for jt in judged.terms)
    titles = [KIND_TITLES.get(t.kind, t.kind.value) for t in terms] or (
        ["negligible"] if judged is not None and judged.negligible
        else ["no output (identically 0)"])
    no_terms = ["The row's output is identically zero: it can be removed."]
    if judged is not None and judged.negligible:
        no_terms = ["Negligible: its physical terms are not named (see the flags)."]
    j = row.index + 1
    discrete, signals = _difference_equations(row, model.sample_time)
    return {
        "number": str(j),
        "title": p.math(p._print(row.input_symbol)) + " -- " + p.text(", ".join(titles)),
        "bookmark": p.text(f"Row {j}: {row.input}, {', '.join(titles)}"),
        "input": p.text(row.input),
        "role": p.text(role_title(row.role, model.axis)),
        "elements": _elements_text(p, row),
        "chain": [chain_diagram(row, chain_printer())],
        "equations": _row_equations(p, row),
        "discrete": discrete,
        "signals": signals,
        "term_lists": [[_term(p, t) for t in terms]] if terms else [],
        "no_terms": [] if terms else no_terms,
        "flags": [] if judged is None else row_flags(p, judged),
        "rms": [{"log": where, "value": rms_text(p, values[row.index])}
                for where, values in rms_on],
    }
