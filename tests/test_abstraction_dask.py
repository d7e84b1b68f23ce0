"""One run spread over a dask.distributed cluster (the optional extra ``edm_sym[dask]``)."""

from __future__ import annotations

import pytest
from helpers import SMALL, friction_log, run

from edm_sym.core.result import dumps
from edm_sym.engines.abstraction.parallel import Parallel

distributed = pytest.importorskip("distributed")


def _workers_with_the_run(client) -> int:  # noqa: ANN001
    counts = client.run(lambda: len(__import__(
        "edm_sym.engines.abstraction.worker", fromlist=["_WORKERS"])._WORKERS))
    return sum(1 for v in counts.values() if v)


def _workers_sharing_the_stores(client) -> int:  # noqa: ANN001
    # A LocalCluster's workers run on this machine: they map the run's stores in /dev/shm.
    shared = client.run(lambda: any(w.rows is not None and w.prefix_rows is not None
                                    for w in __import__("edm_sym.engines.abstraction.worker",
                                                        fromlist=["_WORKERS"])._WORKERS.values()))
    return sum(1 for v in shared.values() if v)


def test_a_dask_cluster_gives_the_same_result_as_one_process() -> None:
    log, _ = friction_log(2.0)
    want = dumps(run(log, SMALL, seed=8, parallel=Parallel(workers=1)))
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        # One lane per cluster worker (scheduler=): the run's data went to both, and
        # is dropped there when the run ends.
        seen: list = []

        def look(info) -> None:  # noqa: ANN001
            if info.generation == 1 and not seen:
                seen.append(_workers_with_the_run(client))
                seen.append(_workers_sharing_the_stores(client))

        res = run(log, SMALL, seed=8, parallel=Parallel(scheduler=client), callback=look)
        assert dumps(res) == want
        assert seen == [2, 2] and _workers_with_the_run(client) == 0
        # Any executor (unpinned lanes): the same bytes again.
        res = run(log, SMALL, seed=8, parallel=Parallel(executor=client.get_executor(), workers=2))
        assert dumps(res) == want
        # The scheduler's address, as `edm abstract --scheduler ADDRESS` gives it.
        res = run(log, SMALL, seed=8, parallel=Parallel(scheduler=cluster.scheduler_address))
        assert dumps(res) == want
