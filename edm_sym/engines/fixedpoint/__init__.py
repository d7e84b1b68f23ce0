"""Fixed-point design of a compensator: Q formats, tables, integer filters, their error.

| module | what it holds |
| --- | --- |
| `formats.py` | the word types (q31, q15), their goals and margins, Q formats, integer rounding |
| `excitation.py` | the synthetic excitation inside the recorded input ranges |
| `design.py` | `design()`: every signal's format and every stage's integer realisation |
| `model.py` | the bit-exact model of the generated integer C (plain integers, numpy int64) |
| `switching.py` | the switching rule: the reference a build is measured against, its switching events |
| `accuracy.py` | the deviation from the double simulator: a priori bound, measurement, refusal |
"""

from __future__ import annotations

from edm_sym.engines.fixedpoint.accuracy import Accuracy, Build, build, check_accuracy, input_ints
from edm_sym.engines.fixedpoint.design import (
    FilterStage,
    FixedDesign,
    FixedPointError,
    RelayStage,
    RingStage,
    TableStage,
    design,
    input_ranges,
)
from edm_sym.engines.fixedpoint.excitation import excitation
from edm_sym.engines.fixedpoint.formats import WORDS, Word
from edm_sym.engines.fixedpoint.model import run_fixed
from edm_sym.engines.fixedpoint.switching import SWITCH_LSB, Reference, SwitchEvent, reference

__all__ = [
    "SWITCH_LSB", "WORDS", "Accuracy", "Build", "FilterStage", "FixedDesign", "FixedPointError",
    "Reference", "RelayStage", "RingStage", "SwitchEvent", "TableStage", "Word", "build",
    "check_accuracy", "design", "excitation", "input_ints", "input_ranges", "reference",
    "run_fixed",
]
