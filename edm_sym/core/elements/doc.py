"""Generate ``docs/elements.md`` from the registry.

Run ``python -m edm_sym.core.elements.doc docs/elements.md`` after changing an
element; a test fails while the committed file is stale.
"""

from __future__ import annotations

import sys

from edm_sym.core.discrete import METHODS
from edm_sym.core.elements import all_elements
from edm_sym.core.elements.base import DelayElement, Element, LinearElement, RelayElement

HEADER = """# Elements

Generated from the element registry (`edm_sym/core/elements/`) by
`python -m edm_sym.core.elements.doc docs/elements.md`; do not edit by hand.

Each element maps its input x to its output y. Its chromosome gene is an
integer code and a normalised parameter p in [0, 1]; p becomes the parameter a
through the element's range and scaling: linear (paper, eq. 4)
`a = (high - low) p + low`, or logarithmic (eq. 5)
`a = 10^((log10 high - log10 low) p + log10 low)`. Default ranges depend on the
sample time Ts and the record length T_sum (eqs. 6-7) and can be overridden in
the abstraction config; result.json stores the ranges it was decoded with.
Every bound lies within +-1e12, and a log range starts at 1e-12 or above
(`RANGE_LIMIT`): beyond, products of parameters overflow double precision.

Dynamic elements start from rest (zero state) and run at the sample time Ts;
the discretisation named here is the one the simulator, the python-control
systems, the generated C and Python and the report all use.

Where the paper leaves a definition open, edm_sym chooses:

- **power gain**: a positive gain searched over decades (log scaling), so tiny
  viscous coefficients and large gains are equally reachable; `gain` covers
  signed gains linearly.
- **shift operator**: the backward shift q^-k by a few whole samples (k = 1..10);
  `dead time` covers longer delays in seconds.
- **one way**: a one-sided limiter `max(x, a)`; with a = 0 a half-wave rectifier.
- **sine (phase)** `sin(x + a)` and **sine (amp.)** `a sin(x)`; likewise for the tangent.
- **hysteresis**: a relay with hysteresis (output -1, 0 before the first switch, +1).
- **logarithm**: `sgn(x) ln(1 + |x|/a)`, the odd, everywhere-defined logarithm.
- **power**: `sgn(x) |x|^a`, the odd extension.
- **arctangent** and **hyperbolic tangent** carry a slope a; arcsine and arccosine none.

"""


def _discretisation(el: type[Element]) -> str:
    if issubclass(el, LinearElement):
        return METHODS[el.method]
    if issubclass(el, DelayElement):
        return "exact: a ring buffer of N samples, starting at zero"
    if issubclass(el, RelayElement):
        return "exact: one state (last output), starting at 0"
    return "none: memoryless"


def _state(el: type[Element]) -> str:
    if issubclass(el, LinearElement):
        num, den = el.tf(1.0)
        return str(max(len(num), len(den)) - 1)
    if issubclass(el, DelayElement):
        return "N (the decoded delay)"
    if issubclass(el, RelayElement):
        return "1"
    return "0"


def render() -> str:
    """The Markdown text of ``docs/elements.md``."""
    lines = [HEADER, "| code | name | element | kind | formula | parameter a | default range |\n",
             "|---:|---|---|---|---|---|---|\n"]
    for el in all_elements():
        par = f"{el.param.meaning} [{el.param.unit}]" if el.param else "none"
        rng = el.param.rule if el.param else "-"
        lines.append(f"| {el.code} | `{el.name}` | {el.title} | {el.kind} | `{el.formula}` "
                     f"| {par} | {rng} |\n")
    lines.append("\n## Each element\n")
    for el in all_elements():
        lines.append(f"\n### {el.code} `{el.name}`: {el.title} ({el.category})\n\n")
        lines.append(f"- formula: `{el.formula}`\n")
        if el.param:
            scaling = el.param.default(1e-3, 20.0).scaling
            lines.append(f"- parameter a: {el.param.meaning} [{el.param.unit}]\n")
            lines.append(f"- default range: {el.param.rule}; scaling: {scaling}\n")
        else:
            lines.append("- parameter a: none (p is kept in the chromosome and ignored)\n")
        lines.append(f"- discretisation: {_discretisation(el)}\n")
        lines.append(f"- state size: {_state(el)}\n")
        lines.append(f"- guard: {el.guard}\n")
    return "".join(lines)


def main(argv: list[str] | None = None) -> int:
    """Write the documentation to the path given (or print it)."""
    argv = sys.argv[1:] if argv is None else argv
    text = render()
    if argv:
        from edm_sym.core.fileio import write_atomic

        write_atomic(argv[0], text)
    else:
        sys.stdout.write(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
