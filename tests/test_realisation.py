"""Realisations: every element realises to a known type, and every consumer covers every type."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import TS, smooth_signal

from edm_sym.core.elements import all_elements, default_ranges
from edm_sym.core.elements.realisation import (
    REALISATIONS,
    DelayLine,
    LinearFilter,
    Realisation,
    Relay,
    StaticMap,
    dispatch,
)
from edm_sym.engines.symbolic.lti import _PARTS
from edm_sym.engines.symbolic.rowexpr import OPERATORS
from edm_sym.outputs.printing import EdmC99Printer, EdmPythonPrinter
from edm_sym.outputs.report.rows import _EQUATIONS

RANGES = default_ranges(TS, 20.0)
ELEMENTS = all_elements()


def _realise(el, p: float = 0.6) -> Realisation:  # noqa: ANN001
    return el.realise(RANGES[el.name].decode(p) if el.param else None, TS)


@pytest.mark.parametrize("el", ELEMENTS, ids=lambda e: e.name)
def test_every_element_realises_to_a_known_frozen_type(el) -> None:  # noqa: ANN001
    r = _realise(el)
    assert type(r) in REALISATIONS
    assert r == _realise(el) and hash(r) == hash(_realise(el))  # frozen, compared by value
    with pytest.raises(AttributeError):
        r.kind_of_change = 1  # type: ignore[attr-defined]
    a = RANGES[el.name].decode(0.6) if el.param else None
    assert len(r.state_labels("c0")) == r.state_size == el.state_size(a, TS)


@pytest.mark.parametrize("el", ELEMENTS, ids=lambda e: e.name)
def test_the_per_sample_update_equals_the_batched_step(el) -> None:  # noqa: ANN001
    # update() on a state vector (python-control's path) against run() (numpy, the simulator).
    r = _realise(el)
    x = 2.5 * smooth_signal(600, seed=el.code)
    want = r.run(x)
    state = np.zeros(r.state_size)
    got = np.empty_like(x)
    for k, v in enumerate(x):
        nxt = state.copy()
        got[k] = r.update(float(v), state, nxt, 0)
        state = nxt
    scale = max(float(np.max(np.abs(want))), 1.0)
    assert np.allclose(got, want, rtol=1e-9, atol=1e-9 * scale), el.name


@pytest.mark.parametrize("kind", REALISATIONS, ids=lambda k: k.__name__)
@pytest.mark.parametrize("printer", [EdmC99Printer({"real": "double", "prefix": "p"}),
                                     EdmPythonPrinter()], ids=["c", "python"])
def test_every_printer_prints_every_realisation_type(kind, printer) -> None:  # noqa: ANN001
    example = next(r for r in (_realise(el) for el in ELEMENTS) if type(r) is kind)
    assert callable(dispatch(printer, "_stage_", example))


def test_every_consumer_table_covers_every_realisation_type() -> None:
    assert set(OPERATORS) == set(REALISATIONS)
    assert set(_PARTS) == {LinearFilter, DelayLine}  # the linear ones have transfer functions
    assert set(_EQUATIONS) | {StaticMap} == set(REALISATIONS)  # static maps compose into one


def test_dispatch_names_the_missing_method() -> None:
    class Bare:
        pass

    with pytest.raises(TypeError, match="_stage_Relay"):
        dispatch(Bare(), "_stage_", Relay(0.5))


def test_state_layouts_name_what_the_generated_code_declares() -> None:
    assert [p.suffix for p in LinearFilter((1.0, 0.5), (1.0, -0.5), "bilinear").state_layout()] == ["z"]
    assert [p.suffix for p in DelayLine(1).state_layout()] == ["buf"]
    assert [(p.suffix, p.size) for p in DelayLine(3).state_layout()] == [("buf", 3), ("pos", None)]
    assert [(p.suffix, p.size) for p in Relay(0.2).state_layout()] == [("out", 1)]
    with pytest.raises(ValueError, match="finite"):
        LinearFilter((1.0, float("nan")), (1.0, 0.0), "bilinear").validate()
    with pytest.raises(ValueError, match=">= 1 sample"):
        DelayLine(0).validate()
