"""Where a run's work goes: :class:`Parallel`, the parallel-execution settings of :func:`abstract`.

Processes on this machine (``workers``), any ``concurrent.futures.Executor``
(``executor``) or a dask cluster (``scheduler``); none of them changes a
result (docs/abstraction.md#speed-design, "The knobs").
:meth:`Parallel.connected` opens the dask client a scheduler's address
names, for the length of a run.
"""

from __future__ import annotations

from collections.abc import Iterator
from concurrent.futures import Executor
from contextlib import contextmanager
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from edm_sym.core.errors import ConfigError


@dataclass(frozen=True)
class Parallel:
    """The parallel-execution settings of a run; validated on construction.

    Parameters
    ----------
    workers : int, optional
        Processes evaluating, this one included (default: every usable core;
        1: this process only). Independent searches share them: side by side,
        one process each.
    executor : concurrent.futures.Executor, optional
        Where chunks of individuals are evaluated (``workers`` unpinned lanes;
        for a dask cluster ``scheduler`` is better); it is not shut down.
        None: this process and ``workers - 1`` forked processes.
    scheduler : str or distributed.Client, optional
        A dask.distributed scheduler's address (``tcp://host:8786``) or a
        connected client: chunks of individuals go to its workers, one lane
        each (``workers`` and ``executor`` are then ignored). Needs the extra
        ``edm_sym[dask]``.

    Raises
    ------
    ConfigError
        Naming ``workers`` (not an integer >= 1) or ``executor`` (not an Executor).

    Examples
    --------
    >>> abstract(data, target="tau_ext", inputs=["omega"], parallel=Parallel(workers=2))  # doctest: +SKIP
    """

    workers: int | None = None
    executor: Executor | None = None
    scheduler: Any = None

    def __post_init__(self) -> None:
        w = self.workers
        if w is not None and (isinstance(w, bool) or not isinstance(w, int | np.integer) or w < 1):
            raise ConfigError("workers", f"expected an integer >= 1, found {w!r}")
        if self.executor is not None and not isinstance(self.executor, Executor):
            raise ConfigError("executor", f"expected a concurrent.futures.Executor, found "
                                          f"{type(self.executor).__name__}")

    @contextmanager
    def connected(self) -> Iterator[Parallel]:
        """These settings with ``scheduler`` a connected dask client (None without one).

        A client opened here from an address is closed when the block ends; a
        client given is left open.

        Raises
        ------
        ConfigError
            When dask.distributed is not installed, or no scheduler answers at
            the address, or it has no worker within a minute.
        """
        client, own = _dask_client(self.scheduler)
        try:
            yield replace(self, scheduler=client)
        finally:
            if own:
                client.close()


def _dask_client(scheduler: Any) -> tuple[Any, bool]:
    """A dask client for ``scheduler`` (an address or a client) and whether it is ours to close."""
    if scheduler is None:
        return None, False
    try:
        import distributed
    except ImportError:
        raise ConfigError("scheduler", "expected dask.distributed (pip install 'edm_sym[dask]'), "
                                       "found it not installed") from None
    if not isinstance(scheduler, str):
        return scheduler, False
    try:
        client = distributed.Client(scheduler, timeout=10)
    except (OSError, TimeoutError, ValueError) as exc:
        raise ConfigError("scheduler", f"expected a dask scheduler at {scheduler}, found none "
                                       f"({type(exc).__name__}: {exc})") from None
    try:
        client.wait_for_workers(1, timeout=60)
    except (OSError, TimeoutError) as exc:
        client.close()
        raise ConfigError("scheduler", f"expected a worker on the dask scheduler at {scheduler}, "
                                       f"found none within 60 s ({type(exc).__name__})") from None
    return client, True
