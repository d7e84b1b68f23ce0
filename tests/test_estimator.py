"""edm_sym.EDMRegressor: the scikit-learn estimator (docs/estimator.md)."""

from __future__ import annotations

import importlib.util
import pickle
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

sklearn = pytest.importorskip("sklearn")
pd = pytest.importorskip("pandas")

from sklearn.base import clone  # noqa: E402
from sklearn.exceptions import NotFittedError  # noqa: E402
from sklearn.model_selection import TimeSeriesSplit, cross_val_score  # noqa: E402
from sklearn.utils.estimator_checks import parametrize_with_checks  # noqa: E402

import edm_sym  # noqa: E402
from edm_sym.application.estimator import FIT_SOURCE, EDMRegressor  # noqa: E402
from edm_sym.core.data import DataLog  # noqa: E402
from edm_sym.engines.abstraction import parse_config  # noqa: E402

TS = 1e-3
#: One step, 2 rows of 2 elements, 16 individuals: a Coulomb + viscous log is found in a fraction of a second.
TINY_FILE = Path(__file__).parent / "data" / "estimator_tiny.toml"
TINY = {
    "ga": {"population": 16, "generations": 20, "continue": "no",
           "elements": ["through", "gain", "power_gain", "sign", "tanh", "lpf"]},
    "step": [{"n_rows": 2, "n_elements": 2}],
}
TINY_CONFIG = parse_config(TINY, "<tiny>")
COULOMB, VISCOUS = 0.8, 0.05


def friction_log(n: int = 2000, *, f1: float = 1.5, f2: float = 4.1, seed: int = 0) -> pd.DataFrame:
    """A free-motion log: omega, alpha and a Coulomb + viscous torque with a little noise."""
    t = np.arange(n) * TS
    omega = 3.0 * np.sin(2 * np.pi * f1 * t) + 1.5 * np.sin(2 * np.pi * f2 * t + 0.3)
    alpha = np.gradient(omega, TS)
    noise = 0.01 * np.random.default_rng(seed).standard_normal(n)
    tau = COULOMB * np.sign(omega) + VISCOUS * omega + noise
    return pd.DataFrame({"omega": omega, "alpha": alpha, "tau_ext": tau})


@pytest.fixture(scope="module")
def log() -> pd.DataFrame:
    return friction_log()


@pytest.fixture(scope="module")
def fitted(log: pd.DataFrame) -> EDMRegressor:
    return EDMRegressor(sample_time=TS, config=TINY_CONFIG, seed=1).fit(log[["omega", "alpha"]],
                                                                        log["tau_ext"])


# --- optional dependency ---

def test_sklearn_is_optional_and_imported_on_first_use() -> None:
    # One fresh interpreter (importing edm_sym takes seconds on a loaded machine).
    code = "\n".join([
        "import sys, edm_sym",
        "assert 'sklearn' not in sys.modules and 'edm_sym.application.estimator' not in sys.modules",
        "assert 'EDMRegressor' in dir(edm_sym) and 'EDMRegressor' not in edm_sym.__all__",
        "sys.modules['sklearn'] = None  # as if scikit-learn were not installed",
        "from edm_sym import *",
        "try:",
        "    edm_sym.EDMRegressor",
        "except ImportError as exc:",
        "    print(exc)",
        "del sys.modules['sklearn']",
        "print(edm_sym.EDMRegressor.__name__)",
    ])
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    missing, found = out.stdout.strip().splitlines()
    assert "pip install 'edm_sym[sklearn]'" in missing and "scikit-learn" in missing
    assert found == "EDMRegressor"


def test_api_doc_names_the_estimator() -> None:
    api = (Path(__file__).parents[1] / "docs" / "api.md").read_text("utf-8")
    assert "| `EDMRegressor` |" in api.split("## Python API", 1)[1]


def test_unknown_attribute_is_still_an_attribute_error() -> None:
    with pytest.raises(AttributeError, match="no attribute 'EdmRegressor'"):
        edm_sym.EdmRegressor  # noqa: B018


# --- parameters ---

def test_params_clone_and_set_params_round_trip() -> None:
    roles = {"x": "velocity"}
    est = EDMRegressor(sample_time=2e-3, config=TINY_CONFIG, seed=7, time_limit=3.0, roles=roles,
                       target_name="tau", workers=2, searches=2, progress=True, axis="linear",
                       observer_bandwidth=150.0)
    params = est.get_params()
    assert params == {"sample_time": 2e-3, "config": TINY_CONFIG, "seed": 7, "time_limit": 3.0,
                      "roles": roles, "target_name": "tau", "workers": 2, "searches": 2,
                      "progress": True, "axis": "linear", "observer_bandwidth": 150.0}
    twin = clone(est)
    assert twin is not est and twin.get_params() == params
    assert EDMRegressor(**params).get_params() == params
    assert twin.set_params(seed=3, sample_time=1e-4) is twin
    assert twin.seed == 3 and twin.sample_time == 1e-4 and est.seed == 7
    with pytest.raises(ValueError, match="Invalid parameter 'populaton'"):
        twin.set_params(populaton=3)


def test_constructor_stores_without_checking_and_repr_is_one_line() -> None:
    est = EDMRegressor(sample_time=-1.0, seed="x")  # sklearn: checks happen in fit
    assert est.sample_time == -1.0 and est.seed == "x"
    text = repr(EDMRegressor(sample_time=1e-3, seed=2))
    assert text == "EDMRegressor(sample_time=0.001, seed=2)"
    with pytest.raises(TypeError):
        EDMRegressor(1e-3)  # keyword-only


# --- fit, predict, score ---

def test_fit_predict_score_on_coulomb_viscous(fitted: EDMRegressor, log: pd.DataFrame) -> None:
    X, y = log[["omega", "alpha"]], log["tau_ext"]
    assert fitted.score(X, y) > 0.9
    held_out = friction_log(3000, f1=0.7, f2=2.3, seed=5)
    assert fitted.score(held_out[["omega", "alpha"]], held_out["tau_ext"]) > 0.9
    assert isinstance(fitted.result_, edm_sym.EdmResult)
    assert fitted.result_.target == "tau_ext"
    assert fitted.result_.sample_time == TS
    assert fitted.result_.provenance["seed"] == 1


def test_predict_is_the_reference_simulator(fitted: EDMRegressor, log: pd.DataFrame) -> None:
    data = DataLog({c: log[c].to_numpy() for c in log.columns}, TS)
    expected = edm_sym.simulate(fitted.result_, data).total
    got = fitted.predict(log[["omega", "alpha"]])
    assert got.shape == (len(log),)
    np.testing.assert_array_equal(got, expected)
    np.testing.assert_array_equal(fitted.predict(log[["omega", "alpha"]].to_numpy()), expected)


def test_predict_warns_where_a_row_reads_a_feature_beyond_its_fit_range(
        fitted: EDMRegressor, log: pd.DataFrame) -> None:
    """Twice the velocities of fit: predict warns, naming the feature, both ranges and the
    rows that read it, and predicts the same numbers as the simulator; on the log of fit,
    nothing (docs/estimator.md#predict-warns-where-the-model-extrapolates)."""
    import warnings

    fast = log.copy()
    fast["omega"] *= 2.0
    fast["alpha"] *= 2.0
    X = fast[["omega", "alpha"]]
    with pytest.warns(UserWarning, match=r"^EDMRegressor.predict: omega reaches .* in X, beyond "
                      r"its range .* in <EDMRegressor.fit>, on .* % of the samples: rows? "):
        got = fitted.predict(X)
    data = DataLog({c: fast[c].to_numpy() for c in fast.columns}, TS)
    np.testing.assert_array_equal(got, edm_sym.simulate(fitted.result_, data).total)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        fitted.predict(log[["omega", "alpha"]])


def test_same_seed_same_result(fitted: EDMRegressor, log: pd.DataFrame, tmp_path: Path) -> None:
    again = clone(fitted).fit(log[["omega", "alpha"]], log["tau_ext"])
    a = edm_sym.save_result(fitted.result_, tmp_path / "a.json").read_bytes()
    b = edm_sym.save_result(again.result_, tmp_path / "b.json").read_bytes()
    assert a == b


def test_time_limit_reaches_the_abstraction(log: pd.DataFrame) -> None:
    est = EDMRegressor(sample_time=TS, config=TINY_CONFIG, time_limit=0.0)
    est.fit(log[["omega", "alpha"]], log["tau_ext"])
    assert est.result_.provenance["stop_reason"] == "time_limit"
    assert est.result_.steps[0].generations < 20


@pytest.mark.slow
def test_workers_do_not_change_the_result(fitted: EDMRegressor, log: pd.DataFrame) -> None:
    pooled = clone(fitted).set_params(workers=2).fit(log[["omega", "alpha"]], log["tau_ext"])
    assert pooled.result_.compensator == fitted.result_.compensator
    assert pooled.result_.fitness == fitted.result_.fitness


def test_searches_reach_the_abstraction(log: pd.DataFrame) -> None:
    est = EDMRegressor(sample_time=TS, config=TINY_CONFIG, seed=1, searches=2, workers=2)
    est.fit(log[["omega", "alpha"]], log["tau_ext"])
    found = est.result_.provenance["searches"]
    assert [s["seed"] for s in found][0] == 1 and len(found) == 2
    with pytest.raises(edm_sym.ConfigError, match="searches"):
        EDMRegressor(sample_time=TS, config=TINY_CONFIG, searches=0).fit(
            log[["omega", "alpha"]], log["tau_ext"])


def test_config_from_a_toml_file(log: pd.DataFrame) -> None:
    X, y = log[["omega", "alpha"]], log["tau_ext"]
    from_file = EDMRegressor(sample_time=TS, config=str(TINY_FILE), seed=1).fit(X, y)
    from_object = EDMRegressor(sample_time=TS, config=TINY_CONFIG, seed=1).fit(X, y)
    assert from_file.result_.compensator == from_object.result_.compensator
    with pytest.raises(edm_sym.ConfigError, match="EDMRegressor.config"):
        EDMRegressor(sample_time=TS, config=3).fit(X, y)


def test_predictions_depend_on_sample_order() -> None:
    """A compensator with memory (a low pass) starts at rest at the first row."""
    m = edm_sym.make_matrix(["x0"], [("x0", [("lpf", 0.5), ("gain", 0.75)])])
    provenance = {"seed": None, "package_version": edm_sym.__version__, "data_sha256": None}
    est = EDMRegressor(sample_time=TS)
    est.result_ = edm_sym.EdmResult(edm_sym.Compensator(m, TS, {}), "tau_ext", provenance=provenance)
    est.n_features_in_, est.feature_names_in_ = 1, np.array(["x0"], dtype=object)
    X = np.sin(np.arange(400) * 0.05)[:, None]
    whole = est.predict(X)
    assert not np.allclose(est.predict(X[200:]), whole[200:])
    assert not np.allclose(est.predict(X[::-1])[::-1], whole)
    np.testing.assert_array_equal(whole, edm_sym.simulate(est.result_, {"x0": X[:, 0]}).total)


# --- names ---

def test_dataframe_column_names_are_kept(fitted: EDMRegressor, log: pd.DataFrame) -> None:
    assert list(fitted.feature_names_in_) == ["omega", "alpha"]
    assert fitted.feature_names_in_.dtype == object
    assert fitted.n_features_in_ == 2
    assert fitted.result_.inputs == ("omega", "alpha")
    assert {s.name for s in fitted.sympy().free_symbols} <= {"omega", "alpha"}
    with pytest.raises(ValueError, match=r"expected \['omega', 'alpha'\].*found \['alpha', 'omega'\]"):
        fitted.predict(log[["alpha", "omega"]])


def test_array_names_and_feature_names(log: pd.DataFrame) -> None:
    X, y = log[["omega", "alpha"]].to_numpy(), log["tau_ext"].to_numpy()
    est = EDMRegressor(sample_time=TS, config=TINY_CONFIG).fit(X, y)
    assert list(est.feature_names_in_) == ["x0", "x1"]
    assert est.result_.inputs == ("x0", "x1")
    named = EDMRegressor(sample_time=TS, config=TINY_CONFIG).fit(X, y, feature_names=["w", "a"])
    assert named.result_.inputs == ("w", "a")
    np.testing.assert_array_equal(named.predict(X), est.predict(X))  # same data, other names
    with pytest.raises(ValueError, match="expected 2 names"):
        EDMRegressor(sample_time=TS, config=TINY_CONFIG).fit(X, y, feature_names=["w"])
    with pytest.raises(ValueError, match=r"expected X's column names \['omega', 'alpha'\]"):
        EDMRegressor(sample_time=TS, config=TINY_CONFIG).fit(log[["omega", "alpha"]], y,
                                                             feature_names=["w", "a"])


def test_a_linear_axis_reaches_the_result_and_its_outputs(tmp_path: Path) -> None:
    """axis="linear" gives N, m/s and N s/m everywhere."""
    t = np.arange(2000) * TS
    v = 0.15 * np.sin(2 * np.pi * 1.5 * t) + 0.08 * np.sin(2 * np.pi * 4.1 * t + 0.3)
    force = 20.0 * np.sign(v) + 60.0 * v + 0.2 * np.random.default_rng(0).standard_normal(len(t))
    X = pd.DataFrame({"vel": v, "acc": np.gradient(v, TS)})
    est = EDMRegressor(sample_time=TS, config=TINY_CONFIG, seed=1, axis="linear",
                       target_name="force").fit(X, force)
    assert est.result_.axis == "linear"
    table = est.describe().table()
    assert "linear axis, target in N" in table and "N s/m" in table
    assert "N m" not in table and "rad/s" not in table
    header = est.to_c(tmp_path, prefix="lin")[0].read_text()
    assert "[N]" in header and "m/s" in header and "N m" not in header and "rad/s" not in header
    assert est.to_control().dt == TS


def test_the_observers_bandwidth_reaches_the_result_and_describe(log: pd.DataFrame) -> None:
    """As ``edm abstract --observer-bandwidth``: recorded in the provenance, where
    describe reads it; without it nothing is recorded."""
    X, y = log[["omega", "alpha"]], log["tau_ext"]
    told = EDMRegressor(sample_time=TS, config=TINY_CONFIG, seed=1, observer_bandwidth=150).fit(X, y)
    assert told.result_.provenance["observer_bandwidth"] == 150.0
    assert told.result_.observer_bandwidth == 150.0
    assert told.describe(X, y).physics.bandwidth == 150.0
    blind = EDMRegressor(sample_time=TS, config=TINY_CONFIG, seed=1).fit(X, y)
    assert "observer_bandwidth" not in blind.result_.provenance
    assert blind.describe(X, y).physics.bandwidth is None


@pytest.mark.parametrize("g", [0.0, -1.0, float("nan"), float("inf"), "150", True])
def test_fit_refuses_a_bad_observer_bandwidth(g: object, log: pd.DataFrame) -> None:
    with pytest.raises(ValueError, match=r"EDMRegressor.observer_bandwidth: expected a finite "
                                         r"number > 0 \[rad/s\] or None, found"):
        EDMRegressor(sample_time=TS, config=TINY_CONFIG, observer_bandwidth=g).fit(
            log[["omega"]], log["tau_ext"])


# --- errors ---

@pytest.mark.parametrize("axis", ["angular", None, 1])
def test_fit_refuses_an_unknown_axis(axis: object, log: pd.DataFrame) -> None:
    with pytest.raises(ValueError, match=r"EDMRegressor.fit: axis: expected 'rotary' or 'linear', found"):
        EDMRegressor(sample_time=TS, config=TINY_CONFIG, axis=axis).fit(log[["omega"]], log["tau_ext"])


@pytest.mark.parametrize("ts", [None, 0.0, -1e-3, float("nan"), "1e-3", True])
def test_fit_needs_a_sample_time(ts: object, log: pd.DataFrame) -> None:
    hint = r"sample_time: expected .* > 0\), found .*; hint: EDMRegressor\(sample_time=1e-3\)"
    with pytest.raises(ValueError, match=hint):
        EDMRegressor(sample_time=ts, config=TINY_CONFIG).fit(log[["omega"]], log["tau_ext"])


def test_wrong_number_of_features(fitted: EDMRegressor, log: pd.DataFrame) -> None:
    with pytest.raises(ValueError, match="X has 1 features, but EDMRegressor is expecting 2 features"):
        fitted.predict(log[["omega"]].to_numpy())


def test_target_name_must_not_be_a_feature(log: pd.DataFrame) -> None:
    with pytest.raises(ValueError, match="target_name: 'omega' is also a feature name"):
        EDMRegressor(sample_time=TS, target_name="omega").fit(log[["omega"]], log["tau_ext"])


def test_duplicate_names_are_refused(log: pd.DataFrame) -> None:
    X = log[["omega", "alpha"]].to_numpy()
    with pytest.raises(ValueError, match=r"expected each name once, found \['w'\]"):
        EDMRegressor(sample_time=TS, config=TINY_CONFIG).fit(X, log["tau_ext"], feature_names=["w", "w"])
    with pytest.raises(ValueError, match="unique column names"):  # scikit-learn's own check
        EDMRegressor(sample_time=TS, config=TINY_CONFIG).fit(log[["omega", "omega"]], log["tau_ext"])


def test_unfitted_estimator(tmp_path: Path) -> None:
    est = EDMRegressor(sample_time=TS)
    for call in (lambda: est.predict(np.zeros((3, 1))), est.sympy, lambda: est.to_c(tmp_path)):
        with pytest.raises(NotFittedError):
            call()


# --- the fitted model in other forms ---

def test_sympy_and_latex(fitted: EDMRegressor) -> None:
    expr = fitted.sympy()
    assert expr == edm_sym.decode(fitted.result_).total()
    assert fitted.sympy() is expr  # decoded once
    text = fitted.latex()
    assert isinstance(text, str) and r"\omega" in text and "$" not in text


def test_roles_reach_the_decoder(fitted: EDMRegressor) -> None:
    est = clone(fitted).set_params(roles={"omega": None})
    est.result_, est.n_features_in_, est.feature_names_in_ = (
        fitted.result_, fitted.n_features_in_, fitted.feature_names_in_)
    assert est._model().roles["omega"] is None
    assert fitted._model().roles["omega"] == "velocity"


def test_describe_calls_edm_sym_describe(fitted: EDMRegressor, log: pd.DataFrame,
                                         monkeypatch: pytest.MonkeyPatch) -> None:
    seen = {}

    def describe(result, data=None, **options):  # noqa: ANN001, ANN202  (the shape of edm_sym.describe)
        seen.update(result=result, data=data, **options)
        return "described"

    monkeypatch.setattr(edm_sym, "describe", describe, raising=False)
    est = clone(fitted).set_params(roles={"alpha": "acceleration"})
    est.result_, est.n_features_in_, est.feature_names_in_ = (
        fitted.result_, fitted.n_features_in_, fitted.feature_names_in_)
    assert est.describe() == "described"
    assert seen == {"result": fitted.result_, "data": None, "roles": {"alpha": "acceleration"}}
    assert est.describe(log[["omega", "alpha"]], log["tau_ext"], roles=None) == "described"
    data = seen["data"]
    assert seen["roles"] is None
    assert isinstance(data, DataLog) and data.ts == TS and list(data.columns) == ["omega", "alpha", "tau_ext"]
    np.testing.assert_array_equal(data.column("tau_ext"), log["tau_ext"].to_numpy())
    with pytest.raises(ValueError, match="expected both X and y"):
        est.describe(log[["omega", "alpha"]])
    monkeypatch.delattr(edm_sym, "describe")
    with pytest.raises(NotImplementedError, match="no edm_sym.describe"):
        est.describe()


def test_to_c_and_to_python(fitted: EDMRegressor, log: pd.DataFrame, tmp_path: Path) -> None:
    c_files = fitted.to_c(tmp_path / "c", prefix="friction")
    assert [p.name for p in c_files] == ["friction.h", "friction.c"]
    (py,) = fitted.to_python(tmp_path / "py")
    spec = importlib.util.spec_from_file_location("edm_est_generated", py)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    assert module.INPUTS == ("omega", "alpha") and module.SAMPLE_TIME == TS
    X = log[["omega", "alpha"]]
    np.testing.assert_allclose(module.simulate(X), fitted.predict(X), rtol=0, atol=1e-9)


def test_pickled_after_decoding(fitted: EDMRegressor, log: pd.DataFrame) -> None:
    fitted.sympy()
    twin = pickle.loads(pickle.dumps(fitted))
    X = log[["omega", "alpha"]]
    np.testing.assert_array_equal(twin.predict(X), fitted.predict(X))
    assert twin.sympy() == fitted.sympy()


def test_cross_validation_on_contiguous_folds(log: pd.DataFrame) -> None:
    est = EDMRegressor(sample_time=TS, config=TINY_CONFIG)
    scores = cross_val_score(est, log[["omega", "alpha"]], log["tau_ext"], cv=TimeSeriesSplit(n_splits=2))
    assert scores.shape == (2,) and np.all(scores > 0.9)


def test_fit_log_is_named(fitted: EDMRegressor) -> None:
    assert FIT_SOURCE == "<EDMRegressor.fit>"
    assert fitted.result_.provenance["data_sha256"] is None


# --- scikit-learn's estimator checks ---

#: Checks that do not apply to a model of one time series, with the reason (docs/estimator.md).
TIME_SERIES_CHECKS = {
    "check_methods_sample_order_invariance":
        "rows are consecutive samples: filters, delays and relays make predict depend on their order",
    "check_methods_subset_invariance":
        "predict on a part of a log starts the compensator at rest there, not where the whole log had it",
}


def _expected_failed_checks(estimator: EDMRegressor) -> dict[str, str]:
    return TIME_SERIES_CHECKS


# A file name, not a config object, keeps the estimator's repr (the tests' ids) short.
@parametrize_with_checks([EDMRegressor(sample_time=TS, config=str(TINY_FILE))],
                         expected_failed_checks=_expected_failed_checks)
def test_sklearn_estimator_checks(estimator: EDMRegressor, check) -> None:  # noqa: ANN001
    check(estimator)


def test_to_control_equals_predict(fitted: EDMRegressor, log: pd.DataFrame) -> None:
    import control as ct

    sys = fitted.to_control()
    assert sys.input_labels == ["omega", "alpha"] and sys.dt == TS
    u = log[["omega", "alpha"]].to_numpy().T
    resp = ct.input_output_response(sys, np.arange(u.shape[1]) * TS, u, squeeze=False)
    assert np.max(np.abs(resp.outputs[0] - fitted.predict(log[["omega", "alpha"]]))) <= 1e-9
