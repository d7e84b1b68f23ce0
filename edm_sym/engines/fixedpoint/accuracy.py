"""The deviation of a fixed-point build from the double simulator: bound, measurement, refusal.

Two figures describe a build:

* the **a priori bound** (:attr:`FixedDesign.error`): each stage's rounding,
  coefficient and table errors propagated through the stages after it (a
  table by its steepest slope, a filter by the l1 norm of its impulse
  response), for inputs inside their formats' ranges. A switching element
  (relay, sign) after any rounding, or an integrator, leaves no finite bound:
  only measurement speaks for such a row;
* the **measured deviation**: the bit-exact model
  (:mod:`~edm_sym.engines.fixedpoint.model`) against the reference simulator
  under the switching rule (:mod:`~edm_sym.engines.fixedpoint.switching`), on
  the synthetic excitation and on the recorded log the formats were sized on;
  stated with the switching events the rule allowed and the raw deviation
  from the plain double simulator.

The export promises the word's goal (:attr:`Word.goal` of the RMS of the
compensation on the excitation) and refuses the model when a measurement
exceeds it, naming the stage where the fixed chain leaves the reference
(:func:`culprit`): the first whose output deviates by more than the goal of
its range, whether it errs by itself or amplifies its input's rounding (a
steep function after a gain).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from edm_sym.engines.fixedpoint.design import FixedDesign, FixedPointError
from edm_sym.engines.fixedpoint.formats import to_int, to_real
from edm_sym.engines.fixedpoint.model import run_fixed, run_stage
from edm_sym.engines.fixedpoint.switching import (
    SWITCH_LSB,
    Reference,
    SwitchEvent,
    describe_events,
    reference,
)

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
        The promised largest deviation (``word.goal`` times the RMS on the excitation).
    measured : float
        The largest deviation measured there, under the switching rule.
    bound : float
        The a priori bound (inf when only measurement is possible).
    samples : int
        How many samples were measured.
    raw : float
        The largest deviation from the plain double simulator (without the rule).
    events : tuple of SwitchEvent
        The switching events the rule allowed.
    """

    rms: float
    goal: float
    measured: float
    bound: float
    samples: int
    raw: float
    events: tuple[SwitchEvent, ...]

    @property
    def bounded(self) -> bool:
        """True when the a priori bound is finite."""
        return math.isfinite(self.bound)

    def lines(self, word: str, unit: str, on: str, *, switching: bool = False) -> list[str]:
        """The deviation lines the header and the command line state.

        ``switching``: the model holds a switching element (the events are stated,
        none included).
        """
        bound = (f"a priori bound {self.bound:.3g} {unit} over the input ranges" if self.bounded
                 else "no a priori bound (a switching element or an integrator): measured only")
        return [f"promised: at most {self.goal:.3g} {unit} from the double simulator "
                f"({_goal_text(self.goal, self.rms)} of the RMS {self.rms:.4g} {unit})",
                f"measured: {self.measured:.3g} {unit} ({self.measured / self.rms:.2e} of the RMS) "
                f"on {self.samples} samples of {on}, by the bit-exact model of the {word} C"
                f"{self.rule_text(unit, switching)}",
                bound]

    def rule_text(self, unit: str, switching: bool) -> str:
        """``"; 2 switching events (...); without the rule 1.2 N m"`` ("" without a switching element)."""
        if not switching:
            return ""
        if not self.events:
            return "; no switching event"
        return f"; {describe_events(self.events)}; without the rule {self.raw:.3g} {unit}"


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
    """The stage where the build leaves the reference, and why (for a refusal).

    The row whose output deviates most is followed stage by stage, the fixed
    chain (the bit-exact model) beside the reference chain under the switching
    rule, on the same inputs: the stage named is the first whose output
    deviates by more than the word's goal of its range (else the one that
    grows the deviation most). The reason says whether the stage errs by
    itself (its own error, on its quantised input) or turns its input's small
    deviation into a large one (an integrator, a steep function, or a switching
    element whose input strays further than the rule allows).
    """
    u = input_ints(d, x)
    rows, _, per = run_fixed(d, u, stages=True)
    ref = reference(d, comp, x, u, per)
    worst_row, worst = 0, -1.0
    paths = []
    for k, row in enumerate(d.rows):
        v = x[row.input_index]
        fin = row.stages[0].fin
        rel_in = float(np.max(np.abs(to_real(to_int(v, fin, d.word), fin) - v))) / _scale(v, fin)
        steps = []
        for st, got, want in zip(row.stages, per[k], ref.stages[k], strict=True):
            rel = float(np.max(np.abs(to_real(got, st.fout) - want))) / _scale(want, st.fout)
            steps.append((st, rel_in, rel))
            rel_in = rel
        paths.append(steps)
        dev = float(np.max(np.abs(to_real(rows[k], d.out_frac) - ref.stages[k][-1])))
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
               f"{rel:.1e} of its output's (by itself it errs by {own:.1e}: an integrator, a "
               "steep function or a switching element whose input strays more than "
               f"{SWITCH_LSB} LSB amplifies its input's rounding)")
    return st.where, why


def measure(d: FixedDesign, comp: Any, x: np.ndarray) -> tuple[np.ndarray, Reference]:
    """The build's total on real inputs ``x`` (reals) and the reference it is measured against."""
    u = input_ints(d, x)
    _, total, per = run_fixed(d, u, stages=True)
    return to_real(total, d.out_frac), reference(d, comp, x, u, per)


def check_accuracy(d: FixedDesign, comp: Any, x: np.ndarray, *, on: str = "the excitation",
                   refuse: bool = True, promise: float | None = None) -> Accuracy:
    """Measure ``d`` against the reference (switching rule) on real inputs ``x`` (n_inputs, N).

    The goal is ``promise`` when given (a build's promise, checked on a log),
    else the word's goal of the RMS of the double compensation on ``x``.

    Raises
    ------
    FixedPointError
        With ``refuse``, when the measured deviation exceeds the goal: one line
        naming the stage where the build leaves the reference (:func:`culprit`).
    """
    got, ref = measure(d, comp, x)
    dev = float(np.max(np.abs(got - ref.total)))
    raw = float(np.max(np.abs(got - ref.raw)))
    rms = float(np.sqrt(np.mean(ref.raw ** 2)))
    goal = d.word.goal * rms if promise is None else promise
    acc = Accuracy(rms, goal, dev, d.error, x.shape[-1], raw, ref.events)
    if refuse and dev > acc.goal:
        miss = (f"the {d.word.name} build misses the double simulator by {dev:.3g} on {on}"
                + ("" if not ref.events else
                   f" (under the switching rule, {describe_events(ref.events)})")
                + f", more than {_goal_text(acc.goal, rms) if promise is None else 'its promise'}"
                + f"{' of the RMS' if promise is None else ''} ({acc.goal:.3g})")
        outside = _outside(d, x)
        if outside:
            raise FixedPointError(f"{outside}; {miss}")
        where, why = culprit(d, comp, x)
        raise FixedPointError(
            f"{where}: {miss}; {why}; use "
            f"real=\"{'q31' if d.word.name == 'q15' else 'float'}\" or narrow the input "
            "ranges (input_range)")
    return acc


def _outside(d: FixedDesign, x: np.ndarray) -> str:
    """The first read input of ``x`` beyond its format's range (it saturates), or ""."""
    read = {row.input_index for row in d.rows}
    for i in sorted(read):
        top = d.word.max_int * 2.0 ** -d.input_fracs[i]
        peak = float(np.max(np.abs(x[i]), initial=0.0))
        if peak > top:
            name = d.inputs[i]
            lo, hi = d.ranges[name]
            return (f"inputs: {name}: reaches {peak:.6g}, beyond the range +-{top:.6g} of its "
                    f"format (from the range {lo:.6g} .. {hi:.6g}), where it saturates; widen it "
                    f"with input_range={{\"{name}\": (LO, HI)}}")
    return ""


@dataclass(frozen=True)
class Build:
    """A fixed-point build with its accuracy, ready to print.

    Attributes
    ----------
    design : FixedDesign
    accuracy : Accuracy
        Measured on the synthetic excitation (the promise is made there).
    log : Accuracy or None
        Measured on the recorded log the formats were also sized on, against
        the same promise, or None without a log.
    log_name : str
        The log's name ("" without one).
    signals : numpy.ndarray or None
        The log's real inputs (n_inputs, N), or None.
    """

    design: FixedDesign
    accuracy: Accuracy
    log: Accuracy | None = None
    log_name: str = ""
    signals: np.ndarray | None = field(default=None, compare=False, repr=False)

    def lines(self, unit: str) -> list[str]:
        """The deviation lines the header and the command line state."""
        switching = any(st.switches for row in self.design.rows for st in row.stages)
        out = self.accuracy.lines(self.design.word.name, unit, EXCITATION, switching=switching)
        if self.log is not None:
            out.append(f"on the log {self.log_name}: measured {self.log.measured:.3g} {unit} "
                       f"({self.log.measured / self.log.rms:.2e} of its RMS {self.log.rms:.4g} "
                       f"{unit}) on {self.log.samples} samples, within the promise"
                       f"{self.log.rule_text(unit, switching)}")
        if switching:
            out.append(f"switching rule: a relay or sign reads the build's own input where it "
                       f"is within {SWITCH_LSB} LSB of the double simulator's (docs/codegen.md, "
                       "The switching rule); the figures hold under it")
        return out


def build(comp: Any, word: Any, ranges: Any, *, labels: Any = None,
          log: tuple[np.ndarray, str] | None = None) -> Build:
    """Design ``comp`` in ``word`` over ``ranges`` and check it (refusing a miss).

    Without ``log`` the internal signals are sized on the synthetic
    excitation. With ``log`` (real inputs of shape (n_inputs, N) and the
    log's name) they are sized on the excitation followed by the log (each
    format covers both), and the deviation is measured on the log as well.
    The promise is made on the excitation; a miss there or on the log is refused.
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
    on_log = check_accuracy(d, comp, xl, on=f"the log {log[1]}", promise=acc.goal)
    return Build(d, acc, on_log, log[1], xl)
