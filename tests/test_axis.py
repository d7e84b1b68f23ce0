"""The axis of a result (rotary or linear): recorded in result.json, read back, old files rotary."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import pytest

from edm_sym.core.errors import ResultFormatError
from edm_sym.core.result import dumps, load_result, save_result
from edm_sym.core.units import axis_units

ROOT = Path(__file__).resolve().parents[1]
HANDWRITTEN = ROOT / "tests" / "data" / "handwritten_result.json"


def test_a_file_without_axis_is_rotary(tmp_path: Path) -> None:
    doc = json.loads(HANDWRITTEN.read_text())
    doc.pop("axis")
    path = tmp_path / "old.json"
    path.write_text(json.dumps(doc))
    res = load_result(path)
    assert res.axis == "rotary"
    assert res.units.force == "N m"
    assert json.loads(dumps(res))["axis"] == "rotary"  # written out once saved again


def test_linear_axis_round_trips(tmp_path: Path) -> None:
    res = replace(load_result(HANDWRITTEN), axis="linear")
    back = load_result(save_result(res, tmp_path / "r.json"))
    assert back.axis == "linear"
    assert back.units == axis_units("linear")
    assert back.units.viscous == "N s/m"


def test_an_unknown_axis_is_refused_naming_the_field(tmp_path: Path) -> None:
    doc = json.loads(HANDWRITTEN.read_text())
    doc["axis"] = "angular"
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(doc))
    with pytest.raises(ResultFormatError, match=r"bad.json: axis.*angular"):
        load_result(path)


def test_the_closing_summarys_fitness_is_in_the_axis_unit() -> None:
    from edm_sym.application.summary import fitness_line

    res = replace(load_result(HANDWRITTEN), fitness=0.25, validation={})
    assert fitness_line(res) == ("fitness (weighted eq. 8): training 0.25 N m, "
                                 "validation: none held out")
    assert fitness_line(replace(res, axis="linear")) == ("fitness (weighted eq. 8): training 0.25 N, "
                                                         "validation: none held out")


def test_a_fitness_never_recorded_is_said_so_not_printed_inf() -> None:
    # result-format.md: fitness is null for a hand-written matrix; the report says "not
    # recorded" and describe "-", but the closing summary and repr said "inf".
    from edm_sym.application.summary import fitness_line

    res = replace(load_result(HANDWRITTEN), fitness=None, validation={})
    assert fitness_line(res) == ("fitness (weighted eq. 8): training not recorded, "
                                 "validation: none held out")
    assert "fitness not recorded" in repr(res) and "inf" not in repr(res)
