"""Real logs as they are: a named time column, column roles, the axis's units, provenance, bad logs.

docs/data.md ("Columns and roles", "Provenance", "Units", "Too few samples").
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import numpy as np
import pytest
from helpers import friction_log

import edm_sym
from edm_sym.application.cli import main
from edm_sym.core.data import LOG_ROLES, ColumnRoles, DataLog, load_data, write_csv
from edm_sym.core.elements import element
from edm_sym.core.errors import DataFormatError
from edm_sym.core.matrix import Compensator, make_matrix
from edm_sym.core.result import dumps, load_result, schema
from edm_sym.engines.symbolic import ClassifyOptions, decode

TS = 1e-3
QUICK = """
[ga]
population = 12
generations = 3
continue = "no"

[[step]]
n_rows = 2
n_elements = 2
"""


def _logger_export(path: Path, n: int = 1000) -> Path:
    """A drive logger's export: time in ``time_s`` from 12.5 s, odd names, an unused column."""
    log, _ = friction_log(n * TS)
    c = log.columns
    cols = {"time_s": 12.5 + c["t"], "dqm": c["omega"], "ddqm": c["alpha"],
            "temp": 20 + 0.001 * np.arange(n), "F": c["tau_ext"]}
    return write_csv(path, cols)


@pytest.fixture(scope="module")
def export_csv(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return _logger_export(tmp_path_factory.mktemp("logs") / "drive.csv")


@pytest.fixture(scope="module")
def linear_result(export_csv: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """``edm abstract`` told everything by options: no --target, no --inputs, no renaming."""
    folder = tmp_path_factory.mktemp("abs")
    cfg = folder / "cfg.toml"
    cfg.write_text(QUICK)
    out = folder / "r.json"
    rc = main(["abstract", str(export_csv), "--time-column", "time_s", "--role", "F=target",
               "--role", "dqm=velocity", "--role", "ddqm=acceleration", "--axis", "linear",
               "--config", str(cfg), "--seed", "2", "-o", str(out), "--workers", "1", "--quiet"])
    assert rc == 0
    return out


# -- roles ---------------------------------------------------------------------------------

def test_roles_from_options_and_a_table_merge_with_options_on_top() -> None:
    table = ColumnRoles.from_table("cfg.toml: columns", {"t": "time", "tau": "target",
                                                        "qm": "position"})
    given = ColumnRoles.parse(["F=target", "dqm=velocity"], time_column="time_s")
    both = given.over(table)
    assert both.time == "time_s" and both.target == "F"  # the options' replace the table's
    assert both.roles == {"qm": "position", "time_s": "time", "F": "target", "dqm": "velocity"}
    assert both.inputs == ("qm", "dqm")


@pytest.mark.parametrize(("items", "time", "said", "printed"), [
    (["x=velocity", "x=position"], None, "roles['x']: expected one role per column, found "
     "'velocity' and 'position'", "--role x: expected one role per column"),
    (["a=target", "b=target"], None, "roles['b']: expected one column with the role 'target', "
     "found it given twice ('a' and 'b')", "--role b: expected one column with the role"),
    (["s=time"], "t", "roles['s']: expected one column with the role 'time'",
     "--role s: expected one column with the role 'time'"),
    (["x=speed"], None, "roles['x']: expected a role of time, target, position",
     "--role x: expected a role of time, target, position"),
    (["x"], None, "roles: expected COL=ROLE", "--role: expected COL=ROLE"),
])
def test_a_role_given_twice_or_unknown_is_refused(items: list, time: str | None, said: str,
                                                  printed: str) -> None:
    with pytest.raises(DataFormatError) as err:  # a Python caller: the parameter
        ColumnRoles.parse(items, time_column=time)
    assert said in str(err.value) and "--" not in str(err.value)
    with pytest.raises(DataFormatError) as err:  # a command: its option
        ColumnRoles.parse(items, time_column=time, where="--role")
    assert printed in str(err.value)


def test_the_schema_knows_every_role() -> None:
    role = schema()["$defs"]["log"]["properties"]["columns"]["items"]["properties"]["role"]
    assert role["enum"] == [None, *LOG_ROLES]


# -- a named time column -------------------------------------------------------------------

def test_a_named_time_column_gives_the_sample_time_and_names_itself_in_errors(
        tmp_path: Path) -> None:
    path = tmp_path / "a.csv"
    path.write_text("time_s,x\n10.000,1\n10.002,2\n10.004,3\n10.004,4\n")
    with pytest.raises(DataFormatError, match=r"a.csv: row 5, column 'time_s': expected "
                                              r"increasing time stamps, found a repeated one"):
        load_data(path, columns=ColumnRoles.parse(time_column="time_s"))
    path.write_text("time_s,x\n10.000,1\n10.002,2\n10.004,3\n")
    log = load_data(path, columns=ColumnRoles.parse(time_column="time_s"))
    assert log.ts == pytest.approx(0.002) and log.time_column == "time_s"
    assert list(log.times) == pytest.approx([10.0, 10.002, 10.004])
    # Without the option, the log has no time column at all.
    with pytest.raises(DataFormatError, match=r"expected a time column 't' \(or one named by "
                                              r"`time_column`\) or the option `ts=SECONDS`"):
        load_data(path)


def test_a_role_naming_a_missing_column_is_refused(export_csv: Path) -> None:
    with pytest.raises(DataFormatError, match=r"drive.csv: column 'qm': expected a position "
                                              r"column named 'qm', found only: time_s, dqm"):
        load_data(export_csv, columns=ColumnRoles.parse(["qm=position"], time_column="time_s"))


# -- provenance ----------------------------------------------------------------------------

def test_the_result_records_the_axis_and_each_log_with_its_columns_and_roles(
        export_csv: Path, linear_result: Path) -> None:
    doc = json.loads(linear_result.read_text())
    assert doc["axis"] == "linear"
    assert doc["target"] == "F" and doc["inputs"] == ["dqm", "ddqm"]
    (log,) = doc["logs"]
    assert log["use"] == "abstraction" and log["file"] == "drive.csv"
    assert log["sha256"] == hashlib.sha256(export_csv.read_bytes()).hexdigest()
    assert log["rows"] == 1000 and log["sample_time"] == pytest.approx(TS, rel=1e-9)
    assert [{k: c[k] for k in ("name", "role")} for c in log["columns"]] == [
        {"name": "time_s", "role": "time"}, {"name": "dqm", "role": "velocity"},
        {"name": "ddqm", "role": "acceleration"}, {"name": "temp", "role": None},
        {"name": "F", "role": "target"}]
    # Each column's range, which the exports give as an input's expected range.
    raw = load_data(export_csv, columns=ColumnRoles.parse(time_column="time_s"))
    for col in log["columns"]:
        values = raw.columns[col["name"]]
        assert (col["min"], col["max"]) == (float(values.min()), float(values.max()))
        assert col["min"] < col["max"]
    # The scores are in the linear axis's force unit.
    assert doc["validation"]["training"]["rmse"][1] == "N"
    assert load_result(linear_result).roles == {"dqm": "velocity", "ddqm": "acceleration"}


def test_a_validation_log_is_recorded_too(export_csv: Path, tmp_path: Path) -> None:
    second = _logger_export(tmp_path / "second.csv", 600)
    cfg = tmp_path / "cfg.toml"
    cfg.write_text(QUICK)
    out = tmp_path / "r.json"
    assert main(["abstract", str(export_csv), "--time-column", "time_s", "--target", "F",
                 "--inputs", "dqm", "--validate", str(second), "--config", str(cfg),
                 "-o", str(out), "--workers", "1", "--quiet"]) == 0
    logs = json.loads(out.read_text())["logs"]
    assert [(g["use"], g["file"], g["rows"]) for g in logs] == [("abstraction", "drive.csv", 1000),
                                                               ("validation", "second.csv", 600)]
    assert json.loads(out.read_text())["axis"] == "rotary"


# -- a second log: the recorded time column, roles and sample time -------------------------

def test_simulate_takes_the_recorded_time_column_and_starts_its_csv_with_it(
        linear_result: Path, tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    second = _logger_export(tmp_path / "second.csv", 700)
    out = tmp_path / "sim.csv"
    assert main(["simulate", str(linear_result), str(second), "-o", str(out)]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[-1].startswith("rmse ") and lines[-1].endswith(" N")
    header = out.read_text().splitlines()[0].split(",")
    assert header[0] == "time_s" and header[-2:] == ["tau_cmp", "residual"]
    assert float(out.read_text().splitlines()[1].split(",")[0]) == pytest.approx(12.5)
    # An --axis other than the result's is refused.
    assert main(["simulate", str(linear_result), str(second), "-o", str(tmp_path / "b.csv"),
                 "--axis", "rotary"]) == 2
    assert "--axis: expected linear as in" in capsys.readouterr().err
    assert not (tmp_path / "b.csv").exists()


def test_describe_reads_the_recorded_roles_and_prints_linear_units(
        linear_result: Path, export_csv: Path, capsys: pytest.CaptureFixture) -> None:
    assert main(["describe", str(linear_result), "--data", str(export_csv)]) == 0
    table = capsys.readouterr().out
    assert "linear axis, target in N, position in m" in table.splitlines()[0]
    assert "N m" not in table and "rad/s " not in table.replace("rad/s)", "")
    assert "(velocity)" in table or "(acceleration)" in table  # the roles given, not the names'
    desc = edm_sym.describe(linear_result, export_csv).to_json()
    units = {u for r in desc["rows"] for t in r["terms"] for _, u in t["parameters"].values()}
    assert units and units <= {"N", "N s/m", "kg", "m/s", "m/s^2", "m", "1", "1/m", "rad",
                               "rad/s", "s"}
    assert desc["fitness"]["data"]["rmse"][1] == "N"


# -- units by axis -------------------------------------------------------------------------

def _enc(name: str, value: float) -> float:
    return element(name).param.default(TS, 20.0).encode(value)


@pytest.mark.parametrize(("axis", "viscous", "coulomb", "inertia"), [
    ("rotary", "N m s/rad", "N m", "kg m^2"), ("linear", "N s/m", "N", "kg")])
def test_the_classifier_prints_the_axis_units(axis: str, viscous: str, coulomb: str,
                                              inertia: str) -> None:
    rows = [("v", [("sign", 0.0), ("gain", _enc("gain", 4.0))]),
            ("v", [("power_gain", _enc("power_gain", 2.0)), ("through", 0.0)]),
            ("a", [("gain", _enc("gain", 0.5)), ("through", 0.0)])]
    comp = Compensator(make_matrix(("v", "a"), rows), TS, {}, 20.0)
    model = decode(comp, roles={"v": "velocity", "a": "acceleration"}, systems=False, axis=axis)
    assert model.axis == axis
    terms = {t.kind: t for r in model.rows for t in r.terms}
    assert terms["coulomb"].parameters["level"] == (pytest.approx(4.0), coulomb)
    assert terms["viscous"].parameters["coefficient"] == (pytest.approx(2.0), viscous)
    assert terms["acceleration"].parameters["inertia"] == (pytest.approx(0.5), inertia)
    assert f"{viscous}" in terms["viscous"].description


def test_a_spatial_term_on_a_linear_axis_is_in_cycles_per_metre() -> None:
    # 0.05 N sin(2 pi 1.5/m * x): one cycle every 2/3 m of travel (the gain reaches 10 at most).
    k = 2 * np.pi * 1.5
    rows = [("x", [("gain", _enc("gain", k)), ("sin_amp", _enc("sin_amp", 0.05))])]
    comp = Compensator(make_matrix(("x",), rows), TS, {}, 20.0)
    (term,) = decode(comp, roles={"x": "position"}, systems=False, axis="linear").rows[0].terms
    assert term.kind == "spatial"
    assert term.parameters["period"] == (pytest.approx(2 / 3), "m")
    assert term.parameters["cycles_per_metre"] == (pytest.approx(1.5), "1/m")
    assert term.parameters["amplitude"] == (pytest.approx(0.05), "N")
    assert "cycles_per_revolution" not in term.parameters


def test_linear_thresholds_are_the_axis_defaults() -> None:
    lin = ClassifyOptions.for_axis("linear")
    assert (lin.axis, lin.units.velocity, lin.velocity_range) == ("linear", "m/s", 0.5)
    assert ClassifyOptions.for_axis("rotary") == ClassifyOptions()
    with pytest.raises(ValueError, match="axis: expected one of rotary, linear"):
        ClassifyOptions.for_axis("angular")


# -- bad logs: one line naming file and column, exit 2, nothing written --------------------

@pytest.mark.parametrize(("make", "extra", "expect"), [
    ("constant", ["--target", "F", "--inputs", "dqm,temp0"],
     "drive.csv: column 'temp0': expected a varying signal for an input, found 20 on all "
     "1000 rows"),
    ("export", ["--role", "F=target", "--role", "dqm=velocity", "--role", "dqm=acceleration"],
     "--role dqm: expected one role per column, found 'velocity' and 'acceleration'"),
    ("export", ["--role", "F=target", "--role", "dqm=target"],
     "--role dqm: expected one column with the role 'target', found it given twice"),
    ("export", ["--target", "F", "--role", "dqm=target", "--inputs", "ddqm"],
     "--role dqm: expected the target column 'F', found 'dqm' given the role 'target'"),
    ("export", ["--role", "dqm=velocity"], "--target: expected the target column"),
    ("export", ["--target", "F"], "--inputs: expected the input columns"),
    ("short", ["--target", "F", "--inputs", "dqm"],
     "drive.csv: the 16 samples fitted (the held-out blocks aside): expected at least 21 "
     "samples to fit"),
])
def test_bad_logs_exit_2_with_one_line_and_write_nothing(
        tmp_path: Path, capsys: pytest.CaptureFixture, make: str, extra: list,
        expect: str) -> None:
    path = _logger_export(tmp_path / "drive.csv", 20 if make == "short" else 1000)
    if make == "constant":
        text = path.read_text().splitlines()
        text = [text[0] + ",temp0"] + [line + ",20" for line in text[1:]]
        path.write_text("\n".join(text) + "\n")
    out = tmp_path / "r.json"
    rc = main(["abstract", str(path), "--time-column", "time_s", "-o", str(out),
               "--workers", "1", "--quiet", *extra])
    err = capsys.readouterr().err.strip()
    assert rc == 2
    assert len(err.splitlines()) == 1 and "Traceback" not in err
    assert expect in err
    assert not out.exists() and not (tmp_path / "r.json.checkpoint").exists()


def test_a_constant_input_is_refused_by_the_api_too() -> None:
    log, _ = friction_log(1.0)
    cols = dict(log.columns)
    cols["still"] = np.zeros(len(log))
    with pytest.raises(DataFormatError, match="column 'still': expected a varying signal"):
        edm_sym.engines.abstraction.abstract(DataLog(cols, TS, "still.csv"), target="tau_ext",
                                             inputs=["omega", "still"])


# -- pipeline: [columns] and axis ----------------------------------------------------------

def test_pipeline_reads_columns_and_axis(export_csv: Path, tmp_path: Path) -> None:
    from edm_sym.application.pipeline import load_pipeline

    (tmp_path / "cfg.toml").write_text('axis = "linear"\n' + QUICK + '\n[columns]\ndqm = "velocity"\n')
    pipe = tmp_path / "p.toml"
    pipe.write_text(f'[data]\nabstraction = "{export_csv}"\n\n[columns]\ntime_s = "time"\n'
                    'F = "target"\nddqm = "acceleration"\n\n[abstraction]\nconfig = "cfg.toml"\n')
    p = load_pipeline(pipe)
    assert p.axis == "linear"  # from the abstraction config
    assert p.target == "F" and p.inputs == ("dqm", "ddqm")
    assert p.columns.time == "time_s"
    pipe.write_text(pipe.read_text().replace("[columns]\n", "[columns]\nG = \"target\"\n"))
    with pytest.raises(ValueError, match=r"p.toml: columns.F: expected one column with the role "
                                         r"'target', found it given twice \('G' and 'F'\)"):
        load_pipeline(pipe)


def test_same_seed_same_bytes_with_logs_recorded(export_csv: Path, tmp_path: Path) -> None:
    cfg = tmp_path / "cfg.toml"
    cfg.write_text(QUICK)
    outs = []
    for k in range(2):
        out = tmp_path / f"r{k}.json"
        assert main(["abstract", str(export_csv), "--time-column", "time_s", "--role", "F=target",
                     "--role", "dqm=velocity", "--config", str(cfg), "--seed", "5", "-o", str(out),
                     "--workers", "1", "--quiet"]) == 0
        outs.append(out.read_bytes())
    assert outs[0] == outs[1]
    assert dumps(load_result(tmp_path / "r0.json")).encode() == outs[0]


# -- the shipped EMPS example: a linear axis without the data ------------------------------

EMPS_EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "emps"


def test_emps_example_is_a_linear_axis_end_to_end(tmp_path: Path) -> None:
    from edm_sym.engines.abstraction import load_config

    result = load_result(EMPS_EXAMPLE / "result.json")
    config = load_config(EMPS_EXAMPLE / "abstraction.toml")
    assert result.axis == config.axis == "linear"
    # The roles the config gives are the ones the result recorded for its log.
    recorded = {c["name"]: c["role"] for c in result.logs[0]["columns"] if c["role"]}
    assert recorded == config.columns.roles
    desc = edm_sym.describe(result)
    kinds = {t.term.kind: t.term for r in desc.rows for t in r.terms}
    assert kinds["viscous"].parameters["coefficient"][1] == "N s/m"
    assert kinds["acceleration"].parameters["inertia"][1] == "kg"
    assert "linear axis, target in N" in desc.table()
    written = edm_sym.export(result, "c", tmp_path)
    assert [p.name for p in written] == ["edm_comp.h", "edm_comp.c"]


def test_describe_accepts_clock_drift_and_says_so(linear_result: Path, tmp_path: Path) -> None:
    log, _ = friction_log(1.0)
    c = log.columns
    drifted = {"time_s": c["t"] * (1 + 5e-4), "dqm": c["omega"], "ddqm": c["alpha"],
               "F": c["tau_ext"]}
    path = write_csv(tmp_path / "drift.csv", drifted)
    desc = edm_sym.describe(linear_result, path)
    assert any("relative drift 0.0005, accepted" in n for n in desc.notes)
    assert desc.fitness["data"]["samples"] == 1000
    # The rounding of a time column's steps is no drift: no note (one said "0.001 s in
    # the log, 0.001 s in the result, relative drift 1.1e-16").
    drifted["time_s"] = c["t"] * (1 + 3e-16)
    rounded = edm_sym.describe(linear_result, write_csv(tmp_path / "rounded.csv", drifted))
    assert not any("drift" in n for n in rounded.notes)
    # Beyond the tolerance: refused with both values and the way out named.
    drifted["time_s"] = c["t"] * 1.01
    far = write_csv(tmp_path / "far.csv", drifted)
    with pytest.raises(DataFormatError, match=r"far.csv: sample time: expected 0.001 s as in "
                                              r"r.json .* found 0.00101 s; `resample=True`"):
        edm_sym.describe(linear_result, far)
