"""Tests of edm_sym.engines.lugre: the LuGre baseline (paper eqs. 8, 10-14)."""

from __future__ import annotations

import fnmatch
import inspect
import json
import math
import time
from pathlib import Path

import jsonschema
import numpy as np
import pytest
from conftest import emps_path
from helpers import COMPLIANT, SHA, STIFF, TS, synthetic, write_corrupted
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy import signal
from scipy.integrate import solve_ivp

import edm_sym.engines.lugre as lugre
from edm_sym.core.errors import ResultFormatError
from edm_sym.engines.lugre import (
    METHODS,
    LuGreParams,
    LuGreResult,
    MethodOutcome,
    identify_lugre,
    load_lugre,
    register_method,
    save_lugre,
    simulate_lugre,
    steady_state,
    weighted_rmse,
)


def friction(p: LuGreParams, v: np.ndarray, z: np.ndarray) -> np.ndarray:
    """Eq. 10 with eq. 11 for dz/dt, written out independently of the module."""
    g = (p.tau_c + (p.tau_s - p.tau_c) * np.exp(-((v / p.v_s) ** 2))) / p.sigma0
    return p.sigma0 * z + p.sigma1 * (v - np.abs(v) / g * z) + p.sigma2 * v


def with_sigma0(sigma0: float) -> LuGreParams:
    return LuGreParams(
        v_s=0.5,
        tau_c=1.0,
        tau_s=1.5,
        z0=0.2 / sigma0,
        sigma0=sigma0,
        sigma1=0.05 * math.sqrt(sigma0),
        sigma2=0.1,
    )


def reversing_velocity(t: np.ndarray) -> np.ndarray:
    return 2.0 * np.sin(2 * np.pi * 1.5 * t) + 0.3 * np.sin(2 * np.pi * 7 * t) - 0.2


# ---------------------------------------------------------------- parameters


def test_params_coerce_to_float_and_round_trip_dict():
    p = LuGreParams(v_s=np.float32(0.5), tau_c=1, tau_s=2.0, z0=0, sigma0=np.int64(10), sigma1=0, sigma2=0)
    assert all(type(getattr(p, n)) is float for n in lugre.PARAMETER_NAMES)
    assert LuGreParams.from_dict(p.to_dict()) == p
    assert list(p.to_dict()) == list(lugre.PARAMETER_NAMES)


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("v_s", 0.0),
        ("v_s", -1.0),
        ("sigma0", 0.0),
        ("sigma0", -3.0),
        ("tau_c", -0.1),
        ("tau_s", -0.1),
        ("sigma1", -1e-9),
        ("sigma2", -1.0),
        ("z0", math.nan),
        ("sigma0", math.inf),
        ("tau_c", "1.0"),
        ("sigma1", True),
    ],
)
def test_params_rejects_bad_values_naming_the_field(field, value):
    values = STIFF.to_dict() | {field: value}
    with pytest.raises(ValueError, match=rf"^{field}: expected"):
        LuGreParams(**values)


def test_params_rejects_zero_friction_levels():
    with pytest.raises(ValueError, match="tau_c \\+ tau_s must be positive"):
        LuGreParams(**(STIFF.to_dict() | {"tau_c": 0.0, "tau_s": 0.0}))


def test_from_dict_names_missing_and_unknown_parameters():
    values = STIFF.to_dict()
    del values["sigma1"]
    with pytest.raises(ValueError, match="^sigma1: missing"):
        LuGreParams.from_dict(values)
    with pytest.raises(ValueError, match="^sigma3: unknown"):
        LuGreParams.from_dict(STIFF.to_dict() | {"sigma3": 1.0})


# ---------------------------------------------------------------- simulation


def zoh_reference(p: LuGreParams, v: np.ndarray, ts: float) -> np.ndarray:
    """Eq. 11 integrated by Radau sample by sample, v held over each sample."""
    z, out = p.z0, []
    for vk in v:
        g = float(p.g(vk))
        sol = solve_ivp(
            lambda _t, y, vk=vk, g=g: vk - abs(vk) / g * y,
            (0.0, ts),
            [z],
            method="Radau",
            rtol=1e-11,
            atol=1e-9 * g,
        )
        z = sol.y[0, -1]
        out.append(z)
    return friction(p, v, np.array(out))


@pytest.mark.parametrize("sigma0", [1e6, 1e3])
def test_exact_update_matches_stiff_ode_with_held_velocity(sigma0):
    # Same hold as the simulator, so only integration error remains:
    # agreement to 1e-8 of max |tau| (observed ~1e-11).
    p = with_sigma0(sigma0)
    v = reversing_velocity(np.arange(300) * 4e-3)
    assert np.any(np.diff(np.sign(v)) != 0), "the profile must reverse"
    tau = simulate_lugre(p, v, 4e-3)
    ref = zoh_reference(p, v, 4e-3)
    np.testing.assert_allclose(tau, ref, rtol=0, atol=1e-8 * np.max(np.abs(ref)))


def smooth_reference(p: LuGreParams, t: np.ndarray) -> np.ndarray:
    """Eq. 11 on the continuous velocity (no hold), Radau at tight tolerance."""
    ts = t[1] - t[0]

    def rhs(tt, y):
        vv = reversing_velocity(tt)
        return [vv - abs(vv) / float(p.g(vv)) * y[0]]

    sol = solve_ivp(
        rhs, (t[0] - ts, t[-1]), [p.z0], method="Radau", t_eval=t, rtol=1e-10,
        atol=1e-9 * p.tau_c / p.sigma0,
    )  # fmt: skip
    return friction(p, reversing_velocity(t), sol.y[0])


@pytest.mark.parametrize("sigma0", [1e6, 1e3])
def test_sampled_model_converges_to_continuous_model(sigma0):
    # The sampled velocity differs from the continuous one within a sample;
    # the error sits at velocity reversals and shrinks with the sample time.
    p = with_sigma0(sigma0)
    errors, scale = {}, 0.0
    for ts in (1e-3, 1e-4):
        t = np.arange(int(round(1.0 / ts))) * ts
        ref = smooth_reference(p, t)
        diff = simulate_lugre(p, reversing_velocity(t), ts) - ref
        errors[ts], scale = math.sqrt(np.mean(diff**2)), np.max(np.abs(ref))
    # Observed RMS at 0.1 ms: 0.7 % (sigma0 = 1e6), 0.1 % (1e3) of max |tau|.
    assert errors[1e-4] < 0.02 * scale
    assert errors[1e-4] < 0.5 * errors[1e-3]


@pytest.mark.parametrize("params", [STIFF, COMPLIANT, with_sigma0(1e3)])
@pytest.mark.parametrize("velocity", [-40.0, -2.0, -0.3, 0.01, 0.7, 5.0, 62.8])
def test_constant_velocity_settles_to_steady_state(params, velocity):
    # Start from the opposite deflection; eq. 14 must be reached.
    p = LuGreParams(**(params.to_dict() | {"z0": -math.copysign(params.tau_s, velocity) / params.sigma0}))
    tau = simulate_lugre(p, np.full(5000, velocity), TS)
    expected = float(steady_state(p, velocity))
    assert tau[-1] == pytest.approx(expected, rel=1e-9, abs=1e-12)


def test_steady_state_is_odd_and_matches_both_forms_of_eq14():
    v = np.linspace(-70.0, 70.0, 2001)
    ss = steady_state(COMPLIANT, v)
    np.testing.assert_allclose(ss, -steady_state(COMPLIANT, -v), rtol=0, atol=1e-15)
    first_form = COMPLIANT.sigma0 * COMPLIANT.g(v) * np.sign(v) + COMPLIANT.sigma2 * v
    np.testing.assert_allclose(ss, first_form, rtol=1e-12)
    assert steady_state(COMPLIANT, 1e-9) == pytest.approx(COMPLIANT.tau_s, rel=1e-6)
    assert steady_state(COMPLIANT, 0.0) == 0.0


def test_zero_velocity_holds_the_bristles():
    p = LuGreParams(**(COMPLIANT.to_dict() | {"z0": 3e-4}))
    tau = simulate_lugre(p, np.zeros(50), TS)
    np.testing.assert_allclose(tau, p.sigma0 * 3e-4)


def test_degenerate_stribeck_function_stays_finite():
    # tau_s = 0 gives g(0) = 0; tau_c = 0 gives g -> 0 at high speed.
    no_stiction = LuGreParams(**(COMPLIANT.to_dict() | {"tau_s": 0.0}))
    no_coulomb = LuGreParams(**(COMPLIANT.to_dict() | {"tau_c": 0.0}))
    v = np.array([0.0, 0.0, 1.0, 100.0, 1e3, 0.0, -1e3])
    for p in (no_stiction, no_coulomb):
        tau = simulate_lugre(p, v, TS)
        assert np.all(np.isfinite(tau))
    tau = simulate_lugre(no_coulomb, v, TS)
    assert tau[4] == pytest.approx(no_coulomb.sigma2 * 1e3)
    # Between the two, g(v) subnormal: |v| / g overflows (a fuzzed LUGRE.json with
    # tau_c = 0 simulated NaN, exit 0). The bristles relax at once there too.
    sweep = no_coulomb.v_s * np.linspace(20.0, 40.0, 4001)
    g = no_coulomb.g(sweep)
    with np.errstate(over="ignore", divide="ignore"):
        assert np.any((g > 0) & ~np.isfinite(sweep / g))
    tau = simulate_lugre(no_coulomb, sweep, TS)
    np.testing.assert_allclose(tau, no_coulomb.sigma2 * sweep, rtol=1e-9)


def test_simulate_rejects_bad_input():
    with pytest.raises(ValueError, match=r"velocity\[2\]"):
        simulate_lugre(STIFF, [0.0, 1.0, math.nan], TS)
    with pytest.raises(ValueError, match="1-D"):
        simulate_lugre(STIFF, np.zeros((2, 2)), TS)
    with pytest.raises(ValueError, match="ts"):
        simulate_lugre(STIFF, [1.0], 0.0)


def test_weighted_rmse_is_eq8():
    target, tau = np.array([1.0, 2.0, 3.0, 4.0]), np.array([0.0, 2.0, 1.0, 4.0])
    assert weighted_rmse(target, tau) == pytest.approx(math.sqrt(5 / 4))
    assert weighted_rmse(target, tau, [1.0, 1.0, 0.0, 1.0]) == pytest.approx(0.5)


# ------------------------------------------------------------ identification


@pytest.mark.slow
@pytest.mark.parametrize("truth", [STIFF, COMPLIANT], ids=["sigma0=1e6", "sigma0=2e3"])
def test_identification_recovers_friction(truth):
    v, clean, noisy = synthetic(truth)
    start = time.perf_counter()
    result = identify_lugre(noisy, v, TS, seed=0)
    elapsed = time.perf_counter() - start
    # Steady-state curve over the log's velocity range, |error| <= 3 % of
    # max |tau_ss| (pointwise, v = 0 excluded where both jump).
    grid = np.linspace(-np.max(np.abs(v)), np.max(np.abs(v)), 4000)
    true_ss, found_ss = steady_state(truth, grid), steady_state(result.params, grid)
    assert np.max(np.abs(found_ss - true_ss)) <= 0.03 * np.max(np.abs(true_ss))
    # Simulated friction within 5 % RMS of the noise-free truth.
    sim = simulate_lugre(result.params, v, TS)
    assert math.sqrt(np.mean((sim - clean) ** 2)) <= 0.05 * math.sqrt(np.mean(clean**2))
    assert result.rmse == pytest.approx(weighted_rmse(noisy, sim))
    assert result.method == "scipy" and result.sample_time == TS and result.evaluations > 100
    print(f"identified in {elapsed:.1f} s, {result.evaluations} evaluations: {result.params}")


@pytest.mark.slow
def test_identification_on_real_emps_axis_matches_published_friction():
    # Real data: Janot et al.'s EMPS axis. The published least-squares model
    # has Fc = 20.3935 N, Fv = 203.5034 N s/m; above the stiction region the
    # LuGre steady state must agree with Fc sgn(v) + Fv v within 3 %.
    from scipy.io import loadmat

    data = loadmat(emps_path())
    t, q = data["t"].ravel(), data["qm"].ravel()
    ts = float(t[1] - t[0])
    force = float(data["gtau"].item()) * data["vir"].ravel()
    b, a = signal.butter(4, 100.0 / (0.5 / ts))
    qd = np.gradient(signal.filtfilt(b, a, q), ts)
    target = force - 95.1089 * np.gradient(qd, ts)
    result = identify_lugre(target, qd, ts, seed=0)
    v = np.linspace(0.01, np.max(np.abs(qd)), 200)
    v = np.r_[-v, v]
    published = 20.3935 * np.sign(v) + 203.5034 * v
    assert np.max(np.abs(steady_state(result.params, v) - published)) <= 0.03 * np.max(np.abs(published))


def test_same_seed_gives_same_parameters():
    v, _, noisy = synthetic(COMPLIANT, duration=3.0)
    first = identify_lugre(noisy, v, TS, seed=7)
    second = identify_lugre(noisy, v, TS, seed=7)
    assert first == second


def test_weights_exclude_samples():
    # The second half is garbage but weighted zero: it must not matter.
    v, clean, _ = synthetic(COMPLIANT, duration=6.0)
    target = clean.copy()
    half = len(v) // 2
    target[half:] = 50.0 * np.random.default_rng(3).standard_normal(len(v) - half)
    weights = np.r_[np.ones(half), np.zeros(len(v) - half)]
    result = identify_lugre(target, v, TS, seed=0, weights=weights)
    sim = simulate_lugre(result.params, v, TS)
    assert result.rmse == pytest.approx(weighted_rmse(target, sim, weights))
    assert result.rmse < 0.01 * np.max(np.abs(clean))
    np.testing.assert_allclose(sim[:half], clean[:half], rtol=0, atol=0.05 * np.max(np.abs(clean)))


def test_time_limit_returns_best_so_far():
    v, _, noisy = synthetic(STIFF, duration=2.0)
    result = identify_lugre(noisy, v, TS, time_limit=0.0)
    assert result.evaluations == 1
    assert isinstance(result.params, LuGreParams)
    assert result.rmse == pytest.approx(weighted_rmse(noisy, simulate_lugre(result.params, v, TS)))


def test_unknown_method_is_refused():
    with pytest.raises(ValueError, match="unknown method 'nope' \\(known: .*scipy"):
        identify_lugre(np.ones(10), np.ones(10), TS, method="nope")


def test_methods_are_dispatched_through_the_registry():
    calls = []

    def fixed(problem, *, seed):
        calls.append((len(problem.velocity), seed))
        return MethodOutcome(params=STIFF, evaluations=1)

    register_method("test-fixed")(fixed)
    try:
        with pytest.raises(ValueError, match="already registered"):
            register_method("test-fixed")(fixed)
        # (a velocity that varies: a constant one is refused before any method runs)
        result = identify_lugre(np.ones(10), np.linspace(0.5, 1.5, 10), TS, method="test-fixed",
                                seed=4)
    finally:
        del METHODS["test-fixed"]
    assert calls == [(10, 4)]
    assert result.params == STIFF and result.method == "test-fixed"


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"target": np.ones(9)}, "target: expected a 1-D array of 10"),
        ({"target": np.r_[np.ones(9), np.nan]}, r"target\[9\]"),
        ({"velocity": np.zeros(10), "target": np.ones(10)}, "all samples are zero"),
        ({"velocity": np.full(10, 0.3)}, "expected a varying velocity"),
        ({"velocity": np.linspace(-1, 1, 7), "target": np.ones(7)},
         "more samples than the model's 7 parameters"),
        ({"weights": -np.ones(10)}, "weights"),
        ({"ts": -1.0}, "ts"),
        ({"seed": 1.5}, "seed"),
        ({"time_limit": -1.0}, "time_limit"),
        ({"time_limit": "soon"}, "time_limit"),
        # A finite speed whose square overflows (eq. 12) crashed the fit (IndexError, exit 1).
        ({"velocity": np.r_[np.linspace(-1, 1, 9), 1e308]}, "velocity: expected values whose"),
        # 1e-160 gave an IndexError, a target of 1e160 an AssertionError (exit 1).
        ({"velocity": 1e-160 * np.linspace(-1, 1, 10)}, "velocity: expected values whose"),
        ({"target": 1e160 * np.linspace(0, 1, 10)}, "target: expected values whose"),
    ],
)
def test_identify_rejects_bad_input(kwargs, match):
    args = {"target": np.ones(10), "velocity": np.linspace(-1, 1, 10), "ts": TS} | kwargs
    with pytest.raises(ValueError, match=match):
        identify_lugre(**args)


def test_edm_lugre_names_the_file_and_column_of_a_refused_velocity(tmp_path, capsys):
    from edm_sym.application.cli import main
    from edm_sym.core.data import write_csv

    v = np.r_[np.linspace(-1, 1, 19), 1e308]
    write_csv(tmp_path / "log.csv", {"t": np.arange(20) * TS, "w": v, "tau": np.ones(20)})
    out = tmp_path / "l.json"
    assert main(["lugre", str(tmp_path / "log.csv"), "--target", "tau", "--velocity", "w",
                 "-o", str(out), "--quiet"]) == 2
    assert capsys.readouterr().err == ("edm: log.csv: column 'w': expected values whose "
                                       "largest magnitude is from 1e-150 to 1e+150 (their "
                                       "squares normal numbers), found 1e+308\n")
    assert not out.exists()


# ----------------------------------------------------------------- LUGRE.json


def a_result() -> LuGreResult:
    return LuGreResult(params=STIFF, method="scipy", rmse=0.0123, evaluations=42, sample_time=TS)


def valid_document(tmp_path: Path) -> dict:
    path = tmp_path / "lugre.json"
    save_lugre(path, a_result(), target="tau_ext", velocity="omega", data_sha256=SHA, seed=3)
    return json.loads(path.read_text())


def test_save_load_round_trip(tmp_path):
    path = tmp_path / "sub" / "LUGRE.json"
    save_lugre(path, a_result(), target="tau_ext", velocity="omega", data_sha256=SHA, seed=3)
    text = path.read_text()
    assert text.endswith("}\n")
    assert text == json.dumps(json.loads(text), sort_keys=True, indent=2) + "\n"
    assert [p.name for p in path.parent.iterdir()] == ["LUGRE.json"]  # no temporary left
    loaded = load_lugre(path)
    assert loaded.params == STIFF
    assert (loaded.method, loaded.rmse, loaded.evaluations, loaded.sample_time) == (
        "scipy", 0.0123, 42, TS,
    )  # fmt: skip
    assert (loaded.target_name, loaded.velocity_name) == ("tau_ext", "omega")
    assert loaded.provenance.seed == 3 and loaded.provenance.data_sha256 == SHA
    doc = json.loads(text)
    assert doc["format"] == "edm-lugre" and doc["version"] == 1 and doc["fitness"] == 0.0123
    jsonschema.validate(doc, lugre.lugre_schema())


def test_save_refuses_invalid_document(tmp_path):
    path = tmp_path / "LUGRE.json"
    with pytest.raises(ValueError, match="data_sha256"):
        save_lugre(path, a_result(), target="y", velocity="v", data_sha256="xyz", seed=0)
    assert not path.exists()


def set_at(doc: dict, dotted: str, value) -> dict:
    *parents, last = dotted.split(".")
    node = doc
    for key in parents:
        node = node[key]
    if value is DELETE:
        del node[last]
    else:
        node[last] = value
    return doc


DELETE = object()

CORRUPTIONS = [
    ("format", "edm-result", "lugre.json: format", 'expected "edm-lugre", found "edm-result"'),
    ("version", 2, "lugre.json: version", "expected 1, found 2"),
    (
        "parameters.sigma0",
        -3,
        "lugre.json: parameters.sigma0",
        "expected a positive number, found -3",
    ),
    ("parameters.sigma0", DELETE, "lugre.json: parameters.sigma0", "required field is missing"),
    ("parameters.tau_c", "1.0", "lugre.json: parameters.tau_c", 'expected a number, found "1.0"'),
    ("parameters.sigma1", -0.5, "lugre.json: parameters.sigma1", "expected a non-negative number"),
    ("parameters.v_s", 0, "lugre.json: parameters.v_s", "expected a positive number, found 0"),
    ("parameters.sigma3", 1.0, "lugre.json: parameters.sigma3", "unexpected field"),
    ("sample_time", 0.0, "lugre.json: sample_time", "expected a positive number"),
    ("evaluations", 1.5, "lugre.json: evaluations", "expected an integer, found 1.5"),
    ("target", "", "lugre.json: target", "expected a non-empty string"),
    ("velocity", DELETE, "lugre.json: velocity", "required field is missing"),
    ("fitness", None, "lugre.json: fitness", "expected a number, found null"),
    ("provenance.data_sha256", "abc", "lugre.json: provenance.data_sha256", "64 lowercase hex"),
    ("provenance.seed", True, "lugre.json: provenance.seed", "expected an integer, found true"),
    ("parameters", [1, 2], "lugre.json: parameters", "expected an object"),
]


@pytest.mark.parametrize(("field", "value", "where", "problem"), CORRUPTIONS)
def test_corrupted_field_is_refused(tmp_path, field, value, where, problem):
    doc = set_at(valid_document(tmp_path), field, value)
    path = tmp_path / "lugre.json"
    path.write_text(json.dumps(doc))
    with pytest.raises(ResultFormatError) as info:
        load_lugre(path)
    assert info.value.where == where
    assert problem in info.value.problem


def test_sigma0_message_is_one_clear_line(tmp_path):
    path = tmp_path / "lugre.json"
    path.write_text(json.dumps(set_at(valid_document(tmp_path), "parameters.sigma0", -3)))
    with pytest.raises(ResultFormatError) as info:
        load_lugre(path)
    assert str(info.value) == "lugre.json: parameters.sigma0: expected a positive number, found -3"


def test_bound_across_fields_is_refused(tmp_path):
    doc = valid_document(tmp_path)
    doc["parameters"].update(tau_c=0.0, tau_s=0.0)
    path = tmp_path / "lugre.json"
    path.write_text(json.dumps(doc))
    with pytest.raises(ResultFormatError, match="parameters.tau_s: tau_c \\+ tau_s must be positive"):
        load_lugre(path)


@pytest.mark.parametrize(
    ("text", "where", "problem"),
    [
        ("", "lugre.json: line 1 column 1", "invalid JSON"),
        ('{"format": "edm-lugre",', "lugre.json: line 1", "invalid JSON"),
        ("[1, 2]", "lugre.json", "expected a JSON object at the top level"),
        (None, "lugre.json", "NaN is not allowed"),
        (None, "lugre.json: parameters.sigma2", "finite"),
        (None, "lugre.json", "duplicate key 'format'"),
    ],
    ids=["empty", "truncated", "list", "nan", "overflow", "duplicate"],
)
def test_malformed_file_is_refused(tmp_path, text, where, problem, request):
    good = json.dumps(valid_document(tmp_path), sort_keys=True, indent=2)
    case = request.node.callspec.id
    if case == "nan":
        text = good.replace('"sigma1": 30.0', '"sigma1": NaN')
    elif case == "overflow":
        text = good.replace('"sigma2": 0.01', '"sigma2": 1e999')
    elif case == "duplicate":
        text = good.replace('"format": "edm-lugre"', '"format": "edm-lugre", "format": "x"')
    path = tmp_path / "lugre.json"
    path.write_text(text)
    with pytest.raises(ResultFormatError) as info:
        load_lugre(path)
    assert info.value.where.startswith(where)
    assert problem in info.value.problem


def test_missing_or_binary_file_is_refused(tmp_path):
    with pytest.raises(ResultFormatError, match="no such file"):
        load_lugre(tmp_path / "absent.json")
    path = tmp_path / "lugre.json"
    path.write_bytes(b"\xff\xfe{}")
    with pytest.raises(ResultFormatError, match="not UTF-8"):
        load_lugre(path)


def leaf_paths(doc, prefix=()):
    for key, value in doc.items():
        if isinstance(value, dict):
            yield from leaf_paths(value, (*prefix, key))
        yield (*prefix, key)


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.data())
def test_any_corruption_loads_cleanly_or_is_refused_clearly(tmp_path, data):
    doc = valid_document(tmp_path)
    path_in_doc = data.draw(st.sampled_from(sorted(leaf_paths(doc))))
    path = write_corrupted(doc, path_in_doc, data, tmp_path)
    try:
        loaded = load_lugre(path)
    except ResultFormatError as exc:
        assert exc.where.startswith("lugre.json")
        dotted = ".".join(str(k) for k in path_in_doc)
        assert dotted.split(".")[0] in exc.where or exc.where == "lugre.json"
        assert "\n" not in str(exc)
    else:
        assert isinstance(loaded, LuGreResult)


def test_an_odd_key_is_named_quoted_on_one_line(tmp_path):
    doc = valid_document(tmp_path)
    doc["parameters"]["a\nb c"] = 1.0
    path = tmp_path / "lugre.json"
    path.write_text(json.dumps(doc))
    with pytest.raises(ResultFormatError) as info:
        load_lugre(path)
    assert "\n" not in str(info.value)
    assert info.value.where == 'lugre.json: parameters["a\\nb c"]'


# --------------------------------------------------------------------- hygiene


def test_schema_is_declared_as_package_data():
    # An installed edm_sym must carry lugre.schema.json, or load_lugre cannot work.
    pyproject = Path(__file__).resolve().parents[1] / "pyproject.toml"
    if not pyproject.exists():
        pytest.skip("not running from a source tree")
    try:
        import tomllib
    except ModuleNotFoundError:  # Python 3.10
        import tomli as tomllib
    config = tomllib.loads(pyproject.read_text())
    package_data = config.get("tool", {}).get("setuptools", {}).get("package-data", {})
    candidates = [(p, "lugre/lugre.schema.json") for p in package_data.get("edm_sym", [])]
    candidates += [(p, "lugre.schema.json") for p in package_data.get("edm_sym.engines.lugre", [])]
    assert any(fnmatch.fnmatch(name, pattern) for pattern, name in candidates), (
        "pyproject.toml: [tool.setuptools.package-data] must ship the LuGre schema, e.g. "
        'edm_sym = [..., "lugre/*.json"]'
    )


def test_schema_file_is_a_valid_schema():
    jsonschema.Draft202012Validator.check_schema(lugre.lugre_schema())


@pytest.mark.parametrize("name", lugre.__all__)
def test_public_api_is_documented(name):
    obj = getattr(lugre, name)
    if not (inspect.isfunction(obj) or inspect.isclass(obj)):
        return
    doc = inspect.getdoc(obj) or ""
    assert doc, f"{name} has no docstring"
    if inspect.isfunction(obj) and inspect.signature(obj).parameters:
        assert "Parameters\n----------" in doc, f"{name}: no numpydoc Parameters section"
