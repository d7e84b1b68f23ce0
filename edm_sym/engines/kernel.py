"""The row kernel: a row compiled to a few instructions, run by numba.

The reference simulator (:mod:`edm_sym.engines.simulate`) runs one numpy or
scipy call per element over the whole signal. The genetic algorithm simulates
hundreds of thousands of rows, and there the temporaries, the calls and the
passes over memory cost several times what the generated C needs. This module
compiles a row's realisations into one program of instructions and runs the
whole row in one compiled call, each instruction one tight loop over the
signal, in place:

* a :class:`~edm_sym.core.elements.realisation.StaticMap` becomes the
  instructions its element's ``f`` performs, found by calling ``f`` on a
  tracer (:class:`TraceOps`, a third implementation of the math interface of
  :mod:`edm_sym.core.elements.ops`), so elements are still defined once;
* a :class:`LinearFilter`, :class:`DelayLine` or :class:`Relay` becomes one
  instruction with its coefficients, length or threshold.

Each consumer dispatches on the realisation's type (``_encode_<Type>``). The
instructions compute what the realisations' numpy steps compute, in the same
order (direct form II transposed as ``scipy.signal.lfilter`` runs it, numpy's
NaN rules for limits and signs), so the kernel agrees with the reference
simulator to rounding (tested to 1e-12; numpy's own ``tanh`` differs from the
C library's by an ulp, the rest is bit for bit on the machines tried).

numba is optional (``pip install edm_sym[fast]``). Without it :data:`NUMBA` is
False and the genetic algorithm runs the reference realisations instead; the
kernel functions then are plain Python (slow, but the same code, which the
tests run on short signals). The compiled code is cached on disk
(``cache=True``): the first import on a machine compiles it once (about
:data:`COMPILE_SECONDS_HINT` s), later processes load it.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from edm_sym.core.elements.ops import NUMPY
from edm_sym.core.elements.realisation import (
    DelayLine,
    LinearFilter,
    Realisation,
    Relay,
    StaticMap,
    dispatch,
)

try:  # pragma: no cover (depends on the installation)
    import numba

    NUMBA = True
except ImportError:  # pragma: no cover
    numba = None
    NUMBA = False

__all__ = ["NUMBA", "Program", "TraceOps", "compile_row", "compile_steps", "dot", "encode",
           "gene_encoder", "run_program", "score", "simulate_rows"]

#: CPU seconds the first compilation took on the development machine (docs only).
COMPILE_SECONDS_HINT = 6


def _jit(fn: Any) -> Any:
    if NUMBA:
        return numba.njit(cache=True, nogil=True)(fn)
    return fn


# Opcodes of the compiled instructions.
NEG, ADD, MUL, CONST, SIGN, SAT, LOWER, DEAD_ZONE = 0, 1, 2, 3, 4, 5, 6, 7
LFILTER, FIR, DELAY, RELAY, STORE = 8, 9, 10, 11, 12

#: Methods of the math interface the kernel compiles (exact arithmetic, limits,
#: signs). The others (sin, tan, log ...) run as numpy's own implementation
#: (:data:`edm_sym.core.elements.ops.NUMPY`) on the whole signal, so their
#: bits are numpy's, as in the reference simulator.
COMPILED = {"neg": NEG, "add": ADD, "mul": MUL, "const": CONST, "sign": SIGN, "sat": SAT,
            "lower_limit": LOWER, "dead_zone": DEAD_ZONE}


class _Signal:
    """A traced signal: the steps (math-interface method, numbers) applied so far."""

    __slots__ = ("steps",)

    def __init__(self, steps: tuple = ()):
        self.steps = steps

    def then(self, name: str, *args: Any) -> _Signal:
        return _Signal((*self.steps, (name, tuple(_number(c) for c in args))))

    def __neg__(self) -> _Signal:
        return self.then("neg")

    def __add__(self, c: float) -> _Signal:
        return self.then("add", c)

    __radd__ = __add__

    def __sub__(self, c: float) -> _Signal:
        return self.then("add", -_number(c))  # x - c is x + (-c) to the bit

    def __mul__(self, c: float) -> _Signal:
        return self.then("mul", c)

    __rmul__ = __mul__


class _Param:
    """The parameter ``a`` times a number, while a static element's template is traced."""

    __slots__ = ("k",)

    def __init__(self, k: float = 1.0):
        self.k = k

    def __neg__(self) -> _Param:
        return _Param(-self.k)

    def __mul__(self, c: Any) -> Any:
        if isinstance(c, int | float) and not isinstance(c, bool):
            return _Param(self.k * c)
        return NotImplemented

    __rmul__ = __mul__

    def __float__(self) -> float:
        raise TypeError("the template needs a's value")


def _number(c: Any) -> float | _Param:
    if isinstance(c, _Param):
        return c
    if isinstance(c, _Signal) or not isinstance(c, int | float | np.floating | np.integer):
        raise TypeError(f"the kernel traces functions of one signal and numbers, found {c!r}")
    return float(c)


def _traced(name: str) -> Any:
    def method(x: _Signal, *args: float) -> _Signal:
        if not isinstance(x, _Signal):
            raise TypeError(f"the kernel traces functions of one signal, found {name}({x!r})")
        return x.then(name, *args)

    method.__name__ = name
    return staticmethod(method)


class TraceOps:
    """The math interface (:mod:`edm_sym.core.elements.ops`) recording the steps.

    A static element's ``f(TRACE, x, a)`` with ``x`` a traced signal returns
    the signal with the steps ``f`` applies, each a method of the interface
    and its numbers.
    """

    pi = math.pi


for _name in ("sin", "atan", "tanh", "sign", "sat", "lower_limit", "dead_zone", "sym_log",
              "sym_pow", "tan", "asin", "acos"):
    setattr(TraceOps, _name, _traced(_name))

TRACE = TraceOps()


@dataclass(frozen=True)
class Program:
    """A row's program: compiled segments and numpy steps, in order, and coefficients.

    ``parts`` holds compiled segments (float64 arrays of shape (S, 5), one
    instruction ``[opcode, i1, i2, r1, r2]`` a line) and ``(method, numbers)``
    pairs of the math interface run by numpy; ``stores`` is the number of
    STORE instructions (rows of the ``inter`` array that :func:`run_program`
    fills).
    """

    parts: tuple
    coef: np.ndarray
    stores: int


class _Encoder:
    """The steps of one realisation, by its type: compiled ``(op, i1, r1, r2, coef)``
    tuples and numpy ``(name, args)`` pairs."""

    def __init__(self) -> None:
        self.items: list[tuple] = []

    def _encode_StaticMap(self, r: StaticMap) -> None:  # noqa: N802
        template = _template(r.element)
        if template is not None and r.a is not None:
            a = float(r.a)
            self.items.extend(_instance(template, a))
            return
        y = r.element.f(TRACE, _Signal(), r.a)
        self.items.extend(_items(y))

    def _encode_LinearFilter(self, r: LinearFilter) -> None:  # noqa: N802
        self.items.extend(_linear_items(r.b, r.a))

    def _encode_DelayLine(self, r: DelayLine) -> None:  # noqa: N802
        self.items.append((DELAY, r.samples, 0.0, 0.0, ()))

    def _encode_Relay(self, r: Relay) -> None:  # noqa: N802
        self.items.append((RELAY, 0, r.threshold, 0.0, ()))


def _items(y: Any) -> list[tuple]:
    """The steps of a traced output as encoder items."""
    if not isinstance(y, _Signal):  # a constant output
        return [(CONST, 0, _number(y), 0.0, ())]
    out = []
    for name, args in y.steps:
        op = COMPILED.get(name)
        if op is None:
            out.append((name, args))
        else:
            out.append((op, 0, args[0] if args else 0.0, args[1] if len(args) > 1 else 0.0, ()))
    return out


_TEMPLATES: dict[type, list | None] = {}


def _template(element: type) -> list | None:
    """A static element traced once with a symbolic ``a`` (None: trace each value instead)."""
    if element not in _TEMPLATES:
        try:
            items = _items(element.f(TRACE, _Signal(), _Param()))
        except TypeError:
            items = None
        _TEMPLATES[element] = items
    return _TEMPLATES[element]


def _value(v: Any, a: float) -> Any:
    if isinstance(v, _Param):
        return a if v.k == 1.0 else (-a if v.k == -1.0 else v.k * a)
    return v


def _instance(template: list, a: float) -> list[tuple]:
    out = []
    for item in template:
        if len(item) == 2:
            out.append((item[0], tuple(_value(v, a) for v in item[1])))
        else:
            op, i1, r1, r2, c = item
            out.append((op, i1, _value(r1, a), _value(r2, a), c))
    return out


def _linear_items(r_b: Sequence[float], r_a: Sequence[float]) -> tuple:
    # A pure FIR (a derivative) as the reference runs it: without the a terms.
    op = LFILTER if any(r_a[1:]) else FIR
    return ((op, len(r_a) - 1, 0.0, 0.0, (*r_b, *r_a[1:])),)


def gene_encoder(element: type, ts: float, probe: float | None) -> Any:
    """A function ``a -> steps`` of one element class (what :func:`encode` gives, faster).

    The class's realisation type, found once with the parameter ``probe``,
    picks the way: a static map instantiates its traced template, a linear
    filter discretises the transfer function straight into its coefficients
    (skipping the realisation object), anything else encodes the realisation.
    """
    kind = type(element.realise(probe, ts))
    if kind is StaticMap:
        template = _template(element)
        if template is not None and probe is not None:
            return lambda a: tuple(_instance(template, float(a)))
    if kind is LinearFilter:
        def linear(a: float) -> tuple:
            b, den = element.coefficients(a, ts)
            return _linear_items(b.tolist(), den.tolist())

        return linear
    return lambda a: encode(element.realise(a, ts))


def encode(stage: Realisation) -> tuple:
    """The steps of one stage (a realisation), for :func:`compile_steps`; () changes nothing.

    Raises
    ------
    TypeError
        When a static element's function is not one of a signal and numbers.
    """
    enc = _Encoder()
    dispatch(enc, "_encode_", stage)(stage)
    return tuple(enc.items)


def compile_steps(stages: Sequence[tuple], *, store: bool = False
                  ) -> tuple[Program, list[int]]:
    """A row's program from its stages' steps (:func:`encode`).

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
    parts: list = []
    lines: list[tuple] = []
    coef: list[float] = []
    stored: list[int] = []
    last = len(stages) - 1
    for i, steps in enumerate(stages):
        for step in steps:
            if len(step) == 2:  # a numpy step
                if lines:
                    parts.append(np.array(lines, dtype=np.float64))
                    lines = []
                parts.append(step)
                continue
            op, i1, r1, r2, c = step
            lines.append((op, i1, len(coef), r1, r2))
            coef.extend(c)
        if steps and store and i < last:
            lines.append((STORE, len(stored), 0, 0.0, 0.0))
            stored.append(i + 1)
    if lines:
        parts.append(np.array(lines, dtype=np.float64))
    return Program(tuple(parts), np.array(coef or [0.0], dtype=np.float64), len(stored)), stored


def compile_row(stages: Sequence[Realisation], *, store: bool = False
                ) -> tuple[Program, list[int]]:
    """A row's program from its realisations (see :func:`compile_steps`)."""
    return compile_steps([encode(r) for r in stages], store=store)


@_jit
def _run(code, coef, v, inter, slots):  # noqa: ANN001, ANN202, C901
    # One instruction at a time over the whole signal, in place: each inner loop
    # is tight, and a signal of 20 000 samples stays in the L2 cache.
    N = v.shape[0]  # noqa: N806
    for s in range(code.shape[0]):
        op = int(code[s, 0])
        i1, i2, r1, r2 = int(code[s, 1]), int(code[s, 2]), code[s, 3], code[s, 4]
        if op == MUL:
            c = r1
            for k in range(N):
                v[k] = c * v[k]
        elif op == ADD:
            c = r1
            for k in range(N):
                v[k] = v[k] + c
        elif op == NEG:
            for k in range(N):
                v[k] = -v[k]
        elif op == CONST:
            c = r1
            for k in range(N):
                v[k] = c
        elif op == LFILTER:
            # Direct form II transposed, operation for operation as lfilter runs it.
            n, c = i1, i2
            if n == 1:
                b0, b1, a1 = coef[c], coef[c + 1], coef[c + 2]
                z = 0.0
                for k in range(N):
                    u = v[k]
                    y = z + b0 * u
                    z = u * b1 - y * a1
                    v[k] = y
            else:
                z = np.zeros(n)
                for k in range(N):
                    u = v[k]
                    y = z[0] + coef[c] * u
                    for i in range(n - 1):
                        z[i] = z[i + 1] + u * coef[c + 1 + i] - y * coef[c + n + 1 + i]
                    z[n - 1] = u * coef[c + n] - y * coef[c + 2 * n]
                    v[k] = y
        elif op == FIR:
            # A pure FIR (the derivative) as the reference computes it: no a terms.
            n, c = i1, i2
            if n == 1:
                b0, b1 = coef[c], coef[c + 1]
                z = 0.0
                for k in range(N):
                    u = v[k]
                    v[k] = z + b0 * u
                    z = u * b1
                continue
            z = np.zeros(n)
            for k in range(N):
                u = v[k]
                y = z[0] + coef[c] * u
                for i in range(n - 1):
                    z[i] = z[i + 1] + u * coef[c + 1 + i]
                z[n - 1] = u * coef[c + n]
                v[k] = y
        elif op == DELAY:
            n = i1
            if n < N:
                for k in range(N - 1, n - 1, -1):
                    v[k] = v[k - n]
            for k in range(min(n, N)):
                v[k] = 0.0
        elif op == RELAY:
            a = r1
            h = 0.0
            for k in range(N):
                u = v[k]
                if u >= a:
                    h = 1.0
                elif u <= -a:
                    h = -1.0
                v[k] = h
        elif op == STORE:
            row = slots[i1]
            for k in range(N):
                inter[row, k] = v[k]
        elif op == SIGN:
            # numpy's sign: 0 stays 0, NaN stays NaN.
            for k in range(N):
                u = v[k]
                if u > 0.0:
                    v[k] = 1.0
                elif u < 0.0:
                    v[k] = -1.0
        elif op == SAT:
            # np.clip and np.maximum: NaN stays NaN (no comparison holds).
            lo, hi = r1, r2
            for k in range(N):
                u = v[k]
                if u < lo:
                    v[k] = lo
                elif u > hi:
                    v[k] = hi
        elif op == LOWER:
            lo = r1
            for k in range(N):
                if v[k] < lo:
                    v[k] = lo
        elif op == DEAD_ZONE:
            a = r1
            for k in range(N):
                u = v[k]
                if u > a:
                    v[k] = u - a
                elif u < -a:
                    v[k] = u + a
                else:
                    v[k] = 0.0  # NaN too, as np.where gives


def run_program(program: Program, x: np.ndarray, out: np.ndarray | None = None,
                inter: np.ndarray | None = None, slots: np.ndarray | None = None) -> np.ndarray:
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
    np.copyto(out, x)
    if len(program.parts) == 1 and isinstance(program.parts[0], np.ndarray):
        _run(program.parts[0], program.coef, out, inter, slots)
        return out
    with np.errstate(all="ignore"):
        for part in program.parts:
            if isinstance(part, np.ndarray):
                _run(part, program.coef, out, inter, slots)
            else:
                name, args = part
                np.copyto(out, getattr(NUMPY, name)(out, *args))
    return out


def simulate_rows(comp: Any, rows: Sequence[Any], inputs: np.ndarray) -> np.ndarray:
    """:func:`edm_sym.engines.simulate.simulate_rows` with the row kernel (no caching).

    Parameters
    ----------
    comp : Compensator
        Gives the sample time and parameter ranges.
    rows : sequence of Row
        Rows to simulate; ``row.input`` indexes the first axis of ``inputs``.
    inputs : numpy.ndarray
        Shape (n_inputs, N).

    Returns
    -------
    numpy.ndarray
        Shape (len(rows), N), equal to the reference simulator's to rounding.
    """
    x = np.ascontiguousarray(inputs, dtype=float)
    out = np.empty((len(rows), x.shape[-1]))
    no_store = np.empty((0, x.shape[-1]))
    ts = comp.sample_time
    for k, row in enumerate(rows):
        steps = [encode(g.element.realise(comp.value(g), ts)) for g in row.genes]
        program, _ = compile_steps(steps)
        run_program(program, x[row.input], out[k], no_store, _NO_SLOTS)
    return out


_NO_SLOTS = np.zeros(0, dtype=np.int64)


@_jit
def _sum_sq(e, w):  # noqa: ANN001, ANN202
    # sum(w e^2) with four running sums (a fixed order: the same bits every time).
    n = e.shape[0]
    uniform = w.shape[0] == 1
    a0 = a1 = a2 = a3 = 0.0
    k = 0
    while k + 4 <= n:
        if uniform:
            a0 += e[k] * e[k]
            a1 += e[k + 1] * e[k + 1]
            a2 += e[k + 2] * e[k + 2]
            a3 += e[k + 3] * e[k + 3]
        else:
            a0 += w[k] * e[k] * e[k]
            a1 += w[k + 1] * e[k + 1] * e[k + 1]
            a2 += w[k + 2] * e[k + 2] * e[k + 2]
            a3 += w[k + 3] * e[k + 3] * e[k + 3]
        k += 4
    while k < n:
        a0 += (1.0 if uniform else w[k]) * e[k] * e[k]
        k += 1
    acc = (a0 + a1) + (a2 + a3)
    return acc * w[0] if uniform else acc


@_jit
def _score(store, slots, y, w, e):  # noqa: ANN001, ANN202
    # The weighted sum of squares of e = y - sum(rows): one pass per row (e: scratch).
    for k in range(e.shape[0]):
        e[k] = y[k]
    for i in range(slots.shape[0]):
        r = store[slots[i]]
        for k in range(e.shape[0]):
            e[k] -= r[k]
    return _sum_sq(e, w)


@_jit
def _dot(a, b, w):  # noqa: ANN001, ANN202
    n = a.shape[0]
    uniform = w.shape[0] == 1
    a0 = a1 = a2 = a3 = 0.0
    k = 0
    while k + 4 <= n:
        if uniform:
            a0 += a[k] * b[k]
            a1 += a[k + 1] * b[k + 1]
            a2 += a[k + 2] * b[k + 2]
            a3 += a[k + 3] * b[k + 3]
        else:
            a0 += w[k] * a[k] * b[k]
            a1 += w[k + 1] * a[k + 1] * b[k + 1]
            a2 += w[k + 2] * a[k + 2] * b[k + 2]
            a3 += w[k + 3] * a[k + 3] * b[k + 3]
        k += 4
    while k < n:
        a0 += (1.0 if uniform else w[k]) * a[k] * b[k]
        k += 1
    acc = (a0 + a1) + (a2 + a3)
    return acc * w[0] if uniform else acc


def score(store: np.ndarray, slots: np.ndarray, target: np.ndarray, weights: np.ndarray,
          scratch: np.ndarray | None = None) -> float:
    """Eq. 8 of the individual whose rows are ``store[slots]``.

    Parameters
    ----------
    store : numpy.ndarray
        Shape (S, N) row outputs.
    slots : numpy.ndarray
        int64, the individual's m rows in ``store``.
    target : numpy.ndarray
        Shape (N,).
    weights : numpy.ndarray
        Shape (N,) Lambda, or (1,) for a constant one.
    scratch : numpy.ndarray, optional
        Shape (N,): room for the residual (reused: no allocation per call).

    Returns
    -------
    float
        ``sqrt(sum(Lambda e^2) / N)`` with ``e = target - sum(rows)``, inf when not finite.
    """
    if NUMBA:
        e = scratch if scratch is not None else np.empty(target.shape[0])
        acc = _score(store, slots, target, weights, e)
    else:  # numpy: einsum's own loops, not BLAS (the same bits whatever the threads)
        e = target - store[slots].sum(axis=0)
        with np.errstate(over="ignore", invalid="ignore"):
            acc = float(np.einsum("i,i", e, e) * weights[0] if weights.shape[0] == 1
                        else np.einsum("i,i,i", weights, e, e))
    f = math.sqrt(acc / target.shape[0]) if acc >= 0.0 else math.nan
    return f if math.isfinite(f) else math.inf


def dot(a: np.ndarray, b: np.ndarray, weights: np.ndarray) -> float:
    """``sum(Lambda a b)`` (weights of shape (N,) or (1,))."""
    if NUMBA:
        return float(_dot(a, b, weights))
    with np.errstate(over="ignore", invalid="ignore"):
        return float(np.einsum("i,i", a, b) * weights[0] if weights.shape[0] == 1
                     else np.einsum("i,i,i", weights, a, b))
