"""The layers of docs/architecture.md, checked: imports point down only.

The import-linter contracts live in pyproject.toml ([tool.importlinter]);
this test runs them, and checks that no module imports the package face.
"""

from __future__ import annotations

from pathlib import Path

import pytest

importlinter = pytest.importorskip("importlinter", reason="pip install -e .[test]")

REPO = Path(__file__).resolve().parents[1]


def test_the_import_linter_contracts_are_kept(monkeypatch: pytest.MonkeyPatch,
                                              capsys: pytest.CaptureFixture[str]) -> None:
    from importlinter.cli import lint_imports

    monkeypatch.chdir(REPO)
    status = lint_imports(config_filename=str(REPO / "pyproject.toml"), no_cache=True)
    out = capsys.readouterr().out
    assert status == 0, out
    assert "0 broken" in out and "Layers point down" in out


def test_no_module_imports_the_package_face() -> None:
    # edm_sym/__init__.py is the application's face: it imports the layers, never the reverse.
    import grimp

    graph = grimp.build_graph("edm_sym")
    # The scikit-learn face (EDMRegressor) stands beside the package face and calls its public API.
    importers = sorted(set(graph.find_modules_that_directly_import("edm_sym")) - {"edm_sym.estimator"})
    assert importers == [], f"these modules import edm_sym itself: {importers}"


def test_every_top_level_module_has_a_layer() -> None:
    import pkgutil
    import sys

    import edm_sym

    if sys.version_info >= (3, 11):
        import tomllib
    else:  # pragma: no cover
        import tomli as tomllib

    cfg = tomllib.loads((REPO / "pyproject.toml").read_text("utf-8"))["tool"]["importlinter"]
    layers = next(c for c in cfg["contracts"] if c["type"] == "layers")["layers"]
    named = {m.strip() for layer in layers for m in layer.replace("|", ":").split(":")}
    found = {f"edm_sym.{m.name}" for m in pkgutil.iter_modules(edm_sym.__path__)}
    found -= {"edm_sym.schema", "edm_sym.templates"}  # data folders, no code
    assert sorted(found - named) == [], "pyproject.toml [tool.importlinter]: give these a layer"
