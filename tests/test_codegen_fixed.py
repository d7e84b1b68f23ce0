"""The q31 and q15 C on the host: strict warnings, sanitizers, bit for bit the Python model.

Each build is compiled by gcc (and clang: for the examples always (q31 the shipped
one, q15 the relay one of `cg_support.FIXED_EXAMPLES`), for
every element kind and the random matrices with ``--slow``) with
``-Wall -Wextra -Wconversion`` and the undefined-behaviour sanitizer (signed
overflow included); a harness runs the kit's vectors through ``<prefix>_step``
and every output must equal the bit-exact model's integer; the kit itself must
pass. Every element kind is exported in both words (a refusal must name its
row and element).
"""

from __future__ import annotations

import math
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest
from firmware import cg_support as cg  # noqa: E402

from edm_sym import load_result
from edm_sym.application.exporting import export, recorded_log
from edm_sym.core.elements import all_elements
from edm_sym.engines.fixedpoint import FixedPointError, excitation, input_ints, run_fixed
from edm_sym.engines.fixedpoint.formats import KIT_SAMPLES
from edm_sym.engines.symbolic.model import build_model
from edm_sym.outputs.render.context import source_of
from edm_sym.outputs.render.fixed_context import fixed_build

pytestmark = [pytest.mark.toolchain,
              pytest.mark.skipif(not cg.have("gcc"), reason="needs gcc")]

WARN = ["-std=c99", "-Wall", "-Wextra", "-Wpedantic", "-Wconversion", "-Wshadow", "-Werror", "-O2"]
SANITIZE = {"gcc": ["-fsanitize=undefined,signed-integer-overflow", "-fno-sanitize-recover=all"],
            # clang's runtime library is not always installed: the sanitizer traps instead.
            "clang": ["-fsanitize=undefined,signed-integer-overflow", "-fsanitize-trap=undefined"]}
#: Ranges for the test matrices, whose results record none.
RANGES = {"theta_w": (0.0, 2 * math.pi), "theta_uw": (0.0, 50.0), "omega": (-40.0, 40.0)}

HARNESS = """\
#define EDM_COMP_TEST_NO_MAIN
#include "edm_comp_test.c"
#include <stdio.h>

int main(void)
{
    edm_comp_state_t s;
    size_t k;
    edm_comp_init(&s);
    for (k = 0u; k < EDM_COMP_TEST_SAMPLES; ++k) {
        printf("%ld\\n", (long)edm_comp_step(&s, edm_comp_test_u[k], NULL));
    }
    return edm_comp_test(NULL);
}
"""


def build_and_run(result, real: str, folder: Path, cc: str = "gcc",  # noqa: ANN001
                  input_range=None) -> np.ndarray:  # noqa: ANN001
    """Export c + test, compile strictly with sanitizers, run harness and kit; the outputs."""
    export(result, "c", folder, real=real, input_range=input_range)
    export(result, "test", folder, real=real, input_range=input_range)
    (folder / "harness.c").write_text(HARNESS)
    flags = [*WARN, *SANITIZE[cc]]
    cg.run([cc, *flags, "-o", "harness", "harness.c", "edm_comp.c"], cwd=folder)
    cg.run([cc, *flags, "-o", "kit", "edm_comp_test.c", "edm_comp.c"], cwd=folder)
    kit = subprocess.run(["./kit"], cwd=folder, capture_output=True, text=True, timeout=120)
    assert kit.returncode == 0 and kit.stdout.startswith("PASS"), kit.stdout + kit.stderr
    run = subprocess.run(["./harness"], cwd=folder, capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stdout[-500:] + run.stderr
    assert "runtime error" not in run.stderr
    return np.array([int(v) for v in run.stdout.split()], dtype=np.int64)


def model_outputs(result, real: str, input_range=None) -> np.ndarray:  # noqa: ANN001
    source = source_of(result)
    model = build_model(result.compensator, sha256=source.sha256, target=result.target,
                        axis=source.axis)
    b = fixed_build(model, source, real, input_range, recorded_log(result))
    d = b.design
    x = (b.signals[:, :KIT_SAMPLES] if b.signals is not None
         else excitation(d.inputs, d.ranges, d.sample_time, KIT_SAMPLES))
    return run_fixed(d, input_ints(d, x))[1]


@pytest.mark.parametrize("cc", ["gcc", "clang"])
@pytest.mark.parametrize("real", ["q31", "q15"])
def test_example_bit_exact_and_kit_passes(real: str, cc: str, tmp_path: Path) -> None:
    if not shutil.which(cc):
        pytest.skip(f"{cc} is not installed")
    result = load_result(cg.FIXED_EXAMPLES[real])
    got = build_and_run(result, real, tmp_path, cc)
    np.testing.assert_array_equal(got, model_outputs(result, real))
    text = (tmp_path / "edm_comp.c").read_text() + (tmp_path / "edm_comp.h").read_text()
    code = re.sub(r"/\*.*?\*/", "", text, flags=re.S)  # the comments name the double simulator
    for banned in ("float", "double", "math.h"):
        assert banned not in code, banned
    assert not re.search(r"\b\d+\.\d*|\b\d+[eE][-+]?\d", code), "a real literal"


#: gcc always; clang too with --slow (it doubles the compile time).
COMPILERS = ["gcc", pytest.param("clang", marks=pytest.mark.slow)]


@pytest.mark.parametrize("cc", COMPILERS)
@pytest.mark.parametrize("real", ["q31", "q15"])
@pytest.mark.parametrize("name", sorted(e.name for e in all_elements()))
def test_every_element_kind(name: str, real: str, cc: str, tmp_path: Path) -> None:
    if not shutil.which(cc):
        pytest.skip(f"{cc} is not installed")
    result = cg.as_result(cg.element_compensator(name))
    try:
        got = build_and_run(result, real, tmp_path, cc, input_range=RANGES)
    except FixedPointError as exc:  # a refusal names the stage and says why
        assert str(exc).startswith("rows[") and "elements[" in str(exc), str(exc)
        assert "\n" not in str(exc)
        pytest.skip(f"refused: {exc}")
    np.testing.assert_array_equal(got, model_outputs(result, real, RANGES))


@pytest.mark.parametrize("cc", COMPILERS)
@pytest.mark.parametrize("seed", range(4))
def test_random_matrices(seed: int, cc: str, tmp_path: Path) -> None:
    if not shutil.which(cc):
        pytest.skip(f"{cc} is not installed")
    rng = np.random.default_rng(1000 + seed)
    codes = [e.code for e in all_elements()]
    result = cg.as_result(cg.random_compensator(rng, must_use=codes[(7 * seed) % len(codes)]))
    for real in ("q31", "q15"):
        try:
            got = build_and_run(result, real, tmp_path / real, cc, input_range=RANGES)
        except FixedPointError as exc:
            assert str(exc).startswith(("rows[", "inputs:")), str(exc)
            continue
        np.testing.assert_array_equal(got, model_outputs(result, real, RANGES))


@pytest.mark.parametrize("cc", COMPILERS)
@pytest.mark.parametrize("name", ["tan_amp", "tan_phase"])
def test_the_tangents_clear_of_their_poles(name: str, cc: str, tmp_path: Path) -> None:
    # Over +-40 rad a tangent crosses its poles and is refused; over a range clear of
    # them both words realise it (the table's margin doubles the range it covers).
    if not shutil.which(cc):
        pytest.skip(f"{cc} is not installed")
    narrow = {"theta_w": (0.0, 1.5), "theta_uw": (0.0, 50.0), "omega": (-1.5, 1.5)}
    result = cg.as_result(cg.element_compensator(name))
    for real in ("q31", "q15"):
        got = build_and_run(result, real, tmp_path / real, cc, input_range=narrow)
        np.testing.assert_array_equal(got, model_outputs(result, real, narrow))


@pytest.mark.parametrize("real", ["q31", "q15"])
def test_the_kit_applies_the_switching_rule_as_the_export_measures(real: str,
                                                                   tmp_path: Path) -> None:
    # The kit's verdict, its switching events and its raw deviation are the Python
    # measurement's on the same vectors, integer for integer.
    from edm_sym.engines.fixedpoint.accuracy import measure
    from edm_sym.engines.fixedpoint.formats import to_int

    result = load_result(cg.FIXED_EXAMPLES[real])
    export(result, "c", tmp_path, real=real)
    export(result, "test", tmp_path, real=real)
    cg.run(["gcc", *WARN, *SANITIZE["gcc"], "-o", "kit", "edm_comp_test.c", "edm_comp.c"],
           cwd=tmp_path)
    out = subprocess.run(["./kit"], cwd=tmp_path, capture_output=True, text=True, timeout=120)
    assert out.returncode == 0 and out.stdout.startswith("PASS"), out.stdout + out.stderr
    dev = int(re.search(r"max deviation (\d+) LSB \(tolerance", out.stdout).group(1))
    events, raw = map(int, re.search(r"(\d+) switching event\(s\) under the rule; without it, "
                                     r"max deviation (\d+) LSB", out.stdout).groups())
    source = source_of(result)
    model = build_model(result.compensator, sha256=source.sha256, target=result.target,
                        axis=source.axis)
    b = fixed_build(model, source, real, None, recorded_log(result))
    d = b.design
    x = b.signals[:, :KIT_SAMPLES]
    _, ref = measure(d, result.compensator, x)
    total = run_fixed(d, input_ints(d, x))[1]
    assert dev == int(np.max(np.abs(total - to_int(ref.total, d.out_frac, d.word))))
    assert raw == int(np.max(np.abs(total - to_int(ref.raw, d.out_frac, d.word))))
    assert events == len(ref.events)
    if real == "q15":  # the relay's first switching, 75 samples early, is in the kit's vectors
        assert events == 1 and raw > 100 * dev


@pytest.mark.parametrize("real", ["double", "float"])
def test_kit_of_the_real_builds_passes(real: str, tmp_path: Path) -> None:
    result = load_result(cg.EXAMPLE)
    export(result, "c", tmp_path, real=real)
    export(result, "test", tmp_path, real=real)
    cg.run(["gcc", *WARN, "-Wdouble-promotion", "-o", "kit", "edm_comp_test.c", "edm_comp.c",
            "-lm"], cwd=tmp_path)
    kit = subprocess.run(["./kit"], cwd=tmp_path, capture_output=True, text=True, timeout=120)
    assert kit.returncode == 0 and kit.stdout.startswith("PASS"), kit.stdout


def test_example_is_sized_on_its_recorded_log(tmp_path: Path) -> None:
    # The shipped example stores plant:auger/abstraction: the q31 build is sized and
    # measured on it, and the kit's vectors come from it.
    result = load_result(cg.EXAMPLE)
    export(result, "c", tmp_path, real="q31")
    export(result, "test", tmp_path, real="q31")
    header = (tmp_path / "edm_comp.h").read_text()
    kit = (tmp_path / "edm_comp_test.c").read_text()
    assert "on the log plant:auger/abstraction: measured" in " ".join(
        line.strip(" *") for line in header.splitlines())
    assert "4000 samples of the log plant:auger/abstraction" in " ".join(
        line.strip(" *") for line in kit.splitlines()[:8])


def test_a_given_log_is_used_and_a_bad_one_refused(tmp_path: Path) -> None:
    from edm_sym.core.errors import DataFormatError

    result = load_result(cg.EXAMPLE)
    x, name = recorded_log(result, data="plant:auger/evaluation")
    assert name == "plant:auger/evaluation" and x.shape[0] == len(result.compensator.matrix.inputs)
    with pytest.raises(DataFormatError):
        recorded_log(result, data=str(tmp_path / "missing.csv"))
