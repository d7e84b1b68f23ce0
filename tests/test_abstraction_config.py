"""The abstraction config (TOML, data only): format, validation, weighting (eqs. 15-16)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from edm_sym.core.data import DataLog
from edm_sym.core.elements import ParamRange, default_ranges
from edm_sym.core.errors import ConfigError
from edm_sym.engines.abstraction import (
    AbstractionConfig,
    GaSettings,
    StepConfig,
    Weighting,
    abstract,
    default_config,
    load_config,
    parse_config,
)
from edm_sym.engines.abstraction.parallel import Parallel

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = sorted((ROOT / "examples" / "configs").glob("*.toml"))


def test_there_are_example_configs() -> None:
    assert {p.name for p in EXAMPLES} >= {"default.toml", "paper_auger.toml"}


@pytest.mark.parametrize("path", EXAMPLES, ids=lambda p: p.name)
def test_every_example_config_loads(path: Path) -> None:
    cfg = load_config(path)
    assert cfg.steps and cfg.source == path.name


def test_the_default_schedule_grows_the_matrix_with_lambda_one() -> None:
    cfg = default_config()
    assert [(s.n_elements, s.n_rows) for s in cfg.steps] == [(4, 2), (4, 3), (4, 4), (4, 5)]
    assert all(s.weighting.is_constant and s.weighting.constant == 1.0 for s in cfg.steps)
    assert all(s.ga.patience > 0 for s in cfg.steps)  # a step ends when it stops improving
    assert load_config(ROOT / "examples/configs/default.toml").to_json() == cfg.to_json()


def test_the_paper_schedule_reads_as_written() -> None:
    cfg = load_config(ROOT / "examples/configs/paper_auger.toml")
    assert [s.n_rows for s in cfg.steps] == [2, 3, 4, 5]
    w1, w4 = cfg.steps[0].weighting, cfg.steps[3].weighting
    assert w1.windows == ((0.0, 10.0, 1.0),) and w1.otherwise == 0.0
    assert (w4.threshold, w4.above, w4.below) == (0.8, 20000.0, 1.0)
    assert cfg.initial[0].elements == (("sign", None), ("gain", 0.9))


def test_step_settings_override_the_ga_table() -> None:
    cfg = parse_config({"ga": {"population": 30, "patience": 5},
                        "step": [{"n_rows": 2, "population": 12}, {"n_rows": 3}]})
    assert cfg.steps[0].ga.population == 12 and cfg.steps[1].ga.population == 30
    assert cfg.steps[0].ga.patience == cfg.steps[1].ga.patience == 5
    assert cfg.steps[0].n_elements == 4


# -- weighting ---------------------------------------------------------------------

def test_eq_15_time_windows() -> None:
    t = np.arange(0, 20, 0.5)
    w = Weighting(windows=((0.0, 10.0, 1.0), (10.0, 20.0, 0.0)))
    lam = w.weights(t, np.zeros_like(t))
    assert np.array_equal(lam, np.where(t < 10, 1.0, 0.0))


def test_later_windows_win_and_otherwise_fills_the_gaps() -> None:
    t = np.arange(10.0)
    w = Weighting(windows=((0, 6, 2.0), (4, 8, 3.0)), otherwise=0.5)
    assert w.weights(t, t).tolist() == [2, 2, 2, 2, 3, 3, 3, 3, 0.5, 0.5]


def test_eq_16_threshold_on_the_target() -> None:
    tau = np.array([0.0, 0.5, -0.8, 0.79, -2.0])
    w = Weighting(threshold=0.8, above=20000.0, below=1.0)
    assert w.weights(np.arange(5.0), tau).tolist() == [1, 1, 20000, 1, 20000]


def test_factors_multiply_and_constant_stays_a_number() -> None:
    w = Weighting(constant=2.0, windows=((0, 1, 3.0),), threshold=1.0, above=5.0)
    assert w.weights(np.array([0.5, 0.5, 2.0]), np.array([0.0, 2.0, 2.0])).tolist() == [6, 30, 0]
    assert Weighting(constant=4.0).weights(np.zeros(3), np.zeros(3)) == 4.0


def test_weighting_json_round_trips_through_the_config() -> None:
    w = Weighting(windows=((0.0, 1.5, 2.0),), otherwise=0.25, threshold=0.3, above=7.0)
    back = parse_config({"step": [{"n_rows": 1, "weighting": w.to_json()}]}).steps[0].weighting
    assert back == w


# -- validation --------------------------------------------------------------------

def _write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "cfg.toml"
    path.write_text(text)
    return path


@pytest.mark.parametrize("text, where, what", [
    ("colour = 1", "cfg.toml: colour", "unknown key"),
    ("[ga]\npopulaton = 10", "cfg.toml: ga.populaton", "unknown key"),
    ("[ga]\npopulation = '64'", "cfg.toml: ga.population", "expected an integer, found string"),
    ("[ga]\npopulation = 6.5", "cfg.toml: ga.population", "expected an integer"),
    ("[ga]\npopulation = 2", "cfg.toml: ga.population", ">= 4"),
    ("[ga]\ncrossover_rate = 1.5", "cfg.toml: ga.crossover_rate", "<= 1"),
    ("[ga]\ngain_fit = 1", "cfg.toml: ga.gain_fit", "true or false"),
    ("[ga]\ncontinue = 'maybe'", "cfg.toml: ga.continue", "'improving'"),
    ("[ga]\nelites = 64", "cfg.toml: ga.elites", "fewer than population"),
    ("[ga]\nelements = ['sign', 'frobnicate']", "cfg.toml: ga.elements[1]", "element name"),
    ("[ga]\nelements = []", "cfg.toml: ga.elements", "non-empty"),
    ("step = []", "cfg.toml: step", "at least one [[step]]"),
    ("axis = []", "cfg.toml: axis", "expected rotary or linear, found array"),
    ("[[step]]\nn_elements = 4", "cfg.toml: step[0].n_rows", "missing"),
    ("[[step]]\nn_rows = 0", "cfg.toml: step[0].n_rows", "integer >= 1"),
    ("[[step]]\nn_rows = 2\nrows = 3", "cfg.toml: step[0].rows", "unknown key"),
    ("[[step]]\nn_rows = 3\n[[step]]\nn_rows = 2", "cfg.toml: step[1].n_rows", "expected >= 3"),
    ("[[step]]\nn_rows = 2\nweighting = 'flat'", "cfg.toml: step[0].weighting", "a number or a table"),
    ("[[step]]\nn_rows = 2\nweighting = {window = []}", "cfg.toml: step[0].weighting.window",
     "unknown key"),
    ("[[step]]\nn_rows = 2\nweighting = {windows = [[0, 1]]}",
     "cfg.toml: step[0].weighting.windows[0]", "[t_start, t_end, weight]"),
    ("[[step]]\nn_rows = 2\nweighting = {windows = [[2, 1, 1]]}",
     "cfg.toml: step[0].weighting.windows[0]", "t_start < t_end"),
    ("[[step]]\nn_rows = 2\nweighting = {above = 3}", "cfg.toml: step[0].weighting.threshold",
     "expected a threshold"),
    ("[[step]]\nn_rows = 2\nweighting = {constant = -1}", "cfg.toml: step[0].weighting.constant",
     ">= 0"),
    # 1e308 overflowed eq. 8: refused only at the end, by the JSON writer (inf).
    ("[[step]]\nn_rows = 2\nweighting = 1e308", "cfg.toml: step[0].weighting.constant",
     "expected a weight <= 1e12"),
    ("[[step]]\nn_rows = 2\nweighting = {windows = [[0, 1, 1e13]], otherwise = 0}",
     "cfg.toml: step[0].weighting.windows[0]", "found 1e+13"),
    ("[ranges.gain]\nlow = 2\nhigh = 1", "cfg.toml: ranges.gain", "low < high"),
    ("[ranges.gain]\nscaling = 'cubic'", "cfg.toml: ranges.gain.scaling", "'linear' or 'log'"),
    ("[ranges.sign]\nlow = 0", "cfg.toml: ranges.sign", "no parameter"),
    ("[ranges.gian]\nlow = 0", "cfg.toml: ranges.gian", "element name"),
    ("[initial]\nrows = [{input = 'omega', elements = [['gain']]}]",
     "cfg.toml: initial.rows[0].elements[0]", "found no value"),
    ("[initial]\nrows = [{input = 'omega', elements = [['sign', 3.0]]}]",
     "cfg.toml: initial.rows[0].elements[0]", "has no parameter), found the value float 3.0"),
    ("[initial]\nrows = [{input = 'omega', elements = [['sgn']]}]",
     "cfg.toml: initial.rows[0].elements[0]", "element name"),
    ("[initial]\nrows = [{elements = [['sign']]}]", "cfg.toml: initial.rows[0].input",
     "input column name"),
    ("[ga\npopulation = 3", "cfg.toml", "expected TOML"),
])
def test_bad_configs_name_the_file_and_key(tmp_path: Path, text: str, where: str,
                                           what: str) -> None:
    with pytest.raises(ConfigError) as err:
        load_config(_write(tmp_path, text))
    assert err.value.where == where
    assert what in err.value.problem
    assert "\n" not in str(err.value)


def test_a_missing_config_file_is_a_config_error(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="cannot be read"):
        load_config(tmp_path / "nope.toml")


def test_a_human_model_too_wide_for_step_1_is_refused() -> None:
    doc = {"initial": {"rows": [{"input": "x", "elements": [["sign"]]}] * 3},
           "step": [{"n_rows": 2}]}
    with pytest.raises(ConfigError, match="at most 2 rows"):
        parse_config(doc, "c.toml")


def test_range_overrides_apply_to_the_defaults() -> None:
    cfg = parse_config({"ranges": {"gain": {"low": -2.0, "high": 2.0},
                                   "lpf": {"high": 100.0}}})
    ranges = cfg.resolve_ranges(1e-3, 20.0)
    base = default_ranges(1e-3, 20.0)
    assert ranges["gain"] == ParamRange(-2.0, 2.0, "linear")
    assert ranges["lpf"] == ParamRange(base["lpf"].low, 100.0, "log")
    assert ranges["tanh"] == base["tanh"]


def test_an_override_that_breaks_a_range_is_refused_at_run_time() -> None:
    cfg = parse_config({"ranges": {"lpf": {"high": 1e-3}}}, "c.toml")
    with pytest.raises(ConfigError, match="ranges.lpf"):
        cfg.resolve_ranges(1e-3, 20.0)


def _tiny_log() -> DataLog:
    t = np.arange(400) * 1e-3
    return DataLog({"t": t, "omega": np.sin(5 * t), "tau": np.cos(5 * t)}, 1e-3)


def test_human_model_values_outside_their_range_are_refused() -> None:
    doc = {"initial": {"rows": [{"input": "omega", "elements": [["gain", 50.0]]}]},
           "step": [{"n_rows": 1}]}
    with pytest.raises(ConfigError, match=r"initial.rows\[0\].elements\[0\].*widen"):
        abstract(_tiny_log(), target="tau", inputs=["omega"], config=parse_config(doc, "c"),
                 parallel=Parallel(workers=1))


def test_human_model_inputs_must_be_run_inputs() -> None:
    doc = {"initial": {"rows": [{"input": "alpha", "elements": [["sign"]]}]},
           "step": [{"n_rows": 1}]}
    with pytest.raises(ConfigError, match=r"initial.rows\[0\].input"):
        abstract(_tiny_log(), target="tau", inputs=["omega"], config=parse_config(doc, "c"),
                 parallel=Parallel(workers=1))


def test_a_weighting_that_is_zero_on_the_whole_log_is_refused() -> None:
    doc = {"step": [{"n_rows": 1, "weighting": {"windows": [[5.0, 6.0, 1.0]]}}]}
    with pytest.raises(ConfigError, match=r"step\[0\].weighting"):
        abstract(_tiny_log(), target="tau", inputs=["omega"], config=parse_config(doc, "c"),
                 parallel=Parallel(workers=1))


def test_options_are_validated_on_construction() -> None:
    with pytest.raises(ConfigError, match="GaSettings.population"):
        GaSettings(population=2)
    with pytest.raises(ConfigError, match="StepConfig.n_rows"):
        StepConfig(n_rows=0)
    with pytest.raises(ValueError):
        Weighting(constant=float("nan"))
    assert AbstractionConfig().steps == default_config().steps


_value = st.one_of(st.integers(-5, 100), st.floats(allow_nan=True), st.text(max_size=5),
                   st.booleans(), st.lists(st.integers(0, 3), max_size=3))
_keys = st.sampled_from(["population", "elites", "tournament", "crossover_rate",
                         "shift_min", "continue", "elements", "gain_fit", "n_rows",
                         "weighting", "bogus"])


@settings(max_examples=200, deadline=None)
@given(ga=st.dictionaries(_keys, _value, max_size=4),
       step=st.dictionaries(_keys, _value, max_size=4))
def test_any_table_is_either_a_config_or_a_config_error(ga: dict, step: dict) -> None:
    doc = {"ga": {k: v for k, v in ga.items() if k not in ("n_rows", "weighting")},
           "step": [step]}
    try:
        cfg = parse_config(doc, "fuzz.toml")
    except ConfigError as err:
        assert err.where.startswith("fuzz.toml: ")
    else:
        assert cfg.steps[0].n_rows >= 1
