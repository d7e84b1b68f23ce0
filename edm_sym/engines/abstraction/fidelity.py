"""Multi-fidelity evaluation: most individuals ranked on windows of the log, few on all of it.

A generation's new individuals are ranked on a **low-fidelity part** of the
training log: ``windows`` windows of ``samples / windows`` scored samples,
spread evenly over the samples the step's weighting fits (so they cover
every regime of the log: a staircase and a chirp alike), each simulated
after ``warm_up`` seconds of the log before it, which carry its rows'
state and are not scored. The windows are laid end to end as one signal
(:class:`WindowPlan`), so the row kernel runs them as it runs a log; the
first window starts at the log's first sample, from rest, as the log does.
Its eq. 8 ranks them: each scored sample with the step's Lambda, weighed so
the value is a stratified estimate of the whole log's (the first window's
samples as in the log, the others for the rest of it: :meth:`WindowPlan.weights`).

A new individual whose low-fidelity eq. 8 is at most ``1 + margin`` times
the largest low-fidelity eq. 8 among the current elites **may enter the
elite**: the ``promote`` lowest of them are scored on the whole training
log too (:func:`promoted`). The elites are the best by their whole-log eq. 8
(:func:`rank_multi`), so the elites, the step bests, the history and the
stopping rule see every training sample; the other places are ranked by
the low-fidelity eq. 8. The two fidelities are two evaluators with their own
stores and memos (:class:`~edm_sym.engines.abstraction.evaluator.Evaluator`),
so a cache never mixes their values.

``fidelity = "auto"`` (the default) runs ``"full"`` (every individual on every
sample, as Algorithm 1 does) when the training data holds at most
:data:`AUTO_SAMPLES` samples, and ``"multi"`` above it
(docs/abstraction.md#multi-fidelity-evaluation).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, fields
from typing import Any

import numpy as np

from edm_sym.core.errors import ConfigError
from edm_sym.engines.abstraction.tables import settings_from_table

#: The values of the config key ``fidelity``.
MODES = ("auto", "full", "multi")
#: With ``fidelity = "auto"``: the most training samples (every log together) that run
#: ``"full"``; a longer training log runs ``"multi"``.
AUTO_SAMPLES = 40_000
_KEYS = ("samples", "windows", "warm_up", "margin", "promote")


@dataclass(frozen=True)
class FidelitySettings:
    """The low-fidelity part and the promotion rule (the ``[multi_fidelity]`` table).

    Parameters
    ----------
    samples : int
        Scored samples of the low-fidelity part (>= 100), cut into ``windows``
        windows of equal length.
    windows : int
        Windows spread over the samples the step fits (>= 1).
    warm_up : float
        Seconds of the log simulated before each window (but the first, which
        starts at the log's start) and not scored: they carry the rows' state.
    margin : float
        A new individual may enter the elite when its low-fidelity eq. 8 is at
        most ``1 + margin`` times the largest one among the elites (>= 0).
    promote : int
        The most new individuals of a generation scored on the whole training
        log (>= 1), the lowest low-fidelity eq. 8 first.
    """

    samples: int = 16_000
    windows: int = 64
    warm_up: float = 0.2
    margin: float = 0.02
    promote: int = 4

    def __post_init__(self) -> None:
        for name, lo in (("samples", 100), ("windows", 1), ("promote", 1)):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int) or v < lo:
                raise ConfigError(f"multi_fidelity.{name}",
                                  f"expected an integer >= {lo}, found {v!r}")
        for name in ("warm_up", "margin"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int | float) or not (
                    math.isfinite(v) and v >= 0):
                raise ConfigError(f"multi_fidelity.{name}",
                                  f"expected a number >= 0, found {v!r}")
            object.__setattr__(self, name, float(v))
        if self.windows > self.samples:
            raise ConfigError("multi_fidelity.windows",
                              f"expected at most samples ({self.samples}), found {self.windows}")

    def to_json(self) -> dict[str, Any]:
        """The settings as a config table."""
        return {f.name: getattr(self, f.name) for f in fields(self)}


def parse_fidelity(where: str, value: Any) -> str:
    """The config key ``fidelity``: one of :data:`MODES`.

    Raises
    ------
    ConfigError
        Naming ``where``, what was expected and what was found.
    """
    if not isinstance(value, str) or value not in MODES:
        kind = {bool: "boolean", int: "integer", float: "float", str: "string", list: "array",
                dict: "table"}.get(type(value), type(value).__name__)
        found = f"{kind} {value!r}"
        raise ConfigError(where, f"expected one of {', '.join(map(repr, MODES))}, found {found}")
    return value


def parse_multi_fidelity(where: str, doc: Any) -> FidelitySettings:
    """Read the ``[multi_fidelity]`` table of a config (unknown keys and bad values refused)."""
    return settings_from_table(FidelitySettings, _KEYS, where, doc)


def effective(mode: str, n_samples: int) -> str:
    """``"full"`` or ``"multi"``: what ``mode`` runs on a training log of ``n_samples``."""
    if mode == "auto":
        return "multi" if n_samples > AUTO_SAMPLES else "full"
    return mode


def window_samples(settings: FidelitySettings, n: int, ts: float | None) -> int:
    """The most samples of the low-fidelity signal :func:`plan_windows` lays out on a
    training log of ``n`` samples: ``windows`` windows and their warm-ups, at most ``n``
    (``ts`` None: the warm-ups' length unknown, ``n``)."""
    if ts is None or not ts > 0:
        return int(n)
    length = max(1, math.ceil(settings.samples / settings.windows))
    warm = int(round(settings.warm_up / ts))
    return int(min(n, settings.windows * (length + warm)))


@dataclass(frozen=True)
class WindowPlan:
    """The low-fidelity part: windows of the training log laid end to end.

    Attributes
    ----------
    index : numpy.ndarray
        The training log's samples that make the low-fidelity signal, in order.
    scored : numpy.ndarray
        Per sample of ``index``: scored (True) or warm-up (False).
    n : int
        Samples of the training log.
    start : int
        The log's first samples the low-fidelity signal simulates exactly as
        the log does (from rest, no jump before them): the first span when it
        starts at the log's start, else 0. They stand for themselves in eq. 8;
        the other scored samples stand for the rest of the log.
    """

    index: np.ndarray
    scored: np.ndarray
    n: int
    start: int

    def __eq__(self, other: object) -> bool:
        return (isinstance(other, WindowPlan) and np.array_equal(self.index, other.index)
                and np.array_equal(self.scored, other.scored) and self.n == other.n
                and self.start == other.start)

    __hash__ = None  # type: ignore[assignment]

    def weights(self, full: np.ndarray | float) -> np.ndarray:
        """Lambda on the low-fidelity signal, so that eq. 8 (a mean over every sample)
        estimates the whole log's: a stratified estimate of the log's mean.

        The log's first ``start`` samples (simulated exactly, from rest) weigh as
        they do in the log, ``len / n`` times Lambda. The other scored samples
        stand for the rest of the log: their Lambda is scaled so that together
        they weigh what Lambda weighs over the rest of the log (times ``len /
        n``), so a constant residual scores exactly its whole-log eq. 8. The
        warm-ups weigh 0.
        """
        lam = np.asarray(full, dtype=float)
        out = np.where(self.scored, lam[self.index] if lam.ndim else lam, 0.0)
        length = len(self.index)
        first = self.index < self.start
        mass = float(np.sum(lam[self.start:])) if lam.ndim else float(lam) * (self.n - self.start)
        sampled = float(np.sum(out[~first]))
        rest = mass / sampled if sampled > 0 else 0.0
        return out * np.where(first, 1.0, rest) * (length / self.n)


def plan_windows(weights: np.ndarray | float, n: int, ts: float,
                 settings: FidelitySettings) -> WindowPlan:
    """Windows spread over the samples a step fits, each after its warm-up.

    The samples with a positive Lambda (the step's weighting times the
    held-out mask) are numbered in order; window k starts at the fitted
    sample of number ``k (P - L) / (windows - 1)`` (P fitted samples, L a
    window's length), so the first starts at the first fitted sample and the
    last ends at the last one. A window is the L samples from its start
    (held-out samples inside it weigh 0), preceded by ``warm_up`` seconds;
    overlapping spans are merged.

    Parameters
    ----------
    weights : numpy.ndarray or float
        The step's Lambda over the training samples (masked).
    n : int
        Training samples.
    ts : float
        Sample time [s].
    settings : FidelitySettings

    Returns
    -------
    WindowPlan
    """
    lam = np.broadcast_to(np.asarray(weights, dtype=float), (n,))
    fitted = np.flatnonzero(lam > 0)
    k = settings.windows
    length = max(1, math.ceil(settings.samples / k))
    warm = int(round(settings.warm_up / ts))
    if len(fitted) == 0:
        fitted = np.arange(n)
    last = max(0, len(fitted) - length)
    at = fitted[np.round(np.linspace(0, last, k)).astype(np.int64)] if k > 1 else fitted[:1]
    spans = sorted({(max(0, int(s) - warm), min(n, int(s) + length), int(s)) for s in at})
    index: list[np.ndarray] = []
    scored: list[np.ndarray] = []
    end = 0
    for lo, hi, start in spans:
        lo = max(lo, end)  # merged into the span before it
        if hi <= lo:
            continue
        idx = np.arange(lo, hi)
        index.append(idx)
        scored.append(idx >= start)
        end = hi
    # A sample scored by one window is scored even when it is another's warm-up.
    out_index = np.concatenate(index)
    out_scored = np.concatenate(scored)
    for _, hi, start in spans:
        out_scored |= (out_index >= start) & (out_index < hi)
    start = int(index[0][-1]) + 1 if len(index[0]) and int(index[0][0]) == 0 else 0
    return WindowPlan(out_index, out_scored, n=int(n), start=start)


def rank_multi(full: np.ndarray, low: np.ndarray, keys: Sequence[bytes], elites: int
               ) -> np.ndarray:
    """Order of a population, best first: the elites by whole-log eq. 8, the rest by low fidelity.

    The first ``elites`` places go to the distinct genomes with the lowest
    finite whole-log eq. 8 (``full``; ``inf`` where not scored on the whole
    log); the other individuals follow by their low-fidelity eq. 8 (``low``),
    a genome repeating one placed before going after every distinct genome
    (as :func:`~edm_sym.engines.abstraction.ga.rank`). Ties keep index order.
    """
    seen: set[bytes] = set()
    elite: list[int] = []
    for k in np.argsort(full, kind="stable").tolist():
        if len(elite) == elites or not math.isfinite(full[k]):
            break
        if keys[k] not in seen:
            seen.add(keys[k])
            elite.append(k)
    placed = set(elite)
    rest: list[int] = []
    dup: list[int] = []
    for k in np.argsort(low, kind="stable").tolist():
        if k in placed:
            continue
        (dup if keys[k] in seen else rest).append(k)
        seen.add(keys[k])
    return np.array(elite + rest + dup, dtype=np.intp)


def promoted(low: np.ndarray, reference: float | None, settings: FidelitySettings, *,
             least: int = 0, always: Sequence[int] = ()) -> list[int]:
    """Which new individuals are scored on the whole training log.

    Those whose low-fidelity eq. 8 is finite and at most ``(1 + margin)``
    times ``reference`` (the largest low-fidelity eq. 8 among the elites;
    None: no elites yet, every one qualifies), the ``promote`` lowest (at
    least ``least``: the initial population must fill the elites), ties in
    index order; plus ``always`` (the inherited model of a step's first
    population).
    """
    order = [k for k in np.argsort(low, kind="stable").tolist() if math.isfinite(low[k])]
    if reference is not None and math.isfinite(reference):
        bound = reference * (1.0 + settings.margin)
        order = [k for k in order if low[k] <= bound]
    out = order[:max(settings.promote, least)]
    out += [k for k in always if k not in out]
    return sorted(out)
