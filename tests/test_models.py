"""engines.models: one interface for EDM and LuGre models (docs/architecture.md#one-model-interface)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from edm_sym.core.errors import ResultFormatError
from edm_sym.core.result import load_result
from edm_sym.engines.lugre import load_lugre, simulate_lugre
from edm_sym.engines.models import EdmModel, LuGreModel, file_format, load_model, model_of
from edm_sym.engines.simulate import simulate
from edm_sym.engines.sources import load_data

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "auger"


@pytest.fixture(scope="module")
def log():  # noqa: ANN201
    return load_data("plant:auger/evaluation").window(0, 3000)


def test_an_edm_file_runs_as_the_reference_simulator(log) -> None:  # noqa: ANN001
    model = load_model(EXAMPLE / "result.json")
    result = load_result(EXAMPLE / "result.json")
    assert isinstance(model, EdmModel) and model.kind == "edm" and model.name == "result.json"
    assert model.inputs == tuple(result.inputs) and model.target == result.target
    run = model.run(log)
    sim = simulate(result, log)
    np.testing.assert_array_equal(run.torque, sim.total)
    assert list(run.parts) == [f"row_{j}" for j in range(1, len(sim.rows) + 1)]
    np.testing.assert_array_equal(sum(run.parts.values()), sum(sim.rows))


def test_a_lugre_file_reads_only_its_velocity(log) -> None:  # noqa: ANN001
    path = EXAMPLE / "lugre.json"
    model = load_model(path)
    lugre = load_lugre(path)
    assert isinstance(model, LuGreModel) and model.kind == "lugre"
    assert model.inputs == (lugre.velocity_name,)
    expected = simulate_lugre(lugre.params, log.columns[lugre.velocity_name], log.ts)
    np.testing.assert_array_equal(model.run(log).torque, expected)
    assert model.run(log).parts == {}
    assert model_of(lugre).run(log).torque.tolist() == expected.tolist()


def test_model_of_refuses_other_objects() -> None:
    with pytest.raises(TypeError, match="EdmResult or a LuGreResult"):
        model_of({"format": "edm-result"})


@pytest.mark.parametrize(("text", "where"), [
    ('{"format": "edm-other"}', "x.json: format"),
    ("[1, 2]", "x.json: (top level)"),
    ("{not json", "x.json"),
    ("[" * 100_000 + "]" * 100_000, "x.json"),
])
def test_file_format_names_the_file_and_field(tmp_path: Path, text: str, where: str) -> None:
    path = tmp_path / "x.json"
    path.write_text(text)
    with pytest.raises(ResultFormatError) as info:
        file_format(path)
    assert str(info.value).startswith(where), str(info.value)
    assert "\n" not in str(info.value)


def test_the_kind_is_decided_in_one_module() -> None:
    # The commands and the report use the interface; only engines/models.py reads "edm-lugre".
    root = Path(__file__).resolve().parents[1] / "edm_sym"
    readers = sorted(str(p.relative_to(root)) for p in root.rglob("*.py")
                     if '"edm-lugre"' in p.read_text("utf-8"))
    assert readers == ["engines/lugre/fileformat.py", "engines/models.py"], readers
    assert json.loads((EXAMPLE / "lugre.json").read_text())["format"] == "edm-lugre"
