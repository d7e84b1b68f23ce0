"""result.json and data files: round trips, and bad files refused cleanly.

Every bad file gives exit 2, one line on stderr naming the file and the field
(or row/column), no traceback, and no output file.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from conftest import TS

from edm_sym.application.cli import main
from edm_sym.core.data import load_data, write_csv
from edm_sym.core.errors import DataFormatError, ResultFormatError
from edm_sym.core.result import EdmResult, StepRecord, dumps, load_result, save_result


@pytest.fixture
def result_doc(coulomb_viscous, tmp_path: Path) -> dict:
    res = EdmResult(coulomb_viscous, "tau_ext",
                    (StepRecord(1, coulomb_viscous.matrix, 0.5, (0.9, 0.7, 0.5), 3, 60,
                                {"kind": "constant", "value": 1.0}),),
                    {"seed": 3, "package_version": "0.1.0", "data_sha256": "0" * 64}, 0.5)
    return json.loads(dumps(res))


@pytest.fixture
def data_csv(tmp_path: Path) -> Path:
    n = 400
    t = np.arange(n) * TS
    omega = 5 * np.sin(2 * np.pi * t)
    cols = {"t": t, "theta_w": np.mod(np.cumsum(omega) * TS, 2 * np.pi), "omega": omega,
            "tau_ext": 0.93 * np.sign(omega) + 0.007 * omega}
    return write_csv(tmp_path / "log.csv", cols)


def test_round_trip_is_byte_identical(result_doc: dict, tmp_path: Path) -> None:
    p = tmp_path / "r.json"
    p.write_text(json.dumps(result_doc, sort_keys=True, indent=2) + "\n")
    res = load_result(p)
    q = save_result(res, tmp_path / "again.json")
    assert q.read_bytes() == p.read_bytes()
    assert res.sha256 and len(res.sha256) == 64
    assert res.steps[0].history == (0.9, 0.7, 0.5)
    text = p.read_text()
    assert list(json.loads(text)) == sorted(json.loads(text))


def test_simulate_cli_writes_contract_columns(result_doc, data_csv, tmp_path, capsys) -> None:
    p = tmp_path / "r.json"
    p.write_text(json.dumps(result_doc))
    out = tmp_path / "sim.csv"
    assert main(["simulate", str(p), str(data_csv), "-o", str(out)]) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    assert lines[-1].startswith("rmse ")
    sim = load_data(out)
    assert list(sim.columns) == ["t", "row_1", "row_2", "tau_cmp", "residual"]
    np.testing.assert_allclose(sim.columns["row_1"] + sim.columns["row_2"], sim.columns["tau_cmp"])
    rmse = float(lines[-1].split()[1])
    assert rmse == pytest.approx(np.sqrt(np.mean(sim.columns["residual"] ** 2)), rel=1e-9)
    assert rmse < 1e-6  # the log was made by this very model (up to the p rounding)


def test_simulate_says_where_a_row_reads_beyond_its_training_range(result_doc, data_csv, tmp_path,
                                                                   capsys) -> None:
    """A model that met omega within +-2 rad/s, run on a log that reaches +-5: the rows that
    read omega extrapolate there, and ``edm simulate`` says so on stderr, naming the input,
    both ranges, the share of samples and the rows; the output is written all the same.
    Within the recorded range, the range over every abstraction log of a multi-log result,
    or with none recorded, nothing is said (docs/cli.md#edm-simulate)."""
    omega = np.asarray(load_data(data_csv).columns["omega"])
    share = np.mean(np.abs(omega) > 2.0 + 0.04)

    def log(name: str, top: float) -> dict:
        return {"use": "abstraction", "file": name, "sha256": None, "rows": 400,
                "sample_time": TS,
                "columns": [{"name": "t", "role": "time", "min": 0.0, "max": 0.399},
                            {"name": "omega", "role": None, "min": -top, "max": top},
                            {"name": "tau_ext", "role": "target", "min": -1.0, "max": 1.0}]}

    cases = {"narrow": ([log("train.csv", 2.0)], True), "wide": ([log("train.csv", 5.0)], False),
             "two": ([log("train.csv", 2.0), log("fast.csv", 5.0)], False), "none": (None, False)}
    for case, (logs, expect) in cases.items():
        doc = json.loads(json.dumps(result_doc))
        if logs is not None:
            doc["logs"] = logs
        p = tmp_path / "r.json"
        p.write_text(json.dumps(doc))
        out = tmp_path / f"sim_{case}.csv"
        assert main(["simulate", str(p), str(data_csv), "-o", str(out)]) == 0
        err = capsys.readouterr().err
        assert out.exists()
        if expect:
            assert err.strip() == (
                f"omega reaches {omega.min():.6g} .. {omega.max():.6g} in {data_csv.name}, "
                f"beyond its range -2 .. 2 in train.csv, on {100 * share:.3g} % of the samples: "
                "rows 1, 2 read it and extrapolate there")
        else:
            assert "beyond" not in err


def test_describe_notes_where_a_row_reads_beyond_its_training_range(result_doc, data_csv,
                                                                    tmp_path, capsys) -> None:
    """``edm describe --data`` on a log whose omega leaves the range the abstraction log had:
    a note under the fitness says where the rows extrapolate (the line of ``edm simulate``);
    within the range no such note (docs/cli.md#edm-describe)."""
    omega = np.asarray(load_data(data_csv).columns["omega"])
    share = np.mean(np.abs(omega) > 2.0 + 0.04)
    for top, expect in ((2.0, True), (5.0, False)):
        doc = json.loads(json.dumps(result_doc))
        doc["logs"] = [{"use": "abstraction", "file": "train.csv", "sha256": None, "rows": 400,
                        "sample_time": TS,
                        "columns": [{"name": "t", "role": "time", "min": 0.0, "max": 0.399},
                                    {"name": "omega", "role": None, "min": -top, "max": top},
                                    {"name": "tau_ext", "role": "target", "min": -1.0,
                                     "max": 1.0}]}]
        p = tmp_path / "r.json"
        p.write_text(json.dumps(doc))
        assert main(["describe", str(p), "--data", str(data_csv)]) == 0
        out = capsys.readouterr().out.splitlines()
        line = (f"note: omega reaches {omega.min():.6g} .. {omega.max():.6g} in {data_csv.name}, "
                f"beyond its range -2 .. 2 in train.csv, on {100 * share:.3g} % of the samples: "
                "rows 1, 2 read it and extrapolate there")
        if expect:
            assert line in out and out.index(line) < out.index("row 1: omega (velocity)")
        else:
            assert not [x for x in out if "beyond its range" in x]


def test_simulate_says_nothing_of_a_row_that_repeats_over_a_revolution(tmp_path, capsys) -> None:
    """On a rotary axis, a row on the unwrapped angle that repeats over one revolution
    (``sin(3 theta)``) meets nothing new beyond the angle's training range, and nothing is
    said; a dead zone on the angle that opens past 5 rad does meet something new, and its row
    is named (docs/cli.md#edm-simulate)."""
    from edm_sym.core.elements import default_ranges
    from edm_sym.core.matrix import Compensator, make_matrix

    ranges = default_ranges(TS, 20.0)
    n = 2000
    t = np.arange(n) * TS
    theta = 3.0 * t ** 2  # one way, to 12 rad
    log = write_csv(tmp_path / "far.csv", {"t": t, "theta_uw": theta, "tau_ext": 0 * t})
    rows = {"wave": [("gain", ranges["gain"].encode(3.0)), ("sin_phase", 0.0),
                     ("gain", ranges["gain"].encode(0.05))],
            "dead zone": [("dead_zone", ranges["dead_zone"].encode(5.0)),
                          ("gain", ranges["gain"].encode(0.05)), ("through", 0.0)]}
    for kind, genes in rows.items():
        comp = Compensator(make_matrix(["theta_uw"], [("theta_uw", genes)]), TS, {}, 20.0)
        doc = json.loads(dumps(EdmResult(comp, "tau_ext", (), {"seed": 1, "package_version": "0.1.0",
                                                               "data_sha256": "0" * 64}, 0.5)))
        doc["logs"] = [{"use": "abstraction", "file": "near.csv", "sha256": None, "rows": n,
                        "sample_time": TS,
                        "columns": [{"name": "t", "role": "time", "min": 0.0, "max": 2.0},
                                    {"name": "theta_uw", "role": None, "min": 0.0, "max": 6.0},
                                    {"name": "tau_ext", "role": "target", "min": -1.0,
                                     "max": 1.0}]}]
        p = tmp_path / "r.json"
        p.write_text(json.dumps(doc))
        assert main(["simulate", str(p), str(log), "-o", str(tmp_path / "sim.csv")]) == 0
        err = capsys.readouterr().err
        if kind == "wave":
            assert "beyond" not in err
        else:
            assert (f"theta_uw reaches 0 .. {theta.max():.6g} in far.csv, beyond its range 0 .. 6 "
                    "in near.csv") in err
            assert err.strip().endswith("row 1 reads it and extrapolates there")


def _set(doc: dict, path: list, value) -> dict:
    node = doc
    for k in path[:-1]:
        node = node[k]
    if value is _DELETE:
        del node[path[-1]]
    else:
        node[path[-1]] = value
    return doc


_DELETE = object()

# (description, mutation, text expected in the message)
CORRUPTIONS = [
    ("wrong format", lambda d: _set(d, ["format"], "edm-other"), "format"),
    ("wrong version", lambda d: _set(d, ["version"], 2), "version"),
    ("unknown element code", lambda d: _set(d, ["matrix", "rows", 1, "elements", 0, "code"], 41),
     "matrix.rows[1].elements[0].code: 41 is not a known element code"),
    ("p above 1", lambda d: _set(d, ["matrix", "rows", 0, "elements", 1, "p"], 1.5),
     "matrix.rows[0].elements[1].p"),
    ("p negative", lambda d: _set(d, ["matrix", "rows", 0, "elements", 2, "p"], -0.1),
     "matrix.rows[0].elements[2].p"),
    ("missing sample time", lambda d: _set(d, ["sample_time"], _DELETE), "sample_time"),
    ("missing matrix", lambda d: _set(d, ["matrix"], _DELETE), "matrix"),
    ("missing provenance seed", lambda d: _set(d, ["provenance", "seed"], _DELETE),
     "provenance.seed"),
    ("row count disagrees", lambda d: _set(d, ["matrix", "n_rows"], 3), "matrix.n_rows"),
    ("ragged row", lambda d: _set(d, ["matrix", "rows", 1, "elements"],
                                  d["matrix"]["rows"][1]["elements"][:2]),
     "matrix.rows[1].elements"),
    ("input code out of range", lambda d: _set(d, ["matrix", "rows", 0, "input_code"], 5),
     "matrix.rows[0].input_code"),
    ("input name disagrees", lambda d: _set(d, ["matrix", "rows", 0, "input"], "theta_w"),
     "matrix.rows[0].input"),
    ("element name disagrees", lambda d: _set(d, ["matrix", "rows", 0, "elements", 0, "name"], "tanh"),
     "matrix.rows[0].elements[0].name"),
    ("negative sample time", lambda d: _set(d, ["sample_time"], -1e-3), "sample_time"),
    ("code not an integer", lambda d: _set(d, ["matrix", "rows", 0, "elements", 0, "code"], "19"),
     "matrix.rows[0].elements[0].code"),
    ("bad range", lambda d: _set(d, ["parameter_ranges", "gain"],
                                 {"low": 3.0, "high": 1.0, "scaling": "linear"}),
     "parameter_ranges.gain"),
    ("log range from zero", lambda d: _set(d, ["parameter_ranges", "power_gain"],
                                           {"low": 0.0, "high": 1.0, "scaling": "log"}),
     "parameter_ranges.power_gain"),
    ("missing range", lambda d: _set(d, ["parameter_ranges", "gain"], _DELETE),
     "parameter_ranges.gain"),
    ("bad data sha", lambda d: _set(d, ["provenance", "data_sha256"], "xyz"),
     "provenance.data_sha256"),
    ("inputs not names", lambda d: _set(d, ["inputs"], ["theta w", "omega"]), "inputs[0]"),
    ("history not numbers", lambda d: _set(d, ["steps", 0, "history"], [0.1, "a"]),
     "steps[0].history[1]"),
    ("top level a list", lambda d: [d], "top level"),
]


@pytest.mark.parametrize("desc,mutate,where", CORRUPTIONS, ids=[c[0] for c in CORRUPTIONS])
def test_corrupted_result_is_refused(desc, mutate, where, result_doc, data_csv, tmp_path,
                                     capsys) -> None:
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(mutate(result_doc)))
    out = tmp_path / "out.csv"
    assert main(["simulate", str(bad), str(data_csv), "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert "bad.json" in err and where in err, err
    assert "Traceback" not in err
    assert not out.exists()
    assert set(tmp_path.iterdir()) == {bad, data_csv}  # no temporary file left either


def test_a_result_with_a_byte_order_mark_is_read(tmp_path: Path, result_doc: dict) -> None:
    # As a CSV log with one is: Windows editors write it (it was refused as invalid JSON).
    p = tmp_path / "r.json"
    p.write_bytes(b"\xef\xbb\xbf" + json.dumps(result_doc).encode())
    assert load_result(p).fitness == result_doc["fitness"]


@pytest.mark.parametrize("text,where", [
    ("{not json", "expected JSON"),
    ("", "expected JSON"),
    ('{"format": "edm-result", "version": 1, "sample_time": NaN}', "expected JSON"),
    # An integer too large for a double is refused by its key, not read.
    ('{"format": "edm-result", "version": 1, "fitness": 1' + "0" * 400 + "}",
     r"r\.json: fitness: expected a finite number, found an integer of 401 digits \(it "
     r"overflows a double\)"),
])
def test_unparsable_result_is_refused(text, where, tmp_path) -> None:
    p = tmp_path / "r.json"
    p.write_text(text)
    with pytest.raises(ResultFormatError, match=where):
        load_result(p)


# -- data files -------------------------------------------------------------------
BAD_DATA = [
    ("empty.csv", "", "empty file"),
    ("header_only.csv", "t,omega\n", "found none"),
    ("nan.csv", "t,omega\n0,1\n0.001,nan\n0.002,1\n", "row 3, column 'omega'"),
    ("inf.csv", "t,omega\n0,1\n0.001,1\n0.002,-inf\n", "row 4, column 'omega'"),
    ("text.csv", "t,omega\n0,1\n0.001,abc\n", "row 3, column 'omega'"),
    ("nonuniform.csv", "t,omega\n0,1\n0.001,1\n0.0025,1\n0.0035,1\n", "row 4, column 't'"),
    ("ragged.csv", "t,omega\n0,1\n0.001\n", "row 3"),
    ("missing_column.csv", "t,theta_w\n0,1\n0.001,1\n", "column 'omega'"),
    ("repeated_time.csv", "t,omega\n0,1\n0.001,1\n0.001,1\n0.002,1\n", "row 4, column 't'"),
    ("decreasing_time.csv", "t,omega\n0,1\n0.001,1\n0.0005,1\n0.002,1\n", "row 4, column 't'"),
    ("gap.csv", "t,omega\n0,1\n0.001,1\n0.002,1\n0.005,1\n0.006,1\n", "row 5, column 't'"),
    # Python's float() reads 1_0 as 10; a CSV number has no digit separators.
    ("underscore.csv", "t,omega\n0,1\n0.001,1_0\n0.002,1\n", "row 3, column 'omega'"),
]


@pytest.mark.parametrize("name,text,where", BAD_DATA, ids=[b[0] for b in BAD_DATA])
def test_bad_data_is_refused(name, text, where, result_doc, tmp_path, capsys) -> None:
    res = tmp_path / "r.json"
    res.write_text(json.dumps(result_doc))
    data = tmp_path / name
    data.write_text(text)
    out = tmp_path / "out.csv"
    assert main(["simulate", str(res), str(data), "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and name in err and where in err, err
    assert not out.exists()


def test_npz_and_mat_are_read(tmp_path: Path) -> None:
    from scipy import io as sio

    t = np.arange(100) * TS
    np.savez(tmp_path / "log.npz", t=t, omega=np.sin(t))
    log = load_data(tmp_path / "log.npz")
    assert log.ts == pytest.approx(TS) and list(log.columns) == ["t", "omega"]
    sio.savemat(tmp_path / "log.mat", {"t": t[:, None], "qm": np.cos(t)[:, None], "gtau": 35.1})
    log = load_data(tmp_path / "log.mat")
    assert set(log.columns) == {"t", "qm"} and log.scalars["gtau"] == pytest.approx(35.1)
    np.savez(tmp_path / "bad.npz", t=t, omega=np.r_[np.sin(t[:-1]), np.nan])
    with pytest.raises(DataFormatError, match="row 100, column 'omega'"):
        load_data(tmp_path / "bad.npz")
    (tmp_path / "junk.mat").write_bytes(b"not a mat file at all")
    with pytest.raises(DataFormatError, match="junk.mat"):
        load_data(tmp_path / "junk.mat")


@pytest.mark.parametrize("scale, ts, where", [
    (1e-310, None, "column 't'"), (1e306, None, "column 't'"),
    (None, 1e-320, "ts"), (None, 1e308, "ts"),
])
def test_a_sample_time_beyond_what_the_models_hold_is_refused(tmp_path: Path, scale, ts,
                                                               where) -> None:
    # Found by a fuzz pass: such logs crashed `edm simulate --resample` (ZeroDivisionError,
    # exit 1) or gave library messages ("math domain error", "Maximum allowed size exceeded").
    t = np.arange(20) * 1e-3 * (scale or 1.0)
    cols = {"omega": np.linspace(-1, 1, 20)} | ({"t": t} if scale else {})
    write_csv(tmp_path / "log.csv", cols)
    with pytest.raises(DataFormatError, match="from 1e-09 s to 1000 s") as err:
        load_data(tmp_path / "log.csv", ts=ts)
    assert err.value.where == f"log.csv: {where}"
    if ts is not None:  # the range's ends are sample times
        assert [load_data(tmp_path / "log.csv", ts=ok).ts for ok in (1e-9, 1e3)] == [1e-9, 1e3]


def test_ts_option_for_logs_without_time(tmp_path: Path) -> None:
    p = tmp_path / "x.csv"
    p.write_text("omega\n1\n2\n3\n")
    assert load_data(p, ts=0.002).ts == 0.002


def test_no_traceback_from_a_real_process(tmp_path: Path) -> None:
    bad = tmp_path / "bad.json"
    bad.write_text('{"format": "edm-result", "version": 7}')
    proc = subprocess.run([sys.executable, "-m", "edm_sym", "simulate", str(bad), "x.csv"],
                          capture_output=True, text=True, cwd=tmp_path)
    assert proc.returncode == 2
    assert proc.stderr.strip() == 'edm: bad.json: version: expected 1, found 7'
    assert proc.stdout == ""


def test_usage_error_is_one_line_exit_2(capsys) -> None:
    assert main(["plant", "--excitation", "abstraction"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "--preset" in err


@pytest.mark.parametrize("args", [
    ["simulate", "tests/data/handwritten_result.json", "plant:auger/evaluation"],
    ["plant", "--preset", "auger", "--excitation", "abstraction"],
    ["export", "tests/data/handwritten_result.json", "--target", "c"],
], ids=["simulate", "plant", "export"])
def test_an_empty_output_name_is_refused_not_taken_for_the_default(
        args: list[str], tmp_path: Path, monkeypatch, capsys) -> None:  # noqa: ANN001
    # `-o ''` wrote the command's default file (<data>_sim.csv, auger_abstraction.csv,
    # generated/<name>/) in the current folder, replacing one of the user's there.
    repo = Path(__file__).resolve().parents[1]
    args = [str(repo / a) if a.startswith("tests/") else a for a in args]
    monkeypatch.chdir(tmp_path)
    assert main([*args, "-o", ""]) == 2
    assert capsys.readouterr().err.endswith(
        "-o: expected a file or folder name, found an empty one\n")
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("args, message", [
    (["abstract", "{log}", "--target", "tau_ext", "--inputs", "t,omega", "-o", "r.json"],
     "log.csv: column 't': expected a signal of the axis for an input, found the log's time "
     "column"),
    (["lugre", "{log}", "--target", "tau_ext", "--velocity", "t", "-o", "l.json"],
     "log.csv: column 't': expected a signal of the axis"),
    (["lugre", "{log}", "--target", "tau_ext", "--velocity", "tau_ext", "-o", "l.json"],
     "--velocity: expected a column other than the target 'tau_ext', found it"),
], ids=["abstract-time", "lugre-time", "lugre-target"])
def test_the_clock_or_the_target_is_no_input(args: list[str], message: str, tmp_path: Path,
                                              monkeypatch, capsys) -> None:  # noqa: ANN001
    # Accepted before (a fuzz pass): a model of the clock, or of the target itself.
    n = 200
    write_csv(tmp_path / "log.csv", {"t": np.arange(n) * TS, "omega": np.sin(np.arange(n) / 9),
                                     "tau_ext": np.cos(np.arange(n) / 7)})
    monkeypatch.chdir(tmp_path)
    assert main([a.format(log="log.csv") for a in args]) == 2
    assert message in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["log.csv"]


@pytest.mark.parametrize("seed,problem", [("-1", "expected an integer >= 0, found -1"),
                                          ("1_0", "expected an integer, found '1_0'"),
                                          ("x", "expected an integer, found 'x'")])
def test_a_plant_spec_with_a_bad_seed_is_refused_naming_the_spec(seed: str, problem: str) -> None:
    from edm_sym.engines.sources import load_data as load_any

    with pytest.raises(DataFormatError) as info:
        load_any(f"plant:auger/evaluation@{seed}")
    assert info.value.where == f"plant:auger/evaluation@{seed}: seed"
    assert problem in info.value.problem


@pytest.mark.parametrize("value,found", [
    (np.ones((50, 3)), "a 2-D array of shape (50, 3)"),
    (np.ones(50) + 1j, "a complex array of shape (50,)"),
    (np.array(["a"] * 50), "an array of text of shape (50,)"),
])
def test_an_npz_array_that_is_no_column_is_named_as_what_it_is(tmp_path: Path, value,
                                                                found: str) -> None:
    path = tmp_path / "log.npz"
    np.savez(path, t=np.arange(50) * TS, omega=value, tau_ext=np.ones(50))
    with pytest.raises(DataFormatError) as info:
        load_data(path, require=["omega", "tau_ext"])
    assert info.value.where == "log.npz: column 'omega'"
    assert info.value.problem == f"expected a 1-D array of real numbers, found {found}"
    assert set(load_data(path).columns) == {"t", "tau_ext"}  # not asked for: left aside


def test_an_npz_time_column_of_timedelta64_is_read_in_seconds(tmp_path: Path) -> None:
    # numpy counts a timedelta64 an integer: read as its count of milliseconds, the log
    # had a sample time of 1 s instead of 1 ms.
    ms = np.arange(500).astype("timedelta64[ms]")
    np.savez(tmp_path / "log.npz", t=ms, omega=np.sin(np.arange(500) * 1e-3))
    log = load_data(tmp_path / "log.npz")
    assert log.ts == pytest.approx(1e-3)
    np.testing.assert_allclose(log.columns["t"], np.arange(500) * 1e-3)
    ms[7] = np.timedelta64("NaT")
    np.savez(tmp_path / "nat.npz", t=ms, omega=np.sin(np.arange(500) * 1e-3))
    with pytest.raises(DataFormatError) as info:
        load_data(tmp_path / "nat.npz")
    assert info.value.where == "nat.npz: row 8, column 't'"


@pytest.mark.skipif(not Path("/proc/self").exists(), reason="needs Linux's /proc")
@pytest.mark.parametrize("out", ["/proc/edm_sim.csv", "/proc/edm_sub/sim.csv"])
def test_an_output_where_nothing_can_be_made_is_refused_before_the_work(out: str,
                                                                        capsys) -> None:
    # As root the permission bits allow /proc: the write failed only after the work.
    assert main(["plant", "--preset", "lugre", "--excitation", "abstraction", "-o", out]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"edm: -o {out}: cannot write in /proc"), err
    assert len(err.splitlines()) == 1


def test_checking_an_output_leaves_nothing_behind(tmp_path: Path) -> None:
    from edm_sym.core.fileio import check_outputs

    check_outputs([tmp_path / "r.json", tmp_path / "new" / "deeper" / "r.json"])
    assert list(tmp_path.iterdir()) == []
