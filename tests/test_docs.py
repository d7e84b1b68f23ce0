"""Documentation: generated docs are current; every public function is documented."""

from __future__ import annotations

import argparse
import importlib
import inspect
import json
import os
import pkgutil
import re
from pathlib import Path

import pytest

import edm_sym
from edm_sym.application.cli import build_parser
from edm_sym.core.elements import doc

ROOT = Path(__file__).resolve().parents[1]


def test_elements_doc_is_current() -> None:
    committed = (ROOT / "docs" / "elements.md").read_text()
    assert committed == doc.render(), (
        "docs/elements.md is stale: run python -m edm_sym.core.elements.doc docs/elements.md"
    )


def test_elements_doc_lists_every_element() -> None:
    text = doc.render()
    for el in edm_sym.core.elements.all_elements():
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


# --- The contract lives in docs/: every reference resolves, every field is described ---

#: Files whose text may point at documentation.
_SCANNED = {".py", ".md", ".j2", ".toml"}
#: A bare repository path to a doc page, optionally with an anchor: docs/cli.md#exit-status.
_DOC_REF = re.compile(r"(?<![\w/.-])(docs/[\w./-]+?\.md)(#[\w-]+)?")
#: A Markdown link target: [text](target).
_MD_LINK = re.compile(r"\]\(([^)\s]+)\)")
#: References to the contract document that users never had (built so this file does not match).
_GONE = re.compile(r"contract" + r"\.md|contract,? sections? \d", re.IGNORECASE)
_FENCE = re.compile(r"^(```|~~~).*?^\1[^\n]*$", re.MULTILINE | re.DOTALL)


def _repo_files(root: Path):
    for dirpath, dirnames, filenames in os.walk(root):
        dirnames[:] = sorted(d for d in dirnames if not d.startswith((".", "__"))
                             and d not in ("build", "dist") and not d.endswith(".egg-info"))
        for name in sorted(filenames):
            if Path(name).suffix in _SCANNED:
                yield Path(dirpath) / name


def _slug(heading: str) -> str:
    """GitHub's anchor of a heading: link text kept, punctuation dropped, spaces to hyphens."""
    text = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", heading.strip()).lower()
    return re.sub(r"[^\w\- ]", "", text).replace(" ", "-")


def _anchors(page: Path) -> set[str]:
    text = _FENCE.sub("", page.read_text("utf-8"))
    found: set[str] = set(re.findall(r"<a (?:id|name)=\"([^\"]+)\"", text))
    counts: dict[str, int] = {}
    for heading in re.findall(r"^#{1,6}\s+(.+?)\s*#*\s*$", text, re.MULTILINE):
        slug = _slug(heading)
        n = counts.get(slug, 0)
        counts[slug] = n + 1
        found.add(slug if n == 0 else f"{slug}-{n}")
    return found


def _reference_problems(root: Path) -> list[str]:
    """Every reference to a missing doc file or anchor, and every contract reference left."""
    problems = []
    anchors: dict[Path, set[str]] = {}

    def check(where: str, target: Path, anchor: str) -> None:
        if not target.exists():
            problems.append(f"{where}: {target.relative_to(root)} does not exist")
        elif anchor and target.suffix == ".md":
            have = anchors.setdefault(target, _anchors(target))
            if anchor not in have:
                problems.append(f"{where}: {target.relative_to(root)} has no anchor #{anchor}")

    for path in _repo_files(root):
        text = path.read_text("utf-8", errors="replace")
        rel = path.relative_to(root)
        for lineno, line in enumerate(text.splitlines(), start=1):
            where = f"{rel}:{lineno}"
            for m in _GONE.finditer(line):
                problems.append(f"{where}: {m.group(0)!r} points at no file in the repository")
            for m in _DOC_REF.finditer(line):
                check(where, root / m.group(1), (m.group(2) or "#")[1:])
        if path.suffix != ".md":
            continue
        for m in _MD_LINK.finditer(_FENCE.sub("", text)):
            target = m.group(1)
            if "://" in target or target.startswith("mailto:"):
                continue
            file_part, _, anchor = target.partition("#")
            dest = (path.parent / file_part).resolve() if file_part else path
            check(f"{rel}: link ({target})", dest, anchor)
    return problems


def test_doc_references_resolve() -> None:
    problems = _reference_problems(ROOT)
    assert not problems, "broken documentation references:\n" + "\n".join(problems)


def test_reference_check_finds_broken_references(tmp_path: Path) -> None:
    d = "docs"  # the bad references are assembled, so this file's own text holds none
    (tmp_path / d).mkdir()
    (tmp_path / d / "cli.md").write_text("# CLI\n\n## Exit status\n\n```sh\n# not a heading\n```\n")
    (tmp_path / d / "api.md").write_text(
        "[ok](cli.md#exit-status) [no file](gone.md) [no anchor](cli.md#not-a-heading)\n")
    (tmp_path / "mod.py").write_text(
        f'"""See {d}/cli.md#exit-status, {d}/missing.md and {d}/cli.md#nowhere."""\n'
        "# old: " + "CONTRACT" + ".md section 2, and contract" + " section 4\n")
    problems = "\n".join(_reference_problems(tmp_path))
    assert f"{d}/gone.md does not exist" in problems
    assert f"{d}/missing.md does not exist" in problems
    assert "has no anchor #not-a-heading" in problems
    assert "has no anchor #nowhere" in problems
    assert "mod.py:2: 'CONTRACT" + ".md'" in problems
    assert "mod.py:2: 'contract" + " section 4'" in problems
    assert "#exit-status" not in problems
    assert len(problems.splitlines()) == 6


def _schema_fields(schema: dict) -> list[str]:
    """Dotted paths of every property: ``matrix.rows[].elements[].code``, ``comparison.<name>.fitness``.

    A ``$ref`` is expanded where it first appears; later uses name only the field.
    """
    defs = schema.get("$defs", {})
    expanded: set[str] = set()

    def walk(node: dict, prefix: str):
        ref = node.get("$ref")
        if ref is not None:
            if ref in expanded:
                return
            expanded.add(ref)
            node = defs[ref.rsplit("/", 1)[-1]]
        for name, sub in node.get("properties", {}).items():
            path = f"{prefix}.{name}" if prefix else name
            yield path
            yield from walk(sub, path)
        if isinstance(node.get("items"), dict):
            yield from walk(node["items"], prefix + "[]")
        if isinstance(node.get("additionalProperties"), dict):
            yield from walk(node["additionalProperties"], prefix + ".<name>")

    return list(walk(schema, ""))


def _section(page: str, heading: str) -> str:
    text = (ROOT / "docs" / page).read_text("utf-8")
    start = text.index(f"\n{heading}\n")
    end = text.find("\n#", start + len(heading) + 2)
    return text[start:] if end < 0 else text[start:end]


def _undocumented(fields: list[str], section: str) -> list[str]:
    return [f for f in fields if f"| `{f}` |" not in section]


@pytest.mark.parametrize(("schema_file", "heading"), [
    ("edm_sym/schema/result.schema.json", "### result.json fields"),
    ("edm_sym/engines/lugre/lugre.schema.json", "### LUGRE.json fields"),
])
def test_result_format_describes_every_schema_field(schema_file: str, heading: str) -> None:
    schema = json.loads((ROOT / schema_file).read_text("utf-8"))
    fields = _schema_fields(schema)
    assert set(schema["properties"]) <= set(fields)
    section = _section("result-format.md", heading)
    missing = _undocumented(fields, section)
    assert not missing, f"docs/result-format.md ({heading}) does not describe: {missing}"
    assert f"](../{schema_file})" in (ROOT / "docs" / "result-format.md").read_text("utf-8")


def test_schema_field_check_sees_a_missing_top_level_property() -> None:
    schema = json.loads((ROOT / "edm_sym/schema/result.schema.json").read_text("utf-8"))
    section = _section("result-format.md", "### result.json fields")
    assert "matrix.rows[].elements[].code" in _schema_fields(schema)
    assert "parameter_ranges.<name>.scaling" in _schema_fields(schema)
    gutted = section.replace("| `record_length` |", "| record length |")
    assert _undocumented(_schema_fields(schema), gutted) == ["record_length"]


def _subcommands() -> dict[str, argparse.ArgumentParser]:
    parser = build_parser()
    (sub,) = (a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return dict(sub.choices)


@pytest.mark.parametrize("command", sorted(_subcommands()))
def test_cli_doc_lists_every_option(command: str) -> None:
    section = _section("cli.md", f"## edm {command}")
    options = [opt for action in _subcommands()[command]._actions for opt in action.option_strings
               if opt not in ("-h", "--help")]
    missing = [opt for opt in options if f"`{opt}" not in section and f" {opt}`" not in section]
    assert options and not missing, f"docs/cli.md (## edm {command}) does not describe {missing}"


def test_api_doc_lists_the_public_names() -> None:
    section = _section("api.md", "## Python API")
    missing = [name for name in edm_sym.__all__ if f"`{name}" not in section]
    assert not missing, f"docs/api.md (## Python API) does not describe {missing}"


@pytest.mark.parametrize("command", sorted(_subcommands()))
def test_every_option_has_help_text(command: str) -> None:
    bare = [a.option_strings or [a.dest] for a in _subcommands()[command]._actions if not a.help]
    assert not bare, f"edm {command}: options without help text: {bare}"


@pytest.mark.parametrize("entry", ["main", "export_main"])
def test_version_is_printed(entry: str, capsys: pytest.CaptureFixture) -> None:
    import edm_sym.application.cli as cli
    from edm_sym.core.version import __version__

    with pytest.raises(SystemExit) as info:
        getattr(cli, entry)(["--version"])
    assert info.value.code == 0
    assert capsys.readouterr().out.strip().endswith(__version__)


def test_the_module_map_names_every_module_of_the_search() -> None:
    """docs/architecture.md#module-map-enginesabstraction lists each module of the search."""
    text = (ROOT / "docs" / "architecture.md").read_text("utf-8")
    section = text.split("## Module map: `engines/abstraction/`", 1)[1].split("\n## ", 1)[0]
    modules = sorted(p.name for p in (ROOT / "edm_sym" / "engines" / "abstraction").glob("*.py")
                     if p.name != "__init__.py")
    assert modules and [m for m in modules if f"| `{m}` |" not in section] == []
