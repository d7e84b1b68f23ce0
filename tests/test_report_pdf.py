"""The report compiles with latexmk: no errors, no undefined references, nothing off the page.

Needs TeX Live with latexmk (marker ``toolchain``); skipped cleanly without it.
"""

from __future__ import annotations

import re
import shutil
import subprocess
from pathlib import Path

import pytest
import update_golden_report as ugr  # tests/ is on sys.path (pytest rootdir)

import edm_sym
from edm_sym.outputs.printing.latex import format_number
from edm_sym.outputs.report import write_report
from edm_sym.outputs.report.context import KIND_TITLES
from edm_sym.outputs.report.pdf import AUX_SUFFIXES, compile_pdf

pytestmark = [
    pytest.mark.toolchain,
    pytest.mark.skipif(shutil.which("latexmk") is None, reason="latexmk is not installed"),
]

#: The widest overfull box accepted [pt].
OVERFULL_LIMIT = 10.0
#: The largest accepted report PDF [bytes].
REPO = Path(__file__).resolve().parents[1]
PDF_LIMIT = 2_000_000


def _build(case: ugr.Case, folder: Path):  # noqa: ANN202
    result, kw = ugr.case_inputs(case, folder)
    files = write_report(result, folder, **kw)
    pdf, log = compile_pdf(files[0], keep_aux=True)
    return result, files, pdf, log


def _check_log(log) -> None:  # noqa: ANN001
    assert log.errors == ()
    assert log.undefined == ()
    assert log.worst_overfull <= OVERFULL_LIMIT, log.overfull
    assert not [w for w in log.warnings if "multiply defined" in w or "Rerun" in w]


def _pdftext(pdf: Path) -> str:
    if shutil.which("pdftotext") is None:
        pytest.skip("pdftotext is not installed")
    out = subprocess.run(["pdftotext", "-layout", str(pdf), "-"], capture_output=True, text=True,
                         check=True).stdout
    return re.sub(r"\s+", " ", out)


def _as_printed(value: float) -> str:
    """A table value as pdftotext reads it: the mantissa of the 6-digit form."""
    return format_number(value, 6).split(r" \times")[0].replace("-", "−")


def test_example_report_compiles_cleanly(tmp_path: Path) -> None:
    case = ugr.CASES[0]  # the shipped example, both logs, LuGre
    result, files, pdf, log = _build(case, tmp_path)
    _check_log(log)
    assert pdf.stat().st_size < PDF_LIMIT
    text = _pdftext(pdf)
    model = edm_sym.decode(result)
    for row in model.rows:
        for term in row.terms:
            assert KIND_TITLES[term.kind] in text, term.kind
    for info in model.params:
        assert _as_printed(info.value) in text, info.symbol
    for heading in ("Summary", "The element matrix", "Parameters", "Contributions of the rows",
                    "Time responses", "Comparison with the LuGre model", "Reproducibility"):
        assert heading in text
    assert "LuGre (conventional)" in text and "EDM (this compensator)" in text
    assert result.sha256 in text
    # The method's paper is cited and listed; the fitness is named as the weighted eq. 8
    # with its unit; the LuGre parameters have SI units.
    from edm_sym.outputs.report.context import PAPER

    assert "the method of [1]" in text and f"References [1] {PAPER['title']}." in text
    assert "Weighted fitness (eq. 8) " in text
    lugre = text.split("Parameters of the LuGre model", 1)[1]
    for unit in ("rad/s", "N m", "rad", "N m/rad", "N m s/rad"):
        assert f" {unit} " in lugre, unit


def test_write_report_pdf_keeps_only_tex_figures_and_pdf(tmp_path: Path) -> None:
    result, kw = ugr.case_inputs(ugr.CASES[1], tmp_path / "in")
    out = tmp_path / "out"
    files = write_report(result, out, pdf=True, **kw)
    assert files[-1] == out / "steps_report.pdf" and files[-1].is_file()
    assert files[0] == out / "steps_report.tex"
    assert sorted(p.name for p in out.iterdir()) == sorted(p.name for p in files)
    for suffix in AUX_SUFFIXES:
        assert not (out / f"steps_report{suffix}").exists()


def _parameter_free():  # noqa: ANN202
    from edm_sym.core.matrix import Compensator, make_matrix
    from edm_sym.core.result import EdmResult

    m = make_matrix(ugr.INPUTS, [("omega", [("sign", 0.0), ("invert", 0.0)]),
                                 ("theta_w", [("asin", 0.0), ("through", 0.0)])])
    return EdmResult(Compensator(m, ugr.TS, {}, 10.0), "tau_ext")


@pytest.mark.parametrize("which", ["one_row", "eight_rows", "parameter_free"])
def test_one_and_eight_row_reports_compile(which: str, tmp_path: Path) -> None:
    if which == "one_row":
        case = ugr.Case("one", ugr.steps_result, logs=(), options={"prefix": "one"})
    elif which == "parameter_free":
        case = ugr.Case("free", _parameter_free, logs=("evaluation",), options={"prefix": "free"})
    else:
        case = ugr.Case("eight", ugr.eight_row_result, lugre=True, options={"prefix": "eight"})
    result, _, pdf, log = _build(case, tmp_path)
    _check_log(log)
    assert pdf.stat().st_size < PDF_LIMIT
    text = _pdftext(pdf)
    assert f"{result.compensator.matrix.n_elements} × {result.compensator.matrix.n_rows}" in text


@pytest.mark.slow
def test_pdf_is_byte_identical_when_rebuilt(tmp_path: Path) -> None:
    result, kw = ugr.case_inputs(ugr.CASES[1], tmp_path / "a")
    first = write_report(result, tmp_path / "a", pdf=True, **kw)[-1].read_bytes()
    _, kw = ugr.case_inputs(ugr.CASES[1], tmp_path / "b")
    second = write_report(result, tmp_path / "b", pdf=True, **kw)[-1].read_bytes()
    assert first == second


def test_latex_failure_names_the_error_and_keeps_the_log(tmp_path: Path) -> None:
    from edm_sym.outputs.report.pdf import LatexError

    tex = tmp_path / "x.tex"
    tex.write_text("\\documentclass{article}\\begin{document}\\undefinedmacro\\end{document}\n")
    with pytest.raises(LatexError, match=r"x\.tex: LaTeX failed: ! Undefined control sequence"):
        compile_pdf(tex)
    assert (tmp_path / "x.log").is_file() and not (tmp_path / "x.pdf").exists()


def test_shipped_example_report_compiles_and_names_its_four_terms(tmp_path: Path) -> None:
    """examples/auger/result.json with the logs and LuGre file it records (report_inputs).

    Three rows: Coulomb, viscous (whose filters also hold the inertia error, named
    with the observer's lag taken out) and the ripple.
    """
    from edm_sym.application.exporting import report_inputs

    result = edm_sym.load_result(REPO / "examples" / "auger" / "result.json")
    pdf, log = compile_pdf(write_report(result, tmp_path, **report_inputs(result))[0])
    text = _pdftext(pdf)
    described = edm_sym.describe(result, "plant:auger/evaluation").to_json()
    kinds = {t["kind"] for row in described["rows"] for t in row["terms"]}
    assert kinds == {"coulomb", "viscous", "acceleration", "spatial"}
    for kind in kinds:
        assert KIND_TITLES[kind] in text, kind
    assert "LuGre" in text


def test_earlier_example_report_compiles_and_names_the_four_terms(tmp_path: Path) -> None:
    """The shipped example of the release before (5 rows: the paper's four laws)."""
    from edm_sym.application.exporting import report_inputs

    result = edm_sym.load_result(REPO / "tests" / "golden" / "legacy_auger_result.json")
    inputs = {**report_inputs(result), "lugre": REPO / "examples" / "auger" / "lugre.json"}
    files = write_report(result, tmp_path, **inputs)
    pdf, log = compile_pdf(files[0], keep_aux=True)
    _check_log(log)
    assert pdf.stat().st_size < PDF_LIMIT
    text = _pdftext(pdf)
    model = edm_sym.decode(result)
    # The report names the rows as edm describe does on its last (evaluation) log: a
    # negligible term (row 4's offset of 0.002 N m) is not named, the flag says so.
    described = edm_sym.describe(result, "plant:auger/evaluation").to_json()
    kinds = {t["kind"] for row in described["rows"] for t in row["terms"]}
    # the four physical laws of the paper's section IV-C, in the model and in the report
    assert {"coulomb", "viscous", "acceleration", "spatial"} <= kinds
    for kind in kinds:
        assert KIND_TITLES[kind] in text, kind
    assert "negligible: term offset" in text
    for info in model.params:
        assert _as_printed(info.value) in text, info.symbol
    assert "LuGre" in text
    # The summary lists the negligible term; units in prose are set as superscripts.
    assert "Negligible rows and terms row 4: term offset (level -0.002334 N m) contributes" in text
    assert "m^2" not in text and "textasciicircum" not in text
    # Table 1's units are SI, traced along each row (pdftotext sets superscripts inline).
    table = _pdftext_lines(pdf, "Table 1: Parameters of the element matrix.")
    units = {int(m.group(1)): m.group(3).replace(" ", "") for m in
             (re.match(r"^\s*a(\d+)\s.*\s(linear|log)\s+(\S.*?)\s*$", line) for line in table) if m}
    assert units == {2: "rad/s", 4: "kgm2", 5: "s2", 6: "rad/s", 7: "Nm", 8: "rad/s", 9: "rad/s",
                     10: "–", 11: "Nm", 12: "rad/s", 13: "rad/s", 14: "rad/s", 16: "Nms/rad",
                     17: "rad", 18: "rad", 19: "samples", 20: "Nm"}
    assert "unit of the input" not in " ".join(table) and "output unit per" not in " ".join(table)


def _pdftext_lines(pdf: Path, start: str) -> list[str]:
    """The -layout lines of ``pdf`` from the line holding ``start`` to the next blank pair."""
    out = subprocess.run(["pdftotext", "-layout", str(pdf), "-"], capture_output=True, text=True,
                         check=True).stdout.splitlines()
    k = next(i for i, line in enumerate(out) if start in line)
    end = next(i for i in range(k + 2, len(out)) if not out[i].strip() and not out[i - 1].strip())
    return out[k:end]


def test_a_law_carried_by_every_row_fits_the_physics_table(tmp_path: Path,
                                                             monkeypatch: pytest.MonkeyPatch) -> None:
    """The rows column breaks its lines: a law eight rows carry, each share with its sign
    and a decimal, stays within the page (it was a fixed-width column: 15 pt over)."""
    from edm_sym.outputs.report import context

    made = context._physics

    def carried_by_all(p, model, result, runs):  # noqa: ANN001, ANN202
        out = made(p, model, result, runs)
        shares = [-123.4, 56.7, 38.9, -12.3, 45.6, 78.9, -10.1, 25.8]
        rows = ", ".join(rf"{j + 1}: {p.math(p.number(s))}\,\%" for j, s in enumerate(shares))
        law = {"kind": p.text("viscous"), "params": p.text("coefficient ") + p.math("0.001234"),
               "share": p.math("12.35") + r"\,\%", "rows": rows}
        laws = out["tables"][0]["laws"] if out["tables"] else []
        out["tables"] = [{"laws": [*laws, law]}]
        return out

    monkeypatch.setattr(context, "_physics", carried_by_all)
    case = ugr.Case("eight", ugr.eight_row_result, lugre=True, options={"prefix": "eight"})
    _, _, pdf, log = _build(case, tmp_path)
    _check_log(log)
    assert "-123.4" in _pdftext(pdf).replace("−", "-")
