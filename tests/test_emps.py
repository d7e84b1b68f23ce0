"""Real data: EDM on the EMPS axis generalises at least as well as the reference model."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest
from conftest import emps_path

REPO = Path(__file__).resolve().parents[1]
BENCH = REPO / "benchmarks" / "bench_emps.py"


def _bench():
    spec = importlib.util.spec_from_file_location("edm_bench_emps", BENCH)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.slow
def test_emps_held_out_error_no_worse_than_reference() -> None:
    path = emps_path()
    bench = _bench()
    r = bench.run(time_limit=None, seed=1, path=path)
    print(f"EMPS held out: EDM {r['edm_held_out']:.4f} %, reference {r['reference_held_out']:.4f} % "
          f"(published {bench.PUBLISHED} %)")
    assert r["edm_held_out"] <= r["reference_held_out"]
    assert r["edm_train"] < 5.0
