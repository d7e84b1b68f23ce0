"""Held-out validation: the part of the data the genetic algorithm never fits.

Two layouts hold out ``share`` (default 20 %) of the abstraction log:

* ``blocks`` (the default): ``blocks`` (default 10) contiguous blocks of
  equal length, one in the middle of each of ``blocks`` equal sections of
  the log, so the held-out data samples every regime of a log made of
  several experiments (a staircase and a chirp, say). The GA simulates the
  whole log (its rows need the inputs of every sample to carry their state)
  but its weighting Lambda is 0 on the held-out samples: their **target** is
  never fitted. Each block is scored after the samples before it. The cold
  start of the log is not held out: it happens once, and the GA must see it
  to learn a compensator that starts well from rest.
* ``end``: the last ``share`` of the log as one segment. The compensator is
  causal, so the GA runs on the first part alone and provably never sees the
  held-out samples. On a log whose end is one regime (the fast end of a
  chirp) the score then says little about the rest.

Why blocks are the default: with the last 20 % held out, the held-out score
of the shipped example's seeds did not follow their error on the evaluation
log, and pruning judged there made models worse (docs/abstraction.md#seed-robustness).

Scores of a model are computed by simulating the **whole** log with the
reference simulator (:mod:`edm_sym.engines.simulate`) and scoring only the samples
of one part: the training samples and the held-out ones. With a second log
(``validate=``, ``--validate FILE``) the GA fits the whole abstraction log and
every sample of the second log is scored (it is simulated from rest, like the
abstraction log).

Each score is eq. 8 with the final step's weighting Lambda (its windows in
seconds of the log scored) and the plain RMSE, both in the unit of the
target.
"""

from __future__ import annotations

import math
from collections import OrderedDict
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from edm_sym.core.data import DataLog
from edm_sym.core.errors import ConfigError, DataFormatError
from edm_sym.core.matrix import Compensator, Row
from edm_sym.engines.abstraction.poles import prefix_has_pole
from edm_sym.engines.abstraction.tables import settings_from_table
from edm_sym.engines.abstraction.weighting import Weighting
from edm_sym.engines.simulate import simulate_row

#: Largest share of a log that may be held out.
MAX_SHARE = 0.9
#: Memory bound of the row outputs a :class:`Scorer` keeps [bytes].
CACHE_BYTES = 128 * 2**20
#: How the held-out share is laid out over the log.
LAYOUTS = ("blocks", "end")
_KEYS = ("share", "layout", "blocks", "unit")


@dataclass(frozen=True)
class ValidationSettings:
    """What to hold out (the ``[validation]`` table of the config).

    Parameters
    ----------
    share : float
        Share of the abstraction log held out, in [0, 0.9] (0: nothing held
        out; ignored when a second log is given).
    layout : str
        ``"blocks"``: ``blocks`` blocks spread over the log (one in the middle
        of each of ``blocks`` equal sections); ``"end"``: one segment at the end.
    blocks : int
        Number of held-out blocks of the ``blocks`` layout (>= 1).
    unit : str or None
        Unit of the target column, written beside every fitness value;
        None: the axis's force unit (N m rotary, N linear), set by ``abstract``.
    """

    share: float = 0.2
    layout: str = "blocks"
    blocks: int = 10
    unit: str | None = None

    def __post_init__(self) -> None:
        s = self.share
        if isinstance(s, bool) or not isinstance(s, int | float) or not (
                math.isfinite(s) and 0.0 <= s <= MAX_SHARE):
            raise ConfigError("validation.share",
                              f"expected a number in [0, {MAX_SHARE:g}], found {s!r}")
        object.__setattr__(self, "share", float(s))
        if self.layout not in LAYOUTS:
            raise ConfigError("validation.layout",
                              f"expected one of {', '.join(LAYOUTS)}, found {self.layout!r}")
        b = self.blocks
        if isinstance(b, bool) or not isinstance(b, int) or b < 1:
            raise ConfigError("validation.blocks", f"expected an integer >= 1, found {b!r}")
        if self.unit is not None and (not isinstance(self.unit, str) or not self.unit.strip()):
            raise ConfigError("validation.unit", f"expected a non-empty unit, found {self.unit!r}")

    def to_json(self) -> dict[str, Any]:
        """The settings as a config table."""
        return {"share": self.share, "layout": self.layout, "blocks": self.blocks,
                **({"unit": self.unit} if self.unit is not None else {})}


def parse_validation(where: str, doc: Any) -> ValidationSettings:
    """Read the ``[validation]`` table of a config.

    Parameters
    ----------
    where : str
        ``"<file>: validation"``, for messages.
    doc : mapping
        The parsed table.

    Returns
    -------
    ValidationSettings

    Raises
    ------
    ConfigError
        Unknown key, wrong type or a value out of range.
    """
    return settings_from_table(ValidationSettings, _KEYS, where, doc)


@dataclass(frozen=True)
class Part:
    """Samples to score: ``sl`` of the simulation of the whole ``x``.

    ``sl`` is a slice or an array of sample indices (the ``blocks`` layout).

    Parameters
    ----------
    x : numpy.ndarray
        Inputs (n_inputs, N) of the log simulated (from rest).
    y : numpy.ndarray
        Its target (N,).
    t : numpy.ndarray
        Its sample times [s] (for the weighting windows).
    sl : slice or numpy.ndarray
        The samples that count (a slice, or their indices in increasing order).
    starts : tuple of int
        Where further logs begin in ``x`` (several logs laid end to end, each
        simulated from rest); empty for one log.
    """

    x: np.ndarray
    y: np.ndarray
    t: np.ndarray
    sl: slice | np.ndarray
    starts: tuple[int, ...] = ()

    @property
    def samples(self) -> int:
        """Number of samples scored."""
        if isinstance(self.sl, slice):
            return len(range(*self.sl.indices(len(self.y))))
        return len(self.sl)


@dataclass(frozen=True)
class Holdout:
    """The training data of the GA and the held-out part.

    Attributes
    ----------
    n_train : int
        The GA simulates samples ``[0, n_train)`` of the abstraction log.
    mask : numpy.ndarray or None
        Over those samples, a factor of every step's Lambda: 0 where the
        target is held out, ``n_train / n_fitted`` where the GA fits it (so the
        GA's eq. 8, a mean over every sample it simulates, is the mean over the
        fitted ones); None: it fits them all.
    training : Part
        The training samples.
    validation : Part or None
        The held-out samples (None: nothing held out).
    record : dict
        What was held out, as written to result.json (``held_out``).
    unit : str
        Unit of the target.
    """

    n_train: int
    mask: np.ndarray | None
    training: Part
    validation: Part | None
    record: dict[str, Any]
    unit: str


def _times(data: DataLog) -> np.ndarray:
    return data.times


def plan_holdout(data: DataLog, *, target: str, inputs: Sequence[str],
                 settings: ValidationSettings, validate: DataLog | None = None,
                 logs: Sequence[DataLog] = ()) -> Holdout:
    """Split the data into what the GA fits and what is held out.

    Parameters
    ----------
    data : DataLog
        The abstraction log.
    target : str
        The target column.
    inputs : sequence of str
        The input columns.
    settings : ValidationSettings
        The share held out at the end of ``data`` (unused with ``validate``).
    validate : DataLog, optional
        A second log held out as a whole; the GA then fits all of ``data``.
    logs : sequence of DataLog
        The logs ``data`` joins end to end, when several (:func:`join_logs`):
        each is simulated from rest, and the held-out blocks (or end) are laid
        out in every one of them.

    Returns
    -------
    Holdout

    Raises
    ------
    DataFormatError
        A missing column in ``validate`` or a sample time unlike ``data``'s.
    ConfigError
        A share that leaves no sample on one side.
    """
    x = data.stack(inputs)
    y = np.asarray(data.column(target, role="target column"), dtype=float)
    t = _times(data)
    n = len(y)
    unit = settings.unit
    starts = log_starts(logs)
    if validate is not None:
        if abs(float(validate.ts) - float(data.ts)) > 1e-6 * float(data.ts):
            raise DataFormatError(f"{validate.source}: sample time",
                                  f"expected {data.ts:g} s as in {data.source}, "
                                  f"found {validate.ts:g} s")
        vx = validate.stack(inputs)
        vy = np.asarray(validate.column(target, role="target column"), dtype=float)
        record = {"kind": "file", "file": validate.source, "sha256": validate.sha256,
                  "samples": len(vy)}
        return Holdout(n, None, Part(x, y, t, slice(0, n), starts),
                       Part(vx, vy, _times(validate), slice(0, len(vy))), record, unit)
    if settings.share == 0.0:
        return Holdout(n, None, Part(x, y, t, slice(0, n), starts), None, {"kind": "none"}, unit)
    if starts:
        return _in_every_log(x, y, t, settings, unit, logs, starts)
    if settings.layout == "blocks":
        return _blocks(x, y, t, settings, unit, data.source)
    n_train = int(round(n * (1.0 - settings.share)))
    if not 1 <= n_train < n:
        raise ConfigError("validation.share",
                          f"expected a share that leaves samples on both sides of the "
                          f"{n} samples of {data.source}, found {settings.share:g}")
    record = {"kind": "segment", "end": "last", "share": settings.share,
              "rows": [n_train, n], "t": [float(t[n_train]), float(t[-1])]}
    return Holdout(n_train, None, Part(x, y, t, slice(0, n_train)),
                   Part(x, y, t, slice(n_train, n)), record, unit)


def _blocks(x: np.ndarray, y: np.ndarray, t: np.ndarray, settings: ValidationSettings,
            unit: str | None, source: str = "the log") -> Holdout:
    """The ``blocks`` layout: one held-out block in the middle of each of k equal sections."""
    n = len(y)
    # A short log gets fewer blocks, each of at least one sample (the count is recorded).
    k = min(settings.blocks, max(1, int(round(n * settings.share))))
    length = int(round(n * settings.share / k))
    if not (1 <= length and k * length < n and n // k >= length):
        raise ConfigError("validation.share",
                          f"expected a share that leaves samples on both sides of the {n} "
                          f"samples of {source} (blocks of at least one sample), found "
                          f"{settings.share:g} in {k} block{'s' if k > 1 else ''}")
    held = np.zeros(n, dtype=bool)
    spans = []
    for j in range(k):
        start = (j * n // k + (j + 1) * n // k - length) // 2
        held[start:start + length] = True
        spans.append([start, start + length])
    record = {"kind": "blocks", "share": settings.share, "count": k, "blocks": spans,
              "times": [[float(t[a]), float(t[b - 1])] for a, b in spans]}
    # n / n_train on the fitted samples: eq. 8 over the whole log (what the GA computes)
    # is then the mean over the training samples alone, the training score.
    mask = np.where(held, 0.0, n / int(np.count_nonzero(~held)))
    return Holdout(n, mask, Part(x, y, t, np.flatnonzero(~held)),
                   Part(x, y, t, np.flatnonzero(held)), record, unit)


def log_starts(logs: Sequence[DataLog]) -> tuple[int, ...]:
    """Where each log after the first begins when ``logs`` are laid end to end."""
    return tuple(int(k) for k in np.cumsum([len(d) for d in logs])[:-1]) if len(logs) > 1 else ()


def _in_every_log(x: np.ndarray, y: np.ndarray, t: np.ndarray, settings: ValidationSettings,
                  unit: str | None, logs: Sequence[DataLog], starts: tuple[int, ...]) -> Holdout:
    """The held-out layout in each of several logs laid end to end: its blocks (or its end)."""
    n = len(y)
    held = np.zeros(n, dtype=bool)
    spans: list[list[int]] = []
    at = 0
    for log in logs:
        m = len(log)
        if settings.layout == "blocks":
            part = _blocks(x[:, at:at + m], y[at:at + m], t[at:at + m], settings, unit, log.source)
            local = part.record["blocks"]
        else:
            keep = int(round(m * (1.0 - settings.share)))
            if not 1 <= keep < m:
                raise ConfigError("validation.share",
                                  f"expected a share that leaves samples on both sides of the "
                                  f"{m} samples of {log.source}, found {settings.share:g}")
            local = [[keep, m]]
        for a, b in local:
            held[at + a:at + b] = True
            spans.append([at + a, at + b])
        at += m
    record = {"kind": "blocks", "share": settings.share, "count": len(spans), "blocks": spans,
              "times": [[float(t[a]), float(t[b - 1])] for a, b in spans],
              "layout": settings.layout,
              "logs": [{"file": d.source, "rows": [a, a + len(d)]}
                       for d, a in zip(logs, (0, *starts), strict=True)]}
    mask = np.where(held, 0.0, n / int(np.count_nonzero(~held)))
    return Holdout(n, mask, Part(x, y, t, np.flatnonzero(~held), starts),
                   Part(x, y, t, np.flatnonzero(held), starts), record, unit)


def mask_weights(weights: np.ndarray | float, mask: np.ndarray | None) -> np.ndarray | float:
    """A step's Lambda with the held-out samples at 0 (``weights`` itself without a mask)."""
    if mask is None:
        return weights
    return np.asarray(weights, dtype=float) * mask


class Scorer:
    """Training and validation scores of models, with row outputs cached.

    Parameters
    ----------
    holdout : Holdout
        The parts to score.
    weighting : Weighting
        Lambda of eq. 8 (the final step's).
    measure : str
        What :meth:`criterion` takes: ``"fitness"``, eq. 8 (its RMSE where Lambda
        is 0 on every sample), or ``"rmse"``, the plain RMSE.
    """

    def __init__(self, holdout: Holdout, weighting: Weighting, measure: str = "fitness"):
        self.holdout, self.weighting, self.measure = holdout, weighting, measure
        self._reference: tuple[float, float] | None = None
        self.parts = {"training": holdout.training}
        if holdout.validation is not None:
            self.parts["validation"] = holdout.validation
        self._lam = {k: weighting.weights(p.t, p.y) for k, p in self.parts.items()}
        self._rows: OrderedDict[tuple[str, Any], np.ndarray] = OrderedDict()
        longest = max(len(p.y) for p in self.parts.values())
        self._max_rows = max(16, CACHE_BYTES // (8 * longest))

    def row_output(self, comp: Compensator, part: str, row: Row) -> np.ndarray:
        """One row simulated over the whole log of ``part`` (cached by its genes)."""
        p = self.parts[part]
        key = (part if p.x is not self.holdout.training.x else "training", row)
        out = self._rows.get(key)
        if out is None:
            with np.errstate(all="ignore"):
                out = simulate_row(comp, row, p.x[row.input], starts=p.starts)
            self._rows[key] = out
            if len(self._rows) > self._max_rows:
                self._rows.popitem(last=False)
        else:
            self._rows.move_to_end(key)
        return out

    def outputs(self, comp: Compensator, part: str) -> np.ndarray:
        """The matrix output over the whole log of ``part``."""
        total = np.zeros(len(self.parts[part].y))
        for row in comp.matrix.rows:
            total = total + self.row_output(comp, part, row)
        return total

    def weights(self, part: str) -> np.ndarray | float:
        """Lambda on the scored samples of ``part`` (a float when constant)."""
        lam = self._lam[part]
        return lam[self.parts[part].sl] if isinstance(lam, np.ndarray) else lam

    def score(self, comp: Compensator, part: str) -> dict[str, Any]:
        """Eq. 8 (weighted) and the plain RMSE of ``comp`` on the samples of ``part``.

        Returns
        -------
        dict
            ``{"fitness": [value or None, unit], "rmse": [value, unit],
            "samples": count}``; the weighted value is None when Lambda is
            0 on every sample of the part. Non-finite values become None too.
        """
        p = self.parts[part]
        e = (p.y - self.outputs(comp, part))[p.sl]
        lam = self.weights(part)
        with np.errstate(all="ignore"):
            rmse = float(np.sqrt(np.mean(e * e)))
            weighted = (float(np.sqrt(np.mean(np.asarray(lam) * e * e)))
                        if np.any(np.asarray(lam) > 0) else None)
        return {"fitness": [_finite(weighted), self.holdout.unit],
                "rmse": [_finite(rmse), self.holdout.unit], "samples": p.samples}

    def criterion(self, comp: Compensator) -> float:
        """The number a simpler model must not worsen, on the held-out part.

        The plain RMSE there (``measure="rmse"``) or eq. 8 (``"fitness"``, its
        RMSE where Lambda is 0 on every held-out sample), guarded by the
        training part after :meth:`guard`; without held-out data, the same on
        the training part. Non-finite: ``inf``.
        """
        if "validation" not in self.parts:
            return self._measured(comp, "training")
        value = self._measured(comp, "validation")
        if self._reference is not None and math.isfinite(value):
            # Guarded: the training part may not worsen more than the held-out part.
            v0, t0 = self._reference
            value = v0 * max(value / v0, self._measured(comp, "training") / t0)
        return value

    def _measured(self, comp: Compensator, part: str) -> float:
        s = self.score(comp, part)
        value = s["rmse"][0]
        if self.measure == "fitness" and s["fitness"][0] is not None:
            value = s["fitness"][0]
        return float("inf") if value is None else float(value)

    def guard(self, comp: Compensator) -> None:
        """Guard :meth:`criterion` by ``comp``'s scores (the search's model).

        From then on, with held-out data, the criterion is the held-out value
        or the training value scaled to it, whichever worsened more against
        ``comp``'s: ``v0 * max(v / v0, t / t0)``. A simplification must then
        keep **both** parts within the tolerance: the held-out blocks are a
        fifth of the log, and a change they do not see (a reversal's relay,
        say) is not free because of that.
        """
        self._reference = None
        if "validation" in self.parts:
            v0, t0 = self._measured(comp, "validation"), self._measured(comp, "training")
            if all(math.isfinite(v) and v > 0 for v in (v0, t0)):
                self._reference = (v0, t0)

    def whole_rmse(self, comp: Compensator) -> float:
        """The plain RMSE over every sample of the abstraction log, fitted and held out.

        Non-finite: ``inf``.
        """
        p = self.holdout.training
        e = p.y - self.outputs(comp, "training")
        with np.errstate(all="ignore"):
            value = float(np.sqrt(np.mean(e * e)))
        return value if math.isfinite(value) else float("inf")

    def held_out_rmse(self, comp: Compensator) -> float | None:
        """The plain RMSE on the held-out samples (None: nothing held out; ``inf``: not finite)."""
        if "validation" not in self.parts:
            return None
        value = self.score(comp, "validation")["rmse"][0]
        return float("inf") if value is None else float(value)

    @property
    def criterion_name(self) -> str:
        """What :meth:`criterion` measures, as recorded in result.json."""
        part = "validation" if "validation" in self.parts else "training"
        lam = self.weights(part)
        kind = "fitness" if self.measure == "fitness" and np.any(np.asarray(lam) > 0) else "rmse"
        return f"{part}.{kind}" + ("+training" if self._reference is not None else "")

    def report(self, comp: Compensator) -> dict[str, Any]:
        """The ``validation`` entry of result.json for the exported model."""
        return {
            "held_out": dict(self.holdout.record),
            "weighting": self.weighting.to_json(),
            "training": self.score(comp, "training"),
            "validation": (self.score(comp, "validation") if "validation" in self.parts
                           else None),
        }


def fragile_rows(comp: Compensator, x: np.ndarray) -> list[int]:
    """Rows with a tangent pole inside the range their input takes in the data (0-based).

    See :mod:`edm_sym.engines.abstraction.poles`: a tangent of the row's static
    prefix whose argument crosses pi/2 + k pi for an input inside the data's
    range, on a grid of :data:`~edm_sym.engines.abstraction.poles.FINAL_GRID` points.

    Parameters
    ----------
    comp : Compensator
    x : numpy.ndarray
        The inputs (n_inputs, N) of the data.
    """
    out = []
    for j, row in enumerate(comp.matrix.rows):
        sig = np.asarray(x[row.input], dtype=float)
        sig = sig[np.isfinite(sig)]
        if sig.size >= 2 and prefix_has_pole(float(sig.min()), float(sig.max()),
                                             comp.row_elements(j), comp.sample_time):
            out.append(j)
    return out


def _finite(v: float | None) -> float | None:
    return v if v is not None and math.isfinite(v) else None
