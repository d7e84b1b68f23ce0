"""The bit-exact model of the generated integer C.

:func:`run_fixed` computes, with plain integers (numpy int64 where whole
signals are processed at once, Python ints in the filters' recursions), what
``<prefix>_step`` computes sample after sample: the same products, the same
rounding (half up, by an arithmetic shift) and the same saturations. The
tests check the C against it integer for integer.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from edm_sym.engines.fixedpoint.design import (
    FilterStage,
    FixedDesign,
    RelayStage,
    RingStage,
    Stage,
    TableStage,
)
from edm_sym.engines.fixedpoint.formats import rshift_round, saturate


def _table(st: TableStage, x: np.ndarray, lo: int, hi: int) -> np.ndarray:
    if st.identity:
        return x
    if st.period is not None:
        x = np.mod(x, st.period)  # the C's x % p, then + p when negative
    xb = np.asarray(st.xb, dtype=np.int64)
    yb = np.asarray(st.yb, dtype=np.int64)
    n = len(xb) - 1
    i = np.clip(np.searchsorted(xb, x, side="right") - 1, 0, max(n - 1, 0))
    slope = np.asarray(st.slope + (0,), dtype=np.int64)[i]
    shift = np.asarray(st.shift + (0,), dtype=np.int64)[i]
    d = (x - xb[i]) * slope
    half = np.where(shift > 0, np.left_shift(np.int64(1), np.maximum(shift - 1, 0)), 0)
    d = np.right_shift(d + half, shift)
    y = saturate(yb[i] + d, lo, hi)
    y = np.where(x <= xb[0], yb[0], y)
    return np.where(x >= xb[-1], yb[-1], y)


def _filter(st: FilterStage, x: np.ndarray, lo: int, hi: int) -> np.ndarray:
    n = st.order
    b, a = st.b_int, st.a_int
    s_acc, s_out = st.facc - st.fwide, st.fwide - st.fout
    h_acc = (1 << (s_acc - 1)) if s_acc > 0 else 0
    h_out = (1 << (s_out - 1)) if s_out > 0 else 0
    wlo, whi = -(1 << 31), (1 << 31) - 1
    xh, wh = [0] * n, [0] * n
    out = np.empty_like(x)
    for k, v in enumerate(x.tolist()):
        acc = b[0] * v
        for j in range(n):
            acc += b[j + 1] * xh[j] - a[j + 1] * wh[j]
        w = (acc + h_acc) >> s_acc if s_acc > 0 else acc
        w = wlo if w < wlo else (whi if w > whi else w)
        y = (w + h_out) >> s_out if s_out > 0 else w
        out[k] = lo if y < lo else (hi if y > hi else y)
        if n:
            xh = [v, *xh[:-1]]
            wh = [w, *wh[:-1]]
    return out


def _ring(st: RingStage, x: np.ndarray, lo: int, hi: int) -> np.ndarray:
    y = np.zeros_like(x)
    if st.samples < len(x):
        y[st.samples:] = x[:len(x) - st.samples]
    return y


def _relay(st: RelayStage, x: np.ndarray, lo: int, hi: int) -> np.ndarray:
    out, held = np.empty_like(x), 0
    for k, v in enumerate(x.tolist()):
        if v >= st.on:
            held = st.one
        elif v <= st.off:
            held = -st.one
        out[k] = held
    return out


_RUN: dict[type, Callable[[Any, np.ndarray, int, int], np.ndarray]] = {
    TableStage: _table, FilterStage: _filter, RingStage: _ring, RelayStage: _relay,
}


def run_stage(st: Stage, x: np.ndarray, lo: int, hi: int) -> np.ndarray:
    """One stage over the integer signal ``x`` (int64), from rest; words in ``[lo, hi]``."""
    return _RUN[type(st)](st, np.asarray(x, dtype=np.int64), lo, hi)


def run_fixed(d: FixedDesign, u: np.ndarray, *, stages: bool = False
              ) -> tuple[np.ndarray, np.ndarray] | tuple[np.ndarray, np.ndarray, list[list[np.ndarray]]]:
    """The integer outputs of ``d`` on integer inputs ``u`` (shape (n_inputs, N)).

    Returns
    -------
    rows : numpy.ndarray
        Shape (n_rows, N): each row's output in the output format ``d.out_frac``.
    total : numpy.ndarray
        Shape (N,): their saturated sum, in the same format.
    outputs : list of list of numpy.ndarray
        With ``stages=True``: each stage's output, row by row (its own format).
    """
    lo, hi = d.word.min_int, d.word.max_int
    u = np.asarray(u, dtype=np.int64)
    rows = np.empty((len(d.rows), u.shape[-1]), dtype=np.int64)
    per: list[list[np.ndarray]] = []
    for k, row in enumerate(d.rows):
        x = u[row.input_index]
        outs = []
        for st in row.stages:
            x = run_stage(st, x, lo, hi)
            outs.append(x)
        per.append(outs)
        rows[k] = saturate(rshift_round(x, row.stages[-1].fout - d.out_frac), lo, hi)
    total = saturate(rows.sum(axis=0), lo, hi)
    return (rows, total, per) if stages else (rows, total)
