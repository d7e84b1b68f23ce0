"""Sample time of measured logs: clock drift and jitter accepted, larger mismatches refused or resampled.

A model abstracted on one log of a drive must run on a second log of the same
drive, whose logger's clock differs slightly (docs/data.md, "Sample time").
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from conftest import TS, emps_path

from edm_sym.application.cli import main
from edm_sym.core.data import JITTER_RTOL, TIME_RTOL, DataLog, load_data, match_sample_time, write_csv
from edm_sym.core.errors import DataFormatError
from edm_sym.core.result import EdmResult, StepRecord, dumps


def _second_recording(t: np.ndarray, *, drift: float, jitter: float, start: float,
                      seed: int = 0) -> np.ndarray:
    """Time stamps of a second recording: another clock rate, jittered stamps, another start."""
    rng = np.random.default_rng(seed)
    step = float(np.median(np.diff(t)))
    return start + (t - t[0]) * (1 + drift) + rng.uniform(-jitter, jitter, len(t)) * step


@pytest.fixture(scope="module")
def emps_halves() -> tuple[DataLog, DataLog]:
    log = load_data(emps_path())
    n = len(log) // 2
    return log.window(0, n), log.window(n)


@pytest.mark.parametrize("drift", [-8e-4, 3e-4, 8e-4])
def test_a_second_emps_recording_runs_on_the_first_ones_sample_time(
    emps_halves: tuple[DataLog, DataLog], drift: float, tmp_path: Path
) -> None:
    first, second = emps_halves
    cols = dict(second.columns)
    cols["t"] = _second_recording(cols["t"], drift=drift, jitter=0.1, start=57.3)
    path = write_csv(tmp_path / "second.csv", cols)
    log = load_data(path)  # jitter of 10 % of a step on every stamp is read as it is
    assert log.ts == pytest.approx(first.ts * (1 + drift), rel=2e-4)
    assert match_sample_time(log, first.ts, model="r.json") is log


def test_a_mismatch_beyond_the_drift_tolerance_is_refused_naming_both_and_resample(
    emps_halves: tuple[DataLog, DataLog], tmp_path: Path
) -> None:
    first, second = emps_halves
    cols = dict(second.columns)
    cols["t"] = _second_recording(cols["t"], drift=5 * TIME_RTOL, jitter=0.0, start=0.0)
    log = load_data(write_csv(tmp_path / "second.csv", cols))
    with pytest.raises(DataFormatError) as info:
        match_sample_time(log, first.ts, model="r.json")
    msg = str(info.value)
    assert f"{first.ts:g}" in msg and f"{log.ts:g}" in msg and "`resample=True`" in msg
    assert "second.csv" in msg and "\n" not in msg


def test_jitter_beyond_a_quarter_step_is_a_gap_or_burst(tmp_path: Path) -> None:
    t = np.arange(50) * TS
    t[20:] += (JITTER_RTOL + 0.05) * TS  # one step a little too long
    p = write_csv(tmp_path / "late.csv", {"t": t, "omega": np.ones(50)})
    with pytest.raises(DataFormatError, match=r"late.csv: row 22, column 't'.*gap"):
        load_data(p)


def _result_file(compensator, path: Path) -> Path:  # noqa: ANN001
    res = EdmResult(compensator, "tau_ext",
                    (StepRecord(1, compensator.matrix, 0.5, (0.5,), 1, 10, {"kind": "constant",
                                                                             "value": 1.0}),),
                    {"seed": 0, "package_version": "0.1.0", "data_sha256": "0" * 64}, 0.5)
    path.write_text(dumps(res))
    return path


def _log(ts: float, duration: float = 4.0) -> dict[str, np.ndarray]:
    t = np.arange(int(round(duration / ts))) * ts
    omega = 5 * np.sin(2 * np.pi * 0.5 * t)
    return {"t": t, "theta_w": np.mod(np.cumsum(omega) * ts, 2 * np.pi), "omega": omega,
            "tau_ext": 0.93 * np.tanh(omega / 0.05) + 0.007 * omega}


def test_simulate_reports_both_sample_times_under_drift(coulomb_viscous, tmp_path: Path, capsys) -> None:
    res = _result_file(coulomb_viscous, tmp_path / "r.json")
    cols = _log(TS)
    cols["t"] = _second_recording(cols["t"], drift=4e-4, jitter=0.05, start=3.0)
    data = write_csv(tmp_path / "second.csv", cols)
    assert main(["simulate", str(res), str(data), "-o", str(tmp_path / "out.csv")]) == 0
    err = capsys.readouterr().err
    assert "second.csv" in err and "r.json" in err and "accepted" in err


def test_resample_puts_a_faster_log_on_the_models_grid(coulomb_viscous, tmp_path: Path, capsys) -> None:
    res = _result_file(coulomb_viscous, tmp_path / "r.json")
    fast = write_csv(tmp_path / "fast.csv", _log(TS / 2))
    assert main(["simulate", str(res), str(fast), "-o", str(tmp_path / "no.csv")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "--resample" in err and "fast.csv" in err
    assert not (tmp_path / "no.csv").exists()

    out_fast, out_ref = tmp_path / "fast_sim.csv", tmp_path / "ref_sim.csv"
    assert main(["simulate", str(res), str(fast), "--resample", "-o", str(out_fast)]) == 0
    ref = write_csv(tmp_path / "ref.csv", _log(TS))
    assert main(["simulate", str(res), str(ref), "-o", str(out_ref)]) == 0
    a = np.genfromtxt(out_fast, delimiter=",", names=True)
    b = np.genfromtxt(out_ref, delimiter=",", names=True)
    assert len(a) == len(b)
    np.testing.assert_allclose(a["t"], b["t"], atol=1e-12)
    # The resampled log gives the compensation of the log recorded at the model's rate,
    # away from the edges of the anti-aliasing filter and the sign's switching instants.
    inner = slice(100, -100)
    close = np.abs(a["tau_cmp"][inner] - b["tau_cmp"][inner]) < 1e-3
    assert close.mean() > 0.97


def test_a_log_without_time_takes_the_models_sample_time_and_gets_a_time_column(
    coulomb_viscous, tmp_path: Path
) -> None:
    res = _result_file(coulomb_viscous, tmp_path / "r.json")
    cols = _log(TS)
    del cols["t"]
    data = write_csv(tmp_path / "no_t.csv", cols)
    out = tmp_path / "sim.csv"
    assert main(["simulate", str(res), str(data), "-o", str(out)]) == 0
    header = out.read_text().splitlines()[0].split(",")
    assert header[0] == "t"
    t = np.genfromtxt(out, delimiter=",", names=True)["t"]
    np.testing.assert_allclose(np.diff(t), TS, rtol=1e-9)
    assert json.loads(res.read_text())["sample_time"] == pytest.approx(TS)


def test_a_log_without_time_and_without_a_model_still_needs_ts(tmp_path: Path) -> None:
    p = tmp_path / "no_t.csv"
    p.write_text("omega\n1\n2\n")
    with pytest.raises(DataFormatError, match=r"no_t.csv: column 't'.*`ts=SECONDS`"):
        load_data(p)


# -- MATLAB v7.3 (HDF5) -----------------------------------------------------------

def _write_mat73(path: Path, arrays: dict[str, np.ndarray]) -> Path:
    """A MATLAB v7.3-style file: a 512-byte MATLAB header, then HDF5 with column-major arrays."""
    h5py = pytest.importorskip("h5py")
    with h5py.File(path, "w", userblock_size=512) as f:
        for key, value in arrays.items():
            arr = np.atleast_2d(np.asarray(value, dtype=float))
            if arr.shape[0] == 1 and np.ndim(value) == 1:
                arr = arr.T  # a MATLAB column vector, N x 1
            ds = f.create_dataset(key, data=arr.T)  # stored transposed, as MATLAB does
            ds.attrs["MATLAB_class"] = np.bytes_("double")
        text = f.create_dataset("name", data=np.frombuffer(b"emps", dtype=np.uint8)[None, :].astype("<u2"))
        text.attrs["MATLAB_class"] = np.bytes_("char")
    header = b"MATLAB 7.3 MAT-file, Platform: GLNXA64, HDF5 schema 1.00 ."
    with open(path, "r+b") as fh:
        fh.write(header.ljust(116, b" ") + b"\0" * 8 + b"\x00\x02IM")
    return path


def test_a_matlab_v73_log_is_read_like_an_older_mat(tmp_path: Path) -> None:
    t = np.arange(200) * TS
    qm = np.sin(2 * np.pi * t)
    path = _write_mat73(tmp_path / "log73.mat", {"t": t, "qm": qm, "gtau": 35.15065})
    log = load_data(path)
    assert set(log.columns) == {"t", "qm"}  # the char array "name" is skipped
    np.testing.assert_array_equal(log.columns["qm"], qm)
    assert log.ts == pytest.approx(TS) and log.scalars == {"gtau": pytest.approx(35.15065)}


def test_a_v73_log_without_h5py_names_the_extra(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    import builtins

    path = _write_mat73(tmp_path / "log73.mat", {"t": np.arange(10) * TS})
    real_import = builtins.__import__

    def no_h5py(name, *args, **kwargs):  # noqa: ANN001, ANN002, ANN003, ANN202
        if name == "h5py":
            raise ImportError("no h5py")
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", no_h5py)
    with pytest.raises(DataFormatError, match=r"log73.mat.*v7.3.*edm_sym\[mat73\]"):
        load_data(path)


@pytest.mark.parametrize("log_ts", [1000.0, 1e-9])
def test_resample_refuses_a_ratio_beyond_small_integers(log_ts: float) -> None:
    # 1000 s onto 1 ms made a log of 1e6 times the samples (the process was killed for
    # memory); 1e-9 s rounded the ratio to 0 (ZeroDivisionError, exit 1).
    from edm_sym.core.data import DataLog, match_sample_time

    data = DataLog({"omega": np.sin(np.arange(500) / 9.0)}, log_ts, "slow.csv")
    with pytest.raises(DataFormatError, match="expected a ratio of small integers"):
        match_sample_time(data, TS, model="r.json", resample=True)
