"""The closing summary of the long commands (docs/cli.md#progress-and-summary).

``edm abstract``, ``edm lugre``, ``edm pipeline`` and ``edm-export`` end with
what they wrote (standard output, one file per line, as before), then a short
summary on standard error: the fitness (eq. 8, weighted, training and
validation) and the flags a user must not miss before using the model:

* parameters at their range bounds (:func:`edm_sym.core.bounds.bound_summary`),
  and LuGre shape parameters on a bound of their search box
  (:func:`edm_sym.engines.lugre.shape_bound_flags`);
* negligible rows: a row whose output's RMS is below 1 % of the target's
  (the threshold of :class:`~edm_sym.engines.symbolic.significance.SignificanceOptions`),
  measured on a log when the command has one. ``edm describe`` gives every
  flag of every row and term.

The summary is computed without sympy, so it costs a simulation of the rows
at most.
"""

from __future__ import annotations

import sys
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import IO, Any

import numpy as np

from edm_sym.core.bounds import bound_summary
from edm_sym.core.units import axis_units

__all__ = ["fitness_line", "negligible_rows", "physics_line", "physics_of", "print_summary", "result_flags",
           "with_physics"]

def fitness_line(result: Any) -> str:
    """``fitness (weighted eq. 8): training 0.0421 N m, validation 0.0433 N m``.

    Parameters
    ----------
    result : EdmResult

    Returns
    -------
    str
        The training score (the result's ``fitness`` when it holds no
        held-out validation) and the validation score, or ``validation: none
        held out``.
    """
    val = result.validation if isinstance(result.validation, Mapping) else {}
    parts = []
    for part in ("training", "validation"):
        score = val.get(part)
        if isinstance(score, Mapping) and score.get("fitness"):
            value, unit = score["fitness"]
            parts.append(f"{part} " + ("n/a (Lambda = 0 there)" if value is None
                                       else f"{value:.6g} {unit}"))
    if not parts:
        fit = result.fitness
        unit = axis_units(getattr(result, "axis", None) or "rotary").force
        parts.append("training " + ("not recorded" if fit is None else f"{fit:.6g} {unit}"))
    if len(parts) == 1:
        parts.append("validation: none held out")
    return "fitness (weighted eq. 8): " + ", ".join(parts)


def negligible_rows(result: Any, log: Any) -> list[str]:
    """The rows ``edm describe`` calls negligible on ``log``: below 1 % of the target's RMS,
    alone or with a row they cancel (:func:`edm_sym.engines.symbolic.significance.row_shares`,
    the one place of the rule).

    Parameters
    ----------
    result : EdmResult
    log : DataLog or list of DataLog
        Holds the result's inputs and target (several logs: over all, each from rest).

    Returns
    -------
    list of str
        One line per negligible row (none when the target is all zero).
    """
    from edm_sym.engines.simulate import simulate_rows
    from edm_sym.engines.symbolic.significance import SignificanceOptions, row_shares

    comp = result.compensator
    logs = list(log) if isinstance(log, list | tuple) else [log]  # several: each from rest
    target = np.concatenate([d.column(result.target, role="target column") for d in logs])
    with np.errstate(all="ignore"):
        outputs = np.concatenate([simulate_rows(comp, comp.matrix.rows, d.stack(comp.matrix.inputs))
                                  for d in logs], axis=1)
    shares = row_shares(outputs, target)
    if shares is None:
        return []
    source = " + ".join(d.source for d in logs)
    threshold = 100 * SignificanceOptions().threshold
    out = []
    for j, row in enumerate(shares):
        if not row.negligible:
            continue
        name = f"row {j + 1} ({comp.matrix.inputs[comp.matrix.rows[j].input]}) is negligible"
        if 100 * row.share < threshold:
            out.append(f"{name}: {100 * row.share:.4g} % of the target's RMS on {source} "
                       f"(threshold {threshold:g} %)")
        else:
            k, both = min(row.cancels, key=lambda c: c[1])
            out.append(f"{name}: it cancels with row {k + 1}, together {100 * both / row.ref:.4g} % "
                       f"of the target's RMS on {source} (threshold {threshold:g} %)")
    return out


def physics_of(result: Any, log: Any) -> Any:
    """The laws the model holds by its behaviour on ``log``'s motion (one log or a list).

    :func:`edm_sym.engines.physics.physics_on_log` with the shares measured on
    the whole log: what ``edm abstract`` prints and writes into result.json's
    ``physics``. None when the log has no motion to probe over.
    """
    from edm_sym.core.roles import input_roles
    from edm_sym.engines.physics import PhysicsOptions, physics_on_log
    from edm_sym.engines.simulate import simulate_rows

    comp = result.compensator
    names = comp.matrix.inputs
    role_map = input_roles(names, getattr(result, "roles", {}) or {})
    logs = list(log) if isinstance(log, list | tuple) else [log]  # several: each from rest
    xs = [lg.stack(names) for lg in logs]
    with np.errstate(all="ignore"):
        rows = np.concatenate([simulate_rows(comp, comp.matrix.rows, x) for x in xs], axis=1)
    x = np.concatenate(xs, axis=1)
    target = np.concatenate([lg.column(result.target, role="target column") for lg in logs])
    first = logs[0]
    source = ", ".join(str(lg.source) for lg in logs)
    g = first.scalars.get("observer_bandwidth")
    g = float(g) if isinstance(g, int | float) and not isinstance(g, bool) and g > 0 else None
    try:
        return physics_on_log(comp, [role_map[n] for n in names], x=x, rows=rows, target=target,
                              ts=first.ts, source=source, axis=getattr(result, "axis", "rotary"),
                              bandwidth=g, options=PhysicsOptions(), fitted=True)
    except (ValueError, np.linalg.LinAlgError):
        return None


def with_physics(result: Any, log: Any) -> tuple[Any, Any]:
    """``result`` with its ``physics`` measured on ``log`` (:func:`physics_of`), and the physics.

    An interrupted run's result is returned as it is (its model is the search's
    unfinished one, and the answer to an interrupt must not wait for probes).
    """
    from dataclasses import replace

    if result.provenance.get("stop_reason") == "interrupted":
        return result, None
    phys = physics_of(result, log)
    if phys is None:
        return result, None
    return replace(result, physics=phys.to_json()), phys


def physics_line(phys: Any) -> str | None:
    """The laws of ``phys`` (:func:`physics_of`) in one line.

    ``physics (by behaviour, over log.csv): coulomb level 0.948 N m; viscous
    coefficient 0.00506 N m s/rad``: the same laws as ``edm describe``'s
    ``physics`` (:mod:`edm_sym.engines.physics`). None without physics.
    """
    if phys is None:
        return None
    laws = "; ".join(f"{t.kind.value} " + ", ".join(f"{k.replace('_', ' ')} {v:.4g}"
                                                     + (f" {u}" if u != "1" else "")
                                                     for k, (v, u) in t.parameters.items()
                                                     if k not in ("phase", "peak", "harmonics"))
                     for t in phys.terms) or "no law above the threshold"
    return f"physics (by behaviour, over {phys.ranges.source}): {laws}"


def result_flags(result: Any, log: Any = None) -> list[str]:
    """Flags of an EDM result: parameters at a range bound, and negligible rows on ``log``.

    Parameters
    ----------
    result : EdmResult
    log : DataLog, optional
        Without it, the negligible rows are not measured (see :data:`NOT_MEASURED`).

    Returns
    -------
    list of str
    """
    lines = bound_summary(result.compensator)
    if log is not None:
        lines += negligible_rows(result, log)
    return lines


#: The summary's note when no log was at hand to measure the rows on.
NOT_MEASURED = "negligible rows: not measured (no log given; `edm describe RESULT.json` measures them)"


def print_summary(prog: str, *, fitness: Iterable[str] = (), flags: Sequence[str] = (),
                  describe: str | Path | None = None, stream: IO[str] | None = None) -> None:
    """Print the summary's fitness lines and flags, one per line, prefixed by ``prog``.

    Parameters
    ----------
    prog : str
        E.g. ``edm abstract``.
    fitness : iterable of str
        The fitness lines.
    flags : sequence of str
        Each printed as ``PROG: warning: ...``; ``flags: none`` when empty.
    describe : path-like, optional
        A result file: when there are flags, a last line points to ``edm describe`` on it.
    stream : file, optional
        Default: standard error.
    """
    stream = stream if stream is not None else sys.stderr
    for line in fitness:
        print(f"{prog}: {line}", file=stream)
    for line in flags:
        print(f"{prog}: warning: {line}", file=stream)
    if not flags:
        print(f"{prog}: flags: none", file=stream)
    elif describe is not None:
        print(f"{prog}: see `edm describe {describe}` for every row's flags", file=stream)
