"""Row prefixes: keys, and a store of them shared between processes.

A row's prefix k is its signal after its first k elements. A row that
differs from a stored one only in its later elements starts from their
longest common prefix, and stores the prefixes it computes.

A process without a shared store keeps its prefixes in a
:class:`~edm_sym.engines.abstraction.cache.SlotStore` of its own. With the
default pool the prefixes live in one shared store, which the main process
manages as it manages the rows: before a batch is sent, :func:`plan_prefixes`
finds each new row's longest stored prefix and gives every prefix the batch
will make a slot of its own (a prefix two new rows share once, so the lanes
never compute one twice); the lane that simulates the row reads and writes
them through a :class:`ChunkPrefixes` and answers which slots it wrote, which
the main process then records as each piece comes in (:meth:`PrefixPlan.record`).

Both kinds of store answer the same calls (``lookup``, ``get``, ``place``,
``commit``, ``storing``), so :func:`~edm_sym.engines.abstraction.worker.simulate_into`
runs the same way on either.
"""

from __future__ import annotations

from collections.abc import Collection, Sequence
from dataclasses import dataclass, field

import numpy as np

from edm_sym.engines.abstraction.cache import SlotStore


def prefix_key(line: np.ndarray, n: int, k: int) -> bytes:
    """Key of the first ``k`` elements of a gene-table line (the row key of that prefix)."""
    return line[:1 + k].tobytes() + line[1 + n:1 + n + k].tobytes()


def prefix_keys(table: np.ndarray, k: int) -> list[bytes]:
    """:func:`prefix_key` of every line of ``table`` for one ``k`` (at once)."""
    n = (table.shape[1] - 1) // 2
    part = np.ascontiguousarray(np.concatenate([table[:, :1 + k], table[:, 1 + n:1 + n + k]],
                                               axis=1))
    return part.view(np.dtype((np.void, part.shape[1] * 8))).ravel().tolist()


@dataclass
class PrefixPlan:
    """Where a batch's rows start and where the prefixes they make go.

    Attributes
    ----------
    start : numpy.ndarray
        Shape (R,) int64: per line of the batch's table, the number of
        elements of its longest stored prefix (0: none, or a row not simulated).
    slots : numpy.ndarray
        Shape (R, n) int64: column ``start`` the slot of that prefix; columns
        above, the slots its new prefixes go to (all or none: -1); -1 elsewhere.
    cost : numpy.ndarray
        Shape (R,): the estimated cost of the elements each line runs (from
        its longest stored prefix; 0 for a row not simulated).
    new : dict
        Slot to key of every new prefix.
    """

    start: np.ndarray
    slots: np.ndarray
    cost: np.ndarray
    new: dict[int, bytes] = field(default_factory=dict)
    written: set[int] = field(default_factory=set)

    def record(self, store: SlotStore, written: np.ndarray) -> None:
        """Record the new prefixes one lane wrote (slots), as soon as its piece is in."""
        for s in written.tolist():
            self.written.add(s)
            store.commit(self.new[s], s)

    def release(self, store: SlotStore) -> None:
        """Give back the slots of the new prefixes no lane wrote (once every piece is in)."""
        store.release([s for s in self.new if s not in self.written])


def stored_prefixes(store: SlotStore, table: np.ndarray, depth: np.ndarray
                    ) -> tuple[np.ndarray, np.ndarray, set[bytes]]:
    """Each line's longest stored prefix of at most ``depth[r]`` elements.

    A gain-fit candidate differs from its row from element ``depth`` on, so
    it can start where that row's stored prefix ends.

    Parameters
    ----------
    store : SlotStore
        The shared prefix store.
    table : numpy.ndarray
        Shape (R, 1 + 2 n): the batch's distinct rows.
    depth : numpy.ndarray
        Shape (R,) int: the deepest prefix wanted (0: none).

    Returns
    -------
    start : numpy.ndarray
        Shape (R,) int64: the prefix's length (0: none stored).
    slots : numpy.ndarray
        Shape (R,) int64: its slot (-1: none).
    found : set of bytes
        Their keys (for :func:`plan_prefixes`' ``keep``).
    """
    count = table.shape[0]
    start = np.zeros(count, dtype=np.int64)
    slots = np.full(count, -1, dtype=np.int64)
    found: set[bytes] = set()
    want = np.flatnonzero(depth > 0)
    if not len(want):
        return start, slots, found
    sub = table[want]
    deep = depth[want]
    got = np.zeros(len(want), dtype=np.int64)  # per wanted line: its prefix's length (0: none)
    at = np.full(len(want), -1, dtype=np.int64)
    for k in range(int(deep.max()), 0, -1):
        open_ = np.flatnonzero((deep >= k) & (got == 0))
        if not len(open_):
            continue
        keys = prefix_keys(sub[open_], k)
        where = np.array(store.lookup_many(keys), dtype=np.int64)
        hit = np.flatnonzero(where >= 0)
        found.update(keys[a] for a in hit.tolist())
        got[open_[hit]], at[open_[hit]] = k, where[hit]
    start[want], slots[want] = got, at
    return start, slots, found


def plan_prefixes(store: SlotStore, table: np.ndarray, simulate: np.ndarray,
                  costs: np.ndarray | None = None, keep: Collection[bytes] = ()) -> PrefixPlan:
    """Each new row's longest stored prefix, and a slot for each prefix the batch makes.

    Parameters
    ----------
    store : SlotStore
        The shared prefix store (its least recent prefixes make room).
    table : numpy.ndarray
        Shape (R, 1 + 2 n): the batch's distinct rows.
    simulate : numpy.ndarray
        Shape (R,) bool: the rows to simulate.
    costs : numpy.ndarray, optional
        Shape (R, n): the estimated cost of each element of each row (default
        1 each: :attr:`PrefixPlan.cost` counts the elements run).
    keep : collection of bytes
        Keys of stored prefixes the batch reads besides (they keep their
        slots; the new prefixes get at most the rest of the store).

    Returns
    -------
    PrefixPlan
        A row whose new prefixes do not fit in half the store gets none (it
        is simulated without storing them).
    """
    count = table.shape[0]
    n = (table.shape[1] - 1) // 2
    start = np.zeros(count, dtype=np.int64)
    slots = np.full((count, max(n, 1)), -1, dtype=np.int64)
    if costs is None:
        costs = np.ones((count, n))
    # rest[r, k]: the cost of row r's elements k .. n - 1.
    rest = np.cumsum(costs[:, ::-1], axis=1)[:, ::-1]
    cost = np.where(simulate, rest[:, 0] if n else 0.0, 0.0)
    plan = PrefixPlan(start, slots, cost)
    todo = np.flatnonzero(simulate)
    if n < 2 or not len(todo):
        return plan
    sub = table[todo]
    keys = [None, *(prefix_keys(sub, k) for k in range(1, n))]
    used: set[bytes] = set(keep)
    wants: dict[bytes, list[tuple[int, int]]] = {}
    rows = todo.tolist()
    # Each row's longest stored prefix: every length looked up at once, the longest
    # found kept, and only those refreshed, in row order (as a lookup per row would).
    deepest = np.zeros(len(rows), dtype=np.int64)
    at = np.full(len(rows), -1, dtype=np.int64)
    for k in range(1, n):
        where = np.array(store.peek(keys[k]), dtype=np.int64)
        hit = where >= 0
        deepest[hit], at[hit] = k, where[hit]
    hit = np.flatnonzero(deepest).tolist()
    found = deepest.tolist()
    read = [keys[found[a]][a] for a in hit]
    store.touch(read)
    used.update(read)
    slots[todo[hit], deepest[hit]] = at[hit]
    start[todo] = deepest
    cost[todo] = rest[todo, deepest]
    # The prefixes read keep their slots: the new ones get at most the others.
    budget = min(store.slots // 2, store.slots - len(used))
    roomy = sum(n - 1 - f for f in found) <= budget  # every row's new prefixes fit
    for a, r in enumerate(rows):
        if not roomy:
            fresh = sum(1 for k in range(found[a] + 1, n) if keys[k][a] not in wants)
            if len(wants) + fresh > budget:
                continue
        for k in range(found[a] + 1, n):
            wants.setdefault(keys[k][a], []).append((r, k))
    if wants:
        order = list(wants)
        for key, slot in zip(order, store.place(order, used), strict=True):
            plan.new[slot] = key
            for r, k in wants[key]:
                slots[r, k] = slot
    return plan


class ChunkPrefixes:
    """A lane's view of the shared prefix store for one chunk.

    Parameters
    ----------
    rows : numpy.ndarray
        The shared store's rows.
    table : numpy.ndarray
        The chunk's rows.
    start, slots : numpy.ndarray
        Their lines of a :class:`PrefixPlan`.
    capacity : int
        The shared store's slot count (bounds the rows run together).
    """

    def __init__(self, rows: np.ndarray, table: np.ndarray, start: np.ndarray,
                 slots: np.ndarray, capacity: int):
        self.rows = rows
        self.slots = int(capacity)
        n = (table.shape[1] - 1) // 2
        self._known: dict[bytes, int] = {}
        self._assigned: dict[bytes, int] = {}
        for line, k0, mine in zip(table, start.tolist(), slots.tolist(), strict=True):
            if k0:
                self._known[prefix_key(line, n, k0)] = mine[k0]
            for k in range(k0 + 1, n):
                if mine[k] >= 0:
                    self._assigned[prefix_key(line, n, k)] = mine[k]
        self.written: list[int] = []

    @classmethod
    def reader(cls, rows: np.ndarray, known: dict[bytes, int]) -> ChunkPrefixes:
        """A view of the shared store that reads the prefixes ``known`` (key: slot), stores none.

        Gain-fit candidates start from their rows' prefixes, stored before the
        batch or written by their chunk (:meth:`reading`); theirs are not kept.
        """
        view = cls(rows, np.zeros((0, 1)), np.zeros(0, dtype=np.int64),
                   np.zeros((0, 1), dtype=np.int64), rows.shape[0])
        view._known = dict(known)
        return view

    def reading(self, known: dict[bytes, int]) -> ChunkPrefixes:
        """:meth:`reader` of ``known`` and the prefixes this chunk knows (those it wrote too)."""
        return ChunkPrefixes.reader(self.rows, {**known, **self._known})

    def lookup(self, key: bytes) -> int | None:
        """The slot of a stored prefix (one the plan named, or one this chunk wrote), or None."""
        return self._known.get(key)

    def get(self, key: bytes) -> np.ndarray | None:
        """A view of a stored prefix, or None."""
        slot = self._known.get(key)
        return None if slot is None else self.rows[slot]

    def storing(self, keys: Collection[bytes]) -> bool:
        """Whether the plan gave slots to all these new prefixes (a row stores all or none)."""
        return all(key in self._assigned for key in keys)

    def place(self, keys: Sequence[bytes], keep: Collection[bytes]) -> list[int]:
        """The slots the plan gave these new prefixes."""
        return [self._assigned[key] for key in keys]

    def commit(self, key: bytes, slot: int) -> None:
        """Record that ``slot`` holds the prefix ``key``."""
        self._known[key] = slot
        self.written.append(slot)
