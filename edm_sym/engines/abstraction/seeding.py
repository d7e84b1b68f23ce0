"""Seeds: new rows drawn from the residual's strongest angle harmonics and Stribeck humps.

A ripple over the angle (cogging, a gear's mesh, a periodic load) needs a row
``A sin(k theta + phi)``: a gain of k on the angle, a sine with its phase and
an amplitude, three genes that must all be right before the row helps. A GA
that draws rows at random meets that rarely (docs/benchmarks.md#bench_namingpy:
the plants' ripple was missing from most models). So when a step adds rows to
the model it inherits, a few of the inherited individuals get, as their first
new row, a harmonic of the inherited model's residual over the angle:

1. the inherited model is simulated on the training samples (held-out blocks
   weigh nothing, as in the fitness);
2. the residual is fitted by weighted least squares on ``cos k theta`` and
   ``sin k theta`` for ``k = 1 .. MAX_ORDER`` and a constant, and on the same
   columns through a low-pass of scanned corner: a ripple at many cycles a
   revolution and a high speed reaches the target through the observer's lag;
3. the ``ga.harmonic_seeds`` orders of largest amplitude each give one
   individual the row ``theta -> gain(k) -> sin_phase(phi) -> gain(A)``, with
   ``lpf(c)`` before the last gain when the lagged fit is the better one.

The GA decides the rest: a seed that does not lower the fitness is outranked
and bred out like any other row, and pruning removes a row the held-out blocks
do not need. Seeds are drawn on a rotary axis with an angle input only (a
wrapped angle preferred; ``sin`` makes the unwrapped one alike). They take no
random numbers, so a run stays a function of its seed.

**Stribeck seeds** do the same for the hump of friction at low speed,
``dF exp(-(v/v_s)^2) sign(v)``, which a random row meets as rarely (the
family's misses were mostly the Stribeck peak, docs/benchmarks.md#bench_namingpy).
No element chain is that law, but two rows make a close one:
``dF sign(v) (1 - tanh(|v| / a))`` is a Coulomb row with its level raised by
``dF`` and the row ``v -> tanh(1/a) -> gain(-dF)``. The residual is fitted on
``1``, ``sign v``, ``v`` and ``tanh(v / a)`` over a grid of ``a``
(:func:`residual_stribeck`); the ``ga.stribeck_seeds`` best ``a`` each give one
inherited individual the ``tanh`` row, and the gain fit, which sets every
row's scale by least squares, raises its Coulomb row.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import NamedTuple

import numpy as np
from scipy.optimize import minimize_scalar
from scipy.signal import lfilter

from edm_sym.core.elements import BY_NAME, ParamRange
from edm_sym.engines.simulate import segments

__all__ = ["LAG_CORNERS", "LAG_GAIN", "MAX_ORDER", "STRIBECK_GRID", "Harmonic", "angle_input",
           "harmonic_rows", "residual_harmonics", "residual_stribeck", "stribeck_rows",
           "stribeck_slopes", "velocity_input"]

#: Highest harmonic order looked for (cycles per revolution).
MAX_ORDER = 10
#: Low-pass corners tried by :func:`residual_harmonics` (log-spaced over the ``lpf`` range).
LAG_CORNERS = 16
#: A lagged harmonic fit is kept when it leaves at least this share less of the residual
#: than the plain one (a 7-cycle ripple through a 250 rad/s observer: 65-80 % less; the
#: residual of a plant without ripple: 1-2 % less, spuriously).
LAG_GAIN = 0.2
#: Stribeck velocities tried by :func:`residual_stribeck`.
STRIBECK_GRID = 24
#: The most samples the seeds' least squares fit (:func:`fitted_samples`): on a
#: 320 000-sample log the whole-log fits took 0.3 GB and 20 s at every step.
SEED_SAMPLES = 40_000


def angle_input(roles: Sequence[str | None], axis: str) -> int | None:
    """The input a ripple is a function of: the wrapped angle, else the angle; None on a
    linear axis or without one."""
    if axis != "rotary":
        return None
    for want in ("angle_wrapped", "angle"):
        if want in roles:
            return list(roles).index(want)
    return None


class Harmonic(NamedTuple):
    """One harmonic of a residual: ``amplitude sin(order theta + phase)``, through the
    low-pass ``corner / (s + corner)`` when ``corner`` is not None."""

    order: int
    amplitude: float
    phase: float
    corner: float | None = None


def _lowpassed(theta: np.ndarray, ks: np.ndarray, corner: float, ts: float,
               starts: Sequence[int], chosen: np.ndarray) -> np.ndarray:
    """``cos k theta`` then ``sin k theta`` for each ``k`` of ``ks`` through the ``lpf``
    element's discrete filter, from rest at every log start, at the ``chosen`` samples:
    shape (len(chosen), 2 len(ks)). One column at a time over the whole log, so a long
    log never holds more than one whole column
    (docs/abstraction.md#hierarchy-and-inheritance-figs-8-19)."""
    b, a = BY_NAME["lpf"].coefficients(corner, ts)
    out = np.empty((chosen.size, 2 * ks.size))
    full = np.empty(theta.size)
    for j, wave in enumerate([np.cos] * ks.size + [np.sin] * ks.size):
        column = wave(theta * ks[j % ks.size])
        for lo, hi in segments(theta.size, starts):
            full[lo:hi] = lfilter(b, a, column[lo:hi])
        out[:, j] = full[chosen]
    return out


def fitted_samples(weights: np.ndarray) -> np.ndarray:
    """The samples the seeds' least squares use: those of positive weight, every one up to
    :data:`SEED_SAMPLES` of them, else every k-th (the smallest k that keeps at most that
    many): a long log's seeds cost what a 40 000-sample log's do."""
    kept = np.flatnonzero(np.asarray(weights) > 0)
    stride = max(1, -(-kept.size // SEED_SAMPLES))
    return kept[::stride]


def _typical_speed(theta: np.ndarray, ts: float, starts: Sequence[int]) -> float:
    """The median speed of the angle [rad/s] over the samples that move (above 2 % of the
    fastest), the angle unwrapped within each log."""
    speed = np.concatenate([np.abs(np.diff(np.unwrap(theta[lo:hi]))) / ts
                            for lo, hi in segments(theta.size, starts)])
    moving = speed[speed > 0.02 * speed.max()] if speed.size else speed
    return float(np.median(moving)) if moving.size else math.inf


def residual_harmonics(theta: np.ndarray, residual: np.ndarray, weights: np.ndarray,
                       count: int, max_order: int = MAX_ORDER, *,
                       corners: Sequence[float] = (), ts: float | None = None,
                       starts: Sequence[int] = ()) -> list[Harmonic]:
    """The ``count`` strongest harmonics of ``residual`` over ``theta``.

    The residual is fitted by weighted least squares on a constant and
    ``cos k theta``, ``sin k theta`` for ``k = 1 .. max_order``; with
    ``corners``, also on those columns through each corner's low-pass (the
    ``lpf`` element, from rest at every log start), and the corner whose fit
    leaves the least of the residual (the best of the grid, refined between
    its neighbours) is kept when it leaves at least the share
    :data:`LAG_GAIN` less than the plain fit. Only corners at or above the
    angle's median speed over the samples that move are tried: a low-pass slower than even the
    first harmonic at a typical speed turns the harmonics into slow signals
    that fit any slow part of the residual (on a plant without ripple, the
    search then started from rows of amplitude 0.6 N m through a 1 rad/s
    low-pass and stayed there). A ripple at many cycles a revolution and a
    high speed reaches the target through the observer's lag; the same
    harmonic without it leaves most of it behind.

    Parameters
    ----------
    theta : numpy.ndarray
        The angle [rad].
    residual : numpy.ndarray
        Target minus the model, same length.
    weights : numpy.ndarray
        Non-negative sample weights (0 on held-out samples).
    count : int
    max_order : int
    corners : sequence of float, optional
        Low-pass corners [rad/s] tried (none: no lag).
    ts : float, optional
        Sample time [s]; needed with ``corners``.
    starts : sequence of int, optional
        The first sample of each log after the first
        (:func:`edm_sym.engines.simulate.segments`).

    Returns
    -------
    list of Harmonic
        Largest amplitude first.
    """
    w = np.sqrt(np.maximum(np.asarray(weights, dtype=float), 0.0))
    chosen = fitted_samples(w)
    if count <= 0 or chosen.size <= 2 * max_order + 1:
        return []
    th, r = np.asarray(theta, dtype=float), np.asarray(residual, dtype=float)
    ks = np.arange(1, max_order + 1)
    arg = np.outer(th[chosen], ks)
    waves = np.hstack([np.cos(arg), np.sin(arg)])
    ones = np.ones((chosen.size, 1))
    rk, wk = r[chosen], w[chosen]

    def fit(columns: np.ndarray) -> tuple[float, np.ndarray]:
        basis = np.hstack([ones, columns])
        coef, *_ = np.linalg.lstsq(basis * wk[:, None], rk * wk, rcond=None)
        return float(np.sum(((rk - basis @ coef) * wk) ** 2)), coef

    plain, coef = fit(waves)
    floor = _typical_speed(th, ts, starts) if len(corners) and ts is not None else math.inf
    grid = [float(c) for c in corners if c >= floor]
    corner = None
    if grid and math.isfinite(plain):
        def lag(c: float) -> tuple[float, np.ndarray]:
            return fit(_lowpassed(th, ks, c, ts, starts, chosen))

        tried = [lag(c)[0] for c in grid]
        i = int(np.nanargmin(tried)) if np.any(np.isfinite(tried)) else 0
        # The best corner of the grid, refined between its neighbours (on a log scale).
        lo, hi = math.log(grid[max(i - 1, 0)]), math.log(grid[min(i + 1, len(grid) - 1)])
        c = grid[i]
        if hi > lo:
            found = minimize_scalar(lambda u: lag(math.exp(u))[0], bounds=(lo, hi),
                                    method="bounded", options={"xatol": 0.01})
            if found.success and found.fun < tried[i]:
                c = float(math.exp(found.x))
        left, lag_coef = lag(c)
        if math.isfinite(left) and left < (1.0 - LAG_GAIN) * plain:
            corner, coef = c, lag_coef
    if not np.all(np.isfinite(coef)):
        return []
    a, b = coef[1:max_order + 1], coef[max_order + 1:]
    amp = np.hypot(a, b)
    order = np.argsort(-amp, kind="stable")[:count]
    # a cos + b sin = A sin(k theta + phi) with A = hypot(a, b), phi = atan2(a, b).
    return [Harmonic(int(ks[i]), float(amp[i]), float(math.atan2(a[i], b[i])), corner)
            for i in order if amp[i] > 0]


def _row(n_elements: int, genes: Sequence[tuple[int, float]]) -> tuple[np.ndarray, np.ndarray]:
    """A row's ``(codes, ps)``: ``genes`` first, ``through`` after them."""
    codes = np.full(n_elements, BY_NAME["through"].code, dtype=np.int64)
    ps = np.zeros(n_elements)
    for i, (code, p) in enumerate(genes):
        codes[i], ps[i] = code, p
    return codes, ps


def harmonic_rows(harmonics: Sequence[Harmonic | tuple[int, float, float]],
                  ranges: dict[str, ParamRange], n_elements: int, allowed: set[int]
                  ) -> list[tuple[np.ndarray, np.ndarray]]:
    """Each harmonic as a row's genes ``(codes, ps)`` of length ``n_elements``:
    ``theta -> gain(k) -> sin_phase(phi) -> gain(A)``, with ``lpf(corner)`` before the
    last gain when the harmonic has a corner.

    A harmonic whose gain or amplitude lies outside the gain's range, or a
    schedule without ``gain`` and ``sin_phase`` (or with fewer than three
    elements a row), gives no row. Its corner is left out when it lies outside
    the ``lpf`` range, the schedule has no ``lpf`` or a row fewer than four
    elements.
    """
    gain, sine, lpf = BY_NAME["gain"], BY_NAME["sin_phase"], BY_NAME["lpf"]
    if n_elements < 3 or not {gain.code, sine.code} <= allowed:
        return []
    g, s = ranges[gain.name], ranges[sine.name]
    f = ranges.get(lpf.name)
    out = []
    for h in harmonics:
        k, amp, phase = h[0], h[1], h[2]
        corner = h[3] if len(h) > 3 else None
        if not (g.low <= k <= g.high and g.low <= amp <= g.high):
            continue
        genes = [(gain.code, g.encode(float(k))), (sine.code, s.encode(phase))]
        if (corner is not None and f is not None and n_elements >= 4 and lpf.code in allowed
                and f.low <= corner <= f.high):
            genes.append((lpf.code, f.encode(float(corner))))
        codes, ps = _row(n_elements, [*genes, (gain.code, g.encode(amp))])
        out.append((codes, ps))
    return out


def velocity_input(roles: Sequence[str | None]) -> int | None:
    """The input a Stribeck hump is a function of: the velocity, or None without one."""
    return list(roles).index("velocity") if "velocity" in roles else None


def stribeck_slopes(v: np.ndarray) -> np.ndarray:
    """The grid of ``1 / v_s`` tried: ``v_s`` from the 5th to the 95th percentile of |v|."""
    speed = np.abs(v[v != 0])
    if speed.size < 8:
        return np.empty(0)
    low, high = np.percentile(speed, [5, 95])
    if not (high > low > 0):
        return np.empty(0)
    return 1.0 / np.geomspace(low, high, STRIBECK_GRID)


def residual_stribeck(v: np.ndarray, residual: np.ndarray, weights: np.ndarray, count: int
                      ) -> list[tuple[float, float, float]]:
    """The ``count`` best Stribeck humps of ``residual`` over the velocity ``v``.

    For each slope ``k`` of a grid (:data:`STRIBECK_GRID` values, ``1/k`` from
    the 5th to the 95th percentile of |v|) the residual is fitted by weighted
    least squares on ``1``, ``sign v``, ``v`` and ``tanh(k v)``: the hump
    ``dF sign(v) (1 - tanh(k |v|))`` is the ``sign`` and ``tanh`` columns
    together, the first carried by the model's Coulomb row, whose gain the
    gain fit sets. Slopes are ranked by the residual left; each one taken is
    at least a factor 2 from those before it.

    Returns
    -------
    list of (float, float, float)
        ``(k, c, drop)``: the slope [1/unit of v], the gain of ``tanh(k v)``
        [unit of the residual], and the share of the residual's weighted square
        the fit removes; best first.
    """
    w = np.sqrt(np.maximum(np.asarray(weights, dtype=float), 0.0))
    chosen = fitted_samples(w)
    if count <= 0 or chosen.size <= 8:
        return []
    v, r, w = (np.asarray(v, dtype=float)[chosen], np.asarray(residual, dtype=float)[chosen],
               w[chosen])
    ks = stribeck_slopes(v)
    total = float(np.sum((r * w) ** 2))
    if ks.size == 0 or not total > 0:
        return []
    fits = []
    for k in ks:
        basis = np.column_stack([np.ones_like(v), np.sign(v), v, np.tanh(k * v)])
        coef, *_ = np.linalg.lstsq(basis * w[:, None], r * w, rcond=None)
        left = float(np.sum(((r - basis @ coef) * w) ** 2))
        if np.all(np.isfinite(coef)) and math.isfinite(left):
            fits.append((left, float(k), float(coef[3])))
    out: list[tuple[float, float, float]] = []
    for left, k, c in sorted(fits):
        if len(out) == count:
            break
        if all(abs(math.log(k / k0)) >= math.log(2.0) for k0, _, _ in out):
            out.append((k, c, 1.0 - left / total))
    return out


def stribeck_rows(humps: Sequence[tuple[float, float, float]], ranges: dict[str, ParamRange],
                  n_elements: int, allowed: set[int]) -> list[tuple[np.ndarray, np.ndarray]]:
    """Each hump as a row's genes ``(codes, ps)``: ``v -> tanh(k) -> gain(c)``.

    A hump whose slope or gain lies outside its element's range, or a schedule
    without ``tanh`` and ``gain`` (or with fewer than two elements a row),
    gives no row.
    """
    gain, tanh = BY_NAME["gain"], BY_NAME["tanh"]
    if n_elements < 2 or not {gain.code, tanh.code} <= allowed:
        return []
    g, t = ranges[gain.name], ranges[tanh.name]
    out = []
    for k, c, _ in humps:
        if not (t.low <= k <= t.high and g.low <= c <= g.high):
            continue
        codes, ps = _row(n_elements, [(tanh.code, t.encode(k)), (gain.code, g.encode(c))])
        out.append((codes, ps))
    return out
