"""edm-export on the command line: outputs, default folder, one-line errors, exit codes."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from edm_sym.application.cli import export_main, main

REPO = Path(__file__).resolve().parent.parent
EXAMPLE = REPO / "examples" / "auger" / "result.json"


def test_writes_and_prints_every_file(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    assert export_main([str(EXAMPLE), "--target", "all", "-o", str(tmp_path)]) == 0
    printed = capsys.readouterr().out.split()
    names = [Path(p).name for p in printed]
    assert names[:3] == ["edm_comp.h", "edm_comp.c", "edm_comp.py"]
    assert "edm_comp_report.tex" in names  # "all" includes the LaTeX report
    assert all(Path(p).is_file() for p in printed)


def test_edm_export_equals_edm_export_subcommand(tmp_path: Path) -> None:
    assert export_main([str(EXAMPLE), "--target", "c", "-o", str(tmp_path / "a")]) == 0
    assert main(["export", str(EXAMPLE), "--target", "c", "-o", str(tmp_path / "b")]) == 0
    for name in ("edm_comp.h", "edm_comp.c"):
        assert (tmp_path / "a" / name).read_bytes() == (tmp_path / "b" / name).read_bytes()


def test_default_folder_is_generated_slash_result_folder(tmp_path: Path,
                                                         monkeypatch: pytest.MonkeyPatch) -> None:
    src = tmp_path / "examples" / "axis7"
    src.mkdir(parents=True)
    shutil.copy(EXAMPLE, src / "result.json")
    monkeypatch.chdir(tmp_path)
    assert export_main([str(src / "result.json"), "--target", "python"]) == 0
    assert (tmp_path / "generated" / "axis7" / "edm_comp.py").is_file()


def test_two_runs_are_byte_identical(tmp_path: Path) -> None:
    for out in ("one", "two"):
        assert export_main([str(EXAMPLE), "--target", "all", "--real", "float",
                            "-o", str(tmp_path / out)]) == 0
    for path in (tmp_path / "one").iterdir():
        assert path.read_bytes() == (tmp_path / "two" / path.name).read_bytes()


def _one_error_line(capsys: pytest.CaptureFixture) -> str:
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    return err.strip()


@pytest.mark.parametrize(("mutate", "field"), [
    (lambda d: d["matrix"]["rows"][0]["elements"][1].update(code=41), "code"),
    (lambda d: d.pop("sample_time"), "sample_time"),
    (lambda d: d.update(format="other"), "format"),
])
def test_bad_result_file_exit_2_and_writes_nothing(mutate, field: str, tmp_path: Path,  # noqa: ANN001
                                                   capsys: pytest.CaptureFixture) -> None:
    doc = json.loads(EXAMPLE.read_text())
    mutate(doc)
    bad = tmp_path / "result.json"
    bad.write_text(json.dumps(doc))
    out = tmp_path / "out"
    assert export_main([str(bad), "--target", "all", "-o", str(out)]) == 2
    line = _one_error_line(capsys)
    assert line.startswith("edm-export: result.json") and field in line
    assert not out.exists()


def test_missing_and_non_json_result_exit_2(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    assert export_main([str(tmp_path / "nope.json"), "--target", "c", "-o", str(tmp_path)]) == 2
    assert "nope.json" in _one_error_line(capsys)
    junk = tmp_path / "junk.json"
    junk.write_text("{not json")
    assert export_main([str(junk), "--target", "c", "-o", str(tmp_path / "o")]) == 2
    assert "expected JSON" in _one_error_line(capsys)
    assert not (tmp_path / "o").exists()


def test_unwritable_output_folder_is_one_line(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    blocker = tmp_path / "a_file"
    blocker.write_text("")
    code = export_main([str(EXAMPLE), "--target", "c", "-o", str(blocker / "out")])
    assert code in (1, 2)
    assert "cannot create the output folder" in _one_error_line(capsys)


@pytest.mark.skipif(os.name != "posix" or os.geteuid() == 0, reason="root writes anywhere")
def test_read_only_output_folder_is_one_line(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o555)
    try:
        assert export_main([str(EXAMPLE), "--target", "c", "-o", str(ro)]) in (1, 2)
        assert "cannot write" in _one_error_line(capsys)
        assert list(ro.iterdir()) == []
    finally:
        ro.chmod(0o755)


@pytest.mark.parametrize(("args", "expected"), [
    (["--prefix", "9x"], "edm-export: --prefix: expected a C identifier, found '9x'"),
    (["--real", "half"], "edm-export: argument --real: invalid choice: 'half'"),
])
def test_bad_options_exit_2(args: list[str], expected: str, tmp_path: Path,
                            capsys: pytest.CaptureFixture) -> None:
    assert export_main([str(EXAMPLE), "--target", "c", "-o", str(tmp_path / "o"), *args]) == 2
    assert _one_error_line(capsys).startswith(expected)
    assert not (tmp_path / "o").exists()


def test_latex_target_writes_only_the_report(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    assert export_main([str(EXAMPLE), "--target", "latex", "-o", str(tmp_path / "o")]) == 0
    names = {p.name for p in (tmp_path / "o").iterdir()}
    assert "edm_comp_report.tex" in names
    assert not names & {"edm_comp.h", "edm_comp.c", "edm_comp.py"}


def test_console_script_runs_from_another_folder(tmp_path: Path) -> None:
    exe = shutil.which("edm-export") or str(Path(sys.executable).parent / "edm-export")
    if not Path(exe).exists():
        pytest.skip("edm-export is not installed as a console script")
    proc = subprocess.run([exe, str(EXAMPLE), "--target", "all", "-o", "out"], cwd=tmp_path,
                          capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    names = {p.name for p in (tmp_path / "out").iterdir()}
    assert {"edm_comp.c", "edm_comp.h", "edm_comp.py", "edm_comp_report.tex"} <= names


@pytest.mark.parametrize(("module", "argv"), [
    ("edm_sym.application.exporting", ["export", str(EXAMPLE), "--target", "c"]),
    ("edm_sym.application.abstract_cli", ["abstract", "plant:auger/abstraction"]),
])
def test_a_broken_internal_import_is_a_bug_not_a_missing_tool(
        module: str, argv: list[str], tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
        capsys: pytest.CaptureFixture) -> None:
    # Internal modules are always installed: an ImportError there is a defect to report,
    # not "not available in this build" (only optional extras are missing tools).
    monkeypatch.setitem(sys.modules, module, None)  # the next import of it raises ImportError
    assert main([*argv, "-o", str(tmp_path / "out")]) == 1
    err = capsys.readouterr().err
    assert "failed: ModuleNotFoundError" in err and module in err and "this is a bug of edm_sym" in err
    assert "not available" not in err
    assert not (tmp_path / "out").exists()
