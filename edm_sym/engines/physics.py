"""The physics a whole model holds, named by what it does on probe motions.

A compensator found by the search writes one friction law in many ways: a
Coulomb relay and a viscous gain in two rows, a viscous row cancelled by a
dead zone on the integral of the acceleration, an inertia held in the lead of
a velocity filter, a 3-cycle ripple as ``sin(2.5 sin theta)`` minus
``sin theta``. Reading the rows one by one names what each expression looks
like, not what the model does. This module names the model by its behaviour:

1. **Probes.** The reference simulator drives the model with physically
   consistent motions inside the ranges the data (or result.json) records:
   constant-velocity runs in both directions at speeds from the slowest the
   log holds to the fastest (each from rest, long enough for the model's
   filters to settle, but no longer than the log the model was fitted on
   holds a speed, over whole revolutions where the speed allows), and
   triangle waves of velocity at constant acceleration. Every input gets the
   signal its role says (the angle, the wrapped angle, the velocity, the
   acceleration); an input without a role is held at zero (said in the notes).
2. **Laws.** On the settled samples of every run (each run weighted alike),
   with the observer's lag taken out of the model's output (``y + y'/g``,
   ``g`` the observer's bandwidth, when known), one least-squares fit of the
   documented laws: ``Fc sgn(v) + Fs sgn(v) exp(-(v/v_s)^2) + D v + J a + c0
   + sum_k (a_k cos k theta + b_k sin k theta)``, the Stribeck velocity ``v_s``
   scanned. Every parameter carries its relative standard error, and the fit
   how much of the model's probe behaviour the laws explain.
3. **Honest names.** A law is named only when it matters (its term's RMS on
   the data, else on the probes, at least ``threshold`` of the reference RMS)
   and its sign is physical (friction opposes motion); Stribeck only when the
   peak is at least ``stribeck_ratio`` times the Coulomb level; a ripple by
   its dominant harmonic. What is left out is listed with the reason.
4. **Rows.** Each row's output on the same probes is fitted by the same basis:
   its share of each law (the shares add up to one), and what it does that no
   law explains. Rows that carry one law together (a cancelling pair, velocity
   built from an integral or a derivative) show up together.

``edm describe``, the report and ``EDMRegressor.describe`` read this one
source (docs/describe.md#physics-named-by-behaviour).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from edm_sym.core.elements.realisation import DelayLine, LinearFilter
from edm_sym.core.matrix import Compensator
from edm_sym.core.roles import motion_signals
from edm_sym.core.terms import TermKind
from edm_sym.core.units import axis_units
from edm_sym.core.validation import positive_number
from edm_sym.engines.plant.filters import lowpass, sliding_rows

TWO_PI = 2.0 * math.pi


@dataclass(frozen=True)
class PhysicsOptions:
    """Thresholds and probe sizes of :func:`model_physics`.

    Parameters
    ----------
    threshold : float, default 0.01
        A law is named when its term's RMS is at least this share of the
        reference RMS (the target's on the data, else the model's on the probes).
    stribeck_ratio : float, default 1.1
        A Stribeck hump is named when the level at rest (Coulomb plus its
        ``peak``, the excess over Coulomb) is at least this many times the
        Coulomb level.
    max_harmonic : int, default 12
        The highest angle harmonic fitted (cycles per revolution).
    profile : int, default 8
        Cosines of the position over its span fitted on a linear axis.
    levels : int, default 10
        Constant-velocity runs per direction.
    max_settle : float, default 3.0
        The longest settling time a run waits for [s].
    max_window : float, default 10.0
        The longest measuring window of one run [s].
    uncertain : float, default 0.1
        A named parameter whose relative standard error is above this is flagged.
    support : float, default 0.01
        With data, a law is named only when the model without its term (passed
        through the observer's low-pass) fits the target worse by at least this
        share of its RMSE: a term the data does not need is not physics.
    """

    threshold: float = 0.01
    stribeck_ratio: float = 1.1
    max_harmonic: int = 12
    profile: int = 8
    levels: int = 10
    max_settle: float = 3.0
    max_window: float = 10.0
    uncertain: float = 0.1
    support: float = 0.01

    def __post_init__(self) -> None:
        for name in ("threshold", "uncertain", "support"):
            v = getattr(self, name)
            if not (isinstance(v, int | float) and 0.0 <= v < 1.0):
                raise ValueError(f"{name}: expected a number in [0, 1), found {v!r}")
        for name in ("stribeck_ratio", "max_settle", "max_window"):
            v = getattr(self, name)
            if not (isinstance(v, int | float) and math.isfinite(v) and v > 0):
                raise ValueError(f"{name}: expected a finite number, found {v!r}")
        for name in ("max_harmonic", "profile", "levels"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int) or v < 1:
                raise ValueError(f"{name}: expected an integer >= 1, found {v!r}")


@dataclass(frozen=True)
class MotionRange:
    """The motion the model is judged over.

    Attributes
    ----------
    velocity : float
        The fastest speed [rad/s or m/s] (> 0).
    slowest : float
        The slowest speed probed (> 0, below ``velocity``).
    acceleration : float
        The largest acceleration (> 0).
    position : (float, float) or None
        The span of the unwrapped angle (or linear position), when an input has it.
    source : str
        Where the ranges come from (a log, or result.json's recorded ranges).
    hold : float or None
        The longest time the log holds a speed [s] (:func:`held_time`): the
        probes wait no longer than this for the model to settle. None: not
        known (a result written before it was recorded), no limit.
    """

    velocity: float
    slowest: float
    acceleration: float
    position: tuple[float, float] | None
    source: str
    hold: float | None = None


@dataclass(frozen=True)
class Law:
    """One physical law of the model, with what supports it.

    Attributes
    ----------
    kind : TermKind
    parameters : dict of str to (float, str)
        Name -> (value, SI unit).
    share : float
        RMS of the law's term over the reference RMS (0.42 = 42 %).
    errors : dict of str to float
        Relative standard error of each fitted parameter (the probes are
        noise-free: it measures how well the law describes the model): the
        larger of the least-squares one, the jackknife over the probe speeds
        and, when the probes waited only the log's hold, the change of the
        value when the model is held until it settles.
    rows : tuple of float
        Each row's share of the law (they add up to one).
    flags : tuple of (str, str)
        ``(code, message)``: ``uncertain``, ``lag_included``, ...
    """

    kind: TermKind
    parameters: Mapping[str, tuple[float, str]]
    share: float
    errors: Mapping[str, float] = field(default_factory=dict)
    rows: tuple[float, ...] = ()
    flags: tuple[tuple[str, str], ...] = ()

    def to_json(self) -> dict[str, Any]:
        """``{"kind", "parameters", "share", "errors", "rows", "flags"}``."""
        return {"kind": self.kind.value,
                "parameters": {k: [_finite(v), u] for k, (v, u) in self.parameters.items()},
                "share": _finite(self.share),
                "errors": {k: _finite(v) for k, v in self.errors.items()},
                "rows": [{"index": j + 1, "share": _finite(s)} for j, s in enumerate(self.rows)
                         if abs(s) >= ROW_SHARE],
                "flags": [{"code": c, "message": m} for c, m in self.flags]}


@dataclass(frozen=True)
class RowBehaviour:
    """What one row does on the probes and the data.

    Attributes
    ----------
    index : int
        Row number, 1-based.
    laws : dict of str to float
        Law kind -> the row's share of it (only shares of at least 10 %).
    unexplained : float
        RMS of what no law explains in the row's output, over the reference RMS.
    reason : str
        Why the row is unclassified (empty when the laws explain it).
    """

    index: int
    laws: Mapping[str, float]
    unexplained: float
    reason: str = ""

    def to_json(self) -> dict[str, Any]:
        """``{"index", "laws", "unexplained", "reason"}``."""
        return {"index": self.index, "laws": {k: _finite(v) for k, v in self.laws.items()},
                "unexplained": _finite(self.unexplained), "reason": self.reason}


@dataclass(frozen=True)
class Physics:
    """The laws a model holds (:func:`model_physics`).

    Attributes
    ----------
    terms : tuple of Law
        The named laws, in the order of :class:`TermKind`.
    left_out : tuple of (TermKind, str)
        Laws fitted but not named, with the reason.
    explained : float
        Share of the model's (un-lagged) output on the probes that the laws
        explain (R^2, weighted like the fit).
    rows : tuple of RowBehaviour
    ranges : MotionRange
    bandwidth : float or None
        The observer bandwidth whose lag was taken out [rad/s].
    reference : str
        What the shares are of: ``"target"`` (the target's RMS on the data) or
        ``"probes"`` (the model's RMS on the probes, without data).
    notes : tuple of str
        What was assumed, one line each.
    """

    terms: tuple[Law, ...]
    left_out: tuple[tuple[TermKind, str], ...]
    explained: float
    rows: tuple[RowBehaviour, ...]
    ranges: MotionRange
    bandwidth: float | None
    notes: tuple[str, ...] = ()
    reference: str = "target"

    def named(self) -> dict[str, dict[str, float]]:
        """Kind -> parameter -> value of the named laws."""
        return {t.kind.value: {k: v for k, (v, _) in t.parameters.items()} for t in self.terms}

    def to_json(self) -> dict[str, Any]:
        """The ``physics`` key of ``edm describe --json`` (docs/describe.md)."""
        r = self.ranges
        return {"terms": [t.to_json() for t in self.terms],
                "left_out": [{"kind": k.value, "reason": why} for k, why in self.left_out],
                "explained": _finite(self.explained),
                "rows": [b.to_json() for b in self.rows],
                "ranges": {"velocity": _finite(r.velocity), "slowest": _finite(r.slowest),
                           "acceleration": _finite(r.acceleration),
                           "position": None if r.position is None else [_finite(p) for p in r.position],
                           **({} if r.hold is None else {"hold": _finite(r.hold)}),
                           "source": r.source},
                "observer_bandwidth": None if self.bandwidth is None else _finite(self.bandwidth),
                "reference": self.reference, "notes": list(self.notes)}

    def lines(self, axis: str = "rotary") -> list[str]:
        """The laws for people, one line each, then what was left out."""
        out = []
        of = "the target" if self.reference == "target" else "the model on the probes"
        for t in self.terms:
            params = ", ".join(f"{k.replace('_', ' ')} {v:.4g}" + (f" {u}" if u != "1" else "")
                               for k, (v, u) in t.parameters.items())
            rows = ", ".join(f"row {j + 1} {100 * s:.0f} %" for j, s in enumerate(t.rows)
                             if abs(s) >= ROW_SHARE)
            out.append(f"  {t.kind.value}: {params}  ({100 * t.share:.3g} % of {of}"
                       + (f"; {rows}" if rows else "") + ")")
            out += [f"     ! {c}: {m}" for c, m in t.flags]
        out += [f"  not named: {k.value}: {why}" for k, why in self.left_out]
        out.append(f"  the laws explain {100 * self.explained:.4g} % of what the model does on "
                   f"the probes ({self.ranges.source})")
        out += [f"  row {b.index} unclassified: {b.reason}" for b in self.rows if b.reason]
        return out


#: The settled samples of one run the fit reads at most (evenly spaced).
MAX_PER_RUN = 1500
#: A row is listed with a law when it carries at least this share of it.
ROW_SHARE = 0.1
#: On the data, a row is unexplained when this share of its own RMS is outside the laws.
DATA_UNEXPLAINED = 0.5
#: A speed a log holds (a plateau): at least this share of its samples within
#: +-:data:`HELD_BAND` of it (a 1 s plateau in both directions of a 20 s log: 8 %;
#: a chirp's slowest speeds: under 0.2 %).
HELD_SHARE = 0.01
#: The relative half-width of the band around a held speed.
HELD_BAND = 0.05
#: The data's support of a law is judged on the samples where the axis slides: at
#: least the slowest speed probed, for this many observer time constants (1/g) since
#: the last slower sample (the reversals' presliding and the observer's lag left out,
#: as :func:`edm_sym.engines.plant.anchor.fit_anchor` leaves them out).
SLIDE_SETTLE = 6.0
#: Fewer sliding samples than this share of the data: the support is judged on all.
SLIDE_MIN_SHARE = 0.1


def _pct(share: float) -> str:
    """A share as a percentage for a message; below 1e-6 it is "0" (rounding noise, which
    differs from one machine to the next, must not reach a report)."""
    return "0" if abs(share) < 1e-6 else f"{100 * share:.2g}"


def _finite(v: float) -> float | None:
    v = float(v)
    return v if math.isfinite(v) else None


# --------------------------------------------------------------------------- ranges

def ranges_from_result(result: Any, roles: Mapping[str, str | None]) -> MotionRange | None:
    """The motion result.json records for its abstraction log (``logs[].columns`` min/max).

    The velocity range is the largest |velocity| recorded (from the angle's
    span over the log's duration when no velocity is recorded), the slowest a
    fiftieth of it, or the slowest speed the abstraction log holds when the
    result's ``physics`` records a slower one (``physics.ranges.slowest``,
    :func:`ranges_from_data` on that log; at least a two-hundredth of the
    fastest), the acceleration the largest |acceleration| (else the velocity
    over a tenth of a second), the hold the longest time that log held a speed
    (``physics.ranges.hold``; None when not recorded). None when nothing is recorded.
    """
    logs = [g for g in getattr(result, "logs", ()) if g.get("use") == "abstraction"] or list(
        getattr(result, "logs", ()))
    if not logs:
        return None
    cols = {c.get("name"): c for c in logs[0].get("columns", ())}

    def span(role: str) -> tuple[float, float] | None:
        for name, r in roles.items():
            c = cols.get(name)
            if r == role and c and all(isinstance(c.get(k), int | float) for k in ("min", "max")):
                return float(c["min"]), float(c["max"])
        return None

    vel, acc, pos = span("velocity"), span("acceleration"), span("angle")
    if vel is None:
        return None
    v = max(abs(vel[0]), abs(vel[1]))
    if not (v > 0 and math.isfinite(v)):
        return None
    a = max(abs(acc[0]), abs(acc[1])) if acc is not None else 10.0 * v
    name = getattr(result, "source", None) or "result.json"
    slowest = v / 50.0
    recorded = (getattr(result, "physics", None) or {}).get("ranges", {})
    held = positive_number(recorded.get("slowest"))
    if held is not None:
        slowest = min(slowest, max(held, v / 200.0))
    return MotionRange(v, slowest, a if a > 0 and math.isfinite(a) else 10.0 * v, pos,
                       f"the ranges {_basename(name)} records", positive_number(recorded.get("hold")))



def ranges_from_data(velocity: np.ndarray, acceleration: np.ndarray, angle: np.ndarray | None,
                     source: str, ts: float | None = None) -> MotionRange | None:
    """The motion a log reaches: the 99th percentile of |v| and |a|, the slowest
    speed probed (a fiftieth of the fastest, or the slowest speed the log holds down
    to a two-hundredth, :func:`held_speed`), the angle's span, and with the sample
    time ``ts`` the longest time the log holds a speed (:func:`held_time`)."""
    v = np.abs(np.asarray(velocity, dtype=float))
    v = v[np.isfinite(v)]
    if v.size < 2:
        return None
    vmax = float(np.percentile(v, 99.0))
    if not (vmax > 0):
        return None
    held = held_speed(v, vmax / 200.0, vmax / 50.0)
    a = np.abs(np.asarray(acceleration, dtype=float))
    a = a[np.isfinite(a)]
    amax = float(np.percentile(a, 99.0)) if a.size else 10.0 * vmax
    pos = None
    if angle is not None and np.size(angle):
        th = np.asarray(angle, dtype=float)
        th = th[np.isfinite(th)]
        pos = (float(th.min()), float(th.max())) if th.size else None
    # Down to a fiftieth of the fastest (the log the model was fitted to may hold slower
    # speeds than this one: a Stribeck hump at 2 rad/s is invisible from 5 rad/s up),
    # and to the slowest speed this log holds, down to a two-hundredth.
    return MotionRange(vmax, vmax / 50.0 if held is None else held,
                       amax if amax > 0 else 10.0 * vmax, pos, source,
                       None if ts is None else held_time(velocity, ts, vmax / 200.0))


def held_speed(speed: np.ndarray, low: float, high: float) -> float | None:
    """The slowest speed in ``[low, high]`` a log holds: a plateau, not a passage.

    A speed is held when at least :data:`HELD_SHARE` of the samples' ``|speed|``
    lie within +-:data:`HELD_BAND` of it. Scanned on a geometric grid (steps of
    half the band) from ``low`` up; from the first speed held, the scan climbs
    to the share's local peak (the plateau's level). None when no speed in the
    interval is held (a chirp, a sweep, a stick-slip that never settles).
    """
    v = np.abs(np.asarray(speed, dtype=float))
    v = v[np.isfinite(v)]
    if v.size == 0 or not (0.0 < low < high):
        return None
    v = np.sort(v)
    grid = np.exp(np.arange(math.log(low), math.log(high) + 1e-12, HELD_BAND / 2.0))
    shares = (np.searchsorted(v, grid * (1.0 + HELD_BAND))
              - np.searchsorted(v, grid / (1.0 + HELD_BAND))) / v.size
    held = np.flatnonzero(shares >= HELD_SHARE)
    if held.size == 0:
        return None
    i = int(held[0])
    while i + 1 < grid.size and shares[i + 1] > shares[i]:
        i += 1
    return float(grid[i])


def held_time(velocity: np.ndarray, ts: float, floor: float) -> float | None:
    """The longest time [s] a log holds one speed: a stretch of one sign, every
    ``|v|`` at least ``floor`` and within +-:data:`HELD_BAND` of one level (the
    largest at most ``(1 + HELD_BAND)^2`` times the smallest). A staircase of 1 s
    plateaus holds 0.9 s (its noise included), a chirp a fraction of its slowest
    period. None when nothing moves above ``floor``.

    One pass with the running extremes of a sliding window (monotonic queues).
    """
    from collections import deque

    v = np.asarray(velocity, dtype=float)
    speed = np.abs(v)
    sign = np.sign(v)
    moving = np.isfinite(v) & (speed >= floor) & (speed > 0)
    limit = (1.0 + HELD_BAND) ** 2
    best, lo = 0, 0
    top: deque[int] = deque()
    low: deque[int] = deque()
    for i in range(v.size):
        if not moving[i]:
            lo = i + 1
            top.clear()
            low.clear()
            continue
        if i > lo and sign[i] != sign[i - 1]:
            lo = i
            top.clear()
            low.clear()
        while top and speed[top[-1]] <= speed[i]:
            top.pop()
        top.append(i)
        while low and speed[low[-1]] >= speed[i]:
            low.pop()
        low.append(i)
        while speed[top[0]] > limit * speed[low[0]]:
            lo += 1
            if top[0] < lo:
                top.popleft()
            if low[0] < lo:
                low.popleft()
        best = max(best, i - lo + 1)
    return best * float(ts) if best else None


def _basename(path: str) -> str:
    return str(path).replace("\\", "/").rsplit("/", 1)[-1]


# --------------------------------------------------------------------------- probes

@dataclass(frozen=True)
class Run:
    """One probe motion from rest: angle, velocity, acceleration per sample, the
    samples where the model has settled (``steady``), and the probe speed it
    belongs to (``speed``: its index, both directions alike; -1 for a triangle
    wave), which the jackknife of the laws' errors leaves out in turn."""

    theta: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray
    steady: np.ndarray
    speed: int = -1


def settling_time(comp: Compensator, max_settle: float) -> float:
    """Five times the slowest row's summed time constants plus its delays [s], at most
    ``max_settle`` and at least 20 samples."""
    ts = comp.sample_time
    worst = 0.0
    for row in comp.matrix.rows:
        total = 0.0
        for gene in row.genes:
            rl = gene.element.realise(comp.value(gene), ts)
            if isinstance(rl, LinearFilter) and len(rl.a) > 1:
                r = float(np.max(np.abs(np.roots(rl.a))))
                total += math.inf if r >= 1.0 else (-ts / math.log(r) if r > 0 else 0.0)
            elif isinstance(rl, DelayLine):
                total += rl.samples * ts / 5.0
        worst = max(worst, total)
    return float(min(max(5.0 * worst, 20 * ts), max_settle))


def _profile(v_of_t: np.ndarray, ts: float, theta0: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Angle and acceleration of a velocity profile (trapezoidal integration, exact for ramps)."""
    theta = theta0 + np.concatenate([[0.0], np.cumsum(0.5 * (v_of_t[1:] + v_of_t[:-1]) * ts)])
    acc = np.gradient(v_of_t, ts) if v_of_t.size > 1 else np.zeros_like(v_of_t)
    return theta, v_of_t, acc


def probe_runs(ranges: MotionRange, ts: float, settle: float, *, rotary: bool,
               options: PhysicsOptions) -> list[Run]:
    """The probe motions: constant-velocity runs and triangle waves of velocity.

    Constant-velocity runs: ``options.levels`` speeds per direction, spaced
    geometrically from ``ranges.slowest`` to ``ranges.velocity``, each reached
    as a sweep down in its direction (from rest up to ``ranges.velocity`` and
    down to the speed, at constant acceleration: a relay or a hysteresis in the
    model is in the state sliding that way sets, not the one it starts in), then
    held for the settling time and a window of one revolution (rotary; the
    position span on a linear axis), at most ``options.max_window``. Positive
    runs start at the low end of the recorded position, negative ones at the
    high end. Triangle waves: four periods between ``-V`` and ``V`` (``V`` the
    fastest speed and a third of it) at half and an eighth of the recorded
    acceleration (the log's time scales: a filter's response there is what the
    search fitted, not its DC gain on a minute-long ramp), from the middle of
    the position span; steady after the first period (or the settling time)
    and away from each turn of the acceleration and each zero crossing of the
    velocity (the settling time, at most a third of a ramp).
    """
    lo, hi = ranges.position if ranges.position is not None else (0.0, 0.0)
    span = (hi - lo) if hi > lo else (TWO_PI if rotary else 0.0)
    travel = TWO_PI if rotary else span
    n_settle = max(int(round(settle / ts)), 1)
    runs = []
    speeds = np.geomspace(ranges.slowest, ranges.velocity, options.levels)
    a_ramp = 0.5 * ranges.acceleration
    for sign in (1.0, -1.0):
        for index, speed in enumerate(speeds):
            up = max(int(math.ceil(ranges.velocity / a_ramp / ts)), 1)
            down = int(math.ceil((ranges.velocity - speed) / a_ramp / ts))
            ramp = up + down
            window = travel / speed if travel > 0 else 0.5
            window = min(max(window, 50 * ts, settle), options.max_window)
            n_hold = n_settle + int(round(window / ts))
            v = sign * np.concatenate([np.linspace(0.0, ranges.velocity, up + 1),
                                       np.linspace(ranges.velocity, speed, down + 1)[1:],
                                       np.full(n_hold, speed)])
            theta, v, a = _profile(v, ts, lo if sign > 0 else hi)
            steady = np.zeros(v.size, dtype=bool)
            steady[ramp + 1 + n_settle:] = True
            runs.append(Run(theta, v, a, steady, index))
    for top, share in ((ranges.velocity, 0.5), (ranges.velocity / 3.0, 0.5),
                       (ranges.velocity, 0.125), (ranges.velocity / 3.0, 0.125)):
        # The accelerations of the log, not slower: a filter's response at the log's
        # time scales is what the search fitted; its DC gain on a minute-long ramp is not.
        acc = share * ranges.acceleration
        quarter = max(int(round(top / acc / ts)), 4)
        up = np.linspace(0.0, top, quarter + 1)[:-1]
        down = np.linspace(top, -top, 2 * quarter + 1)[:-1]
        back = np.linspace(-top, 0.0, quarter + 1)[:-1]
        v = np.tile(np.concatenate([up, down, back]), 4)
        theta, v, a = _profile(v, ts, 0.5 * (lo + hi))
        steady = np.ones(v.size, dtype=bool)
        steady[:min(n_settle, 4 * quarter)] = False  # the first period (or settling time)
        guard = max(min(n_settle, quarter // 3), 1)
        events = np.nonzero((np.diff(np.sign(v)) != 0) | (np.abs(np.diff(a)) > 0.5 * acc))[0]
        for e in events:  # after each zero crossing and each turn of the acceleration
            steady[e:e + guard] = False
        runs.append(Run(theta, v, a, steady))
    return runs


def run_inputs(run: Run, roles: Sequence[str | None],
               lags: Mapping[str, float] | None = None, ts: float = 1.0) -> np.ndarray:
    """The model's inputs on a run: each input the signal of its role (zero without one).

    ``lags`` (role -> time constant [s], :func:`input_lags`) delays the velocity and
    acceleration through a first-order low-pass, as the log's own signals lag the
    motion (a filtered encoder difference): the model was fitted to those.
    """
    from scipy.signal import lfilter

    by_role = {"angle": run.theta, "angle_wrapped": np.mod(run.theta, TWO_PI),
               "velocity": run.velocity, "acceleration": run.acceleration}
    for role, tau in (lags or {}).items():
        if role in by_role and tau > 0:
            alpha = ts / (tau + ts)
            by_role[role] = lfilter([alpha], [1.0, alpha - 1.0], by_role[role])
    return np.stack([by_role.get(r, np.zeros_like(run.velocity)) for r in roles])


def input_lags(x: np.ndarray, roles: Sequence[str | None], ts: float) -> dict[str, float]:
    """How far the velocity and acceleration inputs lag the angle's derivatives [s].

    A logged velocity is a filtered difference of the encoder angle, the
    acceleration a filtered difference of that; a model fitted to them holds
    their lag (a viscous law on a velocity that lags by ``tau`` reads as an
    inertia of ``D tau`` on a lag-free one). Estimated by least squares,
    ``x_logged - x_true = -tau d(x_true)/dt``, with ``x_true`` the central
    differences of the unwrapped angle, both sides smoothed alike over 9
    samples; kept within ``[0, 50 ts]``. Empty without an angle input.
    """
    by_role = {r: np.asarray(v, dtype=float) for v, r in zip(x, roles, strict=True) if r}
    angle = by_role.get("angle")
    if angle is None and "angle_wrapped" in by_role:
        angle = np.unwrap(by_role["angle_wrapped"])
    if angle is None or angle.size < 32:
        return {}
    kernel = np.ones(9) / 9.0

    def smooth(z: np.ndarray) -> np.ndarray:
        return np.convolve(z, kernel, mode="same")[8:-8]

    v_true = np.gradient(angle, ts)
    a_true = np.gradient(v_true, ts)
    out = {}
    for role, true, rate in (("velocity", v_true, a_true),
                             ("acceleration", a_true, np.gradient(a_true, ts))):
        logged = by_role.get(role)
        if logged is None:
            continue
        d, r = smooth(logged - true), smooth(rate)
        denom = float(np.dot(r, r))
        if denom > 0 and np.all(np.isfinite(d)):
            out[role] = float(np.clip(-np.dot(d, r) / denom, 0.0, 50 * ts))
    return out


# --------------------------------------------------------------------------- laws

@dataclass(frozen=True)
class _Basis:
    """The law basis: column names and how to evaluate them on a motion.

    ``harmonics`` angle harmonics on a rotary axis; on a linear one, ``profile``
    cosines of the position over its recorded span ``(lo, length)``:
    ``cos(pi k (x - lo) / length)``, which together follow any smooth friction
    profile along the span.
    """

    harmonics: int
    stribeck_velocity: float | None
    profile: int = 0
    span: tuple[float, float] = (0.0, 1.0)

    def names(self) -> list[str]:
        out: list[str] = [TermKind.COULOMB, TermKind.VISCOUS, TermKind.ACCELERATION,
                          TermKind.OFFSET]
        if self.stribeck_velocity is not None:
            out.append(TermKind.STRIBECK)
        out += [f"{t}{k}" for k in range(1, self.harmonics + 1) for t in ("cos", "sin")]
        out += [f"pos{k}" for k in range(1, self.profile + 1)]
        return out

    def matrix(self, v: np.ndarray, a: np.ndarray, theta: np.ndarray | None) -> np.ndarray:
        cols = [np.sign(v), v, a, np.ones_like(v)]
        if self.stribeck_velocity is not None:
            cols.append(np.sign(v) * np.exp(-(v / self.stribeck_velocity) ** 2))
        th = theta if theta is not None else np.zeros_like(v)
        for k in range(1, self.harmonics + 1):
            cols += [np.cos(k * th), np.sin(k * th)]
        lo, length = self.span
        for k in range(1, self.profile + 1):
            cols.append(np.cos(math.pi * k * (np.clip(th, lo, lo + length) - lo) / length))
        return np.column_stack(cols)


def _fit(X: np.ndarray, Y: np.ndarray, w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:  # noqa: N803
    """Weighted least squares: coefficients and the weighted residuals."""
    sw = np.sqrt(w)[:, None]
    coef, *_ = np.linalg.lstsq(X * sw, Y * (sw if Y.ndim == 2 else sw[:, 0]), rcond=None)
    return coef, (Y - X @ coef)


def _jackknife(X: np.ndarray, y: np.ndarray, w: np.ndarray,  # noqa: N803
               groups: np.ndarray) -> np.ndarray:
    """Jackknife standard errors of the weighted fit, leaving out one group of probes at a time.

    The probes are noise-free and their residuals are the model's departures
    from the laws, correlated along each run: the textbook standard error
    treats them as independent samples and shrinks with their number. Leaving
    out each probe speed in turn (``groups``: its label; -1 is never left out)
    says instead how much the parameters hang on one part of the model's
    curve. NaN with fewer than three groups.
    """
    labels = np.unique(groups[groups >= 0])
    g = labels.size
    if g < 3:
        return np.full(X.shape[1], math.nan)
    coefs = np.array([_fit(X[groups != k], y[groups != k], w[groups != k])[0] for k in labels])
    return np.sqrt((g - 1) / g * np.sum((coefs - coefs.mean(axis=0)) ** 2, axis=0))


def _wrms(x: np.ndarray, w: np.ndarray) -> float:
    return float(np.sqrt(np.sum(w * x * x) / np.sum(w)))


def model_physics(
    comp: Compensator,
    roles: Sequence[str | None],
    ranges: MotionRange,
    *,
    axis: str = "rotary",
    bandwidth: float | None = None,
    data: Mapping[str, Any] | None = None,
    options: PhysicsOptions | None = None,
    lags: Mapping[str, float] | None = None,
) -> Physics:
    """Name the laws a model holds by driving it with probe motions.

    One long function on purpose: every law's test reads the one least-squares
    fit of the probes (coefficients, standard errors, row shares) through the
    closures ``share``, ``rel`` and ``consider``; apart, they would pass a dozen
    arrays each.

    Parameters
    ----------
    comp : Compensator
        The model.
    roles : sequence of str or None
        The role of each of ``comp``'s inputs (``angle``, ``angle_wrapped``,
        ``velocity``, ``acceleration``, or None).
    ranges : MotionRange
        The motion to probe over (:func:`ranges_from_data`, :func:`ranges_from_result`).
    axis : str
        ``"rotary"`` or ``"linear"``: the units, and whether angle harmonics are fitted.
    bandwidth : float, optional
        The observer's bandwidth ``g`` [rad/s]: its lag is taken out of the
        model's output. Without it the model's output is taken as it is (a
        target without lag).
    data : mapping, optional
        The reference motion the shares are measured on: ``velocity``,
        ``acceleration``, ``angle`` (or None), ``target`` (arrays of one length),
        and ``rows`` (shape (m, N): each row's output, un-lagged like the probes).
        Without it the shares are measured on the probes, against the model's RMS there.
    options : PhysicsOptions, optional
    lags : mapping of str to float, optional
        The lag of the velocity and acceleration inputs behind the motion
        (:func:`input_lags`, estimated on a log): the probes' signals lag alike.

    Returns
    -------
    Physics
    """
    from edm_sym.engines.simulate import simulate_rows

    opts = options or PhysicsOptions()
    units = axis_units(axis)
    ts = comp.sample_time
    rotary = axis == "rotary"
    notes = []
    settled: dict[str, dict[str, float]] | None = None
    settle = settling_time(comp, opts.max_settle)
    if ranges.hold is not None and settle > max(ranges.hold, 20 * ts):
        # The model's response at the time scales of the log it was fitted on: a filter
        # slower than the log's plateaus was fitted to their transients, and its steady
        # state on a longer hold is one the log never showed (docs/describe.md).
        settle = max(ranges.hold, 20 * ts)
        notes.append(f"a filter of the model settles slower than the log it was fitted on holds "
                     f"a speed ({settle:.3g} s): each run waited {settle:.3g} s, so the laws are "
                     "the model's response at the log's time scales, not a steady state the "
                     "log never showed")
        # The same model probed until it settles (at most max_settle): a law that reads
        # otherwise there hangs on how long a speed is held, and its error says so.
        settled = model_physics(comp, roles, replace(ranges, hold=None), axis=axis,
                                bandwidth=bandwidth, options=opts, lags=lags).named()
    elif settle >= opts.max_settle:
        notes.append(f"a filter of the model settles slower than {opts.max_settle:g} s "
                     f"(an integrator, or a pole near 1): each run waited {opts.max_settle:g} s")
    missing = [j for j, r in enumerate(roles) if r is None]
    if missing:
        notes.append("inputs without a physical role held at zero on the probes: "
                     + ", ".join(comp.matrix.inputs[j] for j in missing))
    if bandwidth is None:
        notes.append("no observer bandwidth: the target is taken as lag-free (its inertia is "
                     "not told from the observer's lag)")
    lags = {k: v for k, v in (lags or {}).items() if v > 0.1 * ts}
    if lags:
        notes.append("the probes' " + " and ".join(f"{k} lags by {1e3 * v:.3g} ms" for k, v in
                                                    sorted(lags.items()))
                     + ", as the log's own signals lag the angle's derivatives")
    runs = probe_runs(ranges, ts, settle, rotary=rotary, options=opts)
    ys, v, a, th, w, grp = [], [], [], [], [], []
    for run in runs:
        out = simulate_rows(comp, comp.matrix.rows, run_inputs(run, roles, lags, ts))
        if bandwidth is not None and out.shape[1] > 2:
            out = out + np.gradient(out, ts, axis=1) / bandwidth
        m = np.nonzero(run.steady)[0]
        if m.size > MAX_PER_RUN:  # evenly spaced: every run weighs alike anyway
            m = m[np.linspace(0, m.size - 1, MAX_PER_RUN).round().astype(int)]
        n = int(m.size)
        if n == 0:
            continue
        ys.append(out[:, m])
        v.append(run.velocity[m])
        a.append(run.acceleration[m])
        th.append(run.theta[m])
        w.append(np.full(n, 1.0 / n))
        grp.append(np.full(n, run.speed))
    Y = np.concatenate(ys, axis=1).T  # (n, m)  # noqa: N806
    V, A, TH, W, G = (np.concatenate(x) for x in (v, a, th, w, grp))  # noqa: N806
    y = Y.sum(axis=1)
    has_angle = any(r in ("angle", "angle_wrapped") for r in roles)
    harmonics = opts.max_harmonic if has_angle and rotary else 0
    profile, span = 0, (0.0, 1.0)
    if not has_angle:
        notes.append("no position input: no position-dependent law is fitted")
    elif not rotary and ranges.position is not None and ranges.position[1] > ranges.position[0]:
        profile = opts.profile
        span = (ranges.position[0], ranges.position[1] - ranges.position[0])
    if not (np.all(np.isfinite(Y))):
        raise ValueError("the model's output on the probes is not finite")
    # The Stribeck velocity: scanned; kept when it improves the fit and the hump is a hump.
    base = _Basis(harmonics, None, profile, span)
    coef0, res0 = _fit(base.matrix(V, A, TH), y, W)
    without = float(np.sum(W * res0 ** 2))
    best = (without, None, coef0)
    for vs in np.geomspace(ranges.slowest, ranges.velocity / 2.0, 24):
        basis = _Basis(harmonics, float(vs), profile, span)
        coef, res = _fit(basis.matrix(V, A, TH), y, W)
        ssr = float(np.sum(W * res ** 2))
        if coef[4] > 0 and ssr < 0.7 * without and ssr < best[0]:
            best = (ssr, float(vs), coef)
    ssr, vs, coef = best
    basis = _Basis(harmonics, vs, profile, span)
    X = basis.matrix(V, A, TH)  # noqa: N806
    names = basis.names()
    resid = y - X @ coef
    total = _wrms(y - np.sum(W * y) / np.sum(W), W)
    explained = 1.0 - (_wrms(resid, W) / total) ** 2 if total > 0 else 1.0
    # Relative standard errors (weighted; residual variance over the fit's dof).
    sw = np.sqrt(W)[:, None]
    dof = max(X.shape[0] - X.shape[1], 1)
    sigma2 = float(np.sum(W * resid ** 2)) / np.sum(W) * X.shape[0] / dof
    try:
        cov = np.linalg.pinv((X * sw).T @ (X * sw)) * sigma2 * np.sum(W) / X.shape[0]
        stderr = np.sqrt(np.maximum(np.diag(cov), 0.0))
    except np.linalg.LinAlgError:
        stderr = np.full(X.shape[1], math.nan)
    # The larger of that and the spread over the probe speeds (each left out in turn):
    # a model whose curve bends between the speeds is not described to a few per cent.
    stderr = np.fmax(stderr, _jackknife(X, y, W, G))
    # Each row on the same basis: its coefficients (they add up to the model's).
    row_coef, row_res = _fit(X, Y, W)
    # The reference motion the shares are measured on.
    if data is not None:
        rv, ra, rth = data["velocity"], data["acceleration"], data.get("angle")
        ref_rms = float(np.sqrt(np.mean(np.asarray(data["target"], dtype=float) ** 2)))
        rw = np.full(rv.size, 1.0 / rv.size)
    else:
        rv, ra, rth, rw = V, A, TH, W
        ref_rms = _wrms(y, W)
    if not (ref_rms > 0):
        ref_rms = 1.0
    RX = basis.matrix(rv, ra, rth if has_angle else None)  # noqa: N806
    idx = {n: i for i, n in enumerate(names)}
    harm_cols = [i for i, n in enumerate(names) if n[:3] in ("cos", "sin")]
    prof_cols = [i for i, n in enumerate(names) if n.startswith("pos")]

    def share(cols: list[int], c: np.ndarray) -> float:
        return _wrms(RX[:, cols] @ c[cols], rw) / ref_rms

    def rows_of(cols: list[int]) -> tuple[float, ...]:
        whole = RX[:, cols] @ coef[cols]
        denom = float(np.sum(rw * whole * whole))
        if not denom > 0:
            return ()
        return tuple(float(np.sum(rw * (RX[:, cols] @ row_coef[cols, j]) * whole) / denom)
                     for j in range(Y.shape[1]))

    def rel(i: int) -> float:
        return float(stderr[i] / abs(coef[i])) if coef[i] != 0 else math.inf

    fit_on_data = None
    if data is not None and data.get("model") is not None:
        model_out = np.asarray(data["model"], dtype=float)
        target_on_data = np.asarray(data["target"], dtype=float)
        # The static laws hold where the axis slides: the support is judged there.
        judged = sliding_rows(rv, ranges.slowest, 0 if bandwidth is None else
                              int(math.ceil(SLIDE_SETTLE / (bandwidth * ts))))
        if np.count_nonzero(judged) < SLIDE_MIN_SHARE * judged.size:
            judged = np.ones(judged.size, dtype=bool)
            notes.append(f"the data slides at {ranges.slowest:.3g} {units.velocity} or faster in "
                         f"under {100 * SLIDE_MIN_SHARE:g} % of its samples: the laws' support is "
                         "judged on every sample, reversals included")
        fit_on_data = float(np.sqrt(np.mean((target_on_data - model_out)[judged] ** 2)))

    def _unsupported(cols: list[int]) -> str:
        """Why the data does not support a law (empty when it does): on the sliding samples,
        the model without the law's term fits the target no worse than with it (by
        ``opts.support``)."""
        if fit_on_data is None or not fit_on_data > 0:
            return ""
        term = RX[:, cols] @ coef[cols]
        if bandwidth is not None and term.size > 1:
            term = lowpass(term, bandwidth, ts)
        without = float(np.sqrt(np.mean((target_on_data - model_out + term)[judged] ** 2)))
        if without >= (1.0 + opts.support) * fit_on_data:
            return ""
        return (f"the data does not support it: without its term the model fits the target "
                f"{'better' if without < fit_on_data else 'no worse'} where the axis slides "
                f"(RMSE {without:.4g} against {fit_on_data:.4g}, a rise under "
                f"{100 * opts.support:g} %)")

    terms: list[Law] = []
    left: list[tuple[TermKind, str]] = []
    th_ = opts.threshold
    of = "the target" if data is not None else "the model on the probes"

    def consider(kind: TermKind, cols: list[int], params: dict[str, tuple[float, str]],
                 errors: dict[str, float], bad_sign: str = "", extra: tuple = ()) -> None:
        s = share(cols, coef)
        if s < th_:
            left.append((kind, f"{_pct(s)} % of {of}, below the {100 * th_:g} % threshold"))
            return
        if bad_sign:
            left.append((kind, bad_sign))
            return
        unsupported = _unsupported(cols)
        if unsupported:
            left.append((kind, unsupported))
            return
        flags = list(extra)
        errors = dict(errors)
        waited = {}
        for k in errors:
            other = (settled or {}).get(kind.value, {}).get(k)
            value = params[k][0]
            if other is not None and value != 0:
                waited[k] = abs(other - value) / abs(value)
                errors[k] = max(errors[k], waited[k])
        for k, e in errors.items():
            if not e <= opts.uncertain:
                why = ("the law describes the model loosely" if waited.get(k, 0.0) < e else
                       "the model, held at a speed until it settles, reads "
                       f"{(settled or {})[kind.value][k]:.4g}: the law hangs on how long a speed is held")
                flags.append(("uncertain", f"{k.replace('_', ' ')}: relative standard error "
                                           f"{100 * e:.2g} % ({why})"))
        terms.append(Law(kind, params, s, errors, rows_of(cols), tuple(flags)))

    fc, d, j, c0 = (float(coef[idx[n]]) for n in (TermKind.COULOMB, TermKind.VISCOUS,
                                                                  TermKind.ACCELERATION, TermKind.OFFSET))
    consider(TermKind.COULOMB, [idx[TermKind.COULOMB]], {"level": (fc, units.force)},
             {"level": rel(idx[TermKind.COULOMB])},
             "" if fc > 0 else f"level {fc:.4g} {units.force}: a negative Coulomb level drives "
                               "the motion, not friction")
    if vs is None:
        left.append((TermKind.STRIBECK, f"no hump at low speed down to {ranges.slowest:.3g} "
                                        f"{units.velocity} (a Stribeck term lowers the residual "
                                        "by less than 30 %)"))
    else:
        fs = float(coef[idx[TermKind.STRIBECK]])
        if fc > 0 and fc + fs >= opts.stribeck_ratio * fc:
            consider(TermKind.STRIBECK, [idx[TermKind.STRIBECK]],
                     {"peak": (fs, units.force), "level_at_rest": (fc + fs, units.force),
                      "stribeck_velocity": (vs, units.velocity)},
                     {"peak": rel(idx[TermKind.STRIBECK])})
        else:
            left.append((TermKind.STRIBECK, f"level at rest {fc + fs:.4g} {units.force} is below "
                                            f"{opts.stribeck_ratio:g} x the Coulomb level"))
    consider(TermKind.VISCOUS, [idx[TermKind.VISCOUS]], {"coefficient": (d, units.viscous)},
             {"coefficient": rel(idx[TermKind.VISCOUS])},
             "" if d > 0 else f"coefficient {d:.4g} {units.viscous}: negative viscous friction "
                              "drives the motion")
    lag = (() if bandwidth is not None else
           (("lag_included", "no observer bandwidth: an observer's lag would show here as "
                             "-(viscous)/g"),))
    consider(TermKind.ACCELERATION, [idx[TermKind.ACCELERATION]], {"inertia": (j, units.inertia)},
             {"inertia": rel(idx[TermKind.ACCELERATION])}, extra=lag)
    consider(TermKind.OFFSET, [idx[TermKind.OFFSET]], {"value": (c0, units.force)}, {})
    if harm_cols:
        amp = np.hypot(coef[harm_cols[0::2]], coef[harm_cols[1::2]])
        k = int(np.argmax(amp)) + 1
        if rotary:
            cyc = ("cycles_per_revolution", (float(k), "1"))
        else:  # not reached: no harmonics on a linear axis
            cyc = ("cycles_per_metre", (k / TWO_PI, "1/m"))
        phase = float(math.atan2(coef[idx[f"cos{k}"]], coef[idx[f"sin{k}"]]))
        significant = [i + 1 for i, x in enumerate(amp) if x / math.sqrt(2) / ref_rms >= th_]
        grid = np.linspace(0, TWO_PI, 721)
        unit_basis = _Basis(harmonics, None, 0, span)
        curve = unit_basis.matrix(0 * grid, 0 * grid, grid)[:, 4:] @ coef[harm_cols]
        errs = {"amplitude": float(np.hypot(stderr[idx[f"cos{k}"]], stderr[idx[f"sin{k}"]])
                                   / amp[k - 1]) if amp[k - 1] > 0 else math.inf}
        consider(TermKind.SPATIAL, harm_cols,
                 {cyc[0]: cyc[1], "amplitude": (float(amp[k - 1]), units.force),
                  "phase": (phase, "rad"), "peak": (float(np.max(np.abs(curve))), units.force),
                  "harmonics": (float(len(significant)), "1")}, errs)
    if prof_cols:
        grid = np.linspace(span[0], span[0] + span[1], 401)
        curve = _Basis(0, None, profile, span).matrix(0 * grid, 0 * grid, grid)[:, 4:] @ coef[prof_cols]
        amp = np.abs(coef[prof_cols])
        k = int(np.argmax(amp)) + 1
        consider(TermKind.SPATIAL, prof_cols,
                 {"amplitude": (float(0.5 * (curve.max() - curve.min())), units.force),
                  "cycles_per_metre": (k / (2.0 * span[1]), "1/m"),
                  "span": (span[1], units.position)}, {})
    terms.sort(key=lambda t: list(TermKind).index(t.kind))
    # Rows: their share of each named law, and what no law explains.
    named_cols = {k: [idx[k]] for k in (TermKind.COULOMB, TermKind.VISCOUS, TermKind.ACCELERATION,
                                        TermKind.OFFSET)}
    named_cols[TermKind.SPATIAL] = harm_cols or prof_cols
    if vs is not None:
        named_cols[TermKind.STRIBECK] = [idx[TermKind.STRIBECK]]
    behaviours = []
    for jr in range(Y.shape[1]):
        laws = {t.kind.value: t.rows[jr] for t in terms if t.rows and abs(t.rows[jr]) >= ROW_SHARE}
        probe_left = _wrms(row_res[:, jr], W) / ref_rms
        data_left = 0.0
        if data is not None and data.get("rows") is not None:
            # On the data only what the row does mostly outside the laws counts: the
            # measured velocity's noise at a reversal moves a relay off sgn(v) too.
            own = np.asarray(data["rows"][jr], dtype=float)
            off = float(np.sqrt(np.mean((own - RX @ row_coef[:, jr]) ** 2)))
            own_rms = float(np.sqrt(np.mean(own ** 2)))
            data_left = off / ref_rms if off >= DATA_UNEXPLAINED * own_rms else 0.0
        left_share = max(probe_left, data_left)
        reason = ""
        if left_share >= th_:
            role = roles[comp.matrix.rows[jr].input]
            if data_left >= th_ and data_left > 2 * probe_left and role == "angle":
                reason = (f"{100 * data_left:.2g} % of the target on the data that no law explains, "
                          "a function of the absolute angle that does not repeat over a "
                          "revolution: a clock of the run (the start from rest), not physics")
            elif data_left > probe_left:
                reason = (f"{100 * data_left:.2g} % of the target on the data that no law "
                          "explains (a transient or a dynamic the steady probes do not show)")
            else:
                where = of if of.endswith("on the probes") else f"{of} on the probes"
                reason = f"{100 * probe_left:.2g} % of {where} that no law explains"
        behaviours.append(RowBehaviour(jr + 1, laws, left_share, reason))
    return Physics(tuple(terms), tuple(left), float(explained), tuple(behaviours), ranges,
                   bandwidth, tuple(notes), "target" if data is not None else "probes")


def physics_on_log(
    comp: Compensator,
    roles: Sequence[str | None],
    *,
    x: np.ndarray,
    rows: np.ndarray,
    target: np.ndarray,
    ts: float,
    source: str,
    axis: str = "rotary",
    bandwidth: float | None = None,
    part: slice | np.ndarray = slice(None),
    fallback: MotionRange | None = None,
    options: PhysicsOptions | None = None,
    fitted: bool = False,
) -> Physics | None:
    """:func:`model_physics` over a log's motion, its shares measured on ``part`` of it.

    The velocity is the ``velocity`` input, else the angle differentiated; the
    acceleration the ``acceleration`` input, else the velocity differentiated;
    the angle the ``angle`` input, else the wrapped one. Derivatives are taken
    on the whole log before ``part`` is cut (held-out blocks joined end to end
    would give a spike at every join). ``edm describe``, the report and the
    closing summary all call this.

    Parameters
    ----------
    comp : Compensator
    roles : sequence of str or None
        The role of each of ``comp``'s inputs.
    x : numpy.ndarray
        Shape (n_inputs, N): the inputs on the log, in ``comp``'s order.
    rows : numpy.ndarray
        Shape (m, N): each row's output on the log (the observer's lag is taken
        out here when ``bandwidth`` is given).
    target : numpy.ndarray
        Shape (N,).
    ts : float
        Sample time [s].
    source : str
        The log, for the ranges' ``source``.
    axis, bandwidth, options
        As for :func:`model_physics`.
    part : slice or numpy.ndarray
        The samples the shares are measured on (the held-out rows).
    fallback : MotionRange, optional
        The ranges result.json records (:func:`ranges_from_result`): probed over
        when the log has no motion (no velocity or angle input); otherwise its
        slowest speed, the speed the model was fitted down to, lowers the
        probes' slowest when it is slower than this log's (down to a
        two-hundredth of this log's fastest), and its hold, the longest time
        the model's log held a speed, limits the probes' wait instead of this
        log's.
    fitted : bool, default False
        The log is the one the model was fitted on (``edm abstract``'s summary):
        its own hold limits the probes' wait. Otherwise only a recorded hold
        (``fallback``) does; without one the probes wait as long as the model
        needs (at most ``options.max_settle``).

    Returns
    -------
    Physics or None
        None when there is no motion to probe over.
    """
    motion = motion_signals(list(x), roles, ts)
    if motion is None:
        return None if fallback is None else model_physics(
            comp, roles, fallback, axis=axis, bandwidth=bandwidth, options=options)
    vel, acc = motion
    by_role = {r: np.asarray(v, dtype=float) for v, r in zip(x, roles, strict=True) if r}
    angle = by_role.get("angle", by_role.get("angle_wrapped"))
    ranges = ranges_from_data(vel, acc, angle, source, ts)
    if ranges is None:
        ranges = fallback
    else:
        # The time scale is the log's the model was fitted on: this one when it is that
        # log, else what result.json records (None in a result written before: no limit).
        if not fitted:
            ranges = replace(ranges, hold=None if fallback is None else fallback.hold)
        if fallback is not None and fallback.slowest < ranges.slowest:
            ranges = replace(ranges, slowest=max(fallback.slowest, ranges.velocity / 200.0))
    if ranges is None:
        return None
    out = np.asarray(rows, dtype=float)
    if bandwidth is not None and out.shape[1] > 2:
        out = out + np.gradient(out, ts, axis=1) / bandwidth
    whole_out = np.asarray(rows, dtype=float).sum(axis=0)
    data = {"velocity": vel[part], "acceleration": acc[part],
            "angle": None if angle is None else angle[part],
            "target": np.asarray(target, dtype=float)[part], "rows": out[:, part],
            "model": np.asarray(rows, dtype=float).sum(axis=0)[part]}
    phys = model_physics(comp, roles, ranges, axis=axis, bandwidth=bandwidth, data=data,
                         options=options, lags=input_lags(x, roles, ts))
    if "angle" in by_role:
        unwrapped = by_role["angle"]
    elif "angle_wrapped" in by_role:
        unwrapped = np.unwrap(by_role["angle_wrapped"])
    else:
        return phys
    return inertia_on_data(phys, unwrapped, whole_out, ts, axis=axis, options=options)


def inertia_on_data(phys: Physics, angle: np.ndarray, model_out: np.ndarray, ts: float, *,
                    axis: str = "rotary", options: PhysicsOptions | None = None) -> Physics:
    """``phys`` with its named inertia measured on the log's own motion.

    The inertia a model holds depends on the accelerations it is driven with:
    a row on the acceleration through a filter, a dead zone or a saturation
    gives another gain on the probes' constant accelerations than on the
    log's. On a log the acceleration the plant meets is the log's, so there
    the inertia is the engineer's least squares
    (:func:`edm_sym.engines.plant.anchor.fit_anchor`: sign, velocity,
    acceleration, offset, the named Stribeck hump and angle harmonics, each
    through the observer's low-pass, the reversals left out) of the model's
    own output on the log. The probes' value stays in the law's flags. The
    law's share is scaled by the same ratio; under ``options.threshold`` the
    law is left out (``left_out``, with both values) and no row lists it.

    Parameters
    ----------
    phys : Physics
        :func:`model_physics` of the model with the log as data.
    angle : numpy.ndarray
        The unwrapped angle (position) over the whole log.
    model_out : numpy.ndarray
        The model's output over the whole log (the observer's lag in it).
    ts : float
    axis : str
    options : PhysicsOptions, optional
        Its ``max_harmonic``: the angle harmonics fitted beside the inertia.

    Returns
    -------
    Physics
    """
    from edm_sym.engines.plant.anchor import fit_anchor

    law = next((t for t in phys.terms if t.kind is TermKind.ACCELERATION), None)
    if law is None or angle.size < 16:
        return phys
    stribeck = next((t for t in phys.terms if t.kind is TermKind.STRIBECK), None)
    vs = stribeck.parameters["stribeck_velocity"][0] if stribeck is not None else None
    g = phys.bandwidth if phys.bandwidth is not None else 1e12  # no observer: no lag
    fit = fit_anchor({"theta_uw": angle, "tau_ext": model_out}, g_rtob=g, ts=ts,
                     stribeck_velocity=vs,
                     harmonics=range(1, (options or PhysicsOptions()).max_harmonic + 1) if axis == "rotary"
                     else (), min_speed=phys.ranges.slowest)
    old, unit = law.parameters["inertia"]
    if not (math.isfinite(fit.inertia) and old != 0 and fit.inertia * old > 0):
        return phys  # the log cannot tell it (or tells another sign): the probes' value stays
    share = law.share * abs(fit.inertia / old)
    threshold = (options or PhysicsOptions()).threshold
    if share < threshold:
        # Measured where the plant moves, the term is too small to name: it was the
        # probes' constant accelerations that made it look like one.
        reason = (f"{_pct(share)} % of the target measured on the log's motion ({fit.inertia:.4g} "
                  f"{unit}; on the probes {old:.4g} {unit}), below the {100 * threshold:g} % "
                  "threshold")
        kind = TermKind.ACCELERATION.value
        rows = tuple(replace(r, laws={k: v for k, v in r.laws.items() if k != kind})
                     for r in phys.rows)
        return replace(phys, terms=tuple(t for t in phys.terms if t is not law),
                       left_out=(*phys.left_out, (TermKind.ACCELERATION, reason)), rows=rows)
    note = ("on_data", f"measured on the log's motion (least squares of the model's output); "
                       f"on the probes {old:.4g} {unit}")
    new = replace(law, parameters={**law.parameters, "inertia": (fit.inertia, unit)},
                  share=share, flags=(*law.flags, note))
    return replace(phys, terms=tuple(new if t is law else t for t in phys.terms))
