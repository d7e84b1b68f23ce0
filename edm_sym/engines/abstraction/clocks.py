"""Clocks: an angle that only moves one way over a run, and the rows that read time from it.

Within a run that turns one way (a torque or velocity step from rest) the
unwrapped angle only rises (or only falls): it is a clock of the run, like
the time column the search refuses as an input. A function of it fits the
run's history (the start from rest, a warm-up) as a function of the time
since the start, and carries to no other run; on the drive, where the angle
keeps growing, it is a function of how long the axis has run. Physics reads
the angle either through its changes (a derivative is a velocity) or
through where the axis is within a revolution (a ripple repeats over it).

**Clock** (:func:`is_clock`): over one log, the input moves from its first to
its last value without ever going back by more than :data:`RETREAT` of that
travel (an encoder count or two of jitter at the start from rest does not
make a run two-way), and keeps moving: at the log's middle sample it has
covered at most :data:`HALFWAY` of it (a velocity that steps to a level and
holds it is no clock). A wrapped angle never counts.

**Passenger** (:func:`passengers`): a row on an angle input that is a clock in
at least one training log, whose output changes when the angle is shifted
by one revolution either way (on a linear axis: by its range). A
derivative of the angle and a ripple that repeats over a revolution are
unchanged (one revolution, not many: a ripple found at 7.0002 cycles a
revolution is still the ripple); a function of the absolute angle is not. Each log is simulated
after a warm-up at its first (shifted) value as long as the longest log,
so a filter starts settled and a step at the log's start is not mistaken for
a dependence. The change counts when its RMS over the training samples is
at least :data:`SHARE` of the target's.

After the search, every candidate for the search's model loses its
passengers and has its row gains refitted (``finish``), before the choice
and the pruning: the held-out blocks cannot judge a clock (interleaved
blocks of one run reward its mean like an offset), so the rule is physical
(docs/abstraction.md#clocks-rows-that-read-time-from-the-angle).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from edm_sym.core.matrix import Compensator, ElementMatrix, Row
from edm_sym.engines.simulate import segments, simulate_row

#: The most an input may go back over a log, as a share of its travel, and still be a clock.
RETREAT = 0.01
#: The most of its travel a clock may have covered at the log's middle sample.
HALFWAY = 0.75
#: A passenger's output changes under the shift by at least this share of the target's RMS.
SHARE = 0.01
#: The role of an input that can be a clock (the unwrapped angle, a linear axis' position).
CLOCK_ROLE = "angle"


def is_clock(col: np.ndarray) -> bool:
    """Whether ``col`` (one log) moves one way and keeps moving: it never goes back by
    more than :data:`RETREAT` of its travel from first to last value, and at the log's
    middle sample it has covered at most :data:`HALFWAY` of that travel (a velocity that
    steps to a level and holds it is no clock)."""
    col = np.asarray(col, dtype=float)
    if col.size < 3 or not np.all(np.isfinite(col)):
        return False
    travel = float(col[-1] - col[0])
    if travel == 0.0:
        return False
    rising = col if travel > 0 else -col
    retreat = float(np.max(np.maximum.accumulate(rising) - rising))
    halfway = float(col[col.size // 2] - col[0]) / travel
    return retreat <= RETREAT * abs(travel) and halfway <= HALFWAY


@dataclass(frozen=True)
class Passenger:
    """A row dropped as a function of a clock (result.json ``parsimony.clock_rows``)."""

    row: int
    """Index of the row in its matrix (0-based)."""
    input: int
    shift: float
    """The shift of the angle that changed its output [the input's unit]."""
    change: float
    """RMS of the output's change under the shift over the target's RMS."""


def _angle_clocks(x: np.ndarray, starts: Sequence[int], roles: Sequence[str | None]
                  ) -> dict[int, list[bool]]:
    """For each angle input (role :data:`CLOCK_ROLE`), whether it is a clock in each log."""
    edges = segments(x.shape[-1], starts)
    return {i: [is_clock(np.asarray(x[i][a:b], dtype=float)) for a, b in edges]
            for i, role in enumerate(roles) if role == CLOCK_ROLE}


def clock_shifts(x: np.ndarray, starts: Sequence[int], roles: Sequence[str | None],
                 axis: str) -> dict[int, float]:
    """The angle inputs that are a clock in at least one log, and the shift that tests a row.

    ``x``: the inputs (n_inputs, N) of the training logs laid end to end,
    ``starts`` where each further log begins. On a rotary axis the shift is one
    revolution; on a linear axis the input's range over all logs.
    """
    return {i: 2.0 * math.pi if axis == "rotary" else float(np.ptp(np.asarray(x[i], dtype=float)))
            for i, logs in _angle_clocks(x, starts, roles).items() if any(logs)}


def barred_inputs(x: np.ndarray, starts: Sequence[int], roles: Sequence[str | None]
                  ) -> tuple[int, ...]:
    """The angle inputs the search's rows leave out: a clock in every training log.

    Only when the inputs hold a velocity, what physics reads from the angle's
    changes (a ripple repeats over the wrapped angle; without one, the ripple
    seeds may still put a row on the angle). Without a velocity the search
    keeps the angle (its derivative is the velocity). Rows on it that read
    time go after the search (:func:`passengers`).
    """
    if "velocity" not in roles:
        return ()
    return tuple(i for i, logs in _angle_clocks(x, starts, roles).items() if all(logs))


def _settled(comp: Compensator, row: Row, col: np.ndarray, starts: Sequence[int],
             warm: int) -> np.ndarray:
    """The row over ``col``, each log after ``warm`` samples at its first value."""
    parts = []
    for a, b in segments(len(col), starts):
        seg = col[a:b]
        y = simulate_row(comp, row, np.concatenate([np.full(warm, seg[0]), seg]))
        parts.append(y[warm:])
    return np.concatenate(parts)


def passengers(comp: Compensator, matrix: ElementMatrix, x: np.ndarray, starts: Sequence[int],
               shifts: dict[int, float], samples: slice | np.ndarray, target_rms: float
               ) -> list[Passenger]:
    """The rows of ``matrix`` that read time from a clock (module docstring).

    ``samples``: the samples the change is measured on (the training ones);
    ``target_rms``: the target's RMS there.
    """
    if not shifts or not target_rms > 0:
        return []
    warm = max(b - a for a, b in segments(x.shape[-1], starts))
    out = []
    for j, row in enumerate(matrix.rows):
        shift = shifts.get(row.input)
        if shift is None:
            continue
        col = np.asarray(x[row.input], dtype=float)
        with np.errstate(all="ignore"):
            base = _settled(comp, row, col, starts, warm)
            change = max(float(np.sqrt(np.mean((_settled(comp, row, col + d, starts, warm)
                                                 - base)[samples] ** 2)))
                         for d in (shift, -shift))
        if not math.isfinite(change) or change >= SHARE * target_rms:
            out.append(Passenger(j, row.input, shift,
                                 change / target_rms if math.isfinite(change) else math.inf))
    return out
