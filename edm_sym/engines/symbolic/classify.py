"""Physical terms of a row: what its simplified numeric expression means, in SI units.

A row's simplified expression (with numbers) is split into its additive terms.
Each term is ``c f(w)`` with one *leaf* ``w``: the input itself, or the input
through transfer functions and delays. A transfer function ``s^k H(s)`` moves
the leaf's role k steps along angle -> velocity -> acceleration (an integral
moves it back) with the low-frequency gain ``H(0)``; the poles of ``H`` are
reported as filter corners. Then, by the leaf's role (the units are a rotary
axis's; on a linear axis they read N, N s/m, kg, m and m/s, and a spatial
term's frequency is given in cycles per metre, ``ClassifyOptions.axis``):

========================  ===========================================  ============
pattern                   term                                         parameters
========================  ===========================================  ============
``c``                     offset                                       level [N m]
``c v``                   viscous friction                             N m s/rad
``c sign(v)``             Coulomb friction                             level [N m]
``c tanh(k v)`` and       Coulomb friction when the transition         level, transition
``atan``, ``Sat``,        velocity (level / slope at 0) is at most     velocity [rad/s]
``Relay``                 ``coulomb_velocity``                         (hysteresis)
``c a`` or ``c s v``      acceleration-dependent (inertia)             kg m^2, corner
``c tanh(k a)``, ...      saturating acceleration-dependent term       kg m^2, N m
``F(sin(k q + phi))``     position-dependent (spatial) friction        amplitude, period,
                                                                       cycles/rev, phase
odd hump in v             Stribeck-like                                peak, velocities
========================  ===========================================  ============

``LTI(f(v), G)`` with a finite ``G(0)`` is classified as ``G(0) f(v)``, the
filter noted; an odd velocity function that fits ``Fc sign(v) + D v`` over the
velocity range to 0.1 % gives those two terms (noted as fitted).

A term no exact pattern fits is measured on its *static characteristic*
(:mod:`edm_sym.engines.symbolic.characteristic`), which makes the classification hold
for the nested rows the genetic algorithm finds:

* position-dependent (``spatial``): any non-constant term of the wrapped angle,
  and a term of the unwrapped angle whose every occurrence of the angle sits in
  ``sin/cos/tan(k q + c)`` with whole multiples ``k`` of a common fundamental
  (``harmonic_tolerance``); filters count with their DC gain, delays as
  identity; amplitude (half peak-to-peak), period, cycles per revolution and
  the fundamental's phase come from one period of that characteristic;
* acceleration-dependent: a term whose input reaches acceleration (or, through
  a band pass, beyond) along every path; filters count with their gain at
  ``acceleration_frequency``, and the equivalent inertia is the least-squares
  slope over ``+-acceleration_range`` (R^2 reported; below 0.95 the term is
  called nonlinear), with the filters' phase and pass band.

A term that fits none of these is ``"unclassified"`` with the reason.
"""

from __future__ import annotations

import cmath
import math
from collections.abc import Mapping
from dataclasses import dataclass, field, replace

import numpy as np
import sympy as sp

from edm_sym.core.terms import TermKind
from edm_sym.core.units import AxisUnits, axis_units
from edm_sym.engines.symbolic.characteristic import (
    acceleration_gain,
    corners,
    describe_operators,
    measure_acceleration,
    measure_periodic,
    measure_velocity,
    response,
    s_power,
    tf_coefficients,
)
from edm_sym.engines.symbolic.functions import NUMPY_FUNCTIONS, Sat
from edm_sym.engines.symbolic.operators import LTI, Delay, Relay
from edm_sym.engines.symbolic.simplify import fold_constants

#: The kinds of physical term.
KINDS = (TermKind.COULOMB, TermKind.VISCOUS, TermKind.ACCELERATION, TermKind.SPATIAL,
         TermKind.STRIBECK, TermKind.OFFSET, TermKind.UNCLASSIFIED)

_CHAIN = ("angle", "velocity", "acceleration")


@dataclass(frozen=True)
class PhysicalTerm:
    """One physical term of a row.

    Attributes
    ----------
    kind : TermKind
        One of :data:`KINDS` (a string given is made one).
    parameters : dict of str to (float, str)
        Name -> (value, SI unit).
    description : str
        One readable line; for ``"unclassified"`` the reason.
    expr : sympy.Expr or None
        The term of the row expression this describes.
    """

    kind: TermKind
    parameters: Mapping[str, tuple[float, str]] = field(default_factory=dict)
    description: str = ""
    expr: sp.Expr | None = field(default=None, compare=False)

    def __post_init__(self) -> None:
        if not isinstance(self.kind, TermKind):
            object.__setattr__(self, "kind", TermKind(self.kind))


#: Default thresholds per axis, in its units (rotary: the field defaults of
#: ClassifyOptions): a rotary motor axis turns at up to some 10 rad/s, a linear
#: (ball-screw) axis moves at up to some 0.5 m/s; the Coulomb threshold is 2.5 %
#: of that range on both, the acceleration range 100 or 20 times it.
AXIS_DEFAULTS: dict[str, dict[str, float]] = {
    "rotary": {},  # the field defaults below
    "linear": {"coulomb_velocity": 0.0125, "velocity_range": 0.5, "acceleration_range": 10.0},
}


@dataclass(frozen=True)
class ClassifyOptions:
    """Thresholds of the classification.

    Every threshold is in the SI units of ``axis`` (rad or m); the defaults
    are a rotary axis's, :meth:`for_axis` gives those of a linear one.

    Parameters
    ----------
    axis : str, default "rotary"
        ``"rotary"`` or ``"linear"``: the units of the terms' parameters
        (:func:`edm_sym.core.units.axis_units`) and of the thresholds below.
    coulomb_velocity : float, default 0.25 (linear: 0.0125)
        [rad/s or m/s] A saturating function of velocity counts as Coulomb friction
        when its level divided by its slope at the origin is at most this
        velocity (``tanh(k v)``: 1/k; ``atan(k v)``: pi/(2k)). A servo log
        sampled at 1 ms moves its velocity by about that much per sample at
        a few hundred rad/s^2, so a transition below it cannot be told from
        a step.
    velocity_range : float, default 10.0 (linear: 0.5)
        [rad/s or m/s] The velocities over which shapes are judged (Stribeck-like
        humps, Coulomb + viscous fits).
    acceleration_frequency : float, default 4 pi (2 Hz)
        [rad/s] The representative frequency of a filtered acceleration-dependent
        term that fits no exact pattern: its transfer functions count with their
        gain here (about the geometric middle of a 0.2 - 20 Hz excitation).
    acceleration_range : float, default 1000.0 (linear: 10.0)
        [rad/s^2 or m/s^2] The accelerations, ``[-range, range]``, over which such a
        term's static characteristic is fitted by a line (its slope is the
        equivalent inertia).
    harmonic_tolerance : float, default 0.01
        A term of the unwrapped angle whose angle enters only through
        ``sin/cos/tan(k q + c)`` is periodic when every ``k`` is within this of
        a whole multiple of a common fundamental.
    """

    axis: str = "rotary"
    coulomb_velocity: float = 0.25
    velocity_range: float = 10.0
    acceleration_frequency: float = 4 * math.pi
    acceleration_range: float = 1000.0
    harmonic_tolerance: float = 0.01

    @classmethod
    def for_axis(cls, axis: str = "rotary") -> ClassifyOptions:
        """The default thresholds of an axis (:data:`AXIS_DEFAULTS`)."""
        try:
            return cls(axis=axis, **AXIS_DEFAULTS[axis])
        except KeyError:
            raise ValueError(f"axis: expected one of {', '.join(AXIS_DEFAULTS)}, "
                             f"found {axis!r}") from None

    @property
    def units(self) -> AxisUnits:
        """The SI units of the axis."""
        return axis_units(self.axis)

    def __post_init__(self) -> None:
        if self.axis not in AXIS_DEFAULTS:
            raise ValueError(f"axis: expected one of {', '.join(AXIS_DEFAULTS)}, found {self.axis!r}")
        for name in ("coulomb_velocity", "velocity_range", "acceleration_frequency",
                     "acceleration_range", "harmonic_tolerance"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
                raise ValueError(f"{name}: expected a positive number, found {v!r}")
        if self.harmonic_tolerance >= 0.5:
            raise ValueError("harmonic_tolerance: expected a number below 0.5, found "
                             f"{self.harmonic_tolerance!r}")


@dataclass(frozen=True)
class _Leaf:
    role: str | None
    gain: float
    notes: tuple[str, ...] = ()
    corners: tuple[float, ...] = ()
    delay: float = 0.0


def _tf_split(G: sp.Expr) -> tuple[int, float, tuple[float, ...]] | None:  # noqa: N803
    """``G = s^k H`` -> (k, H(0), |poles of H|); None when G is not numeric."""
    tf = tf_coefficients(G)
    if tf is None:
        return None
    n, d = (np.trim_zeros(c, "b") for c in tf)
    return s_power(tf), _h0(tf), corners((n, d))


def _h0(tf: tuple[np.ndarray, np.ndarray]) -> float:
    """``H(0)`` for ``G = s^k H`` given by its coefficients."""
    n, d = (np.trim_zeros(c, "b") for c in tf)
    return float(n[-1] / d[-1])


def _leaf(e: sp.Expr, u: sp.Symbol, role: str | None) -> _Leaf | None:
    """The leaf description when ``e`` is the input through LTIs and delays only."""
    if e == u:
        return _Leaf(role, 1.0)
    if isinstance(e, Delay) and e.args[1].is_Number:
        inner = _leaf(e.args[0], u, role)
        if inner is None:
            return None
        return _Leaf(inner.role, inner.gain, inner.notes, inner.corners,
                     inner.delay + float(e.args[1]))
    if isinstance(e, LTI):
        inner = _leaf(e.args[0], u, role)
        split = _tf_split(e.args[1])
        if inner is None or split is None:
            return None
        k, h0, corners = split
        notes = list(inner.notes)
        new_role = inner.role
        if inner.role == "angle_wrapped" and k > 0:
            notes.append("differentiates the wrapped angle, which jumps at each wrap")
            new_role = "angle"
        if new_role in _CHAIN and k:
            i = _CHAIN.index(new_role) + k
            new_role = _CHAIN[i] if 0 <= i < len(_CHAIN) else None
        elif k:
            new_role = None
        return _Leaf(new_role, inner.gain * h0, tuple(notes), inner.corners + corners,
                     inner.delay)
    return None


def _shifted(e: sp.Expr, w: float) -> bool:
    """Whether the filters of a leaf shift it by more than 45 deg at ``w`` against DC.

    Each ``LTI`` counts as ``G(j w) / ((j w)^k H(0))`` for ``G = s^k H``: its
    derivatives are the leaf's change of role, not a shift.
    """
    rel = 1.0 + 0.0j
    for node in sp.preorder_traversal(e):
        if isinstance(node, LTI):
            tf = tf_coefficients(node.args[1])
            if tf is None:
                return False
            rel *= complex(response(tf, w)) / ((1j * w) ** s_power(tf) * _h0(tf))
    return abs(cmath.phase(rel)) > math.pi / 4


def _leaves(e: sp.Expr, u: sp.Symbol, role: str | None, out: dict) -> None:
    lf = _leaf(e, u, role)
    if lf is not None:
        out[e] = lf
        return
    for a in e.args:
        if a.has(u):
            _leaves(a, u, role, out)


def _extras(leaf: _Leaf) -> tuple[dict[str, tuple[float, str]], str]:
    params: dict[str, tuple[float, str]] = {}
    notes = list(leaf.notes)
    if leaf.corners:
        if len(leaf.corners) == 1:
            params["corner"] = (leaf.corners[0], "rad/s")
        else:
            for i, c in enumerate(leaf.corners, 1):
                params[f"corner_{i}"] = (c, "rad/s")
        notes.append("through a filter with corner(s) "
                     + ", ".join(f"{c:.4g}" for c in leaf.corners) + " rad/s")
    if leaf.delay:
        params["delay"] = (leaf.delay, "s")
        notes.append(f"delayed by {leaf.delay:.4g} s")
    return params, ("; " + "; ".join(notes)) if notes else ""


#: A term linear in a velocity or an acceleration: (kind, parameter, unit attribute, name).
_LINEAR = {
    "velocity": (TermKind.VISCOUS, "coefficient", "viscous", "viscous friction"),
    "acceleration": (TermKind.ACCELERATION, "inertia", "inertia", "acceleration-dependent term"),
}


def classify_expression(
    expr: sp.Expr, u: sp.Symbol, role: str | None, *, options: ClassifyOptions | None = None,
    axis: str | None = None,
) -> tuple[PhysicalTerm, ...]:
    """Split a numeric row expression into physical terms.

    Parameters
    ----------
    expr : sympy.Expr
        The row's simplified expression with numbers.
    u : sympy.Symbol
        The row's input symbol.
    role : str or None
        The input's role (see :mod:`edm_sym.engines.symbolic.roles`).
    options : ClassifyOptions, optional
        Default: ``ClassifyOptions.for_axis(axis)``.
    axis : str, optional
        ``"rotary"`` or ``"linear"``; overrides ``options.axis`` (the units of
        the parameters). Default: ``options.axis``, else rotary.

    Returns
    -------
    tuple of PhysicalTerm
    """
    if options is None:
        opts = ClassifyOptions.for_axis(axis or "rotary")
    else:
        opts = options if axis is None or axis == options.axis else replace(options, axis=axis)
    out: list[PhysicalTerm] = []
    for term in sp.Add.make_args(expr):
        found = _classify_term(term, u, role, opts)
        if role is not None and len(found) == 1 and found[0].kind is TermKind.UNCLASSIFIED:
            found = _measured(term, u, role, opts) or found
        out += found
    return tuple(out)


def _classify_term(term: sp.Expr, u: sp.Symbol, role: str | None,
                   opts: ClassifyOptions) -> list[PhysicalTerm]:
    if term.is_zero:
        return []
    if not term.has(u):
        return [_offset(term, opts.units)]
    if role is None:
        return [_unclassified(term, f"input {u.name!r} has no physical role "
                              f"(pass roles={{{u.name!r}: 'velocity'}} or another role)")]
    c, core = term.as_coeff_Mul()
    c = float(c)
    # A nonlinear function filtered afterwards: classify its low-frequency part.
    if isinstance(core, LTI) and _leaf(core, u, role) is None:
        split = _tf_split(core.args[1])
        if split is None:
            return [_unclassified(term, f"a transfer function that is not numeric: {core}")]
        k, h0, corners = split
        if k == 0:
            note = ("; through a filter with corner(s) "
                    + ", ".join(f"{x:.4g}" for x in corners) + " rad/s") if corners else ""
            return [_annotate(t, note, corners, term)
                    for t in _classify_term(c * h0 * core.args[0], u, role, opts)]
        return [_unclassified(term, "a nonlinear function of the input, then differentiated "
                              "or integrated")]
    if isinstance(core, Delay) and _leaf(core, u, role) is None and core.args[1].is_Number:
        T = float(core.args[1])
        return [_annotate(t, f"; delayed by {T:.4g} s", (), term, delay=T)
                for t in _classify_term(c * core.args[0], u, role, opts)]
    found: dict[sp.Expr, _Leaf] = {}
    _leaves(core, u, role, found)
    if len(found) != 1:
        return [_unclassified(term, f"the input enters through {len(found)} different paths")]
    (leaf_expr, leaf), = found.items()
    if leaf.role is None:
        return [_unclassified(term, "a derivative or integral of the input beyond "
                              "angle, velocity and acceleration")]
    w = sp.Dummy("w", real=True)
    f = core.xreplace({leaf_expr: w})
    extra, note = _extras(leaf)
    if leaf.role == "acceleration" and leaf.corners and _shifted(
            leaf_expr, opts.acceleration_frequency):
        # A filtered acceleration (c H(s) a, c s H(s) v) whose filters shift it by more
        # than 45 deg at acceleration_frequency: there its DC gain says little (it can even
        # have the other sign), so its filters count with their gain there, as in a
        # measured acceleration term; saturated (c tanh(k H(s) a)), so does its slope.
        if f == w:
            found = _measured_acceleration(term, u, role, opts)
            if found:
                return found
        elif _saturation(f, w) is not None:
            wa = opts.acceleration_frequency
            at = acceleration_gain(leaf_expr, u, _INDEX[role], wa)
            if at is not None:
                extra = {**extra, "frequency": (wa, "rad/s"), "filter_phase": (at[1], "rad")}
                note += (f"; the filters taken with their gain at {wa:.4g} rad/s, where they "
                         f"shift it by {math.degrees(at[1]):.3g} deg")
                leaf = replace(leaf, gain=at[0])
    return _match(term, c, f, w, leaf, extra, note, opts)


def _match(term: sp.Expr, c: float, f: sp.Expr, w: sp.Dummy, leaf: _Leaf,
           extra: dict, note: str, opts: ClassifyOptions) -> list[PhysicalTerm]:
    g, role, U = leaf.gain, leaf.role, opts.units
    if f == w:
        if role in _LINEAR:
            kind, pname, attr, what = _LINEAR[role]
            v, unit = c * g, getattr(U, attr)
            return [PhysicalTerm(kind, {pname: (v, unit), **extra},
                                 f"{what}: {v:.6g} {unit}{note}", term)]
        stiff = f"{U.force}/{U.position}"
        return [_unclassified(term, f"linear in the {_moved(U)}: a stiffness of {c * g:.6g} {stiff}, "
                              "not a friction term" + note, {"stiffness": (c * g, stiff)})]
    if role == "velocity":
        hit = _coulomb(term, c, f, w, g, extra, note, opts)
        if hit is not None:
            return hit
    if role == "acceleration":
        hit = _saturating_acceleration(term, c, f, w, g, extra, note, U)
        if hit is not None:
            return hit
    if role in ("angle", "angle_wrapped"):
        hit = _spatial(term, c, f, w, g, role, extra, note, U)
        if hit is not None:
            return hit
    if role == "velocity" and not f.has(LTI, Delay, Relay):
        return _velocity_shape(term, c, f, w, g, extra, note, opts)
    return [_unclassified(term, f"no physical pattern for {term} ({role} input)" + note)]


def _coulomb(term: sp.Expr, c: float, f: sp.Expr, w: sp.Dummy, g: float, extra: dict,
             note: str, opts: ClassifyOptions) -> list[PhysicalTerm] | None:
    sg = math.copysign(1.0, g)
    F, V = opts.units.force, opts.units.velocity
    if f == sp.sign(w):
        level = c * sg
        return [PhysicalTerm(TermKind.COULOMB, {"level": (level, F), **extra},
                             f"Coulomb friction: {level:.6g} {F} sgn(velocity){note}", term)]
    if isinstance(f, Relay) and f.args[0] == w and f.args[1].is_Number:
        level, band = c * sg, float(f.args[1]) / abs(g)
        return [PhysicalTerm(TermKind.COULOMB, {"level": (level, F),
                                         "hysteresis": (band, V), **extra},
                             f"Coulomb friction with hysteresis: {level:.6g} {F}, switching "
                             f"at +-{band:.4g} {V}{note}", term)]
    sat = _saturation(f, w)
    if sat is None:
        return None
    name, top, k = sat
    level, vt = c * top * math.copysign(1.0, k * g), top / abs(k * g)
    if vt <= opts.coulomb_velocity:
        return [PhysicalTerm(TermKind.COULOMB, {"level": (level, F),
                                         "transition_velocity": (vt, V), **extra},
                             f"Coulomb friction ({name}-smoothed): {level:.6g} {F}, "
                             f"transition {vt:.4g} {V}{note}", term)]
    return [_unclassified(term, f"a saturating function of velocity ({name}, level "
                          f"{level:.4g} {F}) whose transition velocity {vt:.4g} {V} is above "
                          f"the Coulomb threshold {opts.coulomb_velocity:g} {V}" + note,
                          {"level": (level, F), "transition_velocity": (vt, V)})]


def _saturation(f: sp.Expr, w: sp.Dummy) -> tuple[str, float, float] | None:
    """``f = F(k w)`` with F = tanh, atan or a symmetric Sat -> (name, F's level, k).

    The level is the limit of F (1, pi/2, the saturation bound); ``F`` has slope
    1 at the origin, so ``level / k`` is where the function's tangent meets its level.
    """
    if isinstance(f, (sp.tanh, sp.atan)):
        k = _linear_coeff(f.args[0], w)
        if k is not None:
            return f.func.__name__, (1.0 if isinstance(f, sp.tanh) else math.pi / 2), k
    elif isinstance(f, Sat) and f.args[1].is_Number and f.args[2].is_Number and (
            f.args[1] + f.args[2]).is_zero and f.args[2] > 0:
        k = _linear_coeff(f.args[0], w)
        if k is not None:
            return "Sat", float(f.args[2]), k
    return None


def _saturating_acceleration(term: sp.Expr, c: float, f: sp.Expr, w: sp.Dummy, g: float,
                             extra: dict, note: str, U: AxisUnits) -> list[PhysicalTerm] | None:  # noqa: N803
    sat = _saturation(f, w)
    if sat is None:
        return None
    name, top, k = sat
    inertia, level = c * k * g, c * top * math.copysign(1.0, k * g)
    return [PhysicalTerm(TermKind.ACCELERATION, {"inertia": (inertia, U.inertia),
                                          "saturation_level": (level, U.force), **extra},
                         f"saturating acceleration-dependent term ({name}): {inertia:.6g} "
                         f"{U.inertia} for small accelerations, limited to {level:.6g} "
                         f"{U.force}{note}", term)]


def _linear_coeff(arg: sp.Expr, w: sp.Dummy) -> float | None:
    """k when ``arg == k w`` with a number k."""
    k = arg / w
    if k.is_Number and not k.is_zero:
        return float(k)
    return None


def _sine_of(f: sp.Expr, w: sp.Dummy) -> tuple[sp.Expr, float, float] | None:
    """``f = F(sin(k w + phi))`` -> (sine subexpression, k, phi)."""
    inner = set()
    for a in sp.preorder_traversal(f):
        if isinstance(a, (sp.sin, sp.cos)) and a.has(w):
            phi, kw = a.args[0].as_independent(w, as_Add=True)
            k = _linear_coeff(kw, w)
            if k is not None and phi.is_Number:
                inner.add((a, k, phi))
    if len(inner) != 1:
        return None
    (sn, k, phi), = inner
    phi = float(phi) + (math.pi / 2 if isinstance(sn, sp.cos) else 0.0)
    if f.xreplace({sn: sp.Dummy()}).has(w):
        return None
    return sn, k, phi


def _wrap(phi: float) -> float:
    return math.remainder(phi, 2 * math.pi)


def _spatial(term: sp.Expr, c: float, f: sp.Expr, w: sp.Dummy, g: float, role: str,
             extra: dict, note: str, U: AxisUnits) -> list[PhysicalTerm] | None:  # noqa: N803
    found = _sine_of(f, w)
    if found is None:
        return None
    sn, k, phi = found
    k = k * g
    amp = c
    dominant: dict[str, tuple[float, str]] = {}
    if isinstance(sn, sp.sin) and f == sn or isinstance(sn, sp.cos) and f == sn:
        if k < 0:
            k, phi, amp = -k, -phi, -amp
        if amp < 0:
            amp, phi = -amp, phi + math.pi
        shape = "sinusoidal"
    elif not f.has(LTI, Delay, Relay):
        # A function of one sinusoid: periodic with the same period; measure it.
        z = sp.Dummy("z")
        F = sp.lambdify(z, c * f.xreplace({sn: z}), modules=[NUMPY_FUNCTIONS, "numpy"])
        with np.errstate(all="ignore"):
            vals = np.asarray(F(np.sin(np.linspace(0, 2 * np.pi, 721))), dtype=float)
        amp = float(np.ptp(vals * np.ones(721)) / 2)
        if not math.isfinite(amp):
            return None
        k = abs(k)
        shape = f"periodic, non-sinusoidal ({f})"
        # F(sin) holds harmonics of k: sin(3.7 sin q) is mostly 3 cycles/rev.
        with np.errstate(all="ignore"):
            y = np.asarray(F(np.sin((np.arange(720) + 0.5) * (2 * np.pi / 720))),
                           dtype=float) * np.ones(720)
        mag = np.abs(np.fft.rfft(y))[1:] if np.all(np.isfinite(y)) else np.zeros(1)
        top = int(np.argmax(mag)) + 1
        if top > 1:
            _, strongest, per_unit = spatial_frequency(top * k, U)
            dominant = {"dominant_cycles": strongest,
                        "dominant_amplitude": (float(2 * mag[top - 1] / y.size), U.force)}
            shape += f", strongest harmonic {strongest[0]:.6g} {per_unit}"
    else:
        return None
    phi = _wrap(phi)
    key, cycles, per = spatial_frequency(k, U)
    params = {"amplitude": (amp, U.force), "period": (2 * math.pi / k, U.position),
              key: cycles, "phase": (phi, "rad"), **dominant, **extra}
    wrap_note = ""
    if role == "angle_wrapped" and abs(k - round(k)) > 1e-9:
        per_wrap = "revolution" if U.axis == "rotary" else "wrap of the position"
        wrap_note = f"; not a whole number of cycles per {per_wrap}: it jumps at each wrap"
    return [PhysicalTerm(TermKind.SPATIAL, params,
                         f"position-dependent friction, {shape}: amplitude {amp:.6g} {U.force}, "
                         f"{cycles[0]:.6g} {per} (period {2 * math.pi / k:.6g} {U.position}), "
                         f"phase {phi:.4g} rad{wrap_note}{note}", term)]


def _moved(U: AxisUnits) -> str:  # noqa: N803
    """What the position of the axis is called in the terms' texts."""
    return "angle" if U.axis == "rotary" else "position"


def spatial_frequency(k: float, U: AxisUnits) -> tuple[str, tuple[float, str], str]:  # noqa: N803
    """The spatial frequency of ``sin(k q)``: k cycles per revolution (rotary, q in rad),
    k / 2 pi cycles per metre (linear, q in m). -> (parameter, (value, unit), text unit)."""
    if U.axis == "linear":
        return "cycles_per_metre", (k / (2 * math.pi), "1/m"), "cycles/m"
    return "cycles_per_revolution", (k, "1"), "cycles/rev"


def _velocity_shape(term: sp.Expr, c: float, f: sp.Expr, w: sp.Dummy, g: float,
                    extra: dict, note: str, opts: ClassifyOptions) -> list[PhysicalTerm]:
    vmax = opts.velocity_range
    N, V = opts.units.force, opts.units.velocity
    v = np.linspace(vmax / 2000, vmax, 2000)
    F = sp.lambdify(w, c * f, modules=[NUMPY_FUNCTIONS, "numpy"])
    with np.errstate(all="ignore"):
        pos = np.asarray(F(g * v), dtype=float) * np.ones_like(v)
        neg = np.asarray(F(-g * v), dtype=float) * np.ones_like(v)
    scale = float(np.max(np.abs(pos))) if np.all(np.isfinite(pos)) else 0.0
    odd = scale > 0 and np.all(np.isfinite(neg)) and np.max(np.abs(pos + neg)) <= 1e-9 * scale
    if not odd:
        return [_unclassified(term, f"a function of velocity that is not odd ({term})" + note)]
    a = np.abs(pos)
    i = int(np.argmax(a))
    same_sign = np.all(np.sign(pos[pos != 0]) == np.sign(pos[i]))
    if same_sign and 0 < i < v.size - 1 and a[-1] < 0.9 * a[i]:
        half = a[-1] + 0.5 * (a[i] - a[-1])
        after = np.nonzero(a[i:] <= half)[0]
        vs = float(v[i + after[0]]) if after.size else vmax
        params = {"peak": (float(pos[i]), N), "peak_velocity": (float(v[i]), V),
                  "level_at_range": (float(pos[-1]), N),
                  "stribeck_velocity": (vs, V), **extra}
        return [PhysicalTerm(TermKind.STRIBECK, params,
                             f"Stribeck-like hump: peak {pos[i]:.4g} {N} at {v[i]:.4g} {V}, "
                             f"falling to {pos[-1]:.4g} {N} at {vmax:g} {V}{note}", term)]
    # Coulomb + viscous fit by least squares over the range.
    A = np.column_stack([np.ones_like(v), v])
    (fc, d), *_ = np.linalg.lstsq(A, pos, rcond=None)
    if np.max(np.abs(A @ np.array([fc, d]) - pos)) <= 1e-3 * scale:
        out = []
        if abs(fc) > 1e-6 * scale:
            out.append(PhysicalTerm(TermKind.COULOMB, {"level": (float(fc), N), **extra},
                                    f"Coulomb friction (fitted to {f}): {fc:.6g} {N}{note}",
                                    term))
        D = opts.units.viscous
        out.append(PhysicalTerm(TermKind.VISCOUS, {"coefficient": (float(d), D), **extra},
                                f"viscous friction (fitted to {f}): {d:.6g} {D}{note}",
                                term))
        return out
    split = _stribeck_split(term, f, v, pos, scale, extra, note, opts)
    if split is not None:
        return split
    return [_unclassified(term, f"an odd function of velocity ({term}) that is neither "
                          "Coulomb, viscous nor Stribeck-like over the velocity range" + note)]


#: Share of the velocity range, at its top, where a Stribeck curve has settled.
_TAIL = 0.2


def _stribeck_split(term: sp.Expr, f: sp.Expr, v: np.ndarray, pos: np.ndarray, scale: float,
                    extra: dict, note: str, opts: ClassifyOptions
                    ) -> list[PhysicalTerm] | None:
    """An odd velocity function that is Coulomb + viscous at speed and deviates below.

    The GA writes a Stribeck curve as several rows: ``Fs sign(v)`` in one, and in
    another a function that bends the sum down to the Coulomb level at speed
    (``c sin(Sat(v))``, ``-c tanh(k v)``). Over the top ``_TAIL`` of the range
    the function must be ``Fc + D v`` within 1 % of its peak; that asymptote
    gives the Coulomb and viscous parts, and what differs from it at lower
    speed, when it reaches ``_SIGNIFICANT`` of the peak, is the Stribeck part,
    unless it has halved by ``coulomb_velocity``: then it is the smoothing of
    the Coulomb step, which the data cannot tell from a step.
    """
    top = v >= (1.0 - _TAIL) * v[-1]
    A = np.column_stack([np.ones(int(top.sum())), v[top]])
    (fc, d), *_ = np.linalg.lstsq(A, pos[top], rcond=None)
    if np.max(np.abs(A @ np.array([fc, d]) - pos[top])) > 0.01 * scale:
        return None
    dev = pos - (fc + d * v)
    i = int(np.argmax(np.abs(dev)))
    peak = float(dev[i])
    if abs(peak) < _SIGNIFICANT * scale:
        return None
    after = np.nonzero(np.abs(dev[i:]) <= 0.5 * abs(peak))[0]
    vs = float(v[i + after[0]]) if after.size else float(v[-1])
    N, V, D = opts.units.force, opts.units.velocity, opts.units.viscous
    how = f" (the asymptote of {f} over the top {100 * _TAIL:g} % of +-{v[-1]:g} {V})"
    out = []
    if abs(fc) >= _SIGNIFICANT * scale:
        out.append(PhysicalTerm(TermKind.COULOMB, {"level": (float(fc), N), **extra},
                                f"Coulomb friction: {fc:.6g} {N}{how}{note}", term))
    if abs(d) * v[-1] >= _SIGNIFICANT * scale:
        out.append(PhysicalTerm(TermKind.VISCOUS, {"coefficient": (float(d), D), **extra},
                                f"viscous friction: {d:.6g} {D}{how}{note}", term))
    if vs <= opts.coulomb_velocity:
        return out or None
    out.append(PhysicalTerm(TermKind.STRIBECK, {"peak": (peak, N),
                                         "peak_velocity": (float(v[i]), V),
                                         "stribeck_velocity": (vs, V), **extra},
                            f"Stribeck-like: {peak:.4g} {N} above Coulomb + viscous at "
                            f"{v[i]:.4g} {V}, half of that at {vs:.4g} {V}{note}", term))
    return out


_INDEX = {"angle": 0, "velocity": 1, "acceleration": 2}


def _measured(term: sp.Expr, u: sp.Symbol, role: str,
              opts: ClassifyOptions) -> list[PhysicalTerm] | None:
    """A term no exact pattern fits, classified from its static characteristic."""
    U = opts.units
    F = U.force
    if role in ("angle", "angle_wrapped"):
        p = measure_periodic(term, u, role == "angle_wrapped", opts.harmonic_tolerance)
        if p is not None and p.jump and abs(p.jump) >= p.amplitude:
            # Max(3.9, q_w) and the like: a sawtooth of the wrap, not a friction of the position.
            return [_unclassified(term, f"a function of the wrapped angle whose jump at each wrap "
                                  f"({p.jump:.4g} {F}) is at least its amplitude "
                                  f"({p.amplitude:.4g} {F}): it follows the wrap, not a "
                                  "position-dependent friction",
                                  {"wrap_jump": (p.jump, F), "amplitude": (p.amplitude, F)})]
        if p is not None:
            params, note = describe_operators(p.form, "DC gains")
            period = 2 * math.pi / p.cycles
            key, cycles, per = spatial_frequency(p.cycles, U)
            more = ""
            if abs(p.dominant_cycles - p.cycles) > 1e-9:
                dominant = spatial_frequency(p.dominant_cycles, U)[1]
                params["dominant_cycles"] = dominant
                params["dominant_amplitude"] = (p.dominant_amplitude, F)
                more = (f"; strongest harmonic {dominant[0]:.6g} {per}, "
                        f"{p.dominant_amplitude:.4g} {F}")
            if p.jump:
                params["wrap_jump"] = (p.jump, F)
                more += f"; jumps by {p.jump:.4g} {F} at each wrap of the {_moved(U)}"
            return [PhysicalTerm(TermKind.SPATIAL, {
                "amplitude": (p.amplitude, F), "period": (period, U.position),
                key: cycles, "phase": (p.phase, "rad"),
                "fundamental_amplitude": (p.fundamental_amplitude, F), **params},
                f"position-dependent friction, periodic: amplitude {p.amplitude:.6g} {F} "
                f"(half peak-to-peak), {cycles[0]:.6g} {per} (period {period:.6g} {U.position}), "
                f"fundamental {p.fundamental_amplitude:.4g} {F} at phase {p.phase:.4g} rad"
                f"{more}{note}", term)]
    if role == "velocity":
        found = _measured_velocity(term, u, opts)
        if found:
            return found
    return _measured_acceleration(term, u, role, opts)


def _measured_acceleration(term: sp.Expr, u: sp.Symbol, role: str,
                           opts: ClassifyOptions) -> list[PhysicalTerm] | None:
    """A term of acceleration, its filters at ``acceleration_frequency`` (None: it is none)."""
    U = opts.units
    F = U.force
    if role not in _INDEX:
        return None
    w, a_range = opts.acceleration_frequency, opts.acceleration_range
    a = measure_acceleration(term, u, _INDEX[role], w, a_range)
    if a is None:
        return None
    params, note = describe_operators(a.form, f"filter gains at {w:.4g} rad/s")
    params = {"inertia": (a.inertia, U.inertia), "linearity_r2": (a.r2, "1"), **params}
    what = "acceleration-dependent term" if a.r2 >= _LINEAR_R2 else (
        "nonlinear acceleration-dependent term")
    text = (f"{what}: equivalent inertia {a.inertia:.6g} {U.inertia} (least-squares slope over "
            f"+-{a_range:g} {U.acceleration}, R^2 {a.r2:.3f})")
    if a.r2 < _LINEAR_R2:
        params["peak"] = (a.peak, F)
        text += f"; at most {a.peak:.4g} {F} over that range"
    if a.form.filters:
        params["frequency"] = (w, "rad/s")
        params["filter_phase"] = (a.phase, "rad")
        text += f"; at {w:.4g} rad/s the filters shift it by {math.degrees(a.phase):.3g} deg"
        if abs(math.cos(a.phase)) < math.sqrt(0.5):
            text += " (there it acts mostly as a derivative or integral of the acceleration)"
    if a.band is not None:
        _, lo, hi = a.band
        if lo is not None:
            params["band_low"] = (lo, "rad/s")
        if hi is not None:
            params["band_high"] = (hi, "rad/s")
        text += "; pass band " + (f"{lo:.4g} - {hi:.4g} rad/s" if lo is not None and hi is not None
                                  else f"above {lo:.4g} rad/s" if lo is not None
                                  else f"below {hi:.4g} rad/s")
        if (lo is not None and w < lo or hi is not None and w > hi) and math.isfinite(
                a.inertia_in_band):
            params["inertia_in_band"] = (a.inertia_in_band, U.inertia)
            text += f", where the inertia is {a.inertia_in_band:.6g} {U.inertia}"
    return [PhysicalTerm(TermKind.ACCELERATION, params, text + note, term)]


#: A part of a measured velocity term counts when it makes this share of its peak.
_SIGNIFICANT = 0.05


def _measured_velocity(term: sp.Expr, u: sp.Symbol,
                       opts: ClassifyOptions) -> list[PhysicalTerm] | None:
    """A velocity term whose characteristic is Coulomb + viscous (+ offset), eq. 14's shape."""
    v_range = opts.velocity_range
    fit = measure_velocity(term, u, v_range, opts.coulomb_velocity)
    if fit is None or fit.r2 < _LINEAR_R2:
        return None
    # As for the exact patterns, a Coulomb part must switch within +-coulomb_velocity;
    # a term that is mostly a gentle step stays unclassified (a smooth saturation),
    # a small gentle part beside a viscous slope is left out.
    coulomb = abs(fit.coulomb) >= _SIGNIFICANT * fit.peak
    if coulomb and abs(fit.jump) < 0.9 * 2 * abs(fit.coulomb):
        if abs(fit.coulomb) >= 0.5 * fit.peak:
            return None
        coulomb = False
    params, note = describe_operators(fit.form, "DC gains")
    F, D = opts.units.force, opts.units.viscous
    how = (f" (fit of its static characteristic over +-{v_range:g} {opts.units.velocity}, "
           f"R^2 {fit.r2:.3f}{note})")
    out = []
    if coulomb:
        out.append(PhysicalTerm(TermKind.COULOMB, {"level": (fit.coulomb, F), **params},
                                f"Coulomb friction: {fit.coulomb:.6g} {F}{how}", term))
    if abs(fit.viscous) * v_range >= _SIGNIFICANT * fit.peak:
        out.append(PhysicalTerm(TermKind.VISCOUS, {"coefficient": (fit.viscous, D), **params},
                                f"viscous friction: {fit.viscous:.6g} {D}{how}", term))
    if abs(fit.offset) >= _SIGNIFICANT * fit.peak:
        out.append(PhysicalTerm(TermKind.OFFSET, {"level": (fit.offset, F)},
                                f"constant offset: {fit.offset:.6g} {F}{how}", term))
    return out or None


#: A line fit at least this good (R^2) is a plain acceleration-dependent term.
_LINEAR_R2 = 0.95


def _offset(term: sp.Expr, U: AxisUnits) -> PhysicalTerm:  # noqa: N803
    """A constant term; through filters, delays and relays, its final value."""
    notes = []
    value = term
    for d in [a for a in sp.preorder_traversal(term) if isinstance(a, (LTI, Delay, Relay))]:
        if isinstance(d, LTI):
            split = _tf_split(d.args[1])
            if split is None or split[0] != 0:
                return _unclassified(term, "a constant through a derivative or integral")
            value = value.xreplace({d: split[1] * d.args[0]})
            notes.append("the final value of a filter's step response")
        elif isinstance(d, Delay):
            value = value.xreplace({d: d.args[0]})
            notes.append("after a delay")
        else:
            x, a = (float(v) for v in d.args) if all(v.is_Number for v in d.args) else (0, -1)
            if a < 0:
                return _unclassified(term, f"a relay of a constant that is not numeric: {d}")
            value = value.xreplace({d: sp.Float(1.0 if x >= a else -1.0 if x <= -a else 0.0)})
            notes.append("a relay's output once switched")
    try:
        level = float(fold_constants(value))
    except TypeError:
        return _unclassified(term, f"a constant that does not evaluate to a number: {term}")
    note = f" ({'; '.join(notes)})" if notes else ""
    return PhysicalTerm(TermKind.OFFSET, {"level": (level, U.force)},
                        f"constant offset {level:.6g} {U.force}{note}", term)


def _unclassified(term: sp.Expr, reason: str,
                  params: dict[str, tuple[float, str]] | None = None) -> PhysicalTerm:
    return PhysicalTerm(TermKind.UNCLASSIFIED, params or {}, reason, term)


def _annotate(t: PhysicalTerm, note: str, corners: tuple[float, ...], term: sp.Expr,
              delay: float = 0.0) -> PhysicalTerm:
    params = dict(t.parameters)
    for i, c in enumerate(corners, 1):
        params["corner" if len(corners) == 1 else f"corner_{i}"] = (c, "rad/s")
    if delay:
        params["delay"] = (delay, "s")
    return PhysicalTerm(t.kind, params, t.description + note, term)
