"""What the C header and the Python module say about the inputs.

Each input with its SI unit (from its role and the result's axis) and its
expected range (the abstraction log's min/max, recorded in result.json
``logs[]``); inputs no row reads are never read (and the Python ``simulate``
does not need their columns); the elements' guards are listed.
"""

from __future__ import annotations

import importlib.util
import math
import re
import shutil
import subprocess
import warnings
from dataclasses import replace
from pathlib import Path
from types import ModuleType

import numpy as np
import pytest

from edm_sym import load_result
from edm_sym.application.exporting import export
from edm_sym.core.data import DataLog
from edm_sym.core.elements import element
from edm_sym.core.matrix import Compensator, make_matrix
from edm_sym.core.result import EdmResult, save_result
from edm_sym.engines.simulate import simulate
from edm_sym.outputs.render.inputs import NO_GUARDS, OUTSIDE_RANGE

EXAMPLE = Path(__file__).resolve().parent.parent / "examples" / "auger" / "result.json"
TS = 1e-3
N = 2000


def _log() -> DataLog:
    """A linear-axis log: position q (unused by the model), an encoder speed, an acceleration."""
    t = np.arange(N) * TS
    v = 0.4 * np.sin(2 * np.pi * 0.7 * t) + 0.05
    cols = {"t": t, "q": np.cumsum(v) * TS - 0.2, "enc_speed": v,
            "qdd": 0.4 * 2 * np.pi * 0.7 * np.cos(2 * np.pi * 0.7 * t),
            "aux": np.linspace(-3.0, 7.5, N), "F": 2.0 * np.sign(v) + 5.0 * v}
    roles = {"t": "time", "enc_speed": "velocity", "F": "target"}
    return DataLog(cols, TS, "drive.csv", "0" * 64, {}, roles)


def _result(tmp_path: Path) -> tuple[EdmResult, DataLog]:
    """Rows on enc_speed (through a limited tangent), qdd and aux; q is read by no row."""
    log = _log()
    rows = [("enc_speed", [("tan_amp", 0.6), ("gain", 0.7)]),
            ("qdd", [("gain", 0.4), ("through", 0.0)]),
            ("aux", [("gain", 0.5), ("through", 0.0)])]
    comp = Compensator(make_matrix(("q", "enc_speed", "qdd", "aux"), rows), TS, {}, N * TS)
    result = EdmResult(comp, "F", (), {"seed": None, "package_version": "test",
                                       "data_sha256": None},
                       axis="linear", logs=(log.record("abstraction"),))
    save_result(result, tmp_path / "result.json")
    return load_result(tmp_path / "result.json"), log


def _comment_text(header: str) -> str:
    """The header's opening comment as one line of words."""
    block = header[:header.index("*/")]
    return " ".join(re.sub(r"^\s*/?\*+", "", line).strip() for line in block.splitlines()).strip()


def _words(text: str) -> str:
    return " ".join(text.split())


def _module(path: Path) -> ModuleType:
    spec = importlib.util.spec_from_file_location(f"gen_{path.stem}_{abs(hash(path))}", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _rng(values: np.ndarray) -> str:
    return f"expected {format(float(values.min()), '.6g')} .. {format(float(values.max()), '.6g')}"


def _export(result: EdmResult, out: Path) -> tuple[str, ModuleType]:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        export(result, "c", out)
        export(result, "python", out)
    return (out / "edm_comp.h").read_text(), _module(out / "edm_comp.py")


def test_each_input_has_its_unit_range_and_rows_in_the_header_and_docstring(tmp_path: Path) -> None:
    result, log = _result(tmp_path)
    header, mod = _export(result, tmp_path / "out")
    c_text, py_text = _comment_text(header), _words(mod.__doc__)
    cols = log.columns
    expected = [
        f"q: position [m], {_rng(cols['q'])} (its range in drive.csv); read by no row",
        f"enc_speed: velocity [m/s], {_rng(cols['enc_speed'])} (its range in drive.csv); "
        "read by row 1",
        f"qdd: acceleration [m/s^2], {_rng(cols['qdd'])} (its range in drive.csv); read by row 2",
        # aux has no role: its unit is that of its column, not an SI unit guessed.
        f"aux: no physical role, in the unit of its log column, {_rng(cols['aux'])} "
        "(its range in drive.csv); read by row 3",
    ]
    for text in expected:
        assert text in c_text, text
        assert text in py_text, text
    # The linear axis's force unit names the output; no rotary unit appears.
    assert "a model of F [N]" in c_text and "a model of F [N]" in py_text
    assert "rad" not in c_text and "N m" not in c_text
    assert "the compensation force, a model of F [N]" in c_text
    assert "the compensation force, a model of F [N]" in py_text
    assert "torque" not in header and "torque" not in mod.__doc__
    # The index macros carry the unit and say which slot is not read.
    assert re.search(r"#define EDM_COMP_INPUT_Q 0 +/\* q \[m\], read by no row \*/", header)
    assert re.search(r"#define EDM_COMP_INPUT_ENC_SPEED 1 +/\* enc_speed \[m/s\] \*/", header)
    assert "(EDM_COMP_INPUT_Q): they need no value" in c_text
    assert mod.USED_INPUTS == ("enc_speed", "qdd", "aux") and mod.INPUTS[0] == "q"


def test_a_multi_log_result_documents_each_inputs_range_over_every_abstraction_log(
        tmp_path: Path) -> None:
    """A result abstracted from two logs learnt from both: each input's expected range is
    the union of the two logs' ranges, named by both files (before, the first log's only)."""
    result, log = _result(tmp_path)
    fast = DataLog({k: (2.0 * v if k == "enc_speed" else v) for k, v in log.columns.items()}, TS,
                   "fast.csv", "1" * 64, {}, dict(log.roles))
    logs = (log.record("abstraction"), fast.record("abstraction"), fast.record("evaluation"))
    header, mod = _export(replace(result, logs=logs), tmp_path / "two")
    both = np.concatenate([log.columns["enc_speed"], fast.columns["enc_speed"]])
    text = (f"enc_speed: velocity [m/s], {_rng(both)} (its range in drive.csv, fast.csv); "
            "read by row 1")
    assert text in _comment_text(header) and text in _words(mod.__doc__)


def test_guards_and_what_an_input_outside_its_range_does_are_documented(tmp_path: Path) -> None:
    result, _ = _result(tmp_path)
    header, mod = _export(result, tmp_path / "out")
    guard = _words(element("tan_amp").guard)
    for text in (_comment_text(header), _words(mod.__doc__)):
        assert _words(OUTSIDE_RANGE) in text
        assert "row 1, element 1, tan_amp (a_1 = " in text
        assert guard in text
        assert NO_GUARDS not in text
    # A model whose elements are all total says so.
    plain = Compensator(make_matrix(("omega",), [("omega", [("gain", 0.5)])]), TS, {}, 1.0)
    header, mod = _export(EdmResult(plain, "tau_ext", (), {"seed": None, "package_version": "t",
                                                          "data_sha256": None}),
                          tmp_path / "plain")
    assert f"Guards (what an input outside an element's domain does): {NO_GUARDS}" in \
        _comment_text(header)
    assert NO_GUARDS in _words(mod.__doc__)


def test_the_python_module_needs_no_column_of_an_input_no_row_reads(tmp_path: Path) -> None:
    result, log = _result(tmp_path)
    _, mod = _export(result, tmp_path / "out")
    cols = {k: list(v) for k, v in log.columns.items()}
    want = simulate(result, log.columns).total
    without_q = mod.simulate({k: cols[k] for k in ("enc_speed", "qdd", "aux")})
    assert np.allclose(without_q, want, rtol=0, atol=1e-9)
    assert mod.simulate(cols) == without_q
    # step() never reads the slot: a NaN there changes nothing.
    a, b = mod.Compensator(), mod.Compensator()
    for k in range(50):
        u = [cols[name][k] for name in mod.INPUTS]
        assert a.step([math.nan, *u[1:]]) == b.step(u)
    # A used column is still required.
    with pytest.raises(KeyError, match="qdd"):
        mod.simulate({k: cols[k] for k in ("enc_speed", "aux")})


def test_a_result_without_logs_says_its_ranges_are_not_recorded(tmp_path: Path) -> None:
    # An older result (the shipped example of an earlier release) predates logs[]: no range
    # is invented.
    header, mod = _export(load_result(EXAMPLE.parents[2] / "tests" / "golden"
                                      / "legacy_auger_result.json"), tmp_path)
    for text in (_comment_text(header), _words(mod.__doc__)):
        assert "theta_w: position wrapped to one revolution [rad], range not recorded; read by row 5" \
            in text
        assert "theta_uw: position [rad], range not recorded; read by no row" in text
        assert "omega: velocity [rad/s], range not recorded; read by rows 3, 4" in text
        assert "alpha: acceleration [rad/s^2], range not recorded; read by rows 1, 2" in text
        assert "a model of tau_ext [N m]" in text
    assert mod.USED_INPUTS == ("theta_w", "omega", "alpha")


HARNESS = r"""
#include <math.h>
#include <stdio.h>
#include "edm_comp.h"
int main(void)
{
    static edm_comp_state_t a, b;
    double u[EDM_COMP_NUM_INPUTS];
    int k;
    edm_comp_init(&a);
    edm_comp_init(&b);
    for (k = 0; k < %(n)d; ++k) {
        double x = 0.3 * sin(0.01 * k), ya, yb;
        u[EDM_COMP_INPUT_ENC_SPEED] = x;
        u[EDM_COMP_INPUT_QDD] = cos(0.02 * k);
        u[EDM_COMP_INPUT_AUX] = 0.001 * k;
        u[EDM_COMP_INPUT_Q] = NAN;
        ya = edm_comp_step(&a, u, NULL);
        u[EDM_COMP_INPUT_Q] = 0.0;
        yb = edm_comp_step(&b, u, NULL);
        if (ya != yb || ya != ya) return 1;
    }
    return 0;
}
"""


@pytest.mark.toolchain
@pytest.mark.skipif(not shutil.which("gcc"), reason="gcc is not installed")
def test_the_c_step_never_reads_the_slot_of_an_input_no_row_reads(tmp_path: Path) -> None:
    result, _ = _result(tmp_path)
    _export(result, tmp_path)
    (tmp_path / "main.c").write_text(HARNESS % {"n": 500})
    subprocess.run(["gcc", "-std=c99", "-O1", "-o", "prog", "main.c", "edm_comp.c", "-lm"],
                   cwd=tmp_path, check=True, capture_output=True)
    assert subprocess.run([str(tmp_path / "prog")], cwd=tmp_path).returncode == 0


def test_export_builds_the_model_on_the_results_axis(tmp_path: Path, monkeypatch) -> None:
    """The C/Python model is built with the linear axis, not a rotary default."""
    import edm_sym.application.exporting as exporting
    from edm_sym.engines.symbolic import build_model
    from edm_sym.outputs.render import render

    result, _ = _result(tmp_path)
    seen = []

    def spy(res, target, **kw):  # noqa: ANN001, ANN202
        seen.append(kw["model"].axis)
        return render(res, target, **kw)

    monkeypatch.setattr(exporting, "render", spy)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        header = (export(result, "c", tmp_path / "out")[0]).read_text()
    assert seen == ["linear"]
    comment = _comment_text(header)
    assert "[N]" in comment and "[m/s]" in comment
    assert "N m" not in comment and "rad/s" not in comment
    # A model of another axis than the result's is refused, not printed with the wrong units.
    with pytest.raises(ValueError, match=r"model: axis: expected 'linear' as in result.json, found 'rotary'"):
        render(result, "c", model=build_model(result.compensator))
