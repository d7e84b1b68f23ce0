"""Golden files: fresh renders equal tests/golden/ and the committed generated/auger/, byte for byte.

Update both only with ``python tests/update_golden.py`` and review the diff.
"""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path
from types import ModuleType

import pytest

REPO = Path(__file__).resolve().parent.parent


def _update_golden() -> ModuleType:
    name = "edm_update_golden"
    if name not in sys.modules:
        spec = importlib.util.spec_from_file_location(name, REPO / "tests" / "update_golden.py")
        sys.modules[name] = module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
    return sys.modules[name]


ug = _update_golden()
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
        from edm_sym.result import dumps

        assert dumps(case.make()) == case.result_file.read_text(), f"{case.result_file} ({HINT})"
    fresh = ug.render_case(case, tmp_path)
    assert_same_files(fresh, ug.GOLDEN / case.name, skip=(case.result_file.name,))


def test_committed_generated_auger_is_up_to_date(tmp_path: Path) -> None:
    from edm_sym.cli import export_main

    assert export_main([str(ug.EXAMPLE), "--target", "all", "-o", str(tmp_path)]) == 0
    assert_same_files(list(tmp_path.iterdir()), ug.GENERATED)


def test_example_result_is_what_its_script_writes() -> None:
    spec = importlib.util.spec_from_file_location(
        "edm_auger_example", REPO / "examples" / "auger" / "make_handwritten.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    from edm_sym.result import dumps

    doc = dumps(module.build())
    committed = ug.EXAMPLE.read_text()
    # The package version is the only field allowed to move on with releases.
    strip = [line for line in doc.splitlines() if "package_version" not in line]
    assert strip == [line for line in committed.splitlines() if "package_version" not in line]
