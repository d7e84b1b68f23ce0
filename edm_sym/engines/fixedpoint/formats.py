"""Word types, Q formats and the integer rounding the generated C performs.

A signal in a fixed-point build is an integer ``v`` of the build's word
(``int32_t`` for q31, ``int16_t`` for q15) standing for ``v * 2**-frac``; each
signal has its own ``frac`` (its Q format), chosen from its range. Products and
sums are formed in ``int64_t``; every narrowing rounds half up and saturates.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

#: The simulated range of an internal signal is widened by this factor (one bit of headroom).
MARGIN = 2.0
#: The recorded range of an input is widened by this factor before its format is chosen.
INPUT_HEADROOM = 1.25
#: Samples of the synthetic excitation (and of the verification kit's vectors).
EXCITATION_SAMPLES = 20000
#: Samples of the verification kit's vectors.
KIT_SAMPLES = 4000
#: Width of the filters' feedback words and coefficients (both builds).
WIDE_BITS = 32


@dataclass(frozen=True)
class Word:
    """A fixed-point build.

    Attributes
    ----------
    name : str
        ``"q31"`` or ``"q15"`` (the ``--real`` value).
    bits : int
        Width of a signal word (32 or 16).
    goal : float
        The largest deviation from the double simulator accepted, as a fraction
        of the RMS of the compensation on the excitation.
    table_tolerance : float
        A static function's table meets this fraction of its output's bound.
    max_segments : int
        The most segments one table may hold.
    """

    name: str
    bits: int
    goal: float
    table_tolerance: float
    max_segments: int

    @property
    def c_type(self) -> str:
        """The C type of a signal word (``int32_t``)."""
        return f"int{self.bits}_t"

    @property
    def max_int(self) -> int:
        """The largest integer of the word."""
        return (1 << (self.bits - 1)) - 1

    @property
    def min_int(self) -> int:
        """The smallest integer of the word."""
        return -(1 << (self.bits - 1))

    @property
    def wide_extra(self) -> int:
        """Extra fractional bits of a filter's feedback word over its output's."""
        return WIDE_BITS - self.bits


#: The fixed-point builds, by ``--real`` value.
WORDS = {
    "q31": Word("q31", 32, 1e-3, 2e-5, 1024),
    "q15": Word("q15", 16, 2e-2, 5e-4, 256),
}


def frac_for(bound: float, bits: int) -> int:
    """The most fractional bits with which ``[-bound, bound]`` fits a word of ``bits`` bits.

    A zero bound takes the format of 1 (``frac = bits - 2``). The result lies
    within ``[-bits, 2 * bits]`` so that every shift between formats stays below 63.
    """
    b = float(bound)
    if not math.isfinite(b):
        raise ValueError(f"a range bound: expected a finite number, found {b!r}")
    b = max(abs(b), 2.0 ** -bits)
    frac = bits - 1 - math.ceil(math.log2(b))
    while frac > -bits and b * 2.0 ** frac > (1 << (bits - 1)) - 1:
        frac -= 1
    return int(min(max(frac, -bits), 2 * bits))


def to_int(x: np.ndarray | float, frac: int, word: Word) -> np.ndarray:
    """``x`` as the word's integers of format ``frac``: rounded to nearest, saturated."""
    v = np.round(np.asarray(x, dtype=float) * 2.0 ** frac)
    return np.clip(v, word.min_int, word.max_int).astype(np.int64)


def to_real(v: np.ndarray | int, frac: int) -> np.ndarray:
    """The reals integers ``v`` of format ``frac`` stand for."""
    return np.asarray(v, dtype=float) * 2.0 ** -frac


def rshift_round(v: np.ndarray, s: int) -> np.ndarray:
    """``v / 2**s`` rounded half up, as the C helper does (``s >= 0``; int64 arrays)."""
    if s <= 0:
        return v
    return (v + (1 << (s - 1))) >> s


def saturate(v: np.ndarray, lo: int, hi: int) -> np.ndarray:
    """``v`` limited to ``[lo, hi]`` (the narrowing to a word)."""
    return np.clip(v, lo, hi)


def describe_format(frac: int, bits: int) -> str:
    """``"Q7.24 (LSB 6e-08, range +-128)"`` for a word of ``bits`` bits and ``frac`` fractional bits."""
    ints = bits - 1 - frac
    return (f"Q{ints}.{frac} (LSB {2.0 ** -frac:.3g}, range +-{2.0 ** ints:.6g})")
