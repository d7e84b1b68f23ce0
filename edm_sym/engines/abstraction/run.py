"""Hierarchical abstraction (paper, Figs. 8 and 19): steps of Algorithm 1.

Each step runs the genetic algorithm on a matrix of its own size and with its
own weighting Lambda; its initial population holds the previous step's best
(or, for the first step, the human model of the config) with new random rows,
beside fully random individuals. Elite preservation keeps the best, so a
step's best never gets worse from one generation to the next.

A run is a pure function of the data, the config and the seed: every random
number comes from one generator, the evaluation never draws any, and the
state at a generation boundary is checkpointed (every few seconds, at each
step's end and when the run stops), so a resumed run ends with the same
result as an uninterrupted one. Only ``time_limit`` depends on the
clock, and it ends a run at a generation boundary.
"""

from __future__ import annotations

import hashlib
import json
import math
import time
import warnings
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np
from threadpoolctl import threadpool_limits

from edm_sym.core.budget import Estimate, MultiFidelitySize, StepSize, abstraction_estimate, check
from edm_sym.core.data import DataLog, join_logs
from edm_sym.core.elements import BY_NAME, ParamRange, all_elements
from edm_sym.core.errors import TARGET_AS_INPUT, ConfigError, DataFormatError, NumericsWarning
from edm_sym.core.fitness import magnitude_problem
from edm_sym.core.matrix import Compensator, ElementMatrix
from edm_sym.core.result import EdmResult, StepRecord, input_name_problem, target_name_problem
from edm_sym.core.roles import LOG_ROLE_NAMES, ROLES, default_role
from edm_sym.core.units import axis_units
from edm_sym.core.validation import positive_number
from edm_sym.engines.abstraction.checkpoint import (
    FinishedStep,
    RunState,
    StepState,
    check_resume,
    load_checkpoint,
    save_checkpoint,
)
from edm_sym.engines.abstraction.clocks import barred_inputs, clock_shifts, is_clock
from edm_sym.engines.abstraction.evaluator import EvalStats, Evaluator
from edm_sym.engines.abstraction.fidelity import effective, window_samples
from edm_sym.engines.abstraction.ga import THROUGH, Operators, Population, Progress, allowed_codes, rank
from edm_sym.engines.abstraction.holdout import Holdout, mask_weights, plan_holdout
from edm_sym.engines.abstraction.local_search import tune_parameters
from edm_sym.engines.abstraction.multi import Fidelities, MultiSteps, evaluate_fitted
from edm_sym.engines.abstraction.parallel import Parallel
from edm_sym.engines.abstraction.prune import LAW_ROWS
from edm_sym.engines.abstraction.schedule import AbstractionConfig, GaSettings, StepConfig, default_config
from edm_sym.engines.abstraction.searches import (
    checkpoint_files,
    finish_searches,
    run_searches,
    search_seeds,
)
from edm_sym.engines.abstraction.seeding import (
    LAG_CORNERS,
    angle_input,
    harmonic_rows,
    residual_harmonics,
    residual_stribeck,
    stribeck_rows,
    velocity_input,
)
from edm_sym.engines.abstraction.worker import default_workers
from edm_sym.engines.simulate import fitness, simulate_rows

#: Elements whose output is identically 0 at a = 0 (a new row that changes nothing):
#: those whose output is a f(x).
_ZERO_ELEMENTS = tuple(el.name for el in all_elements() if el.scales_output)


@dataclass(frozen=True)
class GenerationInfo:
    """What a ``callback`` is told after every generation.

    Attributes
    ----------
    step : int
        1-based step number.
    generation : int
        Generations done in this step (0: the initial population).
    best : float
        Best fitness of the step so far.
    evaluations : int
        Individuals evaluated in this step.
    elapsed : float
        Seconds since the run (or the resumed run) started.
    stats : EvalStats
        The evaluator's counters so far (rows requested and simulated, cache
        hit rate, element-samples and seconds in simulation).
    best_matrix : ElementMatrix
        The step's best individual so far.
    steps : int
        Steps of the schedule.
    shape : tuple of int
        ``(n_elements, n_rows)`` of this step's matrix.
    generations_left : int
        The fewest generations the run still needs if its best stopped
        improving now (the stopping rule's patience or block end, the
        restarts left, and every later step's shortest run): a time-left
        estimate for progress lines, not a promise.
    time_limit : float or None
        The run's wall-time limit in seconds (with several searches, the
        search's share of it).
    search : int
        Which of the run's independent searches reports (0-based; config
        ``searches``).
    searches : int
        The run's independent searches.
    """

    step: int
    generation: int
    best: float
    evaluations: int
    elapsed: float
    stats: EvalStats
    best_matrix: ElementMatrix | None = None
    steps: int = 1
    shape: tuple[int, int] = (0, 0)
    generations_left: int = 0
    time_limit: float | None = None
    search: int = 0
    searches: int = 1


def _fewest_generations(ga: GaSettings, generation: int, since_improvement: int,
                        restarts_done: int) -> int:
    """Generations a step still runs if its best never improves again (Progress.after's rule)."""
    to_block_end = ga.generations - generation % ga.generations
    if ga.continue_mode == "always" and generation // ga.generations + 1 < ga.max_blocks:
        to_block_end = ga.generations * ga.max_blocks - generation
    by_patience = ga.patience - since_improvement if ga.patience else to_block_end
    now = max(0, min(to_block_end, by_patience))
    fresh = min(ga.generations * (ga.max_blocks if ga.continue_mode == "always" else 1),
                ga.patience or ga.generations * ga.max_blocks)
    return now + max(0, ga.restarts - restarts_done) * fresh


class _Stop(Exception):
    def __init__(self, reason: str):
        super().__init__(reason)
        self.reason = reason


def _fingerprint(cfg: AbstractionConfig, target: str, inputs: Sequence[str], seed: int,
                 x: np.ndarray, y: np.ndarray, ts: float, starts: Sequence[int] = ()
                 ) -> tuple[str, dict[str, Any]]:
    """The run's fingerprint, and what it is made of (to name what differs on --resume)."""
    config = json.dumps(cfg.to_json(), sort_keys=True)
    h = hashlib.sha256()
    # Where the logs begin counts only with several (one log's fingerprint stays as it was).
    logs = {"starts": list(starts)} if starts else {}
    h.update(json.dumps({"config": cfg.to_json(), "target": target, "inputs": list(inputs),
                         "seed": seed, "ts": ts, "shape": list(x.shape), **logs},
                        sort_keys=True).encode())
    d = hashlib.sha256(json.dumps({"ts": ts, "shape": list(x.shape), **logs}).encode())
    for part in (np.ascontiguousarray(x), np.ascontiguousarray(y)):
        h.update(part.tobytes())
        d.update(part.tobytes())
    identity = {"data": d.hexdigest(), "config": hashlib.sha256(config.encode()).hexdigest(),
                "target": target, "inputs": list(inputs), "seed": seed}
    return h.hexdigest(), identity


def _human_rows(cfg: AbstractionConfig, inputs: Sequence[str], ranges: dict[str, ParamRange]
                ) -> Population | None:
    if not cfg.initial:
        return None
    n = max(len(r.elements) for r in cfg.initial)
    ins, codes, ps = [], [], []
    for j, row in enumerate(cfg.initial):
        where = f"{cfg.source}: initial.rows[{j}]"
        if row.input not in inputs:
            raise ConfigError(f"{where}.input",
                              f"expected one of the inputs ({', '.join(inputs)}), "
                              f"found {row.input!r}")
        ins.append(inputs.index(row.input))
        rc, rp = [], []
        for i, (name, value) in enumerate(row.elements):
            rc.append(BY_NAME[name].code)
            if value is None:
                rp.append(0.0)
                continue
            rng = ranges[name]
            if not (rng.low <= value <= rng.high):
                raise ConfigError(f"{where}.elements[{i}]",
                                  f"expected a value in the range of {name!r} [{rng.low:g}, "
                                  f"{rng.high:g}], found {value:g} (widen [ranges.{name}])")
            rp.append(rng.encode(value))
        rc += [THROUGH] * (n - len(rc))
        rp += [0.0] * (n - len(rp))
        codes.append(rc)
        ps.append(rp)
    return Population(np.array([ins], dtype=np.int64), np.array([codes], dtype=np.int64),
                      np.array([ps], dtype=float))


def _zero_gene(step: StepConfig, ranges: dict[str, ParamRange]) -> tuple[int, float] | None:
    allowed = set(allowed_codes(step.ga.elements).tolist())
    for name in _ZERO_ELEMENTS:
        el = BY_NAME[name]
        if el.code in allowed:
            p = ranges[name].encode(0.0)
            if ranges[name].decode(p) == 0.0:
                return el.code, p
    return None


#: The checkpoint is written at most this often [s] (each step's end and a stop always):
#: writing it after every generation cost 3-6 % of a run's wall time.
CHECKPOINT_SECONDS = 2.0


class _Runner:
    """One run: its data, evaluator, generator and committed state."""

    def __init__(self, *, cfg: AbstractionConfig, x: np.ndarray, y: np.ndarray, t: np.ndarray,
                 ts: float, ranges: dict[str, ParamRange], human: Population | None,
                 inputs: Sequence[str],
                 evaluator: Evaluator, state: RunState, rng: np.random.Generator,
                 checkpoint: Path | None, time_limit: float | None,
                 callback: Callable[[GenerationInfo], bool | None] | None,
                 mask: np.ndarray | None = None, fidelities: Fidelities | None = None,
                 periodic: int | None = None, velocity: int | None = None,
                 starts: Sequence[int] = (), barred: Sequence[int] = ()):
        self.cfg, self.x, self.y, self.t, self.ts = cfg, x, y, t, ts
        # Multi-fidelity evaluation (docs/abstraction.md#multi-fidelity-evaluation); None: full.
        self.fid = fidelities
        self.multi = MultiSteps(fidelities, rng) if fidelities is not None else None
        self.mask, self.periodic, self.starts = mask, periodic, tuple(starts)
        self.velocity, self.barred = velocity, tuple(barred)
        self._lam: np.ndarray | float = 1.0
        self.ranges, self.human, self.evaluator = ranges, human, evaluator
        self.inputs = tuple(inputs)
        self.state, self.rng, self.checkpoint = state, rng, checkpoint
        self.time_limit, self.callback = time_limit, callback
        self.start = time.monotonic()
        self._saved = -math.inf  # when the checkpoint was last written
        self._unsaved = False  # a committed state the checkpoint does not have yet

    # -- commit -------------------------------------------------------------
    def _commit(self, current: StepState | None, finished: FinishedStep | None = None) -> None:
        st = self.state
        new = RunState(st.fingerprint, self.rng.bit_generator.state,
                       st.finished + ([finished] if finished else []), current, st.identity)
        self.state = new
        self._unsaved = True
        if finished is not None or time.monotonic() - self._saved >= CHECKPOINT_SECONDS:
            self.save()

    def save(self) -> None:
        """Write the committed state to the checkpoint (if there is one and it lacks it)."""
        if self.checkpoint is not None and self._unsaved:
            save_checkpoint(self.checkpoint, self.state)
            self._saved, self._unsaved = time.monotonic(), False

    def _after_generation(self, cur: StepState) -> None:
        elapsed = time.monotonic() - self.start
        best = float(np.min(cur.fitness))
        if self.callback is not None:
            steps = self.cfg.steps
            step = steps[cur.step]
            left = _fewest_generations(step.ga, cur.generation, cur.since_improvement,
                                       cur.restarts) if not cur.done else 0
            left += sum(_fewest_generations(s.ga, 0, 0, 0) for s in steps[cur.step + 1:])
            info = GenerationInfo(cur.step + 1, cur.generation, best, cur.evaluations, elapsed,
                                  self.stats(),
                                  cur.population.matrix(int(np.argmin(cur.fitness)),
                                                        self.inputs),
                                  steps=len(steps), shape=(step.n_elements, step.n_rows),
                                  generations_left=left, time_limit=self.time_limit)
            if self.callback(info):
                raise _Stop("stopped")
        if self.time_limit is not None and elapsed >= self.time_limit:
            raise _Stop("time_limit")

    def stats(self) -> EvalStats:
        """A copy of the evaluators' counters so far."""
        return self.fid.stats if self.fid is not None else replace(self.evaluator.stats)

    # -- steps ------------------------------------------------------------------
    def run(self) -> None:
        steps = self.cfg.steps
        k0 = self.state.current.step if self.state.current else len(self.state.finished)
        for k in range(k0, len(steps)):
            step = steps[k]
            lam = mask_weights(step.weighting.weights(self.t, self.y), self.mask)
            if not np.any(np.asarray(lam) > 0):
                raise ConfigError(f"{self.cfg.source}: step[{k}].weighting",
                                  "expected a positive weight for some sample of the data, "
                                  "found all zero")
            self._lam = lam
            if self.fid is not None:
                self.fid.set_step(lam, step.ga.reject_poles)
            else:
                self.evaluator.set_weights(lam)
                self.evaluator.set_reject_poles(step.ga.reject_poles)
            ops = Operators(step.ga, self.x.shape[0], self.barred)
            cur = self.state.current
            if cur is None or cur.step != k:
                cur = self._init_step(k, step, ops)
                self._commit(cur)
                self._after_generation(cur)
            while not cur.done:
                cur = self._generation(cur, step, ops)
                self._commit(cur)
                self._after_generation(cur)
            best = int(np.argmin(cur.fitness))
            done = FinishedStep(k + 1, cur.population.take([best]), float(cur.fitness[best]),
                                cur.history, cur.generation, cur.evaluations,
                                step.weighting.to_json())
            self._commit(None, done)

    def _init_step(self, k: int, step: StepConfig, ops: Operators) -> StepState:
        ga = step.ga
        p, m, n = ga.population, step.n_rows, step.n_elements
        pop = ops.random_population(self.rng, p, m, n)
        seed = self.state.finished[-1].best if k > 0 else self.human
        if seed is not None:
            m0, n0 = seed.codes.shape[1], seed.codes.shape[2]
            count = max(1, int(round(ga.inherit_fraction * p)))
            pop.inputs[:count, :m0] = seed.inputs[0]
            pop.codes[:count, :m0, :n0] = seed.codes[0]
            pop.ps[:count, :m0, :n0] = seed.ps[0]
            pop.codes[:count, :m0, n0:] = THROUGH
            pop.ps[:count, :m0, n0:] = 0.0
            zero = _zero_gene(step, self.ranges)
            if zero is not None and m0 < m:
                # The inherited model with new rows that output 0 (through ... through,
                # gain 0): a step starts where the previous one ended.
                pop.codes[0, m0:], pop.ps[0, m0:] = THROUGH, 0.0
                pop.codes[0, m0:, -1], pop.ps[0, m0:, -1] = zero
            if m0 < m and (ga.harmonic_seeds or ga.stribeck_seeds):
                self._seed_rows(pop, seed, step, count, ops)
        # Individual 0 is the seed as it is: the gain fit improves copies of it later.
        low = None
        if self.multi is not None:
            fit, low, extra = self.multi.first(pop, ops, keep_first=seed is not None)
        else:
            fit, extra = self._evaluate(pop, ops, keep_first=seed is not None)
        best = float(np.min(fit))
        return StepState(step=k, generation=0, blocks=0, block_start_best=best, ref_best=best,
                         since_improvement=0, done=False, population=pop, fitness=fit,
                         history=[best], evaluations=p + extra, low=low)

    def _seed_rows(self, pop: Population, seed: Population, step: StepConfig, count: int,
                   ops: Operators) -> None:
        """Give inherited individuals 1, 2 ... as their first new row a harmonic of the seed's
        residual over the angle, then a Stribeck hump over the velocity
        (:mod:`edm_sym.engines.abstraction.seeding`)."""
        matrix = seed.matrix(0, self.inputs)
        comp = Compensator(matrix, self.ts, self.ranges, len(self.y) * self.ts)
        with np.errstate(all="ignore"):
            resid = self.y - simulate_rows(comp, matrix.rows, self.x, starts=self.starts).sum(axis=0)
        if not np.all(np.isfinite(resid)):
            return
        w = np.broadcast_to(np.asarray(self._lam, dtype=float), resid.shape)
        allowed = set(ops.allowed.tolist())
        ga, seeded = step.ga, []
        if ga.harmonic_seeds and self.periodic is not None:
            lpf = self.ranges.get("lpf")
            corners = (() if lpf is None or BY_NAME["lpf"].code not in allowed
                       else tuple(np.geomspace(lpf.low, lpf.high, LAG_CORNERS)))
            found = residual_harmonics(self.x[self.periodic], resid, w, ga.harmonic_seeds,
                                       corners=corners, ts=self.ts, starts=self.starts)
            seeded += [(self.periodic, row) for row in
                       harmonic_rows(found, self.ranges, step.n_elements, allowed)]
        if ga.stribeck_seeds and self.velocity is not None:
            humps = residual_stribeck(self.x[self.velocity], resid, w, ga.stribeck_seeds)
            seeded += [(self.velocity, row) for row in
                       stribeck_rows(humps, self.ranges, step.n_elements, allowed)]
        m0 = seed.codes.shape[1]
        for i, (inp, (codes, ps)) in enumerate(seeded[:max(count - 1, 0)], start=1):
            pop.inputs[i, m0] = inp
            pop.codes[i, m0], pop.ps[i, m0] = codes, ps

    def _evaluate(self, pop: Population, ops: Operators, keep_first: bool = False
                  ) -> tuple[np.ndarray, int]:
        """Fitness of ``pop``, improved in place by the gain fit; also the extra evaluations."""
        return evaluate_fitted(self.evaluator, pop, ops, keep_first)

    def _generation(self, cur: StepState, step: StepConfig, ops: Operators) -> StepState:
        if self.multi is not None:
            return self.multi.generation(cur, step, ops)
        ga = step.ga
        pop, fit = cur.population, cur.fitness
        keys = self.evaluator.individual_keys(pop.inputs, pop.codes, pop.ps)
        order = rank(fit, keys)
        ranked, rfit = pop.take(order), fit[order]
        size = len(pop)
        kids = ops.offspring(self.rng, ranked, size - ga.elites)
        kfit, extra = self._evaluate(kids, ops)
        new_pop = Population.concat([ranked.take(np.arange(ga.elites)), kids])
        new_fit = np.concatenate([rfit[:ga.elites], kfit])
        best = float(np.min(new_fit))
        before = Progress(cur.generation, cur.blocks, cur.block_start_best, cur.ref_best,
                          cur.since_improvement)
        prog = before.after(ga, best)
        if prog.stagnant(ga):
            # Stagnation: tune the best individual's parameters; the result takes the
            # place of the worst individual, so the original stays in the population.
            k = int(np.argmin(new_fit))
            tuned, tfit, used = tune_parameters(self.evaluator, new_pop.take([k]),
                                                float(new_fit[k]),
                                                max_evaluations=ga.local_search_evaluations)
            extra += used
            if tfit < best:
                worst = int(np.argmax(new_fit))
                new_pop.inputs[worst], new_pop.codes[worst], new_pop.ps[worst] = (
                    tuned.inputs[0], tuned.codes[0], tuned.ps[0])
                new_fit[worst] = tfit
                best = tfit
                prog = before.after(ga, best)
        restarts = cur.restarts
        if prog.done and restarts < ga.restarts:
            restarts += 1
            new_pop, new_fit, used = self._restart(new_pop, new_fit, ops)
            extra += used
            best = float(np.min(new_fit))
            prog = replace(Progress.start(best), generation=prog.generation)
        return StepState(step=cur.step, generation=prog.generation, blocks=prog.blocks,
                         block_start_best=prog.block_start_best, ref_best=prog.ref_best,
                         since_improvement=prog.since_improvement,
                         done=prog.done, population=new_pop, fitness=new_fit,
                         history=[*cur.history, best],
                         evaluations=cur.evaluations + len(kids) + extra, restarts=restarts)

    def _restart(self, pop: Population, fit: np.ndarray, ops: Operators
                 ) -> tuple[Population, np.ndarray, int]:
        """A stagnating step's new population: its elites, the best with one row anew, random."""
        ga = ops.ga
        p, m, n = pop.shape
        keys = self.evaluator.individual_keys(pop.inputs, pop.codes, pop.ps)
        order = rank(fit, keys)[:ga.elites]
        elites = pop.take(order)
        fresh = ops.random_population(self.rng, p - ga.elites, m, n)
        count = max(1, int(round(ga.inherit_fraction * p)))
        redraw = self.rng.integers(m, size=count)
        for i in range(count):
            keep = np.arange(m) != redraw[i]
            fresh.inputs[i, keep] = elites.inputs[0, keep]
            fresh.codes[i, keep] = elites.codes[0, keep]
            fresh.ps[i, keep] = elites.ps[0, keep]
        ffit, extra = self._evaluate(fresh, ops)
        return (Population.concat([elites, fresh]), np.concatenate([fit[order], ffit]),
                len(fresh) + extra)

    # -- result -------------------------------------------------------------------
    def records(self) -> list[FinishedStep]:
        """Finished steps plus the step in progress (at its last boundary)."""
        out = list(self.state.finished)
        cur = self.state.current
        if cur is not None:
            best = int(np.argmin(cur.fitness))
            out.append(FinishedStep(cur.step + 1, cur.population.take([best]),
                                    float(cur.fitness[best]), cur.history, cur.generation,
                                    cur.evaluations,
                                    self.cfg.steps[cur.step].weighting.to_json()))
        return out


def abstract(
    data: DataLog | Sequence[DataLog],
    *,
    target: str,
    inputs: Sequence[str],
    config: AbstractionConfig | None = None,
    seed: int = 0,
    time_limit: float | None = None,
    checkpoint: Path | None = None,
    resume: bool = False,
    callback: Callable[[GenerationInfo], bool | None] | None = None,
    validate: DataLog | None = None,
    validation_share: float | None = None,
    select: str | None = None,
    axis: str = "rotary",
    searches: int | None = None,
    parallel: Parallel | None = None,
) -> EdmResult:
    """Run the hierarchical EDM abstraction (Algorithm 1, step by step) on a log.

    Parameters
    ----------
    data : DataLog or sequence of DataLog
        The abstraction log (free motion), or several logs of the axis with
        one sample time and the same column roles: each is simulated from rest
        on its own, eq. 8 is taken over all their samples (so each log weighs
        by its length), and the held-out blocks are laid out in every one
        (docs/abstraction.md#several-logs).
    target : str
        The column to compensate (the RTOB's estimated external torque).
    inputs : sequence of str
        The columns the rows may select as their input.
    config : AbstractionConfig, optional
        Schedule, GA settings, ranges, human model; None: the default schedule.
    seed : int
        Seed of the random generator (>= 0): equal seeds give equal results.
    time_limit : float, optional
        Wall-clock seconds; the run ends at the first generation boundary
        after it and returns the best so far.
    checkpoint : pathlib.Path, optional
        Where to write the run's state at a generation boundary: at most every
        :data:`CHECKPOINT_SECONDS`, at each step's end and when the run stops
        (removed when the run completes).
    resume : bool
        Continue from ``checkpoint`` when that file exists.
    callback : callable, optional
        Called with a :class:`GenerationInfo` after every generation; a true
        return value ends the run there, like a time limit. The engine prints
        nothing: progress bars and lines are such a callback
        (:class:`edm_sym.application.progress.ProgressReporter`).
    validate : DataLog, optional
        A second log held out as a whole (the GA then fits all of ``data``).
    validation_share : float, optional
        Share of ``data`` held out at its end, in [0, 0.9]; None: the
        config's ``[validation] share`` (default 0.2). See
        :mod:`edm_sym.engines.abstraction.holdout`.
    select : str, optional
        Which member of the complexity-vs-fitness front is exported:
        ``"best"``, ``"knee"`` or ``"simplest-within=PCT"``; None: the
        config's ``[parsimony]`` rule (default: the simplest member within
        its tolerance, 1 %). See :mod:`edm_sym.engines.abstraction.prune`.
    axis : str
        ``"rotary"`` or ``"linear"``: the SI units of the log (docs/data.md#units),
        recorded in the result; the scores' unit when the config sets none.
    searches : int, optional
        Independent searches of the whole schedule, each from its own seed
        (search 0 from ``seed``); None: the config's ``searches`` (default
        1). On this machine they run side by side, one process each, on
        ``parallel.workers`` cores; with a scheduler or an executor one after
        another, each on all of it. The search's model is chosen among the
        step bests of all of them; ``provenance.searches`` records each one
        (docs/abstraction.md#independent-searches).
    parallel : Parallel, optional
        Where the work goes: ``Parallel(workers=..., executor=...,
        scheduler=...)`` (:class:`~edm_sym.engines.abstraction.parallel.Parallel`);
        None: this process and a forked worker per further usable core. No
        setting of it changes the result.

    Returns
    -------
    EdmResult
        The final compensator, every step's record, the provenance
        (``seed``, ``package_version``, ``data_sha256``, ``stop_reason``: one of
        ``"completed"``, ``"time_limit"``, ``"stopped"``, ``"interrupted"``),
        the axis and the record of each log used (``logs``).

    Raises
    ------
    ConfigError
        Bad inputs or config (unknown input in the human model, a weighting
        that is zero everywhere, a checkpoint of another run, an unknown axis).
    DataFormatError
        A missing target or input column, or an input column that is constant.
    KeyboardInterrupt
        Only when interrupted before the first population was evaluated.
    """
    logs = _given_logs(data)
    _check_arguments(config, time_limit, parallel)
    inputs = check_inputs(target, inputs)
    # Several logs are laid end to end; every simulation starts each from rest (``starts``).
    data = logs[0] if len(logs) == 1 else join_logs(logs, [target, *inputs])
    logs = logs if len(logs) > 1 else []
    cfg = _settings(config, seed=seed, searches=searches, axis=axis,
                    validation_share=validation_share)
    parallel = parallel if parallel is not None else Parallel()
    hold = _holdout(data, cfg, target=target, inputs=inputs, validate=validate, logs=logs,
                    validation_share=validation_share)
    # The sizes first (config alone), then whether the log can support them.
    check_budget(cfg, hold.n_train, len(inputs), workers=parallel.workers, time_limit=time_limit,
                 ts=float(data.ts))
    _require_samples(data, hold.n_train if hold.mask is None
                     else int(np.count_nonzero(hold.mask)), cfg, blocks=hold.mask is not None)
    check_data(data, target, inputs, logs=logs)
    job = _search_job(cfg, data, logs, hold, target=target, inputs=inputs, axis=axis)
    _warn_barred(job)
    seeds = search_seeds(int(seed), cfg.searches)
    checkpoint = Path(checkpoint) if checkpoint is not None else None
    files = checkpoint_files(checkpoint, cfg.searches)
    if resume:
        # Every search's checkpoint is checked before any search starts (and writes its own).
        check_resume(checkpoint, files, [_fingerprint(cfg, target, inputs, int(s), job.x, job.y,
                                                      job.ts, job.starts) for s in seeds])
    with parallel.connected() as here:
        outcomes = run_searches(job, seeds, files, resume, parallel=here, time_limit=time_limit,
                                callback=callback)
    return _search_result(job, outcomes, seeds, files, data=data, logs=logs, validate=validate,
                          seed=int(seed), select=select, axis=axis)


def _given_logs(data: DataLog | Sequence[DataLog]) -> list[DataLog]:
    """The logs of ``abstract(data)``: one, or a non-empty list of DataLog.

    Raises
    ------
    DataFormatError
        Naming ``data``.
    """
    logs = list(data) if isinstance(data, list | tuple) else [data]
    for log in logs:
        if not isinstance(log, DataLog):
            raise DataFormatError("data", f"expected a DataLog (edm_sym.load_data) or a list of "
                                  f"them, found {type(log).__name__}")
    if not logs:
        raise DataFormatError("data", "expected a DataLog or a list of them, found an empty list")
    return logs


def _check_arguments(config: Any, time_limit: Any, parallel: Any) -> None:
    """Refuse a ``config``, ``time_limit`` or ``parallel`` of the wrong kind (ConfigError)."""
    if config is not None and not isinstance(config, AbstractionConfig):
        raise ConfigError("config", f"expected an AbstractionConfig (load_config(path)), found "
                          f"{type(config).__name__}")
    if time_limit is not None and (isinstance(time_limit, bool)
                                   or not isinstance(time_limit, int | float | np.floating)
                                   or not math.isfinite(time_limit) or time_limit < 0):
        raise ConfigError("time_limit", f"expected a number of seconds >= 0, found {time_limit!r}")
    if parallel is not None and not isinstance(parallel, Parallel):
        raise ConfigError("parallel", f"expected a Parallel(workers=..., executor=..., "
                          f"scheduler=...), found {type(parallel).__name__}")


def _settings(config: AbstractionConfig | None, *, seed: Any, searches: int | None, axis: str,
              validation_share: float | None) -> AbstractionConfig:
    """The config a run uses: the given one (or the default) with the arguments over it.

    Raises
    ------
    ConfigError
        Naming ``seed``, ``searches`` or ``axis``.
    """
    cfg = config if config is not None else default_config()
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer) or seed < 0:
        raise ConfigError("seed", f"expected an integer >= 0, found {seed!r}")
    if searches is not None:
        try:
            cfg = replace(cfg, searches=searches)
        except ConfigError as exc:
            raise ConfigError("searches", exc.problem) from None
    try:
        units = axis_units(axis)
    except ValueError as exc:
        raise ConfigError("axis", str(exc)) from None
    if validation_share is not None:
        cfg = replace(cfg, validation=replace(cfg.validation, share=validation_share))
    if cfg.validation.unit is None:
        cfg = replace(cfg, validation=replace(cfg.validation, unit=units.force))
    return cfg


def _holdout(data: DataLog, cfg: AbstractionConfig, *, target: str, inputs: tuple[str, ...],
             validate: DataLog | None, logs: list[DataLog], validation_share: float | None
             ) -> Holdout:
    """The held-out layout (:func:`plan_holdout`), its errors named where the share came from:
    the argument, else the config file's key."""
    try:
        return plan_holdout(data, target=target, inputs=inputs, settings=cfg.validation,
                            validate=validate, logs=logs)
    except ConfigError as exc:
        if not exc.where.startswith("validation."):
            raise
        if validation_share is not None:
            raise ConfigError("validation_share", exc.problem) from None
        raise ConfigError(f"{cfg.source}: {exc.where}", exc.problem) from None


def _search_job(cfg: AbstractionConfig, data: DataLog, logs: list[DataLog], hold: Holdout, *,
                target: str, inputs: tuple[str, ...], axis: str) -> _SearchJob:
    """What every search of the run shares: the training samples, the ranges, the human model."""
    # The GA sees the training samples only (causal rows: they do not depend on later ones);
    # with held-out blocks it simulates them all and its Lambda is 0 on the held-out ones.
    part = hold.training
    x = np.ascontiguousarray(part.x[:, :hold.n_train])
    y, t = part.y[:hold.n_train], part.t[:hold.n_train]
    ts = float(data.ts)
    # T_sum of the ranges: the longest log (no filter state lives longer than one log).
    n = max(len(d) for d in logs) if logs else len(data)
    ranges = cfg.resolve_ranges(ts, n * ts)
    human = _human_rows(cfg, inputs, ranges)
    roles = _roles(data, inputs)
    periodic, velocity = angle_input(roles, axis), velocity_input(roles)
    # Multi-fidelity evaluation on a long training log (docs/abstraction.md#multi-fidelity-evaluation).
    return _SearchJob(cfg=cfg, target=target, inputs=inputs, x=x, y=y, t=t, ts=ts, ranges=ranges,
                      human=human, hold=hold, n=n, starts=hold.training.starts,
                      fidelity=effective(cfg.fidelity, hold.n_train),
                      periodic=periodic, velocity=velocity,
                      barred=barred_inputs(part.x, hold.training.starts, roles),
                      clocks=clock_shifts(part.x, hold.training.starts, roles, axis),
                      laws=_law_inputs(roles, velocity, periodic),
                      observer=positive_number(data.scalars.get("observer_bandwidth")))


def _search_result(job: _SearchJob, outcomes: list[tuple], seeds: Sequence[int],
                   files: Sequence[Path | None], *, data: DataLog, logs: list[DataLog],
                   validate: DataLog | None, seed: int, select: str | None, axis: str
                   ) -> EdmResult:
    """The run's result from its searches' outcomes: the search's model chosen, pruned and
    scored (:func:`finish_searches`), the provenance, the logs' records; the checkpoints
    of a completed run removed."""
    from edm_sym.core.version import __version__

    cfg, count = job.cfg, len(seeds)
    groups = [o[0] for o in outcomes]
    reasons = [o[1] for o in outcomes]
    made = [o[2] for o in outcomes] if count > 1 else None
    reason = ("interrupted" if "interrupted" in reasons
              else next((r for r in reasons if r != "completed"), "completed"))
    ranges_comp = Compensator(next(g for g in groups if g)[-1].matrix, job.ts, job.ranges,
                              job.n * job.ts)
    fin = cfg
    if reason == "interrupted":
        # An interrupt is answered at once: the search's own model, scored, with no refit
        # and no pruning (these take a minute on a long log); --resume finishes the run.
        fin = replace(cfg, parsimony=replace(cfg.parsimony, prune=False))
        made = None
    # Rows that read time from a clock (the unwrapped angle of a one-way run) are no physics.
    comp, parsimony, final, chosen = finish_searches(groups, ranges_comp, job.hold, fin, select,
                                                     made, job.clocks, job.laws, job.observer)
    steps = groups[chosen]
    fit = final["training"]["fitness"][0] if parsimony else steps[-1].fitness
    provenance: dict[str, Any] = {"seed": seed, "package_version": __version__,
                                  "data_sha256": data.sha256, "stop_reason": reason}
    if job.barred:
        provenance["clock_inputs"] = [job.inputs[i] for i in job.barred]
    if job.fidelity == "multi":
        # Only when used: a run of full fidelity writes the result.json it always did.
        provenance["fidelity"] = {"mode": "multi", "config": cfg.fidelity,
                                  **cfg.multi_fidelity.to_json()}
    if count > 1:
        provenance["searches"] = [
            {"search": k, "seed": seeds[k], "stop_reason": reasons[k],
             "evaluations": sum(s.evaluations for s in g),
             "step_fitness": [s.fitness if math.isfinite(s.fitness) else None for s in g],
             "chosen": k == chosen} for k, g in enumerate(groups)]
    if reason == "completed":
        for f in files:
            if f is not None and f.exists():
                f.unlink()
    records = tuple(d.record("abstraction") for d in (logs or [data]))
    records += (validate.record("validation"),) if validate else ()
    return EdmResult(comp, job.target, tuple(steps), provenance, fit, validation=final,
                     parsimony=parsimony, axis=axis, logs=records)


@dataclass(frozen=True)
class _SearchJob:
    """What every search of a run shares: the config, the training data."""

    cfg: AbstractionConfig
    target: str
    inputs: tuple[str, ...]
    x: np.ndarray
    y: np.ndarray
    t: np.ndarray
    ts: float
    ranges: dict[str, ParamRange]
    human: Population | None
    hold: Holdout
    #: Samples of the abstraction log (the record length of the ranges).
    n: int = 0
    #: Where further logs begin in ``x`` (several logs, each simulated from rest).
    starts: tuple[int, ...] = ()
    #: ``"full"`` or ``"multi"``: the fidelity the search runs (``fidelity.effective``).
    fidelity: str = "full"
    #: The input a ripple is a function of (:func:`seeding.angle_input`), or None.
    periodic: int | None = None
    #: The input a Stribeck hump is a function of (:func:`seeding.velocity_input`), or None.
    velocity: int | None = None
    #: Angle inputs no row of the search takes: a clock of every training log
    #: (:func:`~edm_sym.engines.abstraction.clocks.barred_inputs`).
    barred: tuple[int, ...] = ()
    #: Angle inputs that are a clock of some training log, and the shift that tests a row on
    #: one after the search (:func:`~edm_sym.engines.abstraction.clocks.clock_shifts`).
    clocks: Mapping[int, float] = field(default_factory=dict)
    #: The input of each linear law's row offered before pruning
    #: (:func:`~edm_sym.engines.abstraction.prune.offer_law_rows`).
    laws: Mapping[str, int] = field(default_factory=dict)
    #: The observer's bandwidth [rad/s] the log records (its scalar ``observer_bandwidth``),
    #: or None: the law rows are also offered through its low-pass.
    observer: float | None = None

    @property
    def mask(self) -> np.ndarray | None:
        """The held-out samples' mask (Lambda is 0 there), or None."""
        return self.hold.mask

    def run(self, seed: int, parallel: Parallel, checkpoint: Path | None, resume: bool,
            time_limit: float | None, callback: Callable[[GenerationInfo], bool | None] | None
            ) -> tuple[list[StepRecord], str]:
        """One search of the schedule from ``seed``, where ``parallel`` says (its
        ``scheduler`` a connected client or None): its step bests and how it ended.

        Raises
        ------
        KeyboardInterrupt
            Only when interrupted before the first population was evaluated.
        """
        cfg, x, y, t, ts = self.cfg, self.x, self.y, self.t, self.ts
        fingerprint, identity = _fingerprint(cfg, self.target, self.inputs, int(seed), x, y, ts,
                                             self.starts)
        rng = np.random.default_rng(int(seed))
        if resume and checkpoint is not None and checkpoint.exists():
            state = load_checkpoint(checkpoint, fingerprint, identity)
            rng.bit_generator.state = state.rng_state
        else:
            state = RunState(fingerprint, rng.bit_generator.state, identity=identity)
        batch = max(s.ga.population * s.n_rows for s in cfg.steps)
        cache = int(cfg.cache_mb * 2**20)
        fid = None
        if self.fidelity == "multi":
            # The whole log's evaluator scores a few promoted individuals at once: a quarter
            # of the cache, at least room for two such batches; the windows' evaluator, whose
            # rows are short, half (docs/abstraction.md#multi-fidelity-evaluation).
            evaluator = Evaluator(x, y, ts, self.ranges, executor=parallel.executor,
                                  workers=parallel.workers, cache_bytes=cache // 4,
                                  max_batch_rows=_whole_log_batch(cfg), client=parallel.scheduler,
                                  starts=self.starts)
            fid = Fidelities(evaluator, x, y, ts, self.ranges, cfg.multi_fidelity,
                             executor=parallel.executor, workers=parallel.workers,
                             cache_bytes=cache // 2, max_batch_rows=batch,
                             client=parallel.scheduler)
        else:
            evaluator = Evaluator(x, y, ts, self.ranges, executor=parallel.executor,
                                  workers=parallel.workers, cache_bytes=cache,
                                  max_batch_rows=batch, client=parallel.scheduler,
                                  starts=self.starts)
        evaluator.start()
        runner = _Runner(cfg=cfg, x=x, y=y, t=t, ts=ts, ranges=self.ranges, human=self.human,
                         inputs=self.inputs, evaluator=evaluator, state=state, rng=rng,
                         checkpoint=checkpoint, time_limit=time_limit, callback=callback,
                         mask=self.mask, fidelities=fid, periodic=self.periodic, velocity=self.velocity,
                         starts=self.starts, barred=self.barred)
        reason = "completed"
        try:
            # One BLAS thread in this process's lane too (see worker.worker_init).
            with threadpool_limits(1):
                runner.run()
        except _Stop as stop:
            reason = stop.reason
            runner.save()
        except KeyboardInterrupt:
            reason = "interrupted"
            evaluator.abort()
            if fid is not None:
                fid.abort()
            runner.save()
            if not runner.records():
                raise
        finally:
            if fid is not None:
                fid.close()
            evaluator.close()
        steps = []
        for r in runner.records():
            matrix = r.best.matrix(0, self.inputs)
            lam = mask_weights(cfg.steps[r.step - 1].weighting.weights(t, y), self.mask)
            steps.append(StepRecord(step=r.step, matrix=matrix,
                                    fitness=_reference_fitness(matrix, ts, self.ranges, x, y, lam,
                                                               r.fitness, r.step, self.starts),
                                    history=tuple(r.history), generations=r.generations,
                                    evaluations=r.evaluations, weighting=r.weighting))
        return steps, reason


def _whole_log_batch(cfg: AbstractionConfig) -> int:
    """Rows of the largest batch the whole log's evaluator of a multi-fidelity run takes:
    a step's promoted individuals (its elites, at first) and the inherited model, or a
    local search's candidates."""
    return max(s.n_rows * max(max(cfg.multi_fidelity.promote, s.ga.elites) + 1, 1 + s.n_elements)
               for s in cfg.steps)


def _law_inputs(roles: Sequence[str | None], velocity: int | None, angle: int | None
                ) -> dict[str, int]:
    """The input each law's row reads before pruning (:mod:`~edm_sym.engines.abstraction.prune`):
    the linear laws' inputs (:data:`~edm_sym.engines.abstraction.prune.LAW_ROWS`), and for the
    static laws' block the velocity (Coulomb, Stribeck) and the angle a ripple is a function
    of, the seeds' own (:func:`~edm_sym.engines.abstraction.seeding.velocity_input`,
    :func:`~edm_sym.engines.abstraction.seeding.angle_input`)."""
    laws = {law: roles.index(role) for law, role in LAW_ROWS if role in roles}
    if velocity is not None:
        laws["coulomb"] = velocity
    if angle is not None:
        laws["spatial"] = angle
    return laws


def _roles(data: DataLog, inputs: Sequence[str]) -> list[str | None]:
    """Each input's physical role: the log's, else the default of its name."""
    out = []
    for name in inputs:
        role = data.role_of(name)
        role = LOG_ROLE_NAMES.get(role, role) if role is not None else default_role(name)
        out.append(role if role in ROLES else None)
    return out


def check_inputs(target: str, inputs: Sequence[str]) -> tuple[str, ...]:
    """The input names as a tuple; refuses none, a repeated one, a bad name or the target
    (and a target name an export cannot print).

    Raises
    ------
    ConfigError
        Naming ``inputs`` (and the name).
    """
    problem = target_name_problem(target) if isinstance(target, str) else None
    if problem:
        raise ConfigError(f"target: {target!r}", problem)
    inputs = tuple(inputs)
    if not inputs:
        raise ConfigError("inputs", "expected at least one input column, found none")
    for k, name in enumerate(inputs):
        if inputs.index(name) != k:
            raise ConfigError("inputs", f"expected each column once, found {name!r} twice")
        problem = input_name_problem(name, inputs[:k])
        if problem:
            raise ConfigError(f"inputs: {name!r}", problem)
    if target in inputs:
        raise ConfigError("inputs", TARGET_AS_INPUT.format(target=target))
    return inputs


def clock_inputs(data: DataLog, inputs: Sequence[str]) -> list[tuple[str, float, float]]:
    """The inputs that only rise or only fall over the log: ``(name, first, last)``.

    :func:`~edm_sym.engines.abstraction.clocks.is_clock` decides (a retreat of
    at most 1 % of the travel, jitter at the start from rest, is allowed).

    Within such a log the input is a clock, like the time column: the unwrapped
    angle of a run that turns one way. A model of it explains the run's time
    (the start from rest, a warm-up), not the axis, unless it repeats over the
    angle (a ripple of the wrapped angle does). A wrapped angle never counts.
    """
    out = []
    for name in inputs:
        col = np.asarray(data.column(name, role="input column"), dtype=float)
        if col.size < 3 or (data.role_of(name) or "") == "position_wrapped":
            continue
        if is_clock(col):
            out.append((name, float(col[0]), float(col[-1])))
    return out


def warn_clocks(data: DataLog, inputs: Sequence[str]) -> None:
    """Warn (:class:`~edm_sym.core.errors.ClockWarning`) of every input :func:`clock_inputs` finds."""
    import warnings

    from edm_sym.core.errors import ClockWarning

    for name, first, last in clock_inputs(data, inputs):
        way = "rises" if last > first else "falls"
        warnings.warn(f"{data.source}: column {name!r} only {way} over the log ({first:.4g} to "
                      f"{last:.4g}): within this run it is a clock, and what the search explains "
                      "through it is the run's time (the start from rest), not the axis, unless it "
                      "repeats over the angle; edm describe names no physics from it",
                      ClockWarning, stacklevel=3)


def _warn_barred(job: _SearchJob) -> None:
    """Warn (:class:`~edm_sym.core.errors.ClockWarning`) of the inputs the search's rows leave out."""
    import warnings

    from edm_sym.core.errors import ClockWarning

    for i in job.barred:
        warnings.warn(f"input {job.inputs[i]!r} only moves one way in every log: the search's "
                      "rows leave it out and read the velocity instead "
                      "(docs/abstraction.md#clocks-rows-that-read-time-from-the-angle)",
                      ClockWarning, stacklevel=3)


def check_data(data: DataLog, target: str, inputs: Sequence[str], *,
               logs: Sequence[DataLog] = ()) -> None:
    """Refuse a log the search cannot fit: inputs that say nothing about the axis (constant,
    the clock), values that are not finite, a constant target or one whose square overflows.

    ``logs``: the logs ``data`` joins, when several (each warned of its own clocks).

    Raises
    ------
    DataFormatError
        Naming the file and the column.
    """
    data.require_varying(inputs)
    for log in logs or [data]:
        log.require_finite([*inputs, target])
        warn_clocks(log, inputs)
    y_all = data.column(target, role="target column")
    if np.all(y_all == y_all[0]):
        raise DataFormatError(f"{data.source}: column {target!r}",
                              f"expected a varying target (a constant one leaves nothing to "
                              f"model), found {y_all[0]:g} on all {len(y_all)} rows")
    problem = magnitude_problem(y_all)  # eq. 8 squares the error: 1e160 made every fitness inf
    if problem:
        raise DataFormatError(f"{data.source}: column {target!r}", problem)


def _require_samples(data: DataLog, n_train: int, cfg: AbstractionConfig, *,
                     blocks: bool = False) -> None:
    """Refuse a training part too short to fit the schedule's largest matrix.

    Its parameters (one per element) must not outnumber the samples fitted,
    and the filters' default corner range, 2 pi/T_sum .. pi/Ts, is empty below
    3 samples (docs/data.md#too-few-samples).
    """
    largest = max(cfg.steps, key=lambda s: s.n_rows * s.n_elements)
    need = max(3, largest.n_rows * largest.n_elements + 1)
    if n_train < need:
        raise DataFormatError(
            (f"{data.source}: the {n_train} samples fitted (the held-out blocks aside)" if blocks
             else f"{data.source}: samples 1-{n_train} (the training part)"),
            f"expected at least {need} samples to fit (more than the {largest.n_rows}x"
            f"{largest.n_elements} matrix's parameters), found {n_train}; use a longer log, a "
            "smaller schedule or a smaller held-out share")


def check_budget(cfg: AbstractionConfig, n_samples: int, n_inputs: int, *,
                 workers: int | None = None, time_limit: float | None = None,
                 ts: float | None = None) -> Estimate:
    """Refuse a run that cannot fit this machine, before it starts (:mod:`edm_sym.core.budget`).

    The run is estimated at the fidelity it will have (``fidelity.effective``
    of the config's ``fidelity`` and ``n_samples``): a run of multi fidelity
    as its two evaluators are sized (:func:`_whole_log_batch`, the windows of
    ``[multi_fidelity]``; docs/cli.md#sizes-that-cannot-fit).

    Parameters
    ----------
    cfg : AbstractionConfig
    n_samples : int
        Samples the GA fits.
    n_inputs : int
        Input columns.
    workers : int, optional
        Processes (default: every usable core).
    time_limit : float, optional
        The run's wall-time limit [s]: then only the first generation must fit the time limit.
    ts : float, optional
        Sample time [s]: the length of a multi-fidelity run's warm-ups (None: the windows
        are taken as long as the log).

    Returns
    -------
    Estimate
        The figures checked.

    Raises
    ------
    BudgetError
        Naming the config and the largest step, with the estimate and the limit.
    """
    # A step runs at least one block (or its patience), and each restart as much again.
    sizes = [StepSize(s.ga.population, s.n_rows, s.n_elements,
                      (1 + s.ga.restarts) * (min(s.ga.generations, s.ga.patience)
                                             if s.ga.patience else s.ga.generations))
             for s in cfg.steps]
    multi = None
    if effective(cfg.fidelity, int(n_samples)) == "multi":
        multi = MultiFidelitySize(window_samples(cfg.multi_fidelity, int(n_samples), ts),
                                  cfg.multi_fidelity.promote, _whole_log_batch(cfg))
    est = abstraction_estimate(sizes, n_samples=n_samples, n_inputs=n_inputs,
                               cache_bytes=int(cfg.cache_mb * 2**20),
                               workers=int(workers) if workers else default_workers(),
                               time_limit=time_limit, multi=multi)
    check(est, cfg.source, "use a smaller population or matrix, or a shorter log",
          time_hint="use a smaller population or matrix, fewer generations (or patience), "
                    "a shorter log or a time limit")
    return est


def _reference_fitness(matrix: ElementMatrix, ts: float, ranges: dict[str, ParamRange],
                       x: np.ndarray, y: np.ndarray, lam: np.ndarray | float, ga_value: float,
                       step: int, starts: Sequence[int] = ()) -> float:
    """Eq. 8 of a step's best by the reference simulator, the numeric truth.

    The GA ranks with a faster realisation of the same difference equations;
    the two agree to rounding unless a row amplifies rounding (a tangent of a
    huge argument, say), which is worth a warning.
    """
    comp = Compensator(matrix, ts, ranges, len(y) * ts)
    with np.errstate(over="ignore", invalid="ignore"):
        value = fitness(y - simulate_rows(comp, matrix.rows, x, starts=starts).sum(axis=0), lam)
    if not np.isfinite(value):
        value = float("inf")
    if abs(value - ga_value) > 1e-6 * max(abs(value), 1e-300):
        warnings.warn(NumericsWarning(
            f"step {step}: the best matrix's fitness is {value:.10g} by the reference "
            f"simulator but {ga_value:.10g} in the GA; one of its rows amplifies rounding"),
            stacklevel=3)
    return float(value)
