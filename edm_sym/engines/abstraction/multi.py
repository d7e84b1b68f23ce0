"""A search's generations with multi-fidelity evaluation (``fidelity = "multi"``).

The rule is :mod:`~edm_sym.engines.abstraction.fidelity`'s: every new
individual is ranked on the low-fidelity part of the training log (its
gain fit too), the few that may enter the elite are scored on the whole
training log, the elites are the best by that score. :class:`Fidelities`
holds the two evaluators (the whole log's, and one of the low-fidelity part,
made anew when a step's weighting moves the windows); :class:`MultiSteps`
runs a step's first population, its generations and its restarts as
:mod:`~edm_sym.engines.abstraction.run` does with one evaluator, drawing
the same random numbers in the same order. The local search tunes the best
individual on the low-fidelity part; the tuned copy is scored on the whole
training log and joins the population only when it is better there.

:func:`evaluate_fitted` is the gain-fitted evaluation both fidelities use.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import replace
from typing import Any

import numpy as np

from edm_sym.core.elements import ParamRange
from edm_sym.engines.abstraction.checkpoint import StepState
from edm_sym.engines.abstraction.evaluator import Evaluator
from edm_sym.engines.abstraction.fidelity import (
    FidelitySettings,
    WindowPlan,
    plan_windows,
    promoted,
    rank_multi,
)
from edm_sym.engines.abstraction.ga import Operators, Population, Progress
from edm_sym.engines.abstraction.gain_fit import GAIN, scale_places
from edm_sym.engines.abstraction.local_search import tune_parameters
from edm_sym.engines.abstraction.schedule import StepConfig
from edm_sym.engines.abstraction.stats import EvalStats


def evaluate_fitted(evaluator: Evaluator, pop: Population, ops: Operators,
                    keep_first: bool = False) -> tuple[np.ndarray, int]:
    """Eq. 8 of ``pop``, improved in place by the gain fit; also the candidates made.

    The lanes make and evaluate each individual's gain-fit candidate where
    they fit it (one batch); only the genes of the better ones are written
    here. ``keep_first``: individual 0 (a step's inherited model) stays as it is.
    """
    if not ops.ga.gain_fit:
        return evaluator.evaluate(pop.inputs, pop.codes, pop.ps), 0
    gain = GAIN in ops.allowed
    places = scale_places(pop.codes, gain)
    res = evaluator.evaluation(pop.inputs, pop.codes, pop.ps, free=places[0] >= 0,
                               gain_allowed=gain)
    fit, scales, fitted = res.fitness, list(res.scales), res.fitted
    if keep_first:
        scales[0] = None
    made, better = 0, []
    for k, (f, _) in enumerate(fitted):
        if scales[k] is not None and not math.isnan(f):
            made += 1
            if f < fit[k]:
                better.append(k)
    for k in better:
        f, genes = fitted[k]
        j, i = genes[:, 0].astype(np.intp), genes[:, 1].astype(np.intp)
        pop.codes[k, j, i] = genes[:, 2].astype(np.int64)
        pop.ps[k, j, i] = genes[:, 3]
        fit[k] = f
    if better:
        evaluator.remember(pop.inputs[better], pop.codes[better], pop.ps[better], fit[better])
    return fit, made


class Fidelities:
    """The evaluators of a multi-fidelity search: the whole training log's and the windows'.

    Parameters
    ----------
    full : Evaluator
        The whole training log's (started by the caller).
    x, y : numpy.ndarray
        The training inputs (n_inputs, N) and target (N,).
    ts : float
        Sample time [s].
    ranges : mapping
        The parameter ranges (the whole log's: a gene means the same at both fidelities).
    settings : FidelitySettings
        The windows and the promotion rule.
    **evaluator : Any
        For the low-fidelity evaluator (``executor``, ``workers``, ``cache_bytes``,
        ``max_batch_rows``, ``client``).
    """

    def __init__(self, full: Evaluator, x: np.ndarray, y: np.ndarray, ts: float,
                 ranges: Mapping[str, ParamRange], settings: FidelitySettings, **evaluator: Any):
        self.full, self.x, self.y, self.ts = full, x, y, float(ts)
        self.ranges, self.settings, self.options = dict(ranges), settings, evaluator
        self.low: Evaluator | None = None
        self.plan: WindowPlan | None = None
        self._closed = EvalStats()

    def set_step(self, weights: np.ndarray | float, reject_poles: bool) -> None:
        """A step's Lambda (masked) and pole rule on both evaluators; new windows if they move."""
        self.full.set_weights(weights)
        self.full.set_reject_poles(reject_poles)
        plan = plan_windows(weights, self.y.shape[0], self.ts, self.settings)
        if self.low is None or plan != self.plan:
            self._close_low()
            self.low = Evaluator(np.ascontiguousarray(self.x[:, plan.index]), self.y[plan.index],
                                 self.ts, self.ranges, spans=self.full.spans, full_log=False,
                                 **self.options)
            self.low.start()
            self.plan = plan
        self.low.set_weights(plan.weights(weights))
        self.low.set_reject_poles(reject_poles)

    @property
    def stats(self) -> EvalStats:
        """Both evaluators' counters added up (and those of low-fidelity evaluators closed)."""
        parts = [self._closed, self.full.stats] + ([self.low.stats] if self.low else [])
        return EvalStats.merged(parts)

    def _close_low(self) -> None:
        if self.low is not None:
            self.low.close()
            self._closed = EvalStats.merged([self._closed, self.low.stats])
            self.low = None

    def close(self) -> None:
        """Close the low-fidelity evaluator (the caller closes the full one)."""
        self._close_low()

    def abort(self) -> None:
        """Shut the low-fidelity evaluator's processes down without waiting."""
        if self.low is not None:
            self.low.abort()


def _reference(full: np.ndarray, low: np.ndarray) -> float | None:
    """The largest low-fidelity eq. 8 among elites scored on the whole log (None: none)."""
    known = np.isfinite(full)
    return float(np.max(low[known])) if known.any() else None


class MultiSteps:
    """A step's populations judged at two fidelities (see the module text).

    Parameters
    ----------
    fid : Fidelities
        The evaluators (the step's weighting set).
    rng : numpy.random.Generator
        The run's generator (the same draws as a search of full fidelity).
    """

    def __init__(self, fid: Fidelities, rng: np.random.Generator):
        self.fid, self.rng = fid, rng

    def judge(self, pop: Population, ops: Operators, reference: float | None, *,
              least: int = 0, always: Sequence[int] = ()) -> tuple[np.ndarray, np.ndarray, int]:
        """Low-fidelity eq. 8 of ``pop`` (gain-fitted in place), the promoted ones' whole-log eq. 8.

        Returns
        -------
        full : numpy.ndarray
            Eq. 8 on the whole training log (``inf`` where not promoted).
        low : numpy.ndarray
            Eq. 8 on the low-fidelity part.
        made : int
            Gain-fit candidates evaluated.
        """
        low, made = evaluate_fitted(self.fid.low, pop, ops, keep_first=bool(always))
        idx = promoted(low, reference, self.fid.settings, least=least, always=always)
        full = np.full(len(pop), np.inf)
        if idx:
            full[idx] = self.fid.full.evaluate(pop.inputs[idx], pop.codes[idx], pop.ps[idx])
        return full, low, made

    def first(self, pop: Population, ops: Operators, keep_first: bool
              ) -> tuple[np.ndarray, np.ndarray, int]:
        """A step's initial population: the elites' places filled from the whole log's scores."""
        return self.judge(pop, ops, None, least=ops.ga.elites, always=(0,) if keep_first else ())

    def generation(self, cur: StepState, step: StepConfig, ops: Operators) -> StepState:
        """One generation of Algorithm 1 with the elites judged on the whole training log."""
        ga = step.ga
        pop, fit, low = cur.population, cur.fitness, cur.low
        keys = self.fid.full.individual_keys(pop.inputs, pop.codes, pop.ps)
        order = rank_multi(fit, low, keys, ga.elites)
        ranked, rfit, rlow = pop.take(order), fit[order], low[order]
        size, e = len(pop), ga.elites
        kids = ops.offspring(self.rng, ranked, size - e)
        kfit, klow, extra = self.judge(kids, ops, _reference(rfit[:e], rlow[:e]))
        new_pop = Population.concat([ranked.take(np.arange(e)), kids])
        new_fit = np.concatenate([rfit[:e], kfit])
        new_low = np.concatenate([rlow[:e], klow])
        best = float(np.min(new_fit))
        before = Progress(cur.generation, cur.blocks, cur.block_start_best, cur.ref_best,
                          cur.since_improvement)
        prog = before.after(ga, best)
        if prog.stagnant(ga):
            # Stagnation: the best individual tuned on the low-fidelity part, the tuned copy
            # scored on the whole training log; where it is better there, it takes the place
            # of the worst by low fidelity, so the original stays.
            k = int(np.argmin(new_fit))
            tuned, tlow, used = tune_parameters(self.fid.low, new_pop.take([k]),
                                                float(new_low[k]),
                                                max_evaluations=ga.local_search_evaluations)
            extra += used
            if tlow < new_low[k]:
                tfit = float(self.fid.full.evaluate(tuned.inputs, tuned.codes, tuned.ps)[0])
                if tfit < best:
                    worst = e + int(np.argmax(new_low[e:]))
                    new_pop.inputs[worst], new_pop.codes[worst], new_pop.ps[worst] = (
                        tuned.inputs[0], tuned.codes[0], tuned.ps[0])
                    new_fit[worst], new_low[worst] = tfit, tlow
                    best = tfit
                    prog = before.after(ga, best)
        restarts = cur.restarts
        if prog.done and restarts < ga.restarts:
            restarts += 1
            new_pop, new_fit, new_low, used = self._restart(new_pop, new_fit, new_low, ops)
            extra += used
            best = float(np.min(new_fit))
            prog = replace(Progress.start(best), generation=prog.generation)
        return StepState(step=cur.step, generation=prog.generation, blocks=prog.blocks,
                         block_start_best=prog.block_start_best, ref_best=prog.ref_best,
                         since_improvement=prog.since_improvement,
                         done=prog.done, population=new_pop, fitness=new_fit,
                         history=[*cur.history, best],
                         evaluations=cur.evaluations + len(kids) + extra, restarts=restarts,
                         low=new_low)

    def _restart(self, pop: Population, fit: np.ndarray, low: np.ndarray, ops: Operators
                 ) -> tuple[Population, np.ndarray, np.ndarray, int]:
        """A stagnating step's new population (as a search of full fidelity draws it)."""
        ga = ops.ga
        p, m, n = pop.shape
        keys = self.fid.full.individual_keys(pop.inputs, pop.codes, pop.ps)
        order = rank_multi(fit, low, keys, ga.elites)[:ga.elites]
        elites = pop.take(order)
        fresh = ops.random_population(self.rng, p - ga.elites, m, n)
        count = max(1, int(round(ga.inherit_fraction * p)))
        redraw = self.rng.integers(m, size=count)
        for i in range(count):
            keep = np.arange(m) != redraw[i]
            fresh.inputs[i, keep] = elites.inputs[0, keep]
            fresh.codes[i, keep] = elites.codes[0, keep]
            fresh.ps[i, keep] = elites.ps[0, keep]
        ffit, flow, extra = self.judge(fresh, ops, _reference(fit[order], low[order]))
        return (Population.concat([elites, fresh]), np.concatenate([fit[order], ffit]),
                np.concatenate([low[order], flow]), len(fresh) + extra)
