"""Packaging of the code generator: templates ship inside the wheel as edm_sym/templates."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parent.parent

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    tomllib = pytest.importorskip("tomli")


def setuptools_config() -> dict:
    return tomllib.loads((REPO / "pyproject.toml").read_text())["tool"]["setuptools"]


def test_templates_are_mapped_into_the_package() -> None:
    cfg = setuptools_config()
    assert cfg["package-dir"]["edm_sym.templates"] == "templates"
    assert "edm_sym.templates" in cfg["packages"]
    assert "*.j2" in cfg["package-data"]["edm_sym.templates"]
    assert (REPO / "templates" / "c_source.c.j2").is_file()


def test_every_subpackage_is_listed() -> None:
    """The package list is explicit (see pyproject.toml); a new subpackage must join it."""
    listed = set(setuptools_config()["packages"])
    found = {".".join(p.parent.relative_to(REPO).parts)
             for p in (REPO / "edm_sym").rglob("__init__.py")}
    missing = sorted(found - listed)
    assert not missing, f"pyproject.toml [tool.setuptools] packages: add {missing}"


@pytest.mark.slow
def test_wheel_holds_the_templates(tmp_path: Path) -> None:
    import subprocess
    import zipfile

    proc = subprocess.run([sys.executable, "-m", "pip", "wheel", str(REPO), "--no-deps",
                           "-w", str(tmp_path), "-q"], capture_output=True, text=True)
    if proc.returncode != 0:
        pytest.skip(f"cannot build a wheel here: {proc.stderr.strip()[-200:]}")
    (wheel,) = tmp_path.glob("edm_sym-*.whl")
    names = set(zipfile.ZipFile(wheel).namelist())
    for t in ("c_header.h.j2", "c_source.c.j2", "python_module.py.j2"):
        assert f"edm_sym/templates/{t}" in names
    assert "edm_sym/schema/result.schema.json" in names
