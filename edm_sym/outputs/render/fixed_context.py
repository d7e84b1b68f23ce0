"""Template contexts of the fixed-point C (``--real q31``/``q15``) and of the verification kit.

:func:`fixed_c_context` turns a :class:`~edm_sym.engines.fixedpoint.Build`
into the strings of ``c_fixed_header.h.j2`` and ``c_fixed_source.c.j2``,
asking :class:`~edm_sym.outputs.printing.fixed.FixedCPrinter` for every piece
of C; :func:`kit_context` makes the vectors and the tolerance of
``c_test.c.j2`` for any real type (double, float, q31, q15).
"""

from __future__ import annotations

import textwrap
from typing import Any

import numpy as np

from edm_sym.engines.fixedpoint import WORDS, Build, build, excitation, input_ints, input_ranges
from edm_sym.engines.fixedpoint.accuracy import EXCITATION, measure
from edm_sym.engines.fixedpoint.formats import KIT_SAMPLES, describe_format, to_int, to_real
from edm_sym.engines.fixedpoint.switching import SWITCH_LSB, describe_events
from edm_sym.engines.simulate import simulate_rows
from edm_sym.engines.symbolic.model import SymbolicModel
from edm_sym.outputs.printing import EdmC99Printer, c_comment_text
from edm_sym.outputs.printing.fixed import FixedCPrinter
from edm_sym.outputs.render.context import (
    RowPlan,
    Source,
    _common,
    check_context,
    input_macros,
    plan,
    wrap,
)

#: The ``--real`` values of the fixed-point builds.
FIXED = tuple(WORDS)
#: What the double and float C promise against the simulator (docs/codegen.md#float-or-double):
#: double an absolute 1e-9, float a fraction of the RMS of the compensation.
DOUBLE_TOLERANCE = 1e-9
FLOAT_TOLERANCE = 1e-4


def _labels(rows: tuple[RowPlan, ...]) -> dict[tuple[int, int], str]:
    return {(r.index, sp.col): sp.label for r in rows for sp in r.stages}


def fixed_build(model: SymbolicModel, source: Source, real: str,
                input_range: Any = None, log: Any = None) -> Build:
    """The fixed-point build of ``model`` in ``real`` (``"q31"``/``"q15"``), checked.

    ``log``, (real inputs of shape (n_inputs, N), name), sizes the internal
    signals and measures the deviation instead of the synthetic excitation.

    Raises
    ------
    FixedPointError
        When a stage cannot meet the word's accuracy, naming its row and element.
    """
    comp = model.compensator
    rows = plan(model, "edm_comp")
    used = {r.input for r in rows}
    ranges = input_ranges(tuple(model.inputs), used, source.ranges, input_range)
    return build(comp, WORDS[real], ranges, labels=_labels(rows), log=log)


def accuracy_lines(b: Build, unit: str) -> list[str]:
    """The deviation lines of a build (header and command line)."""
    return b.lines(unit)


def _format_notes(b: Build, rows: tuple[RowPlan, ...]) -> list[str]:
    d, bits = b.design, b.design.word.bits
    out = []
    for row, rp in zip(d.rows, rows, strict=True):
        parts = [f"row {row.index + 1}: {rp.input} Q{bits - 1 - d.input_fracs[row.input_index]}."
                 f"{d.input_fracs[row.input_index]}"]
        for st in row.stages:
            parts.append(f"{st.label} Q{bits - 1 - st.fout}.{st.fout}")
        out.append(" -> ".join(parts))
    return out


def _stage_notes(b: Build) -> list[str]:
    out = []
    for row in b.design.rows:
        for st in row.stages:
            head = f"row {row.index + 1}, element {st.col + 1}, {st.label}: "
            kind = type(st).__name__
            if kind == "TableStage" and not st.identity:
                lo, hi = to_real(st.xb[0], st.fin), to_real(st.xb[-1], st.fin)
                red = " after reduction modulo 2 pi" if st.period is not None else ""
                out.append(head + f"table of {st.segments} segments over {lo:.6g} .. {hi:.6g}{red}"
                           f" (clamped outside), interpolation error {st.accuracy:.2g} at "
                           "15 points per segment")
            elif kind == "FilterStage":
                out.append(head + f"direct form I, coefficients in {st.facc} fractional bits of "
                           f"a 64-bit accumulator, feedback in 32 bits ({st.fwide} fractional)")
            elif kind == "RelayStage":
                out.append(head + f"switches at x >= {st.on} and x <= {st.off} (input units)")
    return out or ["none"]


def fixed_c_context(model: SymbolicModel, source: Source, *, prefix: str = "edm_comp",
                    real: str = "q31", build: Build | None = None,
                    input_range: Any = None, log: Any = None) -> dict[str, Any]:
    """The context of the fixed-point header and source templates."""
    rows = plan(model, prefix)
    b = build or fixed_build(model, source, real, input_range, log)
    d = b.design
    pr = FixedCPrinter(d.word, prefix)
    macro = prefix.upper()
    members: list[str] = []
    init: list[str] = []
    loops = False
    tables: list[str] = []
    seen: set[str] = set()
    out_rows = []
    for row, rp in zip(d.rows, rows, strict=True):
        stages = []
        for st, sp in zip(row.stages, rp.stages, strict=True):
            lv = {}
            for suffix, kind, size, comment in pr.state_parts(st):
                member = f"{sp.name}_{suffix}"
                note = (comment if sp.name in seen else
                        f"row {row.index + 1} element {st.col + 1} {sp.label}: {comment}")
                seen.add(sp.name)
                members.append(pr.declare(member, kind, size, c_comment_text(note)))
                lv[suffix] = f"s->{member}"
                init += pr.zero(lv[suffix], kind, size)
                loops |= size is not None and size > 1
            tables += pr.table_definitions(st, sp.name)
            fmt = f"Q{d.word.bits - 1 - st.fout}.{st.fout}"
            stages.append({"comment": c_comment_text(f"element {st.col + 1}: {sp.label} -> {fmt}"),
                           "lines": pr.stage_lines(st, sp.name, lv)})
        out_rows.append({"index": row.index, "input_macro": rp.input_macro,
                         "comment": [c_comment_text(t) for t in wrap(rp.summary)],
                         "stages": stages,
                         "output": pr.row_output(row.stages[-1].fout - d.out_frac)})
    has_state = bool(members)
    if not has_state:
        members.append("uint8_t unused;  /* no state: every element is static */")
        init.append("s->unused = 0u;")
    ctx = _common(model, source, rows)
    unit = ctx["force_unit"]
    macros = input_macros(prefix, model.inputs)
    ctx.update({
        "prefix": prefix, "macro": macro, "real": d.word.name, "q_t": pr.q_t,
        "word_type": d.word.c_type, "state_t": f"{prefix}_state_t",
        "header_file": f"{prefix}.h", "source_file": f"{prefix}.c", "guard": f"{macro}_H",
        "sample_time_ns": str(round(model.sample_time * 1e9)),
        "inputs": [{"macro": m, "index": i, "frac": d.input_fracs[i],
                    "name": c_comment_text(f"{n}, {describe_format(d.input_fracs[i], d.word.bits)}")}
                   for i, (n, m) in enumerate(zip(model.inputs, macros, strict=True))],
        "out_frac": d.out_frac,
        "out_format": describe_format(d.out_frac, d.word.bits),
        "summary": [[c_comment_text(t) for t in wrap(s, 76)] for s in ctx["summary"]],
        "input_notes": [[c_comment_text(t) for t in wrap(s, 76)] for s in ctx["input_notes"]],
        "formats": [[c_comment_text(t) for t in wrap(s, 76)] for s in _format_notes(b, rows)],
        "stage_notes": [[c_comment_text(t) for t in wrap(s, 76)] for s in _stage_notes(b)],
        "accuracy": [[c_comment_text(t) for t in wrap(s, 76)] for s in accuracy_lines(b, unit)],
        "margin_note": [c_comment_text(t) for t in textwrap.wrap(
            "Formats: an input's from its range (x1.25); an internal signal's from its range on "
            f"{_sized_on(b)} through the reference simulator, "
            "widened x2, or from a guaranteed bound where tighter. Outside its format a value "
            "saturates, never wraps; a table clamps its input to its range.", 78)],
        "source_name": c_comment_text(source.name),
        "target": c_comment_text(source.target),
        "members": members, "init_locals": ["size_t i;"] if loops else [], "init_lines": init,
        "step_unused": [] if has_state else ["(void)s;"],
        "tables": tables, "rows": out_rows, "tail_rows": out_rows[1:],
        "tolerance_lsb": str(int(np.ceil(b.accuracy.goal * 2.0 ** d.out_frac))),
    })
    pr.helpers_used.add("sat")  # the step's return
    ctx["helpers"] = pr.helper_definitions()
    return check_context(ctx, FIXED_KEYS)


FIXED_KEYS = ("prefix", "macro", "real", "q_t", "state_t", "header_file", "source_file", "guard",
              "inputs", "members", "init_lines", "rows", "helpers", "source", "summary",
              "formats", "accuracy", "force_unit", "effort")


def kit_context(model: SymbolicModel, source: Source, *, prefix: str = "edm_comp",
                real: str = "double", build: Build | None = None,
                input_range: Any = None, log: Any = None) -> dict[str, Any]:
    """The context of the verification kit ``<prefix>_test.c`` for the ``real`` build.

    The vectors are the first :data:`KIT_SAMPLES` samples of the recorded log
    (``log``: real inputs (n_inputs, N) and its name; a fixed-point build's
    own log), else the synthetic excitation inside the input ranges, as the
    build reads them (rounded to float, or to each input's Q format), and the
    reference simulator's output on exactly those inputs.
    """
    comp = model.compensator
    rows = plan(model, prefix)
    macro = prefix.upper()
    used = {r.input for r in rows}
    raw_parts: list[dict[str, Any]] = []
    if real in FIXED:
        b = build or fixed_build(model, source, real, input_range, log)
        d = b.design
        if b.signals is not None:
            x, vectors = b.signals[:, :KIT_SAMPLES], f"the log {b.log_name}"
        else:
            x, vectors = excitation(d.inputs, d.ranges, d.sample_time, KIT_SAMPLES), EXCITATION
        u = input_ints(d, x)
        _, ref = measure(d, comp, x)
        expected = to_int(ref.total, d.out_frac, d.word)
        raw = to_int(ref.raw, d.out_frac, d.word)
        pr = FixedCPrinter(d.word, prefix)
        value_t, dev_t = pr.q_t, "int64_t"
        lit = pr.word_literal
        u_text = [[lit(v) for v in col] for col in u.T]
        y_text = [lit(v) for v in expected]
        tolerance = f"INT64_C({int(np.ceil(b.accuracy.goal * 2.0 ** d.out_frac))})"
        unit_note = f"output LSBs (2^-{d.out_frac} {_unit(source)})"
        checks = [f"{macro}_OUTPUT_FRAC != {d.out_frac}"] + [
            f"{m}_FRAC != {d.input_fracs[i]}" for i, m in enumerate(input_macros(prefix, model.inputs))]
        printf = ('"%s: max deviation %lld LSB (tolerance %lld), 2^-' + str(d.out_frac) + ' '
                  + _unit(source) + ' each\\n"')
        print_cast = "(long long)"
        promise = b.lines(_unit(source))[0]
        raw_parts = [_raw_part(expected, raw, ref.events, lit, macro)]
    else:
        ranges = input_ranges(tuple(model.inputs), used, source.ranges, input_range)
        if log is not None:
            x, vectors = np.asarray(log[0], dtype=float)[:, :KIT_SAMPLES], f"the log {log[1]}"
        else:
            x = excitation(tuple(model.inputs), ranges, comp.sample_time, KIT_SAMPLES)
            vectors = EXCITATION
        if real == "float":
            x = x.astype(np.float32).astype(float)
        ref = simulate_rows(comp, comp.matrix.rows, x).sum(axis=0)
        pr = EdmC99Printer({"real": real, "prefix": prefix})
        value_t = dev_t = pr.real_t
        u_text = [[pr.literal(v) for v in col] for col in x.T]
        y_text = [pr.literal(v) for v in ref]
        rms = float(np.sqrt(np.mean(ref ** 2)))
        tol = DOUBLE_TOLERANCE if real == "double" else FLOAT_TOLERANCE * rms
        tolerance = pr.literal(tol)
        unit_note = _unit(source)
        checks = []
        printf = '"%s: max deviation %.3e (tolerance %.3e) ' + _unit(source) + '\\n"'
        print_cast = "(double)"
        promise = (f"promised: at most {tol:.3g} {_unit(source)} from the double simulator "
                   f"({'absolute' if real == 'double' else f'{FLOAT_TOLERANCE:g} of the RMS {rms:.4g}'})")
    ctx = {
        "prefix": prefix, "macro": macro, "real": real, "header_file": f"{prefix}.h",
        "test_file": f"{prefix}_test.c", "value_t": value_t, "dev_t": dev_t,
        "state_t": f"{prefix}_state_t", "samples": len(y_text), "num_inputs": len(model.inputs),
        "u_lines": [", ".join(r) for r in u_text], "y_lines": _chunks(y_text),
        "tolerance": tolerance, "unit_note": unit_note, "checks": checks,
        "printf": printf, "print_cast": print_cast,
        "promise": [c_comment_text(t) for t in textwrap.wrap(promise, 76)],
        "source_name": c_comment_text(source.name), "source": source,
        "vectors": [c_comment_text(t) for t in textwrap.wrap(
            f"The vectors: {len(y_text)} samples of {vectors}, as this build reads them, and the "
            + ("reference simulator's output on the unrounded inputs under the switching rule "
               "(below)." if raw_parts else "reference simulator's output on exactly those inputs."),
            76)],
        "raw": raw_parts,
    }
    return ctx


def _raw_part(expected: np.ndarray, raw: np.ndarray, events: Any, lit: Any,
              macro: str) -> dict[str, Any]:
    """The kit's switching-rule block: where the plain double simulator's output differs.

    The pairs (sample, plain output) end with a sentinel at the number of
    samples, so the arrays are never empty.
    """
    where = np.nonzero(raw != expected)[0]
    rule = (f"The switching rule (docs/codegen.md): a relay or sign of the reference reads the "
            f"build's own input where it is within {SWITCH_LSB} LSB of the double "
            "simulator's, so it steps where the build does when the two straddle a threshold "
            f"by a rounding. In these vectors: {describe_events(tuple(events))}. The expected "
            "outputs above follow the rule; the plain double simulator's outputs differ at "
            f"{len(where)} samples, listed here.")
    return {
        "comment": [c_comment_text(t) for t in textwrap.wrap(rule, 76)],
        "events": str(len(events)),
        "count": f"{macro}_TEST_RAW_SAMPLES",
        "samples": str(len(where)),
        "k_lines": _chunks([f"{int(k)}u" for k in where] + [f"{macro}_TEST_SAMPLES"]),
        "y_lines": _chunks([lit(v) for v in raw[where]] + [lit(0)]),
    }


def _sized_on(b: Build) -> str:
    if b.signals is None:
        return "a synthetic excitation inside the input ranges"
    return (f"a synthetic excitation inside the input ranges and on the log {b.log_name} "
            f"({b.signals.shape[-1]} samples)")


def _unit(source: Source) -> str:
    from edm_sym.core.units import axis_units

    return axis_units(source.axis).force


def _chunks(items: list[str], n: int = 8) -> list[str]:
    return [", ".join(items[i:i + n]) for i in range(0, len(items), n)]
