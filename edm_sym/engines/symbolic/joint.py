"""Friction judged as a whole: the velocity terms of several rows summed into one characteristic.

The genetic algorithm often writes one friction curve as several rows: a
Coulomb step in one, a gentle saturation that bends it at speed in another,
two large rows that nearly cancel, a relay whose wide hysteresis holds the
breakaway level after each reversal. Named one by one over a fixed velocity
range, such rows give Coulomb and viscous values far from the curve they
make together. :func:`joint_velocity_terms` sums the static characteristics
of every term that acts on velocity (filters with the low-frequency gain of
``G / s^k``, so ``LTI(q, s/(s + a))`` is ``q'/a``; delays as identity) and
judges the sum over the data's velocity range (``ClassifyOptions.velocity_range``):

* the input sweeps up from ``-range`` to ``+range`` (and back), so a relay's
  hysteresis shows as what it does after a reversal;
* its odd part, over ``coulomb_velocity`` to the range, is fitted by
  ``Fc + D v + Fs exp(-(v/v_s)^2)`` (the plant's Stribeck curve; ``v_s`` by a
  search over a log grid, the rest by least squares), and must follow it
  within ``_FIT`` of its peak (RMS): ``Fc`` is the Coulomb level, ``D`` the
  viscous coefficient (each named from ``_NAMED`` of the peak), and ``Fs``,
  when it reaches ``_SIGNIFICANT`` of the peak towards the Coulomb sign, the
  Stribeck part; an ``Fs`` of the other sign is the smoothing of the Coulomb
  step (its ``transition_velocity``: where the curve reaches half the level);
* an even part beyond ``_SIGNIFICANT`` of the peak leaves the terms as they
  were named one by one.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import sympy as sp

from edm_sym.core.terms import TermKind
from edm_sym.engines.symbolic.characteristic import Filter, static_form
from edm_sym.engines.symbolic.classify import ClassifyOptions, PhysicalTerm
from edm_sym.engines.symbolic.functions import NUMPY_FUNCTIONS

#: The kinds a velocity term may have been named by one at a time.
VELOCITY_KINDS = (TermKind.COULOMB, TermKind.VISCOUS, TermKind.STRIBECK, TermKind.UNCLASSIFIED)
#: The role index of each input role (an angle's derivative is a velocity).
_INDEX = {"angle": 0, "velocity": 1, "acceleration": 2}
#: A Stribeck part (or a departure from the sum's odd symmetry) counts when it
#: reaches this share of the summed characteristic's peak.
_SIGNIFICANT = 0.05
#: A Coulomb or viscous part is named when it reaches this share of the peak
#: over the range (the contribution threshold's default).
_NAMED = 0.01
#: The fit must follow the sum within this share of its peak (RMS over the range).
_FIT = 0.05
#: Stribeck velocities tried, as shares of the velocity range (log-spaced).
_VS = np.geomspace(1e-3, 0.5, 60)
#: Points of the sweep on each side of zero.
_SAMPLES = 2000


@dataclass(frozen=True)
class VelocityPart:
    """A term that acts on velocity, ready to be summed.

    Attributes
    ----------
    term : PhysicalTerm
        The term as it was named on its own.
    symbol : sympy.Symbol
        Its row's input.
    expr : sympy.Expr
        Its static characteristic as a function of the velocity (``symbol``
        standing for it), relays kept.
    """

    term: PhysicalTerm
    symbol: sp.Symbol
    expr: sp.Expr


def _low_gain(f: Filter) -> float:
    """``H(0)`` of ``G = s^k H``: the gain of the filter past its derivative or integral."""
    n, d = (np.trim_zeros(c, "b") for c in f.tf)
    return float(n[-1] / d[-1])


def velocity_part(term: PhysicalTerm, u: sp.Symbol, role: str | None) -> VelocityPart | None:
    """``term`` as a static function of velocity, or None when it is not one.

    A term of a velocity, or of an angle through a derivative (an acceleration
    through an integral), whose every path reaches velocity; the wrapped angle
    does not count (its derivative jumps at each wrap).
    """
    if term.kind not in VELOCITY_KINDS or term.expr is None or role not in _INDEX:
        return None
    if not term.expr.has(u):
        return None
    form = static_form(term.expr, u, _INDEX[role], _low_gain, keep_relays=True)
    if form is None or form.index != 1:
        return None
    return VelocityPart(term, u, form.expr)


def _relay_sweep(x: np.ndarray, a: float) -> np.ndarray:
    """A relay along a sweep: +1 once ``x >= a``, -1 once ``x <= -a``, else held (from 0)."""
    x = np.asarray(x, dtype=float)
    out = np.empty_like(x)
    state = 0.0
    for i, xi in enumerate(x.flat):
        if xi >= a:
            state = 1.0
        elif xi <= -a:
            state = -1.0
        out.flat[i] = state
    return out


def _sweep(parts: Sequence[VelocityPart], v: np.ndarray) -> np.ndarray | None:
    """The summed characteristic along the sweep ``v`` (in that order); None unless finite."""
    total = np.zeros_like(v)
    for p in parts:
        f = sp.lambdify(p.symbol, p.expr,
                        modules=[{"Relay": _relay_sweep}, NUMPY_FUNCTIONS, "numpy"])
        with np.errstate(all="ignore"):
            try:
                y = np.asarray(f(v), dtype=float) * np.ones_like(v)
            except (TypeError, ValueError, ZeroDivisionError, NameError, AttributeError):
                return None
        if not np.all(np.isfinite(y)):
            return None
        total += y
    return total


def _fit(v: np.ndarray, y: np.ndarray, v_low: float, scale: float
         ) -> tuple[float, float, float, float] | None:
    """``y ~ Fc + D v + Fs exp(-(v/v_s)^2)`` over ``v >= v_low`` -> (Fc, D, Fs, v_s).

    ``v_s`` by search over :data:`_VS` (above ``v_low``), the rest by least
    squares; ``Fs = 0`` when the Stribeck part stays below ``_SIGNIFICANT`` of
    the peak. None when even the best fit misses the sum by more than ``_FIT`` (RMS).
    """
    keep = v >= v_low
    v, y = v[keep], y[keep]
    if v.size < 10:
        return None
    base = np.column_stack([np.ones_like(v), v])

    def solve(a: np.ndarray) -> tuple[np.ndarray, float]:
        coef, *_ = np.linalg.lstsq(a, y, rcond=None)
        return coef, float(np.sqrt(np.mean((a @ coef - y) ** 2)))

    (fc, d), err = solve(base)
    best = (float(fc), float(d), 0.0, 0.0, err)
    for vs in _VS * v[-1]:
        if vs <= v_low:
            continue
        coef, e = solve(np.column_stack([base, np.exp(-(v / vs) ** 2)]))
        if e < best[4] and abs(coef[2]) >= _SIGNIFICANT * scale:
            best = (float(coef[0]), float(coef[1]), float(coef[2]), float(vs), e)
    if best[4] > _FIT * scale:
        return None
    return best[:4]


def joint_velocity_terms(parts: Sequence[VelocityPart], options: ClassifyOptions,
                         where: str = "") -> tuple[PhysicalTerm, ...] | None:
    """Coulomb, viscous and Stribeck parts of the summed velocity characteristic.

    Parameters
    ----------
    parts : sequence of VelocityPart
        From :func:`velocity_part`.
    options : ClassifyOptions
        ``velocity_range`` (the data's, for a description on a log) and
        ``coulomb_velocity``.
    where : str
        Names the terms summed in the descriptions (``"rows 1, 2 and 4"``).

    Returns
    -------
    tuple of PhysicalTerm or None
        None when the sum is not odd, not ``Fc + D v`` at speed, or not finite:
        the terms keep their names one by one.
    """
    vmax = options.velocity_range
    grid = np.linspace(vmax / _SAMPLES, vmax, _SAMPLES)
    up = _sweep(parts, np.concatenate([-grid[::-1], grid]))
    down = _sweep(parts, np.concatenate([grid[::-1], -grid]))
    if up is None or down is None:
        return None
    pos = up[_SAMPLES:]               # after a reversal from -range
    neg = down[_SAMPLES:]             # after a reversal from +range, at -grid
    y, even = 0.5 * (pos - neg), 0.5 * (pos + neg)
    scale = float(np.max(np.abs(y)))
    if not scale > 0 or float(np.max(np.abs(even))) > _SIGNIFICANT * scale:
        return None
    fit = _fit(grid, y, options.coulomb_velocity, scale)
    if fit is None:
        return None
    fc, d, fs, vs = fit
    U = options.units
    N, V, D = U.force, U.velocity, U.viscous
    how = (f" ({where} together: a fit of Fc sgn(v) + D v + Fs exp(-(v/v_s)^2) to their summed "
           f"velocity characteristic over {options.coulomb_velocity:g} - {vmax:.4g} {V})")
    sign = math.copysign(1.0, fc)
    coulomb: dict[str, tuple[float, str]] = {"level": (float(fc), N)}
    text = f"Coulomb friction: {fc:.6g} {N}"
    if fs * sign < 0:  # below the line at low speed: the Coulomb step is smoothed
        low = np.nonzero(y * sign >= 0.5 * abs(fc))[0]
        vt = float(grid[low[0]]) if low.size else vmax
        if vt > options.coulomb_velocity:
            coulomb["transition_velocity"] = (vt, V)
            text += f", reaching half of it at {vt:.4g} {V}"
    expr = sp.Add(*(p.term.expr for p in parts))
    out = []
    if abs(fc) >= _NAMED * scale:
        out.append(PhysicalTerm(TermKind.COULOMB, coulomb, text + how, expr))
    if abs(d) * vmax >= _NAMED * scale:
        out.append(PhysicalTerm(TermKind.VISCOUS, {"coefficient": (float(d), D)},
                                f"viscous friction: {d:.6g} {D}{how}", expr))
    if fs * sign > 0:
        out.append(PhysicalTerm(
            TermKind.STRIBECK, {"peak": (float(fs), N), "stribeck_velocity": (float(vs), V)},
            f"Stribeck friction: {fs:.4g} {N} above Coulomb + viscous at rest (after a "
            f"reversal), falling as exp(-(v/{vs:.4g} {V})^2){how}", expr))
    return tuple(out) or None
