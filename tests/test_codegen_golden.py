"""Golden files: fresh renders equal tests/golden/ and the committed generated/auger/, byte for byte.

Update both only with ``python tests/update_golden.py`` and review the diff.
"""

from __future__ import annotations

import importlib.util
import re
import sys
from pathlib import Path
from types import ModuleType

import pytest

REPO = Path(__file__).resolve().parent.parent


def _script(name: str) -> ModuleType:
    """Import tests/<name>.py (the explicit golden-update scripts) as a module."""
    key = f"edm_{name}"
    if key not in sys.modules:
        spec = importlib.util.spec_from_file_location(key, REPO / "tests" / f"{name}.py")
        sys.modules[key] = module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
    return sys.modules[key]


ug = _script("update_golden")


HINT = "run `python tests/update_golden.py` if the change is intended, and review the diff"


def assert_same_files(fresh: list[Path], folder: Path, skip: tuple[str, ...] = ()) -> None:
    expected = sorted(p.name for p in folder.iterdir() if p.name not in skip)
    assert sorted(p.name for p in fresh) == expected, f"{folder}: other files ({HINT})"
    for path in fresh:
        assert path.read_bytes() == (folder / path.name).read_bytes(), \
            f"{folder / path.name} differs from a fresh render ({HINT})"


@pytest.mark.parametrize("case", ug.CASES, ids=[c.name for c in ug.CASES])
def test_golden(case, tmp_path: Path) -> None:  # noqa: ANN001
    if case.make is not None:  # the generated result file is golden too
        from edm_sym.core.result import dumps

        assert dumps(case.make()) == case.result_file.read_text(), f"{case.result_file} ({HINT})"
    fresh = ug.render_case(case, tmp_path)
    assert_same_files(fresh, ug.GOLDEN / case.name, skip=(case.result_file.name,))


def _recorded_version(tex: str, package: str) -> str | None:
    match = re.search(rf"^{re.escape(package)} & ([^ ]+) \\\\$", tex, re.MULTILINE)
    return match.group(1) if match else None


def test_committed_generated_auger_is_up_to_date(tmp_path: Path) -> None:
    """``edm-export examples/auger/result.json --target all`` reproduces generated/auger/.

    Code is compared byte for byte; the report's .tex byte for byte once the
    dependency versions it records are blanked (they are the installing
    machine's); the figures byte for byte when this matplotlib is the one that
    drew them. The compiled PDF (made with --pdf) is checked by the report tests.
    """
    from importlib.metadata import version

    from edm_sym.application.cli import export_main

    normalize = _script("update_golden_report").normalize
    assert export_main([str(ug.EXAMPLE), "--target", "all", "-o", str(tmp_path)]) == 0
    committed = sorted(p.name for p in ug.GENERATED.iterdir() if p.name != "edm_comp_report.pdf")
    assert sorted(p.name for p in tmp_path.iterdir()) == committed, f"other files ({HINT})"
    tex = (ug.GENERATED / "edm_comp_report.tex").read_text()
    same_matplotlib = _recorded_version(tex, "matplotlib") == version("matplotlib")
    for name in committed:
        fresh, old = (tmp_path / name).read_bytes(), (ug.GENERATED / name).read_bytes()
        if name.endswith(".tex"):
            assert normalize(fresh.decode()) == normalize(old.decode()), f"{name} differs ({HINT})"
        elif name.endswith(".pdf"):
            assert fresh.startswith(b"%PDF") and old.startswith(b"%PDF")
            if same_matplotlib:
                assert fresh == old, f"{name} differs ({HINT})"
        else:
            assert fresh == old, f"{name} differs from a fresh render ({HINT})"


def test_handwritten_fixture_is_what_its_script_writes() -> None:
    spec = importlib.util.spec_from_file_location(
        "edm_handwritten", REPO / "tests" / "make_handwritten_result.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    from edm_sym.core.result import dumps

    doc = dumps(module.build())
    committed = (REPO / "tests" / "data" / "handwritten_result.json").read_text()
    # The package version is the only field allowed to move on with releases.
    strip = [line for line in doc.splitlines() if "package_version" not in line]
    assert strip == [line for line in committed.splitlines() if "package_version" not in line]
