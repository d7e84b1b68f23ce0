"""Parsimony: prune the search's model and keep the complexity-vs-fitness front.

After the search, a deterministic greedy backward elimination starts from the
search's model (by default the step best, refitted or as the GA left it, of
the lowest plain RMSE over the whole log, the held-out RMSE choosing among
those within ``[parsimony] tie`` of it: ``abstraction.finish.start_candidate``). At
every stage it tries each simplification:

* replace one element by ``through``;
* drop one row, or two rows on the same input together (rows that cancel);
* merge two rows of the same input and structure into one (the sum of their
  gains at the row's scale position, exact when only the gain differs);
* halve a delay (``dead_time``, ``shift``): a delay the data cannot support
  shrinks towards zero, and a filter it cannot support becomes ``through``;

(Before that, every parameter the search left at a range bound is moved
just inside it, :func:`relieve_bounds`, when the criterion stays within the
tolerance: a bound the data does not need is no estimate, and would keep the
row from being named as physics.) It scores every candidate by the
**criterion** (eq. 8 on the held-out part with the final step's weighting;
its RMSE there when that weighting is 0 on every held-out sample; the
training eq. 8 when nothing is held out), takes the best one, then refits
the row gains of the result by weighted least squares on the **training**
part (kept when it lowers the criterion), and goes on until one row with
nothing to drop is left. Every model on the way
is a candidate member of the front; the front keeps, for each complexity,
the best criterion, and only members no simpler member beats or equals.

**Complexity** = rows + active elements (every element but ``through``) +
state size (the values the firmware keeps between samples: 1 per
first-order filter state, the delay length in samples for a dead time).

**Selection** (``select``): ``best`` the lowest criterion; ``knee`` the
largest drop of ln(criterion) per unit of complexity against the next
simpler member, among members within 1.5 times the best criterion (PySR's
rule); ``simplest-within=PCT`` the simplest member within PCT % of the best
criterion. The default is ``simplest-within=`` the tolerance (1 %): every
element and row whose removal worsens the criterion by less than that goes.
"""

from __future__ import annotations

import math
from collections.abc import Collection, Mapping
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from edm_sym.core.bounds import BOUND_MARGIN, bound_flags, complexity
from edm_sym.core.elements import BY_NAME, REGISTRY
from edm_sym.core.matrix import Compensator, ElementMatrix, Gene, Row
from edm_sym.engines.abstraction.ga import THROUGH
from edm_sym.engines.abstraction.gain_fit import HOMOGENEOUS, row_gains, scale_position
from edm_sym.engines.abstraction.holdout import Scorer
from edm_sym.engines.abstraction.parsimony import ParsimonySettings, check_select, select
from edm_sym.engines.abstraction.seeding import MAX_ORDER, fitted_samples, stribeck_slopes

#: The ``gain`` and ``lpf`` elements' codes (a law row's scale and its observer lag), and
#: the gain a law row starts from before its refit (the middle of the range when a
#: config's gain range leaves it out).
GAIN = BY_NAME["gain"].code
LPF = BY_NAME["lpf"].code
SIGN = BY_NAME["sign"].code
TANH = BY_NAME["tanh"].code
SIN_PHASE = BY_NAME["sin_phase"].code
LAW_START = 1e-3
#: Elements whose parameter multiplies their output: gains and amplitudes, ``a s``, ``a / s``.
MULTIPLYING = frozenset(c for c, el in REGISTRY.items() if el.multiplies_output)
COMPLEXITY = ("rows + active elements (all but through) + state size (values kept between "
              "samples; a delay's length in samples)")


@dataclass(frozen=True)
class Member:
    """A model of the front."""

    matrix: ElementMatrix
    complexity: int
    criterion: float
    change: str


def _with(comp: Compensator, matrix: ElementMatrix) -> Compensator:
    return replace(comp, matrix=matrix)


def _gene_value(comp: Compensator, g: Gene) -> float | None:
    return comp.value(g) if g.element.has_param() else None


def _set_value(comp: Compensator, g: Gene, a: float) -> Gene | None:
    rng = comp.ranges[g.element.name]
    if not (rng.low <= a <= rng.high) or (rng.scaling == "log" and not a > 0):
        return None
    return Gene(g.code, rng.encode(a))


def _candidates(comp: Compensator, m: ElementMatrix) -> list[tuple[str, ElementMatrix]]:
    rows, out = m.rows, []
    drop = lambda *js: tuple(r for k, r in enumerate(rows) if k not in js)  # noqa: E731
    for j, row in enumerate(rows):
        for i, g in enumerate(row.genes):
            if g.code == THROUGH:
                continue
            genes = list(row.genes)
            genes[i] = Gene(THROUGH, 0.0)
            out.append((f"row {j + 1}: {g.element.name} replaced by through",
                        ElementMatrix(m.inputs, rows[:j] + (Row(row.input, genes),) + rows[j + 1:])))
            if g.element.is_delay and g.element.state_size(comp.value(g), comp.sample_time) > 1:
                half = _set_value(comp, g, 0.5 * comp.value(g))
                if half is not None and half != g:
                    genes[i] = half
                    out.append((f"row {j + 1}: {g.element.name} halved",
                                ElementMatrix(m.inputs,
                                              rows[:j] + (Row(row.input, genes),) + rows[j + 1:])))
    if len(rows) > 1:
        for j in range(len(rows)):
            out.append((f"drop row {j + 1}", ElementMatrix(m.inputs, drop(j))))
    for j in range(len(rows)):
        for k in range(j + 1, len(rows)):
            rj, rk = rows[j], rows[k]
            if rj.input != rk.input:
                continue
            if len(rows) > 2:
                out.append((f"drop rows {j + 1} and {k + 1}", ElementMatrix(m.inputs, drop(j, k))))
            merged = _merge(comp, rj, rk)
            if merged is not None:
                keep = tuple(merged if q == j else r for q, r in enumerate(rows) if q != k)
                out.append((f"merge rows {j + 1} and {k + 1}", ElementMatrix(m.inputs, keep)))
    return out


def _merge(comp: Compensator, rj: Row, rk: Row) -> Row | None:
    codes = [g.code for g in rj.genes]
    if codes != [g.code for g in rk.genes]:
        return None
    place = scale_position(codes, gain_allowed=False)
    if place is None:
        return None
    i = place[0]
    a = comp.value(rj.genes[i]) + comp.value(rk.genes[i])
    gene = _set_value(comp, rj.genes[i], a)
    if gene is None:
        return None
    genes = list(rj.genes)
    genes[i] = gene
    return Row(rj.input, genes)


def refit_gains(comp: Compensator, m: ElementMatrix, scorer: Scorer) -> ElementMatrix | None:
    """Row gains by weighted least squares on the training part (None: nothing to refit)."""
    part = scorer.parts["training"]
    sl = part.sl
    lam = scorer.weights("training")
    places = [scale_position([g.code for g in r.genes], gain_allowed=False) for r in m.rows]
    free = [j for j, pl in enumerate(places) if pl is not None]
    if not free:
        return None
    outs = [scorer.row_output(comp, "training", r)[sl] for r in m.rows]
    fixed = sum((outs[j] for j in range(len(outs)) if j not in free), np.zeros_like(part.y[sl]))
    a = np.array([outs[j] for j in free])
    b = part.y[sl] - fixed
    w = np.broadcast_to(np.asarray(lam, dtype=float), b.shape)
    with np.errstate(all="ignore"):
        # einsum, not BLAS: the same bytes whatever the thread settings.
        gram = np.einsum("in,jn,n->ij", a, a, w)
        rhs = np.einsum("in,n,n->i", a, b, w)
        if not (np.all(np.isfinite(gram)) and np.all(np.isfinite(rhs))):
            return None
        c = row_gains(gram, rhs, ridge=1e-12)
    if c is None:
        return None
    rows = list(m.rows)
    for q, j in enumerate(free):
        i = places[j][0]
        g = rows[j].genes[i]
        gene = _set_value(comp, g, comp.value(g) * float(c[q]))
        if gene is not None and math.isfinite(float(c[q])):
            genes = list(rows[j].genes)
            genes[i] = gene
            rows[j] = Row(rows[j].input, genes)
    new = ElementMatrix(m.inputs, rows)
    return None if new == m else new


#: Where :func:`relieve_bounds` puts a parameter it moves off a bound: this far inside, in p.
RELIEF = 2 * BOUND_MARGIN


def _rescaled(comp: Compensator, m: ElementMatrix, j: int, col: int) -> ElementMatrix | None:
    """``m`` with the move of row ``j``'s gene ``col`` undone by another gene's scale.

    When the moved gene multiplies the row's output (a gain, an integral's
    constant: :data:`MULTIPLYING`) and so does another one, both past the row's last element that
    is not homogeneous, the row's output is unchanged when the other one takes
    the factor the move took away: the bound was a choice between equivalent
    parameters, not a limit. None when there is no such gene, or the factor
    would put it outside its range or on a bound.
    """
    old, new = comp.matrix.rows[j].genes[col], m.rows[j].genes[col]
    if old.code not in MULTIPLYING:
        return None
    before, after = comp.value(old), comp.value(new)
    if not (before and after):
        return None
    genes = list(m.rows[j].genes)
    for i in range(len(genes) - 1, -1, -1):
        g = genes[i]
        if g.code not in HOMOGENEOUS:
            return None
        if i == col or g.code not in MULTIPLYING:
            continue
        moved = _set_value(comp, g, comp.value(g) * before / after)
        if moved is None or not BOUND_MARGIN < moved.p < 1 - BOUND_MARGIN:
            continue
        genes[i] = moved
        rows = list(m.rows)
        rows[j] = Row(m.rows[j].input, genes)
        return ElementMatrix(m.inputs, rows)
    return None


def relieve_bounds(comp: Compensator, scorer: Scorer, tolerance: float
                   ) -> tuple[Compensator, int]:
    """Move parameters off their range bounds where the data does not need the bound.

    A parameter at (or within the margin of) a bound (:func:`edm_sym.core.bounds.bound_flags`)
    is a limit of the search, not an estimate, and keeps its row from being named
    as physics. Each one in turn is moved ``RELIEF`` inside its range (the row
    gains refitted on the training part when that helps, or the move taken up
    exactly by another gene that scales the row, :func:`_rescaled`); the move is kept when
    the criterion stays within ``tolerance`` of ``comp``'s, the same tolerance
    that lets pruning drop an element: the data then does not ask for the bound.

    Returns
    -------
    comp : Compensator
        With the moves kept.
    moved : int
        How many parameters were moved.
    """
    limit = scorer.criterion(comp) * (1.0 + tolerance)
    moved = 0
    for flag in bound_flags(comp):
        row = comp.matrix.rows[flag.row]
        genes = list(row.genes)
        genes[flag.col] = Gene(genes[flag.col].code,
                               RELIEF if flag.side == "low" else 1.0 - RELIEF)
        rows = list(comp.matrix.rows)
        rows[flag.row] = Row(row.input, genes)
        m = ElementMatrix(comp.matrix.inputs, rows)
        options = [m] + [r for r in (refit_gains(comp, m, scorer),
                                     _rescaled(comp, m, flag.row, flag.col)) if r is not None]
        # A refit may put the parameter (a gain) back on its bound: that is no move.
        options = [c for c in options if not any(
            (b.row, b.col) == (flag.row, flag.col) for b in bound_flags(_with(comp, c)))]
        scored = [(scorer.criterion(_with(comp, c)), q) for q, c in enumerate(options)]
        crit, q = min(scored) if scored else (math.inf, -1)
        if crit <= limit:
            comp = _with(comp, options[q])
            moved += 1
    return comp, moved


#: The linear laws a row of one gain makes, in the order they are offered, and the input
#: role each reads (:func:`offer_law_rows`).
LAW_ROWS = (("viscous", "velocity"), ("inertia", "acceleration"))


def offer_law_rows(comp: Compensator, scorer: Scorer, tolerance: float,
                   inputs: Mapping[str, int], allowed: Collection[int] = (),
                   observer: float | None = None) -> tuple[Compensator, list[str]]:
    """Add the linear laws' rows, plain or through the observer's lag, that the data asks for.

    A search may build the velocity's share of the torque from saturating
    functions that meet the log's few constant speeds and drift between them,
    with a slow filter to make up for it on the chirp (draw 1602 seed 3: the
    model's own least-squares viscous slope over the staircase 0.00106, the
    plant's 0.00261); or carry the viscous and inertia torques through delays
    and filters that match the observer's lag only on the abstraction log's
    chirp (draw 1611 seed 2). For the laws of :data:`LAW_ROWS` whose input
    role the run has (``inputs``: law to input index), each law's row alone
    and all of them together are offered as ``input -> gain`` (``through``
    elsewhere) and, when the observer's bandwidth is known (``observer``,
    within the ``lpf`` range), as ``input -> lpf(observer) -> gain``, the
    target's own lag; with each offer every row's gain is refitted by least
    squares on the training part. The offer that lowers the criterion most is
    added when it lowers it by more than ``tolerance`` (the share a row must
    earn to stay through pruning), rows offered together only when they also
    beat each of them alone by that much; then the laws not added yet are
    offered again. Without ``gain`` among the ``allowed`` element codes (when
    given), nothing is offered; without ``lpf`` among them, only the plain rows.

    Returns
    -------
    comp : Compensator
        With the rows added.
    added : list of str
        The laws added, in order.
    """
    rng = comp.ranges.get("gain")
    if rng is None or (allowed and GAIN not in allowed) or not comp.matrix.rows:
        return comp, []
    n = len(comp.matrix.rows[0].genes)
    start = rng.encode(LAW_START) if rng.low <= LAW_START <= rng.high else 0.5
    paths: list[tuple[Gene, ...]] = [()]
    low_pass = comp.ranges.get("lpf")
    if (observer is not None and low_pass is not None and n >= 2
            and low_pass.low <= observer <= low_pass.high and (not allowed or LPF in allowed)):
        paths.append((Gene(LPF, low_pass.encode(observer)),))
    added: list[str] = []
    while True:
        now = scorer.criterion(comp)
        laws = [law for law, _ in LAW_ROWS if law in inputs and law not in added]
        offers = [(q,) for q in laws] + ([tuple(laws)] if len(laws) > 1 else [])
        best: tuple[float, tuple[str, ...], ElementMatrix] | None = None
        for path in paths:
            alone: dict[str, float] = {}
            for offer in offers:
                rows = tuple(Row(inputs[law], (Gene(THROUGH, 0.0),) * (n - 1 - len(path))
                                 + path + (Gene(GAIN, start),)) for law in offer)
                m = refit_gains(comp, ElementMatrix(comp.matrix.inputs, comp.matrix.rows + rows),
                                scorer)
                if m is None:
                    continue
                value = scorer.criterion(_with(comp, m))
                # Rows offered together each earn their place: together they beat every
                # one of them alone by more than the tolerance.
                if len(offer) == 1:
                    alone[offer[0]] = value
                elif not value < min(alone.get(law, now) for law in offer) * (1.0 - tolerance):
                    continue
                if best is None or value < best[0]:
                    best = (value, offer, m)
        if best is None or not best[0] < now * (1.0 - tolerance):
            return comp, added
        comp = _with(comp, best[2])
        added.extend(best[1])


#: The angle harmonics the static laws' block carries (:func:`offer_law_block`): the
#: orders of largest amplitude in its least squares.
BLOCK_HARMONICS = 2
#: The most ``tanh`` rows of the block's Stribeck hump (two come closer to a Gaussian hump
#: than one: on the family's kept searches the naming passed in 6 more runs of 216).
BLOCK_HUMPS = 2


def _block_row(n: int, input_: int, head: tuple[Gene, ...], lag: Gene, scale: Gene) -> Row:
    """``input -> head -> lpf -> gain``, ``through`` before it, as a row of ``n`` genes."""
    return Row(input_, (Gene(THROUGH, 0.0),) * (n - 2 - len(head)) + head + (lag, scale))


def offer_law_block(comp: Compensator, scorer: Scorer, tolerance: float | None,
                    inputs: Mapping[str, int], allowed: Collection[int] = (),
                    observer: float | None = None) -> tuple[Compensator, list[str]]:
    """Add the documented static laws together, through the observer's lag, when they earn it.

    The search's fitness is the RMSE over the training log, whose largest
    errors are at reversals, where friction follows its bristles and no
    static law holds; a search can win there and spend its rows' shapes on
    it, bending the steady friction curve the rest of the motion needs (on
    the family's draws: 2-5 times the least-squares error above 1 rad/s,
    with a model that beats least squares on the training log as a whole).
    An engineer's least squares on the laws' regressors gets the steady
    curve right. So the laws are offered as rows, all through the observer's
    low-pass ``lpf(observer)`` (without its lag they fit the target poorly):
    Coulomb ``v -> sign``, viscous ``v``, inertia ``a``, a Stribeck hump of
    up to :data:`BLOCK_HUMPS` rows ``v -> tanh(k)`` (its level carried by
    the Coulomb row, as the Stribeck seeds do,
    :mod:`~edm_sym.engines.abstraction.seeding`) and, with an angle, the
    :data:`BLOCK_HARMONICS` angle harmonics ``theta -> gain(k) ->
    sin_phase(phi)`` of largest amplitude. The slopes ``k``, the harmonics'
    orders and phases come from weighted least squares on the training part,
    the search's rows' outputs among its columns (each ``k`` over the
    Stribeck seeds' grid, the best given those before; orders 1 to
    ``MAX_ORDER``); then every row's gain is refitted (:func:`refit_gains`).
    With a ``tolerance``, the block is added only when it lowers the
    criterion by more than it; with None it is returned whenever it can be
    built, and :func:`apply_parsimony` prunes from the model with and
    without it, letting the held-out blocks decide.

    Offered only when the observer's bandwidth is known (``observer``, within
    the ``lpf`` range), the run has a velocity input (``inputs["coulomb"]``)
    and the schedule allows ``sign``, ``lpf`` and ``gain`` (``tanh`` and
    ``sin_phase`` for the hump and the harmonics) with at least three elements
    a row.

    Returns
    -------
    comp : Compensator
        With the block's rows added, or as given.
    added : list of str
        The laws added (empty when the block was not).

    """
    gain, low_pass = comp.ranges.get("gain"), comp.ranges.get("lpf")

    def ok(code: int) -> bool:
        return not allowed or code in allowed

    if (observer is None or gain is None or low_pass is None or "coulomb" not in inputs
            or not comp.matrix.rows or not (low_pass.low <= observer <= low_pass.high)
            or not all(ok(c) for c in (GAIN, LPF, SIGN))):
        return comp, []
    n = len(comp.matrix.rows[0].genes)
    if n < 3:
        return comp, []
    lag, one = Gene(LPF, low_pass.encode(observer)), Gene(GAIN, gain.encode(1.0))
    v = inputs["coulomb"]
    laws: dict[str, Row] = {"coulomb": _block_row(n, v, (Gene(SIGN, 0.0),), lag, one),
                            "viscous": _block_row(n, v, (), lag, one)}
    if "inertia" in inputs:
        laws["inertia"] = _block_row(n, inputs["inertia"], (), lag, one)
    part = scorer.parts["training"]
    # The seeds' thinning: at most SEED_SAMPLES samples in the least squares of a long log.
    lam = np.broadcast_to(np.asarray(scorer.weights("training"), float), part.y[part.sl].shape)
    keep = fitted_samples(lam)
    w = np.sqrt(lam[keep])

    def column(row: Row) -> np.ndarray:
        return scorer.row_output(comp, "training", row)[part.sl][keep]

    humps: list[Row] = []
    tanh = comp.ranges.get("tanh")
    if tanh is not None and ok(TANH):
        speed = part.x[v][part.sl][keep]
        humps = [_block_row(n, v, (Gene(TANH, tanh.encode(float(k))),), lag, one)
                 for k in stribeck_slopes(speed) if tanh.low <= k <= tanh.high]
    waves: list[tuple[int, Row, Row]] = []
    sine = comp.ranges.get("sin_phase")
    if "spatial" in inputs and sine is not None and ok(SIN_PHASE) and n >= 4:
        for k in range(1, MAX_ORDER + 1):
            if gain.low <= k <= gain.high:
                order = Gene(GAIN, gain.encode(float(k)))
                waves.append((k, _block_row(n, inputs["spatial"], (order, Gene(SIN_PHASE,
                              sine.encode(0.0))), lag, one),
                              _block_row(n, inputs["spatial"], (order, Gene(SIN_PHASE,
                              sine.encode(math.pi / 2))), lag, one)))
    base = [column(r) for r in comp.matrix.rows] + [column(r) for r in laws.values()]
    for _, s_row, c_row in waves:
        base += [column(s_row), column(c_row)]
    target = part.y[part.sl][keep]

    def fit(chosen: list[Row]) -> tuple[float, np.ndarray] | None:
        a = np.column_stack(base + [column(h) for h in chosen]) * w[:, None]
        with np.errstate(all="ignore"):
            coef, *_ = np.linalg.lstsq(a, target * w, rcond=None)
            left = float(np.sum((target * w - a @ coef) ** 2))
        return (left, coef) if np.all(np.isfinite(coef)) and math.isfinite(left) else None

    # The hump's slopes one at a time, each the best given those before (none when no slope
    # lowers the fit): two tanh rows come closer to exp(-(v/v_s)^2) than one.
    chosen: list[Row] = []
    best = fit(chosen)
    if best is None:
        return comp, []
    for _ in range(BLOCK_HUMPS):
        tried = [(f, h) for h in humps if h not in chosen and (f := fit([*chosen, h])) is not None]
        if not tried:
            break
        f, h = min(tried, key=lambda t: t[0][0])
        if not f[0] < best[0]:
            break
        chosen.append(h)
        best = f
    coef = best[1]
    rows = list(laws.values()) + chosen
    added = list(laws) + (["stribeck"] if chosen else [])
    first = len(comp.matrix.rows) + len(laws)
    amplitudes = []
    for q, (k, _, _) in enumerate(waves):
        s_coef, c_coef = coef[first + 2 * q], coef[first + 2 * q + 1]
        # s sin(k theta) + c cos(k theta) = A sin(k theta + phi), phi = atan2(c, s).
        amplitudes.append((math.hypot(s_coef, c_coef), k, math.atan2(c_coef, s_coef)))
    for amp, k, phase in sorted(amplitudes, reverse=True)[:BLOCK_HARMONICS]:
        if amp > 0 and gain.low <= amp <= gain.high:
            rows.append(_block_row(n, inputs["spatial"], (Gene(GAIN, gain.encode(float(k))),
                                                          Gene(SIN_PHASE, sine.encode(phase))),
                                   lag, one))
    if waves and len(rows) > len(laws) + len(chosen):
        added.append("spatial")
    m = refit_gains(comp, ElementMatrix(comp.matrix.inputs, comp.matrix.rows + tuple(rows)),
                    scorer)
    if m is None or (tolerance is not None and not scorer.criterion(_with(comp, m))
                     < scorer.criterion(comp) * (1.0 - tolerance)):
        return comp, []
    return _with(comp, m), added


def prune(comp: Compensator, scorer: Scorer, *, start: str = "search") -> list[Member]:
    """The greedy backward elimination from ``comp``'s matrix; returns the front.

    Parameters
    ----------
    comp : Compensator
        The search's model (its ranges and sample time serve every member).
    scorer : Scorer
        Scores on the training and held-out parts.
    start : str
        The ``change`` recorded for ``comp`` itself.

    Returns
    -------
    list of Member
        The Pareto front, simplest first: for each complexity the lowest
        criterion, keeping only members that beat every simpler one.
    """
    cur = comp.matrix
    seen = {cur: Member(cur, complexity(comp, cur), scorer.criterion(comp), start)}
    while True:
        c_cur = seen[cur].complexity
        best: Member | None = None
        for change, m in _candidates(comp, cur):
            if m in seen:
                cand = seen[m]
            else:
                cand = Member(m, complexity(comp, m), scorer.criterion(_with(comp, m)), change)
                seen[m] = cand
            if cand.complexity >= c_cur:
                continue
            if best is None or (cand.criterion, cand.complexity) < (best.criterion,
                                                                      best.complexity):
                best = cand
        if best is None:
            break
        refit = refit_gains(comp, best.matrix, scorer)
        if refit is not None and refit not in seen:
            r = Member(refit, complexity(comp, refit), scorer.criterion(_with(comp, refit)),
                       best.change + ", gains refitted")
            seen[refit] = r
            if r.criterion < best.criterion and r.complexity <= best.complexity:
                best = r
        cur = best.matrix
    return pareto(list(seen.values()))


def pareto(members: list[Member]) -> list[Member]:
    """Members no simpler (or equally complex) member matches or beats, simplest first."""
    order = sorted(members, key=lambda mb: (mb.complexity, _key(mb.criterion)))
    out: list[Member] = []
    for mb in order:
        if not math.isfinite(mb.criterion):
            continue
        if out and (mb.complexity == out[-1].complexity or mb.criterion >= out[-1].criterion):
            continue
        out.append(mb)
    return out


def _key(v: float) -> float:
    return v if math.isfinite(v) else math.inf


def apply_parsimony(comp: Compensator, scorer: Scorer, settings: ParsimonySettings,
                    rule: str | None = None, *, start_step: int | None = None,
                    refit: int = 0, refitted: bool = False, laws: Mapping[str, int] | None = None,
                    allowed: Collection[int] = (), observer: float | None = None
                    ) -> tuple[Compensator, dict[str, Any]]:
    """Prune ``comp``, choose the exported member and describe the front for result.json.

    Parameters
    ----------
    comp : Compensator
        The search's model.
    scorer : Scorer
        Training and held-out scores.
    settings : ParsimonySettings
        Whether to prune, the tolerance and the configured rule.
    rule : str, optional
        A selection rule overriding the settings' (``--select``).
    start_step : int, optional
        The step whose best ``comp`` is (recorded as ``start_step``).
    refit : int
        The refit budget the step bests had (recorded as ``refit``; 0: none).
    refitted : bool
        Whether ``comp`` is that step best refitted on the whole training part
        (recorded as ``refitted``).
    laws : mapping of str to int, optional
        The input of each linear law's row (:func:`offer_law_rows`, with
        ``settings.law_rows``; recorded as ``law_rows`` when one is added).
    allowed : collection of int
        The element codes the schedule allows (empty: every one).
    observer : float, optional
        The observer's bandwidth [rad/s] when the log records it: the law rows
        are also offered through its low-pass, and the static laws' block
        (:func:`offer_law_block`) is built; the pruning then runs from the
        model without and with the block, and the front is the one over every
        member both met (recorded as ``law_block`` when the chosen member
        descends from the block).

    Returns
    -------
    comp : Compensator
        The chosen model (``comp`` itself when pruning is off).
    record : dict
        The ``parsimony`` entry of result.json (empty when pruning is off or
        no model has a finite criterion).
    """
    if not settings.prune:
        return comp, {}
    rule = check_select(rule, "select") if rule is not None else settings.selection
    from edm_sym.core.result import matrix_to_json

    search = comp
    scorer.guard(comp)
    reference = scorer.criterion(comp)
    comp, moved = relieve_bounds(comp, scorer, settings.tolerance)
    # Two starts when the static laws' block can be built: the model without it and with it.
    # Both are pruned and the one front over both decides (the held-out blocks, not the
    # block's first offer on the whole model).
    starts: list[tuple[Compensator, list[str]]] = [(comp, [])]
    if laws and settings.law_rows:
        with_block, block = offer_law_block(comp, scorer, None, laws, allowed, observer)
        if block:
            starts.append((with_block, block))
    origin = ("search" if start_step is None else
              f"search (step {start_step} best{', refitted' if refitted else ''})")
    members_of: dict[ElementMatrix, tuple[list[str], list[str]]] = {}
    every: list[Member] = []
    for begin, block in starts:
        added: list[str] = []
        if laws and settings.law_rows:
            rest = {law: i for law, i in laws.items() if law not in block}
            begin, added = offer_law_rows(begin, scorer, settings.tolerance, rest, allowed,
                                          observer)
        start = (origin + (f", {moved} parameter(s) moved off a range bound" if moved else "")
                 + (f", the static laws' rows added ({', '.join(block)})" if block else "")
                 + "".join(f", a {law} row added" for law in added)
                 + (", gains refitted" if added or block else ""))
        for mb in prune(begin, scorer, start=start):
            if mb.matrix not in members_of:
                members_of[mb.matrix] = (block, added)
                every.append(mb)
    front = pareto(every)
    if not front:  # no model with a finite criterion: nothing to choose from
        return comp, {}
    k = select(front, rule, reference)
    block, added = members_of[front[k].matrix]
    unit = scorer.holdout.unit
    members = []
    for q, mb in enumerate(front, start=1):
        c = _with(comp, mb.matrix)
        members.append({
            "member": q, "complexity": mb.complexity, "criterion": [mb.criterion, unit],
            "change": mb.change, "matrix": matrix_to_json(mb.matrix),
            "training": scorer.score(c, "training"),
            "validation": (scorer.score(c, "validation") if "validation" in scorer.parts
                           else None),
        })
    record = {"complexity": COMPLEXITY, "criterion": scorer.criterion_name,
              "tolerance": settings.tolerance, "select": rule, "selected": k + 1,
              "search_complexity": complexity(search, search.matrix),
              "search_criterion": [reference if math.isfinite(reference) else None, unit],
              "search_matrix": matrix_to_json(search.matrix), "front": members}
    if block:
        record["law_block"] = block
    if added:
        record["law_rows"] = added
    if start_step is not None:
        record["start_step"] = start_step
        record["refit"] = int(refit)
        record["refitted"] = bool(refitted)
    return _with(comp, front[k].matrix), record
