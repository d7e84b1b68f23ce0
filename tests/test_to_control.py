"""``to_control()``: the whole compensator as one python-control system (docs/symbolic.md)."""

from __future__ import annotations

import re
from pathlib import Path

import control as ct
import numpy as np
import pytest

import edm_sym
from edm_sym.engines.symbolic.model import build_model

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "examples" / "auger" / "result.json"


@pytest.fixture(scope="module")
def example() -> edm_sym.EdmResult:
    return edm_sym.load_result(EXAMPLE)


def _response(sys: ct.NonlinearIOSystem, u: np.ndarray) -> np.ndarray:
    t = np.arange(u.shape[1]) * sys.dt
    return np.asarray(ct.input_output_response(sys, t, u, squeeze=False).outputs[0])


def test_equals_the_reference_simulator_on_the_shipped_example(example) -> None:  # noqa: ANN001
    log = edm_sym.load_data("plant:auger/evaluation")
    sys = build_model(example.compensator).to_control()
    assert isinstance(sys, ct.NonlinearIOSystem) and sys.isdtime(strict=True)
    assert sys.dt == example.sample_time
    assert sys.input_labels == list(example.inputs) and sys.output_labels == ["tau_cmp"]
    got = _response(sys, log.stack(example.inputs))
    ref = edm_sym.simulate(example, log).total
    assert len(got) == len(log) == 20000
    assert np.max(np.abs(got - ref)) <= 1e-9


def test_the_decoded_model_gives_the_same_system_with_named_states(example) -> None:  # noqa: ANN001
    model = edm_sym.decode(example, classify=False)
    sys = model.to_control(output="u_comp", name="comp")
    assert sys.name == "comp" and sys.output_labels == ["u_comp"]
    # Every row's states, prefixed by the row: the same layout as the row systems.
    expected = [f"r{row.index + 1}_{label}" for row in model.rows for label in row.system.state_labels]
    assert sys.state_labels == expected and sys.nstates == sum(r.system.nstates for r in model.rows)
    rng = np.random.default_rng(0)
    u = rng.standard_normal((len(example.inputs), 500))
    rows = [_response(row.system, u[[example.inputs.index(row.input)]]) for row in model.rows]
    np.testing.assert_allclose(_response(sys, u), np.sum(rows, axis=0), rtol=0, atol=1e-12)


def test_an_input_no_row_reads_is_an_input_and_is_ignored() -> None:
    m = edm_sym.make_matrix(["omega", "theta"], [("omega", [("sign", 0), ("gain", 0.8), ("lpf", 0.5)])])
    comp = edm_sym.Compensator(m, 1e-3, {})
    sys = build_model(comp).to_control()
    assert sys.input_labels == ["omega", "theta"]
    rng = np.random.default_rng(1)
    u = rng.standard_normal((2, 300))
    other = u.copy()
    other[1] = 1e3 * rng.standard_normal(300)
    np.testing.assert_array_equal(_response(sys, u), _response(sys, other))
    ref = edm_sym.simulate(comp, {"omega": u[0], "theta": u[1]}).total
    assert np.max(np.abs(_response(sys, u) - ref)) <= 1e-12


def _doc_block() -> str:
    text = (ROOT / "docs" / "symbolic.md").read_text("utf-8")
    section = text.split("### The compensator as one system", 1)[1]
    return re.search(r"```python\n(.*?)```", section, re.S).group(1)


def test_the_closed_loop_example_in_the_docs_runs_and_compensates(
    example, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture  # noqa: ANN001
) -> None:
    monkeypatch.chdir(ROOT)
    scope: dict = {}
    exec(compile(_doc_block(), "docs/symbolic.md", "exec"), scope)  # noqa: S102
    printed = capsys.readouterr().out.strip()
    assert printed == (f"velocity error RMS: {scope['rms_with']:.3g} rad/s with the compensator, "
                       f"{scope['rms_without']:.3g} without")
    assert printed in (ROOT / "docs" / "symbolic.md").read_text("utf-8").replace("\n", " ")
    # The P controller alone leaves the friction's steady error; the compensator removes most.
    assert scope["rms_with"] < 0.2 * scope["rms_without"]
    # Inside the loop the compensator computes what the reference simulator computes
    # on the loop's own signals.
    out = scope["with_comp"].outputs
    signals = dict(zip(("theta_w", "theta_uw", "omega", "alpha"), out[:4], strict=True))
    ref = edm_sym.simulate(example, signals).total
    assert np.max(np.abs(out[4] - ref)) <= 1e-9
