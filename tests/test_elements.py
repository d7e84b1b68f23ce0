"""Every element against an independent oracle on a 20 000-sample signal."""

from __future__ import annotations

import math

import control
import numpy as np
import pytest
from conftest import TS, N, smooth_signal
from scipy import signal as sps

from edm_sym.core.elements import (
    BY_NAME,
    REGISTRY,
    DelayElement,
    LinearElement,
    RelayElement,
    StaticElement,
    all_elements,
    default_ranges,
    element,
)
from edm_sym.core.elements.base import Element, ParamRange
from edm_sym.core.elements.base import StaticElement as _Static

RANGES = default_ranges(TS, N * TS)
ELEMENTS = all_elements()


def value(el: type[Element], p: float = 0.5) -> float | None:
    return RANGES[el.name].decode(p) if el.param else None


def test_registry_has_the_papers_thirty_elements() -> None:
    assert len(REGISTRY) == 30
    assert sorted(REGISTRY) == list(range(30))
    cats = {c: sum(e.category == c for e in ELEMENTS) for c in ("basic", "calculation", "nonlinear")}
    assert cats == {"basic": 3, "calculation": 12, "nonlinear": 15}


def test_duplicate_code_is_an_error() -> None:
    with pytest.raises(ValueError, match="already used"):
        class Twice(_Static):  # noqa: F841
            name = "twice"
            code = 3
            title = "Twice"
            category = "basic"
            formula = "y = 2 x"
    assert "twice" not in BY_NAME


def test_missing_declaration_is_an_error() -> None:
    with pytest.raises(TypeError, match="does not declare"):
        class Bare(_Static):  # noqa: F841
            name = "bare"
            code = 99
            title = "Bare"
            category = "basic"


@pytest.mark.parametrize("scaling,low,high", [("linear", -3.0, 7.0), ("log", 1e-3, 1e3)])
def test_range_decode_encode(scaling: str, low: float, high: float) -> None:
    r = ParamRange(low, high, scaling)
    assert r.decode(0.0) == pytest.approx(low)
    assert r.decode(1.0) == pytest.approx(high)
    if scaling == "log":  # eq. 5: the midpoint is the geometric mean
        assert r.decode(0.5) == pytest.approx(math.sqrt(low * high))
    else:  # eq. 4
        assert r.decode(0.5) == pytest.approx((low + high) / 2)
    for p in (0.0, 0.13, 0.5, 0.99):
        assert r.encode(r.decode(p)) == pytest.approx(p)


def test_default_ranges_follow_eqs_6_and_7() -> None:
    r = default_ranges(1e-3, 20.0)
    assert r["lpf"].low == pytest.approx(2 * math.pi / 20.0)
    assert r["lpf"].high == pytest.approx(math.pi / 1e-3)
    assert r["lpf"].scaling == "log"
    assert r["dead_time"].low == pytest.approx(1e-3)
    assert r["dead_time"].high == pytest.approx(20.0)


@pytest.mark.parametrize("el", ELEMENTS, ids=lambda e: e.name)
def test_vectorised_equals_per_sample_loop(el: type[Element], signal: np.ndarray) -> None:
    x = 3.0 * signal
    a = value(el)
    y = el.simulate(x, a, TS)
    step = el.stepper(a, TS)
    y2 = np.array([step(v) for v in x.tolist()])
    np.testing.assert_allclose(y, y2, rtol=1e-12, atol=1e-12)


# -- static elements against closed forms written independently here ----------
def _closed_forms() -> dict:
    return {
        "through": lambda x, a: x,
        "invert": lambda x, a: -x,
        "offset": lambda x, a: x + a,
        "gain": lambda x, a: a * x,
        "power_gain": lambda x, a: a * x,
        "saturation": lambda x, a: np.array([min(max(v, -a), a) for v in x]),
        "one_way": lambda x, a: np.array([v if v > a else a for v in x]),
        "dead_zone": lambda x, a: np.array([v - a if v > a else v + a if v < -a else 0.0 for v in x]),
        "sign": lambda x, a: np.array([math.copysign(1.0, v) if v != 0 else 0.0 for v in x]),
        "log": lambda x, a: np.array([math.copysign(math.log(1 + abs(v) / a), v) for v in x]),
        "power": lambda x, a: np.array([math.copysign(abs(v) ** a, v) for v in x]),
        "sin_phase": lambda x, a: np.array([math.sin(v + a) for v in x]),
        "sin_amp": lambda x, a: np.array([a * math.sin(v) for v in x]),
        "tan_phase": lambda x, a: np.array([math.tan(v + a) for v in x]),
        "tan_amp": lambda x, a: np.array([a * math.tan(v) for v in x]),
        "asin": lambda x, a: np.array([math.asin(max(-1.0, min(1.0, v))) for v in x]),
        "acos": lambda x, a: np.array([math.acos(max(-1.0, min(1.0, v))) for v in x]),
        "atan": lambda x, a: np.array([math.atan(a * v) for v in x]),
        "tanh": lambda x, a: np.array([math.tanh(a * v) for v in x]),
    }


STATIC = [e for e in ELEMENTS if issubclass(e, StaticElement)]


def test_every_static_element_has_an_oracle() -> None:
    assert {e.name for e in STATIC} == set(_closed_forms())


@pytest.mark.parametrize("el", STATIC, ids=lambda e: e.name)
@pytest.mark.parametrize("p", [0.1, 0.5, 0.9])
def test_static_against_closed_form(el: type[Element], p: float, signal: np.ndarray) -> None:
    x = 1.4 * signal  # tan stays away from its poles here; asin/acos see |x| > 1
    a = value(el, p)
    np.testing.assert_allclose(el.simulate(x, a, TS), _closed_forms()[el.name](x, a),
                               rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("el", STATIC, ids=lambda e: e.name)
def test_static_guards_keep_outputs_finite(el: type[Element]) -> None:
    x = np.array([-1e300, -1e4, -math.pi / 2, -1.0, -1e-300, 0.0, 1e-300, 1.0, math.pi / 2,
                  1e4, 1e300])
    for p in (0.0, 0.5, 1.0):
        assert np.all(np.isfinite(el.simulate(x, value(el, p), TS)))


# -- linear elements: python-control simulation, and the continuous limit ------
LINEAR = [e for e in ELEMENTS if issubclass(e, LinearElement)]


@pytest.mark.parametrize("el", LINEAR, ids=lambda e: e.name)
@pytest.mark.parametrize("p", [0.2, 0.6])
def test_linear_against_python_control(el: type[LinearElement], p: float,
                                       signal: np.ndarray) -> None:
    a = value(el, p)
    num, den = el.tf(a)
    if len(num) > len(den):  # improper (derivative): realise s = (1 - z^-1)/Ts directly
        sysd = control.tf([num[0], -num[0]], [TS, 0], dt=TS)
    else:
        method = {"bilinear": "tustin", "backward_diff": "backward_diff"}[el.method]
        sysd = control.sample_system(control.tf(num, den), TS, method=method)
    resp = control.forced_response(sysd, U=signal)
    np.testing.assert_allclose(el.simulate(signal, a, TS), np.squeeze(resp.outputs),
                               rtol=1e-8, atol=1e-9 * max(1.0, np.max(np.abs(resp.outputs))))


@pytest.mark.parametrize("el", LINEAR, ids=lambda e: e.name)
def test_linear_approaches_continuous_time(el: type[LinearElement]) -> None:
    """Halving Ts (twice) brings the discrete response closer to the exact continuous one."""
    t_end = 4.0
    a = 20.0 if el.name not in ("derivative", "integral") else 0.5
    num, den = el.tf(a)
    errs = []
    for ts in (4e-3, 1e-3, 2.5e-4):
        t = np.arange(int(t_end / ts)) * ts
        u = np.sin(2 * np.pi * 1.3 * t) + 0.5 * np.sin(2 * np.pi * 3.1 * t + 1)
        if len(num) > len(den):  # a s: the exact response is a u'(t)
            exact = a * (2 * np.pi * 1.3 * np.cos(2 * np.pi * 1.3 * t)
                         + 0.5 * 2 * np.pi * 3.1 * np.cos(2 * np.pi * 3.1 * t + 1))
        else:
            # fine continuous simulation with scipy's lsim on the continuous system
            _, exact, _ = sps.lsim((np.array(num, float), np.array(den, float)), u, t)
        y = el.simulate(u, a, ts)
        skip = int(0.2 / ts)  # start-up differs for the improper derivative
        errs.append(np.sqrt(np.mean((y[skip:] - exact[skip:]) ** 2)))
    assert errs[2] < errs[1] < errs[0]
    assert errs[2] < 0.05 * max(1.0, np.sqrt(np.mean(exact**2)))


# -- delays and hysteresis against hand-computed sequences ---------------------
def test_dead_time_hand_sequence() -> None:
    dt = element("dead_time")
    x = np.array([1.0, 2.0, 3.0, 4.0, 5.0, 6.0])
    np.testing.assert_array_equal(dt.simulate(x, 3e-3, TS), [0, 0, 0, 1, 2, 3])
    np.testing.assert_array_equal(dt.simulate(x, 2.4e-3, TS), [0, 0, 1, 2, 3, 4])
    np.testing.assert_array_equal(dt.simulate(x, 1e-3, TS), [0, 1, 2, 3, 4, 5])
    assert dt.state_size(3e-3, TS) == 3


def test_shift_hand_sequence() -> None:
    sh = element("shift")
    x = np.array([1.0, -2.0, 3.0, 4.0])
    np.testing.assert_array_equal(sh.simulate(x, 1.0, TS), [0, 1, -2, 3])
    np.testing.assert_array_equal(sh.simulate(x, 2.6, TS), [0, 0, 0, 1])


def test_hysteresis_hand_sequence() -> None:
    hy = element("hysteresis")
    x = np.array([0.0, 0.05, 0.2, 0.05, -0.05, -0.2, -0.05, 0.09, 0.1, 0.0])
    want = np.array([0, 0, 1, 1, 1, -1, -1, -1, 1, 1], dtype=float)
    np.testing.assert_array_equal(hy.simulate(x, 0.1, TS), want)
    # batch axis: each row keeps its own state
    both = hy.simulate(np.vstack([x, -x]), 0.1, TS)
    np.testing.assert_array_equal(both, np.vstack([want, -want]))


def test_derivative_and_integral_closed_forms() -> None:
    t = np.arange(N) * TS
    x = t**2
    d = element("derivative").simulate(x, 1.0, TS)
    np.testing.assert_allclose(d[1:], (2 * t - TS)[1:], rtol=1e-9)  # backward difference
    i = element("integral").simulate(np.ones(N), 2.0, TS)
    np.testing.assert_allclose(i, 2.0 * (np.arange(N) * TS + TS / 2), rtol=1e-9)  # Tustin


@pytest.mark.parametrize("el", ELEMENTS, ids=lambda e: e.name)
def test_state_size_matches_realisation(el: type[Element]) -> None:
    a = value(el)
    if issubclass(el, LinearElement):
        b, den = el.coefficients(a, TS)
        assert el.state_size(a, TS) == max(len(b), len(den)) - 1
    elif issubclass(el, DelayElement):
        assert el.state_size(a, TS) == el.samples(a, TS)
    elif issubclass(el, RelayElement):
        assert el.state_size(a, TS) == 1
    else:
        assert el.state_size(a, TS) == 0


@pytest.mark.parametrize("el", ELEMENTS, ids=lambda e: e.name)
def test_traits_say_what_the_element_computes(el: type[Element], signal: np.ndarray) -> None:
    # The traits other modules ask instead of a kind or a name (docs/architecture.md).
    from edm_sym.core.elements.realisation import DelayLine, LinearFilter, Relay, StaticMap

    a = value(el, 0.3)
    r = el.realise(a, TS)
    kinds = {"is_static": StaticMap, "is_filter": LinearFilter, "is_delay": DelayLine,
             "is_relay": Relay}
    assert [t for t, cls in kinds.items() if getattr(el, t)] == [
        t for t, cls in kinds.items() if isinstance(r, cls)]
    y = el.simulate(signal, a, TS)
    if el.is_identity:
        np.testing.assert_array_equal(y, signal)
    if el.multiplies_output:  # a factor on a is a factor on the output
        np.testing.assert_allclose(el.simulate(signal, 1.5 * a, TS), 1.5 * y, rtol=1e-9,
                                   atol=1e-12 * float(np.max(np.abs(y))))
    if el.scales_output:
        assert el.multiplies_output
    if el.tangent_argument is not None:  # tan of the argument, away from its poles
        x = np.linspace(-0.3, 0.3, 101)
        want = np.tan(el.tangent_argument(x, a)) * (a if el.scales_output else 1.0)
        np.testing.assert_allclose(el.simulate(x, a, TS), want, rtol=1e-9)


def test_batch_axis_matches_single(signal: np.ndarray) -> None:
    x = np.vstack([signal, 2 * signal, -signal])
    for el in ELEMENTS:
        a = value(el, 0.3)
        y = el.simulate(x, a, TS)
        for k in range(3):
            np.testing.assert_allclose(y[k], el.simulate(x[k], a, TS), rtol=1e-13, atol=1e-13)


def test_smooth_signal_fixture_is_nontrivial() -> None:
    s = smooth_signal()
    assert s.shape == (N,) and 0.1 < np.std(s) < 1.0


def _libm_arguments(name: str) -> np.ndarray:
    rng = np.random.default_rng(7)
    x = np.concatenate([rng.standard_normal(100_000) * s for s in (1e-17, 1e-6, 0.3, 1, 4, 25, 1e6)]
                       + [[0.0, -0.0, 1.0, np.nextafter(1.0, 0.0), 22.0, np.nextafter(22.0, 0.0),
                           2.0**-55, np.nextafter(2.0**-55, 0.0), 5e-324, np.inf, 1e308, np.nan]])
    x = np.concatenate([x, -x])
    if name in ("asin", "acos"):
        x = np.concatenate([np.clip(x, -1.0, 1.0), np.nextafter(1.0, 0.0) - np.arange(1000) * 2e-16])
    if name in ("log1p", "pow"):
        x = np.minimum(np.abs(x), 1e6)  # as the elements call them (|x| / a, limited)
    return x


def _c_library(name: str, x: np.ndarray, *a: float) -> np.ndarray:
    fn = getattr(math, name)

    def one(v: float) -> float:
        try:
            return fn(v, *a)
        except ValueError:  # C: NaN (sin(inf), tan(inf))
            return math.nan

    return np.array([one(v) for v in x.tolist()])


@pytest.mark.parametrize("mode", ["compiled", "interpreted"])
@pytest.mark.parametrize("name", ["sin", "cos", "tan", "asin", "acos", "atan", "tanh", "log1p",
                                  "pow"])
def test_the_simulators_functions_are_the_c_librarys_to_the_bit(name: str, mode: str) -> None:
    # The generated C and Python call the C library; numpy's own float64 functions differ
    # from it in the last bit on some arguments, on some processors (on an AVX-512 one:
    # tan, asin, acos, atan, log1p, pow, expm1 and tanh, on 0.1-25 % of arguments).
    import warnings

    from edm_sym.core.elements import libm

    if mode == "compiled" and not libm.use_compiled():
        pytest.skip("numba is not installed")
    fn = libm._compiled(name) if mode == "compiled" else libm._interpreted(name)
    x = _libm_arguments(name)
    exponents = (0.0, 0.37, 1.0, 1.7, 48.0) if name == "pow" else (None,)
    for a in exponents:
        args = () if a is None else (a,)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)  # sin(inf) is invalid, as in numpy
            got = fn(x, *args, out=np.empty_like(x))
        want = _c_library(name, x, *args)
        same = (got.view(np.int64) == want.view(np.int64)) | (np.isnan(got) & np.isnan(want))
        assert same.all(), (name, a, x[~same][:5], got[~same][:5], want[~same][:5])


def test_the_simulators_static_elements_give_the_plain_loops_bits() -> None:
    # The simulator (numpy arrays) and the per-sample loop (Python floats, math's
    # functions: the C library's, as the generated code calls them) give the same bits
    # for every static element, anywhere in its range.
    from edm_sym.core.elements.ops import NUMPY, SCALAR

    rng = np.random.default_rng(3)
    x = np.concatenate([rng.standard_normal(20_000) * s for s in (0.01, 1.0, 30.0, 1e4)])
    x = np.concatenate([x, [0.0, 1.0, -1.0, np.nextafter(1.0, 0.0), np.pi / 2]])
    for el in STATIC:
        for p in (0.0, 0.13, 0.5, 0.91, 1.0):
            a = RANGES[el.name].decode(p) if el.param is not None else None
            with np.errstate(all="ignore"):
                got = np.asarray(el.f(NUMPY, x, a), dtype=float) * np.ones_like(x)
            want = np.array([el.f(SCALAR, v, a) for v in x.tolist()], dtype=float)
            same = (got.view(np.int64) == want.view(np.int64)) | (np.isnan(got) & np.isnan(want))
            assert same.all(), (el.name, p, x[~same][:3], got[~same][:3], want[~same][:3])
