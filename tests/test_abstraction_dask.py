"""One run spread over a dask.distributed cluster (the optional extra ``edm_sym[dask]``)."""

from __future__ import annotations

import pytest
from test_abstraction import SMALL, friction_log, run

from edm_sym.core.result import dumps

distributed = pytest.importorskip("distributed")


def test_a_dask_cluster_gives_the_same_result_as_one_process() -> None:
    log, _ = friction_log(2.0)
    want = dumps(run(log, SMALL, seed=8, workers=1))
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        res = run(log, SMALL, seed=8, executor=client.get_executor(), workers=2)
        assert dumps(res) == want
        # Each worker process received the run's context and simulated rows.
        counts = client.run(lambda: len(__import__(
            "edm_sym.engines.abstraction.rowsim", fromlist=["_WORKERS"])._WORKERS))
        assert sum(counts.values()) >= 1
