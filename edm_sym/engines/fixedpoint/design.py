"""The fixed-point design: every signal's Q format and every stage's integer realisation.

:func:`design` runs the reference simulator's realisations over the synthetic
excitation (:mod:`~edm_sym.engines.fixedpoint.excitation`), stage by stage,
and turns each realisation into its integer counterpart, dispatching on the
realisation's type like the printers do:

* ``StaticMap`` -> :class:`TableStage`: a piecewise-linear table over the
  stage's input range, its breakpoints placed by bisection until the
  interpolation meets the word's table tolerance (an identity needs none; a
  function of the sine and cosine of its input is first reduced modulo 2 pi);
  the input is clamped to the table's ends;
* ``LinearFilter`` -> :class:`FilterStage`: direct form I, 32-bit coefficients
  and feedback words, a 64-bit accumulator;
* ``DelayLine`` -> :class:`RingStage`; ``Relay`` -> :class:`RelayStage`.

A signal's format comes from its range: an input's from the range result.json
records (widened by :data:`~edm_sym.engines.fixedpoint.formats.INPUT_HEADROOM`),
an internal signal's from its range on a recorded log (when one is at hand;
else on the excitation) through the reference simulator, widened by
:data:`~edm_sym.engines.fixedpoint.formats.MARGIN`, or from a guaranteed bound
where that is tighter (a table's largest entry, a relay's 1, a filter's input
bound times the l1 norm of its impulse response). Each stage also carries an a
priori bound of its output's deviation from the double simulator, propagated
from the input's (infinite after a relay or a jump).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy import signal

from edm_sym.core.elements.realisation import Realisation, dispatch
from edm_sym.core.errors import EdmError
from edm_sym.engines.fixedpoint.excitation import excitation
from edm_sym.engines.fixedpoint.formats import (
    EXCITATION_SAMPLES,
    INPUT_HEADROOM,
    MARGIN,
    WIDE_BITS,
    Word,
    frac_for,
    to_int,
)

#: Check points per table segment (the interpolation error is measured there).
CHECKS = 15
#: Samples of the impulse response that measure a filter's l1 norm.
IMPULSE_SAMPLES = 1 << 15


class FixedPointError(EdmError, ValueError):
    """A model that a fixed-point word cannot realise to its accuracy (exit 2)."""


@dataclass(frozen=True)
class Stage:
    """What every integer stage records.

    Attributes
    ----------
    row, col : int
        Its place in the matrix (0-based).
    label : str
        ``"gain (a_3 = 0.503)"``.
    fin, fout : int
        Fractional bits of its input and output.
    bound : float
        The bound of its output that chose ``fout``.
    error : float
        A priori bound of its output's deviation from the double simulator (inf: none).
    switches : bool
        The element steps where its input crosses a threshold (the switching rule,
        :mod:`~edm_sym.engines.fixedpoint.switching`).
    """

    row: int
    col: int
    label: str
    fin: int
    fout: int
    bound: float
    error: float
    switches: bool = False

    @property
    def where(self) -> str:
        """``"rows[0].elements[2] (sin_amp (a_3 = 0.61))"``, as refusals name a stage."""
        return f"rows[{self.row}].elements[{self.col}] ({self.label})"


@dataclass(frozen=True)
class TableStage(Stage):
    """A static function as a piecewise-linear table (or an identity when ``identity``).

    ``y = yb[i] + round((x - xb[i]) * slope[i] / 2**shift[i])`` on
    ``xb[i] <= x < xb[i + 1]``; below ``xb[0]`` and above ``xb[-1]`` the ends.
    ``period`` (in input units) reduces the input first, when not None.
    ``accuracy`` is the largest interpolation error at the check points (output units).
    """

    identity: bool = False
    period: int | None = None
    xb: tuple[int, ...] = ()
    yb: tuple[int, ...] = ()
    slope: tuple[int, ...] = ()
    shift: tuple[int, ...] = ()
    accuracy: float = 0.0

    @property
    def segments(self) -> int:
        """Number of segments (0 for an identity)."""
        return max(len(self.xb) - 1, 0)


@dataclass(frozen=True)
class FilterStage(Stage):
    """A linear filter in direct form I with a 64-bit accumulator.

    ``acc = sum B[k] x[n-k] - sum A[k] w[n-k]`` (``A[0]`` unused) in units of
    ``2**-facc``; ``w = sat32(round(acc / 2**(facc - fwide)))`` is the feedback
    word; ``y = sat(round(w / 2**(fwide - fout)))``.
    """

    b_int: tuple[int, ...] = ()
    a_int: tuple[int, ...] = ()
    facc: int = 0
    fwide: int = 0

    @property
    def order(self) -> int:
        """Number of past inputs and outputs kept."""
        return len(self.b_int) - 1


@dataclass(frozen=True)
class RingStage(Stage):
    """A delay of ``samples`` samples (a ring buffer of words; the format passes through)."""

    samples: int = 1


@dataclass(frozen=True)
class RelayStage(Stage):
    """The relay: +one once ``x >= on``, -one once ``x <= off``, else held; starts at 0."""

    on: int = 0
    off: int = 0
    one: int = 1


@dataclass(frozen=True)
class RowDesign:
    """A row: its input's index and its integer stages; its output has ``stages[-1].fout``."""

    index: int
    input_index: int
    stages: tuple[Stage, ...]


@dataclass(frozen=True)
class FixedDesign:
    """A compensator in integers.

    Attributes
    ----------
    word : Word
    inputs : tuple of str
    input_fracs : tuple of int
        Each input's format (an input no row reads gets the format of its range too).
    ranges : mapping of str to (float, float)
        The input ranges the design used (recorded or given).
    rows : tuple of RowDesign
    out_frac : int
        The format of the rows' outputs and of the total.
    sample_time : float
    """

    word: Word
    inputs: tuple[str, ...]
    input_fracs: tuple[int, ...]
    ranges: Mapping[str, tuple[float, float]]
    rows: tuple[RowDesign, ...]
    out_frac: int
    sample_time: float

    @property
    def error(self) -> float:
        """The a priori bound of the total's deviation (inf when a row has none)."""
        return sum(r.stages[-1].error for r in self.rows) + len(self.rows) * 2.0 ** -self.out_frac


def _row_shift_ok(fracs: list[int], out: int) -> None:
    if any(f < out for f in fracs):  # pragma: no cover - out is their minimum
        raise AssertionError("row formats must not be coarser than the output's")


class _Designer:
    """Turns one realisation into its integer stage (``_design_<RealisationType>``)."""

    def __init__(self, word: Word):
        self.word = word

    def stage(self, real: Realisation, **kw: Any) -> Stage:
        return dispatch(self, "_design_", real)(real, **kw)

    # -- static maps -------------------------------------------------------------
    def _design_StaticMap(self, real: Any, *, x: np.ndarray, y: np.ndarray, base: dict,  # noqa: N802
                          bound_in: float, err_in: float) -> Stage:
        w, fin = self.word, base["fin"]
        lo_int, hi_int = w.min_int, w.max_int
        grid = np.unique(np.round(np.linspace(lo_int, hi_int, 4097)).astype(np.int64))
        xr = grid * 2.0 ** -fin
        with np.errstate(all="ignore"):
            if np.array_equal(real.run(xr.copy()), xr):
                return TableStage(**base, fout=fin, bound=bound_in, error=err_in, identity=True)
        period = None
        lo, hi = float(np.min(x)), float(np.max(x))
        c, h = 0.5 * (lo + hi), 0.5 * (hi - lo) * MARGIN + 2.0 ** -fin
        x0 = int(max(lo_int, math.floor((c - h) * 2.0 ** fin)))
        x1 = int(min(hi_int, math.ceil((c + h) * 2.0 ** fin)))
        p = round(2 * math.pi * 2.0 ** fin)
        if real.element.from_sin_cos is not None and x1 - x0 > p and p <= hi_int:
            period, x0, x1 = p, 0, p
        if x1 <= x0:
            x1 = x0 + 1
        return self._table(real, base, x0, x1, period, err_in)

    def _table(self, real: Any, base: dict, x0: int, x1: int, period: int | None,
               err_in: float) -> TableStage:
        w, fin = self.word, base["fin"]
        where = f"rows[{base['row']}].elements[{base['col']}] ({base['label']})"

        def f(xi: np.ndarray) -> np.ndarray:
            with np.errstate(all="ignore"):
                return real.run(np.asarray(xi, dtype=float) * 2.0 ** -fin)

        grid = np.unique(np.round(np.linspace(x0, x1, 8193)).astype(np.int64))
        fg = f(grid)
        if not np.all(np.isfinite(fg)):
            raise FixedPointError(f"{where}: not finite over its input range "
                                  f"{x0 * 2.0 ** -fin:.6g} .. {x1 * 2.0 ** -fin:.6g}")
        bound = float(np.max(np.abs(fg)))
        fout = frac_for(bound, w.bits)
        tol = max(w.table_tolerance * bound, 2.0 ** -fout)

        def q(xi: np.ndarray) -> np.ndarray:
            return to_int(f(xi), fout, w)

        done: list[tuple[int, int]] = []
        worst = 0.0
        pending = np.array([[x0, x1]], dtype=np.int64)
        t = np.arange(1, CHECKS + 1) / (CHECKS + 1)
        while len(pending):
            a, b = pending[:, 0], pending[:, 1]
            pts = np.round(a[:, None] + (b - a)[:, None] * t).astype(np.int64)
            ya, yb = q(a).astype(float), q(b).astype(float)
            interp = ya[:, None] + (yb - ya)[:, None] * (pts - a[:, None]) / (b - a)[:, None]
            err = np.max(np.abs(interp * 2.0 ** -fout - f(pts)), axis=1)
            ok = (err <= tol) | (b - a <= 1)
            worst = max(worst, float(np.max(err[ok & (b - a > 1)], initial=0.0)))
            done += [(int(i), int(j)) for i, j in pending[ok]]
            bad = pending[~ok]
            mid = (bad[:, 0] + bad[:, 1]) // 2
            pending = np.concatenate([np.stack([bad[:, 0], mid], 1), np.stack([mid, bad[:, 1]], 1)])
            if len(done) + len(pending) > w.max_segments:
                raise FixedPointError(
                    f"{where}: a table of {w.max_segments} segments cannot follow it to "
                    f"{w.table_tolerance:g} of its bound {bound:.6g} over its input range "
                    f"{x0 * 2.0 ** -fin:.6g} .. {x1 * 2.0 ** -fin:.6g} in {w.name}; narrow the "
                    "input's range (input_range) or use real=\"float\"")
        xs = np.array(sorted({i for i, _ in done} | {x1}), dtype=np.int64)
        ys = q(xs)
        slope, shift, steep = [], [], 0.0
        for i in range(len(xs) - 1):
            width, dy = int(xs[i + 1] - xs[i]), int(ys[i + 1] - ys[i])
            s, k = _slope(dy, width)
            slope.append(s)
            shift.append(k)
            steep = max(steep, abs(dy) / width * 2.0 ** (fin - fout))
        error = steep * err_in + worst + 2.0 * 2.0 ** -fout
        if base["switches"] and err_in > 0.0:
            error = math.inf  # any rounding of the input can move a step by samples
        bound_out = float(np.max(np.abs(ys))) * 2.0 ** -fout
        return TableStage(**base, fout=fout, bound=bound_out, error=error, period=period,
                          xb=tuple(int(v) for v in xs), yb=tuple(int(v) for v in ys),
                          slope=tuple(slope), shift=tuple(shift), accuracy=worst)

    # -- linear filters ----------------------------------------------------------
    def _design_LinearFilter(self, real: Any, *, x: np.ndarray, y: np.ndarray,  # noqa: N802
                             base: dict, bound_in: float, err_in: float) -> Stage:
        w, fin = self.word, base["fin"]
        where = f"rows[{base['row']}].elements[{base['col']}] ({base['label']})"
        b, a = np.asarray(real.b, dtype=float), np.asarray(real.a, dtype=float)
        n = len(a) - 1
        l1 = _l1(b, a)
        bound = min(float(np.max(np.abs(y))) * MARGIN, l1 * bound_in)
        if not math.isfinite(bound):
            bound = float(np.max(np.abs(y))) * MARGIN
        fout = frac_for(bound, w.bits)
        fwide = fout + w.wide_extra
        # Every product fits 2**62 / (2n + 1), so the sum and its rounding fit int64.
        cap = 2.0 ** (62 - (WIDE_BITS - 1) - math.ceil(math.log2(2 * n + 1)))
        limits = [math.log2(cap / abs(v)) + fin for v in b if v != 0.0]
        limits += [math.log2(cap / abs(v)) + fwide for v in a[1:] if v != 0.0]
        facc = min(math.floor(min(limits)) if limits else fwide + 30, fwide + 62)
        if facc < fwide:
            fwide = facc
            fout = min(fout, fwide)
        b_int = tuple(int(round(v * 2.0 ** (facc - fin))) for v in b)
        a_int = (0,) + tuple(int(round(v * 2.0 ** (facc - fwide))) for v in a[1:])
        bq = np.array(b_int, dtype=float) * 2.0 ** (fin - facc)
        aq = np.concatenate([[1.0], np.array(a_int[1:], dtype=float) * 2.0 ** (fwide - facc)])
        if n and np.max(np.abs(np.roots(aq))) >= 1.0 > np.max(np.abs(np.roots(a))):
            raise FixedPointError(f"{where}: a pole too close to 1 for {WIDE_BITS}-bit "
                                  f"coefficients (it leaves the unit circle once rounded); "
                                  'use real="float" or real="double"')
        hq = _impulse(bq, aq)
        coef = float(np.sum(np.abs(_impulse(b, a) - hq))) * bound_in
        noise = _l1(np.array([1.0]), aq) * 0.5 * 2.0 ** -fwide + 0.5 * 2.0 ** -fout
        error = float(np.sum(np.abs(hq))) * err_in + coef + noise
        if not math.isfinite(l1):
            error = math.inf  # an integrator accumulates every rounding
        return FilterStage(**base, fout=fout, bound=bound, error=error, b_int=b_int, a_int=a_int,
                           facc=facc, fwide=fwide)

    # -- delays and relays -------------------------------------------------------
    def _design_DelayLine(self, real: Any, *, base: dict, bound_in: float, err_in: float,  # noqa: N802
                          **_: Any) -> Stage:
        return RingStage(**base, fout=base["fin"], bound=bound_in, error=err_in,
                         samples=int(real.samples))

    def _design_Relay(self, real: Any, *, base: dict, err_in: float, **_: Any) -> Stage:  # noqa: N802
        w, fin = self.word, base["fin"]
        a = float(real.threshold)
        on = int(min(max(math.ceil(a * 2.0 ** fin), w.min_int + 1), w.max_int))
        off = int(max(min(math.floor(-a * 2.0 ** fin), w.max_int - 1), w.min_int))
        return RelayStage(**base, fout=w.bits - 2, bound=1.0,
                          error=0.0 if err_in == 0.0 else math.inf,
                          on=on, off=off, one=1 << (w.bits - 2))


def _slope(dy: int, width: int) -> tuple[int, int]:
    """The slope ``dy / width`` as (mantissa, shift): the most precise that keeps the products in int64."""
    if dy == 0 or width <= 1:
        return 0, 0
    r = dy / width
    k = min(62, max(0, math.floor(math.log2((2 ** 31 - 1) / abs(r)))))
    while k > 0 and (abs(round(r * 2 ** k)) > 2 ** 31 - 1
                     or (width - 1) * abs(round(r * 2 ** k)) >= 2 ** 61):
        k -= 1
    return int(round(r * 2 ** k)), k


def _impulse(b: np.ndarray, a: np.ndarray) -> np.ndarray:
    x = np.zeros(IMPULSE_SAMPLES)
    x[0] = 1.0
    with np.errstate(all="ignore"):
        return signal.lfilter(b, a, x)


def _l1(b: np.ndarray, a: np.ndarray) -> float:
    """The l1 norm of the impulse response (inf when it has not decayed in IMPULSE_SAMPLES)."""
    h = _impulse(b, a)
    peak = float(np.max(np.abs(h)))
    if not np.all(np.isfinite(h)) or float(np.max(np.abs(h[-IMPULSE_SAMPLES // 8:]))) > 1e-9 * peak:
        return math.inf
    return float(np.sum(np.abs(h)))


def input_ranges(inputs: tuple[str, ...], used: set[str], recorded: Mapping[str, tuple[float, float]],
                 given: Mapping[str, tuple[float, float]] | None) -> dict[str, tuple[float, float]]:
    """The input ranges a design uses: ``given`` over ``recorded``; refuses a read input without one."""
    given = dict(given or {})
    unknown = sorted(set(given) - set(inputs))
    if unknown:
        raise FixedPointError(f"input_range: {unknown[0]!r} is no input of the model "
                              f"(inputs: {', '.join(inputs)})")
    out = {}
    for name in inputs:
        rng = given.get(name, recorded.get(name))
        if rng is None:
            if name in used:
                raise FixedPointError(f"inputs: {name}: no range recorded in the result; give one "
                                      f'with input_range={{"{name}": (LO, HI)}}')
            continue
        lo, hi = float(rng[0]), float(rng[1])
        if not (math.isfinite(lo) and math.isfinite(hi) and lo <= hi):
            raise FixedPointError(f"inputs: {name}: expected a finite range LO <= HI, found {lo} .. {hi}")
        out[name] = (lo, hi)
    return out


def design(comp: Any, word: Word, ranges: Mapping[str, tuple[float, float]], *,
           labels: Mapping[tuple[int, int], str] | None = None,
           samples: int = EXCITATION_SAMPLES, signals: np.ndarray | None = None) -> FixedDesign:
    """The integer realisation of ``comp`` in ``word``, its formats sized on a log or the excitation.

    Parameters
    ----------
    comp : Compensator
        The decoded matrix (``result.compensator``).
    word : Word
        ``WORDS["q31"]`` or ``WORDS["q15"]``.
    ranges : mapping of str to (float, float)
        Every read input's range (:func:`input_ranges`).
    labels : mapping of (row, col) to str, optional
        Stage labels for messages and comments (default: element names).
    samples : int
        Length of the excitation.
    signals : numpy.ndarray, optional
        Real inputs, shape (n_inputs, N), a recorded log's: the internal
        signals are sized on them instead of on the excitation.

    Raises
    ------
    FixedPointError
        Naming the row and element a word cannot realise.
    """
    ts = comp.sample_time
    inputs = tuple(comp.matrix.inputs)
    if signals is None:
        x_all = excitation(inputs, ranges, ts, samples)
    else:
        x_all = np.asarray(signals, dtype=float)
        samples = x_all.shape[-1]
    fracs = []
    for name in inputs:
        lo, hi = ranges.get(name, (0.0, 0.0))
        fracs.append(frac_for(max(abs(lo), abs(hi)) * INPUT_HEADROOM, word.bits))
    designer = _Designer(word)
    rows, total = [], np.zeros(samples)
    for r, row in enumerate(comp.matrix.rows):
        fin = fracs[row.input]
        bound_in = max(abs(v) for v in ranges[inputs[row.input]]) * INPUT_HEADROOM
        err_in = 0.5 * 2.0 ** -fin
        x = x_all[row.input].copy()
        stages = []
        for c, gene in enumerate(row.genes):
            real = gene.element.realise(comp.value(gene), ts)
            y = real.run(x.copy())
            label = (labels or {}).get((r, c), gene.element.name)
            base = {"row": r, "col": c, "label": label, "fin": fin,
                    "switches": gene.element.switches}
            st = designer.stage(real, x=x, y=y, base=base, bound_in=bound_in, err_in=err_in)
            stages.append(st)
            x, fin, bound_in, err_in = y, st.fout, st.bound, st.error
        rows.append(RowDesign(r, row.input, tuple(stages)))
        total += x
    row_fracs = [rw.stages[-1].fout for rw in rows]
    out = min(min(row_fracs), frac_for(float(np.max(np.abs(total))) * MARGIN, word.bits))
    _row_shift_ok(row_fracs, out)
    return FixedDesign(word, inputs, tuple(fracs), dict(ranges), tuple(rows), out, ts)
