"""The generated C, compiled by gcc and clang with every warning an error, against the simulator.

Needs a host C compiler (marked ``toolchain``; skipped when gcc/clang is missing).
Double precision must match the reference simulator to 1e-9 N m at every
sample of a 20 000-sample log; single precision to 1e-4 of the RMS of the
compensation torque (docs/api.md#numerical-agreement).
"""

from __future__ import annotations

import shutil
import warnings
from pathlib import Path

import numpy as np
import pytest

# tests/ is on sys.path (pytest's rootdir-relative import mode): the shared harness.
from firmware import cg_support as cg  # noqa: E402

from edm_sym import load_result
from edm_sym.application.exporting import export
from edm_sym.core.elements import all_elements
from edm_sym.engines.simulate import simulate

pytestmark = pytest.mark.toolchain

COMPILERS = [pytest.param(cc, marks=pytest.mark.skipif(not shutil.which(cc),
                                                       reason=f"{cc} is not installed"))
             for cc in ("gcc", "clang")]
REALS = ["double", "float"]
LOG = cg.make_log()
X = cg.input_matrix(LOG)

#: Symbols a compensator object may leave undefined: C99 <math.h> functions, and the
#: block operations compilers emit for loops (every C implementation, freestanding
#: ones included, must provide them; the source never calls them).
LIBM = {f"{name}{suffix}" for name in ("sin", "cos", "tan", "asin", "acos", "atan", "tanh",
                                       "log1p", "log", "exp", "pow", "fabs", "fmax", "fmin",
                                       "sqrt") for suffix in ("", "f")}
COMPILER_EMITTED = {"memset", "memcpy", "memmove"}


def element_cases() -> dict[str, object]:
    """prefix -> compensator: one matrix per element, and the shipped example."""
    cases = {f"el_{e.name}": cg.element_compensator(e.name) for e in all_elements()}
    cases["edm_comp"] = load_result(cg.EXAMPLE)
    return cases


CASES = element_cases()


def reference(case) -> np.ndarray:  # noqa: ANN001
    sim = simulate(case, LOG)
    return np.vstack([sim.rows, sim.total]).T


@pytest.fixture(scope="module")
def host_runs(tmp_path_factory: pytest.TempPathFactory):  # noqa: ANN201
    """(cc, real) -> (folder, prefix -> output array), built once per module."""
    cache: dict = {}

    def get(cc: str, real: str):  # noqa: ANN202
        if (cc, real) not in cache:
            folder = tmp_path_factory.mktemp(f"{cc}_{real}")
            for prefix, case in CASES.items():
                result = case if hasattr(case, "sha256") else cg.as_result(case)
                export(result, "c", folder, prefix=prefix, real=real)
            cache[cc, real] = folder, cg.build_and_run_host(cc, folder, list(CASES), X)
        return cache[cc, real]

    return get


@pytest.mark.parametrize("cc", COMPILERS)
def test_double_matches_the_simulator_to_1e_9(cc: str, host_runs) -> None:  # noqa: ANN001
    _, outputs = host_runs(cc, "double")
    for prefix, case in CASES.items():
        ref = reference(case)
        got = outputs[prefix]
        assert got.shape == ref.shape == (cg.N_SAMPLES, ref.shape[1])
        err = cg.max_abs(got, ref)
        assert err <= 1e-9, f"{prefix}: max |C - simulator| = {err:.3g} N m"


@pytest.mark.parametrize("cc", COMPILERS)
def test_float_matches_the_simulator_to_1e_4_of_rms(cc: str, host_runs) -> None:  # noqa: ANN001
    _, outputs = host_runs(cc, "float")
    for prefix, case in CASES.items():
        ref = reference(case)
        rms = float(np.sqrt(np.mean(ref[:, -1] ** 2)))
        err = cg.max_abs(outputs[prefix], ref)
        assert rms > 0 and err <= 1e-4 * rms, f"{prefix}: {err:.3g} > 1e-4 x RMS {rms:.3g}"


@pytest.mark.parametrize("real", REALS)
@pytest.mark.parametrize("cc", COMPILERS)
def test_objects_hold_no_mutable_static_data_and_no_allocator(cc: str, real: str,
                                                              host_runs) -> None:  # noqa: ANN001
    nm = shutil.which("nm")
    if nm is None:
        pytest.skip("nm is not installed")
    folder, _ = host_runs(cc, real)
    for prefix in CASES:
        symbols = cg.nm_symbols(nm, folder / f"{prefix}.o")
        data = [(t, s) for t, s in symbols if t in "DdBbCGgSsVv"]
        assert not data, f"{prefix}: mutable static data {data}"
        undefined = {s for t, s in symbols if t == "U"}
        assert not undefined & {"malloc", "calloc", "realloc", "free"}, prefix
        assert undefined <= LIBM | COMPILER_EMITTED, f"{prefix}: calls {sorted(undefined - LIBM)}"
        defined = {s for t, s in symbols if t == "T"}
        assert defined == {f"{prefix}_init", f"{prefix}_step"}, f"{prefix}: exports {defined}"


@pytest.mark.parametrize("cc", COMPILERS)
def test_header_stands_alone(cc: str, tmp_path: Path) -> None:
    export(load_result(cg.EXAMPLE), "c", tmp_path, real="float")
    (tmp_path / "only.c").write_text('#include "edm_comp.h"\n#include "edm_comp.h"\n'
                                     "int size_of_state(void);\n"
                                     "int size_of_state(void) { return (int)sizeof(edm_comp_state_t); }\n")
    cg.run([cc, *cg.STRICT, "-c", "only.c"], cwd=tmp_path)


def sweep(cc: str, count: int, tmp_path: Path, run_count: int) -> None:
    """Export ``count`` random matrices (every element used), compile all in both reals.

    The first ``run_count`` are also linked into one program and run over a
    short log; in double they must agree with the simulator.
    """
    rng = np.random.default_rng(7)
    comps = [cg.random_compensator(rng, must_use=k % 30) for k in range(count)]
    used = {g.code for c in comps for r in c.matrix.rows for g in r.genes}
    assert used == {e.code for e in all_elements()}
    n = 500
    short = {k: v[:n] for k, v in LOG.items()}
    for real in REALS:
        folder = tmp_path / real
        prefixes = [f"rnd{k:03d}" for k in range(count)]
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # single-precision sensitivity warnings
            for prefix, comp in zip(prefixes, comps, strict=True):
                export(cg.as_result(comp), "c", folder, prefix=prefix, real=real)
        rest = prefixes[run_count:]
        if rest:
            cg.compile_objects(cc, [folder / f"{p}.c" for p in rest], folder, ["-O1"])
        outputs = cg.build_and_run_host(cc, folder, prefixes[:run_count], X[:n])
        if real == "double":
            for prefix, comp in zip(prefixes[:run_count], comps[:run_count], strict=True):
                sim = simulate(comp, short)
                ref = np.vstack([sim.rows, sim.total]).T
                ok = np.abs(outputs[prefix] - ref) <= 1e-9 * np.maximum(1.0, np.abs(ref))
                assert ok.all(), f"{prefix}: {comp.matrix}"


@pytest.mark.parametrize("cc", COMPILERS)
def test_random_matrices_compile_and_run(cc: str, tmp_path: Path) -> None:
    sweep(cc, 30, tmp_path, run_count=30)


@pytest.mark.slow
@pytest.mark.parametrize("cc", COMPILERS)
def test_200_random_matrices_compile(cc: str, tmp_path: Path) -> None:
    sweep(cc, 200, tmp_path, run_count=40)
