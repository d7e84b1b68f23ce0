"""Method ``"ga"``: the LuGre parameters by the project's genetic algorithm.

The paper identifies the LuGre baseline with a GA ("the parameters of the
LuGre model are calculated by GA", Table I). This method runs Algorithm 1 with
the operators of :mod:`edm_sym.engines.abstraction.ga` on the fitness of eq. 8, over
the same reduced space as the ``"scipy"`` method (variable projection): an
individual is one row of four genes whose normalised parameters ``p`` in
[0, 1] map linearly onto the four shape parameters
``theta = (log10 v_s, log10 r, log10 l, zf)`` (see
:mod:`edm_sym.engines.lugre.identify`), and every evaluation solves the friction's
linear parameters ``(tau_c, sigma1, sigma2)`` exactly, a Lamarckian step like
the abstraction's gain fit. The genes' element codes carry no meaning here
(they are all ``through``), so crossover, parameter shift and mutation act on
the parameters only.

Each generation: ranking (repeated genomes after distinct ones), elite
preservation, tournament selection, two-point crossover, parameter shift,
mutation (:meth:`Operators.offspring`), then the stopping rule of the
abstraction (:class:`Progress`: blocks of G_max generations, ``continue``
while improving, ``patience``). All random numbers come from one generator
seeded with ``seed``; the evaluation draws none, so a run is reproducible.
"""

from __future__ import annotations

import math

import numpy as np

from edm_sym.engines.abstraction.ga import Operators, Population, Progress, rank
from edm_sym.engines.abstraction.schedule import GaSettings
from edm_sym.engines.lugre.identify import LuGreProblem, MethodOutcome, _TimeUp, _VarPro, register_method

__all__ = ["LUGRE_GA", "identify_ga"]

#: Settings of the ``"ga"`` method. Four genes per individual, so the per-gene
#: rates are higher than the abstraction's (which has tens of genes), and the
#: smallest shift is 1e-7 of a range (about 1e-6 decades for ``l``) for the
#: final tuning that the ``"scipy"`` method leaves to Nelder-Mead.
LUGRE_GA = GaSettings(
    population=40,
    elites=2,
    tournament=3,
    crossover_rate=0.8,
    row_crossover=0.0,
    shift_rate=0.5,
    shift_min=1e-7,
    shift_max=0.1,
    mutation_rate=0.1,
    input_mutation_rate=0.0,
    through_rate=0.0,
    generations=50,
    continue_mode="improving",
    max_blocks=20,
    patience=25,
    min_improvement=1e-6,
    gain_fit=False,
    elements=("through",),
)


class _Fitness:
    """Eq. 8 of genomes through the variable projection, each distinct genome once."""

    def __init__(self, objective: _VarPro):
        self.objective = objective
        low, high = np.array(objective.bounds, dtype=float).T
        self.low, self.span = low, high - low
        self.seen: dict[bytes, float] = {}

    def __call__(self, pop: Population) -> np.ndarray:
        out = np.empty(len(pop))
        for k, genes in enumerate(pop.ps[:, 0]):
            key = genes.tobytes()
            f = self.seen.get(key)
            if f is None:
                f = self.objective(self.low + genes * self.span)
                f = f if math.isfinite(f) else math.inf
                self.seen[key] = f
            out[k] = f
        return out


@register_method("ga")
def identify_ga(problem: LuGreProblem, *, seed: int, settings: GaSettings = LUGRE_GA) -> MethodOutcome:
    """Identify the LuGre parameters with the genetic algorithm (Algorithm 1).

    Parameters
    ----------
    problem : LuGreProblem
        The identification task.
    seed : int
        Seed of the only random generator: equal seeds give equal results
        (without a deadline).
    settings : GaSettings, optional
        Population, rates and stopping rule (default :data:`LUGRE_GA`);
        ``row_crossover``, ``input_mutation_rate``, ``through_rate``,
        ``inherit_fraction``, ``gain_fit`` and ``elements`` do not apply.

    Returns
    -------
    MethodOutcome
        The best parameters seen and the number of model simulations (a
        genome seen before is not simulated again). At the deadline the
        search stops after at least one simulation.
    """
    objective = _VarPro(problem)
    fitness = _Fitness(objective)
    ops = Operators(settings, 1)
    rng = np.random.default_rng(seed)
    size, elites = settings.population, settings.elites
    try:
        pop = ops.random_population(rng, size, 1, len(objective.bounds))
        fit = fitness(pop)
        progress = Progress.start(float(np.min(fit)))
        while not progress.done:
            order = rank(fit, [genes.tobytes() for genes in pop.ps[:, 0]])
            ranked, ranked_fit = pop.take(order), fit[order]
            kids = ops.offspring(rng, ranked, size - elites)
            pop = Population.concat([ranked.take(np.arange(elites)), kids])
            fit = np.concatenate([ranked_fit[:elites], fitness(kids)])
            progress = progress.after(settings, float(np.min(fit)))
            objective.generation = progress.generation
    except _TimeUp:
        pass
    assert objective.best is not None
    return MethodOutcome(objective.params(*objective.best), objective.evaluations)
