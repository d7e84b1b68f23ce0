"""Template contexts: everything a template shows, computed and validated here.

The plan of a compensator (:func:`plan`) is language-neutral: per row, its
stages with their state as each stage's realisation lays it out (filter
states, ring buffers sized by the decoded delay, relay outputs) and readable
labels. :func:`c_context` and :func:`python_context` turn the plan into the
strings the templates place, asking the printers for every piece of C or
Python (a stage's lines by the type of its realisation); the templates only loop.
"""

from __future__ import annotations

import hashlib
import math
import re
import sys
import textwrap
import warnings
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from edm_sym.core.elements.realisation import LinearFilter, StaticMap
from edm_sym.core.errors import NumericsWarning
from edm_sym.core.result import recorded_ranges
from edm_sym.core.units import axis_units
from edm_sym.engines.symbolic.model import SymbolicModel
from edm_sym.outputs.printing import REALS, EdmC99Printer, EdmPythonPrinter, c_comment_text
from edm_sym.outputs.printing.c import is_c_identifier
from edm_sym.outputs.render.inputs import (
    NO_GUARDS,
    OUTSIDE_RANGE,
    guard_notes,
    input_docs,
)

#: The format and version of the result files the exports name.
RESULT_FORMAT = "edm-result"

#: A filter whose frequency response moves by more than this fraction of its
#: peak when its coefficients are rounded to float gets a NumericsWarning in a
#: single-precision export (docs/api.md#numerical-agreement asks 1e-4 of the RMS; this leaves margin).
FLOAT_RESPONSE_LIMIT = 2e-5


@dataclass(frozen=True)
class Source:
    """Where the exported model comes from, for the files' headers.

    Attributes
    ----------
    name : str
        The result file's name (no folder, so output does not depend on it).
    sha256 : str
        The sha256 of the result file.
    version : int
        The result format version.
    target : str
        The name of the target column the compensator reproduces.
    axis : str
        The result's axis, ``"rotary"`` or ``"linear"`` (the units of the inputs and output).
    roles : mapping of str to str
        The roles the result records for its inputs (``EdmResult.roles``).
    ranges : mapping of str to (float, float)
        The (min, max) of each column recorded for the abstraction log.
    log : str or None
        The abstraction log's file name, None when the result records none.
    """

    name: str
    sha256: str
    version: int
    target: str
    axis: str = "rotary"
    roles: Mapping[str, str] = field(default_factory=dict)
    ranges: Mapping[str, tuple[float, float]] = field(default_factory=dict)
    log: str | None = None


@dataclass(frozen=True)
class StateMember:
    """One state variable of a stage: ``size`` reals, or an index when ``size`` is None.

    ``suffix`` is the realisation's name for it (:class:`~edm_sym.core.elements.realisation.StatePart`).
    """

    name: str
    size: int | None
    comment: str
    suffix: str


@dataclass(frozen=True)
class StagePlan:
    """A stage with its label and state (laid out by its realisation)."""

    row: int
    col: int
    name: str
    label: str
    stage: Any
    state: tuple[StateMember, ...]

    @property
    def kind(self) -> str:
        """The stage kind's readable name (from its realisation's type)."""
        return self.stage.realisation.kind


@dataclass(frozen=True)
class RowPlan:
    """A row: its input (name, index, C macro) and its stages left to right."""

    index: int
    input: str
    input_index: int
    input_macro: str
    stages: tuple[StagePlan, ...]

    @property
    def summary(self) -> str:
        """``"row 1: omega -> sign -> gain (a_2 = 0.95)"``."""
        return f"row {self.index + 1}: " + " -> ".join([self.input, *(s.label for s in self.stages)])


#: C99/C11 standard headers: ``<prefix>.h`` must not shadow one of them.
C_HEADERS = frozenset(
    "assert complex ctype errno fenv float inttypes iso646 limits locale math setjmp signal "
    "stdalign stdarg stdatomic stdbool stddef stdint stdio stdlib stdnoreturn string tgmath "
    "threads time uchar wchar wctype".split())
#: C++ keywords (a C file may be compiled as C++ in a firmware project).
CXX_KEYWORDS = frozenset(
    "alignas alignof and and_eq asm bitand bitor bool catch char16_t char32_t char8_t class "
    "compl concept consteval constexpr constinit const_cast co_await co_return co_yield decltype "
    "delete dynamic_cast explicit export false friend mutable namespace new noexcept not not_eq "
    "nullptr operator or or_eq private protected public reinterpret_cast requires static_assert "
    "static_cast template this thread_local throw true try typeid typename using virtual "
    "wchar_t xor xor_eq".split())
#: Python modules users import beside the generated module: ``<prefix>.py`` must not shadow them.
PYTHON_NEIGHBOURS = frozenset(
    "numpy scipy sympy control matplotlib pandas jinja2 pytest edm_sym".split())


#: The longest prefix: file names of 255 bytes leave room for the report's longest suffix,
#: and C compilers need keep only 63 characters of an internal identifier significant.
MAX_PREFIX = 63


def prefix_problem(prefix: str) -> str | None:
    """Why ``prefix`` cannot name the generated files and symbols, or None when it can.

    A prefix must be a C identifier that starts with a letter (a leading
    underscore is reserved to the C library: ``_`` would make ``__tan``), and
    must be no C, C++ or Python keyword, no C standard header's name
    (``<prefix>.h`` beside ``<math.h>``) and no module of Python's standard
    library or of the packages users import beside the export (``<prefix>.py``
    would shadow it).
    """
    import keyword

    if not isinstance(prefix, str) or not is_c_identifier(prefix):
        return "expected a C identifier"
    if len(prefix) > MAX_PREFIX:
        return (f"expected at most {MAX_PREFIX} characters ({len(prefix)} here; it names "
                f"files such as <prefix>_fig_contributions_evaluation.pdf)")
    if not prefix[0].isalpha():
        return "expected a name starting with a letter (a leading underscore is reserved to the C library)"
    if prefix in CXX_KEYWORDS or keyword.iskeyword(prefix) or keyword.issoftkeyword(prefix):
        return "expected a name that is no C, C++ or Python keyword"
    if prefix in C_HEADERS:
        return f"expected a name that shadows no C header (<{prefix}.h> is one)"
    if prefix in sys.stdlib_module_names or prefix in PYTHON_NEIGHBOURS:
        return f"expected a name that shadows no Python module ({prefix} is one)"
    return None


def validate_prefix(prefix: str) -> str:
    """Return ``prefix`` when it can name the generated files and symbols, else raise ValueError.

    See :func:`prefix_problem` for the rules.
    """
    problem = prefix_problem(prefix)
    if problem:
        raise ValueError(f"prefix: {problem}, found {prefix!r}")
    return prefix


#: The ``real`` values of the fixed-point builds (edm_sym.outputs.render.fixed_context).
FIXED_REALS = ("q31", "q15")


def validate_real(real: str) -> str:
    """Return ``real`` when it is ``"float"``, ``"double"``, ``"q31"`` or ``"q15"``, else raise ValueError."""
    if real not in REALS + FIXED_REALS:
        raise ValueError(f"real: expected one of {', '.join(REALS + FIXED_REALS)}, found {real!r}")
    return real


def input_macros(prefix: str, inputs: tuple[str, ...]) -> tuple[str, ...]:
    """``PREFIX_INPUT_<NAME>`` per input: upper-cased, other characters made ``_``."""
    out = []
    for name in inputs:
        macro = f"{prefix.upper()}_INPUT_{re.sub(r'[^A-Za-z0-9_]', '_', name).upper()}"
        if macro in out:
            other = inputs[out.index(macro)]
            raise ValueError(f"inputs: {other!r} and {name!r} both become the C macro {macro}; "
                             "rename one of them")
        out.append(macro)
    return tuple(out)


def source_of(result: Any) -> Source:
    """The :class:`Source` of an :class:`~edm_sym.core.result.EdmResult`.

    A result not loaded from a file is named by the sha256 of its canonical
    serialisation, which is the file :func:`edm_sym.core.result.save_result` writes.
    """
    from edm_sym.core.result import VERSION, dumps

    sha = result.sha256 or hashlib.sha256(dumps(result).encode("utf-8")).hexdigest()
    name = Path(result.source).name if getattr(result, "source", None) else "result.json"
    log, ranges = recorded_ranges(tuple(getattr(result, "logs", ())))
    return Source(name, sha, VERSION, result.target, getattr(result, "axis", "rotary"),
                  dict(getattr(result, "roles", {})), ranges, log)


def _fmt(v: float) -> str:
    return format(v, ".6g")


def plan(model: SymbolicModel, prefix: str) -> tuple[RowPlan, ...]:
    """The language-neutral plan of ``model``'s rows, validated.

    Raises
    ------
    ValueError
        On a non-finite coefficient, threshold or sample time, an empty delay,
        a filter without state, or two inputs with the same C macro.
    """
    validate_prefix(prefix)
    ts = model.sample_time
    if not (isinstance(ts, float) and math.isfinite(ts) and ts > 0):
        raise ValueError(f"sample_time: expected a positive finite number, found {ts!r}")
    if not model.rows:
        raise ValueError("matrix: expected at least one row, found 0")
    macros = input_macros(prefix, model.inputs)
    rows = []
    for row in model.rows:
        stages = []
        for st in row.stages:
            where = f"rows[{row.index}].elements[{st.col}] ({st.element.name})"
            name = f"r{row.index + 1}_e{st.col + 1}"
            label = st.element.name
            if st.param is not None:
                label += f" ({st.param.symbol} = {_fmt(st.param.value)})"
            if isinstance(st.realisation, StaticMap) and st.expr is None:
                raise ValueError(f"{where}: expected a static expression, found none")
            try:
                st.realisation.validate()
            except ValueError as exc:
                raise ValueError(f"{where}: {exc}") from None
            # The first member's comment says whose state it is; the others follow it.
            state = tuple(
                StateMember(f"{name}_{p.suffix}", p.size, p.comment if k else
                            f"row {row.index + 1} element {st.col + 1} {label}: {p.comment}",
                            p.suffix)
                for k, p in enumerate(st.realisation.state_layout()))
            stages.append(StagePlan(row.index, st.col, name, label, st, state))
        idx = model.inputs.index(row.input)
        rows.append(RowPlan(row.index, row.input, idx, macros[idx], tuple(stages)))
    return tuple(rows)


def float_response_error(b: tuple[float, ...], a: tuple[float, ...]) -> float:
    """How far a filter's frequency response moves when its coefficients become floats.

    Returns the largest change of ``H(e^{jw})`` over a logarithmic grid of
    frequencies up to Nyquist, relative to the largest ``|H|`` there.
    """
    w = np.logspace(-5.0, 0.0, 400) * np.pi
    zi = np.exp(-1j * w)

    def response(bb: np.ndarray, aa: np.ndarray) -> np.ndarray:
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            return np.polyval(bb[::-1], zi) / np.polyval(aa[::-1], zi)

    b64, a64 = np.asarray(b, dtype=float), np.asarray(a, dtype=float)
    h = response(b64, a64)
    hq = response(b64.astype(np.float32).astype(float), a64.astype(np.float32).astype(float))
    ok = np.isfinite(h) & np.isfinite(hq)
    if not ok.any():
        return 0.0
    peak = float(np.max(np.abs(h[ok])))
    return float(np.max(np.abs(hq[ok] - h[ok])) / peak) if peak > 0 else 0.0


def warn_single_precision(rows: tuple[RowPlan, ...]) -> list[str]:
    """Warn (NumericsWarning) about filters too sensitive for single precision.

    Returns the warning messages (empty when every filter is well conditioned).
    """
    messages = []
    for row in rows:
        for sp in row.stages:
            if not isinstance(sp.stage.realisation, LinearFilter):
                continue
            err = float_response_error(sp.stage.realisation.b, sp.stage.realisation.a)
            if err > FLOAT_RESPONSE_LIMIT:
                messages.append(
                    f"rows[{row.index}].elements[{sp.col}] ({sp.label}): rounding its coefficients "
                    f"to float moves its frequency response by {err:.1e} of its peak, so the "
                    "float C may miss the simulator by more than 1e-4 of the RMS; prefer "
                    'real="double"')
    for msg in messages:
        warnings.warn(msg, NumericsWarning, stacklevel=3)
    return messages


def _dynamic_notes(rows: tuple[RowPlan, ...], ts: float) -> list[str]:
    """One line per dynamic stage: where it is and how it is realised in discrete time."""
    out = []
    for row in rows:
        for sp in row.stages:
            note = sp.stage.realisation.describe()
            if note is not None:
                out.append(f"row {row.index + 1}, element {sp.col + 1}, {sp.label}: {note}")
    return out


#: Width of the text of wrapped comment and docstring lines (their indentation aside).
TEXT_WIDTH = 88


_KEEP = "\x00"  # stands for a space that must not break a line


def wrap(text: str, width: int = TEXT_WIDTH) -> list[str]:
    """``text`` as lines of at most ``width`` characters; continuation lines indented by 4.

    Lines break between words, never inside parentheses (``gain (a_2 = 0.95)``).
    """
    kept = re.sub(r"\([^()]*\)", lambda m: m.group(0).replace(" ", _KEEP), text)
    lines = textwrap.wrap(kept, width, subsequent_indent="    ", break_long_words=False,
                          break_on_hyphens=False) or [""]
    return [line.replace(_KEEP, " ") for line in lines]


def _common(model: SymbolicModel, source: Source, rows: tuple[RowPlan, ...]) -> dict[str, Any]:
    docs = input_docs(model, axis=source.axis, roles=source.roles, ranges=source.ranges,
                      log=source.log)
    return {
        "source": source,
        "force_unit": axis_units(source.axis).force,
        "effort": axis_units(source.axis).effort,
        "input_docs": docs,
        "input_notes": [d.text() for d in docs],
        "used_inputs": [d.name for d in docs if d.used],
        "unused_inputs": [d.name for d in docs if not d.used],
        "outside_range": OUTSIDE_RANGE,
        "guards": guard_notes(rows) or [NO_GUARDS],
        "format": RESULT_FORMAT,
        "n_elements": model.compensator.matrix.n_elements,
        "num_rows": len(rows),
        "num_inputs": len(model.inputs),
        "summary": [r.summary for r in rows],
        "dynamics": _dynamic_notes(rows, model.sample_time) or ["none (every element is static)"],
        "sample_time_text": repr(model.sample_time),
    }


def _macro_note(doc: Any) -> str:
    """The comment of an input's index macro: its name, unit and whether a row reads it."""
    unit = f" [{doc.unit}]" if doc.unit else ""
    return doc.name + unit + ("" if doc.used else ", read by no row")


def _unused_note(macros: list[str]) -> list[str]:
    """The header's lines on the slots of ``u`` that no row reads (none when every input is read)."""
    if not macros:
        return []
    text = ("u[] keeps a slot for every input of the result, so the indices stay those of "
            "result.json; the step function never reads the slots of the inputs no row reads ("
            + ", ".join(macros) + "): they need no value.")
    return [c_comment_text(t) for t in textwrap.wrap(text, 80)]


def c_context(model: SymbolicModel, source: Source, *, prefix: str = "edm_comp",
              real: str = "double") -> dict[str, Any]:
    """The context of the C header and source templates.

    Parameters
    ----------
    model : SymbolicModel
    source : Source
    prefix : str
        C identifier prefixing every exported name.
    real : {"float", "double"}
    """
    validate_real(real)
    rows = plan(model, prefix)
    if real == "float":
        warn_single_precision(rows)
    pr = EdmC99Printer({"real": real, "prefix": prefix})
    macro = prefix.upper()
    members: list[str] = []
    init: list[str] = []
    loops = False
    out_rows = []
    for row in rows:
        stages = []
        for sp in row.stages:
            st = sp.stage
            lv = {p.name: pr.state_ref(p.name) for p in sp.state}
            for p in sp.state:
                if p.size is None:
                    members.append(pr.declare_index(p.name, p.comment))
                    init += pr.zero_index(lv[p.name])
                else:
                    members.append(pr.declare_real_array(p.name, p.size, p.comment))
                    init += pr.zero_real_array(lv[p.name], p.size)
                    loops |= p.size > 1
            lines = pr.stage_lines(st, {p.suffix: lv[p.name] for p in sp.state})
            stages.append({"comment": c_comment_text(f"element {sp.col + 1}: {sp.label}"),
                           "lines": lines})
        out_rows.append({"index": row.index, "input_macro": row.input_macro,
                         "comment": [c_comment_text(t) for t in wrap(row.summary)],
                         "stages": stages})
    has_state = bool(members)
    if not has_state:  # C99 has no empty structs
        members.append(pr.declare_placeholder("no state: every element is static"))
        init += pr.zero_placeholder()
    ctx = _common(model, source, rows)
    ctx.update({
        "prefix": prefix,
        "macro": macro,
        "real": real,
        "real_t": pr.real_t,
        "state_t": f"{prefix}_state_t",
        "header_file": f"{prefix}.h",
        "source_file": f"{prefix}.c",
        "guard": f"{macro}_H",
        "sample_time": pr.literal(model.sample_time),
        "inputs": [{"macro": m, "index": d.index, "name": c_comment_text(_macro_note(d))}
                   for d, m in zip(ctx["input_docs"], input_macros(prefix, model.inputs),
                                   strict=True)],
        "summary": [[c_comment_text(t) for t in wrap(s, 76)] for s in ctx["summary"]],
        "dynamics": [[c_comment_text(t) for t in wrap(s, 76)] for s in ctx["dynamics"]],
        "input_notes": [[c_comment_text(t) for t in wrap(s, 76)] for s in ctx["input_notes"]],
        "outside_range": [c_comment_text(t) for t in textwrap.wrap(ctx["outside_range"], 78)],
        "guards": [[c_comment_text(t) for t in wrap(s, 76)] for s in ctx["guards"]],
        "unused_note": _unused_note([m for d, m in zip(ctx["input_docs"], input_macros(
            prefix, model.inputs), strict=True) if not d.used]),
        "source_name": c_comment_text(source.name),
        "target": c_comment_text(source.target),
        "members": members,
        "init_locals": pr.loop_index() if loops else [],
        "init_lines": init,
        "step_unused": [] if has_state else pr.state_unused(),
        "rows": out_rows,
        "tail_rows": out_rows[1:],
    })
    # Helpers last: printing the rows above is what records which ones are used.
    ctx["helpers"] = pr.helper_definitions()
    return check_context(ctx, C_KEYS)


def python_context(model: SymbolicModel, source: Source, *, prefix: str = "edm_comp"
                   ) -> dict[str, Any]:
    """The context of the Python module template."""
    rows = plan(model, prefix)
    pr = EdmPythonPrinter()
    reset: list[str] = []
    out_rows = []
    for row in rows:
        stages = []
        for sp in row.stages:
            st = sp.stage
            attr = {p.name: pr.state_ref(p.name) for p in sp.state}
            reset += [pr.zero_state(attr[p.name], p.size) for p in sp.state]
            lines = pr.stage_lines(st, {p.suffix: attr[p.name] for p in sp.state})
            stages.append({"comment": f"element {sp.col + 1}: {sp.label}", "lines": lines})
        out_rows.append({"index": row.index, "number": row.index + 1,
                         "input_index": row.input_index, "comment": wrap(row.summary),
                         "stages": stages})
    helpers = pr.helper_definitions()
    code = helpers + [ln for r in out_rows for s in r["stages"] for ln in s["lines"]]
    ctx = _common(model, source, rows)
    ctx.update({
        "prefix": prefix,
        "module_file": f"{prefix}.py",
        "imports": ["math"] if pr.uses_math(code) else [],
        "inputs_literal": pr.tuple_of([pr.string(n) for n in model.inputs]),
        "used_inputs_literal": pr.tuple_of([pr.string(n) for n in ctx["used_inputs"]]),
        "rows_tuple": pr.tuple_of([f"r{r['number']}" for r in out_rows]),
        "target_literal": pr.string(source.target),
        "sha256_literal": pr.string(source.sha256),
        "sample_time": pr.literal(model.sample_time),
        "constants": pr.helper_constants(helpers),
        "helpers": helpers,
        "reset_lines": reset or pr.empty_body(),
        "rows": out_rows,
        "tail_rows": out_rows[1:],
    })
    _check_docstring_text(ctx)
    for key in ("summary", "dynamics", "input_notes", "guards"):
        ctx[key] = [wrap(t) for t in ctx[key]]
    ctx["outside_range"] = textwrap.wrap(ctx["outside_range"], TEXT_WIDTH)
    return check_context(ctx, PY_KEYS)


def _check_docstring_text(ctx: Mapping[str, Any]) -> None:
    """Names shown in the module docstring and comments must not end or escape it."""
    for text in (*ctx["summary"], *ctx["dynamics"], *ctx["input_notes"], *ctx["guards"],
                 ctx["source"].name, ctx["source"].target):
        if '"""' in text or "\\" in text or "\n" in text:
            raise ValueError(f"names: expected no triple quote, backslash or newline, found {text!r}")


C_KEYS = ("prefix", "macro", "real", "real_t", "state_t", "header_file", "source_file", "guard",
          "sample_time", "inputs", "members", "init_lines", "rows", "helpers", "source",
          "summary", "dynamics", "input_notes", "outside_range", "guards", "force_unit", "effort")
PY_KEYS = ("prefix", "module_file", "imports", "inputs_literal", "used_inputs_literal",
           "sample_time", "helpers", "reset_lines", "rows", "source", "summary", "dynamics",
           "input_notes", "outside_range", "guards", "force_unit", "effort")


def check_context(ctx: dict[str, Any], keys: tuple[str, ...]) -> dict[str, Any]:
    """Check that ``ctx`` has every key a template reads, each non-empty text or list.

    Raises
    ------
    ValueError
        Naming the missing or empty key (a defect of this module, not of the input).
    """
    for k in keys:
        if k not in ctx:
            raise ValueError(f"context: expected the key {k!r}, found it missing")
        v = ctx[k]
        if v is None or (isinstance(v, str) and not v.strip()):
            raise ValueError(f"context: {k!r} is empty")
    for r in ctx["rows"]:
        for st in r["stages"]:
            if any("\n" in line for line in st["lines"]):
                raise ValueError(f"context: a code line of row {r['index'] + 1} holds a newline")
    return ctx
