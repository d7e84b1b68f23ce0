"""Reprs: one line per row for results and decoded models; LaTeX for notebooks."""

from __future__ import annotations

from pathlib import Path

import edm_sym
from edm_sym.engines.symbolic.model import build_model

ROOT = Path(__file__).resolve().parents[1]


def _result() -> edm_sym.EdmResult:
    m = edm_sym.make_matrix(["omega", "alpha"], [
        ("omega", [("sign", 0), ("gain", 0.8), ("through", 0)]),
        ("alpha", [("gain", 0.6), ("lpf", 0.5), ("through", 0)]),
    ])
    return edm_sym.EdmResult(edm_sym.Compensator(m, 1e-3, {}), "tau_ext", fitness=0.0421)


def test_a_result_shows_one_line_per_row() -> None:
    res = _result()
    comp = res.compensator
    gain, lpf = (comp.value(comp.matrix.rows[j].genes[i]) for j, i in ((0, 1), (1, 1)))
    lines = repr(res).splitlines()
    assert lines[0] == ("EdmResult(target 'tau_ext', inputs omega, alpha, 3x2 matrix, "
                        "Ts = 0.001 s, fitness 0.0421 N m)")
    assert lines[1:] == [f"  row 1: omega -> sign -> gain({gain:.4g})",
                         f"  row 2: alpha -> gain({comp.value(comp.matrix.rows[1].genes[0]):.4g})"
                         f" -> lpf({lpf:.4g} rad/s)"]


def test_the_shipped_result_fits_on_a_screen() -> None:
    res = edm_sym.load_result(ROOT / "examples" / "auger" / "result.json")
    lines = repr(res).splitlines()
    assert len(lines) == 1 + len(res.matrix.rows) and max(map(len, lines)) < 120
    # Four inputs by name would make the header too wide: their number (rows name theirs).
    m, n = len(res.matrix.rows), len(res.matrix.rows[0].genes)  # shown n x m, as the paper
    assert lines[0].startswith(f"EdmResult(target 'tau_ext', 4 inputs, {n}x{m} matrix")
    assert "through" not in repr(res)
    # Each row: its input by name, then its stages.
    for i, (line, row) in enumerate(zip(lines[1:], res.matrix.rows, strict=True), start=1):
        assert line.startswith(f"  row {i}: {res.matrix.inputs[row.input]} -> "), line
    legacy = edm_sym.load_result(ROOT / "tests" / "golden" / "legacy_auger_result.json")
    legacy_lines = repr(legacy).splitlines()
    assert max(map(len, legacy_lines)) < 120 and "shift(5.879 samples)" in legacy_lines[5]
    assert "inputs theta_w, theta_uw, omega, alpha" in legacy_lines[0]


def test_a_decoded_model_shows_each_row_expression() -> None:
    res = _result()
    model = edm_sym.decode(res, classify=False, systems=False)
    lines = repr(model).splitlines()
    assert lines[0] == "SymbolicModel(2 rows, inputs omega, alpha, Ts = 0.001 s, target 'tau_ext')"
    assert lines[1].startswith("  row 1 (omega): ") and "sign(omega)" in lines[1]
    assert lines[2].startswith("  row 2 (alpha): LTI(alpha, ")
    # A stages-only model shows the elements instead of expressions.
    assert repr(build_model(res.compensator)).splitlines()[1:] == repr(res).splitlines()[1:]


def test_latex_for_notebooks_has_one_line_per_row_and_the_sum() -> None:
    res = _result()
    for shown in (res._repr_latex_(), edm_sym.decode(res)._repr_latex_(),
                  build_model(res.compensator)._repr_latex_()):
        assert shown.startswith("$$\\begin{aligned}") and shown.endswith("\\end{aligned}$$")
        rows = shown.split(r" \\ ")
        assert [r.split(" &= ")[0].removeprefix("$$\\begin{aligned}") for r in rows] == [
            "y_{1}", "y_{2}", r"\tau_{\mathrm{cmp}}"]
        assert rows[-1].startswith(r"\tau_{\mathrm{cmp}} &= y_{1} + y_{2}")
        assert r"\operatorname{sgn}\left(\omega\right)" in rows[0]
        assert shown.count("{") == shown.count("}")
