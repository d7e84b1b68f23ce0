"""How a batch of individuals is cut among lanes: speed only, never a result.

With the shared stores of the default pool (a row or prefix simulated once
serves every lane), a batch is cut into *groups*: individuals that need the
same new row form one group, so no row is computed by two lanes, and so do
individuals whose new rows make the same new prefix, up to a cost cap past
which each lane computes that prefix itself (:func:`groups`). Each group
gets an estimated cost (:func:`group_costs`: the elements its new rows run,
each by its ``Element.cost``, and the scoring of its
individuals), and a :class:`Feeder` cuts the groups into one piece per lane,
dearest first, in proportion to the lanes' measured speeds (:class:`Speeds`).

Without shared stores (a dask cluster on other machines, an executor), each
worker keeps its own, so an individual goes to the lane whose store most
likely holds its rows (:func:`by_affinity`).
"""

from __future__ import annotations

import math
from collections import OrderedDict
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from edm_sym.core.elements import REGISTRY
from edm_sym.engines.abstraction.prefixes import PrefixPlan

#: Estimated cost of scoring one row of an individual (eq. 8), in elements run (fitted
#: on the auger schedule's tasks: about 100 us per element, 60 per scored row, 80 more with
#: the gain fit).
SCORE_COST = 0.6
#: Estimated cost of the gain fit of one individual per row (inner products, least squares).
FIT_COST = 0.8


#: A row's own cost (its program, its schedule, its output), in the same unit.
ROW_COST = 0.2
#: Each element code's ``Element.cost`` (the unit of :data:`SCORE_COST`): a tangent or a
#: power costs 20-25 gains, so counting elements alike misjudged the pieces.
_CODE_COST = np.array([REGISTRY[c].cost if c in REGISTRY else 1.0
                       for c in range(max(REGISTRY) + 1)])


def element_costs(table: np.ndarray) -> np.ndarray:
    """The estimated cost of each element of each line of a gene table, shape (R, n).

    A row's own :data:`ROW_COST` is carried by its last element (always run).
    """
    n = (table.shape[1] - 1) // 2
    costs = _CODE_COST[table[:, 1:1 + n].astype(np.int64)]
    if n:
        costs[:, -1] += ROW_COST
    return costs


def scoring_costs(members: np.ndarray, score: np.ndarray, free: np.ndarray | None) -> np.ndarray:
    """Estimated cost of scoring each individual (eq. 8, and the gain fit), in elements run.

    A scored individual costs :data:`SCORE_COST` per row, and with the gain
    fit :data:`FIT_COST` per row more.
    """
    m = members.shape[1]
    per = np.where(score, SCORE_COST * m, 0.0)
    if free is not None:
        per = per + np.where(score & free.any(axis=1), FIT_COST * m, 0.0)
    return per


def candidate_costs(members: np.ndarray, fits: np.ndarray, costs: np.ndarray, pos: np.ndarray
                    ) -> np.ndarray:
    """Estimated cost of each individual's gain-fit candidate, evaluated in its lane.

    Each row it may change runs from its scaled element on (``pos``, from
    the prefix it shares with its row), and the candidate is scored.

    Parameters
    ----------
    members : numpy.ndarray
        Shape (P, m): each individual's rows, as lines of the batch's table.
    fits : numpy.ndarray
        Shape (P, m) bool: the rows its candidate may change.
    costs : numpy.ndarray
        Shape (R, n): :func:`element_costs` of the table.
    pos : numpy.ndarray
        Shape (R,): each line's scaled element (-1: none).
    """
    rest = np.cumsum(costs[:, ::-1], axis=1)[:, ::-1]
    tail = rest[np.arange(len(rest)), np.maximum(pos, 0)]
    m = members.shape[1]
    return np.where(fits.any(axis=1), SCORE_COST * m + (tail[members] * fits).sum(axis=1), 0.0)


def groups(members: np.ndarray, plan: PrefixPlan, missing: np.ndarray,
           per: np.ndarray | None = None, cap: float = math.inf) -> list[list[int]]:
    """Individuals that must run in one chunk: they share a new row (or a new prefix).

    Individuals that need the same new row always form one group (a row is
    simulated once). Individuals whose new rows make the same new prefix
    join too, as long as the group's estimated cost stays within ``cap``;
    past it the groups stay apart, and each lane that gets one of them
    computes that prefix itself (into the same planned slot: the same bits,
    so the lanes' writes agree). A few elements run twice, and no group is
    so large that the lanes cannot end together.

    Parameters
    ----------
    members : numpy.ndarray
        Shape (P, m): each individual's rows, as lines of the batch's table.
    plan : PrefixPlan
        The batch's prefix plan (its new prefixes' slots).
    missing : numpy.ndarray
        Shape (R,) bool: the lines to simulate.
    per : numpy.ndarray, optional
        Shape (P,) each individual's scoring cost (:func:`scoring_costs`;
        default 0).
    cap : float
        The largest estimated cost (new rows' elements and scoring) a group
        joined by a shared prefix may reach (default: no bound).

    Returns
    -------
    list of list of int
        The groups, each sorted, in the order of their first individual.
    """
    count = len(members)
    parent = list(range(count))
    cost = [0.0] * count if per is None else [float(c) for c in per]

    def find(i: int) -> int:
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    def join(i: int, j: int) -> None:
        a, b = find(i), find(j)
        if a != b:
            parent[a] = b
            cost[b] += cost[a]

    new = np.flatnonzero(missing).tolist()
    miss = missing.tolist()
    row_owner: dict[int, int] = {}
    for i, row in enumerate(members.tolist()):
        for r in row:
            if miss[r]:
                j = row_owner.setdefault(r, i)
                if j != i:
                    join(i, j)
    row_cost = plan.cost.tolist()
    for r in new:
        cost[find(row_owner[r])] += row_cost[r]
    made: dict[int, int] = {}  # a new prefix's slot -> one individual that makes it
    slots, start = plan.slots.tolist(), plan.start.tolist()
    for r in new:
        i = row_owner[r]
        for s in slots[r][start[r] + 1:]:
            if s < 0:
                continue
            j = made.setdefault(s, i)
            if j == i:
                continue
            a, b = find(i), find(j)
            if a != b and cost[a] + cost[b] <= cap:
                join(a, b)
    out: dict[int, list[int]] = {}
    for i in range(count):
        out.setdefault(find(i), []).append(i)
    return list(out.values())


def group_costs(parts: Sequence[Sequence[int]], members: np.ndarray, plan: PrefixPlan,
                per: np.ndarray) -> np.ndarray:
    """Estimated cost of each group, in elements run over the signal.

    A new row costs the elements it runs (from its longest stored prefix);
    an individual's scoring ``per`` (:func:`scoring_costs`).
    """
    m = members.shape[1]
    group = np.empty(len(members), dtype=np.int64)
    for g, idx in enumerate(parts):
        group[idx] = g
    # A row to simulate belongs to one group (its individuals are all in it); a row
    # not simulated costs 0 wherever it is.
    owner = np.empty(len(plan.cost), dtype=np.int64)
    owner[members.reshape(-1)] = np.repeat(group, m)
    return (np.bincount(owner, weights=plan.cost, minlength=len(parts))
            + np.bincount(group, weights=per, minlength=len(parts)))


class Feeder:
    """A batch's groups cut into one piece per lane, in proportion to the lanes' speeds.

    The groups go, dearest first, to the piece that would end first with
    them (its estimated cost over its lane's speed): longest processing
    time first, for lanes of different speeds.

    Parameters
    ----------
    parts : sequence of list of int
        The groups.
    costs : numpy.ndarray
        Their estimated costs.
    speeds : sequence of float
        Each lane's speed (estimated cost per second; only the ratios count).
    """

    def __init__(self, parts: Sequence[list[int]], costs: np.ndarray, speeds: Sequence[float]):
        count = len(speeds)
        bins: list[list[int]] = [[] for _ in range(count)]
        self.loads = [0.0] * count
        for g in np.argsort(-costs, kind="stable").tolist():
            b = min(range(count), key=lambda b: (self.loads[b] + costs[g]) / speeds[b])
            bins[b].extend(parts[g])
            self.loads[b] += float(costs[g])
        self.pieces = [sorted(piece) for piece in bins]


class Speeds:
    """Each lane's speed: estimated cost per second, a moving average over its pieces."""

    def __init__(self, count: int):
        self._speed: list[float | None] = [None] * count

    def of(self, lanes: Sequence[int]) -> list[float]:
        """The speeds of ``lanes`` (a lane not timed yet: the mean of the others, or 1)."""
        known = [v for v in self._speed if v is not None]
        guess = sum(known) / len(known) if known else 1.0
        return [guess if self._speed[lane] is None else self._speed[lane] for lane in lanes]

    def timed(self, lane: int, cost: float, seconds: float) -> None:
        """Fold in a piece of ``cost`` that took ``seconds``."""
        if cost > 0.0 and seconds > 1e-4:
            old = self._speed[lane]
            self._speed[lane] = cost / seconds if old is None else old + 0.2 * (cost / seconds - old)


def feed(pieces: Sequence[list[int]], lanes: Sequence[int], here: int | None,
         send: Callable[[int, list[int]], Any], receive: Callable[[int, list[int], Any], Any],
         run: Callable[[list[int]], Any], aside: Callable[[], None] = lambda: None) -> list:
    """Run a batch's pieces, one per lane: the remote ones first, then this process's.

    Parameters
    ----------
    pieces : sequence of list of int
        One per lane (empty: nothing for that lane).
    lanes : sequence of int
        The lanes, in the order of ``pieces``.
    here : int or None
        The position of this process's lane among ``lanes`` (None: it is none).
    send : callable
        ``send(lane, idx)``: submit piece ``idx`` to a remote lane; a future.
    receive : callable
        ``receive(lane, idx, future)``: the piece's result, once it is done.
    run : callable
        ``run(idx)``: run a piece in this process; its result.
    aside : callable
        Work of this process that needs no result, done once the pieces are sent.

    Returns
    -------
    list
        The results, one per non-empty piece.
    """
    sent = [(lane, idx, send(lane, idx))
            for k, (lane, idx) in enumerate(zip(lanes, pieces, strict=True)) if k != here and idx]
    aside()
    results = []
    if here is not None and pieces[here]:
        results.append(run(pieces[here]))
    results.extend(receive(lane, idx, future) for lane, idx, future in sent)
    return results


def by_affinity(keys: Sequence[bytes], members: np.ndarray, lanes: Sequence[int],
                mirrors: Sequence[OrderedDict], limit: int) -> list[tuple[int, list[int]]]:
    """Individuals per lane when each lane keeps its own store.

    Each individual goes to the lane whose store most likely holds most of
    its rows (``mirrors``: per lane, the row keys sent to it lately, at most
    ``limit``), unless that lane already has a quarter more than its share.
    """
    count = len(members)
    cap = math.ceil(count * 5 / (4 * len(lanes)))
    parts: list[list[int]] = [[] for _ in lanes]
    for i in range(count):
        rk = [keys[r] for r in members[i]]
        best, held = None, -1
        for w, lane in enumerate(lanes):
            if len(parts[w]) >= cap:
                continue
            have = sum(k in mirrors[lane] for k in rk)
            if have > held or (have == held and len(parts[w]) < len(parts[best])):
                best, held = w, have
        parts[best].append(i)
        mirror = mirrors[lanes[best]]
        for k in rk:
            mirror[k] = True
            mirror.move_to_end(k)
        while len(mirror) > limit:
            mirror.popitem(last=False)
    return [(lanes[w], idx) for w, idx in enumerate(parts)]
