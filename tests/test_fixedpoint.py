"""The fixed-point design in Python: formats, the bit-exact model, the command line's refusals."""

from __future__ import annotations

import math
import re

import pytest
from firmware import cg_support as cg  # noqa: E402

from edm_sym import load_result
from edm_sym.application.cli import export_main
from edm_sym.engines.fixedpoint import WORDS, check_accuracy, design, excitation, input_ranges
from edm_sym.engines.fixedpoint.formats import frac_for
from edm_sym.outputs.render.context import source_of


def test_frac_for_fits_the_bound() -> None:
    for bits in (16, 32):
        for bound in (1e-3, 0.3, 1.0, 1.5, 63.2, 4000.0):
            f = frac_for(bound, bits)
            assert bound * 2.0 ** f <= 2 ** (bits - 1) - 1 < 2 * bound * 2.0 ** f


@pytest.mark.parametrize(("real", "goal"), [("q31", 1e-3), ("q15", 2e-2)])
def test_example_meets_its_goal(real: str, goal: float) -> None:
    result = load_result(cg.EXAMPLE)
    comp = result.compensator
    ins = tuple(comp.matrix.inputs)
    ranges = input_ranges(ins, {ins[r.input] for r in comp.matrix.rows}, source_of(result).ranges,
                          None)
    d = design(comp, WORDS[real], ranges)
    acc = check_accuracy(d, comp, excitation(ins, ranges, d.sample_time, 20000))
    assert acc.measured < goal * acc.rms
    assert acc.measured < 0.1 * goal * acc.rms  # room to spare on the shipped example


def test_refusal_names_row_and_element(tmp_path, capsys) -> None:  # noqa: ANN001
    result = cg.as_result(cg.element_compensator("tan_amp"))
    path = tmp_path / "r.json"
    from edm_sym.core.result import save_result

    save_result(result, path)
    code = export_main([str(path), "--target", "c", "--real", "q15", "-o",
                        str(tmp_path / "out"), "--input-range", "omega=-40:40",
                        "--input-range", f"theta_w=0:{2 * math.pi}"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2
    assert "rows[0].elements[1] (tan_amp" in err[0]
    assert not (tmp_path / "out" / "edm_comp.c").exists()


def test_an_input_without_range_is_refused(tmp_path, capsys) -> None:  # noqa: ANN001
    result = cg.as_result(cg.element_compensator("gain"))
    path = tmp_path / "r.json"
    from edm_sym.core.result import save_result

    save_result(result, path)
    code = export_main([str(path), "--target", "c", "--real", "q31", "-o", str(tmp_path / "o")])
    assert code == 2
    assert "--input-range" in capsys.readouterr().err


def test_refusal_names_the_stage_that_leaves_the_simulator() -> None:
    # gain -> sign -> ...: the gain's rounding flips the sign near zero; the sign stage is
    # exact on its quantised input, so naming the stage with the largest own error would
    # blame an innocent later stage.
    from edm_sym.engines.fixedpoint import FixedPointError
    from edm_sym.engines.symbolic.model import build_model
    from edm_sym.outputs.render.fixed_context import fixed_build

    result = cg.as_result(cg.element_compensator("sign"))
    source = source_of(result)
    model = build_model(result.compensator, sha256=source.sha256, target=result.target,
                        axis=source.axis)
    ranges = {"theta_w": (0.0, 2 * math.pi), "theta_uw": (0.0, 50.0), "omega": (-40.0, 40.0)}
    with pytest.raises(FixedPointError) as info:
        fixed_build(model, source, "q31", ranges)
    msg = str(info.value)
    assert re.match(r"rows\[\d\]\.elements\[1\] \(sign\): ", msg), msg
    assert "turns its input's deviation" in msg and "\n" not in msg
