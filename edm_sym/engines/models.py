"""A compensation model run on a log: EDM or LuGre, chosen here and nowhere else.

``edm simulate``, the pipeline's evaluation and the report's Table III all ask
the same question of a model file: which columns does it read, at which sample
time, and what compensation torque does it give on a log? :func:`load_model`
reads either kind of file (``format`` ``"edm-result"`` or ``"edm-lugre"``,
docs/result-format.md and docs/lugre.md) and :func:`model_of` wraps a loaded
result; callers then use one interface, :class:`CompensationModel`
(docs/architecture.md, "Layers").
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol

import numpy as np

from edm_sym.core.data import DataLog
from edm_sym.core.errors import ResultFormatError
from edm_sym.core.fileio import json_kind, read_json
from edm_sym.core.result import EdmResult, load_result, recorded_ranges
from edm_sym.core.roles import input_roles

__all__ = ["FORMATS", "CompensationModel", "EdmModel", "LuGreModel", "ModelRun", "load_model", "model_of"]

#: The ``format`` value of each model file kind.
FORMATS = ("edm-result", "edm-lugre")
#: An input is beyond its recorded range when it leaves it by more than this share of the
#: range's span (:meth:`EdmModel.beyond_ranges`).
BEYOND = 0.01
#: A row on the unwrapped angle of a rotary axis whose output a revolution back differs by
#: less than this share of its peak repeats: beyond the angle's range it meets nothing new
#: (``sin(7.002 theta)`` drifts 1.3 % a revolution; a dead zone on the angle differs wholly).
REPEATS = 0.05


@dataclass(frozen=True)
class ModelRun:
    """A model's output over one log.

    Attributes
    ----------
    torque : numpy.ndarray
        The compensation torque (or force), one value per sample.
    parts : mapping of str to numpy.ndarray
        Named parts that sum to it (``row_1``, ``row_2`` ... for EDM; none for LuGre).
    """

    torque: np.ndarray
    parts: Mapping[str, np.ndarray]


class CompensationModel(Protocol):
    """What every model kind offers to the commands and the report."""

    kind: str  #: "edm" or "lugre"
    name: str  #: the file (or label) named in messages
    target: str | None  #: the column the model compensates, when recorded
    inputs: tuple[str, ...]  #: the columns it reads
    sample_time: float  #: [s]
    axis: str | None  #: "rotary" or "linear"; None when the file does not record it

    def column_roles(self) -> Any:
        """The time column and roles the file records (a ColumnRoles), or None."""
        ...

    def run(self, data: DataLog | Mapping[str, np.ndarray], ts: float | None = None) -> ModelRun:
        """The model over ``data`` (which holds every column of ``inputs``)."""
        ...

    def beyond_ranges(self, data: DataLog) -> list[str]:
        """One line per input the model reads beyond what it learnt from (empty: none)."""
        ...


@dataclass(frozen=True)
class EdmModel:
    """An element-matrix compensator (an :class:`~edm_sym.core.result.EdmResult`)."""

    result: EdmResult
    name: str = "result.json"
    kind: str = "edm"

    @property
    def target(self) -> str:
        return self.result.target

    @property
    def inputs(self) -> tuple[str, ...]:
        return tuple(self.result.inputs)

    @property
    def sample_time(self) -> float:
        return float(self.result.sample_time)

    @property
    def axis(self) -> str:
        return self.result.axis

    def column_roles(self) -> Any:
        return self.result.column_roles()

    def run(self, data: DataLog | Mapping[str, np.ndarray], ts: float | None = None) -> ModelRun:
        from edm_sym.engines.simulate import simulate

        sim = simulate(self.result, data)
        parts = {f"row_{j}": row for j, row in enumerate(sim.rows, start=1)}
        return ModelRun(np.asarray(sim.total), parts)

    def beyond_ranges(self, data: DataLog) -> list[str]:
        """Where the model extrapolates on ``data``: one line per input a row reads whose
        values leave the range its column had in the abstraction log (result.json
        ``logs[].columns[].min``/``max``) by more than :data:`BEYOND` of that range's span.

        The rows compute the same formulas there, so they extrapolate what they learnt: a
        row on the unwrapped angle, say, that met 0 .. 56 rad in training, on a log that
        reaches 71. Empty when no input leaves its range or the result records none.
        """
        # Over every abstraction log the result records (several for a multi-log abstraction).
        log, ranges = recorded_ranges(self.result.logs)
        roles = input_roles(self.inputs, self.result.roles)
        out = []
        for k, name in enumerate(self.inputs):
            rows = [j for j, r in enumerate(self.result.matrix.rows, start=1) if r.input == k]
            if not rows or name not in ranges or name not in data.columns:
                continue
            low, high = ranges[name]
            margin = BEYOND * (high - low)
            x = np.asarray(data.columns[name], float)
            beyond = (x < low - margin) | (x > high + margin)
            if beyond.any() and self.axis == "rotary" and roles.get(name) == "angle":
                # A row that repeats over one revolution of the angle meets nothing new there.
                rows = [j for j in rows if not self._repeats(j - 1, x, low - margin, high + margin)]
            if beyond.any() and rows:
                out.append(f"{name} reaches {x.min():.6g} .. {x.max():.6g} in {data.source}, "
                           f"beyond its range {low:.6g} .. {high:.6g} in {log}, on "
                           f"{100 * beyond.mean():.3g} % of the samples: "
                           + (f"rows {', '.join(map(str, rows))} read it and extrapolate there"
                              if len(rows) > 1 else
                              f"row {rows[0]} reads it and extrapolates there"))
        return out

    def _repeats(self, j: int, angle: np.ndarray, low: float, high: float) -> bool:
        """Whether row ``j`` gives the same output on the angle a revolution back (forward, for
        an angle below ``low``) once a start-up has passed: ``sin(3 theta)`` does, and so does
        a velocity made as the angle's derivative; a dead zone on the angle does not. Compared
        to :data:`REPEATS` of the row's largest output, after the first tenth of the log (a filter's
        response to the shift's step at the start)."""
        from edm_sym.engines.simulate import simulate_row

        comp, row = self.result.compensator, self.result.matrix.rows[j]
        after = slice(angle.size // 10, None)
        with np.errstate(all="ignore"):
            a = simulate_row(comp, row, angle)[after]
            scale = float(np.max(np.abs(a), initial=0.0))
            for side, shift in ((angle > high, -2.0 * np.pi), (angle < low, 2.0 * np.pi)):
                if side.any():
                    b = simulate_row(comp, row, angle + shift)[after]
                    if not np.all(np.abs(a - b) <= REPEATS * scale + 1e-12):
                        return False
        return bool(np.all(np.isfinite(a)))


@dataclass(frozen=True)
class LuGreModel:
    """The LuGre baseline (a :class:`~edm_sym.engines.lugre.LuGreResult`); it reads the velocity only."""

    result: Any
    name: str = "lugre.json"
    kind: str = "lugre"

    @property
    def target(self) -> str | None:
        return self.result.target_name

    @property
    def inputs(self) -> tuple[str, ...]:
        return (self.result.velocity_name,) if self.result.velocity_name else ()

    @property
    def sample_time(self) -> float:
        return float(self.result.sample_time)

    @property
    def axis(self) -> None:
        return None  # LUGRE.json records no axis: the command's --axis says it

    def column_roles(self) -> None:
        return None

    def beyond_ranges(self, data: DataLog) -> list[str]:
        """Nothing: LUGRE.json records no ranges, and its law holds at any velocity."""
        return []

    def run(self, data: DataLog | Mapping[str, np.ndarray], ts: float | None = None) -> ModelRun:
        from edm_sym.engines.lugre import simulate_lugre

        if not self.inputs:
            raise ResultFormatError(f"{self.name}: velocity_name",
                                    "expected the velocity column's name, found none")
        columns = data.columns if isinstance(data, DataLog) else data
        step = data.ts if isinstance(data, DataLog) else (ts if ts is not None else self.sample_time)
        velocity = np.asarray(columns[self.inputs[0]], dtype=float)
        return ModelRun(np.asarray(simulate_lugre(self.result.params, velocity, step)), {})


def model_of(result: Any, name: str | None = None) -> EdmModel | LuGreModel:
    """Wrap a loaded result (EdmResult or LuGreResult) as a :class:`CompensationModel`."""
    if isinstance(result, EdmResult):
        return EdmModel(result, name or (Path(result.source).name if result.source else "result.json"))
    from edm_sym.engines.lugre import LuGreResult

    if isinstance(result, LuGreResult):
        return LuGreModel(result, name or "lugre.json")
    raise TypeError(f"expected an EdmResult or a LuGreResult, found {type(result).__name__}")


def file_format(path: str | Path) -> str:
    """The ``format`` of a model file, checked before the file is read as either kind.

    Raises
    ------
    ResultFormatError
        Unreadable file, invalid JSON, or a format that is neither kind.
    """
    path = Path(path)
    doc, _ = read_json(path, ResultFormatError)
    if not isinstance(doc, dict):
        raise ResultFormatError(f"{path.name}: (top level)",
                                f"expected a JSON object, found {json_kind(doc)}")
    kind = doc.get("format")
    if kind not in FORMATS:
        raise ResultFormatError(f"{path.name}: format",
                                f'expected "edm-result" or "edm-lugre", found {json.dumps(kind)}')
    return kind


def load_model(path: str | Path) -> EdmModel | LuGreModel:
    """Read a model file of either kind, validated completely (before any data is read)."""
    path = Path(path)
    if file_format(path) == "edm-lugre":
        from edm_sym.engines.lugre import load_lugre

        return LuGreModel(load_lugre(path), path.name)
    return EdmModel(load_result(path), path.name)
