"""Pole-bearing elements in generated C, float and double, against the simulator.

Each element with a pole, a domain edge or an overflow on its way (the
tangents, the sines with a phase, arc sine and cosine, the guarded logarithm
and power, atan, tanh) gets one matrix whose rows hold it at p = 0, 1, 0.5
and just inside the edges; its input sweeps zero, tiny and large values (all
exact in float, so the simulator and the C see the same input).

* double: every sample within 1e-9 of the simulator (relative, floor 1);
* float, at p in {0, 1, 0.5} on zero and tiny inputs: within 1e-5 of the
  simulator (relative, floor 1). A parameter at its range edge must not put
  the output on the far side of a pole: ``tan_phase`` at p = 0 is tan(-pi/2),
  and -pi/2 rounds below -pi/2 in float, where tan is +inf rather than -inf;
* float, elsewhere: within what float can resolve, the hull of the element
  over its parameter rounded to float and (for a phase) over one float step of
  the argument ``x + a``, widened by 1e-5.

Needs a host C compiler (marked ``toolchain``).
"""

from __future__ import annotations

import shutil

import numpy as np
import pytest

# tests/ is on sys.path (pytest's rootdir-relative import mode): the shared harness.
from firmware import cg_support as cg  # noqa: E402

from edm_sym.application.exporting import export
from edm_sym.core.elements import BY_NAME, default_ranges
from edm_sym.core.elements.ops import NUMPY, TAN_LIMIT
from edm_sym.core.matrix import Compensator, make_matrix
from edm_sym.engines.simulate import simulate

pytestmark = pytest.mark.toolchain
CC = next((cc for cc in ("gcc", "clang") if shutil.which(cc)), None)

ELEMENTS = ("tan_phase", "tan_amp", "sin_phase", "sin_amp", "asin", "acos", "log", "power",
            "atan", "tanh")
#: p at the range edges, the middle, and one float step (about 6e-8) and more inside the edges.
P_STRICT = (0.0, 1.0, 0.5)
P_EDGES = (1e-7, 1.0 - 1e-7, 1e-4, 1.0 - 1e-4)
TS = 1e-3


def _inputs() -> np.ndarray:
    half_pi = float(np.float32(np.pi / 2))
    mags = [0.0, 2.0**-126, 2.0**-100, 1e-30, 0.5, 1.0, half_pi, 3.0, 1e6, 2.0**50, 1e30, 2.0**127]
    vals = sorted({s * m for m in mags for s in (1.0, -1.0)})
    x = np.asarray(vals, dtype=np.float32).astype(np.float64)
    assert np.all(x.astype(np.float32).astype(np.float64) == x)  # exact in float
    return x


X = _inputs()
TINY = np.abs(X) < 1e-20  # zero and tiny inputs


def _compensator(name: str) -> tuple[Compensator, tuple[float, ...]]:
    ps = P_STRICT + P_EDGES if BY_NAME[name].param is not None else (0.5,)
    rows = [("theta_w", [(name, p)]) for p in ps]
    return Compensator(make_matrix(("theta_w",), rows), TS, {}, 20.0), ps


CASES = {name: _compensator(name) for name in ELEMENTS}


@pytest.fixture(scope="module")
def outputs(tmp_path_factory: pytest.TempPathFactory):  # noqa: ANN201
    if CC is None:
        pytest.skip("no host C compiler (gcc or clang)")
    out = {}
    for real in ("double", "float"):
        folder = tmp_path_factory.mktemp(real)
        for name, (comp, _) in CASES.items():
            export(cg.as_result(comp), "c", folder, prefix=f"el_{name}", real=real)
        out[real] = cg.build_and_run_host(CC, folder, [f"el_{n}" for n in CASES], X[:, None])
    return out


def _reference(name: str) -> np.ndarray:
    comp, _ = CASES[name]
    return simulate(comp, {"theta_w": X}).rows


def _hull(name: str, a: float) -> tuple[np.ndarray, np.ndarray]:
    """The element's range of outputs over what float cannot tell apart."""
    el = BY_NAME[name]
    params = {a, float(np.float32(a))}
    if el.param is not None and el.param.period is not None:  # y = f(x + a): the sum rounds
        step = np.spacing(np.float32(np.abs(X) + abs(a))).astype(float)
        shifts = [k / 64 for k in range(-64, 65)]
    else:
        step, shifts = np.zeros_like(X), [0.0]
    with np.errstate(all="ignore"):
        ys = np.array([el.f(NUMPY, X + s * step, q) * np.ones_like(X) for q in params for s in shifts])
    lo, hi = ys.min(axis=0), ys.max(axis=0)
    if name == "tan_phase":  # a pole inside the argument's step: anything in +-TAN_LIMIT
        u = X + a
        pole = np.floor((u - step) / np.pi - 0.5) != np.floor((u + step) / np.pi - 0.5)
        lo, hi = np.where(pole, -TAN_LIMIT, lo), np.where(pole, TAN_LIMIT, hi)
    return lo, hi


@pytest.mark.parametrize("name", ELEMENTS)
def test_double_c_matches_the_simulator_everywhere(outputs, name: str) -> None:  # noqa: ANN001
    ref = _reference(name)
    got = outputs["double"][f"el_{name}"][:, :-1].T
    err = np.abs(got - ref) / np.maximum(1.0, np.abs(ref))
    bad = np.argwhere(~(err <= 1e-9))
    assert not bad.size, [(CASES[name][1][j], X[k], got[j, k], ref[j, k]) for j, k in bad[:5]]


@pytest.mark.parametrize("name", ELEMENTS)
def test_float_c_at_the_range_edges_on_zero_and_tiny_inputs(outputs, name: str) -> None:  # noqa: ANN001
    ref = _reference(name)
    got = outputs["float"][f"el_{name}"][:, :-1].T
    comp, ps = CASES[name]
    for j, p in enumerate(ps):
        if p not in P_STRICT:
            continue
        err = np.abs(got[j] - ref[j]) / np.maximum(1.0, np.abs(ref[j]))
        bad = np.flatnonzero(TINY & ~(err <= 1e-5))
        assert not bad.size, (f"{name} at p = {p}: float C {got[j, bad[:4]]} but the simulator "
                              f"{ref[j, bad[:4]]} on inputs {X[bad[:4]]}")


@pytest.mark.parametrize("name", ELEMENTS)
def test_float_c_stays_within_what_float_resolves(outputs, name: str) -> None:  # noqa: ANN001
    got = outputs["float"][f"el_{name}"][:, :-1].T
    comp, _ = CASES[name]
    for j, row in enumerate(comp.matrix.rows):
        a = comp.value(row.genes[0])
        lo, hi = _hull(name, a)
        pad = 1e-5 * np.maximum(1.0, np.maximum(np.abs(lo), np.abs(hi)))
        bad = np.flatnonzero(~((got[j] >= lo - pad) & (got[j] <= hi + pad)))
        assert not bad.size, (f"{name} at a = {a!r}: float C {got[j, bad[:4]]} outside "
                              f"[{lo[bad[:4]]}, {hi[bad[:4]]}] on inputs {X[bad[:4]]}")


def test_the_sweep_reaches_the_poles_it_is_about() -> None:
    # p = 0 and 1 put tan_phase's argument on -pi/2 and pi/2 for a zero input, where the
    # float parameter lies on the other side of the pole than the double one.
    r = default_ranges(TS, 20.0)["tan_phase"]
    for p, side in ((0.0, -1), (1.0, 1)):
        a = r.decode(p)
        assert a == side * np.pi / 2
        assert np.sign(np.tan(np.float32(a))) == -side  # float: the far side of the pole
    assert 0.0 in X and np.any(TINY & (X != 0))
