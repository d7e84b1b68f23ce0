"""The deviation of a fixed-point build from the double simulator: bound, measurement, refusal.

Two figures describe a build:

* the **a priori bound** (:attr:`FixedDesign.error`): each stage's rounding,
  coefficient and table errors propagated through the stages after it (a
  table by its steepest slope, a filter by the l1 norm of its impulse
  response), for inputs inside their formats' ranges. A relay after any
  rounding, a jump or an integrator leaves no finite bound: only measurement
  speaks for such a row;
* the **measured deviation**: the bit-exact model
  (:mod:`~edm_sym.engines.fixedpoint.model`) against the reference simulator
  on the recorded log the formats were sized on, or on the excitation when
  no log is at hand.

The export promises the word's goal (:attr:`Word.goal` of the RMS of the
compensation) and refuses the model when the measurement exceeds it, naming
the stage where the fixed chain leaves the double one (:func:`culprit`): the
first whose output deviates by more than the goal of its range, whether it
errs by itself or amplifies its input's rounding (a sign after a gain).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from edm_sym.engines.fixedpoint.design import FixedDesign, FixedPointError
from edm_sym.engines.fixedpoint.formats import to_int, to_real
from edm_sym.engines.fixedpoint.model import run_fixed, run_stage
from edm_sym.engines.simulate import simulate_rows

#: What a build is sized and measured on when no log is at hand.
EXCITATION = "the synthetic excitation"


@dataclass(frozen=True)
class Accuracy:
    """How far a fixed-point build is from the double simulator (output units).

    Attributes
    ----------
    rms : float
        The RMS of the double compensation on the signals measured.
    goal : float
        The promised largest deviation (``word.goal * rms``).
    measured : float
        The largest deviation measured there.
    bound : float
        The a priori bound (inf when only measurement is possible).
    samples : int
        How many samples were measured.
    """

    rms: float
    goal: float
    measured: float
    bound: float
    samples: int

    @property
    def bounded(self) -> bool:
        """True when the a priori bound is finite."""
        return math.isfinite(self.bound)

    def lines(self, word: str, unit: str, on: str) -> list[str]:
        """The deviation as the header and the command line state it."""
        bound = (f"a priori bound {self.bound:.3g} {unit} over the input ranges" if self.bounded
                 else "no a priori bound (a relay, a jump or an integrator): measured only")
        return [f"promised: at most {self.goal:.3g} {unit} from the double simulator "
                f"({_goal_text(self.goal, self.rms)} of the RMS {self.rms:.4g} {unit})",
                f"measured: {self.measured:.3g} {unit} ({self.measured / self.rms:.2e} of the RMS) "
                f"on {self.samples} samples of {on}, by the bit-exact model of the {word} C",
                bound]


def _goal_text(goal: float, rms: float) -> str:
    return f"{goal / rms:.0e}" if rms > 0 else "0"


def input_ints(d: FixedDesign, x: np.ndarray) -> np.ndarray:
    """Real inputs (n_inputs, N) as the build's integers, each in its format."""
    return np.vstack([to_int(x[i], d.input_fracs[i], d.word) for i in range(len(d.inputs))])


def stage_errors(d: FixedDesign, comp: Any, x: np.ndarray) -> list[tuple[float, str]]:
    """Each stage's own error (its output against the double stage on the same quantised input).

    Returns (error relative to the stage's output bound, where) pairs, largest first.
    """
    out = []
    lo, hi = d.word.min_int, d.word.max_int
    for row, crow in zip(d.rows, comp.matrix.rows, strict=True):
        v = x[row.input_index].copy()
        for st, gene in zip(row.stages, crow.genes, strict=True):
            real = gene.element.realise(comp.value(gene), comp.sample_time)
            qin = to_int(v, st.fin, d.word)
            exact = real.run(to_real(qin, st.fin))
            got = to_real(run_stage(st, qin, lo, hi), st.fout)
            out.append((float(np.max(np.abs(got - exact))) / _scale(exact, st.fout), st.where))
            v = real.run(v.copy())
    return sorted(out, key=lambda e: -e[0])


def _scale(ref: np.ndarray, frac: int) -> float:
    return max(float(np.max(np.abs(ref), initial=0.0)), 2.0 ** -frac)


def culprit(d: FixedDesign, comp: Any, x: np.ndarray) -> tuple[str, str]:
    """The stage where the build leaves the double simulator, and why (for a refusal).

    The row whose output deviates most is followed stage by stage, the fixed
    chain (the bit-exact model) beside the double one on the same inputs: the
    stage named is the first whose output deviates by more than the word's
    goal of its range (else the one that grows the deviation most). The reason
    says whether the stage errs by itself (its own error, on its quantised
    input) or turns its input's small deviation into a large one (a jump, a
    relay, an integrator or a steep function).
    """
    rows, _, per = run_fixed(d, input_ints(d, x), stages=True)
    worst_row, worst = 0, -1.0
    paths = []
    for k, (row, crow) in enumerate(zip(d.rows, comp.matrix.rows, strict=True)):
        v = x[row.input_index].copy()
        ref_in = v.copy()
        rel_in = float(np.max(np.abs(to_real(to_int(v, row.stages[0].fin, d.word),
                                             row.stages[0].fin) - v))) / _scale(v, row.stages[0].fin)
        steps = []
        for st, gene, got in zip(row.stages, crow.genes, per[k], strict=True):
            real = gene.element.realise(comp.value(gene), comp.sample_time)
            ref = real.run(ref_in.copy())
            rel = float(np.max(np.abs(to_real(got, st.fout) - ref))) / _scale(ref, st.fout)
            steps.append((st, rel_in, rel))
            ref_in, rel_in = ref, rel
        paths.append(steps)
        dev = float(np.max(np.abs(to_real(rows[k], d.out_frac) - ref_in)))
        if dev > worst:
            worst_row, worst = k, dev
    steps = paths[worst_row]
    over = [s for s in steps if s[2] > d.word.goal]
    st, rel_in, rel = over[0] if over else max(steps, key=lambda s: s[2] / max(s[1], 1e-300))
    own = dict((w, e) for e, w in stage_errors(d, comp, x))[st.where]
    if own >= 0.5 * rel:
        why = f"this stage alone errs by {own:.1e} of its output's range"
    else:
        why = (f"this stage turns its input's deviation of {rel_in:.1e} of its range into "
               f"{rel:.1e} of its output's (by itself it errs by {own:.1e}: a jump, a relay, "
               "an integrator or a steep function amplifies its input's rounding)")
    return st.where, why


def check_accuracy(d: FixedDesign, comp: Any, x: np.ndarray, *, on: str = "the excitation",
                   refuse: bool = True) -> Accuracy:
    """Measure ``d`` against the double simulator on real inputs ``x`` (n_inputs, N).

    Raises
    ------
    FixedPointError
        With ``refuse``, when the measured deviation exceeds the word's goal:
        one line naming the stage where the build leaves the simulator (:func:`culprit`).
    """
    ref = simulate_rows(comp, comp.matrix.rows, x).sum(axis=0)
    _, total = run_fixed(d, input_ints(d, x))
    dev = float(np.max(np.abs(to_real(total, d.out_frac) - ref)))
    rms = float(np.sqrt(np.mean(ref ** 2)))
    acc = Accuracy(rms, d.word.goal * rms, dev, d.error, x.shape[-1])
    if refuse and dev > acc.goal:
        where, why = culprit(d, comp, x)
        raise FixedPointError(
            f"{where}: the {d.word.name} build misses the double simulator by {dev:.3g} on "
            f"{on}, more than {_goal_text(acc.goal, rms)} of the RMS ({acc.goal:.3g}); {why}; use "
            f"real=\"{'q31' if d.word.name == 'q15' else 'float'}\" or narrow the input "
            "ranges (input_range)")
    return acc


@dataclass(frozen=True)
class Build:
    """A fixed-point build with its accuracy, ready to print.

    Attributes
    ----------
    design : FixedDesign
    accuracy : Accuracy
        Measured on the synthetic excitation (the promise is checked there).
    log : Accuracy or None
        Measured on the recorded log the formats were also sized on (not
        refused: a relay whose input lingers at its threshold switches a
        sample apart), or None without a log.
    log_name : str
        The log's name ("" without one).
    log_miss : str
        Where and why the build misses its promise on the log ("" when it does not).
    signals : numpy.ndarray or None
        The log's real inputs (n_inputs, N), or None.
    """

    design: FixedDesign
    accuracy: Accuracy
    log: Accuracy | None = None
    log_name: str = ""
    log_miss: str = ""
    signals: np.ndarray | None = field(default=None, compare=False, repr=False)

    @property
    def log_kept(self) -> bool:
        """True when the build meets its promise on the log too (the kit's vectors come from it)."""
        return self.log is not None and self.log.measured <= self.accuracy.goal

    def lines(self, unit: str) -> list[str]:
        """The deviation lines the header and the command line state."""
        out = self.accuracy.lines(self.design.word.name, unit, EXCITATION)
        if self.log is not None:
            verdict = ("within the promise" if self.log_kept else
                       f"beyond the promise, from {self.log_miss}")
            out.append(f"on the log {self.log_name}: measured {self.log.measured:.3g} {unit} on "
                       f"{self.log.samples} samples, {verdict}")
        return out


def build(comp: Any, word: Any, ranges: Any, *, labels: Any = None,
          log: tuple[np.ndarray, str] | None = None) -> Build:
    """Design ``comp`` in ``word`` over ``ranges`` and check it (refusing a miss).

    Without ``log`` the internal signals are sized on the synthetic
    excitation. With ``log`` (real inputs of shape (n_inputs, N) and the
    log's name) they are sized on the excitation followed by the log (each
    format covers both), and the deviation is measured on the log as well.
    The promise is checked, and a miss refused, on the excitation.
    """
    from edm_sym.engines.fixedpoint.design import design
    from edm_sym.engines.fixedpoint.excitation import excitation
    from edm_sym.engines.fixedpoint.formats import EXCITATION_SAMPLES

    ts = comp.sample_time
    x = excitation(tuple(comp.matrix.inputs), ranges, ts, EXCITATION_SAMPLES)
    if log is None:
        d = design(comp, word, ranges, labels=labels)
        return Build(d, check_accuracy(d, comp, x))
    xl = np.asarray(log[0], dtype=float)
    d = design(comp, word, ranges, labels=labels, signals=np.hstack([x, xl]))
    acc = check_accuracy(d, comp, x)
    on_log = check_accuracy(d, comp, xl, on=f"the log {log[1]}", refuse=False)
    miss = "" if on_log.measured <= acc.goal else ": ".join(culprit(d, comp, xl))
    return Build(d, acc, on_log, log[1], miss, xl)
