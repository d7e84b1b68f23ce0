"""A row's program, and batches of rows run together.

:func:`compile_steps` turns a row's steps (:func:`~edm_sym.engines.kernel.trace.encode`)
into a :class:`Program`: compiled lines and numpy steps, in order.
:func:`run_rows` runs the programs of many rows as one schedule: each row in
turn goes as far as it can (its compiled lines, and its numpy steps: numpy's
own functions, one call over its whole signal) while its signal is in the
cache, up to its next filter of order 1 or 2; then the filters every row
waits at run together (:data:`~edm_sym.engines.kernel.loops.GROUP`), their
recurrences overlapped; and so on. A row's first instruction reads its input
where it is (no copy). Each row's operations and their order are its own
program's whatever the batch, so a row's numbers never depend on the rows it
runs with.

The numpy steps (:data:`CALLS`) give what the math interface
(:class:`~edm_sym.core.elements.ops.NumpyOps`) gives, to the bit, with fewer
passes: in place, their guards compiled, and no tangent's sine or saturated
tanh computed where the answer is known (the C library's tanh,
:func:`~edm_sym.core.elements.libm.tanh`, is exactly +-1 from
|x| = :data:`TANH_ONE`, which the tests check). Their transcendental
functions are the C library's (:mod:`~edm_sym.core.elements.libm`), as the
math interface's are.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from edm_sym.core.elements import libm
from edm_sym.core.elements.ops import (
    LOG_QUOTIENT_LIMIT,
    NUMPY,
    POW_INPUT_LIMIT,
    TAN_LIMIT,
)
from edm_sym.core.elements.realisation import Realisation
from edm_sym.engines.kernel.loops import (
    CALL,
    COPY,
    GROUP,
    LFILTER,
    NUMBA,
    STORE,
    clip,
    quotient,
    run_lines,
    saturated,
    scatter,
    sign_times,
    tan_guard,
)
from edm_sym.engines.kernel.trace import encode, gene_encoder

if NUMBA:  # the C library's functions compiled too (the same bits, faster)
    libm.use_compiled()

__all__ = ["CALLS", "Program", "compile_row", "compile_steps", "log_bounds", "run_program",
           "run_rows", "simulate_rows"]


@dataclass(frozen=True)
class Program:
    """A row's program: lines and numpy steps, in order, and coefficients.

    ``lines`` holds ``(op, i1, i2, r1, r2)`` tuples: a compiled instruction
    (``i2`` an offset into ``coef``), or ``CALL`` with ``i1`` indexing
    ``calls``, the ``(method, numbers)`` numpy steps of the math interface.
    ``stores`` is the number of STORE lines (``i1``: the j-th prefix).
    """

    lines: tuple
    calls: tuple
    coef: np.ndarray
    stores: int


def compile_steps(stages: Sequence[tuple], *, store: bool = False
                  ) -> tuple[Program, list[int]]:
    """A row's program from its stages' steps (:func:`~edm_sym.engines.kernel.trace.encode`).

    Parameters
    ----------
    stages : sequence of tuple
        Each stage's steps, left to right.
    store : bool
        Also store the output of every stage but the last that changes its
        input (the row's prefixes, for a prefix cache).

    Returns
    -------
    program : Program
    stored : list of int
        For each STORE, the number of stages whose output it holds.
    """
    lines: list[tuple] = []
    calls: list[tuple] = []
    coef: list[float] = []
    stored: list[int] = []
    last = len(stages) - 1
    for i, steps in enumerate(stages):
        for step in steps:
            if len(step) == 2:  # a numpy step
                lines.append((CALL, len(calls), 0, 0.0, 0.0))
                calls.append(step)
                continue
            op, i1, r1, r2, c = step
            lines.append((op, i1, len(coef), r1, r2))
            coef.extend(c)
        if steps and store and i < last:
            lines.append((STORE, len(stored), 0, 0.0, 0.0))
            stored.append(i + 1)
    program = Program(tuple(lines), tuple(calls), np.array(coef or [0.0], dtype=np.float64),
                      len(stored))
    return program, stored


def compile_row(stages: Sequence[Realisation], *, store: bool = False
                ) -> tuple[Program, list[int]]:
    """A row's program from its realisations (see :func:`compile_steps`)."""
    return compile_steps([encode(r) for r in stages], store=store)


# -- numpy steps: the C library's functions over the signal, their guards compiled --------

def _ufunc(fn: Any) -> Callable[..., None]:
    def call(v: np.ndarray, x: np.ndarray, scratch: np.ndarray) -> None:
        fn(x, out=v)

    return call


def _clipped(fn: Any) -> Callable[..., None]:
    def call(v: np.ndarray, x: np.ndarray, scratch: np.ndarray) -> None:
        clip(x, v, -1.0, 1.0)
        fn(v, out=v)

    return call


#: ``|x|`` from which the C library's tanh (:func:`~edm_sym.core.elements.libm.tanh`) is
#: exactly +-1 (from about 19.06 on; 22 is fdlibm's bound). tests/test_kernel.py checks it.
TANH_ONE = 22.0


def _tanh(v: np.ndarray, x: np.ndarray, scratch: np.ndarray) -> None:
    # Saturated samples are +-1 without the call: the call for the rest only.
    where = _indices(x.shape[0])
    m = saturated(x, v, TANH_ONE, scratch, where)
    if m == x.shape[0]:
        libm.tanh(scratch, out=v)
    elif m:
        part = scratch[:m]
        libm.tanh(part, out=part)
        scatter(v, part, where, m)


def _tan(v: np.ndarray, x: np.ndarray, scratch: np.ndarray) -> None:
    libm.tan(x, out=scratch)
    tan_guard(scratch, x, v, TAN_LIMIT)


def _sym_log(v: np.ndarray, x: np.ndarray, scratch: np.ndarray, a: float) -> None:
    quotient(x, scratch, a, LOG_QUOTIENT_LIMIT)
    libm.log1p(scratch, out=scratch)
    sign_times(x, scratch, v)


def _sym_pow(v: np.ndarray, x: np.ndarray, scratch: np.ndarray, a: float) -> None:
    quotient(x, scratch, 1.0, POW_INPUT_LIMIT)  # |x| / 1 is |x| to the bit
    libm.pow(scratch, a, out=scratch)  # the C library's pow, as the reference computes it
    sign_times(x, scratch, v)


#: The numpy steps: ``fn(v, x, scratch, *numbers)`` sets ``v`` to what the math
#: interface's method (:class:`~edm_sym.core.elements.ops.NumpyOps`) computes
#: from ``x`` (which may be ``v``), to the bit: the same C library function on the
#: same numbers, with the guards around it compiled (exact arithmetic).
#: ``scratch`` is a signal-sized work array.
CALLS: dict[str, Callable[..., None]] = {
    "sin": _ufunc(libm.sin), "atan": _ufunc(libm.atan), "tanh": _tanh,
    "asin": _clipped(libm.asin), "acos": _clipped(libm.acos), "tan": _tan,
    "sym_log": _sym_log, "sym_pow": _sym_pow,
}


def _call(name: str, args: tuple, v: np.ndarray, x: np.ndarray, scratch: np.ndarray) -> None:
    fn = CALLS.get(name)
    if fn is None:  # a method without a form here: the math interface's own
        np.copyto(v, getattr(NUMPY, name)(x, *args))
    else:
        fn(v, x, scratch, *args)


# -- batches --------------------------------------------------------------------------

def _schedule(programs: Sequence[Program], row_slots: Sequence[Sequence[int]],
              first: Sequence[int]) -> tuple[list, np.ndarray]:
    """The parts that run ``programs`` together, and their coefficients.

    A part is an array of lines ``[op, row, i1, i2, r1, r2, src]`` (for
    :func:`~edm_sym.engines.kernel.loops.run_lines`) or ``(row, src, method,
    numbers)``, a numpy step of one row. Row r's first line reads ``first[r]``
    (>= 0: a row of the sources; <= -2: the prefix ``inter[-2 - first[r]]``; -1: the
    row itself), the others the row.
    """
    offsets, total = [], 0
    for prog in programs:
        offsets.append(total)
        total += prog.coef.shape[0]
    coef = (programs[0].coef if len(programs) == 1
            else np.concatenate([p.coef for p in programs]))
    # All lines in one flat list (one array at the end); a numpy step cuts it into parts.
    flat: list[float] = []
    steps: list[tuple[int, tuple]] = []  # (lines before it, the step)
    pcs = [0] * len(programs)
    src = list(first)
    active = []
    for r, prog in enumerate(programs):
        if prog.lines:
            active.append(r)
        elif src[r] != -1:  # nothing to compute: the output is the input
            flat.extend((COPY, r, 0, 0, 0.0, 0.0, src[r]))
    while active:
        # Each row as far as it goes (its numpy steps too, while its signal is in the cache).
        waiting: dict[int, list[int]] = {}
        for r in active:
            prog, pc, off, s = programs[r], pcs[r], offsets[r], src[r]
            code = prog.lines
            while pc < len(code):
                op, i1, i2, r1, r2 = code[pc]
                if op == LFILTER and i1 <= 2:
                    waiting.setdefault(i1, []).append(r)
                    break
                if op == CALL:
                    steps.append((len(flat), (r, s, *prog.calls[i1])))
                else:
                    flat.extend((op, r, row_slots[r][i1] if op == STORE else i1, i2 + off,
                                 r1, r2, s))
                s = -1
                pc += 1
            pcs[r], src[r] = pc, s
        # Then the filters they all wait at, together (by order).
        active = []
        for order, rows in sorted(waiting.items()):
            if len(rows) > 1:
                flat.extend((GROUP, 0, len(rows), order, 0.0, 0.0, -1))
            for r in rows:
                flat.extend((LFILTER, r, order, programs[r].lines[pcs[r]][2] + offsets[r],
                             0.0, 0.0, src[r]))
                src[r] = -1
                pcs[r] += 1
            active.extend(rows)
    code = np.array(flat, dtype=np.float64).reshape(-1, 7)
    parts: list = []
    done = 0
    for at, step in steps:
        if at > done:
            parts.append(code[done // 7:at // 7])
            done = at
        parts.append(step)
    if len(flat) > done:
        parts.append(code[done // 7:])
    return parts, coef


def log_bounds(n: int, starts: Sequence[int] = ()) -> np.ndarray:
    """The kernel's ``bounds`` of a signal of ``n`` samples: each log's first sample, then ``n``.

    Parameters
    ----------
    n : int
        The samples of all the logs, laid end to end.
    starts : sequence of int
        Where the logs after the first begin (empty: one log).

    Returns
    -------
    numpy.ndarray
        int64, ``[0, *starts, n]``.

    Raises
    ------
    ValueError
        When ``starts`` are not increasing sample indices inside the signal.
    """
    edges = [0, *(int(k) for k in starts), int(n)]
    if starts and any(b <= a for a, b in zip(edges, edges[1:], strict=False)):
        raise ValueError(f"starts: expected increasing sample indices between 0 and {n} "
                         f"(exclusive), found {list(starts)!r}")
    return np.array(edges, dtype=np.int64)


_NO_INTER = np.empty((0, 1))
_NO_SOURCES = np.empty((1, 1))
_LOCAL = threading.local()


def _scratch(n: int) -> np.ndarray:
    """This thread's work array of ``n`` samples (kept: no allocation per batch)."""
    buf = getattr(_LOCAL, "scratch", None)
    if buf is None or buf.shape[0] != n:
        buf = _LOCAL.scratch = np.empty(n)
    return buf


def _indices(n: int) -> np.ndarray:
    """This thread's int64 work array of ``n`` indices."""
    buf = getattr(_LOCAL, "indices", None)
    if buf is None or buf.shape[0] < n:
        buf = _LOCAL.indices = np.empty(n, dtype=np.int64)
    return buf


def run_rows(programs: Sequence[Program], starts: Sequence[np.ndarray | int], store: np.ndarray,
             dest: np.ndarray, inter: np.ndarray | None = None,
             row_slots: Sequence[Sequence[int]] | None = None,
             scratch: np.ndarray | None = None, sources: np.ndarray | None = None,
             bounds: np.ndarray | None = None) -> None:
    """Run the programs of several rows, each from rest over its whole signal.

    Parameters
    ----------
    programs : sequence of Program
        From :func:`compile_steps`, one per row.
    starts : sequence of numpy.ndarray or int
        Each row's input: a signal of shape (N,) (copied first), or read in
        place by the row's first instruction: ``k >= 0`` the row k of
        ``sources``, ``k < 0`` the row ``-1 - k`` of ``inter`` (a stored
        prefix, which no prefix of this batch may overwrite).
    store : numpy.ndarray
        Shape (S, N): row ``dest[r]`` gets row r's output (distinct rows).
    dest : numpy.ndarray
        int64, shape (len(programs),).
    inter : numpy.ndarray, optional
        Where the stored prefixes go (shape (P, N)): row r's j-th prefix to
        ``inter[row_slots[r][j]]``.
    row_slots : sequence of sequence of int, optional
        Per row, the ``inter`` rows of its prefixes (needed when a program stores).
    scratch : numpy.ndarray, optional
        Shape (N,) work array of the numpy steps (default: this thread's own).
    sources : numpy.ndarray, optional
        Shape (K, N) float64, C-contiguous: the signals integer starts name
        (neither ``store`` nor ``inter`` may share their memory).
    bounds : numpy.ndarray, optional
        Several logs laid end to end (:func:`log_bounds`): every state starts
        from rest at each log's first sample. Default: one log.
    """
    if not programs:
        return
    first = []
    for r, x in enumerate(starts):
        if isinstance(x, np.ndarray):
            np.copyto(store[dest[r]], x)
            first.append(-1)
        else:
            first.append(int(x) if x >= 0 else int(x) - 1)  # -1 - k: inter row k -> -2 - k
    if row_slots is None:
        row_slots = [()] * len(programs)
    if inter is None:
        inter = _NO_INTER
    if sources is None:
        sources = _NO_SOURCES
    if bounds is None:
        bounds = log_bounds(store.shape[1])
    parts, coef = _schedule(programs, row_slots, first)
    if len(parts) == 1 and isinstance(parts[0], np.ndarray):
        run_lines(parts[0], coef, store, dest, inter, sources, bounds)
        return
    if scratch is None:
        scratch = _scratch(store.shape[1])
    with np.errstate(all="ignore"):
        for part in parts:
            if isinstance(part, np.ndarray):
                run_lines(part, coef, store, dest, inter, sources, bounds)
            else:
                r, i, name, args = part
                v = store[dest[r]]
                x = sources[i] if i >= 0 else (inter[-2 - i] if i <= -2 else v)
                _call(name, args, v, x, scratch)


_ONE = np.zeros(1, dtype=np.int64)


def run_program(program: Program, x: np.ndarray, out: np.ndarray | None = None,
                inter: np.ndarray | None = None, slots: np.ndarray | None = None,
                scratch: np.ndarray | None = None, starts: Sequence[int] = ()) -> np.ndarray:
    """Run a row's program over the signal ``x`` (shape (N,)), from rest.

    Parameters
    ----------
    program : Program
        From :func:`compile_row`.
    x : numpy.ndarray
        The row's input (float64, contiguous).
    out : numpy.ndarray, optional
        Where the row's output goes (shape (N,)); a new array when None.
    inter : numpy.ndarray, optional
        Where the stored prefixes go: row ``slots[j]`` gets the j-th (a new
        array of ``program.stores`` rows when None).
    slots : numpy.ndarray, optional
        int64; default ``0 .. stores - 1``.
    scratch : numpy.ndarray, optional
        Shape (N,) work array of the numpy steps.
    starts : sequence of int
        Where further logs begin in ``x`` (each from rest); empty: one log.

    Returns
    -------
    numpy.ndarray
        ``out``.
    """
    if out is None:
        out = np.empty(x.shape[0])
    if inter is None:
        inter = np.empty((program.stores, x.shape[0]))
    if slots is None:
        slots = np.arange(program.stores, dtype=np.int64)
    run_rows([program], [x], out.reshape(1, -1), _ONE, inter, [slots], scratch,
             bounds=log_bounds(x.shape[0], starts))
    return out


_ENCODERS: dict[tuple[type, float], Any] = {}


def _encoder(element: type, ts: float, a: float | None) -> Any:
    """The element's gene encoder at ``ts`` (made once, ``a`` its probe)."""
    key = (element, ts)
    hit = _ENCODERS.get(key)
    if hit is None:
        if len(_ENCODERS) > 1000:
            _ENCODERS.clear()
        hit = _ENCODERS[key] = gene_encoder(element, ts, a)
    return hit


def simulate_rows(comp: Any, rows: Sequence[Any], inputs: np.ndarray,
                  out: np.ndarray | None = None, starts: Sequence[int] = ()) -> np.ndarray:
    """:func:`edm_sym.engines.simulate.simulate_rows` with the row kernel, rows run together.

    Parameters
    ----------
    comp : Compensator
        Gives the sample time and parameter ranges.
    rows : sequence of Row
        Rows to simulate; ``row.input`` indexes the first axis of ``inputs``.
    inputs : numpy.ndarray
        Shape (n_inputs, N).
    out : numpy.ndarray, optional
        Shape (len(rows), N), where the outputs go (a new array when None).
    starts : sequence of int
        Where further logs begin (each from rest, as the reference's ``starts``).

    Returns
    -------
    numpy.ndarray
        Shape (len(rows), N), equal to the reference simulator's to rounding.
    """
    x = np.ascontiguousarray(inputs, dtype=float)
    if out is None:
        out = np.empty((len(rows), x.shape[-1]))
    ts = comp.sample_time
    programs = []
    for row in rows:
        steps = []
        for g in row.genes:
            a = comp.value(g)
            steps.append(_encoder(g.element, ts, a)(a))
        programs.append(compile_steps(steps)[0])
    run_rows(programs, [int(row.input) for row in rows], out,
             np.arange(len(rows), dtype=np.int64), sources=x, bounds=log_bounds(x.shape[-1], starts))
    return out
