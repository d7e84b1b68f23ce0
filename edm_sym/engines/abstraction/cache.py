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

import contextlib
import mmap
import os
import secrets
import shutil
from collections import OrderedDict
from collections.abc import Collection, Sequence
from itertools import filterfalse, islice, repeat
from pathlib import Path

import numpy as np

#: Where named stores live: memory, not disk, and never shared between machines.
SHM = Path("/dev/shm")


class SlotStore:
    """Rows of N float64 in a shared memory map, by least recent use.

    The map is ``MAP_SHARED``: a process forked after the store was made
    sees the same memory, so workers fill slots in place. A *named* store
    (``path``, a file in ``/dev/shm``) is shared with any process of this
    machine that opens it (:meth:`attach`), such as a dask worker.

    Parameters
    ----------
    slots : int
        Number of rows the store holds.
    n : int
        Samples per row.
    path : str, optional
        Make a named store: a new file at ``path`` (remove it with
        :meth:`unlink` once every process has it open).
    """

    def __init__(self, slots: int, n: int, path: str | None = None):
        self.slots = int(slots)
        self.path = path
        size = max(1, self.slots * n * 8)
        if path is None:
            self._map = _map(-1, size)
        else:
            fd = os.open(path, os.O_RDWR | os.O_CREAT | os.O_EXCL, 0o600)
            try:
                os.ftruncate(fd, size)
                self._map = _map(fd, size)
            finally:
                os.close(fd)
        self.rows = np.frombuffer(self._map, dtype=np.float64,
                                  count=self.slots * n).reshape(self.slots, n)
        self._lru: OrderedDict[bytes, int] = OrderedDict()
        self._free = list(range(self.slots - 1, -1, -1))

    @staticmethod
    def named(slots: int, n: int) -> SlotStore | None:
        """A new named store in ``/dev/shm`` (None where there is none, or no room)."""
        if not SHM.is_dir():  # pragma: no cover (not Linux)
            return None
        try:
            if shutil.disk_usage(SHM).free < 2 * slots * n * 8:
                return None
            return SlotStore(slots, n, str(SHM / f"edm_sym-{os.getpid()}-{secrets.token_hex(8)}"))
        except OSError:  # pragma: no cover (a full or read-only /dev/shm)
            return None

    @staticmethod
    def attach(path: str, slots: int, n: int) -> np.ndarray:
        """The rows of the named store at ``path`` (this process maps it).

        Raises
        ------
        OSError
            When there is no such store here (another machine) or its size differs.
        """
        size = max(1, slots * n * 8)
        fd = os.open(path, os.O_RDWR)
        try:
            if os.fstat(fd).st_size != size:
                raise OSError(f"{path}: {os.fstat(fd).st_size} bytes, expected {size}")
            shared = _map(fd, size)
        finally:
            os.close(fd)
        return np.frombuffer(shared, dtype=np.float64, count=slots * n).reshape(slots, n)

    def unlink(self) -> None:
        """Remove a named store's file (the processes that mapped it keep the memory)."""
        if self.path is not None:
            with contextlib.suppress(FileNotFoundError):
                os.unlink(self.path)

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

    def peek(self, keys: Sequence[bytes]) -> list[int]:
        """The slot of each key's row, -1 where there is none; nothing is refreshed.

        With :meth:`touch` of the keys found, in the same order, it is
        :meth:`lookup` of each key, at C speed (the planning of every batch
        looks up thousands of keys).
        """
        return list(map(self._lru.get, keys, repeat(-1)))

    def touch(self, keys: Sequence[bytes]) -> None:
        """Refresh stored keys, in this order (each becomes the most recent)."""
        refresh = self._lru.move_to_end
        for key in keys:
            refresh(key)

    def lookup_many(self, keys: Sequence[bytes]) -> list[int]:
        """:meth:`lookup` of each key in turn (-1 where there is none)."""
        slots = self.peek(keys)
        self.touch([key for key, slot in zip(keys, slots, strict=True) if slot >= 0])
        return slots

    def allocate(self, count: int, keep: Collection[bytes]) -> list[int]:
        """``count`` free slots, evicting least recently used rows not in ``keep``.

        Raises
        ------
        RuntimeError
            When the store is too small for a batch.
        """
        take = min(count, len(self._free))
        out = self._free[len(self._free) - take:][::-1]  # free slots first, last freed first
        del self._free[len(self._free) - take:]
        if take < count:
            # Then the least recently used rows outside ``keep``, oldest first.
            victims = list(islice(filterfalse(keep.__contains__, self._lru), count - take))
            if len(victims) < count - take:
                self._free.extend(out[::-1])  # nothing taken after all
                raise RuntimeError(f"row store of {self.slots} slots is too small for a "
                                   f"batch of {count} new rows")
            out.extend(map(self._lru.pop, victims))
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


def _map(fd: int, size: int) -> mmap.mmap:
    """A shared map of ``size`` bytes of file ``fd`` (-1: anonymous), its pages made now.

    MAP_POPULATE (where there is one): a page fault per 4 kB on first use
    would cost more than simulating the row that fills it.
    """
    populate = getattr(mmap, "MAP_POPULATE", 0)
    if not populate:  # pragma: no cover (not Linux)
        return mmap.mmap(fd, size)
    flags = mmap.MAP_SHARED | populate
    if fd == -1:
        flags |= getattr(mmap, "MAP_ANONYMOUS", 0x20)
    return mmap.mmap(fd, size, flags=flags)
