"""Outputs never harm inputs, odd outputs are written in place, and every fault has its exit status.

Exit statuses (docs/cli.md#exit-status): 0 done, 1 a bug (with a line saying
how to report it), 2 bad input or an unwritable output, 130 interrupted.
"""

from __future__ import annotations

import json
import os
import stat
from pathlib import Path

import pytest

from edm_sym.application import cli
from edm_sym.application.cli import export_main, main
from edm_sym.core.data import write_csv
from edm_sym.core.result import EdmResult, StepRecord, dumps

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "auger" / "result.json"


@pytest.fixture
def files(coulomb_viscous, tmp_path: Path) -> dict[str, Path]:
    import numpy as np
    from conftest import TS

    res = EdmResult(coulomb_viscous, "tau_ext",
                    (StepRecord(1, coulomb_viscous.matrix, 0.5, (0.5,), 1, 10,
                                {"kind": "constant", "value": 1.0}),),
                    {"seed": 0, "package_version": "0.1.0", "data_sha256": "0" * 64}, 0.5)
    (tmp_path / "r.json").write_text(dumps(res))
    t = np.arange(300) * TS
    omega = 3 * np.sin(2 * np.pi * t)
    log = write_csv(tmp_path / "log.csv", {"t": t, "theta_w": np.mod(t, 6.28), "omega": omega,
                                           "tau_ext": 0.9 * np.sign(omega)})
    return {"result": tmp_path / "r.json", "data": log}


def _one_line(capsys: pytest.CaptureFixture) -> str:
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "Traceback" not in err, err
    return err


def _snapshot(paths: list[Path]) -> dict[Path, bytes]:
    return {p: p.read_bytes() for p in paths}


@pytest.mark.parametrize("which", ["data", "result", "data_via_link"])
def test_simulate_refuses_to_write_over_an_input(files, which: str, tmp_path: Path, capsys) -> None:
    before = _snapshot([files["result"], files["data"]])
    target = files["result"] if which == "result" else files["data"]
    if which == "data_via_link":
        (tmp_path / "link.csv").symlink_to(files["data"])
        target = tmp_path / "link.csv"
    assert main(["simulate", str(files["result"]), str(files["data"]), "-o", str(target)]) == 2
    err = _one_line(capsys)
    assert "expected a new file" in err and files["data" if which != "result" else "result"].name in err
    assert _snapshot([files["result"], files["data"]]) == before


def test_lugre_and_observe_refuse_the_input_as_output(files, capsys) -> None:
    before = _snapshot([files["data"]])
    assert main(["lugre", str(files["data"]), "--target", "tau_ext", "--velocity", "omega",
                 "-o", str(files["data"])]) == 2
    assert "expected a new file" in _one_line(capsys)
    assert main(["observe", str(files["data"]), "--position", "theta_w", "--force", "tau_ext",
                 "--nominal-inertia", "1e-3", "-o", str(files["data"])]) == 2
    assert "expected a new file" in _one_line(capsys)
    assert _snapshot([files["data"]]) == before


def test_abstract_refuses_a_data_file_where_its_checkpoint_goes(files, tmp_path: Path, capsys) -> None:
    data = tmp_path / "out.json.checkpoint"
    data.write_bytes(files["data"].read_bytes())
    before = _snapshot([data])
    assert main(["abstract", str(data), "--target", "tau_ext", "--inputs", "omega",
                 "-o", str(tmp_path / "out.json")]) == 2
    assert "checkpoint" in _one_line(capsys)
    assert _snapshot([data]) == before and not (tmp_path / "out.json").exists()


def test_export_refuses_a_result_named_like_its_own_output(tmp_path: Path, capsys) -> None:
    res = tmp_path / "edm_comp.py"
    res.write_bytes(EXAMPLE.read_bytes())
    assert export_main([str(res), "--target", "python", "-o", str(tmp_path)]) == 2
    assert "expected a new file" in _one_line(capsys)
    assert res.read_bytes() == EXAMPLE.read_bytes()


def test_dev_null_stays_a_device(files, capsys) -> None:
    assert main(["simulate", str(files["result"]), str(files["data"]), "-o", os.devnull]) == 0
    assert stat.S_ISCHR(os.stat(os.devnull).st_mode)


def test_a_fifo_is_written_in_place(files, tmp_path: Path) -> None:
    import threading

    fifo = tmp_path / "pipe.csv"
    os.mkfifo(fifo)
    got: list[bytes] = []
    reader = threading.Thread(target=lambda: got.append(fifo.read_bytes()))
    reader.start()
    assert main(["simulate", str(files["result"]), str(files["data"]), "-o", str(fifo)]) == 0
    reader.join(timeout=30)
    assert stat.S_ISFIFO(os.stat(fifo).st_mode)
    assert got and got[0].startswith(b"t,row_1")


def test_a_folder_as_output_is_refused_before_any_work(files, tmp_path: Path, capsys) -> None:
    folder = tmp_path / "folder"
    folder.mkdir()
    assert main(["abstract", str(files["data"]), "--target", "tau_ext", "--inputs", "omega",
                 "-o", str(folder)]) == 2
    assert "found a folder" in _one_line(capsys)


def test_deeply_nested_json_is_bad_input_not_a_crash(tmp_path: Path, capsys) -> None:
    deep = tmp_path / "deep.json"
    deep.write_text('{"format": "edm-result", "x": ' + "[" * 100_000 + "]" * 100_000 + "}")
    assert main(["simulate", str(deep), "x.csv"]) == 2
    assert "deep.json" in _one_line(capsys)


def test_interrupt_exits_130(monkeypatch: pytest.MonkeyPatch, capsys) -> None:
    def interrupted(args):  # noqa: ANN001, ANN202
        raise KeyboardInterrupt

    monkeypatch.setattr(cli, "_cmd_plant", interrupted)
    assert main(["plant", "--preset", "auger", "--excitation", "abstraction",
                 "-o", os.devnull]) == 130
    assert "interrupted" in _one_line(capsys)


def test_a_bug_exits_1_and_says_how_to_report_it(monkeypatch: pytest.MonkeyPatch, capsys) -> None:
    def broken(args):  # noqa: ANN001, ANN202
        raise ZeroDivisionError("oops")

    monkeypatch.setattr(cli, "_cmd_plant", broken)
    assert main(["plant", "--preset", "auger", "--excitation", "abstraction"]) == 1
    err = _one_line(capsys)
    assert "ZeroDivisionError" in err and "report" in err


def test_every_exit_status_is_documented() -> None:
    doc = (Path(__file__).resolve().parents[1] / "docs" / "cli.md").read_text()
    for code in (cli.EXIT_OK, cli.EXIT_FAILED, cli.EXIT_BAD_INPUT, cli.EXIT_INTERRUPTED):
        assert f"`{code}`" in doc or f"| {code} " in doc, code
    assert cli.EXIT_INTERRUPTED == 128 + 2  # the shell's status for SIGINT


# -- bad values named, never a crash -------------------------------------------------

def test_bad_values_are_one_line_exit_2(files, tmp_path: Path, capsys) -> None:
    huge = tmp_path / "huge.csv"
    huge.write_text("t,omega\n0," + "1" * 200_000 + "\n0.001,1\n")
    short = tmp_path / "short.csv"
    short.write_text("t,q,f\n0,0,0\n0.001,0,0\n")
    constant = tmp_path / "constant.csv"
    constant.write_text("t,omega,tau_ext\n" + "".join(f"{k / 1000},0.5,{k % 3}\n" for k in range(20)))
    cfg = tmp_path / "c.toml"
    cfg.write_text("cache_mb = inf\n")
    text = files["result"].read_text()
    assert '"sample_time": 0.001' in text
    bad = {"tiny_ts.json": text.replace('"sample_time": 0.001', '"sample_time": 1e-300'),
           "huge_number.json": text.replace('"sample_time": 0.001', '"sample_time": 1e999'),
           "null.json": "null\n"}
    for name, body in bad.items():
        (tmp_path / name).write_text(body)
    cases = [
        (["simulate", str(files["result"]), str(huge), "-o", str(tmp_path / "a.csv")], "huge.csv: row 2"),
        (["observe", str(short), "--position", "q", "--force", "f", "--nominal-inertia", "1e-3",
          "-o", str(tmp_path / "b.csv")], "short.csv: column 'q'"),
        (["observe", str(files["data"]), "--position", "theta_w", "--force", "tau_ext",
          "--nominal-inertia", "1e-3", "--force-gain", "inf", "-o", str(tmp_path / "c.csv")],
         "edm observe: --force-gain"),
        (["observe", str(files["data"]), "--position", "theta_w", "--force", "tau_ext",
          "--nominal-inertia", "-1", "-o", str(tmp_path / "c.csv")], "edm observe: --nominal-inertia"),
        (["observe", str(files["data"]), "--force", "tau_ext", "--nominal-inertia", "1",
          "-o", str(tmp_path / "c.csv")], "edm observe: --position"),
        (["lugre", str(files["data"]), "--target", "tau_ext", "-o", str(tmp_path / "l.json")],
         "edm lugre: --velocity"),
        (["lugre", str(constant), "--target", "tau_ext", "--velocity", "omega",
          "-o", str(tmp_path / "l.json")], "constant.csv: column 'omega': expected a varying"),
        (["abstract", str(files["data"]), "--target", "tau_ext", "--inputs", "omega,tau_ext",
          "-o", str(tmp_path / "g.json")], "--inputs: expected input columns other than the target"),
        (["describe", str(tmp_path / "tiny_ts.json")], "tiny_ts.json: sample_time, record_length"),
        (["describe", str(tmp_path / "huge_number.json")],
         "huge_number.json: sample_time: expected a finite number"),
        (["describe", str(tmp_path / "null.json")], "expected a JSON object, found null"),
        (["observe", str(files["data"]), "--position", "theta_w", "--force", "tau_ext",
          "--nominal-inertia", "nan", "-o", str(tmp_path / "d.csv")], "--nominal-inertia"),
        (["abstract", str(files["data"]), "--target", "tau_ext", "--inputs", "omega",
          "--seed", "9" * 5000, "-o", str(tmp_path / "e.json")], "(5000 characters)"),
        (["abstract", str(files["data"]), "--target", "tau_ext", "--inputs", "omega",
          "--config", str(cfg), "-o", str(tmp_path / "f.json")], "c.toml: cache_mb"),
    ]
    for argv, where in cases:
        assert main(argv) == 2, argv
        err = _one_line(capsys)
        assert where in err and len(err) < 400, err
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(
        ["c.toml", "constant.csv", "huge.csv", "log.csv", "r.json", "short.csv", *bad])


@pytest.mark.parametrize("prefix,why", [
    ("math", "C header"), ("stddef", "C header"), ("_", "leading underscore"), ("_x", "leading underscore"),
    ("class", "keyword"), ("None", "keyword"), ("new", "keyword"), ("json", "Python module"),
    ("numpy", "Python module"), ("os", "Python module"), ("1abc", "C identifier"), ("a-b", "C identifier"),
    # Longer, it named files the system refuses ("File name too long", no expected/found).
    ("p" * 64, "expected at most 63 characters"),
])
def test_prefix_that_would_shadow_or_clash_is_refused(prefix: str, why: str, tmp_path: Path, capsys) -> None:
    assert export_main([str(EXAMPLE), "--target", "all", "--prefix", prefix, "-o", str(tmp_path / "g")]) == 2
    err = _one_line(capsys)
    assert "--prefix" in err and why in err and repr(prefix) in err
    assert not (tmp_path / "g").exists()


def test_an_ordinary_prefix_is_accepted(tmp_path: Path) -> None:
    assert export_main([str(EXAMPLE), "--target", "c", "--prefix", "axis2_comp", "-o", str(tmp_path)]) == 0
    assert (tmp_path / "axis2_comp.h").exists()


@pytest.mark.parametrize("inputs,why", [
    ("ω", "ASCII letters"), ("tau ext", "ASCII letters"), ("1abc", "not starting with a digit"),
    ("omega,Omega", "differ in more than case"), ("class", "Python keyword"),
])
def test_input_names_that_cannot_be_exported_are_refused_up_front(tmp_path: Path, inputs: str, why: str,
                                                                   capsys) -> None:
    import numpy as np
    from conftest import TS

    names = inputs.split(",")
    t = np.arange(200) * TS
    cols = {"t": t, **{n: np.sin(t + k) for k, n in enumerate(names)}, "tau_ext": np.sign(np.sin(t))}
    data = write_csv(tmp_path / "odd.csv", cols)
    out = tmp_path / "new.json"
    assert main(["abstract", str(data), "--target", "tau_ext", "--inputs", inputs, "-o", str(out)]) == 2
    err = _one_line(capsys)
    assert why in err and repr(names[-1]) in err
    assert not out.exists()


@pytest.mark.parametrize("low,high,scaling", [(-1e308, 1e308, "linear"), (1e-300, 1.0, "log"),
                                              (0.0, 1e13, "linear")])
def test_a_range_beyond_the_limit_is_refused_in_config_and_result(tmp_path: Path, low: float, high: float,
                                                                  scaling: str, capsys) -> None:
    import json as _json

    from edm_sym.core.errors import ConfigError
    from edm_sym.core.result import load_result
    from edm_sym.engines.abstraction import load_config

    cfg = tmp_path / "c.toml"
    cfg.write_text(f'[ranges.gain]\nlow = {low!r}\nhigh = {high!r}\nscaling = "{scaling}"\n')
    with pytest.raises(ConfigError, match=r"c.toml: ranges.gain.*1e\+12|c.toml: ranges.gain.*1e-12"):
        load_config(cfg).resolve_ranges(1e-3, 20.0)  # a partial override is checked with the defaults
    doc = _json.loads(EXAMPLE.read_text())
    doc["parameter_ranges"]["gain"] = {"low": low, "high": high, "scaling": scaling}
    res = tmp_path / "r.json"
    res.write_text(_json.dumps(doc))
    assert export_main([str(res), "--target", "c", "-o", str(tmp_path / "g")]) == 2
    err = _one_line(capsys)
    assert "parameter_ranges" in err and "gain" in err
    assert not (tmp_path / "g").exists()
    with pytest.raises(Exception, match="1e"):
        load_result(res)


def test_a_failing_pdf_leaves_the_other_targets_and_names_its_own(tmp_path: Path, monkeypatch,
                                                                  capsys) -> None:
    fake = tmp_path / "bin"
    fake.mkdir()
    latexmk = fake / "latexmk"
    latexmk.write_text("#!/bin/sh\necho 'fake latexmk: stopped' >&2\nexit 12\n")
    latexmk.chmod(0o755)
    monkeypatch.setenv("PATH", f"{fake}{os.pathsep}{os.environ['PATH']}")
    out = tmp_path / "gen"
    assert export_main([str(EXAMPLE), "--target", "all", "--pdf", "-o", str(out)]) == 1
    err = _one_line(capsys)
    assert "target latex" in err and "edm_comp.c" in err and "bug" not in err
    for name in ("edm_comp.h", "edm_comp.c", "edm_comp.py", "edm_comp_report.tex"):
        assert (out / name).exists(), name
    assert not (out / "edm_comp_report.pdf").exists()


def test_the_target_is_no_input_of_its_own_model(files) -> None:
    # Through the API too: a model of the target from itself would fit it exactly.
    from edm_sym.core.errors import ConfigError
    from edm_sym.engines.abstraction import abstract
    from edm_sym.engines.sources import load_data

    log = load_data(files["data"])
    with pytest.raises(ConfigError, match="inputs: expected input columns other than the target"):
        abstract(log, target="tau_ext", inputs=["omega", "tau_ext"])


def test_a_libraries_own_value_error_is_a_failure_not_bad_input(capsys) -> None:
    # matplotlib's "Axis limits cannot be NaN or Inf" and the JSON encoder's "Out of range
    # float values" came out as exit 2, bad input, naming no file or field.
    import argparse

    from edm_sym.application.cli import EXIT_BAD_INPUT, EXIT_FAILED, REPORT_BUG, _dispatch
    from edm_sym.core.matrix import ParamRange

    def library(args: argparse.Namespace) -> int:
        json.dumps(float("nan"), allow_nan=False)
        return 0

    def own_check(args: argparse.Namespace) -> int:
        ParamRange(2.0, 1.0)  # edm_sym's own validation: bad input
        return 0

    def builtin(args: argparse.Namespace) -> int:
        float("abc")  # a built-in has no frame: its caller, edm_sym's, counts
        return 0

    for func, code in ((library, EXIT_FAILED), (own_check, EXIT_BAD_INPUT)):
        parser = argparse.ArgumentParser(prog="edm")
        parser.set_defaults(func=func)
        assert _dispatch([], parser) == code, func.__name__
    err = capsys.readouterr().err.splitlines()
    assert err[0].startswith("edm: failed: ValueError: Out of range float") and REPORT_BUG in err[0]
    assert err[1] == "edm: range: expected low < high, found [2.0, 1.0]"
    parser = argparse.ArgumentParser(prog="edm")
    parser.set_defaults(func=builtin)
    # The test's own frame is not edm_sym's: a built-in called from outside is a failure.
    assert _dispatch([], parser) == EXIT_FAILED
