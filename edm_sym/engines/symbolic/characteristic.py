"""Static characteristics of row terms: the numbers behind the robust classifications.

The exact patterns of :mod:`edm_sym.engines.symbolic.classify` read a term's structure.
Rows found by the genetic algorithm often nest their dynamics inside nonlinear
functions (``sin(LTI(sin(q + c), G))``, ``SymPow(LTI(alpha, s/(s + a)), p)``),
where no exact pattern applies. This module measures such a term numerically:

* :func:`static_form` replaces every operator by a static stand-in: ``LTI(x, G)``
  by a real gain times ``x`` (the caller chooses which gain: the DC gain, or the
  gain at a representative frequency), ``Delay(x, T)`` by ``x`` and
  ``Relay(x, a)`` by ``sign(x)`` (a relay whose input swings beyond its band);
  it also tracks how far the transfer functions move the signal's role along
  angle -> velocity -> acceleration;
* :func:`trig_harmonics` and :func:`fundamental` decide whether a term of the
  unwrapped angle is periodic (every occurrence of the angle inside
  ``sin/cos/tan(k q + c)``) and with which fundamental;
* :func:`periodic_shape`, :func:`harmonic_gcd`, :func:`linear_fit` and
  :func:`passband` measure the evaluated characteristic.

Everything here is numpy on small arrays; no sympy simplification is called.
"""

from __future__ import annotations

import cmath
import math
from collections.abc import Callable
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
import sympy as sp

from edm_sym.engines.symbolic.functions import NUMPY_FUNCTIONS, GTan
from edm_sym.engines.symbolic.operators import LTI, Delay, Relay, s

#: A transfer function as numeric coefficients, descending powers of s.
Coefficients = tuple[np.ndarray, np.ndarray]

#: Harmonic multiplier of each periodic function: ``tan`` repeats every half turn.
_TRIG: dict[type, int] = {sp.sin: 1, sp.cos: 1, sp.tan: 2, GTan: 2}


@lru_cache(maxsize=512)
def tf_coefficients(G: sp.Expr) -> Coefficients | None:  # noqa: N803
    """Numerator and denominator of ``G(s)`` as float arrays; None when not numeric.

    Parameters
    ----------
    G : sympy.Expr
        A rational function of :data:`~edm_sym.engines.symbolic.operators.s` with numbers.

    Returns
    -------
    (numpy.ndarray, numpy.ndarray) or None
        Coefficients in descending powers of s.
    """
    num, den = sp.fraction(sp.together(G))
    try:
        n = np.array([float(c) for c in sp.Poly(num, s).all_coeffs()])
        d = np.array([float(c) for c in sp.Poly(den, s).all_coeffs()])
    except (TypeError, sp.PolynomialError):
        return None
    if not (np.all(np.isfinite(n)) and np.all(np.isfinite(d)) and n.any() and d.any()):
        return None
    return n, d


def s_power(tf: Coefficients) -> int:
    """k in ``G = s^k H`` with ``H(0)`` finite and nonzero (a derivative: 1; an integral: -1)."""
    n, d = tf
    return (len(n) - len(np.trim_zeros(n, "b"))) - (len(d) - len(np.trim_zeros(d, "b")))


def response(tf: Coefficients, w: float | np.ndarray) -> complex | np.ndarray:
    """The frequency response ``G(j w)`` at ``w`` [rad/s] (a number or an array)."""
    jw = 1j * np.asarray(w, dtype=float)
    out = np.polyval(tf[0], jw) / np.polyval(tf[1], jw)
    return complex(out) if np.ndim(out) == 0 else out


def corners(tf: Coefficients) -> tuple[float, ...]:
    """The magnitudes of the poles [rad/s], ascending (0 for an integrator)."""
    return tuple(sorted(float(abs(p)) for p in np.roots(np.trim_zeros(tf[1], "f"))))


@dataclass(frozen=True, eq=False)
class Filter:
    """One ``LTI`` of a term, as :func:`static_form` met it.

    Attributes
    ----------
    tf : (numpy.ndarray, numpy.ndarray)
        Its coefficients.
    k : int
        Its power of s (:func:`s_power`).
    index_in : int
        The role index of its input signal: 0 angle, 1 velocity, 2 acceleration
        (also for a derivative of acceleration: a band-passed acceleration).
    """

    tf: Coefficients
    k: int
    index_in: int

    @property
    def to_acceleration(self) -> int:
        """Its steps along the roles; those beyond acceleration do not count."""
        return min(self.index_in + self.k, 2) - self.index_in

    def relative(self, w: float | np.ndarray) -> complex | np.ndarray:
        """``G(j w) / (j w)^to_acceleration``: its gain and phase relative to acceleration."""
        return response(self.tf, w) / (1j * np.asarray(w, dtype=float)) ** self.to_acceleration


@dataclass(frozen=True, eq=False)
class StaticForm:
    """A term with its operators replaced by static stand-ins.

    Attributes
    ----------
    expr : sympy.Expr
        The static characteristic, a function of the input symbol only.
    index : int
        The role index of the term's signal paths (they all agree).
    filters : tuple of Filter
        The transfer functions met, innermost first.
    delays : tuple of float
        The dead times met [s].
    relays : int
        How many relays became ``sign``.
    """

    expr: sp.Expr
    index: int
    filters: tuple[Filter, ...]
    delays: tuple[float, ...]
    relays: int


class _Refused(Exception):
    """The term has no static form (mixed paths, a gain that is not finite, ...)."""


def static_form(expr: sp.Expr, u: sp.Symbol, index: int,
                gain: Callable[[Filter], float], *, keep_relays: bool = False
                ) -> StaticForm | None:
    """``expr`` with ``LTI(x, G)`` -> ``gain(filter) x``, ``Delay(x, T)`` -> ``x``,
    ``Relay(x, a)`` -> ``sign(x)``.

    Parameters
    ----------
    expr : sympy.Expr
        A numeric term of a row.
    u : sympy.Symbol
        The input symbol.
    index : int
        The input's role index (0 angle, 1 velocity, 2 acceleration).
    gain : callable
        Filter -> a finite real gain, or NaN to refuse the term.
    keep_relays : bool, default False
        Keep ``Relay(x, a)`` (of the static ``x``) instead of ``sign(x)``, for
        a caller that sweeps the input and so sees the hysteresis.

    Returns
    -------
    StaticForm or None
        None when a transfer function is not numeric, a gain is not finite, or
        the input reaches a function along paths of different role indices.
    """
    filters: list[Filter] = []
    delays: list[float] = []
    relays = [0]

    def walk(e: sp.Expr) -> tuple[sp.Expr, int | None]:
        if e == u:
            return e, index
        if not e.has(u):
            return e, None
        if isinstance(e, LTI):
            x, i = walk(e.args[0])
            tf = tf_coefficients(e.args[1])
            if tf is None or i is None:
                raise _Refused
            f = Filter(tf, s_power(tf), i)
            g = gain(f)
            if not math.isfinite(g):
                raise _Refused
            filters.append(f)
            # Beyond acceleration is a band-passed acceleration: still acceleration.
            return g * x, min(i + f.k, 2)
        if isinstance(e, Delay):
            if not e.args[1].is_Number:
                raise _Refused
            delays.append(float(e.args[1]))
            return walk(e.args[0])
        if isinstance(e, Relay):
            relays[0] += 1
            x, i = walk(e.args[0])
            return (Relay(x, e.args[1]) if keep_relays else sp.sign(x)), i
        args, seen = [], set()
        for a in e.args:
            x, i = walk(a)
            args.append(x)
            if i is not None:
                seen.add(i)
        if len(seen) != 1:
            raise _Refused
        return e.func(*args), seen.pop()

    try:
        out, i = walk(expr)
    except _Refused:
        return None
    if i is None:
        return None
    return StaticForm(out, i, tuple(filters), tuple(delays), relays[0])


def evaluate(expr: sp.Expr, u: sp.Symbol, x: np.ndarray) -> np.ndarray | None:
    """The static function ``expr`` of ``u`` at the points ``x``; None unless finite."""
    with np.errstate(all="ignore"):
        try:
            f = sp.lambdify(u, expr, modules=[NUMPY_FUNCTIONS, "numpy"])
            y = np.asarray(f(x), dtype=float) * np.ones_like(x)
        except (TypeError, ValueError, ZeroDivisionError, NameError, AttributeError):
            return None  # a function numpy cannot evaluate: no characteristic
    return y if np.all(np.isfinite(y)) else None


def _delayed_input(e: sp.Expr, u: sp.Symbol) -> bool:
    while isinstance(e, Delay) and e.args[1].is_Number:
        e = e.args[0]
    return e == u


def trig_harmonics(expr: sp.Expr, u: sp.Symbol) -> tuple[float, ...] | None:
    """The harmonic numbers of the angle in ``expr``, or None when it is not periodic.

    Every occurrence of ``u`` must be inside ``sin``, ``cos`` or ``tan`` of
    ``k u + c`` (``u`` possibly delayed); the result holds ``|k|`` for each
    (``2 |k|`` for a tangent, whose period is half a sine's). Anything may
    surround those functions, dynamic operators included.

    Parameters
    ----------
    expr : sympy.Expr
    u : sympy.Symbol

    Returns
    -------
    tuple of float or None
    """
    if not expr.has(u):
        return ()
    mult = next((m for t, m in _TRIG.items() if isinstance(expr, t)), 0)
    if mult:
        c, kw = expr.args[0].as_independent(u, as_Add=True)
        k, rest = kw.as_coeff_Mul()
        if c.is_number and k.is_Number and not k.is_zero and _delayed_input(rest, u):
            return (mult * abs(float(k)),)
    if expr == u:
        return None
    out: list[float] = []
    for a in expr.args:
        h = trig_harmonics(a, u)
        if h is None:
            return None
        out += h
    return tuple(out)


def fundamental(harmonics: tuple[float, ...], tol: float,
                max_denominator: int = 12) -> float | None:
    """The largest ``k0`` of which every harmonic is a whole multiple (within ``tol``).

    Harmonics within ``tol`` of multiples of ``1/q`` (``q <= max_denominator``)
    give ``gcd / q``; ``(1, 4)`` -> 1, ``(2.5,)`` -> 2.5, ``(2, 3.0004)`` -> 1.

    Parameters
    ----------
    harmonics : tuple of float
        Positive harmonic numbers.
    tol : float
        Absolute tolerance on each harmonic number.
    max_denominator : int, default 12

    Returns
    -------
    float or None
        None when there are no harmonics or no common fundamental.
    """
    if not harmonics:
        return None
    for q in range(1, max_denominator + 1):
        m = [round(h * q) for h in harmonics]
        if all(mi > 0 and abs(h * q - mi) <= tol * q for h, mi in zip(harmonics, m, strict=True)):
            return math.gcd(*m) / q
    return None


def flat(y: np.ndarray) -> bool:
    """True when the samples are constant (to rounding), zeros included."""
    return bool(np.ptp(y) <= 1e-12 * np.max(np.abs(y)))


def harmonic_gcd(y: np.ndarray, rel: float = 1e-3) -> int | None:
    """The gcd of the harmonics of ``y`` (one revolution) above ``rel`` of the largest.

    None for a constant ``y``.
    """
    if flat(y):
        return None
    mag = np.abs(np.fft.rfft(y))[1:]
    return math.gcd(*(int(i) + 1 for i in np.nonzero(mag >= rel * mag.max())[0]))


def periodic_shape(y: np.ndarray, harmonic: int) -> tuple[float, float, float]:
    """(half peak-to-peak, amplitude and phase of one harmonic) of samples of one period.

    The phase is in the convention ``A sin(harmonic x + phase)``, ``x`` running
    over the samples' period as ``[0, 2 pi)``.

    Parameters
    ----------
    y : numpy.ndarray
        Samples of one period at the midpoints ``x_n = 2 pi (n + 1/2) / N``
        (:func:`period_grid`), so that no sample sits on a wrap.
    harmonic : int
        The FFT bin (1 for the fundamental of a period).

    Returns
    -------
    (float, float, float)
        Amplitude [unit of y], the harmonic's amplitude, its phase [rad] in (-pi, pi].
    """
    x = np.fft.rfft(y)[harmonic] * cmath.exp(-1j * math.pi * harmonic / y.size)
    phase = cmath.phase(1j * x)
    return float(np.ptp(y) / 2), float(2 * abs(x) / y.size), phase if abs(phase) > 1e-12 else 0.0


def period_grid(period: float, n: int) -> np.ndarray:
    """``n`` midpoints of equal parts of ``[0, period)``."""
    return (np.arange(n) + 0.5) * (period / n)


def linear_fit(x: np.ndarray, y: np.ndarray) -> tuple[float, float, float]:
    """Least-squares ``y = slope x + intercept``: (slope, intercept, R^2; 1 for a constant y)."""
    A = np.column_stack([x, np.ones_like(x)])  # noqa: N806
    (slope, icpt), *_ = np.linalg.lstsq(A, y, rcond=None)
    res = float(np.sum((A @ np.array([slope, icpt]) - y) ** 2))
    tot = float(np.sum((y - y.mean()) ** 2))
    return float(slope), float(icpt), (1.0 - res / tot) if tot > 0 else 1.0


def passband(filters: tuple[Filter, ...],
             w_ref: float) -> tuple[float, float | None, float | None] | None:
    """The -3 dB band of the filters' product, relative to acceleration.

    The response is :meth:`Filter.relative` multiplied over the filters. A band
    needs a response that does not grow without bound at either end.

    Parameters
    ----------
    filters : tuple of Filter
    w_ref : float
        [rad/s] A frequency the grid must cover.

    Returns
    -------
    (float, float or None, float or None) or None
        (the frequency of the peak gain, the lower edge, the upper edge) [rad/s],
        an edge None where the band is open; None without filters, for a
        response that grows without bound, or one flat within 3 dB throughout.
    """
    if not filters:
        return None
    low = sum(f.k - f.to_acceleration for f in filters)
    high = sum(len(np.trim_zeros(f.tf[0], "f")) - len(np.trim_zeros(f.tf[1], "f"))
               - f.to_acceleration for f in filters)
    if low < 0 or high > 0:
        return None
    marks = [w_ref]
    for f in filters:
        marks += [abs(r) for r in np.roots(np.trim_zeros(f.tf[1], "f")) if abs(r) > 0]
        marks += [abs(r) for r in np.roots(np.trim_zeros(f.tf[0], "f")) if abs(r) > 0]
    w = np.logspace(math.log10(min(marks) / 100), math.log10(max(marks) * 100), 400)
    mag = np.abs(np.prod([f.relative(w) for f in filters], axis=0))
    i = int(np.argmax(mag))
    inside = mag >= mag[i] / math.sqrt(2)
    lo = i
    while lo > 0 and inside[lo - 1]:
        lo -= 1
    hi = i
    while hi < w.size - 1 and inside[hi + 1]:
        hi += 1
    if lo == 0 and hi == w.size - 1:
        return None  # flat within 3 dB everywhere: no band to speak of
    return (float(w[i]), None if lo == 0 else float(w[lo]),
            None if hi == w.size - 1 else float(w[hi]))


def describe_operators(form: StaticForm, gains: str) -> tuple[dict[str, tuple[float, str]], str]:
    """The filter corners and delays of a static form as parameters, and a note on them.

    Parameters
    ----------
    form : StaticForm
    gains : str
        Which gains stood in for the filters (for the note).

    Returns
    -------
    (dict of str to (float, str), str)
        ``corner`` (or ``corner_1``, ...) [rad/s] and ``delay`` (or ``delay_1``,
        ...) [s]; the note, starting with ``"; "`` (empty without operators).
    """
    params: dict[str, tuple[float, str]] = {}
    notes = []
    poles: list[float] = []
    for c in sorted(c for f in form.filters for c in corners(f.tf)):
        if not poles or abs(c - poles[-1]) > 1e-9 * c:  # a complex pair is one corner
            poles.append(c)
    for i, c in enumerate(poles, 1):
        params["corner" if len(poles) == 1 else f"corner_{i}"] = (c, "rad/s")
    for i, t in enumerate(form.delays, 1):
        params["delay" if len(form.delays) == 1 else f"delay_{i}"] = (t, "s")
    if form.filters:
        where = ", corners " + ", ".join(f"{c:.4g}" for c in poles) + " rad/s" if poles else ""
        notes.append(f"filtered{where}: the static characteristic takes the {gains}")
    if form.delays:
        notes.append("delayed by " + ", ".join(f"{t:.4g}" for t in form.delays)
                     + " s (ignored in the characteristic)")
    if form.relays:
        notes.append("relay(s) taken as sign")
    return params, ("; " + "; ".join(notes)) if notes else ""


# -- the two measurements the classifier reads ---------------------------------

#: Samples of one period (spatial terms) and of the acceleration range.
PERIOD_SAMPLES = 1024
RANGE_SAMPLES = 401


def dc_gain(f: Filter) -> float:
    """A filter's DC gain; NaN for a derivative or integral (they have no static stand-in)."""
    return float(response(f.tf, 0.0).real) if f.k == 0 else math.nan


def _gain_at(w: float) -> Callable[[Filter], float]:
    def gain(f: Filter) -> float:
        # The magnitude, signed by whether the filter keeps (or inverts) the
        # signal relative to acceleration at w.
        return abs(response(f.tf, w)) * (1.0 if f.relative(w).real >= 0 else -1.0)
    return gain


@dataclass(frozen=True)
class Periodic:
    """A position-dependent term, measured over one period of its static characteristic.

    Attributes
    ----------
    cycles : float
        Cycles per revolution of the fundamental.
    amplitude : float
        Half the peak-to-peak value [N m].
    fundamental_amplitude, phase : float
        The fundamental ``A sin(cycles q + phase)`` [N m], [rad].
    dominant_cycles, dominant_amplitude : float
        The strongest harmonic: cycles per revolution, amplitude [N m].
    jump : float
        The step at each wrap of a wrapped angle [N m] (0 for the unwrapped angle).
    form : StaticForm
    """

    cycles: float
    amplitude: float
    fundamental_amplitude: float
    phase: float
    dominant_cycles: float
    dominant_amplitude: float
    jump: float
    form: StaticForm


def measure_periodic(term: sp.Expr, u: sp.Symbol, wrapped: bool,
                     tol: float) -> Periodic | None:
    """The periodic shape of a term of the angle, with filters at their DC gain.

    ``LTI`` operators count with their DC gain and delays as identity: the
    characteristic of slow motion. A wrapped angle gives a periodic term by
    construction (the fundamental is the gcd of the harmonics present over one
    revolution); the unwrapped angle only through ``sin/cos/tan(k q + c)``
    (:func:`trig_harmonics`, :func:`fundamental`).

    Parameters
    ----------
    term : sympy.Expr
    u : sympy.Symbol
    wrapped : bool
        ``u`` is the wrapped angle.
    tol : float
        Tolerance on the harmonic numbers of the unwrapped angle.

    Returns
    -------
    Periodic or None
        None when the term is not periodic in the angle, a filter differentiates
        or integrates, or the characteristic is constant.
    """
    form = static_form(term, u, 0, dc_gain)
    if form is None:
        return None
    if wrapped:
        ends = 2 * np.pi * np.array([1e-12, 1 - 1e-12])
        y = evaluate(form.expr, u, np.append(period_grid(2 * np.pi, PERIOD_SAMPLES), ends))
        if y is None:
            return None
        y, ends = y[:-2], y[-2:]
        k = harmonic_gcd(y)
        if k is None:
            return None
        k0, first, jump = float(k), k, float(ends[0] - ends[1])
    else:
        harmonics = trig_harmonics(term, u)
        k0 = fundamental(harmonics, tol) if harmonics is not None else None
        if k0 is None:
            return None
        y = evaluate(form.expr, u, period_grid(2 * np.pi / k0, PERIOD_SAMPLES))
        if y is None or flat(y):
            return None
        first, jump, ends = 1, 0.0, np.empty(0)
    amp, a1, ph = periodic_shape(y, first)
    amp = max(amp, float(np.ptp(np.append(y, ends)) / 2))  # the ends of a wrap count too
    mag = np.abs(np.fft.rfft(y))[1:]
    top = int(np.argmax(mag)) + 1
    return Periodic(k0, amp, a1, ph, top * k0 / first, float(2 * mag[top - 1] / y.size),
                    jump if abs(jump) > 1e-6 * amp else 0.0, form)


@dataclass(frozen=True)
class AccelerationFit:
    """A term of acceleration measured by a line fit of its static characteristic.

    Attributes
    ----------
    inertia : float
        The least-squares slope [kg m^2] over the acceleration range.
    r2 : float
        The fit's coefficient of determination (1: linear).
    peak : float
        The largest magnitude of the characteristic over the range [N m].
    phase : float
        The filters' phase relative to acceleration at the frequency [rad].
    band : (float, float or None, float or None) or None
        :func:`passband` of the filters.
    inertia_in_band : float
        The slope with the filters at the band's peak frequency (NaN without a band).
    form : StaticForm
    """

    inertia: float
    r2: float
    peak: float
    phase: float
    band: tuple[float, float | None, float | None] | None
    inertia_in_band: float
    form: StaticForm


def _slope(term: sp.Expr, u: sp.Symbol, index: int, w: float,
           a_range: float) -> tuple[float, float, float, StaticForm] | None:
    form = static_form(term, u, index, _gain_at(w))
    if form is None or form.index < 2:
        return None
    # The input swings as much as an acceleration of a_range at w would make it.
    scale = w ** (2 - index)
    x = np.linspace(-a_range / scale, a_range / scale, RANGE_SAMPLES)
    y = evaluate(form.expr, u, x)
    if y is None or flat(y):
        return None
    slope, _, r2 = linear_fit(x, y)
    return slope / scale, r2, float(np.max(np.abs(y))), form


def acceleration_gain(leaf: sp.Expr, u: sp.Symbol, index: int,
                      w: float) -> tuple[float, float] | None:
    """A linear path from the input to acceleration, taken at ``w``: (gain, phase).

    ``leaf`` is the input through filters and delays only (``c H(s) a``,
    ``s H(s) v``). The gain is per unit acceleration, each filter counted as
    in :func:`measure_acceleration` (its magnitude at ``w``, signed by whether
    it keeps or inverts the signal relative to acceleration there); the phase
    is the filters' shift against acceleration at ``w`` [rad]. None when the
    path does not reach acceleration or is not linear.
    """
    form = static_form(leaf, u, index, _gain_at(w))
    if form is None or form.index < 2:
        return None
    gain = sp.expand(form.expr).coeff(u)
    if not gain.is_Number or sp.expand(form.expr - gain * u) != 0:
        return None
    phase = cmath.phase(complex(np.prod([f.relative(w) for f in form.filters]))) \
        if form.filters else 0.0
    return float(gain) / w ** (2 - index), phase


def measure_acceleration(term: sp.Expr, u: sp.Symbol, index: int, w: float,
                         a_range: float) -> AccelerationFit | None:
    """The equivalent inertia of a term that depends on acceleration (or beyond).

    Each ``LTI`` counts with its gain at ``w``, signed by whether it keeps or
    inverts the signal relative to acceleration there (a derivative of the
    velocity turns it into an acceleration: that step is not an inversion);
    delays count as identity and relays as ``sign``. The input sweeps the
    amplitude an acceleration of ``a_range`` gives at ``w`` (a velocity input
    ``a_range / w``), and the slope of the least-squares line through the
    characteristic, per unit acceleration, is the equivalent inertia.

    Parameters
    ----------
    term : sympy.Expr
    u : sympy.Symbol
    index : int
        The input's role index (0 angle, 1 velocity, 2 acceleration).
    w : float
        [rad/s] The representative frequency.
    a_range : float
        [rad/s^2] The acceleration range.

    Returns
    -------
    AccelerationFit or None
        None unless every path of the input reaches acceleration (or beyond),
        or when the characteristic is constant or not finite.
    """
    hit = _slope(term, u, index, w, a_range)
    if hit is None:
        return None
    inertia, r2, peak, form = hit
    phase = cmath.phase(complex(np.prod([f.relative(w) for f in form.filters]))) \
        if form.filters else 0.0
    band = passband(form.filters, w)
    in_band = math.nan
    if band is not None:
        at_peak = _slope(term, u, index, band[0], a_range)
        in_band = at_peak[0] if at_peak is not None else math.nan
    return AccelerationFit(inertia, r2, peak, phase, band, in_band, form)


@dataclass(frozen=True)
class VelocityFit:
    """A term of velocity measured by the fit ``c sgn(v) + b v + d`` (the paper's eq. 14 form).

    Attributes
    ----------
    coulomb, viscous, offset : float
        c [N m], b [N m s/rad] and d [N m] of the least-squares fit.
    r2 : float
        The fit's coefficient of determination.
    peak : float
        The largest magnitude of the characteristic over the range [N m].
    jump : float
        ``y(v_c) - y(-v_c)`` at the Coulomb threshold velocity ``v_c`` [N m].
    form : StaticForm
    """

    coulomb: float
    viscous: float
    offset: float
    r2: float
    peak: float
    jump: float
    form: StaticForm


def measure_velocity(term: sp.Expr, u: sp.Symbol, v_range: float,
                     v_coulomb: float) -> VelocityFit | None:
    """Fit the static characteristic of a velocity term by ``c sgn(v) + b v + d``.

    Filters count with their DC gain, delays as identity and relays as ``sign``;
    the velocity sweeps +-``v_range``; ``v_coulomb`` is where the jump of a
    Coulomb part is measured.

    Returns
    -------
    VelocityFit or None
        None unless the input stays a velocity along every path (no derivative
        or integral), or when the characteristic is constant or not finite.
    """
    form = static_form(term, u, 1, dc_gain)
    if form is None or form.index != 1:
        return None
    v = np.linspace(-v_range, v_range, RANGE_SAMPLES)
    v = v[v != 0.0]  # sgn(0) is a convention, not a friction value
    y = evaluate(form.expr, u, v)
    if y is None or flat(y):
        return None
    design = np.column_stack([np.sign(v), v, np.ones_like(v)])
    coef, *_ = np.linalg.lstsq(design, y, rcond=None)
    resid = y - design @ coef
    total = float(np.sum((y - y.mean()) ** 2))
    r2 = 1.0 - float(np.sum(resid**2)) / total if total > 0 else 1.0
    edge = evaluate(form.expr, u, np.array([-v_coulomb, v_coulomb]))
    jump = float(edge[1] - edge[0]) if edge is not None else math.nan
    return VelocityFit(float(coef[0]), float(coef[1]), float(coef[2]), r2,
                       float(np.max(np.abs(y))), jump, form)
