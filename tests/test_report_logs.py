"""The report on several logs of a kind: the first drawn, the RMSE on each and over all tabled."""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest
import update_golden_report as ugr

from edm_sym.core.fitness import rms
from edm_sym.engines.simulate import simulate
from edm_sym.engines.sources import load_data
from edm_sym.outputs.report import write_report


def _logs(folder: Path, result, names: list[tuple[str, str, int]]) -> list[Path]:  # noqa: ANN001
    return [ugr.write_log(folder / name, ugr.log_columns(result, kind, n))
            for name, kind, n in names]


def _table(tex: str) -> list[str]:
    start = tex.index(r"\label{tab:log-rmse}")
    return tex[start:tex.index(r"\end{tabular}", start)].splitlines()


def test_several_logs_give_a_table_of_each_log_and_over_all(tmp_path: Path) -> None:
    result = ugr.example_result()
    data = _logs(tmp_path, result, [("a.csv", "abstraction", 3000), ("b.csv", "evaluation", 2000)])
    (ev,) = _logs(tmp_path, result, [("c.csv", "evaluation", 2500)])
    lugre = ugr.write_lugre(tmp_path / "lugre.json", data[0])
    tex = write_report(result, tmp_path / "out", data=data, eval_data=[ev], lugre=lugre)[0] \
        .read_text()
    table = _table(tex)
    rows = [line for line in table if "&" in line and "csv" in line or "over all" in line]
    assert [re.search(r"texttt\{(\w\.csv)\}|over all \d logs", r).group(0).split("{")[-1].strip("}")
            for r in rows] == ["a.csv", "b.csv", "over all 2 logs", "c.csv"]
    # Over all: the RMSE of the residuals of both logs, each simulated from rest.
    errors = []
    for path in data:
        log = load_data(path)
        errors.append(log.columns["tau_ext"] - simulate(result, log).total)
    pooled = rms(np.concatenate(errors))
    cells = rows[2].split("&")
    assert cells[2].strip() == "5000"
    assert float(re.sub(r"[^0-9.e-]", "", cells[3].replace(r"\cdot 10^{", "e").replace("}", ""))) \
        == pytest.approx(pooled, rel=1e-3)
    assert math.isfinite(pooled) and "LuGre" in table[3]
    # The commands name every log.
    assert "--data a.csv b.csv" in tex and "--eval-data c.csv" in tex


@pytest.mark.slow
def test_one_log_of_each_kind_gives_no_table(tmp_path: Path) -> None:
    result = ugr.example_result()
    data = _logs(tmp_path, result, [("a.csv", "abstraction", 1500)])
    tex = write_report(result, tmp_path / "out", data=data[0])[0].read_text()
    assert "tab:log-rmse" not in tex
    tex_list = write_report(result, tmp_path / "out2", data=data)[0].read_text()
    assert tex_list == tex
