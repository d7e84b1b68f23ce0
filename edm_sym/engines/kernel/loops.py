"""The row kernel's compiled loops (numba when installed, else plain Python).

A batch of rows is run as a list of lines ``[op, row, i1, i2, r1, r2, src]``:
instruction ``op`` over the whole signal of row ``row`` (``store[dest[row]]``),
in place (or, for a row's first line, from its input, a row of ``sources``
or a stored prefix: no separate copy), with its integers ``i1``, ``i2`` (a length, an offset into
``coef``, an ``inter`` row) and reals ``r1``, ``r2`` (a constant, limits).
Each instruction is one tight loop over the signal, which a signal of 20 000
samples runs from the L2 cache.

The signal may be several logs laid end to end (``bounds``: the first sample
of each log, then the signal's length): an instruction with state (a filter,
a delay, a relay) starts from rest at each log's first sample, so no state
crosses from one log into the next; within a log its operations are those
of one log alone, in the same order. Static instructions ignore the bounds.

A filter is a recurrence: each sample waits for the previous one (an add, a
multiply and a subtract, about nine cycles), so one row's filter runs at the
latency of that chain, not at the machine's throughput. A ``GROUP`` line runs
the filters (all of order 1, or all of order 2) of the next ``m`` lines, of
other rows, together: four or two rows in one loop over time. Their chains
are independent, so the processor overlaps them, as it overlaps the rows of a
compensator in the generated C. Each row's operations and their order stay
those of its own filter, so a row's numbers do not depend on its group.

The numpy steps' guards (:func:`clip`, :func:`tan_guard`, :func:`quotient`,
:func:`sign_times`, :func:`saturated`) are compiled here too: exact
arithmetic only, so they give numpy's bits; the transcendental functions
themselves are the C library's (:mod:`edm_sym.core.elements.libm`). The
limits and signs are selects, not branches: a data-dependent branch
mispredicts on a noisy signal.
"""

from __future__ import annotations

import math
from typing import Any

try:  # pragma: no cover (depends on the installation)
    import numba

    NUMBA = True
except ImportError:  # pragma: no cover
    numba = None
    NUMBA = False

import numpy as np

__all__ = ["NUMBA", "clip", "dot_product", "quotient", "run_lines", "saturated", "scatter", "score_rows",
           "sign_times", "tan_guard"]


def _jit(fn: Any) -> Any:
    if NUMBA:
        return numba.njit(cache=True, nogil=True)(fn)
    return fn


# Opcodes of the compiled instructions.
NEG, ADD, MUL, CONST, SIGN, SAT, LOWER, DEAD_ZONE = 0, 1, 2, 3, 4, 5, 6, 7
LFILTER, FIR, DELAY, RELAY, STORE = 8, 9, 10, 11, 12
#: A numpy step (never compiled: the batch runs it between compiled parts).
CALL = 13
#: The row's input, unchanged (a row whose elements change nothing).
COPY = 15
#: Header of ``i1`` LFILTER lines of order ``i2`` (1 or 2) of distinct rows that follow, run
#: together.
GROUP = 14


@_jit
def _lfilter1(v, x, b0, b1, a1, bounds):  # noqa: ANN001, ANN202
    # Direct form II transposed, operation for operation as lfilter runs it, each log
    # from rest.
    for j in range(bounds.shape[0] - 1):
        z = 0.0
        for k in range(bounds[j], bounds[j + 1]):
            u = x[k]
            y = z + b0 * u
            z = u * b1 - y * a1
            v[k] = y


@_jit
def _lfilter2(v, x, c, coef, bounds):  # noqa: ANN001, ANN202
    # Second order (the notch), as the general loop of _apply with the state in registers.
    b0, b1, b2, a1, a2 = coef[c], coef[c + 1], coef[c + 2], coef[c + 3], coef[c + 4]
    for j in range(bounds.shape[0] - 1):
        z0 = z1 = 0.0
        for k in range(bounds[j], bounds[j + 1]):
            u = x[k]
            y = z0 + b0 * u
            z0 = z1 + u * b1 - y * a1
            z1 = u * b2 - y * a2
            v[k] = y


@_jit
def _lfilter2_x2(v0, v1, x0, x1, c0, c1, coef, bounds):  # noqa: ANN001, ANN202
    b00, b10, b20, a10, a20 = coef[c0], coef[c0 + 1], coef[c0 + 2], coef[c0 + 3], coef[c0 + 4]
    b01, b11, b21, a11, a21 = coef[c1], coef[c1 + 1], coef[c1 + 2], coef[c1 + 3], coef[c1 + 4]
    for j in range(bounds.shape[0] - 1):
        z00 = z10 = z01 = z11 = 0.0
        for k in range(bounds[j], bounds[j + 1]):
            u = x0[k]
            y = z00 + b00 * u
            z00 = z10 + u * b10 - y * a10
            z10 = u * b20 - y * a20
            v0[k] = y
            u = x1[k]
            y = z01 + b01 * u
            z01 = z11 + u * b11 - y * a11
            z11 = u * b21 - y * a21
            v1[k] = y


@_jit
def _lfilter1_x2(v0, v1, x0, x1, c0, c1, coef, bounds):  # noqa: ANN001, ANN202
    b00, b10, a10 = coef[c0], coef[c0 + 1], coef[c0 + 2]
    b01, b11, a11 = coef[c1], coef[c1 + 1], coef[c1 + 2]
    for j in range(bounds.shape[0] - 1):
        z0 = z1 = 0.0
        for k in range(bounds[j], bounds[j + 1]):
            u = x0[k]
            y = z0 + b00 * u
            z0 = u * b10 - y * a10
            v0[k] = y
            u = x1[k]
            y = z1 + b01 * u
            z1 = u * b11 - y * a11
            v1[k] = y


@_jit
def _lfilter1_x4(v0, v1, v2, v3, x0, x1, x2, x3, c0, c1, c2, c3, coef,  # noqa: ANN001, ANN202
                 bounds):
    b00, b10, a10 = coef[c0], coef[c0 + 1], coef[c0 + 2]
    b01, b11, a11 = coef[c1], coef[c1 + 1], coef[c1 + 2]
    b02, b12, a12 = coef[c2], coef[c2 + 1], coef[c2 + 2]
    b03, b13, a13 = coef[c3], coef[c3 + 1], coef[c3 + 2]
    for j in range(bounds.shape[0] - 1):
        z0 = z1 = z2 = z3 = 0.0
        for k in range(bounds[j], bounds[j + 1]):
            u = x0[k]
            y = z0 + b00 * u
            z0 = u * b10 - y * a10
            v0[k] = y
            u = x1[k]
            y = z1 + b01 * u
            z1 = u * b11 - y * a11
            v1[k] = y
            u = x2[k]
            y = z2 + b02 * u
            z2 = u * b12 - y * a12
            v2[k] = y
            u = x3[k]
            y = z3 + b03 * u
            z3 = u * b13 - y * a13
            v3[k] = y


@_jit
def _row(code, s, store, dest):  # noqa: ANN001, ANN202
    return store[dest[int(code[s, 1])]]


@_jit
def _input(code, s, store, dest, sources, inter):  # noqa: ANN001, ANN202
    # A line reads its row in place, or (a row's first line) its input: a row of
    # ``sources`` (src >= 0) or a stored prefix, ``inter[-2 - src]`` (src <= -2).
    i = int(code[s, 6])
    if i >= 0:
        return sources[i]
    return inter[-2 - i] if i <= -2 else store[dest[int(code[s, 1])]]


@_jit
def _group(code, s, m, order, coef, store, dest, sources, inter, bounds):  # noqa: ANN001, ANN202
    # The filters of order 1 or 2 of lines s .. s + m - 1 (distinct rows), several at a time.
    j = 0
    if order == 2:
        while j + 2 <= m:
            a, b = s + j, s + j + 1
            _lfilter2_x2(_row(code, a, store, dest), _row(code, b, store, dest),
                         _input(code, a, store, dest, sources, inter),
                         _input(code, b, store, dest, sources, inter),
                         int(code[a, 3]), int(code[b, 3]), coef, bounds)
            j += 2
        if j < m:
            a = s + j
            _lfilter2(_row(code, a, store, dest), _input(code, a, store, dest, sources, inter),
                      int(code[a, 3]), coef, bounds)
        return
    while j + 4 <= m:
        a, b, c, d = s + j, s + j + 1, s + j + 2, s + j + 3
        _lfilter1_x4(_row(code, a, store, dest), _row(code, b, store, dest),
                     _row(code, c, store, dest), _row(code, d, store, dest),
                     _input(code, a, store, dest, sources, inter),
                     _input(code, b, store, dest, sources, inter),
                     _input(code, c, store, dest, sources, inter),
                     _input(code, d, store, dest, sources, inter),
                     int(code[a, 3]), int(code[b, 3]), int(code[c, 3]), int(code[d, 3]), coef,
                     bounds)
        j += 4
    if j + 2 <= m:
        a, b = s + j, s + j + 1
        _lfilter1_x2(_row(code, a, store, dest), _row(code, b, store, dest),
                     _input(code, a, store, dest, sources, inter),
                     _input(code, b, store, dest, sources, inter),
                     int(code[a, 3]), int(code[b, 3]), coef, bounds)
        j += 2
    if j < m:
        a = s + j
        c = int(code[a, 3])
        _lfilter1(_row(code, a, store, dest), _input(code, a, store, dest, sources, inter),
                  coef[c], coef[c + 1], coef[c + 2], bounds)


@_jit
def _apply(op, i1, i2, r1, r2, coef, v, x, inter, bounds):  # noqa: ANN001, ANN202, C901, PLR0912
    # One instruction over the whole signal: v from x (x is v: in place); an instruction
    # with state starts from rest at each log's first sample (bounds).
    N = v.shape[0]  # noqa: N806
    if op == MUL:
        for k in range(N):
            v[k] = r1 * x[k]
    elif op == ADD:
        for k in range(N):
            v[k] = x[k] + r1
    elif op == NEG:
        for k in range(N):
            v[k] = -x[k]
    elif op == CONST:
        for k in range(N):
            v[k] = r1
    elif op == COPY:
        for k in range(N):
            v[k] = x[k]
    elif op == LFILTER:
        n, c = i1, i2
        if n == 1:
            _lfilter1(v, x, coef[c], coef[c + 1], coef[c + 2], bounds)
            return
        if n == 2:
            _lfilter2(v, x, c, coef, bounds)
            return
        z = np.zeros(n)
        for j in range(bounds.shape[0] - 1):
            z[:] = 0.0
            for k in range(bounds[j], bounds[j + 1]):
                u = x[k]
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
            for j in range(bounds.shape[0] - 1):
                zf = 0.0
                for k in range(bounds[j], bounds[j + 1]):
                    u = x[k]
                    v[k] = zf + b0 * u
                    zf = u * b1
            return
        zs = np.zeros(n)
        for j in range(bounds.shape[0] - 1):
            zs[:] = 0.0
            for k in range(bounds[j], bounds[j + 1]):
                u = x[k]
                y = zs[0] + coef[c] * u
                for i in range(n - 1):
                    zs[i] = zs[i + 1] + u * coef[c + 1 + i]
                zs[n - 1] = u * coef[c + n]
                v[k] = y
    elif op == DELAY:
        n = i1
        for j in range(bounds.shape[0] - 1):
            a, b = bounds[j], bounds[j + 1]
            # Backwards: in place, each input is read before it is overwritten; a log reads
            # only its own samples, so the logs may go in any order.
            if n < b - a:
                for k in range(b - 1, a + n - 1, -1):
                    v[k] = x[k - n]
            for k in range(a, min(a + n, b)):
                v[k] = 0.0
    elif op == RELAY:
        for j in range(bounds.shape[0] - 1):
            h = 0.0
            for k in range(bounds[j], bounds[j + 1]):
                u = x[k]
                h = 1.0 if u >= r1 else (-1.0 if u <= -r1 else h)
                v[k] = h
    elif op == STORE:
        dst = inter[i1]
        for k in range(N):
            dst[k] = x[k]
    elif op == SIGN:
        # numpy's sign: +0 for either zero, NaN stays NaN.
        for k in range(N):
            u = x[k]
            v[k] = 1.0 if u > 0.0 else (-1.0 if u < 0.0 else (0.0 if u == 0.0 else u))
    elif op == SAT:
        # np.clip and np.maximum: NaN stays NaN (no comparison holds).
        for k in range(N):
            u = x[k]
            v[k] = r1 if u < r1 else (r2 if u > r2 else u)
    elif op == LOWER:
        for k in range(N):
            u = x[k]
            v[k] = r1 if u < r1 else u
    elif op == DEAD_ZONE:
        for k in range(N):
            u = x[k]
            v[k] = u - r1 if u > r1 else (u + r1 if u < -r1 else 0.0)  # NaN: 0, as np.where


@_jit
def run_lines(code, coef, store, dest, inter, sources, bounds):  # noqa: ANN001, ANN201
    """Run lines ``[op, row, i1, i2, r1, r2, src]`` on the rows ``store[dest[row]]``, in order.

    A line reads its row in place (``src == -1``), or (a row's first line) its
    input: ``sources[src]`` when ``src >= 0``, the stored prefix
    ``inter[-2 - src]`` when ``src <= -2``. STORE copies its row into ``inter[i1]``;
    a GROUP line runs the filters of the ``i1`` lines that follow (all of
    order ``i2``) together. ``bounds`` (int64): each log's first sample, then
    the signal's length; ``[0, N]`` for one log.
    """
    s = 0
    while s < code.shape[0]:
        op = int(code[s, 0])
        if op == GROUP:
            m = int(code[s, 2])
            _group(code, s + 1, m, int(code[s, 3]), coef, store, dest, sources, inter, bounds)
            s += 1 + m
            continue
        _apply(op, int(code[s, 2]), int(code[s, 3]), code[s, 4], code[s, 5], coef,
               _row(code, s, store, dest), _input(code, s, store, dest, sources, inter), inter,
               bounds)
        s += 1


@_jit
def tan_guard(t, x, v, limit):  # noqa: ANN001, ANN201
    """``v = t`` (``t = tan x``) limited: where ``|t| >= limit``, ``limit`` with the sign of sin x.

    There ``|cos x| <= 1 / limit``, so ``|sin x|`` is 1 to rounding and any
    sine gives the same sign as numpy's. NaN stays NaN. ``x`` may be ``v``.
    """
    for k in range(v.shape[0]):
        u = t[k]
        if abs(u) >= limit:
            u = -limit if math.sin(x[k]) < 0.0 else limit
        v[k] = u


@_jit
def saturated(x, v, limit, rest, where):  # noqa: ANN001, ANN201
    """Where ``|x| >= limit``, ``v = sign(x)``; the other samples (NaN too) packed.

    ``rest[:m]`` gets those samples and ``where[:m]`` their indices; returns m.
    """
    m = 0
    for k in range(x.shape[0]):
        u = x[k]
        if abs(u) >= limit:
            v[k] = 1.0 if u > 0.0 else -1.0
        else:
            rest[m] = u
            where[m] = k
            m += 1
    return m


@_jit
def scatter(v, rest, where, m):  # noqa: ANN001, ANN201
    """``v[where[i]] = rest[i]`` for ``i < m``."""
    for i in range(m):
        v[where[i]] = rest[i]


@_jit
def clip(x, v, lo, hi):  # noqa: ANN001, ANN201
    """``v = clip(x, lo, hi)`` as np.clip computes it (NaN stays NaN); ``x`` may be ``v``."""
    for k in range(v.shape[0]):
        u = x[k]
        v[k] = lo if u < lo else (hi if u > hi else u)


@_jit
def quotient(x, q, a, limit):  # noqa: ANN001, ANN201
    """``q = minimum(|x| / a, limit)`` as numpy computes it (NaN stays NaN)."""
    for k in range(x.shape[0]):
        r = abs(x[k]) / a
        q[k] = limit if r > limit else r


@_jit
def sign_times(x, q, v):  # noqa: ANN001, ANN201
    """``v = sign(x) * q`` with numpy's sign (+0 for either zero, NaN for NaN); ``x`` may be ``v``."""
    for k in range(v.shape[0]):
        u = x[k]
        s = 1.0 if u > 0.0 else (-1.0 if u < 0.0 else (0.0 if u == 0.0 else u))
        v[k] = s * q[k]


@_jit
def score_rows(store, slots, y, w, e):  # noqa: ANN001, ANN201
    """The weighted sum of squares of ``e = y - sum(store[slots])`` (``e``: scratch)."""
    for k in range(e.shape[0]):
        e[k] = y[k]
    for i in range(slots.shape[0]):
        r = store[slots[i]]
        for k in range(e.shape[0]):
            e[k] -= r[k]
    return dot_product(e, e, w)  # sum(w e^2) in dot_product's fixed order


@_jit
def dot_product(a, b, w):  # noqa: ANN001, ANN201
    """``sum(w a b)`` (``w`` of shape (N,), or (1,) for a constant) in a fixed order."""
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
