"""The one-command pipeline: data -> LuGre -> EDM -> evaluation -> export."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from edm_sym.application.cli import main
from edm_sym.application.pipeline import load_pipeline
from edm_sym.core.errors import ConfigError
from edm_sym.core.result import load_result

QUICK_GA = """
[ga]
generations = 4
continue = "no"
population = 16
[[step]]
n_rows = 2
n_elements = 2
"""


def _write(folder: Path, pipeline: str) -> Path:
    (folder / "quick.toml").write_text(QUICK_GA)
    p = folder / "pipeline.toml"
    p.write_text(pipeline)
    return p


PIPELINE = """
[data]
abstraction = "plant:lugre/abstraction"
evaluation = "plant:lugre/evaluation"
[abstraction]
config = "quick.toml"
target = "tau_ext"
inputs = ["omega", "theta_w"]
seed = 3
[lugre]
velocity = "omega"
time_limit = 5
[export]
target = "c"
out_dir = "gen"
"""


def test_pipeline_runs_end_to_end(tmp_path: Path, capsys) -> None:
    p = _write(tmp_path, PIPELINE)
    assert main(["pipeline", str(p), "--quiet"]) == 0
    out = capsys.readouterr().out
    assert "EDM/LuGre" in out and "evaluation" in out
    summary = json.loads((tmp_path / "evaluation.json").read_text())
    for log in ("abstraction", "evaluation"):
        assert summary[log]["edm"] > 0 and summary[log]["lugre"] > 0
        assert summary[log]["ratio"] == pytest.approx(summary[log]["edm"] / summary[log]["lugre"])
    res = load_result(tmp_path / "result.json")
    assert res.report_inputs == {"data": "plant:lugre/abstraction",
                                 "eval_data": "plant:lugre/evaluation", "lugre": "lugre.json"}
    assert (tmp_path / "gen" / "edm_comp.c").exists()
    # --reuse keeps the identified files and only evaluates and exports again
    before = (tmp_path / "result.json").read_bytes()
    assert main(["pipeline", str(p), "--quiet", "--reuse"]) == 0
    assert (tmp_path / "result.json").read_bytes() == before


@pytest.mark.parametrize("text,where", [
    ("[data]\nabstraction = 3\n", "data.abstraction"),
    ("[dta]\n", "dta"),
    ("[data]\nabstraction = 'x.csv'\n[abstraction]\ntarget = 'y'\n", "abstraction.inputs"),
    ("[data]\nabstraction = 'x.csv'\nfoo = 1\n", "data.foo"),
    ("[data\n", "expected TOML"),
])
def test_bad_pipeline_is_refused(text: str, where: str, tmp_path: Path, capsys) -> None:
    p = tmp_path / "pipeline.toml"
    p.write_text(text)
    with pytest.raises(ConfigError, match=where.replace("[", r"\[")):
        load_pipeline(p)
    assert main(["pipeline", str(p)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and where in err


@pytest.mark.parametrize("value", ["-5", "0", "nan", "inf"])
def test_a_time_limit_that_is_no_duration_is_refused(tmp_path: Path, value: str, capsys) -> None:
    p = _write(tmp_path, PIPELINE.replace("seed = 3", f"seed = 3\ntime_limit = {value}"))
    assert main(["pipeline", str(p), "--quiet"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "pipeline.toml: abstraction.time_limit" in err, err
    assert not (tmp_path / "result.json").exists()


@pytest.mark.parametrize("old,new,where", [
    ('target = "c"', 'target = "foo"', "export.target"),
    ('target = "c"', 'target = "c"\nprefix = "9 bad"', "export.prefix"),
    ('target = "c"', 'target = "c"\nreal = "half"', "export.real"),
    ('target = "c"', 'target = "c"\npdf = "yes"', "export.pdf"),
    ("time_limit = 5", 'time_limit = 5\nmethod = "foo"', "lugre.method"),
    ("time_limit = 5", "time_limit = -3", "lugre.time_limit"),
    ("time_limit = 5", 'time_limit = 5\nweighting = "x"', "lugre.weighting"),
    ('velocity = "omega"', "velocity = 3", "lugre.velocity"),
    ('inputs = ["omega", "theta_w"]', 'inputs = ["omega", "tau_ext"]', "abstraction.inputs"),
])
def test_a_bad_value_of_a_later_stage_is_refused_before_any_work(
        tmp_path: Path, old: str, new: str, where: str, capsys) -> None:
    # The last stages' settings are checked with the file, not after the long work:
    # the files of an earlier run stay as they were.
    for kept in ("result.json", "lugre.json", "evaluation.json"):
        (tmp_path / kept).write_text("an earlier run's\n")
    p = _write(tmp_path, PIPELINE.replace(old, new))
    with pytest.raises(ConfigError, match=where):
        load_pipeline(p)
    assert main(["pipeline", str(p), "--quiet"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and f"pipeline.toml: {where}" in err, err
    for kept in ("result.json", "lugre.json", "evaluation.json"):
        assert (tmp_path / kept).read_text() == "an earlier run's\n"
    assert not (tmp_path / "gen").exists()


def test_a_data_file_where_the_pipeline_writes_is_refused_before_any_work(tmp_path: Path, capsys) -> None:
    from edm_sym.core.data import write_csv
    from edm_sym.engines.plant import simulate_plant

    write_csv(tmp_path / "result.json", simulate_plant("lugre", "abstraction").columns)
    before = (tmp_path / "result.json").read_bytes()
    p = _write(tmp_path, PIPELINE.replace('abstraction = "plant:lugre/abstraction"',
                                          'abstraction = "result.json"'))
    assert main(["pipeline", str(p), "--quiet"]) == 2
    err = capsys.readouterr().err.strip()
    assert "expected a new file" in err and "result.json" in err
    assert (tmp_path / "result.json").read_bytes() == before
    assert not (tmp_path / "lugre.json").exists()


@pytest.mark.parametrize("where", ["gen/edm_comp.c", "gen/edm_comp_report.tex"])
def test_an_input_among_the_files_the_export_writes_is_refused_before_any_work(
        where: str, tmp_path: Path, capsys) -> None:  # noqa: ANN001
    # Only <out_dir>/<prefix>.h was checked: a log named gen/edm_comp.c was replaced by
    # the generated C (exit 0), found by a fuzz pass.
    from edm_sym.core.data import write_csv
    from edm_sym.engines.plant import simulate_plant

    (tmp_path / "gen").mkdir()
    write_csv(tmp_path / where, simulate_plant("lugre", "evaluation").columns)
    before = (tmp_path / where).read_bytes()
    p = _write(tmp_path, PIPELINE.replace('evaluation = "plant:lugre/evaluation"',
                                          f'evaluation = "{where}"'))
    assert main(["pipeline", str(p), "--quiet"]) == 2
    err = capsys.readouterr().err.strip()
    assert "found the input" in err and where in err and "choose another out_dir or prefix" in err
    assert (tmp_path / where).read_bytes() == before
    assert not (tmp_path / "lugre.json").exists()


@pytest.mark.parametrize("change, message", [
    (('inputs = ["omega", "theta_w"]', 'inputs = ["omega", "omega"]'),
     "pipeline.toml: abstraction.inputs: expected each column once, found 'omega' twice"),
    (('inputs = ["omega", "theta_w"]', 'inputs = ["t", "omega"]'),
     "column 't': expected a signal of the axis"),
])
def test_what_the_abstraction_refuses_is_refused_before_the_lugre_fit(
        change: tuple[str, str], message: str, tmp_path: Path, capsys) -> None:  # noqa: ANN001
    # Refused only after the LuGre fit (and its lugre.json written over an earlier one's),
    # found by a fuzz pass.
    from edm_sym.core.data import write_csv
    from edm_sym.engines.plant import simulate_plant

    write_csv(tmp_path / "abs.csv", simulate_plant("lugre", "abstraction").columns)
    p = _write(tmp_path, PIPELINE.replace('abstraction = "plant:lugre/abstraction"',
                                          'abstraction = "abs.csv"').replace(*change))
    (tmp_path / "lugre.json").write_text("an earlier run's")
    assert main(["pipeline", str(p), "--quiet"]) == 2
    assert message in capsys.readouterr().err
    assert (tmp_path / "lugre.json").read_text() == "an earlier run's"


@pytest.mark.parametrize("velocity, message", [
    ("tau_ext", "pipeline.toml: lugre.velocity: expected a column other than the target"),
    ("t", "column 't': expected a signal of the axis"),
])
def test_the_target_or_the_clock_is_no_lugre_velocity(velocity: str, message: str,
                                                      tmp_path: Path, capsys) -> None:  # noqa: ANN001
    p = _write(tmp_path, PIPELINE.replace('velocity = "omega"', f'velocity = "{velocity}"'))
    assert main(["pipeline", str(p), "--quiet"]) == 2
    assert message in capsys.readouterr().err
    assert not (tmp_path / "lugre.json").exists()


def test_an_interrupted_abstraction_stops_the_pipeline_with_130(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys
) -> None:
    import edm_sym.engines.abstraction as abstraction

    real = abstraction.abstract

    def interrupted(*args, **kwargs):  # noqa: ANN002, ANN003, ANN202
        kwargs["callback"] = lambda info: True  # ends the run like Ctrl-C would, at a generation
        res = real(*args, **kwargs)
        from dataclasses import replace

        return replace(res, provenance={**res.provenance, "stop_reason": "interrupted"})

    monkeypatch.setattr(abstraction, "abstract", interrupted)
    p = _write(tmp_path, PIPELINE)
    assert main(["pipeline", str(p), "--quiet"]) == 130
    assert "interrupted" in capsys.readouterr().err
    assert (tmp_path / "result.json").exists()  # the best so far is kept
    assert not (tmp_path / "evaluation.json").exists() and not (tmp_path / "gen").exists()


@pytest.mark.parametrize("old,new,where", [
    # An empty string was taken for the key left out: no config, the default axis,
    # no evaluation log, the default out_dir.
    ('config = "quick.toml"', 'config = ""', "abstraction.config"),
    ('evaluation = "plant:lugre/evaluation"', 'evaluation = ""', "data.evaluation"),
    ('evaluation = "plant:lugre/evaluation"', 'evaluation = "plant:lugre/evaluation"\naxis = ""',
     "data.axis"),
    ('target = "tau_ext"', 'target = " "', "abstraction.target"),
    ('out_dir = "gen"', 'out_dir = ""', "export.out_dir"),
])
def test_an_empty_string_is_refused_not_taken_for_a_missing_key(
        tmp_path: Path, old: str, new: str, where: str, capsys) -> None:
    p = _write(tmp_path, PIPELINE.replace(old, new))
    with pytest.raises(ConfigError, match=f"{where}: expected a non-empty str, found"):
        load_pipeline(p)
    assert main(["pipeline", str(p), "--quiet"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and f"pipeline.toml: {where}" in err, err


def test_a_lugre_weighting_zero_on_the_whole_log_names_its_key(tmp_path: Path, capsys) -> None:
    p = _write(tmp_path, PIPELINE.replace(
        "time_limit = 5", "time_limit = 5\nweighting = { windows = [[1000.0, 2000.0, 1.0]], "
        "otherwise = 0.0 }"))
    assert main(["pipeline", str(p), "--quiet"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1, err
    assert "pipeline.toml: lugre.weighting: expected a weighting above zero somewhere" in err
    assert not (tmp_path / "lugre.json").exists()


def test_pipeline_takes_lists_of_logs(tmp_path: Path, capsys) -> None:
    text = PIPELINE.replace(
        'abstraction = "plant:lugre/abstraction"\nevaluation = "plant:lugre/evaluation"',
        'abstraction = ["plant:lugre/abstraction", "plant:lugre/evaluation"]\n'
        'evaluation = ["plant:lugre/evaluation", "plant:lugre/abstraction"]').replace(
        'target = "c"', 'target = "latex"')
    p = _write(tmp_path, text)
    assert main(["pipeline", str(p), "--quiet"]) == 0
    out = capsys.readouterr().out
    summary = json.loads((tmp_path / "evaluation.json").read_text())
    assert set(summary) == {"abstraction", "abstraction: plant:lugre/abstraction",
                            "abstraction: plant:lugre/evaluation", "evaluation",
                            "evaluation: plant:lugre/evaluation", "evaluation: plant:lugre/abstraction"}
    # Over all: the pooled RMSE of the two logs (the same two logs in both kinds).
    both = [summary[f"abstraction: plant:lugre/{k}"]["edm"] for k in ("abstraction", "evaluation")]
    assert min(both) <= summary["abstraction"]["edm"] <= max(both)
    assert summary["evaluation"]["edm"] == pytest.approx(summary["abstraction"]["edm"])
    assert "abstraction: plant:lugre/evaluation" in out
    res = load_result(tmp_path / "result.json")
    assert res.report_inputs == {"lugre": "lugre.json"}  # several logs: given to the export
    assert [log["file"] for log in res.logs] == ["plant:lugre/abstraction", "plant:lugre/evaluation"]
    tex = (tmp_path / "gen" / "edm_comp_report.tex").read_text()
    assert "tab:log-rmse" in tex


def test_a_pipeline_list_of_no_logs_is_refused(tmp_path: Path, capsys) -> None:
    p = _write(tmp_path, PIPELINE.replace('abstraction = "plant:lugre/abstraction"',
                                          'abstraction = []'))
    assert main(["pipeline", str(p), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "pipeline.toml: data.abstraction: expected a log or a list" \
        in err, err


@pytest.mark.slow
def test_the_shipped_example_is_what_the_pipeline_makes(tmp_path: Path) -> None:
    """`edm pipeline examples/auger/pipeline.toml` writes the committed files byte for byte:
    the example is what this release makes (README.md, docs/benchmarks.md). Minutes."""
    root = Path(__file__).resolve().parents[1]
    example = tmp_path / "examples" / "auger"
    example.mkdir(parents=True)
    for name in ("pipeline.toml", "abstraction.toml"):
        (example / name).write_bytes((root / "examples" / "auger" / name).read_bytes())
    assert main(["pipeline", str(example / "pipeline.toml"), "--quiet"]) == 0
    for name in ("result.json", "lugre.json", "evaluation.json"):
        assert (example / name).read_bytes() == (root / "examples" / "auger" / name).read_bytes(), name
    made, shipped = tmp_path / "generated" / "auger", root / "generated" / "auger"
    for name in ("edm_comp.c", "edm_comp.h", "edm_comp.py", "edm_comp_report.tex"):
        assert (made / name).read_bytes() == (shipped / name).read_bytes(), name
