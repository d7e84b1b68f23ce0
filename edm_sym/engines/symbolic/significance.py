"""Honest names: a row is named as physics only when it earns it.

:func:`judge_rows` takes the decoded model, the rows' outputs on a data log and
the target, and decides per row what may be said about it:

* its **contribution**: the RMS of the row's output over the RMS of the target
  (a share, 0.42 = 42 %);
* a row whose contribution is below ``threshold`` (default 1 %) is
  **negligible**: its physical terms are not listed, the flag says what it
  would have been called; so is a pair of rows that **cancels** (the RMS of
  their sum below ``cancel_ratio`` of the smaller one) when the sum is below
  the threshold;
* a term that is a static function of the input (an offset, ``c sign(v)``, ...)
  is measured on its own, and left out as negligible below the threshold;
* an acceleration or spatial term is measured as what it names: ``J a``, or
  its static characteristic along the data's angle, fitted to the row's
  output by least squares. Below the threshold it is **unsupported** and left
  out: the row does something else on the data (a derivative of the
  acceleration, a ripple its filters smooth away at the data's speeds); so is
  an acceleration term when the rows together, with the observer's lag taken
  out, hold an inertia below the threshold;
* a row with a parameter at (or within ``bound_margin`` of) its range bound
  (:mod:`edm_sym.core.bounds`) keeps its parameters, but its terms are
  ``unclassified``: the value is a limit of the search, not an estimate;
* a row whose delays hold ``long_delay`` samples or more is flagged (firmware
  memory, and a delay that long is rarely physics);
* the terms that act on velocity, when there are two or more of them, are
  also judged together (:mod:`edm_sym.engines.symbolic.joint`): when the names
  they get one by one do not add up to what their sum is (a term left
  unclassified, other kinds, Coulomb or viscous values more than 5 % apart),
  the sum's Coulomb, viscous and Stribeck parts replace them, listed on the row
  that contributes most, and every row of the group is flagged ``joint``;
* so are the terms of the angle (:mod:`edm_sym.engines.symbolic.joint_spatial`),
  when one ripple is written as several rows: their sum over one revolution
  is named as one ``spatial`` term;
* with the observer's bandwidth known, the inertia the rows hold together
  (:mod:`edm_sym.engines.symbolic.inertia`: their outputs with the observer's
  lag taken out, regressed on the data) is named as one ``acceleration``
  term where the row-by-row names miss it (an inertia error written into the
  lead filters of velocity rows).

Flags are ``(code, message)`` pairs; the codes are :data:`ROW_FLAGS` and
:data:`TERM_FLAGS`. See ``docs/describe.md``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
import sympy as sp

from edm_sym.core.bounds import BOUND_MARGIN, BoundFlag, bound_flags
from edm_sym.core.terms import TermKind
from edm_sym.core.units import axis_units
from edm_sym.engines.symbolic.classify import ClassifyOptions, PhysicalTerm
from edm_sym.engines.symbolic.functions import NUMPY_FUNCTIONS
from edm_sym.engines.symbolic.inertia import ModelInertia
from edm_sym.engines.symbolic.model import RowModel, SymbolicModel
from edm_sym.engines.symbolic.operators import LTI, Delay, Relay

#: Flags of a row, and what they mean.
ROW_FLAGS = {
    "negligible": "the row (or a term of it) contributes less than the threshold",
    "cancels": "the row's output largely cancels another row's",
    "at_bound": "a parameter is at (or within the margin of) its range bound",
    "long_delay": "the row's delays hold at least long_delay samples",
    "no_output": "the row's output is identically zero",
    "unmeasured": "no data: the contribution was not measured",
    "unsupported": ("a term its expression has (an inertia, a ripple) is not what the row does "
                    "on the data: fitted to the row's output, it explains less than the threshold; "
                    "or an acceleration term of a model whose rows hold no inertia together"),
    "joint": ("its velocity (or position-dependent) terms are named together with other rows' "
              "(their summed characteristic)"),
}
#: Flags of a term, and what they mean.
TERM_FLAGS = {
    "unclassified": "no physical pattern fits; the message is the reason",
    "at_bound": "not named: a parameter of the row is at its range bound",
    "nonlinear": "an acceleration-dependent term that is far from linear (R^2 < 0.95)",
    "derivative_like": "its filters shift it by more than 45 deg at the representative frequency",
    "wrap_jump": "a position-dependent term that jumps at each wrap of the angle",
}


@dataclass(frozen=True)
class Flag:
    """A flag on a row or a term: a stable code and one readable line."""

    code: str
    message: str

    def to_json(self) -> dict[str, str]:
        """``{"code": ..., "message": ...}``."""
        return {"code": self.code, "message": self.message}


@dataclass(frozen=True)
class SignificanceOptions:
    """Thresholds of :func:`judge_rows`.

    Parameters
    ----------
    threshold : float, default 0.01
        A row (or a static term) is negligible below this share of the
        target's RMS.
    bound_margin : float, default 0.01
        A parameter is at its bound when ``p <= bound_margin`` or
        ``p >= 1 - bound_margin`` (normalised ``p``).
    cancel_ratio : float, default 0.5
        Two rows cancel when the RMS of their sum is below this share of the
        smaller of their two RMS values.
    long_delay : int, default 100
        A row whose delays add up to this many samples or more is flagged.
    """

    threshold: float = 0.01
    bound_margin: float = BOUND_MARGIN
    cancel_ratio: float = 0.5
    long_delay: int = 100

    def __post_init__(self) -> None:
        for name, lo, hi in (("threshold", 0.0, 1.0), ("bound_margin", 0.0, 0.5),
                             ("cancel_ratio", 0.0, 1.0)):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and lo <= v < hi):
                raise ValueError(f"{name}: expected a number in [{lo:g}, {hi:g}), found {v!r}")
        if not (isinstance(self.long_delay, int) and self.long_delay >= 1):
            raise ValueError(f"long_delay: expected an integer >= 1, found {self.long_delay!r}")


@dataclass(frozen=True)
class JudgedTerm:
    """A physical term as it may be named, with its flags."""

    term: PhysicalTerm
    flags: tuple[Flag, ...] = ()


@dataclass(frozen=True)
class JudgedRow:
    """What may honestly be said about one row.

    Attributes
    ----------
    index : int
        Row number, 0-based.
    contribution : float or None
        RMS of the row's output / RMS of the target (None without data).
    terms : tuple of JudgedTerm
        The terms that may be listed (empty for a negligible row).
    flags : tuple of Flag
    rms : float or None
        RMS of the row's output [N m].
    bounds : tuple of BoundFlag
        The row's parameters at their bounds.
    """

    index: int
    contribution: float | None
    terms: tuple[JudgedTerm, ...]
    flags: tuple[Flag, ...]
    rms: float | None = None
    bounds: tuple[BoundFlag, ...] = ()

    @property
    def negligible(self) -> bool:
        """True when the row is negligible (its terms are not listed)."""
        return any(f.code == "negligible" for f in self.flags) and not self.terms


def _rms(x: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.square(x))))


@dataclass(frozen=True)
class RowShare:
    """What a row contributes on the data (:func:`row_shares`): the negligible-row rule."""

    #: The RMS of the row's output, and of the target.
    rms: float
    ref: float
    #: The rows it cancels with: ``(k, RMS of the pair's sum)``, k zero-based.
    cancels: tuple[tuple[int, float], ...]
    #: Below the threshold alone, or in a cancelling pair whose sum is.
    negligible: bool

    @property
    def share(self) -> float:
        """The row's RMS over the target's."""
        return self.rms / self.ref


def row_shares(outputs: np.ndarray, target: np.ndarray,
               options: SignificanceOptions | None = None) -> tuple[RowShare, ...] | None:
    """The negligible-row rule, the one place it is decided (``edm describe``, the report
    and the closing summary of ``edm abstract`` all read it).

    A row is negligible when its output's RMS is below ``options.threshold``
    of the target's, or when it cancels with another row (the RMS of their sum
    below ``options.cancel_ratio`` of the smaller of the two) and the pair's
    sum is below the threshold. None when the target's RMS is 0 (nothing to
    measure against).
    """
    opts = options or SignificanceOptions()
    ref = _rms(np.asarray(target, dtype=float))
    if not ref > 0:
        return None
    rms = [_rms(y) for y in outputs]
    out = []
    for j in range(len(rms)):
        negligible = rms[j] / ref < opts.threshold
        cancels = []
        for k in range(len(rms)):
            small = min(rms[j], rms[k])
            if k == j or not small > 0:
                continue
            both = _rms(outputs[j] + outputs[k])
            if both < opts.cancel_ratio * small:
                cancels.append((k, both))
                negligible = negligible or both / ref < opts.threshold
        out.append(RowShare(rms[j], ref, tuple(cancels), negligible))
    return tuple(out)


def _pct(share: float) -> str:
    return f"{100 * share:.4g} %"


def term_summary(term: PhysicalTerm) -> str:
    """``coulomb (level -0.00064 N m)``: a term's kind and its main parameter (in its unit)."""
    if not term.parameters:
        return term.kind.value
    name, (value, unit) = next(iter(term.parameters.items()))
    return f"{term.kind.value} ({name.replace('_', ' ')} {value:.4g} {unit})"


def _term_rms(term: PhysicalTerm, u: sp.Symbol, x: np.ndarray | None) -> float | None:
    """The RMS of a static term on the input ``x`` (None when it has dynamics)."""
    if term.kind is TermKind.OFFSET and "level" in term.parameters:
        return abs(float(term.parameters["level"][0]))
    e = term.expr
    if e is None or x is None or e.has(LTI, Delay, Relay) or e.free_symbols - {u}:
        return None
    f = sp.lambdify(u, e, modules=[NUMPY_FUNCTIONS, "numpy"])
    with np.errstate(all="ignore"):
        y = np.asarray(f(x), dtype=float) * np.ones_like(x)
    return _rms(y) if np.all(np.isfinite(y)) else None


#: The role index of an input (the times it is differentiated to reach the acceleration).
_ROLE_INDEX = {"angle": 0, "velocity": 1, "acceleration": 2}


def acceleration_of(x: np.ndarray, role: str | None, ts: float) -> np.ndarray | None:
    """The acceleration a row's input gives on a contiguous log (None for other roles).

    The acceleration itself, or the velocity or unwrapped angle differentiated
    once or twice (central differences, :func:`numpy.gradient`).
    """
    if role not in _ROLE_INDEX:
        return None
    a = np.asarray(x, dtype=float)
    for _ in range(2 - _ROLE_INDEX[role]):
        if a.size < 2:
            return None
        a = np.gradient(a, ts)
    return a


def _fitted(y: np.ndarray, a: np.ndarray) -> tuple[float, float, float] | None:
    """(c, RMS of c a, R^2): the row's output ``y`` fitted by ``c a`` (least squares)."""
    aa = float(a @ a)
    if not aa > 0 or not (np.all(np.isfinite(y)) and np.all(np.isfinite(a))):
        return None
    c = float(y @ a) / aa
    dev = float(np.sum((y - y.mean()) ** 2))
    r2 = 1.0 - float(np.sum((y - c * a) ** 2)) / dev if dev > 0 else 0.0
    return c, abs(c) * _rms(a), r2


def _position_shape(term: PhysicalTerm, u: sp.Symbol, x: np.ndarray) -> np.ndarray | None:
    """A spatial term's static characteristic (filters at DC) along the angle ``x``."""
    from edm_sym.engines.symbolic.characteristic import dc_gain, evaluate, static_form

    if term.expr is None:
        return None
    form = static_form(term.expr, u, 0, dc_gain)
    return None if form is None else evaluate(form.expr, u, x)


def _term_flags(term: PhysicalTerm) -> list[Flag]:
    p = term.parameters
    out = []
    if term.kind is TermKind.UNCLASSIFIED:
        out.append(Flag("unclassified", term.description or "no physical pattern fits"))
    if "linearity_r2" in p and p["linearity_r2"][0] < 0.95:
        out.append(Flag("nonlinear", f"far from linear in the acceleration "
                                     f"(R^2 {p['linearity_r2'][0]:.4g})"))
    if "filter_phase" in p and abs(math.cos(p["filter_phase"][0])) < math.sqrt(0.5):
        out.append(Flag("derivative_like",
                        f"its filters shift it by {math.degrees(p['filter_phase'][0]):.4g} deg at "
                        f"{p.get('frequency', (float('nan'),))[0]:.4g} rad/s: mostly a derivative "
                        "or integral of the acceleration there"))
    if "wrap_jump" in p:
        value, unit = p["wrap_jump"]
        out.append(Flag("wrap_jump", f"jumps by {value:.4g} {unit} at each wrap"))
    return out


def _delay_samples(row: RowModel) -> int:
    return sum(st.delay for st in row.stages)  # 0 for every stage but a delay line


def judge_rows(
    model: SymbolicModel,
    outputs: np.ndarray | None = None,
    target: np.ndarray | None = None,
    inputs: Sequence[np.ndarray] | None = None,
    *,
    options: SignificanceOptions | None = None,
    classify: ClassifyOptions | None = None,
    accelerations: Sequence[np.ndarray | None] | None = None,
    inertia: ModelInertia | None = None,
) -> tuple[JudgedRow, ...]:
    """Judge every row of a decoded model: contribution, flags, the terms it may name.

    Parameters
    ----------
    model : SymbolicModel
        From :func:`edm_sym.engines.symbolic.decode`.
    outputs : numpy.ndarray, optional
        Shape (m, N): each row's output on the data (the reference simulator's).
    target : numpy.ndarray, optional
        Shape (N,): the target on the same data.
    inputs : sequence of numpy.ndarray, optional
        Each row's input signal (to measure static terms on their own).
    options : SignificanceOptions, optional
    classify : ClassifyOptions, optional
        The thresholds and velocity range of the joint judgement of the
        velocity terms (default: ``ClassifyOptions.for_axis(model.axis)``;
        :func:`edm_sym.engines.description.describe` passes the data's range).
    accelerations : sequence of numpy.ndarray or None, optional
        Per row, the acceleration its input gives on the same samples as
        ``outputs`` (:func:`acceleration_of`; None for a wrapped angle), to
        measure an acceleration term as an inertia (``unsupported``).
        Default: differentiated from ``inputs``, which must then be one
        contiguous stretch of a log.
    inertia : ModelInertia, optional
        The inertia the rows hold with the observer's lag taken out
        (:func:`edm_sym.engines.symbolic.inertia.model_inertia`). Above the
        threshold, and unless the acceleration terms named row by row add up
        to it (within 25 %), it replaces them as one ``acceleration`` term on
        the row that holds most of it; the rows that hold a tenth of it or
        more are flagged ``joint``. Below the threshold the model holds no
        inertia, and the acceleration terms named row by row are left out
        (``unsupported``).

    Returns
    -------
    tuple of JudgedRow
        Without ``outputs`` and ``target`` nothing is measured: every row is
        flagged ``unmeasured`` and keeps its classifier terms.
    """
    opts = options or SignificanceOptions()
    bounds = bound_flags(model.compensator, margin=opts.bound_margin)
    shares = row_shares(outputs, target, opts) if outputs is not None and target is not None \
        else None
    measured = shares is not None
    ref = shares[0].ref if shares else 0.0
    out = []
    for row in model.rows:
        j = row.index
        flags: list[Flag] = []
        share = shares[j].share if measured else None
        if not measured:
            flags.append(Flag("unmeasured", "no data with the target: contribution not measured"))
        negligible = measured and shares[j].negligible
        if measured:
            force = axis_units(model.axis).force
            for k, both in shares[j].cancels:
                flags.append(Flag("cancels", f"cancels with row {k + 1}: together "
                                  f"{both:.4g} {force} RMS ({_pct(both / ref)} of the target's "
                                  f"RMS), alone {shares[j].rms:.4g} and {shares[k].rms:.4g} {force}"))
        row_bounds = tuple(b for b in bounds if b.row == j)
        flags += [Flag("at_bound", b.message()) for b in row_bounds]
        n_delay = _delay_samples(row)
        if n_delay >= opts.long_delay:
            flags.append(Flag("long_delay", f"delays of {n_delay} samples "
                              f"({n_delay * model.sample_time:.4g} s): {n_delay} values of state"))
        if not row.terms:
            flags.append(Flag("no_output", "the row's output is identically zero"))
        terms: list[JudgedTerm] = []
        if negligible:
            would = ", ".join(term_summary(t) for t in row.terms) or "nothing"
            how = f"contributes {_pct(share)} of the target's RMS" if share < opts.threshold \
                else "cancels with another row, and the pair contributes less"
            flags.insert(0, Flag("negligible", f"{how} (threshold {_pct(opts.threshold)}); "
                                               f"would be named {would}"))
        else:
            x = a = None
            if inputs is not None:
                x = np.asarray(inputs[j], dtype=float)
                a = (accelerations[j] if accelerations is not None
                     else acceleration_of(x, row.role, model.sample_time))
            terms = _judge_terms(row, x, ref if measured else None, row_bounds, opts, flags,
                                 (outputs[j], a) if measured else None,
                                 axis_units(model.axis).inertia)
        out.append(JudgedRow(j, share, tuple(terms), tuple(flags),
                             shares[j].rms if measured else None, row_bounds))
    options = classify or ClassifyOptions.for_axis(model.axis)
    out = _joint_spatial(model, _joint(model, out, options), options)
    return _joint_inertia(model, out, inertia, ref if measured else 0.0, opts)


#: Coulomb or viscous values named one by one may differ this much from the sum's.
_JOINT_AGREE = 0.05


def _sums(terms: Sequence[PhysicalTerm]) -> tuple[set[TermKind], float, float]:
    kinds = {t.kind for t in terms}
    total = [sum(float(t.parameters[key][0]) for t in terms if t.kind is kind)
             for kind, key in ((TermKind.COULOMB, "level"), (TermKind.VISCOUS, "coefficient"))]
    return kinds, total[0], total[1]


def _joint(model: SymbolicModel, judged: list[JudgedRow],
           options: ClassifyOptions) -> tuple[JudgedRow, ...]:
    """Replace the velocity terms of several rows by those of their sum, where they disagree."""
    from edm_sym.engines.symbolic.joint import joint_velocity_terms, velocity_part

    parts, named, where = {}, [], {}
    for row, jr in zip(model.rows, judged, strict=True):
        if jr.bounds:
            continue
        for q, jt in enumerate(jr.terms):
            p = velocity_part(jt.term, row.input_symbol, row.role)
            if p is not None:
                # Two names of one term (Coulomb and viscous of a fit) sum it once.
                parts.setdefault((row.index, jt.term.expr), p)
                named.append(jt.term)
                where.setdefault(row.index, []).append(q)
    if len(named) < 2:
        return tuple(judged)
    idx = sorted(where)
    names = "rows " + ", ".join(str(j + 1) for j in idx) if len(idx) > 1 else f"row {idx[0] + 1}"
    joint = joint_velocity_terms(list(parts.values()), options, names)
    if joint is None:
        return tuple(judged)
    kinds, c1, v1 = _sums(named)
    jkinds, c2, v2 = _sums(joint)
    if kinds == jkinds and all(abs(a - b) <= _JOINT_AGREE * max(abs(a), abs(b))
                               for a, b in ((c1, c2), (v1, v2))):
        return tuple(judged)
    return _named_together(judged, where, joint,
                           f"its velocity terms are named with those of {names}, as their sum "
                           f"over +-{options.velocity_range:.4g} "
                           f"{axis_units(model.axis).velocity}: "
                           + ", ".join(term_summary(t) for t in joint))


def _named_together(judged: Sequence[JudgedRow], where: dict[int, list[int]],
                    joint: Sequence[PhysicalTerm], message: str) -> tuple[JudgedRow, ...]:
    """Rows ``where`` (row -> indices of its terms) lose those terms; ``joint`` is listed on
    the one that contributes most, and each gets a ``joint`` flag: ``message`` and where."""
    idx = sorted(where)
    lead = max(idx, key=lambda j: (judged[j].rms or 0.0, -j))
    out = list(judged)
    for j in idx:
        jr = judged[j]
        keep = [jt for q, jt in enumerate(jr.terms) if q not in where[j]]
        if j == lead:
            keep += [JudgedTerm(t, tuple(_term_flags(t))) for t in joint]
        msg = message + (" (here)" if j == lead else f" (listed in row {lead + 1})")
        out[j] = replace(jr, terms=tuple(keep), flags=(*jr.flags, Flag("joint", msg)))
    return tuple(out)


def _joint_spatial(model: SymbolicModel, judged: Sequence[JudgedRow],
                   options: ClassifyOptions) -> tuple[JudgedRow, ...]:
    """Replace the angle terms of several rows by the ripple of their sum, where they disagree."""
    from edm_sym.engines.symbolic.joint_spatial import joint_spatial_term, overlapping, spatial_part

    parts, where = [], {}
    for row, jr in zip(model.rows, judged, strict=True):
        if jr.bounds:
            continue
        for q, jt in enumerate(jr.terms):
            p = spatial_part(jt.term, row.input_symbol, row.role)
            if p is not None:
                parts.append(p)
                where.setdefault(row.index, []).append(q)
    if len(parts) < 2 or not overlapping(parts):
        return tuple(judged)
    idx = sorted(where)
    names = "rows " + ", ".join(str(j + 1) for j in idx) if len(idx) > 1 else f"row {idx[0] + 1}"
    joint = joint_spatial_term(parts, options, names)
    if joint is None:
        return tuple(judged)
    return _named_together(judged, where, (joint,),
                           f"its position-dependent terms are named with those of {names}, as "
                           f"the ripple of their sum over one revolution: {term_summary(joint)}")


def _unsupported(t: PhysicalTerm, u: sp.Symbol, x: np.ndarray | None,
                 data: tuple[np.ndarray, np.ndarray | None] | None,
                 inertia_unit: str) -> tuple[float, str] | None:
    """What an acceleration or spatial term explains of the row's output on the data.

    The term names a signal: ``J a`` for an inertia, its static characteristic
    along the angle for a ripple. Fitted to the row's output by least squares,
    that signal is what the data shows of the term; what the row does beyond
    it (a derivative of the acceleration, a filter that smooths a ripple away at
    the data's speeds) is not that term. -> (RMS of the fit, how it was fitted).
    """
    if data is None:
        return None
    y, a = data
    if t.kind is TermKind.ACCELERATION and a is not None:
        fit = _fitted(y, a)
        what = "as an inertia (the row's output fitted by J a: J = {c:.4g} " + inertia_unit
    elif t.kind is TermKind.SPATIAL and x is not None:
        shape = _position_shape(t, u, x)
        fit = None if shape is None else _fitted(y, shape)
        what = ("as a function of the position (the row's output fitted by c times the "
                "term's static characteristic along the data's angle: c = {c:.4g}")
    else:
        return None
    if fit is None:
        return None
    return fit[1], what.format(c=fit[0]) + f", R^2 {fit[2]:.3g})"


#: Acceleration terms named row by row stand when they add up to the model's inertia this closely.
_INERTIA_AGREE = 0.25
#: A row holds a part of the model's inertia worth naming when it is this share of it or more.
_INERTIA_HOLDS = 0.1


def _joint_inertia(model: SymbolicModel, judged: Sequence[JudgedRow], mi: ModelInertia | None,
                   ref: float, opts: SignificanceOptions) -> tuple[JudgedRow, ...]:
    """Name the inertia the rows hold together, where the row-by-row names miss it."""
    if mi is None or not ref > 0:
        return tuple(judged)
    if mi.rms / ref < opts.threshold:
        return _inertia_not_held(model, judged, mi, ref, opts)
    named = [(j, jt) for j, jr in enumerate(judged) for jt in jr.terms
             if jt.term.kind is TermKind.ACCELERATION]
    total = sum(float(jt.term.parameters["inertia"][0]) for _, jt in named)
    if named and abs(total - mi.inertia) <= _INERTIA_AGREE * abs(mi.inertia):
        return tuple(judged)
    holders = [j for j, c in enumerate(mi.rows) if abs(c) >= _INERTIA_HOLDS * abs(mi.inertia)]
    lead = max(range(len(mi.rows)), key=lambda j: (abs(mi.rows[j]) * (mi.rows[j] * mi.inertia > 0),
                                                   -j))
    where = sorted({*holders, *(j for j, _ in named), lead})
    if any(judged[j].bounds for j in where):
        return tuple(judged)  # a limit of the search is no estimate (as row by row)
    U = axis_units(model.axis)
    parts = ", ".join(f"row {j + 1} {mi.rows[j]:.3g} {U.inertia}" for j in sorted(holders))
    # Sentences apart ("; "): the report lists all but the first as notes.
    term = PhysicalTerm(TermKind.ACCELERATION, {"inertia": (mi.inertia, U.inertia),
                                         "observer_bandwidth": (mi.bandwidth, "rad/s")},
                        f"acceleration-dependent term: equivalent inertia {mi.inertia:.6g} "
                        f"{U.inertia}; the rows' outputs with the observer's lag taken out, "
                        f"y + y'/g at g = {mi.bandwidth:.4g} rad/s, regressed on sgn(v), v, a "
                        f"and 1 over the data; held by {parts}",
                        model.rows[lead].expr_numeric)
    out = list(judged)
    for j in where:
        jr = judged[j]
        keep = [jt for jt in jr.terms if jt.term.kind is not TermKind.ACCELERATION]
        if j == lead:
            keep.append(JudgedTerm(term))
        msg = (f"the model's inertia, {mi.inertia:.4g} {U.inertia}, is named as a whole: "
               f"this row holds {mi.rows[j]:.3g} {U.inertia} of it"
               + (" (named here)" if j == lead else f" (named in row {lead + 1})"))
        out[j] = replace(jr, terms=tuple(keep), flags=(*jr.flags, Flag("joint", msg)))
    return tuple(out)


def _inertia_not_held(model: SymbolicModel, judged: Sequence[JudgedRow], mi: ModelInertia,
                      ref: float, opts: SignificanceOptions) -> tuple[JudgedRow, ...]:
    """Leave out the acceleration terms named row by row when the model holds no inertia.

    With the observer's lag taken out, the rows together hold an inertia below the
    threshold: what a row's filters make look like ``J a`` is the observer's lag,
    or is undone by the other rows (a lead on the velocity, say), so no row of the
    model is an acceleration term (``unsupported``).
    """
    U = axis_units(model.axis)
    out = list(judged)
    for j, jr in enumerate(judged):
        gone = [jt for jt in jr.terms if jt.term.kind is TermKind.ACCELERATION]
        if not gone:
            continue
        flags = tuple(Flag("unsupported", f"term {term_summary(jt.term)} is not the model's: "
                           f"with the observer's lag taken out (y + y'/g at g = "
                           f"{mi.bandwidth:.4g} rad/s), the rows hold {mi.inertia:.3g} "
                           f"{U.inertia} together, {_pct(mi.rms / ref)} of the target's RMS "
                           f"(threshold {_pct(opts.threshold)}): not listed") for jt in gone)
        out[j] = replace(jr, terms=tuple(jt for jt in jr.terms if jt not in gone),
                         flags=(*jr.flags, *flags))
    return tuple(out)


def _judge_terms(row: RowModel, x: np.ndarray | None, ref: float | None,
                 row_bounds: tuple[BoundFlag, ...], opts: SignificanceOptions,
                 flags: list[Flag], data: tuple[np.ndarray, np.ndarray | None] | None = None,
                 inertia_unit: str = "kg m^2") -> list[JudgedTerm]:
    terms = []
    for t in row.terms:
        if ref is not None:
            trms = _term_rms(t, row.input_symbol, x)
            if trms is not None and trms / ref < opts.threshold:
                flags.append(Flag("negligible", f"term {term_summary(t)} contributes "
                                  f"{_pct(trms / ref)} of the target's RMS (threshold "
                                  f"{_pct(opts.threshold)}): not listed"))
                continue
            why = _unsupported(t, row.input_symbol, x, data, inertia_unit)
            if why is not None and why[0] / ref < opts.threshold:
                flags.append(Flag("unsupported", f"term {term_summary(t)} explains "
                                  f"{_pct(why[0] / ref)} of the target's RMS on the data "
                                  f"{why[1]} (threshold {_pct(opts.threshold)}): not listed"))
                continue
        tflags = _term_flags(t)
        if row_bounds and t.kind is not TermKind.UNCLASSIFIED:
            where = "; ".join(b.message() for b in row_bounds)
            tflags.insert(0, Flag("at_bound", f"would be named {term_summary(t)}, but {where}"))
            t = replace(t, kind=TermKind.UNCLASSIFIED,
                        description=f"not named: a parameter is at its range bound ({where}); "
                                    f"would be {t.description}")
        terms.append(JudgedTerm(t, tuple(tflags)))
    return terms


def judged_json(row: JudgedRow) -> list[dict[str, Any]]:
    """The ``terms`` list of ``edm describe --json`` for one judged row.

    A parameter that is not finite (an open pass band's gain) is ``null``.
    """
    return [{"kind": jt.term.kind.value,
             "parameters": {k: [float(v) if math.isfinite(v) else None, unit]
                            for k, (v, unit) in jt.term.parameters.items()},
             "flags": [f.to_json() for f in jt.flags]} for jt in row.terms]
