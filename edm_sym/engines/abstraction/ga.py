"""The genetic operators of Algorithm 1 on a population of element matrices.

An individual is the chromosome of eq. 2: per row an input code (its
parameter fixed at 1) and n element genes, each an element code ``c`` with its
normalised parameter ``p`` in [0, 1]. A population of P individuals with m
rows and n elements per row is held as three arrays: ``inputs`` (P, m),
``codes`` (P, m, n) and ``ps`` (P, m, n). Every operator draws its random
numbers from one :class:`numpy.random.Generator` in a fixed amount and order,
so a run is reproduced exactly from the seed (or from a checkpoint's
generator state).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from edm_sym.core.elements import BY_NAME, REGISTRY
from edm_sym.core.matrix import ElementMatrix, Gene, Row
from edm_sym.engines.abstraction.schedule import GaSettings

THROUGH = BY_NAME["through"].code


@dataclass
class Population:
    """P individuals of m rows and n elements per row (see the module text)."""

    inputs: np.ndarray
    codes: np.ndarray
    ps: np.ndarray

    def __len__(self) -> int:
        return self.codes.shape[0]

    @property
    def shape(self) -> tuple[int, int, int]:
        """(P, m, n)."""
        return self.codes.shape

    def take(self, idx: np.ndarray | Sequence[int]) -> Population:
        """The individuals at ``idx`` (copies)."""
        idx = np.asarray(idx, dtype=np.intp)
        return Population(self.inputs[idx].copy(), self.codes[idx].copy(), self.ps[idx].copy())

    @staticmethod
    def concat(parts: Sequence[Population]) -> Population:
        """Stack populations of the same matrix shape."""
        return Population(np.concatenate([p.inputs for p in parts]),
                          np.concatenate([p.codes for p in parts]),
                          np.concatenate([p.ps for p in parts]))

    def matrix(self, k: int, input_names: Sequence[str]) -> ElementMatrix:
        """Individual ``k`` as an :class:`~edm_sym.core.matrix.ElementMatrix`."""
        rows = tuple(
            Row(int(self.inputs[k, j]),
                tuple(Gene(int(c), float(p))
                      for c, p in zip(self.codes[k, j], self.ps[k, j], strict=True)))
            for j in range(self.codes.shape[1]))
        return ElementMatrix(tuple(input_names), rows)

    @staticmethod
    def from_matrix(matrix: ElementMatrix) -> Population:
        """A population of one individual."""
        return Population(
            np.array([[r.input for r in matrix.rows]], dtype=np.int64),
            np.array([[[g.code for g in r.genes] for r in matrix.rows]], dtype=np.int64),
            np.array([[[g.p for g in r.genes] for r in matrix.rows]], dtype=float))


def allowed_codes(elements: Sequence[str] | None) -> np.ndarray:
    """Element codes the GA may draw, sorted (all registered ones for None)."""
    if elements is None:
        return np.array(sorted(REGISTRY), dtype=np.int64)
    return np.array(sorted(BY_NAME[name].code for name in elements), dtype=np.int64)


class Operators:
    """Selection, crossover, parameter shift and mutation for one step's settings.

    Parameters
    ----------
    ga : GaSettings
        Rates and sizes.
    n_inputs : int
        Number of input signals (input codes are 0 .. n_inputs - 1).
    barred : sequence of int
        Input codes no drawn or mutated row takes (an angle that is a clock of
        every training log: docs/abstraction.md#clocks-rows-that-read-time-from-the-angle);
        empty: every input, drawn with the same random numbers as ever.
    """

    def __init__(self, ga: GaSettings, n_inputs: int, barred: Sequence[int] = ()):
        self.ga = ga
        self.n_inputs = int(n_inputs)
        self.choices = (None if not barred else
                        np.array([i for i in range(self.n_inputs) if i not in set(barred)],
                                 dtype=np.int64))
        self.allowed = allowed_codes(ga.elements)
        self.through_rate = ga.through_rate if THROUGH in self.allowed else 0.0

    # -- drawing ----------------------------------------------------------------
    def random_codes(self, rng: np.random.Generator, shape: tuple[int, ...]) -> np.ndarray:
        """Element codes: ``through`` with probability ``through_rate``, else uniform."""
        pick = self.allowed[rng.integers(len(self.allowed), size=shape)]
        through = rng.random(shape) < self.through_rate
        return np.where(through, THROUGH, pick)

    def random_inputs(self, rng: np.random.Generator, shape: int | tuple[int, ...]) -> np.ndarray:
        """Input codes, uniform over the inputs not barred."""
        if self.choices is None:
            return rng.integers(self.n_inputs, size=shape)
        return self.choices[rng.integers(len(self.choices), size=shape)]

    def random_rows(self, rng: np.random.Generator, count: int, n: int
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``count`` random rows: input codes (count,), codes and ps (count, n)."""
        inputs = self.random_inputs(rng, count)
        codes = self.random_codes(rng, (count, n))
        ps = rng.random((count, n))
        return inputs.astype(np.int64), codes.astype(np.int64), ps

    def random_population(self, rng: np.random.Generator, p: int, m: int, n: int) -> Population:
        """P random individuals."""
        inputs, codes, ps = self.random_rows(rng, p * m, n)
        return Population(inputs.reshape(p, m), codes.reshape(p, m, n), ps.reshape(p, m, n))

    # -- Algorithm 1 ------------------------------------------------------------
    def select(self, rng: np.random.Generator, count: int, size: int) -> np.ndarray:
        """Tournament selection on a ranked population (index 0 is the best).

        Returns the ranks of ``count`` parents; each is the best of
        ``tournament`` ranks drawn uniformly.
        """
        return rng.integers(size, size=(count, self.ga.tournament)).min(axis=1)

    def crossover(self, rng: np.random.Generator, pop: Population) -> None:
        """Two-point crossover of consecutive pairs, in place (Fig. 6).

        The chromosome is read row by row, ``[input, e_1 .. e_n]`` per row;
        the genes between the two cut points are exchanged with both their
        element code and parameter. With probability ``row_crossover`` the
        cut points fall on row boundaries, so whole rows change places.
        """
        p, m, n = pop.shape
        pairs = p // 2
        length = m * (n + 1)
        do = rng.random(pairs) < self.ga.crossover_rate
        aligned = rng.random(pairs) < self.ga.row_crossover
        ra, rb = rng.integers(m + 1, size=pairs), rng.integers(m, size=pairs)
        rb = rb + (rb >= ra)
        ga_, gb = rng.integers(length + 1, size=pairs), rng.integers(length, size=pairs)
        gb = gb + (gb >= ga_)
        lo = np.where(aligned, np.minimum(ra, rb) * (n + 1), np.minimum(ga_, gb))
        hi = np.where(aligned, np.maximum(ra, rb) * (n + 1), np.maximum(ga_, gb))
        pos = np.arange(length).reshape(m, n + 1)
        mask = (pos >= lo[:, None, None]) & (pos < hi[:, None, None]) & do[:, None, None]
        a, b = np.arange(0, 2 * pairs, 2), np.arange(1, 2 * pairs, 2)
        for arr, sel in ((pop.inputs, mask[:, :, 0]),
                         (pop.codes, mask[:, :, 1:]), (pop.ps, mask[:, :, 1:])):
            xa, xb = arr[a], arr[b]
            arr[a] = np.where(sel, xb, xa)
            arr[b] = np.where(sel, xa, xb)

    def shift(self, rng: np.random.Generator, pop: Population) -> None:
        """Parameter shift (Fig. 7a), in place: small steps of ``p`` up or down.

        Each element gene shifts with probability ``shift_rate`` by a step
        whose size is log-uniform in [shift_min, shift_max]; ``p`` stays in
        [0, 1].
        """
        shape = pop.ps.shape
        hit = rng.random(shape) < self.ga.shift_rate
        lo, hi = np.log10(self.ga.shift_min), np.log10(self.ga.shift_max)
        size = 10.0 ** rng.uniform(lo, hi, shape)
        sign = np.where(rng.random(shape) < 0.5, -1.0, 1.0)
        pop.ps[...] = np.where(hit, np.clip(pop.ps + sign * size, 0.0, 1.0), pop.ps)

    def mutate(self, rng: np.random.Generator, pop: Population) -> None:
        """Mutation (Fig. 7b), in place: genes rewritten with a freshly drawn ``p``.

        Each element gene is rewritten with probability ``mutation_rate``
        (new element code and new ``p``); each row's input code with
        probability ``input_mutation_rate``.
        """
        shape = pop.codes.shape
        hit = rng.random(shape) < self.ga.mutation_rate
        codes = self.random_codes(rng, shape)
        ps = rng.random(shape)
        pop.codes[...] = np.where(hit, codes, pop.codes)
        pop.ps[...] = np.where(hit, ps, pop.ps)
        hit_in = rng.random(pop.inputs.shape) < self.ga.input_mutation_rate
        new_in = self.random_inputs(rng, pop.inputs.shape)
        pop.inputs[...] = np.where(hit_in, new_in, pop.inputs)

    def offspring(self, rng: np.random.Generator, ranked: Population, count: int) -> Population:
        """Selection, crossover, parameter shift and mutation: ``count`` children."""
        parents = self.select(rng, count + (count % 2), len(ranked))
        kids = ranked.take(parents)
        self.crossover(rng, kids)
        self.shift(rng, kids)
        self.mutate(rng, kids)
        return kids.take(np.arange(count))


def rank(fitness: np.ndarray, keys: Sequence[bytes]) -> np.ndarray:
    """Order of a population, best first; repeated genomes go after all distinct ones.

    Parameters
    ----------
    fitness : numpy.ndarray
        Shape (P,) fitness values (lower is better).
    keys : sequence of bytes
        Canonical genome keys (see :meth:`Evaluator.individual_keys`).

    Returns
    -------
    numpy.ndarray
        Indices, best first; ties keep index order.
    """
    seen: set[bytes] = set()
    dup = np.zeros(len(keys), dtype=bool)
    for k in np.argsort(fitness, kind="stable"):
        if keys[k] in seen:
            dup[k] = True
        seen.add(keys[k])
    return np.lexsort((np.arange(len(keys)), fitness, dup))


@dataclass(frozen=True)
class Progress:
    """Where a GA run stands for its stopping rule (G_max blocks, ``continue``, ``patience``).

    Parameters
    ----------
    generation : int
        Generations done (0: the initial population).
    blocks : int
        Blocks of ``generations`` (G_max) generations done.
    block_start_best : float
        Best fitness when the current block started.
    ref_best : float
        Best fitness at the last improvement that counted for ``patience``.
    since_improvement : int
        Generations since that improvement.
    done : bool
        Whether the rule says stop.
    """

    generation: int = 0
    blocks: int = 0
    block_start_best: float = math.inf
    ref_best: float = math.inf
    since_improvement: int = 0
    done: bool = False

    @staticmethod
    def start(best: float) -> Progress:
        """The progress after the initial population, whose best fitness is ``best``."""
        return Progress(block_start_best=best, ref_best=best)

    def after(self, ga: GaSettings, best: float) -> Progress:
        """The progress after one more generation whose best fitness is ``best``.

        Parameters
        ----------
        ga : GaSettings
            ``generations``, ``continue_mode``, ``max_blocks``, ``patience``
            and ``min_improvement`` are read.
        best : float
            Best fitness after the generation (never above the previous best:
            the elites are kept).

        Returns
        -------
        Progress
            The new state; ``done`` once ``patience`` generations passed
            without a relative improvement of ``min_improvement``, or after a
            block of G_max generations when ``continue`` says so.
        """
        gen = self.generation + 1
        ref, since = self.ref_best, self.since_improvement + 1
        if best < ref * (1.0 - ga.min_improvement):
            ref, since = best, 0
        blocks, block_start = self.blocks, self.block_start_best
        done = bool(ga.patience and since >= ga.patience)
        if gen % ga.generations == 0:
            blocks += 1
            improved = best < block_start * (1.0 - ga.min_improvement)
            block_start = best
            if (ga.continue_mode == "no" or blocks >= ga.max_blocks
                    or (ga.continue_mode == "improving" and not improved)):
                done = True
        return replace(self, generation=gen, blocks=blocks, block_start_best=block_start,
                       ref_best=ref, since_improvement=since, done=done)

    def stagnant(self, ga: GaSettings) -> bool:
        """Whether the local search runs now: every ``local_search`` generations without
        improvement, and when a step ends without one (full and multi fidelity alike)."""
        return bool(ga.local_search and self.since_improvement and (
            self.done or self.since_improvement % ga.local_search == 0))
