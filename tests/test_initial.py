"""edm abstract --initial: a model that carries over to new logs (docs/abstraction.md)."""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import numpy as np
import pytest
from conftest import TS

from edm_sym.application.cli import main
from edm_sym.core.data import write_csv
from edm_sym.core.result import load_result
from edm_sym.engines.abstraction.schedule import inherit, parse_config

CONFIG = """
[ga]
population = 12
generations = 2

[[step]]
n_rows = 1
n_elements = 3

[[step]]
n_rows = 2
n_elements = 3
"""


def _write(tmp_path: Path, name: str, seed: int, n: int = 500, ts: float = TS) -> Path:
    rng = np.random.default_rng(seed)
    t = np.arange(n) * ts
    omega = np.sin(2 * np.pi * (2 + seed) * t)
    tau = 0.3 * np.tanh(30 * omega) + 0.05 * omega + 0.01 * rng.standard_normal(n)
    return write_csv(tmp_path / name, {"t": t, "omega": omega, "alpha": np.gradient(omega),
                                       "tau": tau})


def _abstract(tmp_path: Path, data: Path, out: str, *extra: str) -> int:
    cfg = tmp_path / "cfg.toml"
    cfg.write_text(CONFIG)
    return main(["abstract", str(data), "--target", "tau", "--inputs", "omega", "--config",
                 str(cfg), "--quiet", "--workers", "1", "-o", str(tmp_path / out), *extra])


def test_a_new_abstraction_starts_from_the_previous_rows_and_records_them(tmp_path: Path) -> None:
    assert _abstract(tmp_path, _write(tmp_path, "a.csv", 1), "first.json") == 0
    first = load_result(tmp_path / "first.json")
    assert _abstract(tmp_path, _write(tmp_path, "b.csv", 2), "second.json", "--initial",
                     str(tmp_path / "first.json")) == 0
    doc = json.loads((tmp_path / "second.json").read_text())
    digest = hashlib.sha256((tmp_path / "first.json").read_bytes()).hexdigest()
    assert doc["provenance"]["initial"] == {"file": "first.json", "sha256": digest}
    # The schedule continued from the first step that holds the previous rows.
    cfg = inherit(parse_config({"ga": {"population": 12, "generations": 2},
                                "step": [{"n_rows": 1, "n_elements": 3},
                                         {"n_rows": 2, "n_elements": 3}]}),
                  first, inputs=["omega"], axis="rotary", ts=TS, t_sum=500 * TS)
    m = len(first.compensator.matrix.rows)
    assert cfg.steps[0].n_rows >= m and len(cfg.initial) == m
    assert [r.input for r in cfg.initial] == ["omega"] * m


@pytest.mark.parametrize("change,reason", [
    (["--axis", "linear"], "expected a result of the linear axis, found one of the rotary axis"),
    (["--inputs", "omega,alpha"], "expected the inputs omega, alpha, found omega"),
])
def test_a_previous_result_of_another_axis_or_inputs_is_refused(tmp_path: Path, capsys, change,
                                                                 reason: str) -> None:
    assert _abstract(tmp_path, _write(tmp_path, "a.csv", 1), "first.json") == 0
    capsys.readouterr()
    code = _abstract(tmp_path, _write(tmp_path, "b.csv", 2), "second.json", "--initial",
                     str(tmp_path / "first.json"), *change)
    assert code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--initial first.json" in err[0] and reason in err[0]
    assert not (tmp_path / "second.json").exists()


def test_a_previous_result_of_another_sample_time_is_refused(tmp_path: Path, capsys) -> None:
    assert _abstract(tmp_path, _write(tmp_path, "a.csv", 1), "first.json") == 0
    capsys.readouterr()
    code = _abstract(tmp_path, _write(tmp_path, "b.csv", 2, ts=2 * TS), "second.json",
                     "--initial", str(tmp_path / "first.json"))
    assert code == 2
    err = capsys.readouterr().err
    assert "expected the sample time 0.002 s of the logs, found 0.001 s" in err


@pytest.mark.parametrize("edit, where", [
    (lambda d: d["provenance"].__setitem__("initial", {"file": "prev.json", "sha256": "abc"}),
     "provenance.initial.sha256"),
    (lambda d: d["provenance"].__setitem__("initial", 3), "provenance.initial"),
    (lambda d: d["logs"][0].__setitem__("decimate", {"factor": 1, "filter": "fir"}),
     "logs[0].decimate.factor"),
    (lambda d: d["logs"][0].__setitem__("decimate", {"factor": 4}), "logs[0].decimate"),
    (lambda d: d["validation"]["held_out"].__setitem__("layout", "middle"),
     "validation.held_out.layout"),
], ids=["initial-sha256", "initial-type", "decimate-factor", "decimate-filter", "layout"])
def test_a_malformed_key_of_several_logs_is_refused_by_name(tmp_path: Path, capsys, edit,  # noqa: ANN001
                                                            where: str) -> None:
    doc = json.loads((Path(__file__).resolve().parents[1] / "examples" / "auger" / "result.json")
                     .read_text("utf-8"))
    edit(doc)
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(doc), encoding="utf-8")
    before = path.read_bytes()
    assert main(["describe", str(path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "bad.json" in err[0] and where in err[0], err
    assert path.read_bytes() == before
