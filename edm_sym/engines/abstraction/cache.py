"""The row store: least-recently-used row outputs in one block of fixed-size slots.

:class:`SlotStore` holds rows in one anonymous memory map of fixed-size slots,
shared with worker processes forked after it was made: they write simulated
rows straight into their slots and read any row from it, so no row output is
ever pickled between processes. Row prefixes go into a second such store,
shared the same way (see :mod:`~edm_sym.engines.abstraction.prefixes`). A
worker without shared stores keeps private ones. A store's size is fixed
when it is made (``cache_mb``), so it bounds the memory by construction.
"""

from __future__ import annotations

import mmap
from collections import OrderedDict
from collections.abc import Collection

import numpy as np


class SlotStore:
    """Rows of N float64 in a shared anonymous memory map, by least recent use.

    The map is ``MAP_SHARED``: a process forked after the store was made
    sees the same memory, so workers fill slots in place.

    Parameters
    ----------
    slots : int
        Number of rows the store holds.
    n : int
        Samples per row.
    """

    def __init__(self, slots: int, n: int):
        self.slots = int(slots)
        # Anonymous and shared (mmap's default for fileno -1). The pages are made now
        # (MAP_POPULATE, where there is one): a page fault per 4 kB on first use
        # would cost more than simulating the row that fills it.
        size = max(1, self.slots * n * 8)
        populate = getattr(mmap, "MAP_POPULATE", 0)
        if populate:
            flags = mmap.MAP_SHARED | getattr(mmap, "MAP_ANONYMOUS", 0x20) | populate
            self._map = mmap.mmap(-1, size, flags=flags)
        else:  # pragma: no cover (not Linux)
            self._map = mmap.mmap(-1, size)
        self.rows = np.frombuffer(self._map, dtype=np.float64,
                                  count=self.slots * n).reshape(self.slots, n)
        self._lru: OrderedDict[bytes, int] = OrderedDict()
        self._free = list(range(self.slots - 1, -1, -1))

    def __len__(self) -> int:
        return len(self._lru)

    def get(self, key: bytes) -> np.ndarray | None:
        """A view of the row of ``key`` (refreshing it), or None."""
        slot = self.lookup(key)
        return None if slot is None else self.rows[slot]

    def lookup(self, key: bytes) -> int | None:
        """The slot of the row of ``key`` (refreshing it), or None."""
        slot = self._lru.get(key)
        if slot is not None:
            self._lru.move_to_end(key)
        return slot

    def allocate(self, count: int, keep: Collection[bytes]) -> list[int]:
        """``count`` free slots, evicting least recently used rows not in ``keep``.

        Raises
        ------
        RuntimeError
            When the store is too small for a batch.
        """
        out = []
        while len(out) < count:
            if self._free:
                out.append(self._free.pop())
                continue
            for key in self._lru:
                if key not in keep:
                    out.append(self._lru.pop(key))
                    break
            else:
                raise RuntimeError(f"row store of {self.slots} slots is too small for a "
                                   f"batch of {count} new rows")
        return out

    def place(self, keys: Collection[bytes], keep: Collection[bytes]) -> list[int]:
        """Slots for the new rows ``keys`` (see :meth:`allocate`); :meth:`commit` each once written."""
        return self.allocate(len(keys), keep)

    def storing(self, keys: Collection[bytes]) -> bool:
        """Whether new rows ``keys`` get slots: always (the store makes room)."""
        return True

    def release(self, slots: Collection[int]) -> None:
        """Give back slots allocated but never committed."""
        self._free.extend(int(s) for s in slots)

    def commit(self, key: bytes, slot: int) -> np.ndarray:
        """Record that ``slot`` holds the row of ``key``; return its view."""
        self._lru[key] = slot
        return self.rows[slot]

    @property
    def nbytes(self) -> int:
        """Bytes of the store (all slots, used or not)."""
        return self.rows.nbytes

    def clear(self) -> None:
        """Forget every row (the memory stays)."""
        self._lru.clear()
        self._free = list(range(self.slots - 1, -1, -1))
