"""Position ripple judged as a whole: the angle terms of several rows summed over one revolution.

The genetic algorithm often writes one ripple as several rows: a 3-cycle
cam as ``sin(2.5 sin q)`` on the unwrapped angle minus ``sin q_w`` on the
wrapped one (the fundamental of the first cancelled by the second), or two
functions of the wrapped angle whose jumps at each wrap cancel. Named one by
one, such rows give a 1-cycle ripple, or two ``unclassified`` sawtooths of
the wrap. :func:`joint_spatial_term` sums the static characteristics of
their terms (filters at their DC gain, delays as identity, as
:func:`edm_sym.engines.symbolic.characteristic.measure_periodic` reads one
term) over one revolution and names the sum:

* a term of the unwrapped angle counts only when it repeats every
  revolution (``f(q + 2 pi) = f(q)``): anything else is not a ripple of the
  position, and the terms keep their names one by one;
* the sum must be periodic: its jump at the wrap (the wrapped-angle terms'
  jumps, summed) below ``_SIGNIFICANT`` of its amplitude;
* it is one ``spatial`` term: amplitude (half peak-to-peak), fundamental
  (the gcd of the harmonics present), the strongest harmonic and its
  amplitude, and the sum's mean over a revolution (``mean``: a constant the
  rows carry together, not position-dependent, so it is said, not named).


:func:`edm_sym.engines.symbolic.significance.judge_rows` uses it only where
the one-by-one names disagree with the sum (:func:`overlapping`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import sympy as sp

from edm_sym.core.terms import TermKind
from edm_sym.engines.symbolic.characteristic import (
    PERIOD_SAMPLES,
    dc_gain,
    evaluate,
    flat,
    harmonic_gcd,
    period_grid,
    periodic_shape,
    static_form,
)
from edm_sym.engines.symbolic.classify import ClassifyOptions, PhysicalTerm, spatial_frequency

#: The kinds an angle term may have been named by one at a time.
SPATIAL_KINDS = (TermKind.SPATIAL, TermKind.UNCLASSIFIED)
#: A wrap jump or mean of the sum counts when it reaches this share of its amplitude;
#: so does a harmonic of one term, against that term's strongest.
_SIGNIFICANT = 0.05
_TWO_PI = 2 * math.pi


@dataclass(frozen=True)
class SpatialPart:
    """An angle term over one revolution ``[0, 2 pi)``.

    Attributes
    ----------
    term : PhysicalTerm
        The term as it was named on its own.
    values : numpy.ndarray
        Its static characteristic at :func:`period_grid`'s midpoints.
    jump : float
        ``f(0+) - f(2 pi -)``: its step at each wrap (0 for the unwrapped angle).
    """

    term: PhysicalTerm
    values: np.ndarray
    jump: float

    def harmonics(self) -> set[int]:
        """The harmonics of one revolution that reach ``_SIGNIFICANT`` of its strongest."""
        mag = np.abs(np.fft.rfft(self.values))[1:]
        if not mag.max() > 0:
            return set()
        return {int(i) + 1 for i in np.nonzero(mag >= _SIGNIFICANT * mag.max())[0]}


def spatial_part(term: PhysicalTerm, u: sp.Symbol, role: str | None) -> SpatialPart | None:
    """``term`` over one revolution, or None when it is not a static function of the angle.

    A term of the wrapped angle (``role == "angle_wrapped"``), or of the
    unwrapped one (``"angle"``) that repeats every revolution, through no
    derivative or integral.
    """
    if term.kind not in SPATIAL_KINDS or term.expr is None or not term.expr.has(u):
        return None
    if role not in ("angle", "angle_wrapped"):
        return None
    form = static_form(term.expr, u, 0, dc_gain)
    if form is None or form.index != 0:
        return None
    x = period_grid(_TWO_PI, PERIOD_SAMPLES)
    n = x.size
    if role == "angle_wrapped":
        y = evaluate(form.expr, u, np.append(x, _TWO_PI * np.array([1e-12, 1 - 1e-12])))
        if y is None:
            return None
        jump = float(y[n] - y[n + 1])
        # Rounding at the ends is no jump (as measure_periodic reads one term).
        return SpatialPart(term, y[:n], jump if abs(jump) > 1e-6 * float(np.ptp(y)) else 0.0)
    y = evaluate(form.expr, u, np.concatenate([x, x + _TWO_PI]))
    if y is None or not np.allclose(y[:n], y[n:], rtol=1e-9,
                                    atol=1e-9 * max(1.0, float(np.max(np.abs(y))))):
        return None
    return SpatialPart(term, y[:n], 0.0)


def overlapping(parts: Sequence[SpatialPart]) -> bool:
    """True when the one-by-one names cannot stand: a term unclassified or jumping at
    the wrap, or two terms sharing a harmonic (one ripple written as several rows)."""
    if any(p.term.kind is not TermKind.SPATIAL or p.jump for p in parts):
        return True
    seen: set[int] = set()
    for p in parts:
        h = p.harmonics()
        if h & seen:
            return True
        seen |= h
    return False


def joint_spatial_term(parts: Sequence[SpatialPart], options: ClassifyOptions,
                       where: str = "") -> PhysicalTerm | None:
    """The ripple the angle terms make together, as one ``spatial`` term.

    Parameters
    ----------
    parts : sequence of SpatialPart
        From :func:`spatial_part`.
    options : ClassifyOptions
        Its ``units`` (rotary: cycles per revolution; linear: per metre).
    where : str
        Names the rows summed in the description (``"rows 3 and 5"``).

    Returns
    -------
    PhysicalTerm or None
        None when the sum is constant or jumps at the wrap.
    """
    y = np.sum([p.values for p in parts], axis=0)
    jump = sum(p.jump for p in parts)
    if flat(y):
        return None
    amp = float(np.ptp(y) / 2)
    if abs(jump) >= _SIGNIFICANT * amp:
        return None
    k = harmonic_gcd(y)
    if k is None:
        return None
    _, a1, phase = periodic_shape(y, k)
    mag = np.abs(np.fft.rfft(y))[1:]
    top = int(np.argmax(mag)) + 1
    U = options.units
    F = U.force
    key, cycles, per = spatial_frequency(float(k), U)
    dominant = spatial_frequency(float(top), U)[1]
    params = {"amplitude": (amp, F), "period": (_TWO_PI / k, U.position), key: cycles,
              "phase": (phase, "rad"), "fundamental_amplitude": (a1, F),
              "dominant_cycles": dominant,
              "dominant_amplitude": (float(2 * mag[top - 1] / y.size), F),
              "mean": (float(y.mean()), F)}
    text = (f"position-dependent friction, periodic ({where} together: the sum of their static "
            f"characteristics over one revolution): amplitude {amp:.6g} {F} (half peak-to-peak), "
            f"{cycles[0]:.6g} {per}, strongest harmonic {dominant[0]:.6g} {per} "
            f"({params['dominant_amplitude'][0]:.4g} {F}); mean over a revolution "
            f"{params['mean'][0]:.4g} {F}")
    expr = sp.Add(*(p.term.expr for p in parts))
    return PhysicalTerm(TermKind.SPATIAL, params, text, expr)
