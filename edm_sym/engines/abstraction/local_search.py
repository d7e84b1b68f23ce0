"""Local search: the elite's continuous parameters tuned by least squares.

The GA finds structures (which elements, which inputs) and rough parameters;
its parameter shift (Fig. 7a) is a random walk, slow to settle a filter's
cut-off, a sine's phase or a dead zone's width, and the gain fit only sets
scales. When a step stagnates, :func:`tune_parameters` runs
:func:`scipy.optimize.least_squares` (trust-region reflective, bounds
[0, 1]) on the normalised parameters ``p`` of one individual, residual
``sqrt(Lambda) * (target - sum of rows)`` (so its cost is eq. 8 squared).
Jacobians are forward differences whose perturbed individuals are evaluated
in one batch of the evaluator (each perturbation changes one row; the others
come from the row cache), so the search uses the workers and is a pure
function of the genes: no random numbers, the same result whatever the
number of workers.

Parameters that only exist on a grid (a dead time in samples) get a zero or
a crude derivative and are left where they are, which is the GA's job.

A relay's band (a :class:`~edm_sym.core.elements.RelayElement`, ``hysteresis``)
moves the samples where the relay switches: the forward differences see no
change until a sample crosses it. After the search, :func:`step_candidates`
also scans each relay's band over factors 1/4 .. 4 (:func:`scan_relay_bands`)
and refits around the best one
(docs/abstraction.md#parsimony-pruning-and-the-complexity-vs-fitness-front).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from edm_sym.core.elements import REGISTRY, ParamRange, RelayElement
from edm_sym.core.matrix import Compensator, ElementMatrix
from edm_sym.core.result import StepRecord
from edm_sym.engines.abstraction.evaluator import Evaluator
from edm_sym.engines.abstraction.ga import Population
from edm_sym.engines.abstraction.holdout import Holdout, mask_weights

#: Element codes with a continuous parameter.
PARAMETRIC = frozenset(code for code, el in REGISTRY.items() if el.param is not None)

#: Forward-difference step in p (a parameter near its upper bound steps down).
STEP = 1e-4

#: Element codes whose parameter is a relay's band (it switches, or not, on a sample).
RELAY_BANDS = frozenset(code for code, el in REGISTRY.items() if issubclass(el, RelayElement))
#: Factors on a relay's band tried by :func:`scan_relay_bands`: 1/4 .. 4 in steps of 2^(1/4).
BAND_FACTORS = tuple(2.0 ** (k / 4) for k in range(-8, 9) if k)


class _Budget(Exception):
    pass


def free_parameters(codes: np.ndarray) -> list[tuple[int, int]]:
    """(row, element) of every gene of one individual that has a parameter."""
    m, n = codes.shape
    return [(j, i) for j in range(m) for i in range(n) if int(codes[j, i]) in PARAMETRIC]


def tune_parameters(evaluator: Evaluator, best: Population, fitness: float, *,
                    max_evaluations: int) -> tuple[Population, float, int]:
    """Least-squares tuning of the parameters of one individual.

    Parameters
    ----------
    evaluator : Evaluator
        With the step's weighting set.
    best : Population
        One individual.
    fitness : float
        Its eq. 8 value.
    max_evaluations : int
        Most individuals evaluated (residuals and Jacobian columns together).

    Returns
    -------
    individual : Population
        The best individual seen (``best`` itself when nothing was better).
    fitness : float
        Its eq. 8 value.
    evaluations : int
        Individuals evaluated.
    """
    free = free_parameters(best.codes[0])
    if not free or not np.isfinite(fitness) or max_evaluations < len(free) + 2:
        return best, fitness, 0
    jj = np.array([j for j, _ in free])
    ii = np.array([i for _, i in free])
    y = evaluator.target
    w = evaluator.weights
    sw = np.sqrt(w) if np.isscalar(w) else np.sqrt(np.asarray(w, dtype=float))
    state = {"evals": 0, "best_p": best.ps[0, jj, ii].copy(), "best_f": float(fitness),
             "residual": {}}

    def batch(points: np.ndarray) -> tuple[np.ndarray, list]:
        count = len(points)
        if state["evals"] + count > max_evaluations:
            raise _Budget
        state["evals"] += count
        ps = np.repeat(best.ps, count, axis=0)
        ps[:, jj, ii] = points
        res = evaluator.evaluation(np.repeat(best.inputs, count, axis=0),
                                   np.repeat(best.codes, count, axis=0), ps, rows=True)
        fit, rows = res.fitness, res.rows
        for k in range(count):
            if fit[k] < state["best_f"]:
                state["best_f"], state["best_p"] = float(fit[k]), points[k].copy()
        return fit, rows

    def residual(p: np.ndarray) -> np.ndarray:
        key = p.tobytes()
        if key not in state["residual"]:
            _, rows = batch(p[None, :])
            # Copies: the evaluator's row views are valid until its next call only.
            outs = [np.array(r) for r in rows[0][1]]
            with np.errstate(over="ignore", invalid="ignore"):
                state["residual"] = {key: (sw * (y - np.sum(outs, axis=0)), outs)}
        return state["residual"][key][0]

    def jacobian(p: np.ndarray) -> np.ndarray:
        res = residual(p)
        base_rows = state["residual"][p.tobytes()][1]
        h = np.where(p + STEP <= 1.0, STEP, -STEP)
        pts = np.repeat(p[None, :], len(p), axis=0)
        pts[np.arange(len(p)), np.arange(len(p))] += h
        _, rows = batch(pts)
        jac = np.empty((res.shape[0], len(p)))
        with np.errstate(over="ignore", invalid="ignore"):
            for k in range(len(p)):
                j = jj[k]
                jac[:, k] = -(sw * (rows[k][1][j] - base_rows[j])) / h[k]
        jac[~np.isfinite(jac)] = 0.0
        return jac

    x0 = best.ps[0, jj, ii].astype(float)
    try:
        if np.all(np.isfinite(residual(x0))):
            least_squares(residual, x0, jac=jacobian, bounds=(0.0, 1.0), method="trf",
                          x_scale=1.0, max_nfev=max_evaluations)
    except _Budget:
        pass
    if not state["best_f"] < fitness:
        return best, fitness, state["evals"]
    out = best.take([0])
    out.ps[0, jj, ii] = state["best_p"]
    return out, state["best_f"], state["evals"]


def scan_relay_bands(evaluator: Evaluator, best: Population, fitness: float,
                     ranges: Mapping[str, ParamRange]) -> tuple[Population, float, int]:
    """Each relay's band scaled by :data:`BAND_FACTORS`, one relay after another.

    A relay's band moves the samples where it switches, a step the least
    squares' forward differences do not see: a band inside the noise of its
    input at rest switches on that noise (the axis standing still at the
    start of a log, the observer's estimate rising from 0), and a slightly
    wider one does not. Each relay's factors are evaluated in one batch;
    the best is kept where it lowers eq. 8, before the next relay.

    Returns
    -------
    individual, fitness, evaluations
        As :func:`tune_parameters`.
    """
    codes = best.codes[0]
    relays = [(j, i) for j in range(codes.shape[0]) for i in range(codes.shape[1])
              if int(codes[j, i]) in RELAY_BANDS]
    if not relays or not np.isfinite(fitness):
        return best, fitness, 0
    out, evals = best.take([0]), 0
    for j, i in relays:
        rng = ranges[REGISTRY[int(codes[j, i])].name]
        band = rng.decode(float(out.ps[0, j, i]))
        points = sorted({rng.encode(band * f) for f in BAND_FACTORS} - {float(out.ps[0, j, i])})
        if not points:
            continue
        ps = np.repeat(out.ps, len(points), axis=0)
        ps[:, j, i] = points
        fit = evaluator.evaluate(np.repeat(out.inputs, len(points), axis=0),
                                 np.repeat(out.codes, len(points), axis=0), ps)
        evals += len(points)
        k = int(np.argmin(fit))
        if fit[k] < fitness:
            fitness = float(fit[k])
            out.ps[0, j, i] = points[k]
    return out, fitness, evals


@dataclass(frozen=True)
class Candidate:
    """A candidate for the search's model: a step best as the GA left it, or its refit."""

    matrix: ElementMatrix
    #: The step whose best it is (1-based).
    step: int
    #: Refitted on the whole training part (True) or as the GA left it.
    refitted: bool
    #: The search it comes from (several independent searches; 0 with one).
    search: int = 0


def step_candidates(steps: Sequence[StepRecord], comp: Compensator, hold: Holdout, *,
                    max_evaluations: int, reject_poles: bool = True
                    ) -> list[Candidate]:
    """The step bests, each followed by its refit on the whole training part where that helps.

    The steps of the schedule optimise different weightings (eq. 15's windows,
    eq. 16's large torques); a step best is fitted to its own. After the
    search, :func:`tune_parameters` refits each with Lambda = 1 on the fitted
    samples and 0 on the held-out ones, closer to the measure the search's
    model is chosen by (docs/abstraction.md#parsimony-pruning-and-the-complexity-vs-fitness-front).

    Parameters
    ----------
    steps : sequence of StepRecord
        The step bests.
    comp : Compensator
        Sample time and parameter ranges.
    hold : Holdout
        The training part and its mask.
    max_evaluations : int
        Budget of each refit (individuals evaluated); 0: no refit.
    reject_poles : bool
        A tangent pole inside an input's range is an infinite fitness (as in the GA).

    Returns
    -------
    list of Candidate
        Each step best, then its refit where that fits better (``search`` 0).
    """
    out = []
    if not max_evaluations:
        return [Candidate(s.matrix, s.step, False) for s in steps]
    n = hold.n_train
    x = np.ascontiguousarray(hold.training.x[:, :n])
    with Evaluator(x, hold.training.y[:n], comp.sample_time, comp.ranges, workers=1,
                   cache_bytes=64 * 2**20, reject_poles=reject_poles,
                   starts=hold.training.starts) as ev:
        ev.set_weights(mask_weights(np.ones(n), hold.mask))
        for s in steps:
            out.append(Candidate(s.matrix, s.step, False))
            pop = Population.from_matrix(s.matrix)
            f0 = float(ev.evaluate(pop.inputs, pop.codes, pop.ps)[0])
            tuned, f1, _ = tune_parameters(ev, pop, f0, max_evaluations=max_evaluations)
            tuned, f1 = (tuned, f1) if f1 < f0 else (pop, f0)
            scanned, f2, _ = scan_relay_bands(ev, tuned, f1, comp.ranges)
            if f2 < f1:
                # A band moved: the other parameters settle around it again.
                tuned, f1, _ = tune_parameters(ev, scanned, f2, max_evaluations=max_evaluations)
            if f1 < f0:
                out.append(Candidate(tuned.matrix(0, s.matrix.inputs), s.step, True))
    return out
