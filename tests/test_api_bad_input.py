"""The Python API refuses what would mislead, naming the argument, the column and the row.

Logs read from files are checked as they are read (tests/test_files.py); these
are logs and arguments made in memory, where a NaN or a wrong sample time used
to pass silently: a NaN spread through every filter after it, a log at 2 ms
was simulated as if at 1 ms, a NaN input was dropped by the search.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import edm_sym
from edm_sym.core.data import DataLog
from edm_sym.core.errors import ConfigError, DataFormatError, ResultFormatError
from edm_sym.engines.abstraction import abstract, load_config
from edm_sym.engines.abstraction.parallel import Parallel
from edm_sym.engines.lugre import identify_lugre

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "auger" / "result.json"
TINY = load_config(Path(__file__).resolve().parent / "data" / "estimator_tiny.toml")


@pytest.fixture(scope="module")
def result():
    return edm_sym.load_result(EXAMPLE)


@pytest.fixture(scope="module")
def columns(result) -> dict[str, np.ndarray]:
    t = np.arange(2000) * result.sample_time
    cols = {"t": t, "tau_ext": 0.5 * np.sign(np.sin(t))}
    for k, name in enumerate(result.inputs):
        cols[name] = np.sin((k + 1) * 2 * np.pi * t)
    return cols


def _with(cols: dict[str, np.ndarray], name: str, row: int, value: float) -> dict:
    col = cols[name].copy()
    col[row] = value
    return {**cols, name: col}


@pytest.mark.parametrize("fn", ["simulate", "describe"])
def test_a_value_that_is_not_finite_is_refused_by_row_and_column(result, columns, fn) -> None:
    bad = DataLog(_with(columns, "omega", 100, np.nan), result.sample_time, "mem")
    with pytest.raises(DataFormatError) as info:
        getattr(edm_sym, fn)(result, bad)
    assert info.value.where == "mem: row 101, column 'omega'"
    assert "expected a finite number, found nan" in info.value.problem


@pytest.mark.parametrize("fn", ["simulate", "describe"])
def test_a_log_at_another_sample_time_is_refused(result, columns, fn) -> None:
    with pytest.raises(DataFormatError, match=r"sample time: expected 0.001 s .* found 0.002 s"):
        getattr(edm_sym, fn)(result, DataLog(columns, 2 * result.sample_time, "mem"))


def test_simulate_refuses_an_empty_log_a_missing_column_and_what_is_no_model(result,
                                                                              columns) -> None:
    with pytest.raises(DataFormatError, match="expected samples, found an empty log"):
        edm_sym.simulate(result, {k: v[:0] for k, v in columns.items()})
    with pytest.raises(DataFormatError, match="column 'alpha': expected the model's input column"):
        edm_sym.simulate(result, {k: v for k, v in columns.items() if k != "alpha"})
    with pytest.raises(DataFormatError, match="column 'alpha': expected 2000 samples"):
        edm_sym.simulate(result, {**columns, "alpha": columns["alpha"][:10]})
    with pytest.raises(ResultFormatError, match="result: expected an EdmResult or a Compensator"):
        edm_sym.simulate(str(EXAMPLE), columns)
    # What is fine still runs: a mapping of the input columns, no sample time to compare.
    assert edm_sym.simulate(result, columns).total.shape == (2000,)


def test_describe_refuses_data_of_another_kind(result, columns) -> None:
    with pytest.raises(DataFormatError, match="data: expected a DataLog, a file or a plant"):
        edm_sym.describe(result, columns)


@pytest.fixture(scope="module")
def small() -> dict[str, np.ndarray]:
    t = np.arange(400) * 1e-3
    omega = np.sin(2 * np.pi * t)
    return {"t": t, "omega": omega, "alpha": np.cos(2 * np.pi * t),
            "tau_ext": 0.5 * np.sign(omega) + 0.1 * omega}


@pytest.mark.parametrize("change,where,problem", [
    (("omega", 50, np.nan), "mem: row 51, column 'omega'", "expected a finite number, found nan"),
    (("tau_ext", 7, np.inf), "mem: row 8, column 'tau_ext'", "expected a finite number, found inf"),
])
def test_abstract_refuses_a_value_that_is_not_finite(small, change, where, problem) -> None:
    # A NaN input was dropped by the search without a word; an infinite target gave fitness inf.
    with pytest.raises(DataFormatError) as info:
        abstract(DataLog(_with(small, *change), 1e-3, "mem"), target="tau_ext",
                 inputs=["omega", "alpha"], config=TINY, parallel=Parallel(workers=1))
    assert (info.value.where, info.value.problem) == (where, problem)


def test_abstract_refuses_a_constant_target(small) -> None:
    with pytest.raises(DataFormatError, match="expected a varying target .* 0 on all 400 rows"):
        abstract(DataLog({**small, "tau_ext": np.zeros(400)}, 1e-3), target="tau_ext",
                 inputs=["omega"], config=TINY, parallel=Parallel(workers=1))


@pytest.mark.parametrize("kwargs,match", [
    ({"time_limit": -1.0}, "time_limit: expected a number of seconds >= 0, found -1.0"),
    ({"time_limit": float("nan")}, "time_limit: expected a number of seconds >= 0, found nan"),
    ({"time_limit": "3"}, "time_limit: expected a number of seconds >= 0, found '3'"),
    ({"config": "abstraction.toml"}, "config: expected an AbstractionConfig"),
    ({"parallel": 2}, r"parallel: expected a Parallel\(workers=..., executor=..., scheduler=...\), "
                      "found int"),
])
def test_abstract_refuses_arguments_of_the_wrong_kind(small, kwargs, match) -> None:
    with pytest.raises(ConfigError, match=match):
        abstract(DataLog(small, 1e-3), target="tau_ext", inputs=["omega"],
                 **{"config": TINY, "parallel": Parallel(workers=1), **kwargs})
    with pytest.raises(DataFormatError, match="data: expected a DataLog"):
        abstract(small, target="tau_ext", inputs=["omega"], config=TINY)


@pytest.mark.parametrize("inputs,rows,where,problem", [
    (["omega"], [("omega", [("zzz", 0)])], "rows[0].elements[0]", "'zzz' is not a known element"),
    (["omega"], [("omega", [(99, 0)])], "rows[0].elements[0]", "99 is not a known element"),
    (["omega"], [("omega", [(True, 0)])], "rows[0].elements[0]", "True is no element name"),
    (["omega"], [("omega", [("gain", "abc")])], "rows[0].elements[0]", "expected (element"),
    (["omega"], [("om", [("sign", 0)])], "rows[0]", "expected one of the inputs omega, found 'om'"),
    (["omega"], [(3, [("sign", 0)])], "rows[0]", "an index below 1, found 3"),
    (["omega"], [("omega",)], "rows[0]", "expected (input, [(element, p), ...])"),
    ("omega", [("omega", [("sign", 0)])], "inputs", "found the string 'omega'"),
])
def test_make_matrix_names_the_row_and_element_it_cannot_build(inputs, rows, where,
                                                               problem) -> None:
    # It raised KeyError, tuple.index's "x not in tuple", or split "omega" into letters.
    with pytest.raises(ConfigError) as info:
        edm_sym.make_matrix(inputs, rows)
    assert info.value.where == where and problem in info.value.problem


def test_make_matrix_still_takes_numpy_integers_for_inputs_and_codes() -> None:
    m = edm_sym.make_matrix(["omega", "alpha"], [(np.int64(1), [(np.int64(19), 0),
                                                                ("gain", np.float64(0.5))])])
    assert m.rows[0].input == 1 and type(m.rows[0].input) is int
    assert [g.element.name for g in m.rows[0].genes] == ["sign", "gain"]


@pytest.mark.parametrize("args,where", [
    ((0, {}), "sample_time"),            # was a ZeroDivisionError in the default ranges
    ((1e-3, {}, 0.0), "record_length"),
    (("0.001", {}), "sample_time"),
    ((1e-3, {"gain": (1, 2)}), "ranges"),
    ((1e-3, None), "ranges"),
])
def test_a_compensator_of_bad_parts_is_refused(args, where) -> None:
    m = edm_sym.make_matrix(["omega"], [("omega", [("sign", 0), ("gain", 0.55)])])
    with pytest.raises(ConfigError) as info:
        edm_sym.Compensator(m, *args)
    assert info.value.where == where


def test_save_result_writes_only_what_load_result_reads(tmp_path: Path) -> None:
    m = edm_sym.make_matrix(["omega"], [("omega", [("sign", 0), ("gain", 0.55)])])
    comp = edm_sym.Compensator(m, 1e-3, {})
    out = tmp_path / "r.json"
    with pytest.raises(ResultFormatError, match="r.json: provenance.seed: required field"):
        edm_sym.save_result(edm_sym.EdmResult(comp, "tau_ext"), out)  # default provenance: {}
    assert not out.exists()
    provenance = {"seed": None, "package_version": edm_sym.__version__, "data_sha256": None}
    edm_sym.save_result(edm_sym.EdmResult(comp, "tau_ext", provenance=provenance), out)
    assert edm_sym.load_result(out).compensator == comp


@pytest.mark.parametrize("params,where", [
    ({"target_name": ""}, "EDMRegressor.target_name"),
    ({"target_name": None}, "EDMRegressor.target_name"),   # saved a result load_result refused
    ({"roles": "x"}, "EDMRegressor.roles"),                # failed later in sympy() as a TypeError
    ({"workers": "2"}, "workers"),
    ({"time_limit": -1.0}, "time_limit"),
])
def test_the_estimator_refuses_bad_parameters_when_it_fits(small, params, where) -> None:
    est = edm_sym.EDMRegressor(sample_time=1e-3, config=TINY, **params)
    with pytest.raises(ConfigError) as info:
        est.fit(np.c_[small["omega"], small["alpha"]], small["tau_ext"])
    assert info.value.where == where


def test_a_residual_needs_one_target_sample_per_simulated_sample(result, columns) -> None:
    sim = edm_sym.simulate(result, columns)
    assert np.array_equal(sim.residual(columns["tau_ext"]), columns["tau_ext"] - sim.total)
    for bad in (None, columns["tau_ext"][:10]):  # None gave all NaN, a short one a numpy error
        with pytest.raises(DataFormatError, match="target: expected 2000 samples"):
            sim.residual(bad)


@pytest.mark.parametrize("ts", [None, "0.001", True])
def test_identify_lugre_names_a_sample_time_of_the_wrong_kind(ts) -> None:
    with pytest.raises(DataFormatError, match="ts: expected a positive finite sample time"):
        identify_lugre(np.ones(50), np.linspace(-1, 1, 50), ts)


def test_a_result_path_of_the_wrong_kind_is_named() -> None:
    with pytest.raises(ResultFormatError, match="path: expected a file path, found NoneType"):
        edm_sym.load_result(None)


@pytest.mark.parametrize("columns,ts,where,problem", [
    ({}, 1e-3, "mem: columns", "expected at least one column, found none"),   # was StopIteration
    ({"a": np.ones(3), "b": np.ones(4)}, 1e-3, "mem: column 'b'",             # numpy broadcast
     "expected 3 rows as column 'a' has, found 4"),
    ({"a": np.ones((3, 2))}, 1e-3, "mem: column 'a'", "expected a column of one dimension"),
    ({"a": np.ones(3)}, np.nan, "mem: sample time", "found nan"),  # simulate accepted it
    ({"a": np.ones(3)}, 0.0, "mem: sample time", "found 0.0"),
    ({"a": np.ones(3)}, "0.001", "mem: sample time", "found '0.001'"),
])
def test_a_log_made_in_memory_is_refused_when_it_is_no_log(columns, ts, where, problem) -> None:
    with pytest.raises(DataFormatError) as info:
        DataLog(columns, ts, "mem")
    assert info.value.where == where and problem in info.value.problem


@pytest.mark.parametrize("rows,where,problem", [
    ([("omega", [("gain", 1.5)])], "rows[0].elements[0].p", "expected 0..1, found 1.5"),
    ([("omega", [("gain", np.nan)])], "rows[0].elements[0].p", "expected 0..1, found nan"),
    ([], "matrix", "expected at least one row, found 0"),
])
def test_make_matrix_refuses_a_parameter_outside_its_range_and_no_rows(rows, where,
                                                                       problem) -> None:
    # These were plain ValueErrors, where make_matrix's other refusals are ConfigErrors.
    with pytest.raises(ConfigError) as info:
        edm_sym.make_matrix(["omega"], rows)
    assert info.value.where == where and problem in info.value.problem


def test_a_sample_time_the_default_ranges_cannot_span_names_the_sample_time() -> None:
    m = edm_sym.make_matrix(["omega"], [("omega", [("sign", 0), ("gain", 0.55)])])
    with pytest.raises(ConfigError) as info:  # named "range" before
        edm_sym.Compensator(m, 1000.0, {})
    assert info.value.where == "sample_time" and "found 1000 s" in info.value.problem


def test_describe_names_a_role_it_does_not_know(result, columns) -> None:
    with pytest.raises(ConfigError) as info:
        edm_sym.describe(result, DataLog(columns, result.sample_time), roles={"omega": "banana"})
    assert info.value.where == "roles['omega']" and "found 'banana'" in info.value.problem
    with pytest.raises(ConfigError, match="expected an input's name .* found 'zz'"):
        edm_sym.describe(result, DataLog(columns, result.sample_time), roles={"zz": "velocity"})


def test_identify_lugre_refuses_a_negative_seed() -> None:
    v = np.sin(np.linspace(0, 20, 500))
    with pytest.raises(ConfigError, match="seed: expected an integer >= 0, found -1"):
        identify_lugre(np.sign(v), v, 1e-3, seed=-1)


def test_a_selection_within_an_infinite_share_is_refused() -> None:
    from edm_sym.engines.abstraction.parsimony import check_select

    assert check_select("simplest-within=1e300", "select") == "simplest-within=1e300"
    with pytest.raises(ConfigError, match="select: expected simplest-within=PCT with a finite"):
        check_select("simplest-within=1e400", "select")


@pytest.mark.parametrize("low,high", [(-1.0, 3.0), (0.1, 100.0)])
def test_a_power_range_where_the_element_is_not_finite_is_refused(tmp_path: Path, low, high,
                                                                  result) -> None:
    # A negative exponent is infinite at x = 0, 100 overflows at |x| = 1e4: the simulator
    # wrote NaN or inf with exit 0 and the generated Python module raised ZeroDivisionError.
    from edm_sym.core.elements import ParamRange

    m = edm_sym.make_matrix(["omega"], [("omega", [("power", 0.5), ("gain", 0.55)])])
    with pytest.raises(ConfigError) as info:
        edm_sym.Compensator(m, 1e-3, {"power": ParamRange(low, high)})
    assert info.value.where == "ranges['power']"
    assert "expected the exponent within 0 .. 48" in info.value.problem
    # The same range in a result file and in a config.
    comp = edm_sym.Compensator(m, 1e-3, {})
    provenance = {"seed": None, "package_version": edm_sym.__version__, "data_sha256": None}
    edm_sym.save_result(edm_sym.EdmResult(comp, "tau_ext", provenance=provenance),
                        tmp_path / "r.json")
    doc = json.loads((tmp_path / "r.json").read_text())
    doc["parameter_ranges"]["power"] = {"low": low, "high": high, "scaling": "linear"}
    (tmp_path / "r.json").write_text(json.dumps(doc))
    with pytest.raises(ResultFormatError, match="r.json: parameter_ranges.power: range: expected "
                                                "the exponent within 0 .. 48"):
        edm_sym.load_result(tmp_path / "r.json")
    (tmp_path / "c.toml").write_text(f"[ranges.power]\nlow = {low}\nhigh = {high}\n")
    with pytest.raises(ConfigError, match="c.toml: ranges.power: range: expected the exponent"):
        load_config(tmp_path / "c.toml").resolve_ranges(1e-3, 20.0)


# -- a Python caller is told about its parameters, a command's user about its options --------

@pytest.mark.parametrize("options,message", [
    ({"prefix": "9x"}, "prefix: expected a C identifier, found '9x'"),
    ({"real": "half"}, "real: expected one of float, double, q31, q15, found 'half'"),
])
def test_export_names_the_parameter_not_the_command_line_option(result, tmp_path: Path, options,
                                                                message) -> None:
    with pytest.raises(ValueError) as info:
        edm_sym.export(result, "c", tmp_path / "out", **options)
    assert str(info.value) == message and "--" not in str(info.value)
    with pytest.raises(ValueError, match=r"^target: expected one of c, python, latex, test, all"):
        edm_sym.export(result, "pascal", tmp_path / "out")
    assert not (tmp_path / "out").exists()


def test_a_fixed_point_build_names_the_parameter_that_gives_an_input_range(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from edm_sym.application.cli import export_main
    from edm_sym.core.errors import as_options

    m = edm_sym.make_matrix(["omega"], [("omega", [("sign", 0), ("gain", 0.55)])])
    provenance = {"seed": None, "package_version": "test", "data_sha256": None}
    bare = edm_sym.EdmResult(edm_sym.Compensator(m, 1e-3, {}), "tau_ext", provenance=provenance)
    with pytest.raises(ValueError) as info:  # no range recorded: the Python caller's words
        edm_sym.export(bare, "c", tmp_path / "py", real="q31")
    said = str(info.value)
    assert 'give one with input_range={"omega": (LO, HI)}' in said and "--" not in said
    # The command says the same in its options' words.
    assert as_options(said).endswith("give one with --input-range omega=LO:HI")
    path = edm_sym.save_result(bare, tmp_path / "r.json")
    capsys.readouterr()
    assert export_main([str(path), "--target", "c", "--real", "q31", "-o", str(tmp_path / "c")]) == 2
    assert capsys.readouterr().err.strip().endswith("give one with --input-range omega=LO:HI")


def test_describe_names_the_axis_parameter(result) -> None:
    with pytest.raises(DataFormatError) as info:
        edm_sym.describe(result, axis="sideways")
    assert info.value.where == "axis"


@pytest.mark.parametrize("message,printed", [
    ("prefix: expected a C identifier, found '9x'", "--prefix: expected a C identifier, found '9x'"),
    ('x: use real="float" or real="double"', "x: use --real float or --real double"),
    ("x: narrow the input's range (input_range)", "x: narrow the input's range (--input-range)"),
    ("names: expected unique names", "--columns: expected unique names"),
    ("x: (or one named by `time_column`) or the option `ts=SECONDS`",
     "x: (or one named by --time-column) or the option --ts SECONDS"),
    ("x: `resample=True` resamples it", "x: --resample resamples it"),
    ('x: select run.mat:data with names="NAME,NAME,..." (7 names)',
     "x: select run.mat:data with --columns NAME,NAME,... (7 names)"),
    # Not a parameter, or not where a parameter is named: left as it is.
    ("result.json: prefix: x", "result.json: prefix: x"), ("inputs: omega: y", "inputs: omega: y"),
    ("a ClassifyOptions.for_axis(axis) call", "a ClassifyOptions.for_axis(axis) call"),
    ("log.csv: ts: x", "log.csv: ts: x"), ("x: `omega` and `q=1`", "x: `omega` and `q=1`"),
])
def test_a_command_prints_the_option_that_gives_a_parameter(message, printed) -> None:
    from edm_sym.core.errors import as_options

    assert as_options(message) == printed


@pytest.mark.parametrize("where,printed", [
    ("log.csv: ts", "log.csv: --ts"),
    ("run.mat:data: ts", "run.mat:data: --ts"),
    # A name alone is the first field (as_options); other places are left as they are:
    # a column, a scalar of the log, a key of a file.
    ("ts", "ts"), ("log.csv: column 't'", "log.csv: column 't'"),
    ("log.csv: observer_bandwidth", "log.csv: observer_bandwidth"),
    ("cfg.toml: axis", "cfg.toml: axis"), ("log.csv: ts.x", "log.csv: ts.x"),
])
def test_a_command_prints_the_option_a_log_was_read_with(where, printed) -> None:
    from edm_sym.core.errors import where_as_options

    assert where_as_options(where) == printed


def test_a_log_read_without_a_sample_time_names_ts_and_the_command_its_option(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from edm_sym.application.cli import main

    path = tmp_path / "no_t.csv"
    path.write_text("omega\n1\n2\n")
    with pytest.raises(DataFormatError) as info:
        edm_sym.load_data(path)
    said = str(info.value)
    assert "`ts=SECONDS`" in said and "`time_column`" in said and "--" not in said
    with pytest.raises(DataFormatError) as info:
        edm_sym.load_data(path, ts=5e3)
    assert info.value.where == "no_t.csv: ts"
    # The command says the same in its options' words.
    observe = ["observe", str(path), "--position", "omega", "--force", "f", "--nominal-inertia",
               "1", "-o", str(tmp_path / "o.csv")]
    capsys.readouterr()
    assert main(observe) == 2
    assert capsys.readouterr().err == (
        "edm: no_t.csv: column 't': expected a time column 't' (or one named by --time-column) "
        "or the option --ts SECONDS, found neither\n")
    assert main([*observe, "--ts", "5e3"]) == 2
    assert capsys.readouterr().err == ("edm: no_t.csv: --ts: expected a sample time from "
                                       "1e-09 s to 1000 s, found 5000 s\n")
    assert not (tmp_path / "o.csv").exists()


@pytest.mark.parametrize("name", ["decode", "describe", "export"])
def test_the_package_face_has_the_signature_of_what_it_calls(name) -> None:
    # edm_sym imports its implementations on first call only, so it repeats their signatures.
    import inspect

    from edm_sym.application.exporting import export
    from edm_sym.engines.description import describe
    from edm_sym.engines.symbolic import decode

    face = inspect.signature(getattr(edm_sym, name)).parameters
    impl = inspect.signature({"decode": decode, "describe": describe, "export": export}[name]
                             ).parameters
    assert [(p.name, p.kind, p.default) for p in face.values()] == [
        (p.name, p.kind, p.default) for p in impl.values()]
    assert all(p.kind is not p.VAR_KEYWORD for p in face.values())


@pytest.mark.parametrize("settings,where,problem", [
    ({"workers": 0}, "workers", "expected an integer >= 1, found 0"),
    ({"workers": True}, "workers", "expected an integer >= 1, found True"),
    ({"workers": 1.5}, "workers", "expected an integer >= 1, found 1.5"),
    ({"executor": "pool"}, "executor", "expected a concurrent.futures.Executor, found str"),
])
def test_parallel_settings_are_refused_when_made(settings, where, problem) -> None:
    with pytest.raises(ConfigError) as info:
        Parallel(**settings)
    assert (info.value.where, info.value.problem) == (where, problem)
