"""Where a batch's gain-fit candidates are evaluated: in the lane that fits them.

The gain fit (:mod:`~edm_sym.engines.abstraction.gain_fit`) makes at most one
candidate per individual, which differs from it only in the scale of some
rows. Evaluating the candidates in a second batch would cost each generation a
second round trip to every lane, with the lanes idle while this process plans
it. Instead the lane that scores an individual also makes its candidate (the
same function on the same genes, so the same candidate), simulates its new
rows and scores it.

With the shared stores of the default pool, this process plans for that
before the batch goes out (:class:`CandidatePlan`):

* spare slots of the row store, one per row a candidate may change (a free
  row of a scored individual), given to the chunk of that individual; the
  lane answers which of them it wrote, and with which rows, recorded as its
  piece comes in (:meth:`CandidatePlan.record`), and the others are given
  back once every piece is in (:meth:`CandidatePlan.release`);
* for each free row, its longest prefix stored before the batch that its
  candidates share (a candidate changes a row from its scaled element on), so
  a candidate runs only the elements after it. Those prefixes keep their slots
  during the batch (:func:`~edm_sym.engines.abstraction.prefixes.plan_prefixes`'
  ``keep``); a lane also reads the prefixes it writes itself, never another
  lane's, which may not be written yet.

A candidate's eq. 8 is a pure function of its genes, as any individual's, so
where it is computed changes nothing but the time.
"""

from __future__ import annotations

from collections.abc import Collection, Sequence
from typing import Any

import numpy as np

from edm_sym.engines.abstraction.balance import candidate_costs
from edm_sym.engines.abstraction.cache import SlotStore
from edm_sym.engines.abstraction.gain_fit import scale_places
from edm_sym.engines.abstraction.prefixes import stored_prefixes


class CandidatePlan:
    """A batch's plan for its gain-fit candidates (see the module text).

    Parameters
    ----------
    table : numpy.ndarray
        Shape (R, 1 + 2 n): the batch's distinct rows.
    members : numpy.ndarray
        Shape (P, m): each individual's rows, as lines of ``table``.
    score : numpy.ndarray
        Shape (P,) bool: the individuals scored.
    free : numpy.ndarray or None
        Shape (P, m) bool: the rows the gain fit may scale.
    gains : bool or None
        Whether a ``through`` may become a ``gain``; None: no candidates.
    store, prefixes : SlotStore or None
        The shared row and prefix stores (None: each lane keeps its own).
    keep : collection of bytes
        The batch's row keys (spare slots never evict them).
    costs : numpy.ndarray, optional
        With the shared stores: the estimated cost of each element of each
        line (:func:`~edm_sym.engines.abstraction.balance.element_costs`),
        which sets :attr:`cost`, each candidate's, for cutting the batch.
    """

    def __init__(self, table: np.ndarray, members: np.ndarray, score: np.ndarray,
                 free: np.ndarray | None, gains: bool | None, store: SlotStore | None,
                 prefixes: SlotStore | None, keep: Collection[bytes],
                 costs: np.ndarray | None = None):
        count = len(members)
        self.gains = gains if free is not None else None
        self.store = store
        self.cost = np.zeros(count)
        self.reads: set[bytes] = set()
        self._spare: np.ndarray | None = None
        self._kept: set[int] = set()
        self._batch = keep  # the batch's row keys: a missing one is recorded by its lane
        self._start = self._slots = None
        if self.gains is None:
            return
        n = (table.shape[1] - 1) // 2
        self._fits = score[:, None] & free  # (P, m): a candidate may change these rows
        pos = scale_places(table[:, 1:1 + n].astype(np.int64), self.gains)[0]
        if costs is not None:
            self.cost = candidate_costs(members, self._fits, costs, pos)
        if store is None:
            return
        lines = np.zeros(len(table), dtype=bool)
        lines[members[self._fits]] = True
        depth = np.where(lines, np.maximum(pos, 0), 0)
        self._start, self._slots, self.reads = stored_prefixes(prefixes, table, depth)
        per = self._fits.sum(axis=1)
        self._offsets = np.concatenate([[0], np.cumsum(per)])
        self._spare = np.array(store.allocate(int(self._offsets[-1]), keep), dtype=np.int64)

    def of(self, idx: Sequence[int], lines: np.ndarray
           ) -> tuple[np.ndarray | None, np.ndarray | None, np.ndarray | None]:
        """The chunk of individuals ``idx`` (table lines ``lines``): spare slots, prefix starts."""
        if self._spare is None:
            return None, None, None
        off = self._offsets
        spare = np.concatenate([self._spare[off[a]:off[a + 1]] for a in idx]
                               or [np.zeros(0, dtype=np.int64)])
        return spare, self._start[lines], self._slots[lines]

    def record(self, res: Any) -> None:
        """Record the candidates' rows one lane wrote (unless stored already)."""
        if self._spare is None or res.fit_lines is None:
            return
        for line, slot in zip(res.fit_lines, res.fit_slots.tolist(), strict=True):
            key = line.tobytes()
            if key not in self._batch and self.store.lookup(key) is None:
                self.store.commit(key, slot)
                self._kept.add(slot)

    def release(self) -> None:
        """Give back the spare slots no candidate row kept (once every piece is in)."""
        if self._spare is not None:
            self.store.release([s for s in self._spare.tolist() if s not in self._kept])
