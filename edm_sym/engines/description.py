"""``edm describe``: what a model found, without building a PDF.

:func:`describe` decodes a result, simulates its rows on a data log (the one
given, else the one the result records), and judges every row
(:mod:`edm_sym.engines.symbolic.significance`): its contribution, the physical terms
it may honestly be named by, and its flags. :class:`Description` prints as a
table for people and converts to the stable JSON shape of ``docs/describe.md``.
"""

from __future__ import annotations

import json
import math
import os
import warnings
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from edm_sym.core.bounds import complexity
from edm_sym.core.data import ColumnRoles, DataLog, drift, is_plant_spec, match_sample_time
from edm_sym.core.errors import DataFormatError
from edm_sym.core.result import EdmResult, load_result
from edm_sym.core.units import axis_units
from edm_sym.engines.physics import ranges_from_result
from edm_sym.engines.sources import load_data
from edm_sym.engines.symbolic.classify import ClassifyOptions
from edm_sym.engines.symbolic.roles import input_roles

#: The velocity range of a log: this percentile of |velocity| (a few spikes do not count).
VELOCITY_PERCENTILE = 99.0


@dataclass(frozen=True)
class RowDescription:
    """One row as ``edm describe`` shows it.

    Attributes
    ----------
    index : int
        Row number, 1-based.
    input, role : str, str or None
        The row's input and its physical role.
    expression : str
        The simplified expression with numbers (4 significant digits).
    contribution : float or None
        RMS of the row's output / RMS of the target on the data (None without data).
    terms : tuple of JudgedTerm
        The physical terms it may be named by (none when negligible).
    flags : tuple of Flag
    """

    index: int
    input: str
    role: str | None
    expression: str
    contribution: float | None
    terms: tuple[Any, ...]
    flags: tuple[Any, ...]


@dataclass(frozen=True)
class Description:
    """What a model found: rows, fitness and complexity (``edm describe``).

    Attributes
    ----------
    rows : tuple of RowDescription
    fitness : dict
        ``training``, ``validation`` (as the result records them, or None) and
        ``data`` (measured here on the data log, or None).
    complexity : int
        Active (non-``through``) elements plus state size (:func:`edm_sym.core.bounds.complexity`).
    physics : Physics or None
        The laws the whole model holds, named by its behaviour on probe motions
        (:func:`edm_sym.engines.physics.model_physics`); None when they could not
        be measured (the reason is in ``notes``).
    source : str
        The result described.
    threshold : float
        The significance threshold used (share of the target's RMS).
    notes : tuple of str
        What was assumed or could not be used, one line each.
    axis : str
        ``"rotary"`` or ``"linear"``: the units of every value.
    """

    rows: tuple[RowDescription, ...]
    fitness: Mapping[str, Any]
    complexity: int
    source: str = "<memory>"
    threshold: float = 0.01
    notes: tuple[str, ...] = field(default=())
    axis: str = "rotary"
    physics: Any = None

    def to_json(self) -> dict[str, Any]:
        """The stable JSON shape of ``edm describe --json`` (docs/describe.md)."""
        from edm_sym.engines.symbolic.significance import JudgedRow, judged_json

        rows = []
        for r in self.rows:
            terms = judged_json(JudgedRow(r.index - 1, r.contribution, r.terms, r.flags))
            rows.append({"index": r.index, "input": r.input, "expression": r.expression,
                         "contribution": r.contribution, "terms": terms,
                         "flags": [f.to_json() for f in r.flags]})
        doc = {"rows": rows, "fitness": _plain(self.fitness), "complexity": self.complexity}
        if self.physics is not None:
            doc["physics"] = self.physics.to_json()
        return doc

    def table(self) -> str:
        """The description for people: a summary table, then each row's terms and flags."""
        u = axis_units(self.axis)
        lines = [f"{self.source}: {len(self.rows)} row(s), complexity {self.complexity} "
                 f"(rows + active elements + state size); {self.axis} axis, target in {u.force}, "
                 f"position in {u.position}"]
        lines += ["fitness: " + _fitness_text(self.fitness)]
        lines += [f"note: {n}" for n in self.notes]
        head = f"{'row':>3}  {'input':<10} {'contribution':>12}  named as"
        lines += ["", head, "-" * len(head)]
        for r in self.rows:
            share = "-" if r.contribution is None else f"{100 * r.contribution:.3g} %"
            lines.append(f"{r.index:>3}  {r.input:<10} {share:>12}  {_names(r)}")
        if self.physics is not None:
            lines += ["", "physics, named by what the whole model does on probe motions:"]
            lines += self.physics.lines(self.axis)
            lines += [f"  note: {n}" for n in self.physics.notes]
        for r in self.rows:
            lines += ["", f"row {r.index}: {r.input} ({r.role or 'no role'})", f"  {r.expression}"]
            for jt in r.terms:
                params = ", ".join(f"{k.replace('_', ' ')} {v:.4g}" + (f" {unit}" if unit != "1"
                                                                           else "")
                                   for k, (v, unit) in jt.term.parameters.items())
                lines.append(f"  -> {jt.term.kind.value}" + (f": {params}" if params else ""))
                lines += [f"     ! {f.code}: {f.message}" for f in jt.flags]
            # Without data the header says so once; the per-row flag stays in the JSON.
            lines += [f"  ! {f.code}: {f.message}" for f in r.flags if f.code != "unmeasured"]
        return "\n".join(lines)


def _names(r: RowDescription) -> str:
    codes = {f.code for f in r.flags}
    if "negligible" in codes and "joint" not in codes and not r.terms:
        return "negligible"
    kinds = [jt.term.kind.value for jt in r.terms]
    text = ", ".join(dict.fromkeys(kinds)) or "nothing"
    others = sorted(codes - {"negligible", "unmeasured"})
    return text + (f"  [{', '.join(others)}]" if others else "")


def _fitness_text(fit: Mapping[str, Any]) -> str:
    parts = []
    for key in ("training", "validation"):
        v = fit.get(key)
        parts.append(f"{key} " + ("-" if not v else ", ".join(
            f"{k} {_value_text(x)}" for k, x in v.items())))
    d = fit.get("data")
    if d:
        rows = f" (held-out rows {d['rows'][0]}-{d['rows'][1]})" if d.get("rows") else ""
        parts.append(f"on {d['source']}{rows}: RMSE {_value_text(d['rmse'])}, target RMS "
                     f"{_value_text(d['target_rms'])}")
    else:
        parts.append("no data: contributions not measured (pass --data)")
    return "; ".join(parts)


def _value_text(x: Any) -> str:
    if isinstance(x, list) and len(x) == 2 and isinstance(x[1], str):
        return f"{_value_text(x[0])} {x[1]}"
    if isinstance(x, float):
        return f"{x:.4g}"
    if isinstance(x, Mapping):
        return "{" + ", ".join(f"{k} {_value_text(v)}" for k, v in x.items()) + "}"
    return str(x)


def _plain(value: Any) -> Any:
    """A JSON-safe deep copy (finite floats only; other values as text)."""
    if isinstance(value, Mapping):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, bool) or value is None or isinstance(value, (int, str)):
        return value
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    return str(value)


def _raw_document(result: EdmResult) -> dict[str, Any]:
    """The result file's JSON, to read keys EdmResult does not hold (read defensively)."""
    if not result.source:
        return {}
    try:
        doc = json.loads(Path(result.source).read_text("utf-8"))
    except (OSError, ValueError):
        return {}
    return doc if isinstance(doc, dict) else {}


def recorded_fitness(result: EdmResult) -> dict[str, Any]:
    """The training and validation scores the result records (docs/abstraction.md#held-out-validation).

    ``training`` and ``validation`` are the ``{fitness, rmse, samples}`` scores
    of result.json's ``validation`` entry, and ``held_out`` says what was held
    out; a result written without held-out validation has only its training
    eq. 8 (``{"fitness": [value, unit]}``, the axis's force unit: ``"N m"`` or
    ``"N"``) and ``validation`` null.
    """
    val = result.validation if isinstance(result.validation, Mapping) else {}
    training = val.get("training")
    if not isinstance(training, Mapping):
        training = ({"fitness": [result.fitness, result.units.force]}
                    if result.fitness is not None else None)
    validation = val.get("validation")
    held = val.get("held_out")
    return {"training": _plain(training) if training else None,
            "validation": _plain(validation) if isinstance(validation, Mapping) else None,
            "held_out": _plain(held) if isinstance(held, Mapping) else None}


def recorded_data(result: EdmResult) -> str | Path | None:
    """The data log a result records, resolved, or None.

    The evaluation log (``report_inputs.eval_data``: data the search did not
    fit) when there is one, else the abstraction log (``report_inputs.data``).
    """
    stored = getattr(result, "report_inputs", None) or {}
    spec = stored.get("eval_data", stored.get("data"))
    if spec is None:
        return None
    if is_plant_spec(spec):
        return spec
    base = Path(result.source).parent if result.source else Path(".")
    return base / spec


def held_out_rows(result: EdmResult, log: DataLog) -> tuple[int, int] | list[list[int]] | None:
    """The rows of ``log`` the search held out, when ``log`` is the log it was fitted to.

    A result that records a held-out segment (``validation.held_out``, kind
    ``segment``, rows ``[n_train, N]``) or held-out blocks (kind ``blocks``,
    ``[[start, stop], ...]``) of a log with the digest ``provenance.data_sha256``
    gives those rows (``(start, stop)`` or the list of blocks) for a log of that
    digest and length; any other log (an evaluation log, a file held out whole)
    gives None: all of it is data the search did not fit, or the caller's choice.
    """
    val = result.validation if isinstance(result.validation, Mapping) else {}
    held = val.get("held_out")
    if not isinstance(held, Mapping) or held.get("kind") not in ("segment", "blocks"):
        return None
    digest = (result.provenance or {}).get("data_sha256")
    if digest is None or log.sha256 != digest:
        return None
    pair = lambda r: (isinstance(r, list | tuple) and len(r) == 2  # noqa: E731
                      and all(isinstance(v, int) for v in r) and 0 <= r[0] < r[1] <= len(log))
    if held["kind"] == "blocks":
        blocks = held.get("blocks")
        if not (isinstance(blocks, list) and blocks and all(pair(b) for b in blocks)):
            return None
        return [list(b) for b in blocks]
    rows = held.get("rows")
    if not pair(rows) or rows[1] != len(log):
        return None
    return rows[0], rows[1]


def held_out_selector(held: tuple[int, int] | list[list[int]]) -> slice | np.ndarray:
    """The samples of :func:`held_out_rows`' answer: a slice, or the indices of the blocks."""
    if isinstance(held, tuple):
        return slice(*held)
    return np.concatenate([np.arange(a, b) for a, b in held])


def data_velocity_range(signals: Mapping[str, np.ndarray], roles: Mapping[str, str | None],
                        ts: float, part: slice | np.ndarray = slice(None)) -> float | None:
    """The velocities a log reaches: the ``VELOCITY_PERCENTILE`` of |velocity| on ``part``.

    From the inputs with the role ``velocity``, else from the differences of
    an (unwrapped) ``angle`` input; None when neither is there or it stands still.

    Parameters
    ----------
    signals : mapping of str to numpy.ndarray
        The inputs by name (whole log).
    roles : mapping of str to str or None
        Each input's role.
    ts : float
        Sample time [s].
    part : slice or numpy.ndarray
        The samples judged (the held-out rows: a slice, or indices of blocks).
    """
    found = [np.abs(np.asarray(signals[n], dtype=float)[part]) for n, r in roles.items()
             if r == "velocity" and n in signals]
    if not found:
        angles = [np.asarray(signals[n], dtype=float) for n, r in roles.items()
                  if r == "angle" and n in signals]
        if isinstance(part, slice):
            found = [np.abs(np.diff(a[part])) / ts for a in angles]
        else:  # differences within the log, taken at the judged samples (not across blocks)
            found = [np.abs(np.diff(a))[part[part < len(a) - 1]] / ts for a in angles]
    found = [f[np.isfinite(f)] for f in found if f.size > 1]
    found = [f for f in found if f.size]
    if not found:
        return None
    v = max(float(np.percentile(f, VELOCITY_PERCENTILE)) for f in found)
    return v if v > 0 and math.isfinite(v) else None


def classify_on(result: EdmResult, x: np.ndarray, *, roles: Mapping[str, str | None] | None = None,
                part: slice | np.ndarray = slice(None)) -> ClassifyOptions:
    """The classifier's options for judging ``result`` on a log: the axis's, over its velocities.

    ``edm describe`` and the report both judge through this, so they name rows alike.

    Parameters
    ----------
    result : EdmResult
    x : numpy.ndarray
        The log's inputs, stacked in the order of ``result``'s inputs (whole log).
    roles : mapping, optional
        Input roles over those the result records and the defaults.
    part : slice or numpy.ndarray
        The samples judged.
    """
    classify = ClassifyOptions.for_axis(result.axis)
    inputs = result.compensator.matrix.inputs
    role_map = input_roles(inputs, {**getattr(result, "roles", {}), **(roles or {})})
    signals = dict(zip(inputs, x, strict=True))
    v_range = data_velocity_range(signals, role_map, result.sample_time, part)
    return replace(classify, velocity_range=v_range) if v_range is not None else classify


def _load(spec: Any, result: EdmResult, ts: float | None, columns: ColumnRoles | None,
          resample: bool) -> DataLog:
    """The log on the result's grid: its recorded time column and roles under the given ones,
    its sample time if the log has none, the drift tolerance of docs/data.md."""
    if isinstance(spec, DataLog):
        from edm_sym.engines.simulate import checked_inputs

        log = spec
        checked_inputs(result.compensator, log)  # present, finite, one length, the model's Ts
        log.column(result.target, role="target column")
        log.require_finite([result.target])
    elif not isinstance(spec, str | os.PathLike):
        raise DataFormatError("data", f"expected a DataLog, a file or a plant: spec, found "
                              f"{type(spec).__name__}")
    else:
        roles = columns.over(result.column_roles()) if columns is not None else result.column_roles()
        log = load_data(spec, ts=ts, require=[*result.inputs, result.target],
                        default_ts=result.sample_time, columns=roles)
    name = Path(result.source).name if result.source else "the result"
    return match_sample_time(log, result.sample_time, model=name, resample=resample)


def describe(
    result: EdmResult | str | Path,
    data: DataLog | str | Path | None = None,
    *,
    ts: float | None = None,
    options: Any = None,
    roles: Mapping[str, str | None] | None = None,
    axis: str | None = None,
    columns: ColumnRoles | None = None,
    resample: bool = False,
    observer_bandwidth: float | None = None,
) -> Description:
    """Describe what a model found: per row its terms, contribution and flags.

    Parameters
    ----------
    result : EdmResult or path-like
        The result (a path is loaded with :func:`edm_sym.load_result`).
    data : DataLog, path-like or str, optional
        The log the contributions are measured on (a file or a
        ``plant:PRESET/EXCITATION`` spec). Default: the data the result records
        (:func:`recorded_data`: its evaluation log, else its abstraction log);
        without any, nothing is measured and every row is flagged ``unmeasured``.
        When it is the log the search was fitted to and the result records a
        held-out segment of it, only those rows are judged (:func:`held_out_rows`).
    ts : float, optional
        Sample time of a log without a time column (default: the result's).
    options : SignificanceOptions, optional
        Thresholds (:class:`edm_sym.engines.symbolic.significance.SignificanceOptions`).
    roles : mapping, optional
        Input roles over those the result records and the defaults, as for
        :func:`edm_sym.decode`.
    axis : str, optional
        ``"rotary"`` or ``"linear"`` instead of the result's ``axis`` (for a
        result written before the axis was recorded).
    columns : ColumnRoles, optional
        The log's time column and roles (``--time-column``), over those the
        result records for its abstraction log.
    resample : bool
        Resample a log whose sample time differs from the result's by more
        than the tolerance (docs/data.md#sample-time) instead of refusing it.
    observer_bandwidth : float, optional
        The bandwidth ``g`` [rad/s] of the observer that estimated the target
        (``g / (s + g)``), to name the inertia the rows hold with its lag taken
        out (:mod:`edm_sym.engines.symbolic.inertia`). Default: the one
        ``edm abstract`` was told (:attr:`EdmResult.observer_bandwidth
        <edm_sym.core.result.EdmResult.observer_bandwidth>`), else the log's
        scalar ``observer_bandwidth`` (a ``plant:`` log records its preset's);
        without any the inertia is named row by row only.

    Returns
    -------
    Description

    Raises
    ------
    ResultFormatError, DataFormatError
        A bad result file or data log (the CLI prints one line, exit 2).
    """
    from edm_sym.engines.symbolic import decode
    from edm_sym.engines.symbolic.significance import acceleration_of, judge_rows

    if not isinstance(result, EdmResult):
        result = load_result(result)
    if axis is not None:
        try:
            axis_units(axis)
        except ValueError as exc:
            raise DataFormatError("axis", str(exc)) from None
        result = replace(result, axis=axis)
    if observer_bandwidth is None:
        observer_bandwidth = result.observer_bandwidth
    log, notes = _log_of(result, data, ts, columns, resample)
    comp = result.compensator
    on = _measure(result, log) if log is not None else None
    if on is not None and drift(log.ts, result.sample_time):
        notes.append(f"sample time {log.ts:.9g} s in {log.source}, {result.sample_time:.9g} s "
                     f"in the result (relative drift {drift(log.ts, result.sample_time):.2g}, "
                     "accepted)")
    # Shapes are judged over the velocities the data reaches, not a fixed range:
    # a gentle saturation that looks viscous over +-10 rad/s acts as Coulomb at 60.
    role_map = input_roles(comp.matrix.inputs, {**getattr(result, "roles", {}), **(roles or {})})
    recorded = ranges_from_result(result, role_map)
    classify = (classify_on(result, on.x, roles=roles, part=on.part)
                if on is not None else ClassifyOptions.for_axis(result.axis))
    if on is None and recorded is not None:
        # Without data, shapes are judged over the velocities the result records, not
        # the axis's default range (+-0.5 m/s judged a +-0.13 m/s axis's Coulomb as viscous).
        classify = replace(classify, velocity_range=recorded.velocity)
    model = decode(result, roles=roles, systems=False, classify=classify)
    accelerations = inertia = None
    if on is not None:
        # Differentiated on the whole log, then cut like the rest: held-out blocks
        # joined end to end would give a spike at every join.
        accelerations = [acceleration_of(v, row.role, log.ts)
                         for v, row in zip(on.full_inputs, model.rows, strict=True)]
        if on.held is not None:
            accelerations = [a if a is None else a[on.part] for a in accelerations]
        inertia = _inertia(model, on, log, observer_bandwidth)
    judged = judge_rows(model, on.outputs if on else None, on.target if on else None,
                        on.inputs if on else None, options=options, classify=classify,
                        accelerations=accelerations, inertia=inertia)
    rows = tuple(RowDescription(row.index + 1, row.input, row.role, _expression(row.expr_numeric),
                                j.contribution, j.terms, j.flags)
                 for row, j in zip(model.rows, judged, strict=True))
    fitness = {**recorded_fitness(result), "data": on.data_fit if on else None}
    threshold = getattr(options, "threshold", 0.01) if options is not None else 0.01
    g_used = None
    if on is not None:
        g_used = observer_bandwidth if observer_bandwidth is not None else log.scalars.get(
            "observer_bandwidth")
    elif observer_bandwidth is not None:
        g_used = observer_bandwidth
    physics, note = _physics(result, role_map, recorded, threshold, g_used, log,
                             on.full_inputs if on else None, on.full_outputs if on else None,
                             on.part if on is not None and on.held is not None else slice(None))
    notes += [note] if note else []
    if log is not None:
        # The named laws come from the recorded ranges; the data's contributions do not.
        from edm_sym.engines.models import EdmModel

        notes += EdmModel(result).beyond_ranges(log)
    return Description(rows, fitness, complexity(comp), result.source or "<memory>",
                       threshold, tuple(notes), result.axis, physics)


def _log_of(result: EdmResult, data: DataLog | str | Path | None, ts: float | None,
            columns: ColumnRoles | None, resample: bool) -> tuple[DataLog | None, list[str]]:
    """The log to measure on: ``data``, else the one the result records, else None; and
    the notes (a recorded log that cannot be used is a warning and a note)."""
    if data is not None:
        return _load(data, result, ts, columns, resample), []
    spec = recorded_data(result)
    if spec is None:
        return None, []
    try:
        return _load(spec, result, ts, columns, resample), []
    except (OSError, ValueError) as exc:
        msg = f"the data the result records cannot be used ({' '.join(str(exc).split())})"
        warnings.warn(msg, stacklevel=3)
        return None, [msg]


@dataclass(frozen=True)
class _Measured:
    """The rows simulated on a log: on the part judged, and on the whole log."""

    #: The log's input columns, stacked in the model's input order.
    x: np.ndarray
    #: The row outputs, the target and each row's input on the part judged.
    outputs: np.ndarray
    target: np.ndarray
    inputs: list[np.ndarray]
    #: The same on the whole log (the held-out rows among the training ones).
    full_outputs: np.ndarray
    full_inputs: list[np.ndarray]
    #: The held-out rows judged alone (:func:`held_out_rows`), or None: the whole log.
    held: Any
    #: The part judged (a selector of the held-out rows, or every sample).
    part: Any
    #: The ``fitness.data`` entry: the log, its samples, the target's RMS and the RMSE.
    data_fit: dict[str, Any]


def _measure(result: EdmResult, log: DataLog) -> _Measured:
    """The rows simulated on ``log``; on the log the search was fitted to, judged on its
    held-out rows alone (simulated after the training rows, as the search scored them)."""
    from edm_sym.engines.simulate import simulate_rows

    comp, force = result.compensator, result.units.force
    x = log.stack(comp.matrix.inputs)
    full_outputs = outputs = simulate_rows(comp, comp.matrix.rows, x)
    target = log.column(result.target, role="target column")
    full_inputs = inputs = [x[row.input] for row in comp.matrix.rows]
    held = held_out_rows(result, log)
    part = slice(None)
    if held is not None:
        part = held_out_selector(held)
        outputs, target, inputs = outputs[:, part], target[part], [v[part] for v in inputs]
    resid = target - outputs.sum(axis=0)
    data_fit = {"source": str(log.source), "samples": len(target),
                "target_rms": [float(np.sqrt(np.mean(target ** 2))), force],
                "rmse": [float(np.sqrt(np.mean(resid ** 2))), force]}
    if held is not None:
        data_fit["rows"] = list(held) if isinstance(held, tuple) else held
    return _Measured(x, outputs, target, inputs, full_outputs, full_inputs, held, part, data_fit)


def _inertia(model: Any, on: _Measured, log: DataLog, observer_bandwidth: float | None) -> Any:
    """The inertia the rows hold together, with the observer's lag taken out
    (:func:`~edm_sym.engines.symbolic.inertia.rows_inertia`); None without a bandwidth.

    Raises
    ------
    DataFormatError
        A bandwidth (given, else the log's scalar) below 2 pi / the log's length.
    """
    from edm_sym.engines.symbolic.inertia import rows_inertia

    g = observer_bandwidth if observer_bandwidth is not None else log.scalars.get(
        "observer_bandwidth")
    if g is None:
        return None
    # An observer slower than the whole log says nothing (its lag y'/g then
    # dwarfs the rows: 1e-300 rad/s named -4.9e298 kg m^2); NaN, 0 or a negative
    # value in a log was dropped in silence.
    low = 2 * math.pi / (len(log) * log.ts)
    if isinstance(g, bool) or not isinstance(g, int | float | np.number) or not (
            math.isfinite(float(g)) and float(g) >= low):
        where = ("observer_bandwidth" if observer_bandwidth is not None
                 else f"{log.source}: observer_bandwidth")
        raise DataFormatError(where, f"expected an observer bandwidth of at least 2 pi / "
                                     f"the log's length, {low:.4g} rad/s, found {g!r}")
    return rows_inertia([row.role for row in model.rows], on.full_outputs, on.full_inputs,
                        log.ts, g, on.part)


def _physics(result: EdmResult, role_map: Mapping[str, str | None], recorded: Any,
             threshold: float, g: float | None, log: DataLog | None,
             inputs: list[np.ndarray] | None, outputs: np.ndarray | None,
             part: slice | np.ndarray) -> tuple[Any, str | None]:
    """The model's laws by behaviour (:mod:`edm_sym.engines.physics`), over the data's motion
    when there is data (its shares measured on ``part``), else over the recorded ranges;
    or None and the note that says why not."""
    from edm_sym.engines.physics import PhysicsOptions, model_physics, physics_on_log

    comp = result.compensator
    roles = [role_map[n] for n in comp.matrix.inputs]
    opts = PhysicsOptions(threshold=threshold)
    bandwidth = None if g is None else float(g)
    try:
        if log is not None and inputs is not None and outputs is not None:
            found = physics_on_log(comp, roles, x=log.stack(comp.matrix.inputs), rows=outputs,
                                   target=log.column(result.target, role="target column"),
                                   ts=log.ts, source=str(log.source), axis=result.axis,
                                   bandwidth=bandwidth, part=part, fallback=recorded, options=opts)
            if found is not None:
                return found, None
        ranges = recorded
        if ranges is None:
            return None, ("the physics is not named by behaviour: no data, and the result records "
                          "no velocity range to probe over")
        return model_physics(comp, roles, ranges, axis=result.axis, bandwidth=bandwidth,
                             options=opts), None
    except (ValueError, np.linalg.LinAlgError) as exc:
        return None, f"the physics could not be named by behaviour ({exc})"


def _expression(expr: Any) -> str:
    import sympy as sp

    if expr is None:
        return "0"
    short = expr.xreplace({f: sp.Float(f, 4) for f in expr.atoms(sp.Float)})
    return sp.sstr(short, full_prec=False)
