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
    importers = set(graph.find_modules_that_directly_import("edm_sym"))
    importers = sorted(importers - {"edm_sym.application.estimator"})
    assert importers == [], f"these modules import edm_sym itself: {importers}"


def test_no_two_modules_import_each_other() -> None:
    # Over the whole package. Type-checking imports count too: a module whose types come
    # from one that imports it is read in a loop all the same; so do imports inside functions.
    import grimp

    graph = grimp.build_graph("edm_sym", exclude_type_checking_imports=False)
    modules = sorted(m for m in graph.modules if m.startswith("edm_sym."))
    cycles = [(a, b) for a in modules for b in sorted(graph.find_modules_directly_imported_by(a))
              if b.startswith("edm_sym.") and b != a and graph.chain_exists(importer=b, imported=a)]
    assert cycles == [], f"these modules import each other, directly or not: {cycles}"


def test_every_module_sits_in_a_layer_folder_and_has_a_layer() -> None:
    # The folder layout shows the layers (docs/architecture.md): edm_sym/{core,engines,outputs,application}.
    import pkgutil
    import sys

    import edm_sym

    if sys.version_info >= (3, 11):
        import tomllib
    else:  # pragma: no cover
        import tomli as tomllib

    # __main__ is `python -m edm_sym`; schema and templates are data folders, no code.
    top = {m.name for m in pkgutil.iter_modules(edm_sym.__path__)} - {"schema", "templates"}
    assert top == {"core", "engines", "outputs", "application", "__main__"}
    cfg = tomllib.loads((REPO / "pyproject.toml").read_text("utf-8"))["tool"]["importlinter"]
    inner = next(c for c in cfg["contracts"] if c["name"].startswith("Layers point down inside"))
    named = {m.strip() for layer in inner["layers"] for m in layer.replace("|", ":").split(":")}
    found = {f"edm_sym.{folder}.{m.name}" for folder in ("core", "engines", "outputs", "application")
             for m in pkgutil.iter_modules([str(Path(edm_sym.__file__).parent / folder)])}
    assert sorted(found - named) == [], "pyproject.toml [tool.importlinter]: give these a layer"


def test_no_module_outside_the_elements_branches_on_an_element_kind_or_name() -> None:
    # docs/architecture.md: consumers dispatch on the realisation's type or ask an element's
    # traits (is_static, is_delay, is_identity, multiplies_output, ...); no module outside
    # core/elements compares an element's or a stage's `kind` or `name` with a string naming
    # a stage kind ("static", "linear", "delay", "relay") or an element ("through", ...).
    import ast

    from edm_sym.core.elements import all_elements
    from edm_sym.core.elements.realisation import Realisation

    words = {el.name for el in all_elements()}
    words |= {cls.kind for cls in Realisation.__subclasses__()}
    assert {"static", "linear", "delay", "relay", "through", "tan_phase"} <= words

    def strings(node: ast.AST) -> set[str]:
        if isinstance(node, ast.Constant) and isinstance(node.value, str):
            return {node.value}
        if isinstance(node, ast.Tuple | ast.List | ast.Set):
            return set().union(*(strings(e) for e in node.elts))
        return set()

    root = REPO / "edm_sym"
    found = []
    for path in sorted(root.rglob("*.py")):
        if (root / "core" / "elements") in path.parents:
            continue
        for node in ast.walk(ast.parse(path.read_text("utf-8"))):
            if not isinstance(node, ast.Compare):
                continue
            sides = [node.left, *node.comparators]
            named = any(isinstance(s, ast.Attribute) and s.attr in ("kind", "name") for s in sides)
            if named and any(strings(s) & words for s in sides):
                found.append(f"{path.relative_to(REPO)}:{node.lineno}: {ast.unparse(node)}")
    assert found == [], "ask the element's traits (core/elements/base.py) instead:\n" + "\n".join(found)


def test_no_function_runs_past_about_100_lines_without_saying_why() -> None:
    # STYLE.md: a long function is split into named steps, or its docstring says why
    # ("... on purpose: ..."). Counted without the docstring: numpydoc sections are not code.
    import ast

    found = []
    for path in sorted((REPO / "edm_sym").rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text("utf-8"))):
            if not isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                continue
            doc = ast.get_docstring(node) or ""
            body = node.body[1:] if doc else node.body
            lines = body[-1].end_lineno - body[0].lineno + 1 if body else 0
            if lines > 100 and "on purpose" not in doc:
                found.append(f"{path.relative_to(REPO)}:{node.lineno} {node.name}: {lines} lines")
    assert found == [], "split these into named steps, or say why in the docstring:\n" + \
        "\n".join(found)
