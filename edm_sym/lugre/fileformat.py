"""LUGRE.json: reading and writing identified LuGre models.

The file is ``{"format": "edm-lugre", "version": 1, "parameters": {...},
"target": ..., "velocity": ..., "sample_time": ..., "method": ...,
"fitness": ..., "evaluations": ..., "provenance": {...}}`` (and, when several
methods were run, ``"comparison": {method: {"fitness": ..., "evaluations":
...}}``) with keys sorted,
validated against ``lugre.schema.json`` (shipped next to this module). Every
defect is reported as a :class:`~edm_sym.errors.ResultFormatError` naming the
file and the field, e.g. ``lugre.json: parameters.sigma0: expected a positive
number, found -3``.
"""

from __future__ import annotations

import functools
import importlib.metadata
import json
import math
import os
from importlib import resources
from pathlib import Path
from typing import Any

import jsonschema

from edm_sym.errors import TOO_DEEP, ResultFormatError
from edm_sym.fileio import write_atomic
from edm_sym.lugre.model import PARAMETER_NAMES, LuGreParams
from edm_sym.lugre.result import LuGreProvenance, LuGreResult, MethodScore
from edm_sym.result import format_path

__all__ = ["FORMAT", "VERSION", "load_lugre", "lugre_schema", "parse_lugre", "save_lugre"]

#: Value of the ``format`` field.
FORMAT = "edm-lugre"
#: Value of the ``version`` field.
VERSION = 1

_TYPE_NAMES = {
    "number": "a number",
    "integer": "an integer",
    "string": "a string",
    "object": "an object",
}


@functools.cache
def lugre_schema() -> dict[str, Any]:
    """The JSON Schema of LUGRE.json (``edm_sym/lugre/lugre.schema.json``).

    Returns
    -------
    dict
        The parsed schema (draft 2020-12). Do not modify it.
    """
    text = resources.files("edm_sym.lugre").joinpath("lugre.schema.json").read_text("utf-8")
    return json.loads(text)


def package_version() -> str:
    """Installed version of edm_sym, or ``"0+unknown"`` when not installed.

    Returns
    -------
    str
        The version string.
    """
    try:
        return importlib.metadata.version("edm_sym")
    except importlib.metadata.PackageNotFoundError:
        return "0+unknown"


def _show(value: Any) -> str:
    text = json.dumps(value) if not isinstance(value, float) or math.isfinite(value) else repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def _dotted(path: list[Any]) -> str:
    return format_path(path)


def _describe(error: jsonschema.ValidationError) -> tuple[list[Any], str]:
    """Field path and a one-line problem for one schema violation."""
    path = list(error.absolute_path)
    kind, rule, found = error.validator, error.validator_value, error.instance
    if kind == "required":
        missing = [k for k in rule if k not in found]
        return path + [missing[0]], "required field is missing"
    if kind == "additionalProperties":
        allowed = sorted(error.schema.get("properties", {}))
        extra = sorted(k for k in found if k not in allowed)
        return path + [extra[0]], f"unexpected field (allowed: {', '.join(allowed)})"
    if kind == "type":
        return path, f"expected {_TYPE_NAMES.get(rule, rule)}, found {_show(found)}"
    if kind == "const":
        return path, f"expected {_show(rule)}, found {_show(found)}"
    if kind == "exclusiveMinimum" and rule == 0:
        return path, f"expected a positive number, found {_show(found)}"
    if kind == "minimum" and rule == 0:
        return path, f"expected a non-negative number, found {_show(found)}"
    if kind == "minProperties" and rule == 1:
        return path, f"expected a non-empty object, found {_show(found)}"
    if kind == "minLength":
        return path, f"expected a non-empty string, found {_show(found)}"
    if kind == "pattern" and path and path[-1] == "data_sha256":
        return path, f"expected 64 lowercase hex digits, found {_show(found)}"
    return path, error.message


def _priority(error: jsonschema.ValidationError) -> tuple[int, list[str], str]:
    # A wrong format or version explains everything else, so report it first.
    path = [str(p) for p in error.absolute_path]
    head = path[0] if path else ""
    if error.validator == "required" and not path:
        head = next((k for k in error.validator_value if k not in error.instance), "")
    return (0 if head in ("format", "version") else 1, path, str(error.validator))


def _reject_constant(token: str) -> float:
    raise ValueError(f"{token} is not allowed (numbers must be finite)")


def _no_duplicates(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    seen: dict[str, Any] = {}
    for key, value in pairs:
        if key in seen:
            raise ValueError(f"duplicate key {key!r}")
        seen[key] = value
    return seen


def _find_nonfinite(value: Any, path: list[Any]) -> list[Any] | None:
    if isinstance(value, float) and not math.isfinite(value):
        return path
    children = (
        value.items() if isinstance(value, dict) else enumerate(value) if isinstance(value, list) else ()
    )
    for key, child in children:
        found = _find_nonfinite(child, path + [key])
        if found is not None:
            return found
    return None


def parse_lugre(document: Any, source: str = "LUGRE.json") -> LuGreResult:
    """Validate a parsed LUGRE.json document and build its result.

    Parameters
    ----------
    document : object
        The parsed JSON (normally a dict).
    source : str, optional
        Name used in error messages (the file name).

    Returns
    -------
    LuGreResult
        With ``target_name``, ``velocity_name`` and ``provenance`` set.

    Raises
    ------
    edm_sym.errors.ResultFormatError
        On any defect, naming ``source`` and the field.
    """
    if not isinstance(document, dict):
        raise ResultFormatError(source, f"expected a JSON object at the top level, found {_show(document)}")
    bad = _find_nonfinite(document, [])
    if bad is not None:
        raise ResultFormatError(
            f"{source}: {_dotted(bad)}", "expected a finite number, found a number out of range"
        )
    validator = jsonschema.Draft202012Validator(lugre_schema())
    errors = sorted(validator.iter_errors(document), key=_priority)
    if errors:
        path, problem = _describe(errors[0])
        where = f"{source}: {_dotted(path)}" if path else source
        raise ResultFormatError(where, problem)
    try:
        params = LuGreParams.from_dict(document["parameters"])
    except ValueError as exc:
        name, _, problem = str(exc).partition(": ")
        raise ResultFormatError(f"{source}: parameters.{name}", problem) from None
    prov = document["provenance"]
    comparison = document.get("comparison")
    try:
        return LuGreResult(
            params=params,
            method=document["method"],
            rmse=document["fitness"],
            evaluations=int(document["evaluations"]),
            sample_time=document["sample_time"],
            target_name=document["target"],
            velocity_name=document["velocity"],
            provenance=LuGreProvenance(
                seed=int(prov["seed"]),
                package_version=prov["package_version"],
                data_sha256=prov["data_sha256"],
            ),
            comparison=None
            if comparison is None
            else {name: MethodScore(s["fitness"], s["evaluations"]) for name, s in comparison.items()},
        )
    except ValueError as exc:  # the cross-field checks of the comparison
        name, _, problem = str(exc).partition(": ")
        raise ResultFormatError(f"{source}: {name}", problem) from None


def load_lugre(path: str | os.PathLike) -> LuGreResult:
    """Read and validate a LUGRE.json file.

    Parameters
    ----------
    path : path-like
        The file.

    Returns
    -------
    LuGreResult
        The model, with ``target_name``, ``velocity_name`` (the data columns
        it was identified on) and ``provenance`` set.

    Raises
    ------
    edm_sym.errors.ResultFormatError
        If the file cannot be read, is not JSON, or breaks the schema or a
        parameter bound; the message names the file and the field.
    """
    path = Path(path)
    name = path.name
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise ResultFormatError(str(path), "no such file") from None
    except UnicodeDecodeError as exc:
        raise ResultFormatError(name, f"not UTF-8 text ({exc.reason} at byte {exc.start})") from None
    except OSError as exc:
        raise ResultFormatError(str(path), f"cannot read: {exc.strerror or exc}") from None
    try:
        document = json.loads(text, parse_constant=_reject_constant, object_pairs_hook=_no_duplicates)
    except json.JSONDecodeError as exc:
        raise ResultFormatError(
            f"{name}: line {exc.lineno} column {exc.colno}", f"invalid JSON: {exc.msg}"
        ) from None
    except ValueError as exc:
        raise ResultFormatError(name, f"invalid JSON: {exc}") from None
    except RecursionError:
        raise ResultFormatError(name, TOO_DEEP) from None
    return parse_lugre(document, name)


def lugre_document(
    result: LuGreResult, *, target: str, velocity: str, data_sha256: str, seed: int
) -> dict[str, Any]:
    """The LUGRE.json document of ``result`` (what :func:`save_lugre` writes).

    Parameters
    ----------
    result : LuGreResult
        The identified model.
    target, velocity : str
        Data columns of the target torque and of the velocity.
    data_sha256 : str
        SHA-256 of the data file (64 hex digits).
    seed : int
        Seed of the identification.

    Returns
    -------
    dict
        The document, valid against the schema.

    Raises
    ------
    ValueError
        If the document would not be valid (e.g. a malformed hash).
    """
    document = {
        "format": FORMAT,
        "version": VERSION,
        "parameters": {n: getattr(result.params, n) for n in PARAMETER_NAMES},
        "target": target,
        "velocity": velocity,
        "sample_time": result.sample_time,
        "method": result.method,
        "fitness": result.rmse,
        "evaluations": result.evaluations,
        "provenance": {
            "seed": seed,
            "package_version": package_version(),
            "data_sha256": data_sha256.lower() if isinstance(data_sha256, str) else data_sha256,
        },
    }
    if result.comparison is not None:
        document["comparison"] = {
            name: {"fitness": score.fitness, "evaluations": score.evaluations}
            for name, score in result.comparison.items()
        }
    try:
        parse_lugre(document, "LUGRE.json")
    except ResultFormatError as exc:
        raise ValueError(f"cannot save: {exc}") from None
    return document


def save_lugre(
    path: str | os.PathLike,
    result: LuGreResult,
    *,
    target: str,
    velocity: str,
    data_sha256: str,
    seed: int,
) -> None:
    """Write ``result`` to a LUGRE.json file, atomically and with sorted keys.

    Parameters
    ----------
    path : path-like
        Destination; written through a temporary file and a rename.
    result : LuGreResult
        The identified model.
    target, velocity : str
        Data columns of the target torque and of the velocity.
    data_sha256 : str
        SHA-256 of the data file (64 hex digits).
    seed : int
        Seed of the identification.

    Raises
    ------
    ValueError
        If the document would not be valid; nothing is written then.
    """
    document = lugre_document(result, target=target, velocity=velocity, data_sha256=data_sha256, seed=seed)
    write_atomic(path, json.dumps(document, sort_keys=True, indent=2, allow_nan=False) + "\n")
