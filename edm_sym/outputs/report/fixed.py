"""The report's fixed-point section: the q31 and q15 builds' Q formats and deviations.

Both builds are designed as ``edm-export --real q31|q15`` designs them, on the
result's recorded input ranges and on the report's first log (the one the
export sizes the formats on), so the figures match the headers': the
deviation under the switching rule, the switching events it allowed and the
raw deviation without it. A build the export would refuse is listed with its
reason.
"""

from __future__ import annotations

from typing import Any

from edm_sym.core.errors import as_options
from edm_sym.engines.fixedpoint import WORDS, FixedPointError
from edm_sym.engines.fixedpoint.formats import describe_format
from edm_sym.outputs.render.context import source_of
from edm_sym.outputs.render.fixed_context import fixed_build


def fixed_context(p: Any, model: Any, result: Any, runs: list[Any], unit: str
                  ) -> tuple[list[dict[str, Any]], list[dict[str, str]]]:
    """The built words (table rows and formats) and the refused ones (word, reason)."""
    log = next(((r.inputs, r.name) for r in runs if r.inputs is not None), None)
    built, refused = [], []
    for real in WORDS:
        try:
            b = fixed_build(model, source_of(result), real, None, log)
        except FixedPointError as exc:
            refused.append({"word": p.mono(real), "reason": p.text(as_options(str(exc)))})
            continue
        d, acc = b.design, b.accuracy
        judged = [a for a in (acc, b.log) if a is not None]
        on_log = "no log" if b.log is None else p.math(p.number(b.log.measured))
        bits = d.word.bits
        formats = []
        for row in d.rows:
            name = d.inputs[row.input_index]
            parts = [f"{name} {describe_format(d.input_fracs[row.input_index], bits)}"]
            parts += [f"{st.label} {describe_format(st.fout, bits)}" for st in row.stages]
            formats.append({"row": str(row.index + 1), "chain": p.text(" -> ".join(parts))})
        built.append({
            "word": p.mono(real),
            "promised": p.math(p.number(acc.goal)),
            "measured": p.math(p.number(acc.measured)),
            "on_log": on_log,
            "events": str(sum(len(a.events) for a in judged)),
            "raw": p.math(p.number(max(a.raw for a in judged))),
            "output": p.text(describe_format(d.out_frac, bits)),
            "formats": formats,
        })
    return built, refused
