"""After the search: the model chosen among the step bests, pruned and scored.

The candidates are the step bests as the GA left them and refitted on the
whole training part (:func:`~edm_sym.engines.abstraction.local_search.step_candidates`);
:func:`start_candidate` chooses the one the pruning starts from (the lowest
whole-log RMSE, the held-out part deciding a tie), and
:func:`~edm_sym.engines.abstraction.prune.apply_parsimony` prunes it
(docs/abstraction.md, "Parsimony").
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import replace
from typing import Any

import numpy as np

from edm_sym.core.matrix import Compensator, ElementMatrix
from edm_sym.core.result import StepRecord, matrix_to_json
from edm_sym.engines.abstraction.clocks import Passenger, passengers
from edm_sym.engines.abstraction.ga import allowed_codes
from edm_sym.engines.abstraction.holdout import Holdout, Scorer, fragile_rows
from edm_sym.engines.abstraction.local_search import Candidate, step_candidates
from edm_sym.engines.abstraction.prune import apply_parsimony, refit_gains
from edm_sym.engines.abstraction.schedule import AbstractionConfig


def finish(steps: Sequence[StepRecord], comp: Compensator, hold: Holdout,
           cfg: AbstractionConfig, select: str | None = None, *,
           candidates_in: Sequence[Candidate] | None = None,
           clocks: Mapping[int, float] | None = None, laws: Mapping[str, int] | None = None,
           observer: float | None = None
           ) -> tuple[Compensator, dict[str, Any], dict[str, Any]]:
    """After the search: choose the search's model, prune it, score the exported one.

    Parameters
    ----------
    steps : sequence of StepRecord
        The steps' bests.
    comp : Compensator
        The last step's best (its ranges and sample time serve every model).
    hold : Holdout
        What was held out (:func:`~edm_sym.engines.abstraction.holdout.plan_holdout`).
    cfg : AbstractionConfig
    select : str, optional
        A selection rule overriding the config's.
    candidates_in : sequence of Candidate, optional
        The candidates of the search's model already made (several searches:
        each made its own,
        :func:`~edm_sym.engines.abstraction.searches.search_candidates`, and
        each names its search). Each of ``start_candidates`` then names its ``search``.
    clocks : mapping of int to float, optional
        The angle inputs that are a clock of a training log, and the shift that
        tests a row (:func:`~edm_sym.engines.abstraction.clocks.clock_shifts`):
        every candidate loses the rows that read time from them
        (:func:`without_passengers`) before the choice and the pruning; without
        pruning (``--no-prune``, an interrupted run) they keep them.
    laws : mapping of str to int, optional
        The input of each linear law's row offered before the pruning
        (:func:`~edm_sym.engines.abstraction.prune.offer_law_rows`).
    observer : float, optional
        The observer's bandwidth [rad/s] the log records: the law rows are also
        offered through its low-pass.

    Returns
    -------
    comp, parsimony, validation
        The exported model, result.json's ``parsimony`` and ``validation`` entries.
    """
    scorer = Scorer(hold, cfg.steps[steps[-1].step - 1].weighting, cfg.parsimony.criterion)
    start_step, refitted, refit = steps[-1].step, False, 0
    clock_rows: list[dict[str, Any]] = []
    candidates: list[dict[str, Any]] = []
    if not cfg.parsimony.prune:
        clocks = None  # --no-prune (and an interrupted run) keep the search's model as it is
    if cfg.parsimony.from_step_bests:
        # The step best with the lowest plain RMSE over the whole log: Step 4's eq. 16
        # weighting, say, may buy large torques with reversals and the cold start, which
        # only the whole log holds. Step bests within ``tie`` of it are tied, and the
        # held-out blocks choose among them (then a later step): a refit lowers the fitted
        # samples' RMSE by construction (docs/abstraction.md, "Parsimony").
        # A step best with a tangent pole inside its input's range is passed over while
        # another is sound (holdout.fragile_rows).
        # Each step best is also refitted on the whole training part: one that learnt a law
        # on eq. 15's windows often beats the others there (docs/abstraction.md#seed-robustness).
        refit = cfg.parsimony.refit
        cands = (list(candidates_in) if candidates_in is not None
                 else step_candidates(steps, comp, hold, max_evaluations=refit,
                                      reject_poles=cfg.steps[-1].ga.reject_poles))
        dropped = []
        for q, c in enumerate(cands):
            m, found = without_passengers(replace(comp, matrix=c.matrix), scorer, clocks)
            cands[q] = replace(c, matrix=m.matrix) if found else c
            dropped.append(_clock_rows(c.matrix, found))
        sound = [q for q, c in enumerate(cands)
                 if not fragile_rows(replace(comp, matrix=c.matrix), hold.training.x)]
        pool = sound or list(range(len(cands)))
        q, candidates = start_candidate([replace(comp, matrix=cands[q].matrix) for q in pool],
                                        scorer, cfg.parsimony.tie)
        start = cands[pool[q]]
        clock_rows = dropped[pool[q]]
        comp, start_step, refitted = replace(comp, matrix=start.matrix), start.step, start.refitted
        for c, r in zip(candidates, pool, strict=True):
            c.update(step=cands[r].step, refitted=cands[r].refitted)
            if dropped[r]:
                c["clock_rows"] = len(dropped[r])
            if candidates_in is not None:
                c["search"] = cands[r].search
    else:
        origin = comp.matrix
        comp, found = without_passengers(comp, scorer, clocks)
        clock_rows = _clock_rows(origin, found)
    comp, parsimony = apply_parsimony(comp, scorer, cfg.parsimony, select, start_step=start_step,
                                      refit=refit, refitted=refitted, laws=laws, observer=observer,
                                      allowed=allowed_codes(cfg.steps[-1].ga.elements).tolist())
    if parsimony and candidates:
        parsimony["start_tie"] = cfg.parsimony.tie
        parsimony["start_candidates"] = candidates
    if parsimony and clock_rows:
        parsimony["clock_rows"] = clock_rows
    return comp, parsimony, scorer.report(comp)


def without_passengers(comp: Compensator, scorer: Scorer, clocks: Mapping[int, float] | None
                       ) -> tuple[Compensator, list[Passenger]]:
    """``comp`` without the rows that read time from a clock, its row gains refitted on the
    training part (:mod:`~edm_sym.engines.abstraction.clocks`); and those rows. A model
    made of nothing else is left as it is (the naming calls its rows a clock)."""
    if not clocks:
        return comp, []
    part = scorer.parts["training"]
    y = part.y[part.sl]
    target_rms = float(np.sqrt(np.mean(y * y)))
    found = passengers(comp, comp.matrix, part.x, part.starts, dict(clocks), part.sl, target_rms)
    if not found or len(found) == len(comp.matrix.rows):
        return comp, []
    gone = {p.row for p in found}
    m = ElementMatrix(comp.matrix.inputs,
                      tuple(r for j, r in enumerate(comp.matrix.rows) if j not in gone))
    refit = refit_gains(comp, m, scorer)
    return replace(comp, matrix=refit if refit is not None else m), found


def _clock_rows(matrix: ElementMatrix, found: Sequence[Passenger]) -> list[dict[str, Any]]:
    """result.json's ``parsimony.clock_rows``: each dropped row, its input and its change."""
    rows = matrix_to_json(matrix)["rows"]
    return [{"row": rows[p.row], "shift": p.shift,
             "change": p.change if math.isfinite(p.change) else None} for p in found]


def start_candidate(comps: Sequence[Compensator], scorer: Scorer, tie: float
                    ) -> tuple[int, list[dict[str, Any]]]:
    """Which candidate the pruning starts from, and each one's scores (result.json).

    The lowest plain RMSE over the whole abstraction log wins, unless others are
    within ``tie`` (relative) of it: then the lowest held-out RMSE among those
    (a later candidate on a tie). With nothing held out, the whole log alone.

    Returns
    -------
    index, candidates
        The index into ``comps``; per candidate ``{"whole_rmse": [v, unit],
        "held_out_rmse": [v or None, unit], "tied": bool, "chosen": bool}``.
    """
    whole = [scorer.whole_rmse(c) for c in comps]
    held = [scorer.held_out_rmse(c) for c in comps]
    low = min(whole)
    tied = [q for q, w in enumerate(whole) if w <= low * (1.0 + tie)]
    q = min(tied, key=lambda q: (whole[q] if held[q] is None else held[q], whole[q], -q))
    unit = scorer.holdout.unit

    def finite(v: float | None) -> float | None:
        return v if v is not None and math.isfinite(v) else None

    return q, [{"whole_rmse": [finite(whole[k]), unit], "held_out_rmse": [finite(held[k]), unit],
                "tied": k in tied, "chosen": k == q} for k in range(len(comps))]
