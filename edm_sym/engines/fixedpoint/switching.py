"""The switching rule: the reference a fixed-point build's deviation is measured against.

A switching element (:attr:`~edm_sym.core.elements.base.Element.switches`: the
relay, the sign) steps between levels where its input crosses a threshold. The
build's input to it is the double chain's rounded to a Q format (and, after
other stages, carrying their rounding). Where the double input passes within
that rounding of a threshold, the two chains step apart: by a sample, for as
long as the input lingers at the threshold, or until the next crossing when
one input touches a relay's threshold and the other misses it by a fraction of
an LSB. The difference is a whole level however small the rounding; a longer
word makes it rarer, none removes it.

**The rule.** The reference element reads the build's own input to it
wherever that lies within :data:`SWITCH_LSB` LSB (of the input's Q format) of
the reference chain's, and the reference chain's input elsewhere; every other
element reads the reference chain's signal, so after a switching element the
reference continues from the steps the build makes. The deviation measured
against this reference is the build's arithmetic. Each run of samples in
which a switching element's reference output differs from what the element
gives on the reference chain's own input is a *switching event*; the events
and the raw deviation from the plain double simulator are stated beside the
deviation under the rule. The verification kit's expected outputs are this
reference, and the kit reports the raw deviation too.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from edm_sym.engines.fixedpoint.design import FixedDesign
from edm_sym.engines.fixedpoint.formats import to_real

#: A switching element reads the build's input where it is within this many LSB of the double's.
SWITCH_LSB = 2


@dataclass(frozen=True)
class SwitchEvent:
    """A run of samples where a switching element steps as the build does, not as on the double input.

    Attributes
    ----------
    where : str
        The stage, as refusals name it (``"rows[0].elements[0] (hysteresis ...)"``).
    start : int
        Its first sample.
    samples : int
        How many samples it lasts.
    """

    where: str
    start: int
    samples: int


@dataclass(frozen=True)
class Reference:
    """The double simulator under the switching rule, beside the plain one.

    Attributes
    ----------
    stages : tuple of tuple of numpy.ndarray
        Each row's stage outputs under the rule (reals).
    total : numpy.ndarray
        Their sum: what the build is measured against.
    raw : numpy.ndarray
        The plain double simulator's total on the same (unrounded) inputs.
    events : tuple of SwitchEvent
        Where the two differ because a switching element read the build's input.
    """

    stages: tuple[tuple[np.ndarray, ...], ...]
    total: np.ndarray
    raw: np.ndarray
    events: tuple[SwitchEvent, ...]


def reference(d: FixedDesign, comp: Any, x: np.ndarray, u: np.ndarray,
              per: list[list[np.ndarray]]) -> Reference:
    """The reference of ``d`` on real inputs ``x`` (n_inputs, N) under the switching rule.

    Parameters
    ----------
    d : FixedDesign
    comp : Compensator
        The matrix ``d`` realises.
    x : numpy.ndarray
        The real inputs.
    u : numpy.ndarray
        The build's integer inputs (:func:`~edm_sym.engines.fixedpoint.accuracy.input_ints`).
    per : list of list of numpy.ndarray
        The build's integer stage outputs, row by row (``run_fixed(..., stages=True)``).
    """
    n = x.shape[-1]
    total, raw = np.zeros(n), np.zeros(n)
    rows, events = [], []
    for k, (row, crow) in enumerate(zip(d.rows, comp.matrix.rows, strict=True)):
        plain = np.array(x[row.input_index], dtype=float)
        ruled = plain.copy()
        seen = to_real(u[row.input_index], d.input_fracs[row.input_index])
        outs = []
        for st, gene, got in zip(row.stages, crow.genes, per[k], strict=True):
            real = gene.element.realise(comp.value(gene), comp.sample_time)
            own = real.run(ruled.copy())
            if st.switches:
                near = np.abs(seen - ruled) <= SWITCH_LSB * 2.0 ** -st.fin
                ruled = real.run(np.where(near, seen, ruled))
                events += [SwitchEvent(st.where, a, b - a) for a, b in _runs(ruled != own)]
            else:
                ruled = own
            plain = real.run(plain.copy())
            seen = to_real(got, st.fout)
            outs.append(ruled)
        rows.append(tuple(outs))
        total += ruled
        raw += plain
    return Reference(tuple(rows), total, raw, tuple(events))


def _runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """The (start, stop) of each run of True in ``mask``."""
    edges = np.diff(np.concatenate([[0], mask.astype(np.int8), [0]]))
    return list(zip(np.nonzero(edges == 1)[0].tolist(), np.nonzero(edges == -1)[0].tolist(),
                    strict=True))


def describe_events(events: tuple[SwitchEvent, ...]) -> str:
    """The events in one phrase: ``"2 switching events (rows[0].elements[0] (hysteresis): 75 and 7
    samples)"``, or ``"no switching event"``."""
    if not events:
        return "no switching event"
    parts = []
    for where in dict.fromkeys(e.where for e in events):
        lengths = [e.samples for e in events if e.where == where]
        if len(lengths) <= 3:
            text = " and ".join([", ".join(map(str, lengths[:-1])), str(lengths[-1])][
                len(lengths) == 1:])
        else:
            text = f"{min(lengths)} to {max(lengths)}"
        parts.append(f"{where}: {text} sample{'s' if max(lengths) > 1 else ''}")
    count = len(events)
    return f"{count} switching event{'s' if count > 1 else ''} ({'; '.join(parts)})"
