"""Write tests/data/handwritten_result.json: a hand-written 4x4 compensator for an auger axis.

A fixture with known content (the shipped example is a genetic-algorithm result
and may change). Each row models one
physical disturbance of the reaction torque observer's estimate ``tau_ext``:

1. Coulomb friction:      omega -> sign -> gain (0.95 N m) -> through -> through
2. viscous friction:      omega -> power_gain (0.005 N m s/rad) -> through x 3
3. acceleration-dependent: omega -> derivative (1 s) -> lpf (100 rad/s) -> gain (0.002 kg m^2)
4. spatial (cogging):     theta_w -> gain (2 cycles/rev) -> sin_phase (0.3 rad) -> sin_amp (0.05 N m)

Run from anywhere: ``python tests/make_handwritten_result.py``.
"""

from __future__ import annotations

from pathlib import Path

import edm_sym
from edm_sym.core.elements import default_ranges
from edm_sym.core.matrix import Compensator, make_matrix
from edm_sym.core.result import EdmResult, save_result

TS = 1e-3
RECORD_LENGTH = 20.0
INPUTS = ("theta_w", "theta_uw", "omega")

#: Each row: its input and (element, intended parameter value or None), left to right.
ROWS = [
    ("omega", [("sign", None), ("gain", 0.95), ("through", None), ("through", None)]),
    ("omega", [("power_gain", 0.005), ("through", None), ("through", None), ("through", None)]),
    ("omega", [("derivative", 1.0), ("lpf", 100.0), ("gain", 0.002), ("through", None)]),
    ("theta_w", [("gain", 2.0), ("sin_phase", 0.3), ("sin_amp", 0.05), ("through", None)]),
]


def build() -> EdmResult:
    """The hand-written result (parameters placed with ParamRange.encode)."""
    ranges = default_ranges(TS, RECORD_LENGTH)
    rows = [(inp, [(name, 0.0 if a is None else ranges[name].encode(a)) for name, a in genes])
            for inp, genes in ROWS]
    comp = Compensator(make_matrix(INPUTS, rows), TS, ranges, RECORD_LENGTH)
    provenance = {"seed": None, "package_version": edm_sym.__version__, "data_sha256": None}
    return EdmResult(comp, "tau_ext", (), provenance, None)


def main() -> None:
    """Write tests/data/handwritten_result.json."""
    path = save_result(build(), Path(__file__).resolve().parent / "data" / "handwritten_result.json")
    print(path)


if __name__ == "__main__":
    main()
