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

RANGES = {"theta_w": (0.0, 2 * math.pi), "theta_uw": (0.0, 50.0), "omega": (-40.0, 40.0)}


def test_frac_for_fits_the_bound() -> None:
    for bits in (16, 32):
        for bound in (1e-3, 0.3, 1.0, 1.5, 63.2, 4000.0):
            f = frac_for(bound, bits)
            assert bound * 2.0 ** f <= 2 ** (bits - 1) - 1 < 2 * bound * 2.0 ** f


@pytest.mark.parametrize(("example", "real", "goal"), [
    (cg.EXAMPLE, "q31", 1e-3), (cg.RELAY_EXAMPLE, "q31", 1e-3), (cg.RELAY_EXAMPLE, "q15", 2e-2)])
def test_example_meets_its_goal(example, real: str, goal: float) -> None:  # noqa: ANN001
    result = load_result(example)
    comp = result.compensator
    ins = tuple(comp.matrix.inputs)
    ranges = input_ranges(ins, {ins[r.input] for r in comp.matrix.rows}, source_of(result).ranges,
                          None)
    d = design(comp, WORDS[real], ranges)
    acc = check_accuracy(d, comp, excitation(ins, ranges, d.sample_time, 20000))
    assert acc.measured < goal * acc.rms
    assert acc.measured < 0.1 * goal * acc.rms  # room to spare on the shipped example


def test_the_shipped_example_is_beyond_q15_and_the_refusal_says_why(tmp_path, capsys) -> None:  # noqa: ANN001
    # Its Coulomb row is a steep tanh (93.9 omega): a 16-bit omega's rounding becomes a
    # tenth of the row's output. The export refuses, names the stage and the way out
    # (q31), and writes nothing; the q31 build of the same model meets its goal (above).
    code = export_main([str(cg.EXAMPLE), "--target", "c", "--real", "q15", "-o",
                        str(tmp_path / "out")])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1
    assert re.search(r"rows\[\d\]\.elements\[0\] \(tanh \(a_9 = ", err[0]), err[0]
    assert "more than its promise" in err[0] and "use --real q31" in err[0]
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").iterdir())


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


def _fixed_build(comp, real: str):  # noqa: ANN001, ANN202
    from edm_sym.engines.symbolic.model import build_model
    from edm_sym.outputs.render.fixed_context import fixed_build

    result = cg.as_result(comp)
    source = source_of(result)
    model = build_model(result.compensator, sha256=source.sha256, target=result.target,
                        axis=source.axis)
    return fixed_build(model, source, real, RANGES)


def test_refusal_names_the_stage_that_leaves_the_simulator() -> None:
    # sin_amp -> hysteresis -> gain: the sine's table errs by about 16 LSB of its output
    # (within its tolerance), more than the switching rule's 2 LSB, so the relay steps
    # where the double one does not. The relay is exact on its quantised input: naming the
    # stage with the largest own error would blame the innocent sine.
    from edm_sym.core.matrix import Compensator, make_matrix
    from edm_sym.engines.fixedpoint import FixedPointError

    rows = [("theta_w", [("sin_amp", cg._p("sin_amp", 3.123636996293847)),
                         ("hysteresis", cg._p("hysteresis", 1.2271888696943782)),
                         ("gain", cg._p("gain", 0.5))])]
    comp = Compensator(make_matrix(cg.INPUTS, rows), cg.TS, {}, 20.0)
    with pytest.raises(FixedPointError) as info:
        _fixed_build(comp, "q15")
    msg = str(info.value)
    assert re.match(r"rows\[0\]\.elements\[1\] \(hysteresis \(a_2 = 1\.22719\)\): ", msg), msg
    assert "turns its input's deviation" in msg and "\n" not in msg


def test_a_sign_a_rounding_flips_is_a_switching_event() -> None:
    # gain -> sign: the gain's rounding flips the sign near zero. The switching rule lets
    # the reference's sign read the build's input (within 2 LSB of the double one): the
    # build meets its promise, and the events and the raw deviation are stated.
    b = _fixed_build(cg.element_compensator("sign"), "q31")
    acc = b.accuracy
    assert acc.events and {e.where for e in acc.events} == {"rows[1].elements[1] (sign)"}
    assert all(e.samples == 1 for e in acc.events)
    assert acc.measured <= acc.goal < acc.raw
    line = b.lines("N m")[1]
    assert f"{len(acc.events)} switching events" in line and "without the rule 0.3 N m" in line
    assert any(t.startswith("switching rule: ") for t in b.lines("N m"))


@pytest.mark.parametrize(("real", "goal"), [("q31", 1e-3), ("q15", 2e-2)])
def test_example_meets_its_goal_on_its_recorded_log(real: str, goal: float) -> None:
    # The relay example's q15 relay reads omega in Q7.8 (LSB 0.0039 rad/s) against a threshold of about
    # 0.011 rad/s: on the log it switches where the unrounded velocity misses the threshold
    # by a fraction of an LSB. Under the switching rule the build meets the goal there, and
    # the events are the relay's.
    from edm_sym.application.exporting import recorded_log
    from edm_sym.engines.fixedpoint import build

    result = load_result(cg.RELAY_EXAMPLE)
    comp = result.compensator
    ins = tuple(comp.matrix.inputs)
    ranges = input_ranges(ins, {ins[r.input] for r in comp.matrix.rows}, source_of(result).ranges,
                          None)
    x, name = recorded_log(result)
    b = build(comp, WORDS[real], ranges, log=(x, name))
    assert name == "plant:auger/abstraction" and b.log.samples == x.shape[-1]
    assert b.log.measured < goal * b.log.rms
    assert b.log.measured < 0.2 * goal * b.log.rms  # room to spare
    k = _relay_row(comp)
    relay = f"rows[{k}].elements[0] (hysteresis)"
    assert {e.where for e in b.log.events} <= {relay}
    if real == "q15":
        assert b.log.events and all(e.samples >= 1 for e in b.log.events)
        assert b.log.raw > 1.0  # what the switching events cost without the rule


def _relay_row(comp) -> int:  # noqa: ANN001
    """The relay example's Coulomb row: the one that starts with a relay."""
    rows = [k for k, r in enumerate(comp.matrix.rows) if r.genes[0].element.is_relay]
    assert len(rows) == 1, "the relay example has one relay row"
    return rows[0]


def test_the_rule_feeds_a_first_switching_element_the_build_s_input() -> None:
    # Oracle: a row that starts with the relay is, under the rule, the double simulator
    # on the input as the build rounds it (the rounding is at most half an LSB).
    import numpy as np

    from edm_sym.engines.fixedpoint import input_ints, reference, run_fixed
    from edm_sym.engines.fixedpoint.formats import to_real
    from edm_sym.engines.simulate import simulate_row

    result = load_result(cg.RELAY_EXAMPLE)
    comp = result.compensator
    ins = tuple(comp.matrix.inputs)
    ranges = input_ranges(ins, {ins[r.input] for r in comp.matrix.rows}, source_of(result).ranges,
                          None)
    d = design(comp, WORDS["q15"], ranges)
    x = excitation(ins, ranges, d.sample_time, 4000)
    k = _relay_row(comp)
    row = comp.matrix.rows[k]
    threshold = comp.value(row.genes[0])
    x[row.input, 100:140] = 0.99 * threshold  # omega just under the threshold ...
    u = input_ints(d, x)
    seen = to_real(u[row.input], d.input_fracs[row.input])
    assert seen[100] > threshold  # ... and over it as the build rounds it
    _, _, per = run_fixed(d, u, stages=True)
    ref = reference(d, comp, x, u, per)
    np.testing.assert_array_equal(ref.stages[k][-1], simulate_row(comp, row, seen))
    assert ref.events and ref.events[0].where.startswith(f"rows[{k}].elements[0] (hysteresis")
    assert not np.array_equal(ref.total, ref.raw)


def test_a_log_beyond_an_input_s_format_is_refused_naming_the_input(tmp_path, capsys) -> None:  # noqa: ANN001
    # omega given as -10 .. 10 (format +-16) while the stored log reaches 63 rad/s: the
    # excitation meets the promise, the log saturates and misses it.
    code = export_main([str(cg.EXAMPLE), "--target", "c", "--real", "q31", "-o",
                        str(tmp_path / "out"), "--input-range", "omega=-10:10"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2
    assert err[-1].startswith("edm-export: inputs: omega: reaches 63.2235, beyond the range +-16 "
                              "of its format"), err[-1]
    assert "on the log plant:auger/abstraction, more than its promise" in err[-1]
    assert not (tmp_path / "out" / "edm_comp.c").exists()
