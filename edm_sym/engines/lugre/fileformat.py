"""LUGRE.json: reading and writing identified LuGre models.

The file is ``{"format": "edm-lugre", "version": 1, "parameters": {...},
"target": ..., "velocity": ..., "sample_time": ..., "method": ...,
"fitness": ..., "evaluations": ..., "provenance": {...}}`` (and, when several
methods were run, ``"comparison": {method: {"fitness": ..., "evaluations":
...}}``) with keys sorted,
validated against ``lugre.schema.json`` (shipped next to this module). Every
defect is reported as a :class:`~edm_sym.core.errors.ResultFormatError` naming the
file and the field, e.g. ``lugre.json: parameters.sigma0: expected a positive
number, found -3``.
"""

from __future__ import annotations

import functools
import json
import math
import os
from importlib import resources
from pathlib import Path
from typing import Any

from edm_sym.core.errors import ResultFormatError
from edm_sym.core.fileio import read_json, write_atomic
from edm_sym.core.validation import json_path, schema_problem, show_value
from edm_sym.core.version import __version__
from edm_sym.engines.lugre.model import PARAMETER_NAMES, LuGreParams
from edm_sym.engines.lugre.result import LuGreProvenance, LuGreResult, MethodScore

__all__ = ["FORMAT", "VERSION", "load_lugre", "lugre_schema", "parse_lugre", "save_lugre"]

#: Value of the ``format`` field.
FORMAT = "edm-lugre"
#: Value of the ``version`` field.
VERSION = 1

@functools.cache
def lugre_schema() -> dict[str, Any]:
    """The JSON Schema of LUGRE.json (``edm_sym/engines/lugre/lugre.schema.json``).

    Returns
    -------
    dict
        The parsed schema (draft 2020-12). Do not modify it.
    """
    text = resources.files("edm_sym.engines.lugre").joinpath("lugre.schema.json").read_text("utf-8")
    return json.loads(text)


def package_version() -> str:
    """Installed version of edm_sym, or ``"0+unknown"`` when not installed.

    Returns
    -------
    str
        The version string.
    """
    return __version__


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
    edm_sym.core.errors.ResultFormatError
        On any defect, naming ``source`` and the field.
    """
    if not isinstance(document, dict):
        raise ResultFormatError(
            source, f"expected a JSON object at the top level, found {show_value(document)}")
    bad = _find_nonfinite(document, [])
    if bad is not None:
        raise ResultFormatError(
            f"{source}: {json_path(bad)}", "expected a finite number, found a number out of range"
        )
    problem = schema_problem(lugre_schema(), document)
    if problem is not None:
        path, text = problem
        raise ResultFormatError(f"{source}: {json_path(path)}" if path else source, text)
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
    edm_sym.core.errors.ResultFormatError
        If the file cannot be read, is not JSON, or breaks the schema or a
        parameter bound; the message names the file and the field.
    """
    path = Path(path)
    name = path.name
    document, _ = read_json(path, ResultFormatError)
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
    result, target, velocity, data_sha256, seed
        As for :func:`lugre_document`, which makes the document.

    Raises
    ------
    ValueError
        If the document would not be valid; nothing is written then.
    """
    document = lugre_document(result, target=target, velocity=velocity, data_sha256=data_sha256, seed=seed)
    write_atomic(path, json.dumps(document, sort_keys=True, indent=2, allow_nan=False) + "\n")
