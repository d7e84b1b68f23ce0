"""Documentation: generated docs are current; every public function is documented."""

from __future__ import annotations

import importlib
import inspect
import pkgutil
from pathlib import Path

import edm_sym
from edm_sym.elements import doc

ROOT = Path(__file__).resolve().parents[1]


def test_elements_doc_is_current() -> None:
    committed = (ROOT / "docs" / "elements.md").read_text()
    assert committed == doc.render(), (
        "docs/elements.md is stale: run python -m edm_sym.elements.doc docs/elements.md"
    )


def test_elements_doc_lists_every_element() -> None:
    text = doc.render()
    for el in edm_sym.elements.all_elements():
        assert f"### {el.code} `{el.name}`" in text


def _public_modules():
    for info in pkgutil.walk_packages(edm_sym.__path__, "edm_sym."):
        if any(part.startswith("_") for part in info.name.split(".")[1:]):
            continue
        try:
            yield importlib.import_module(info.name)
        except ImportError:  # optional extras (dask ...) not installed
            continue


def test_every_public_function_is_documented() -> None:
    missing = []
    for name in edm_sym.__all__:
        obj = getattr(edm_sym, name)
        if (inspect.isfunction(obj) or inspect.isclass(obj)) and not inspect.getdoc(obj):
            missing.append(f"edm_sym.{name}")
    for mod in _public_modules():
        for name, obj in vars(mod).items():
            if name.startswith("_") or getattr(obj, "__module__", None) != mod.__name__:
                continue
            if inspect.isfunction(obj) and not obj.__doc__:
                missing.append(f"{mod.__name__}.{name}")
    assert not missing, f"undocumented public functions: {missing}"
