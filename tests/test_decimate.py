"""Decimation with an anti-alias filter, recorded in the provenance (docs/data.md#decimation)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from edm_sym.application.cli import main
from edm_sym.core.data import DECIMATE_FILTER, DataLog, decimate, decimation_factor, write_csv
from edm_sym.core.errors import DataFormatError

TS = 1e-4


def _log(n: int = 4000) -> DataLog:
    t = np.arange(n) * TS
    slow = np.sin(2 * np.pi * 5 * t)
    fast = 0.5 * np.sin(2 * np.pi * 3900 * t)  # above the new Nyquist frequency (500 Hz at K=10)
    theta = np.mod(2 * np.pi * 3 * t, 2 * np.pi)
    return DataLog({"t": t, "omega": slow + fast, "theta_w": theta}, TS, "fast.csv", "0" * 64,
                   roles={"theta_w": "position_wrapped"})


def test_decimation_filters_keeps_the_time_stamps_and_is_recorded() -> None:
    log = _log()
    out = decimate(log, 10)
    assert len(out) == 400 and out.ts == pytest.approx(10 * TS)
    np.testing.assert_array_equal(out.columns["t"], log.columns["t"][::10])
    slow = np.sin(2 * np.pi * 5 * out.columns["t"])
    # The 3.9 kHz tone would alias onto 100 Hz at the kept samples; the filter takes it out.
    assert np.max(np.abs(out.columns["omega"] - slow)[20:-20]) < 0.02
    assert np.max(np.abs(log.columns["omega"][::10] - slow)) > 0.2
    # The wrapped angle keeps its range and its jumps stay jumps.
    theta = out.columns["theta_w"]
    assert theta.min() >= 0 and theta.max() < 2 * np.pi
    want = np.mod(2 * np.pi * 3 * out.columns["t"], 2 * np.pi)
    err = np.abs(np.angle(np.exp(1j * (theta - want))))
    assert np.max(err[20:-20]) < 1e-3
    rec = out.record("abstraction")
    assert rec["decimate"] == {"factor": 10, "filter": DECIMATE_FILTER}
    assert "decimate" not in log.record("abstraction")
    assert decimate(log, 1) is log


@pytest.mark.parametrize("factor", [0, -2, 2.5, True])
def test_a_bad_factor_is_refused(factor) -> None:
    with pytest.raises(DataFormatError) as info:
        decimate(_log(), factor)
    assert info.value.where == "factor"


def test_a_log_too_short_to_filter_is_refused_naming_the_file() -> None:
    with pytest.raises(DataFormatError) as info:
        decimate(_log(20), 11)
    assert info.value.where == "fast.csv: factor"


def test_edm_abstract_decimates_and_records_it(tmp_path: Path) -> None:
    n = 6000
    t = np.arange(n) * TS
    omega = np.sin(2 * np.pi * 3 * t)
    tau = 0.3 * np.tanh(30 * omega) + 0.05 * omega + 0.01 * np.sin(2 * np.pi * 3000 * t)
    data = write_csv(tmp_path / "fast.csv", {"t": t, "omega": omega, "tau": tau})
    cfg = tmp_path / "cfg.toml"
    cfg.write_text("[ga]\npopulation = 12\ngenerations = 2\n\n[[step]]\nn_rows = 2\n"
                   "n_elements = 2\n")
    out = tmp_path / "r.json"
    assert main(["abstract", str(data), "--target", "tau", "--inputs", "omega", "--config",
                 str(cfg), "--decimate", "10", "--quiet", "--workers", "1", "-o", str(out)]) == 0
    doc = json.loads(out.read_text())
    assert doc["sample_time"] == pytest.approx(10 * TS)
    (log,) = doc["logs"]
    assert log["rows"] == 600 and log["decimate"]["factor"] == 10
    assert log["file"] == "fast.csv (decimated 10)"


@pytest.mark.parametrize("target,factor", [(TS, 1), (10 * TS, 10), (1e-3 * (1 + 1e-5), 10)])
def test_a_target_sample_time_gives_its_whole_factor(target: float, factor: int) -> None:
    assert decimation_factor(_log(), target) == factor


@pytest.mark.parametrize("target", [2.5 * TS, 0.5 * TS, 10.05 * TS])
def test_a_target_that_is_no_whole_multiple_is_refused_naming_the_file(target: float) -> None:
    with pytest.raises(DataFormatError) as info:
        decimation_factor(_log(), target)
    assert info.value.where == "fast.csv: target"
    assert "expected a whole multiple of the log's sample time 0.0001 s" in info.value.problem


def _fast_log(tmp_path: Path, name: str, ts: float, n: int) -> Path:
    t = np.arange(n) * ts
    omega = np.sin(2 * np.pi * 3 * t)
    return write_csv(tmp_path / name, {"t": t, "omega": omega,
                                       "tau": 0.3 * np.tanh(30 * omega) + 0.05 * omega})


def test_edm_abstract_decimates_each_log_to_a_target_sample_time(tmp_path: Path) -> None:
    # A 10 kHz and a 5 kHz log meet at 1 ms: factors 10 and 5.
    a = _fast_log(tmp_path, "a.csv", TS, 6000)
    b = _fast_log(tmp_path, "b.csv", 2 * TS, 3000)
    cfg = tmp_path / "cfg.toml"
    cfg.write_text("[ga]\npopulation = 12\ngenerations = 2\n\n[[step]]\nn_rows = 2\n"
                   "n_elements = 2\n")
    out = tmp_path / "r.json"
    assert main(["abstract", str(a), str(b), "--target", "tau", "--inputs", "omega", "--config",
                 str(cfg), "--decimate-to", "0.001", "--quiet", "--workers", "1",
                 "-o", str(out)]) == 0
    doc = json.loads(out.read_text())
    assert doc["sample_time"] == pytest.approx(10 * TS)
    assert [log["decimate"]["factor"] for log in doc["logs"]] == [10, 5]


@pytest.mark.parametrize("extra,where", [
    (["--decimate-to", "0.00025"], "a.csv: --decimate-to: expected a whole multiple"),
    (["--decimate-to", "0.001", "--decimate", "10"], "--decimate-to: expected either"),
    # The library names its parameter (factor); the command its option.
    (["--decimate", "0"], "edm: --decimate: expected an integer >= 1, found 0"),
    (["--decimate", "500"], "edm: a.csv: --decimate: expected at least 1000 samples"),
])
def test_edm_abstract_refuses_a_target_it_cannot_reach(tmp_path: Path, capsys, extra: list[str],
                                                        where: str) -> None:
    a = _fast_log(tmp_path, "a.csv", TS, 600)
    out = tmp_path / "r.json"
    assert main(["abstract", str(a), "--target", "tau", "--inputs", "omega", "--quiet",
                 "-o", str(out), *extra]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and where in err, err
    assert not out.exists()
