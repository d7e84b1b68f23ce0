"""Tangent poles inside a row's input range: the rows that fit one log and fail the next.

A row's **static prefix** (its elements up to the first one with state) is
continuous but for the poles of its tangents (``tan_phase``, ``tan_amp``).
Evaluated on a dense grid over the range the row's input takes in the data,
a tangent whose argument crosses pi/2 + k pi there has a pole the samples
happened to miss: as the velocity goes through zero, say. Such a row fits
the log it was found on and fails on the next one, where one sample of a
zero crossing lands near the pole (an output up to the guard's 1e6:
docs/elements.md). ``tan(523 sat(omega, 0.0075))`` is one the GA found
(docs/abstraction.md#seed-robustness).

The GA gives an individual with such a row an infinite fitness (``[ga]
reject_poles``, default true); after the search, a step best with one is
not a starting point of pruning (:func:`~edm_sym.engines.abstraction.holdout.fragile_rows`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from edm_sym.core.elements import REGISTRY, Element

#: Codes of the elements with poles, the tangents (``Element.tangent_argument``).
TANGENT_CODES = frozenset(c for c, el in REGISTRY.items() if el.tangent_argument is not None)
_TANGENT_ARRAY = np.array(sorted(TANGENT_CODES))
#: Codes of the elements without state (a static prefix is made of them).
STATIC_CODES = frozenset(c for c, el in REGISTRY.items() if el.is_static)
#: Grid points over the input's range after the search (a step best is checked once).
FINAL_GRID = 200_001
#: Grid points during the search (every new row with a tangent in its static prefix).
SEARCH_GRID = 20_001


def may_have_pole(codes: Sequence[int]) -> bool:
    """Whether a row of these element codes has a tangent in its static prefix."""
    for c in codes:
        if c not in STATIC_CODES:
            return False
        if c in TANGENT_CODES:
            return True
    return False


def with_tangent(codes: np.ndarray) -> np.ndarray:
    """Which rows of an (R, n) array of element codes hold a tangent at all.

    Only those can have a pole (:func:`may_have_pole` then looks closer).
    """
    return np.isin(codes, _TANGENT_ARRAY).any(axis=1)


def prefix_has_pole(lo: float, hi: float, elements: Sequence[tuple[type[Element], float | None]],
                    ts: float, grid: int = FINAL_GRID) -> bool:
    """Whether a tangent of the row's static prefix has a pole for an input in [lo, hi].

    Parameters
    ----------
    lo, hi : float
        The range the row's input takes in the data (nothing is checked unless lo < hi).
    elements : sequence of (element class, decoded parameter)
        The row, left to right.
    ts : float
        Sample time [s] (static elements do not use it).
    grid : int
        Points of the grid over [lo, hi].
    """
    if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
        return False
    y = np.linspace(lo, hi, grid)
    with np.errstate(all="ignore"):
        for el, a in elements:
            if not el.is_static:
                return False
            if el.tangent_argument is not None:
                arg = el.tangent_argument(y, a)
                branch = np.floor(arg[np.isfinite(arg)] / math.pi + 0.5)
                if branch.size and branch.min() != branch.max():
                    return True
            y = el.realise(a, ts).run(y)
    return False
