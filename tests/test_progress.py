"""Progress and closing summaries of the long commands (docs/cli.md#progress-and-summary).

The engines print nothing; ``ProgressReporter`` renders their reports as a bar
on a terminal, as plain lines elsewhere, and as nothing with ``--quiet``.
"""

from __future__ import annotations

import io
import os
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

from edm_sym.application.progress import ProgressReporter, format_seconds
from edm_sym.core.data import write_csv

ROOT = Path(__file__).resolve().parents[1]

QUICK = """
[ga]
population = 16
generations = 4
continue = "no"

[[step]]
n_rows = 1
n_elements = 2

[[step]]
n_rows = 2
n_elements = 2
"""


def _edm(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    """``edm`` in a child process whose stderr is a pipe, not a terminal."""
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    return subprocess.run([sys.executable, "-m", "edm_sym", *args], cwd=cwd, env=env,
                          capture_output=True, text=True, timeout=300)


def _abstract(friction_csv: Path, tmp_path: Path, *extra: str) -> subprocess.CompletedProcess:
    cfg = tmp_path / "cfg.toml"
    cfg.write_text(QUICK)
    return _edm("abstract", str(friction_csv), "--target", "tau_ext", "--inputs", "omega,alpha",
                "--config", str(cfg), "--workers", "1", "-o", str(tmp_path / "res.json"),
                *extra, cwd=tmp_path)


def test_abstract_off_a_terminal_prints_progress_lines_and_a_summary(
    friction_csv: Path, tmp_path: Path
) -> None:
    proc = _abstract(friction_csv, tmp_path)
    assert proc.returncode == 0, proc.stderr
    lines = [ln for ln in proc.stderr.splitlines() if ln.startswith("edm abstract: step ")]
    # The first generation and each new step give a line at once (then one every 5 s).
    assert len(lines) >= 2, proc.stderr
    assert lines[0].startswith("edm abstract: step 1/2 (2x1) gen 0 | best ")
    assert any(ln.startswith("edm abstract: step 2/2 (2x2) gen ") for ln in lines)
    for ln in lines:
        assert " N m | " in ln and " eval/s | time left ~" in ln and "| elapsed " in ln
    assert "\r" not in proc.stderr  # no bar off a terminal
    # The closing summary names the file written and ends with the flags.
    assert proc.stdout.splitlines()[0] == f"wrote {tmp_path / 'res.json'}"
    err = proc.stderr.splitlines()
    assert err[-1] == "edm abstract: flags: none" or "see `edm describe" in err[-1]


def test_quiet_prints_no_progress(friction_csv: Path, tmp_path: Path) -> None:
    proc = _abstract(friction_csv, tmp_path, "--quiet")
    assert proc.returncode == 0, proc.stderr
    assert not [ln for ln in proc.stderr.splitlines() if " gen " in ln or "eval/s" in ln]
    assert proc.stdout.splitlines()[0] == f"wrote {tmp_path / 'res.json'}"


def test_lugre_off_a_terminal_prints_lines_and_a_summary(tmp_path: Path) -> None:
    n, ts = 3000, 1e-3
    t = np.arange(n) * ts
    v = 2.0 * np.sin(2 * np.pi * 0.5 * t)
    tau = 0.8 * np.tanh(v / 0.01) + 0.05 * v  # Coulomb + viscous: no stiction, r -> its floor
    data = write_csv(tmp_path / "log.csv", {"t": t, "tau": tau, "omega": v})
    out = tmp_path / "lugre.json"
    proc = _edm("lugre", str(data), "--target", "tau", "--velocity", "omega", "-o", str(out),
                "--time-limit", "20", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    lines = [ln for ln in proc.stderr.splitlines() if ln.startswith("edm lugre: LuGre scipy gen ")]
    assert lines and all("eval/s | time left <= " in ln for ln in lines)
    assert "edm lugre: fitness (weighted eq. 8): training " in proc.stderr
    assert proc.stderr.splitlines()[-1] == "edm lugre: flags: none"
    assert proc.stdout.splitlines()[0] == f"wrote {out}"
    quiet = _edm("lugre", str(data), "--target", "tau", "--velocity", "omega", "-o",
                 str(tmp_path / "q.json"), "--time-limit", "20", "--quiet", cwd=tmp_path)
    assert " gen " not in quiet.stderr and "fitness (weighted eq. 8)" in quiet.stderr


def test_export_summary_names_the_files_the_fitness_and_the_bound(
    tmp_path: Path, capsys: pytest.CaptureFixture
) -> None:
    from edm_sym.application.cli import export_main
    from edm_sym.core.result import load_result

    # An older result: no held-out validation, one parameter at a range bound.
    example = ROOT / "tests" / "golden" / "legacy_auger_result.json"
    assert export_main([str(example), "--target", "c", "-o", str(tmp_path)]) == 0
    captured = capsys.readouterr()
    assert captured.out.split() == [str(tmp_path / "edm_comp.h"), str(tmp_path / "edm_comp.c")]
    err = captured.err.splitlines()
    fit = load_result(example).fitness  # the example holds no held-out validation
    assert err[0] == f"edm-export: fitness (weighted eq. 8): training {fit:.6g} N m, " \
                     "validation: none held out"
    assert err[1].startswith("edm-export: negligible rows: not measured")
    bound = [ln for ln in err if "range bound" in ln]
    assert len(bound) == 1 and bound[0].startswith("edm-export: warning: parameter at its range "
                                                   "bound: row 1 element 2 (phase")


def test_the_shipped_lugre_model_has_its_stiction_ratio_at_the_floor() -> None:
    from edm_sym.engines.lugre import load_lugre, shape_bound_flags
    from edm_sym.engines.sources import load_data

    lugre = load_lugre(ROOT / "examples" / "auger" / "lugre.json")
    log = load_data("plant:auger/abstraction")
    flags = shape_bound_flags(lugre.params, log.columns["omega"], log.ts)
    # tau_s / tau_c = 0.001: the bottom of the search's [1e-3, 1e2]; nothing else is at a bound
    assert len(flags) == 1 and flags[0].startswith("LuGre tau_s/tau_c (stiction ratio) = 0.001 "
                                                   "is at its low bound 0.001")
    # Moved inside the box, the same ratio is not flagged.
    from dataclasses import replace

    inside = replace(lugre.params, tau_s=0.5 * lugre.params.tau_c)
    assert shape_bound_flags(inside, log.columns["omega"], log.ts) == []


@dataclass
class _Stats:
    individuals: int


@dataclass
class _Info:
    step: int
    generation: int
    best: float
    elapsed: float
    stats: _Stats
    steps: int = 2
    shape: tuple[int, int] = (4, 2)
    generations_left: int = 10
    time_limit: float | None = None
    search: int = 0
    searches: int = 1


def test_lines_come_every_interval_and_at_a_new_step() -> None:
    now = [0.0]
    out = io.StringIO()
    rep = ProgressReporter("edm abstract", stream=out, interval=5.0, unit="N m",
                           clock=lambda: now[0])
    assert rep.mode == "lines"  # a StringIO is no terminal
    for k, (t, step) in enumerate([(0, 1), (1, 1), (4.9, 1), (5.0, 1), (6, 2), (7, 2)]):
        now[0] = t
        rep.abstraction(_Info(step, k, 0.5, t + 1.0, _Stats(100 * (k + 1))))
    lines = out.getvalue().splitlines()
    assert [ln.split(" | ")[0] for ln in lines] == [
        "edm abstract: step 1/2 (4x2) gen 0", "edm abstract: step 1/2 (4x2) gen 3",
        "edm abstract: step 2/2 (4x2) gen 4"]
    # gen 3: 400 evaluations in 6 s; 10 generations left at 6 s / 4 generations = 15 s
    assert lines[1].split(" | ")[1:] == ["best 0.5 N m", "67 eval/s", "time left ~15s",
                                         "elapsed 6s"]


def test_searches_reporting_in_turns_each_get_a_line_every_interval() -> None:
    now = [0.0]
    out = io.StringIO()
    rep = ProgressReporter("edm abstract", stream=out, interval=5.0, clock=lambda: now[0])
    for k, t in enumerate([0, 0.5, 1, 1.5, 5.2, 5.6]):
        now[0] = t
        rep.abstraction(_Info(1, k, 0.5, t + 1.0, _Stats(10), search=k % 2, searches=2))
    assert [ln.split(" | ")[0] for ln in out.getvalue().splitlines()] == [
        "edm abstract: search 1/2 step 1/2 (4x2) gen 0",
        "edm abstract: search 2/2 step 1/2 (4x2) gen 1",
        "edm abstract: search 1/2 step 1/2 (4x2) gen 4",
        "edm abstract: search 2/2 step 1/2 (4x2) gen 5"]


def test_time_left_is_capped_by_the_time_limit_and_quiet_writes_nothing() -> None:
    out = io.StringIO()
    ProgressReporter("x", stream=out).abstraction(
        _Info(1, 0, 1.0, 10.0, _Stats(10), generations_left=1000, time_limit=30.0))
    assert "time left ~20s" in out.getvalue()
    quiet = io.StringIO()
    rep = ProgressReporter("x", stream=quiet, quiet=True)
    rep.abstraction(_Info(1, 0, 1.0, 10.0, _Stats(10)))
    assert quiet.getvalue() == "" and rep.lines_written == 0


def test_the_bar_is_a_tqdm_bar_with_a_total() -> None:
    out = io.StringIO()
    with ProgressReporter("x", stream=out, bar=True) as rep:
        for k in range(3):
            rep.abstraction(_Info(1, k, 1.0, 1.0 + k, _Stats(10), generations_left=2 - k))
    text = out.getvalue()
    assert "3/3" in text and "step 1/2 (4x2) gen 2" in text and "\r" in text


@pytest.mark.parametrize("seconds,text", [(0.4, "0s"), (59, "59s"), (61, "1m01s"),
                                          (3725, "1h02m")])
def test_format_seconds(seconds: float, text: str) -> None:
    assert format_seconds(seconds) == text
