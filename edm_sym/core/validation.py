"""JSON Schema violations as one-line messages: the one translator of the file formats.

result.json (:mod:`edm_sym.core.result`) and LUGRE.json (:mod:`edm_sym.engines.lugre`)
are validated against their JSON Schemas with :func:`schema_problem`, which
picks the violation that explains the most (a wrong ``format`` or ``version``
first, then the first field in document order) and says where it is, what
was expected and what was found::

    lugre.json: parameters.sigma0: expected a positive number, found -3
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Mapping, Sequence
from typing import Any

import jsonschema

__all__ = ["json_path", "positive_number", "schema_problem", "show_value"]

_TYPE_NAMES = {
    "number": "a number",
    "integer": "an integer",
    "string": "a string",
    "object": "an object",
    "array": "a list",
    "boolean": "true or false",
    "null": "null",
}


#: A key shown as ``.name`` in a path; any other is shown JSON-quoted in brackets.
_PLAIN_KEY = re.compile(r"[A-Za-z_][A-Za-z0-9_-]*")


def json_path(parts: Sequence[Any]) -> str:
    """A field path as text: ``["matrix", "rows", 3]`` -> ``"matrix.rows[3]"`` (top level: ``""``).

    A key that is not a plain name (a space, a newline, a quote ...) is shown
    JSON-quoted in brackets, ``parameters["a\\nb"]``, so the path stays one line.
    """
    out = ""
    for part in parts:
        if isinstance(part, int):
            out += f"[{part}]"
        elif not _PLAIN_KEY.fullmatch(str(part)):
            out += f"[{json.dumps(str(part))}]"
        else:
            out += f".{part}" if out else str(part)
    return out


def positive_number(value: Any) -> float | None:
    """A value a file or a log records as a finite positive number (not a bool), else None."""
    ok = isinstance(value, int | float) and not isinstance(value, bool)
    return float(value) if ok and math.isfinite(value) and value > 0 else None


def show_value(value: Any) -> str:
    """A found value as JSON, cut to 60 characters (a non-finite float as Python prints it)."""
    finite = not isinstance(value, float) or math.isfinite(value)
    text = json.dumps(value) if finite else repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def _type_name(rule: Any) -> str:
    names = rule if isinstance(rule, list) else [rule]
    return " or ".join(_TYPE_NAMES.get(n, n) for n in names)


def _describe(error: jsonschema.ValidationError) -> tuple[list[Any], str]:
    """Field path and a one-line problem for one schema violation."""
    path = list(error.absolute_path)
    kind, rule, found = error.validator, error.validator_value, error.instance
    shown = show_value(found)
    if kind == "required":
        missing = [k for k in rule if k not in found]
        return path + missing[:1], "required field is missing"
    if kind == "additionalProperties":
        allowed = sorted(error.schema.get("properties", {}))
        extra = sorted(k for k in found if k not in allowed)
        return path + extra[:1], f"unexpected field (allowed: {', '.join(allowed)})"
    if path and str(path[-1]).endswith("sha256") and kind in ("pattern", "anyOf"):
        null = " null or" if kind == "anyOf" else ""
        return path, f"expected{null} 64 lowercase hex digits, found {shown}"
    if kind == "anyOf":
        # Each alternative by its type; a $ref in these schemas always names an object.
        names = [_type_name(alt.get("type", "object")) if alt.get("type") != "null" else "null"
                 for alt in rule]
        return path, f"expected {' or '.join(names)}, found {shown}"
    texts: Mapping[str, Any] = {
        "type": lambda: _type_name(rule),
        "const": lambda: show_value(rule),
        "enum": lambda: "one of " + ", ".join(show_value(x) for x in rule),
        "exclusiveMinimum": lambda: "a positive number" if rule == 0 else f"a number > {rule}",
        "minimum": lambda: "a non-negative number" if rule == 0 else f"a number >= {rule}",
        "maximum": lambda: f"a number <= {rule}",
        "minProperties": lambda: "a non-empty object" if rule == 1 else f"at least {rule} field(s)",
        "minItems": lambda: f"at least {rule} item(s)",
        "uniqueItems": lambda: "no repeated items",
        "minLength": lambda: "a non-empty string",
        "pattern": lambda: f"text matching {rule}",
    }
    if kind in texts:
        return path, f"expected {texts[kind]()}, found {shown}"
    return path, error.message


def _priority(error: jsonschema.ValidationError) -> tuple[int, list[str], str]:
    # A wrong format or version explains everything else, so report it first.
    path = [str(p) for p in error.absolute_path]
    head = path[0] if path else ""
    if error.validator == "required" and not path:
        head = next((k for k in error.validator_value if k not in error.instance), "")
    return (0 if head in ("format", "version") else 1, path, str(error.validator))


def schema_problem(schema: Mapping[str, Any], document: Any) -> tuple[list[Any], str] | None:
    """The violation of ``schema`` that explains the most, or None when ``document`` is valid.

    Parameters
    ----------
    schema : mapping
        A JSON Schema (draft 2020-12).
    document : object
        The parsed JSON.

    Returns
    -------
    (path, problem) or None
        The field path (keys and indices, for :func:`json_path`) and one line
        saying what was expected and what was found.
    """
    validator = jsonschema.Draft202012Validator(schema)
    errors = sorted(validator.iter_errors(document), key=_priority)
    return _describe(errors[0]) if errors else None
