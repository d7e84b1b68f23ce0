"""Integer C99 printing of a fixed-point design (``--real q31`` / ``q15``).

:class:`FixedCPrinter` writes the statements of each integer stage of a
:class:`~edm_sym.engines.fixedpoint.FixedDesign`, chosen by the stage's type
(``_stage_TableStage``, ``_stage_FilterStage``, ``_stage_RingStage``,
``_stage_RelayStage``), the read-only tables of the static functions and the
few ``static inline`` helpers they call (saturation, rounding shift, table
interpolation, period reduction). Nothing here is floating point: the object
holds integer instructions only. Right shifts of negative values are
arithmetic (what every compiler for ARM and x86 does; C99 leaves it to the
implementation).
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from typing import Any

from edm_sym.core.elements.realisation import dispatch
from edm_sym.engines.fixedpoint import TableStage
from edm_sym.outputs.printing.c import is_c_identifier

# Helper name -> (helpers it calls, C text); {P} is the prefix, {Q} the word type,
# {MIN}/{MAX} the word's limits.
_HELPERS: dict[str, tuple[tuple[str, ...], tuple[str, ...]]] = {
    "sat": ((), (
        "static inline {Q} {P}_sat(int64_t v)",
        "{{",
        "    return (v < {MIN}) ? ({Q}){MIN} : ((v > {MAX}) ? ({Q}){MAX} : ({Q})v);",
        "}}",
    )),
    "sat32": ((), (
        "static inline int32_t {P}_sat32(int64_t v)",
        "{{",
        "    return (v < INT32_MIN) ? INT32_MIN : ((v > INT32_MAX) ? INT32_MAX : (int32_t)v);",
        "}}",
    )),
    "rshr": ((), (
        "/* v / 2^s rounded half up (s >= 1; an arithmetic shift). */",
        "static inline int64_t {P}_rshr(int64_t v, unsigned s)",
        "{{",
        "    return (v + ((int64_t)1 << (s - 1u))) >> s;",
        "}}",
    )),
    "wrap": ((), (
        "/* x reduced to [0, p): one period of a function of sin x and cos x. */",
        "static inline {Q} {P}_wrap({Q} x, int32_t p)",
        "{{",
        "    int32_t r = (int32_t)x % p;",
        "    if (r < 0) {{",
        "        r += p;",
        "    }}",
        "    return ({Q})r;",
        "}}",
    )),
    "pwl": (("sat", "rshr"), (
        "/* Piecewise-linear table of n segments: the ends outside [xb[0], xb[n]]. */",
        "static inline {Q} {P}_pwl({Q} x, const {Q} *xb, const {Q} *yb, const int32_t *sl,",
        "        const uint8_t *sh, size_t n)",
        "{{",
        "    size_t lo = 0u;",
        "    size_t hi = n;",
        "    int64_t d;",
        "    if (x <= xb[0]) {{",
        "        return yb[0];",
        "    }}",
        "    if (x >= xb[n]) {{",
        "        return yb[n];",
        "    }}",
        "    while (hi - lo > 1u) {{",
        "        const size_t mid = lo + (hi - lo) / 2u;",
        "        if (x >= xb[mid]) {{",
        "            lo = mid;",
        "        }} else {{",
        "            hi = mid;",
        "        }}",
        "    }}",
        "    d = ((int64_t)x - (int64_t)xb[lo]) * (int64_t)sl[lo];",
        "    if (sh[lo] > 0u) {{",
        "        d = {P}_rshr(d, sh[lo]);",
        "    }}",
        "    return {P}_sat((int64_t)yb[lo] + d);",
        "}}",
    )),
}


class FixedCPrinter:
    """Integer C for one word (``q31``: ``int32_t`` signals; ``q15``: ``int16_t``).

    Parameters
    ----------
    word : Word
        The build (:data:`edm_sym.engines.fixedpoint.WORDS`).
    prefix : str
        The C identifier prefixing every name.
    """

    def __init__(self, word: Any, prefix: str = "edm_comp"):
        if not is_c_identifier(prefix):
            raise ValueError(f"prefix: expected a C identifier, found {prefix!r}")
        self.word = word
        self.prefix = prefix
        self.helpers_used: set[str] = set()

    @property
    def q_t(self) -> str:
        """The signal word's typedef (``edm_comp_q_t``)."""
        return f"{self.prefix}_q_t"

    # -- numbers -------------------------------------------------------------------
    def word_literal(self, v: int) -> str:
        """An integer constant of the word (its minimum through the ``INTnn_MIN`` macro)."""
        v = int(v)
        if v == self.word.min_int:
            return f"INT{self.word.bits}_MIN"
        return str(v)

    @staticmethod
    def int32_literal(v: int) -> str:
        """An ``int32_t`` constant."""
        return "INT32_MIN" if int(v) == -(1 << 31) else str(int(v))

    @staticmethod
    def int64_literal(v: int) -> str:
        """An ``int64_t`` constant."""
        return f"INT64_C({int(v)})"

    def _call(self, name: str, args: str) -> str:
        self.helpers_used.add(name)
        return f"{self.prefix}_{name}({args})"

    def narrowed(self, value: str, shift: int, helper: str = "sat") -> str:
        """``value`` (an int64 expression) shifted right by ``shift`` with rounding, saturated."""
        if shift > 0:
            value = self._call("rshr", f"{value}, {shift}u")
        return self._call(helper, value)

    # -- helpers ---------------------------------------------------------------------
    def helper_definitions(self, names: Iterable[str] | None = None) -> list[str]:
        """The ``static inline`` helpers used (with those they call), callees first."""
        wanted = set(self.helpers_used if names is None else names)
        todo = list(wanted)
        while todo:
            for dep in _HELPERS[todo.pop()][0]:
                if dep not in wanted:
                    wanted.add(dep)
                    todo.append(dep)
        fmt = {"P": self.prefix, "Q": self.q_t, "MIN": f"INT{self.word.bits}_MIN",
               "MAX": f"INT{self.word.bits}_MAX"}
        return ["\n".join(line.format(**fmt) for line in body)
                for name, (_, body) in _HELPERS.items() if name in wanted]

    # -- tables ------------------------------------------------------------------------
    def table_definitions(self, stage: Any, name: str) -> list[str]:
        """The read-only arrays of a table stage (none for an identity)."""
        if not isinstance(stage, TableStage) or stage.identity:
            return []
        p, n = self.prefix, stage.segments

        def arr(ctype: str, suffix: str, values: Iterable[str], size: int) -> str:
            items = list(values)
            lines = [", ".join(items[i:i + 8]) for i in range(0, len(items), 8)]
            body = ",\n    ".join(lines)
            return f"static const {ctype} {p}_{name}_{suffix}[{size}] = {{\n    {body}\n}};"

        return [arr(self.q_t, "xb", map(self.word_literal, stage.xb), n + 1),
                arr(self.q_t, "yb", map(self.word_literal, stage.yb), n + 1),
                arr("int32_t", "sl", map(self.int32_literal, stage.slope), n),
                arr("uint8_t", "sh", (f"{k}u" for k in stage.shift), n)]

    # -- stages ---------------------------------------------------------------------------
    def stage_lines(self, stage: Any, name: str, state: Mapping[str, str]) -> list[str]:
        """The statements of one sample of ``stage`` on the variable ``x``.

        ``name`` names its tables (``r1_e3``); ``state`` gives the lvalue of
        each state part (``"x"``, ``"w"``, ``"buf"``, ``"pos"``, ``"out"``).
        """
        return dispatch(self, "_stage_", stage)(stage, name, state)

    def _stage_TableStage(self, st: Any, name: str, state: Mapping[str, str]) -> list[str]:  # noqa: N802
        if st.identity:
            return ["/* the identity: nothing to compute */"]
        lines = []
        if st.period is not None:
            lines.append(f"x = {self._call('wrap', f'x, {st.period}')};")
        p = f"{self.prefix}_{name}"
        lines.append(f"x = {self._call('pwl', f'x, {p}_xb, {p}_yb, {p}_sl, {p}_sh, {st.segments}u')};")
        return lines

    def _stage_FilterStage(self, st: Any, name: str, state: Mapping[str, str]) -> list[str]:  # noqa: N802
        n, xs, ws = st.order, state.get("x"), state.get("w")
        lines = ["{", f"    int64_t acc = {self.int64_literal(st.b_int[0])} * x;"]
        if n:
            lines.append("    int32_t w;")
        for j in range(n):
            if st.b_int[j + 1]:
                lines.append(f"    acc += {self.int64_literal(st.b_int[j + 1])} * {xs}[{j}];")
            if st.a_int[j + 1]:
                lines.append(f"    acc -= {self.int64_literal(st.a_int[j + 1])} * {ws}[{j}];")
        if n:
            lines.append(f"    w = {self.narrowed('acc', st.facc - st.fwide, 'sat32')};")
            for j in range(n - 1, 0, -1):
                lines.append(f"    {xs}[{j}] = {xs}[{j - 1}];")
                lines.append(f"    {ws}[{j}] = {ws}[{j - 1}];")
            lines += [f"    {xs}[0] = x;", f"    {ws}[0] = w;",
                      f"    x = {self.narrowed('(int64_t)w', st.fwide - st.fout)};"]
        else:
            wide = self.narrowed("acc", st.facc - st.fwide, "sat32")
            lines.append(f"    x = {self.narrowed(wide, st.fwide - st.fout)};")
        lines.append("}")
        return lines

    def _stage_RingStage(self, st: Any, name: str, state: Mapping[str, str]) -> list[str]:  # noqa: N802
        buf, pos, k = state["buf"], state.get("pos"), st.samples
        if k == 1:
            return ["{", f"    const {self.q_t} y = {buf}[0];", f"    {buf}[0] = x;",
                    "    x = y;", "}"]
        return ["{", f"    const {self.q_t} y = {buf}[{pos}];", f"    {buf}[{pos}] = x;",
                f"    {pos} = ({pos} + 1u < {k}u) ? {pos} + 1u : 0u;", "    x = y;", "}"]

    def _stage_RelayStage(self, st: Any, name: str, state: Mapping[str, str]) -> list[str]:  # noqa: N802
        out, q = state["out"], self.q_t
        return [f"if (x >= {self.word_literal(st.on)}) {{", f"    {out} = ({q}){st.one};",
                f"}} else if (x <= {self.word_literal(st.off)}) {{", f"    {out} = ({q})-{st.one};",
                "}", f"x = {out};"]

    def row_output(self, shift: int) -> str:
        """The expression of a row's output in the output format (``x`` shifted right by ``shift``)."""
        return "x" if shift == 0 else self.narrowed("(int64_t)x", shift)

    # -- state -----------------------------------------------------------------------------
    def state_parts(self, stage: Any) -> list[tuple[str, str, int | None, str]]:
        """(suffix, C type kind, size, comment) of each state part of ``stage``.

        The kind is ``"word"``, ``"int32"`` or ``"index"``; a size of None is a scalar.
        """
        return dispatch(self, "_state_", stage)(stage)

    def _state_TableStage(self, st: Any) -> list[tuple[str, str, int | None, str]]:  # noqa: N802
        return []

    def _state_FilterStage(self, st: Any) -> list[tuple[str, str, int | None, str]]:  # noqa: N802
        if not st.order:
            return []
        return [("x", "word", st.order, "direct form I: past inputs"),
                ("w", "int32", st.order, f"past outputs, {st.fwide} fractional bits")]

    def _state_RingStage(self, st: Any) -> list[tuple[str, str, int | None, str]]:  # noqa: N802
        parts: list[tuple[str, str, int | None, str]] = [
            ("buf", "word", st.samples, f"ring buffer, {st.samples} samples")]
        return parts + ([("pos", "index", None, "its oldest sample")] if st.samples > 1 else [])

    def _state_RelayStage(self, st: Any) -> list[tuple[str, str, int | None, str]]:  # noqa: N802
        return [("out", "word", None, "relay output")]

    def declare(self, name: str, kind: str, size: int | None, comment: str) -> str:
        """A struct member line."""
        ctype = {"word": self.q_t, "int32": "int32_t", "index": "size_t"}[kind]
        dim = "" if size is None else f"[{size}]"
        return f"{ctype} {name}{dim};  /* {comment} */"

    @staticmethod
    def zero(lvalue: str, kind: str, size: int | None) -> list[str]:
        """Init's lines setting a state part to zero."""
        if size is None:
            return [f"{lvalue} = 0{'u' if kind == 'index' else ''};"]
        if size == 1:
            return [f"{lvalue}[0] = 0;"]
        return [f"for (i = 0u; i < {size}u; ++i) {{", f"    {lvalue}[i] = 0;", "}"]
