"""The report on several logs of a kind: each drawn, the fit on each and over all."""

from __future__ import annotations

import math
import re
import shutil
import subprocess
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


def _pooled(values: list[np.ndarray]) -> float:
    return rms(np.concatenate(values))


def test_each_log_gets_its_contributions_and_time_responses(tmp_path: Path) -> None:
    result = ugr.example_result()
    data = _logs(tmp_path, result, [("a.csv", "abstraction", 3000), ("b.csv", "evaluation", 2000)])
    files = write_report(result, tmp_path / "out", data=data, prefix="two")
    tex = files[0].read_text()
    names = {p.name for p in files[1:]}
    for key in ("abstraction", "abstraction2"):
        for fig in ("contributions", "rows", "time", "zoom"):
            assert f"two_fig_{fig}_{key}.pdf" in names
            assert f"two_fig_{fig}_{key}.pdf" in tex
    assert not any("evaluation" in n for n in names)
    # Each log's contribution table, then the one over both; captions name the file.
    assert "On abstraction log 1 of 2, \\texorpdfstring{\\texttt{a.csv}}" in tex
    assert "On abstraction log 2 of 2, \\texorpdfstring{\\texttt{b.csv}}" in tex
    assert "\\subsection{Over all 2 abstraction logs}" in tex
    assert "residuals on abstraction log 2 of 2, \\texttt{b.csv}, over the whole log" in tex
    # Over all: each row's RMS and the RMSE with every row are those of both logs'
    # signals put end to end, each log simulated from rest.
    rows, residuals = [], []
    for path in data:
        log = load_data(path)
        sim = simulate(result, log)
        rows.append(sim.rows)
        residuals.append(log.columns["tau_ext"] - sim.total)
    over = tex[tex.index("\\subsection{Over all 2 abstraction logs}"):]
    over = over[:over.index("\\end{tabular}")]
    cells = [line.split("&") for line in over.splitlines() if line.startswith("$y_{")]
    row_rms = [rms(np.concatenate([r[j] for r in rows])) for j in range(len(cells))]
    for j, cell in enumerate(cells):
        assert _value(cell[1]) == pytest.approx(row_rms[j], rel=1e-3)
    assert _value(cells[-1][2]) == pytest.approx(_pooled(residuals), rel=1e-3)
    facts = tex[:tex.index("\\subsection{The compensator}")]
    assert "RMSE, all 2 abstraction logs" in facts and "sha256, abstraction log 2" in facts
    assert "\\shortstack[r]{RMS [N\\,m]\\\\ 2 abstraction logs}" in tex


def _value(cell: str) -> float:
    """A table cell's number (``$1.23 \\cdot 10^{-3}$`` or ``$0.5$``)."""
    text = cell.replace("\\\\", "").strip().strip("$")
    text = re.sub(r"\\s*\\(?:cdot|times)\\s*10\\^\\{(-?\\d+)\\}", r"e\\1", text)
    return float(re.sub(r"[^0-9.e+-]", "", text))


@pytest.mark.toolchain
@pytest.mark.skipif(shutil.which("latexmk") is None or shutil.which("pdftotext") is None,
                    reason="latexmk or pdftotext is not installed")
def test_two_log_report_compiles_and_names_both_logs(tmp_path: Path) -> None:
    from edm_sym.outputs.report.pdf import compile_pdf

    result = ugr.example_result()
    data = _logs(tmp_path, result, [("first_run.csv", "abstraction", 2500),
                                    ("second_run.csv", "evaluation", 2000)])
    lugre = ugr.write_lugre(tmp_path / "lugre.json", data[0])
    files = write_report(result, tmp_path / "out", data=data, lugre=lugre, prefix="two")
    pdf, log = compile_pdf(files[0], keep_aux=True)
    assert log.errors == () and log.undefined == ()
    assert log.worst_overfull <= 10.0, log.overfull
    text = re.sub(r"\s+", " ", subprocess.run(["pdftotext", "-layout", str(pdf), "-"],
                                              capture_output=True, text=True, check=True).stdout)
    for k, name in enumerate(("first_run.csv", "second_run.csv"), start=1):
        assert f"On abstraction log {k} of 2, {name}" in text
        assert f"Row contributions on abstraction log {k} of 2, {name}" in text
        assert f"residuals on abstraction log {k} of 2, {name}, over the whole log" in text
    assert "Over all 2 abstraction logs" in text and "over all 2 logs" in text
    # Every log's figures are in the PDF, not only named in the .tex.
    figures = [p for p in files[1:] if p.suffix == ".pdf"]
    assert len([p for p in figures if "abstraction2" in p.name]) == 4
