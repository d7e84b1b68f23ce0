"""The report's validation and parsimony section: held-out scores, the front, its plot.

Reads the ``validation`` and ``parsimony`` entries of a result (see
:mod:`edm_sym.engines.abstraction.holdout` and :mod:`edm_sym.engines.abstraction.prune`);
results without them get a one-line note. The context is lists of zero or
one item, so the template needs nothing but loops.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

from edm_sym.outputs.printing.latex import EdmLatexPrinter

#: Figure key of the complexity-vs-fitness plot.
FIGURE = "front"


def _quantity(p: EdmLatexPrinter, q: Any) -> str:
    if not q or q[0] is None:
        return "--"
    return p.math(p.number(float(q[0]))) + "~" + p.text(str(q[1])).replace(" ", r"\,")


#: What samples held out of the abstraction log itself cannot show (said in the report).
SAME_LOG = ("motion this log does not hold: the held-out samples come from the same log, so "
            "a row fitted to what repeats in its motion passes them too; a second log "
            "(edm abstract --validate FILE) tests that")


def _held_out(p: EdmLatexPrinter, held: Mapping[str, Any]) -> str:
    if held["kind"] == "segment":
        a, b = held["rows"]
        t0, t1 = held["t"]
        return p.text(f"the last {100 * held['share']:g} % of the log: samples {a} to {b - 1} "
                      f"({t0:g} s to {t1:g} s)")
    if held["kind"] == "blocks":
        (a0, a1), (b0, b1) = held["times"][0], held["times"][-1]
        return p.text(f"{100 * held['share']:g} % of the log in {held['count']} blocks spread "
                      f"over it, one in the middle of each {100 / held['count']:g} % of it "
                      f"(the first {a0:g} s to {a1:g} s, the last {b0:g} s to {b1:g} s)")
    if held["kind"] == "file":
        return p.mono(str(held["file"])) + p.text(f" ({held['samples']} samples)")
    return p.text("nothing (the scores below are on the training data)")


def front_context(p: EdmLatexPrinter, result: Any, figures: Mapping[str, str]) -> dict[str, Any]:
    """The ``validation`` and ``front`` parts of the report's context.

    Parameters
    ----------
    p : EdmLatexPrinter
        Formats numbers and text.
    result : EdmResult
        The result shown.
    figures : mapping of str to str
        Figure key -> file name of the figures drawn.

    Returns
    -------
    dict
        ``validation`` (zero or one item with ``facts``), ``no_validation``, ``front`` (zero or one
        item with ``members``, ``figures`` and sentences), ``no_front``.
    """
    val, par = dict(result.validation or {}), dict(result.parsimony or {})
    facts = []
    if val:
        facts.append({"label": p.text("Held out from the GA"), "value": _held_out(p, val["held_out"])})
        for part in ("training", "validation"):
            s = val.get(part)
            if s is None:
                continue
            facts.append({"label": p.text(f"{part.capitalize()}: eq. 8 / RMSE"),
                          "value": f"{_quantity(p, s['fitness'])} / {_quantity(p, s['rmse'])}"
                                   + p.text(f" ({s['samples']} samples)")})
        if val["held_out"]["kind"] in ("blocks", "segment"):
            facts.append({"label": p.text("Not tested"), "value": p.text(SAME_LOG)})
    front = []
    if par:
        members = [{
            "member": str(m["member"]), "complexity": str(m["complexity"]),
            "rows": str(m["matrix"]["n_rows"]),
            "criterion": _quantity(p, m["criterion"]),
            "training": _quantity(p, m["training"]["fitness"]),
            "validation": _quantity(p, (m["validation"] or {}).get("fitness")),
            "change": p.text(m.get("change", "")),
            "mark": r"$\leftarrow$" if m["member"] == par["selected"] else "",
        } for m in par["front"]]
        candidates = [{
            "step": str(c["step"]), "refitted": p.text("yes" if c["refitted"] else "no"),
            "whole": _quantity(p, c["whole_rmse"]), "held": _quantity(p, c["held_out_rmse"]),
            "tied": p.text("yes" if c["tied"] else "no"),
            "mark": r"$\leftarrow$" if c["chosen"] else "",
        } for c in par.get("start_candidates", [])]
        fig = figures.get(FIGURE)
        front.append({
            # The candidates of the search's model: one table, or none (an older result).
            "start": [{"candidates": candidates,
                       "tie": p.text(f"{100 * par.get('start_tie', 0.0):g} %")}]
            if candidates else [],
            "members": members,
            "criterion": p.mono(par["criterion"]),
            "rule": p.mono(par["select"]),
            "selected": str(par["selected"]),
            "search": str(par.get("search_complexity", "--")),
            "complexity": p.text(par["complexity"]),
            "figures": [{"file": fig, "label": "fig:front",
                         "caption": "Complexity against the pruning criterion of the members "
                                    "of the front; the exported member is circled."}]
            if fig else [],
        })
    return {
        "validation": [{"facts": facts}] if facts else [],
        "no_validation": [] if facts else ["the result records no held-out validation"],
        "front": front,
        "no_front": [] if front else ["the result records no parsimony front"],
    }


def front_figure(result: Any, path: Path) -> Path:
    """Complexity against criterion of the front's members (log scale), the selected circled.

    Parameters
    ----------
    result : EdmResult
        A result with a ``parsimony`` front.
    path : path-like
        The PDF to write.
    """
    from edm_sym.outputs.report.figures import WIDTH, _pyplot, _save

    plt = _pyplot()
    par = result.parsimony
    cx = [m["complexity"] for m in par["front"]]
    cr = [m["criterion"][0] for m in par["front"]]
    unit = par["front"][0]["criterion"][1]
    fig, ax = plt.subplots(figsize=(0.6 * WIDTH, 2.2))
    ax.plot(cx, cr, color="C0", marker="o", markersize=3)
    sel = par["selected"] - 1
    ax.plot([cx[sel]], [cr[sel]], "o", markersize=9, markerfacecolor="none", color="C3",
            label=f"exported ({par['select']})")
    if all(v > 0 for v in cr):
        ax.set_yscale("log")
    ax.set_xlabel("complexity")
    ax.xaxis.get_major_locator().set_params(integer=True)
    ax.set_ylabel(f"{par['criterion']} [{unit}]")
    ax.legend(loc="upper right")
    fig.tight_layout()
    return _save(fig, path)
