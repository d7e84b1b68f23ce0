"""Rendering: export targets, options, contexts, determinism, templates without logic."""

from __future__ import annotations

import hashlib
import os
import re
import subprocess
import sys
import warnings
from pathlib import Path

import pytest

# tests/ is on sys.path (pytest's rootdir-relative import mode): the shared harness.
from firmware import cg_support as cg  # noqa: E402
from hypothesis import given, settings
from hypothesis import strategies as st

from edm_sym import load_result
from edm_sym.application.exporting import export
from edm_sym.core.elements import all_elements
from edm_sym.core.errors import NumericsWarning
from edm_sym.core.matrix import Compensator, ElementMatrix, Gene, Row, make_matrix
from edm_sym.engines.symbolic.model import build_model
from edm_sym.outputs.render import TARGETS, render
from edm_sym.outputs.render.context import c_context, input_macros, plan, source_of
from edm_sym.outputs.render.environment import environment, template_dir
from edm_sym.outputs.render.writer import OutputError, write_files

# The hand-written fixture: these tests assert its known rows (the shipped example may change).
EXAMPLE = load_result(cg.HANDWRITTEN)


def comp_of(rows) -> Compensator:  # noqa: ANN001
    return Compensator(make_matrix(cg.INPUTS, rows), 1e-3, {}, 20.0)


# -- targets and options -------------------------------------------------------------
@pytest.mark.parametrize(("target", "names"), [
    ("c", ["edm_comp.h", "edm_comp.c"]),
    ("python", ["edm_comp.py"]),
    ("all", ["edm_comp.h", "edm_comp.c", "edm_comp.py"]),
])
def test_targets_write_their_files(target: str, names: list[str], tmp_path: Path) -> None:
    out = tmp_path / "new" / "dir"
    written = export(EXAMPLE, target, out)
    assert [p.name for p in written][: len(names)] == names
    if target == "all":  # then the report: its .tex and figures
        assert "edm_comp_report.tex" in [p.name for p in written[len(names):]]
    else:
        assert len(written) == len(names)
    assert sorted(p.name for p in out.iterdir()) == sorted(p.name for p in written)
    for p in written:
        assert p.stat().st_mode & 0o444 == 0o444  # readable like any file, not 0600


def test_target_all_builds_the_code_model_once_and_the_report_decodes_once(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    import edm_sym.application.exporting
    import edm_sym.engines.symbolic
    import edm_sym.outputs.report
    from edm_sym.engines.symbolic import decoding

    calls: dict[str, list] = {"decode": [], "build": [], "render": [], "report": []}

    def spy(key, fn):  # noqa: ANN001, ANN202
        def wrapped(*args, **kwargs):  # noqa: ANN002, ANN003, ANN202
            out = fn(*args, **kwargs)
            calls[key].append(kwargs.get("model", out))
            return out
        return wrapped

    symbolic, exporting = edm_sym.engines.symbolic, edm_sym.application.exporting
    report = edm_sym.outputs.report
    monkeypatch.setattr(symbolic, "decode", spy("decode", symbolic.decode))
    monkeypatch.setattr(decoding, "build_model", spy("build", decoding.build_model))
    monkeypatch.setattr(symbolic, "build_model", spy("build", symbolic.build_model))
    monkeypatch.setattr(exporting, "render", spy("render", exporting.render))
    monkeypatch.setattr(report, "write_report", spy("report", report.write_report))
    export(EXAMPLE, "all", tmp_path)
    # The code targets share one model of the stages they need; the report decodes the
    # whole model once itself, with the classifier options of the data it judges (as
    # `edm describe` does), so the export hands it none.
    # (decode builds its own stages: the second build.)
    assert len(calls["build"]) == 2 and len(calls["decode"]) == 1 and len(calls["report"]) == 1
    assert calls["render"] == [calls["build"][0]]


def test_prefix_names_files_and_symbols(tmp_path: Path) -> None:
    written = export(EXAMPLE, "all", tmp_path, prefix="axis2_comp")
    assert [p.name for p in written][:3] == ["axis2_comp.h", "axis2_comp.c", "axis2_comp.py"]
    assert "axis2_comp_report.tex" in [p.name for p in written]
    header = (tmp_path / "axis2_comp.h").read_text()
    assert "#define AXIS2_COMP_INPUT_OMEGA 2" in header
    assert "typedef double axis2_comp_real_t;" in header
    assert "} axis2_comp_state_t;" in header
    assert "void axis2_comp_init(axis2_comp_state_t *s);" in header
    assert "edm_comp" not in header + (tmp_path / "axis2_comp.c").read_text()


def test_latex_target_is_the_report(tmp_path: Path) -> None:
    written = export(EXAMPLE, "latex", tmp_path / "x")
    assert written[0].name == "edm_comp_report.tex"
    assert all(p.name.startswith("edm_comp_") for p in written)
    assert "latex" not in TARGETS  # written by edm_sym.outputs.report, not by a code template


@pytest.mark.parametrize(("kwargs", "message"), [
    ({"prefix": "9x"}, "prefix: expected a C identifier, found '9x'"),
    ({"prefix": "my-comp"}, "prefix: expected a C identifier, found 'my-comp'"),
    ({"prefix": "static"}, "prefix: expected a C identifier, found 'static'"),
    ({"real": "half"}, "real: expected one of float, double, q31, q15, found 'half'"),
])
def test_bad_options_are_one_line_value_errors(kwargs: dict, message: str, tmp_path: Path) -> None:
    with pytest.raises(ValueError) as info:
        export(EXAMPLE, "c", tmp_path / "x", **kwargs)
    assert str(info.value) == message
    assert not (tmp_path / "x").exists()


def test_bad_target(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match=r"^target: expected one of c, python, latex, test, all"):
        export(EXAMPLE, "rust", tmp_path)


def test_unwritable_output_is_an_output_error(tmp_path: Path) -> None:
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    with pytest.raises(OutputError, match="cannot create the output folder"):
        write_files(blocker / "sub", {"a.c": "x"})


# -- content ----------------------------------------------------------------------------
def test_header_names_source_format_and_discretisation(tmp_path: Path) -> None:
    export(EXAMPLE, "c", tmp_path)
    header = (tmp_path / "edm_comp.h").read_text()
    digest = hashlib.sha256(cg.HANDWRITTEN.read_bytes()).hexdigest()
    assert f"sha256 {digest}" in header
    assert "edm-result version 1" in header
    assert "row 3, element 1, derivative (a_9 = 1): backward difference" in header
    assert "row 3, element 2, lpf (a_10 = 100): Tustin (bilinear)" in header
    assert "row 1: omega -> sign -> gain (a_2 = 0.95) -> through -> through" in header
    for line in ("#define EDM_COMP_NUM_INPUTS 3", "#define EDM_COMP_NUM_ROWS 4",
                 "#define EDM_COMP_SAMPLE_TIME 0.001", "#define EDM_COMP_INPUT_THETA_W 0",
                 "#define EDM_COMP_INPUT_THETA_UW 1", "#define EDM_COMP_INPUT_OMEGA 2"):
        assert line in header
    assert f"sha256 {digest}" in (tmp_path / "edm_comp.c").read_text()


def test_c_includes_only_the_allowed_headers(tmp_path: Path) -> None:
    export(EXAMPLE, "c", tmp_path)
    text = (tmp_path / "edm_comp.h").read_text() + (tmp_path / "edm_comp.c").read_text()
    includes = set(re.findall(r"#include\s+(\S+)", text))
    assert includes <= {"<math.h>", "<stddef.h>", "<stdint.h>", '"edm_comp.h"'}
    assert not re.search(r"\b(malloc|calloc|realloc|free)\s*\(", text)
    assert not re.search(r"^\s*static\s+(?!inline)", text, re.M)  # no static data


def test_ring_buffers_are_sized_by_the_decoded_delay() -> None:
    comp = comp_of([("omega", [("dead_time", 0.2), ("shift", 0.5), ("shift", 0.0)])])
    model = build_model(comp)
    delays = [st.delay for st in model.rows[0].stages]
    ctx = c_context(model, source_of(cg.as_result(comp)))
    members = "\n".join(ctx["members"])
    assert f"r1_e1_buf[{delays[0]}]" in members
    assert f"r1_e2_buf[{delays[1]}]" in members
    assert "r1_e3_buf[1]" in members and "r1_e3_pos" not in members  # one cell, no index
    assert delays[0] < 20_000  # not the largest possible delay


def test_a_stateless_compensator_has_a_placeholder_member() -> None:
    comp = comp_of([("omega", [("gain", 0.6), ("sign", 0.0)])])
    ctx = c_context(build_model(comp), source_of(cg.as_result(comp)))
    assert ctx["members"][0].startswith("uint8_t unused;")
    assert ctx["step_unused"] == ["(void)s;"]


def test_input_macros_are_upper_cased_and_unique() -> None:
    assert input_macros("edm_comp", ("theta_w", "d.q")) == ("EDM_COMP_INPUT_THETA_W",
                                                            "EDM_COMP_INPUT_D_Q")
    with pytest.raises(ValueError, match="both become the C macro EDM_COMP_INPUT_A_B"):
        input_macros("edm_comp", ("a-b", "a_b"))


def test_plan_summarises_rows() -> None:
    rows = plan(build_model(EXAMPLE.compensator), "edm_comp")
    assert [r.input_macro for r in rows] == ["EDM_COMP_INPUT_OMEGA"] * 3 + ["EDM_COMP_INPUT_THETA_W"]
    assert [sp.kind for sp in rows[2].stages] == ["linear", "linear", "static", "static"]


def test_single_precision_warns_about_sensitive_filters(tmp_path: Path) -> None:
    sensitive = comp_of([("omega", [("notch", 0.3)])])  # notch at 5 rad/s, Ts = 1 ms
    with pytest.warns(NumericsWarning, match=r"rows\[0\]\.elements\[0\] \(notch"):
        render(cg.as_result(sensitive), "c", real="float")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        render(cg.as_result(sensitive), "c", real="double")
        render(EXAMPLE, "c", real="float")


# -- determinism ------------------------------------------------------------------------
def test_output_is_byte_identical_across_runs_and_processes(tmp_path: Path) -> None:
    first = render(EXAMPLE, "all")
    assert render(EXAMPLE, "all") == first
    code = ("import sys, edm_sym; from edm_sym.outputs.render import render; "
            f"files = render(edm_sym.load_result({str(cg.HANDWRITTEN)!r}), 'all'); "
            "sys.stdout.write(''.join(files[k] for k in sorted(files)))")
    outs = []
    for seed in ("1", "2"):
        env = dict(os.environ, PYTHONHASHSEED=seed)
        outs.append(subprocess.run([sys.executable, "-c", code], env=env, check=True,
                                   capture_output=True, text=True).stdout)
    assert outs[0] == outs[1] == "".join(first[k] for k in sorted(first))


def test_no_timestamps_or_paths(tmp_path: Path) -> None:
    text = "".join(render(EXAMPLE, "all").values())
    assert not re.search(r"20\d\d-\d\d-\d\d", text)
    assert str(cg.REPO) not in text


# -- the rendering layer's shape ------------------------------------------------------------
def test_templates_hold_no_logic_beyond_loops() -> None:
    folder = template_dir()
    names = sorted(p.name for p in folder.glob("*.j2"))
    assert {"c_header.h.j2", "c_source.c.j2", "python_module.py.j2"} <= set(names)
    for name in names:
        tags = re.findall(r"{%-?\s*(\w+)", (folder / name).read_text())
        assert set(tags) <= {"for", "endfor", "raw", "endraw"}, f"{name}: {sorted(set(tags))}"


def test_every_table_template_exists_and_environment_is_strict() -> None:
    import jinja2

    env = environment()
    assert env.undefined is jinja2.StrictUndefined
    assert env.autoescape is False and env.keep_trailing_newline
    for target in TARGETS.values():
        for out in target.outputs:
            env.get_template(out.template)
    with pytest.raises(jinja2.UndefinedError):
        env.get_template("c_header.h.j2").render({})


def test_only_the_render_layer_imports_jinja2() -> None:
    import ast

    package = Path(__file__).resolve().parent.parent / "edm_sym"
    for path in package.rglob("*.py"):
        if "render" in path.relative_to(package).parts:
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            names = ([a.name for a in node.names] if isinstance(node, ast.Import)
                     else [node.module or ""] if isinstance(node, ast.ImportFrom) else [])
            assert not any(n.split(".")[0] == "jinja2" for n in names), f"{path} imports jinja2"


def test_a_result_without_a_file_is_named_by_its_canonical_bytes(tmp_path: Path) -> None:
    from edm_sym.core.result import save_result

    result = cg.as_result(comp_of([("omega", [("lpf", 0.4), ("sign", 0.0)])]))
    fresh = render(result, "c")["edm_comp.h"]
    path = save_result(result, tmp_path / "result.json")
    assert render(load_result(path), "c")["edm_comp.h"] == fresh
    assert hashlib.sha256(path.read_bytes()).hexdigest() in fresh


GENES = st.integers(1, 4).flatmap(lambda n: st.lists(
    st.tuples(st.integers(0, 2), st.lists(
        st.tuples(st.sampled_from([e.code for e in all_elements()]), st.floats(0.0, 1.0)),
        min_size=n, max_size=n)),
    min_size=1, max_size=4))


@pytest.mark.filterwarnings("ignore::edm_sym.core.errors.NumericsWarning")
@settings(max_examples=40, deadline=None)
@given(rows=GENES, real=st.sampled_from(["double", "float"]))
def test_any_valid_matrix_renders_valid_python_and_plausible_c(rows: list, real: str) -> None:
    matrix = ElementMatrix(cg.INPUTS, tuple(
        Row(inp, tuple(Gene(c, p) for c, p in genes)) for inp, genes in rows))
    files = render(cg.as_result(Compensator(matrix, 1e-3, {}, 20.0)), "all", real=real)
    compile(files["edm_comp.py"], "edm_comp.py", "exec")
    source = files["edm_comp.c"]
    assert source.count("{") == source.count("}")
    assert f"r[{len(rows) - 1}] = x;" in source


def test_a_failed_write_is_an_output_error(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    import edm_sym.outputs.render.writer as writer

    def refuse(path, data):  # noqa: ANN001, ANN202
        raise PermissionError(13, "Permission denied")

    monkeypatch.setattr(writer, "write_atomic", refuse)
    with pytest.raises(OutputError, match=r"edm_comp\.h: cannot write the file \(Permission denied\)"):
        export(EXAMPLE, "c", tmp_path)
