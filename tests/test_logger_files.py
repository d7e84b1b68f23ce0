"""The files loggers write: MATLAB matrices and structs, HDF5 datasets, Parquet (docs/data.md)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from conftest import TS

from edm_sym.application.cli import main
from edm_sym.core.data import load_data
from edm_sym.core.errors import DataFormatError

N = 200
NAMES = ["t", "ref", "theta", "omega", "tau_cmd", "tau_meas", "current"]


def _matrix() -> np.ndarray:
    t = np.arange(N) * TS
    omega = np.sin(2 * np.pi * 3 * t)
    cols = [t, np.cos(t), np.cumsum(omega) * TS, omega, 0.1 * omega, 0.1 * omega + 0.01,
            2 * omega]
    return np.column_stack(cols)


@pytest.fixture
def coulomb_viscous_result(coulomb_viscous, tmp_path: Path) -> Path:
    from edm_sym.core.result import EdmResult, StepRecord, save_result

    res = EdmResult(coulomb_viscous, "tau_ext",
                    (StepRecord(1, coulomb_viscous.matrix, 0.5, (0.9, 0.7, 0.5), 3, 60,
                                {"kind": "constant", "value": 1.0}),),
                    {"seed": 3, "package_version": "0.1.0", "data_sha256": "0" * 64}, 0.5)
    return save_result(res, tmp_path / "result.json")


def _mat(path: Path, **doc) -> Path:
    from scipy import io as sio

    sio.savemat(path, doc)
    return path


def test_a_mat_matrix_is_read_with_its_columns_named(tmp_path: Path) -> None:
    m = _matrix()
    path = _mat(tmp_path / "run.mat", data=m, Iz=np.arange(5.0), Kp=3.0)
    log = load_data(f"{path}:data", names=",".join(NAMES))
    assert list(log.columns) == NAMES
    np.testing.assert_array_equal(log.columns["omega"], m[:, 3])
    assert log.ts == pytest.approx(TS)
    assert log.source == "run.mat:data"
    # The matrix stored the other way round (7 x N) reads the same.
    path = _mat(tmp_path / "wide.mat", data=m.T)
    np.testing.assert_array_equal(load_data(f"{path}:data", names=NAMES).columns["tau_cmd"], m[:, 4])


def test_a_file_whose_samples_sit_in_a_matrix_is_refused_with_what_it_holds(tmp_path: Path) -> None:
    # Four short 1-D arrays beside the 200 x 7 matrix: reading them as the log was the silent
    # failure; the message lists the file and how to select the matrix.
    path = _mat(tmp_path / "run.mat", data=_matrix(), Iz1=np.arange(5.0), Iz=np.arange(5.0), Kp=2.0)
    with pytest.raises(DataFormatError) as info:
        load_data(path, ts=TS)
    assert info.value.where == "run.mat"
    problem = info.value.problem
    assert problem.startswith("expected the log's samples in 1-D arrays, found them in a matrix; "
                              "the file holds ")
    assert "data (a 200x7 matrix)" in problem and "Iz (5 samples)" in problem
    assert "Kp (a scalar)" in problem
    assert 'select run.mat:data with names="NAME,NAME,..." (7 names)' in problem


def test_a_matrix_without_names_or_with_too_few_is_refused(tmp_path: Path) -> None:
    path = _mat(tmp_path / "run.mat", data=_matrix())
    with pytest.raises(DataFormatError) as info:
        load_data(f"{path}:data")
    assert info.value.where == "run.mat:data"
    assert info.value.problem == ("expected the names of the columns of a 200x7 matrix "
                                  '(names="NAME,NAME,..."), found none')
    with pytest.raises(DataFormatError) as info:
        load_data(f"{path}:data", names="t,ref,theta")
    assert info.value.problem == "expected 3 columns as `names` names, found a 200x7 matrix"
    with pytest.raises(DataFormatError) as info:
        load_data(f"{path}:nothing", names="t,ref,theta")
    assert info.value.where == "run.mat:nothing"
    assert info.value.problem == "expected 'nothing' in run.mat, found only: data (a 200x7 matrix)"


def test_a_struct_and_its_fields_are_selected(tmp_path: Path) -> None:
    m = _matrix()
    run = {"t": m[:, 0], "omega": m[:, 3], "tau": m[:, 4], "gain": 2.0}
    path = _mat(tmp_path / "s.mat", run=run)
    log = load_data(f"{path}:run")
    assert list(log.columns) == ["t", "omega", "tau"] and log.scalars == {"gain": 2.0}
    log = load_data(f"{path}:run.t,run.omega")
    assert list(log.columns) == ["t", "omega"]
    np.testing.assert_array_equal(log.columns["omega"], m[:, 3])
    with pytest.raises(DataFormatError) as info:
        load_data(f"{path}:run.speed")
    assert info.value.where == "s.mat:run.speed"
    assert "expected 'speed' in run, found only: t (200 samples), omega (200 samples)" \
        in info.value.problem
    # Read whole, a file of only a struct says how to select it.
    with pytest.raises(DataFormatError) as info:
        load_data(path)
    assert "select s.mat:run (its fields) or s.mat:run.FIELD" in info.value.problem


def test_hdf5_datasets_and_groups_are_selected(tmp_path: Path) -> None:
    h5py = pytest.importorskip("h5py")
    m = _matrix()
    path = tmp_path / "log.h5"
    with h5py.File(path, "w") as f:
        f["data"] = m
        g = f.create_group("run")
        g["t"], g["omega"] = m[:, 0], m[:, 3]
    log = load_data(f"{path}:data", names=NAMES)
    np.testing.assert_array_equal(log.columns["current"], m[:, 6])
    log = load_data(f"{path}:run")
    assert list(log.columns) == ["omega", "t"]  # HDF5 lists names sorted
    assert log.ts == pytest.approx(TS)
    log = load_data(f"{path}:/run/omega,/run/t")
    assert list(log.columns) == ["omega", "t"]


def test_a_mat73_struct_is_a_group_read_in_matlab_orientation(tmp_path: Path) -> None:
    h5py = pytest.importorskip("h5py")
    m = _matrix()
    path = tmp_path / "v73.mat"
    with h5py.File(path, "w", userblock_size=512) as f:
        f["data"] = m.T  # MATLAB stores column-major: N x 7 is written 7 x N
        f["data"].attrs["MATLAB_class"] = b"double"
        g = f.create_group("run")
        g.attrs["MATLAB_class"] = b"struct"
        g["omega"] = m[:, 3][None, :]
        g["omega"].attrs["MATLAB_class"] = b"double"
    log = load_data(f"{path}:data", names=NAMES)
    np.testing.assert_array_equal(log.columns["theta"], m[:, 2])
    log = load_data(f"{path}:run.omega", ts=TS)
    np.testing.assert_array_equal(log.columns["omega"], m[:, 3])


def test_parquet_columns_are_read(tmp_path: Path) -> None:
    pa = pytest.importorskip("pyarrow")
    import pyarrow.parquet as pq

    m = _matrix()
    path = tmp_path / "log.parquet"
    pq.write_table(pa.table({n: m[:, k] for k, n in enumerate(NAMES)}), path)
    log = load_data(path)
    assert list(log.columns) == NAMES and log.ts == pytest.approx(TS)
    assert list(load_data(f"{path}:t,omega").columns) == ["t", "omega"]


def test_parquet_without_pyarrow_names_the_extra(tmp_path: Path, monkeypatch) -> None:
    import sys

    path = tmp_path / "log.parquet"
    path.write_bytes(b"PAR1 not really")
    monkeypatch.setitem(sys.modules, "pyarrow", None)
    monkeypatch.setitem(sys.modules, "pyarrow.parquet", None)
    with pytest.raises(DataFormatError) as info:
        load_data(path)
    assert info.value.where == "log.parquet"
    assert "install the extra 'edm_sym[parquet]'" in info.value.problem


def test_columns_without_a_matrix_are_refused(tmp_path: Path) -> None:
    path = tmp_path / "log.csv"
    path.write_text("t,x\n0,1\n0.001,2\n")
    with pytest.raises(DataFormatError) as info:
        load_data(path, names="a,b")
    assert info.value.where == "names"
    mat = _mat(tmp_path / "run.mat", t=np.arange(10) * TS, x=np.arange(10.0))
    with pytest.raises(DataFormatError) as info:
        load_data(f"{mat}:t", names="a")
    assert info.value.where == "names"


def test_the_cli_simulates_a_selected_matrix_and_refuses_a_hidden_one(
        tmp_path: Path, capsys, coulomb_viscous_result) -> None:
    m = _matrix()
    path = _mat(tmp_path / "run.mat", data=m, Kp=1.0)
    out = tmp_path / "sim.csv"
    names = "t,ref,theta_w,omega,tau_ext,tau_meas,current"
    assert main(["simulate", str(coulomb_viscous_result), f"{path}:data", "--columns", names,
                 "-o", str(out)]) == 0
    assert out.exists()
    assert main(["simulate", str(coulomb_viscous_result), str(path), "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "select run.mat:data with --columns" in err[0]
