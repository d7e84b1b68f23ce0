"""Any input to a loader or a command: a valid result, or exit 2 with one line and nothing written.

Hypothesis draws files near the valid ones (valid documents with a value
replaced, CSV with cells changed, random bytes, deep nesting) and checks that
nothing but the project's own one-line errors comes out.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from edm_sym.application.cli import main
from edm_sym.application.pipeline import load_pipeline
from edm_sym.core.data import DataLog, load_data
from edm_sym.core.errors import ConfigError, DataFormatError, EdmError, ResultFormatError
from edm_sym.core.result import load_result
from edm_sym.engines.abstraction import load_config
from edm_sym.engines.lugre import load_lugre

REPO = Path(__file__).resolve().parents[1]
RESULT = REPO / "examples" / "auger" / "result.json"
LUGRE = REPO / "examples" / "auger" / "lugre.json"
CONFIG = REPO / "examples" / "auger" / "abstraction.toml"
PIPELINE = REPO / "examples" / "auger" / "pipeline.toml"

SETTINGS = settings(max_examples=60, deadline=None,
                    suppress_health_check=[HealthCheck.function_scoped_fixture])

CELLS = st.one_of(st.floats(allow_nan=True, allow_infinity=True).map(repr),
                  st.text(alphabet=' 0123456789.-+eE,"\n\tnaif', max_size=8), st.just(""))
JSON_VALUES = st.recursive(
    st.none() | st.booleans() | st.integers(min_value=-10**30, max_value=10**30)
    | st.floats() | st.text(max_size=6),
    lambda inner: st.lists(inner, max_size=3) | st.dictionaries(st.text(max_size=5), inner, max_size=3),
    max_leaves=8,
)


def _one_line(exc: Exception, name: str) -> None:
    text = str(exc)
    assert "\n" not in text and name in text, text


@SETTINGS
@given(rows=st.lists(st.lists(CELLS, min_size=0, max_size=4), max_size=6),
       header=st.lists(st.text(alphabet="tabc_ ,", max_size=4), min_size=0, max_size=4))
def test_any_csv_loads_or_is_refused_in_one_line(tmp_path: Path, rows, header) -> None:
    p = tmp_path / "log.csv"
    p.write_text("\n".join([",".join(header)] + [",".join(r) for r in rows]))
    try:
        log = load_data(p, ts=0.001)
    except DataFormatError as exc:
        _one_line(exc, "log.csv")
    else:
        assert isinstance(log, DataLog) and len(log) >= 1


@SETTINGS
@given(raw=st.binary(max_size=600), suffix=st.sampled_from([".mat", ".npz", ".csv"]))
def test_any_bytes_load_or_are_refused_in_one_line(tmp_path: Path, raw: bytes, suffix: str) -> None:
    p = tmp_path / f"log{suffix}"
    p.write_bytes(raw)
    try:
        load_data(p, ts=0.001)
    except DataFormatError as exc:
        _one_line(exc, p.name)


def _leaf_paths(doc, prefix=()):  # noqa: ANN001, ANN202
    items = doc.items() if isinstance(doc, dict) else enumerate(doc) if isinstance(doc, list) else ()
    for key, value in items:
        yield (*prefix, key)
        yield from _leaf_paths(value, (*prefix, key))


def _corrupt(doc, data):  # noqa: ANN001, ANN202
    path = data.draw(st.sampled_from(sorted(_leaf_paths(doc), key=str)))
    node = doc
    for key in path[:-1]:
        node = node[key]
    node[path[-1]] = data.draw(JSON_VALUES)
    return doc


@pytest.mark.parametrize("source,loader", [(RESULT, load_result), (LUGRE, load_lugre)],
                         ids=["result.json", "LUGRE.json"])
@SETTINGS
@given(data=st.data())
def test_any_corrupted_model_file_loads_or_is_refused_in_one_line(tmp_path: Path, source, loader,
                                                                  data) -> None:
    p = tmp_path / "m.json"
    p.write_text(json.dumps(_corrupt(json.loads(source.read_text()), data)))
    try:
        loader(p)
    except ResultFormatError as exc:
        _one_line(exc, "m.json")


def _toml_value(v) -> str:  # noqa: ANN001
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, float):
        return {float("inf"): "inf", float("-inf"): "-inf"}.get(v, "nan" if v != v else repr(v))
    return str(v)


TOML_VALUES = (st.integers(min_value=-10**20, max_value=10**20) | st.floats() | st.booleans()
               | st.text(alphabet="abc_ 0.", max_size=6))


@SETTINGS
@given(data=st.data())
def test_any_edited_config_loads_or_is_refused_in_one_line(tmp_path: Path, data) -> None:
    lines = CONFIG.read_text().splitlines()
    settable = [k for k, ln in enumerate(lines) if "=" in ln and not ln.lstrip().startswith("#")
                and "[" not in ln.split("=", 1)[1] and "{" not in ln.split("=", 1)[1]]
    k = data.draw(st.sampled_from(settable))
    key = lines[k].split("=", 1)[0]
    lines[k] = f"{key}= {_toml_value(data.draw(TOML_VALUES))}"
    p = tmp_path / "cfg.toml"
    p.write_text("\n".join(lines) + "\n")
    try:
        load_config(p)
    except ConfigError as exc:
        _one_line(exc, "cfg.toml")


@SETTINGS
@given(data=st.data())
def test_any_edited_pipeline_loads_or_is_refused_in_one_line(tmp_path: Path, data) -> None:
    lines = PIPELINE.read_text().splitlines()
    settable = [k for k, ln in enumerate(lines) if "=" in ln and not ln.lstrip().startswith("#")]
    k = data.draw(st.sampled_from(settable))
    key = lines[k].split("=", 1)[0]
    lines[k] = f"{key}= {_toml_value(data.draw(TOML_VALUES))}"
    p = tmp_path / "pipe.toml"
    p.write_text("\n".join(lines) + "\n")
    (tmp_path / "abstraction.toml").write_text(CONFIG.read_text())
    try:
        load_pipeline(p)
    except (EdmError, ValueError) as exc:
        _one_line(exc, "pipe.toml")


@pytest.mark.parametrize("kind", ["json", "toml"])
def test_deep_nesting_is_refused_in_one_line(tmp_path: Path, kind: str) -> None:
    deep = "[" * 50_000 + "]" * 50_000
    if kind == "json":
        p = tmp_path / "deep.json"
        p.write_text('{"format": "edm-result", "version": ' + deep + "}")
        loader, error = load_result, ResultFormatError
    else:
        p = tmp_path / "deep.toml"
        p.write_text("cache_mb = " + deep + "\n")
        loader, error = load_config, ConfigError
    with pytest.raises(error) as info:
        loader(p)
    _one_line(info.value, p.name)


@SETTINGS
@given(rows=st.lists(st.lists(CELLS, min_size=3, max_size=3), min_size=0, max_size=5))
def test_simulate_on_any_log_writes_a_valid_output_or_nothing(tmp_path: Path, rows, capsys) -> None:
    data = tmp_path / "log.csv"
    data.write_text("\n".join(["t,omega,theta_w"] + [",".join(r) for r in rows]))
    out = tmp_path / "out.csv"
    out.unlink(missing_ok=True)
    code = main(["simulate", str(RESULT), str(data), "-o", str(out)])
    err = capsys.readouterr().err.strip()
    if code == 0:
        assert out.exists() and out.read_text().startswith("t,")
    else:
        assert code == 2 and not out.exists()
        assert len(err.splitlines()) == 1 and "log.csv" in err and "Traceback" not in err, err
