"""``edm abstract``: the command-line side of the abstraction (docs/cli.md#edm-abstract).

Bad input (config, columns, options) raises :class:`~edm_sym.core.errors.ConfigError`
or :class:`~edm_sym.core.errors.DataFormatError`, which ``edm`` prints as one line
with exit status 2. A time limit ends the run with exit 0, Ctrl-C (or
SIGTERM) with exit 130; both write the best result found so far, and the
checkpoint ``<output>.checkpoint`` lets ``--resume`` continue the run to the
result an uninterrupted run gives.
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from edm_sym.core.errors import TARGET_AS_INPUT, ConfigError

if TYPE_CHECKING:
    from edm_sym.core.result import EdmResult


def checkpoint_path(output: str | Path) -> Path:
    """The checkpoint next to an output file: ``<output>.checkpoint``."""
    out = Path(output)
    return out.with_name(out.name + ".checkpoint")


def _warn_flags(result: EdmResult, output: Path, data) -> None:  # noqa: ANN001
    """The closing summary's flags: parameters at their range bounds, negligible rows."""
    from edm_sym.application.summary import print_summary, result_flags

    print_summary("edm abstract", flags=result_flags(result, data), describe=output)


def run_cli(args: argparse.Namespace) -> int:
    """Run ``edm abstract`` with parsed arguments.

    Parameters
    ----------
    args : argparse.Namespace
        ``data`` (one log or a list), ``target``, ``inputs`` (comma-separated), ``config``,
        ``seed``, ``time_limit``, ``output``, ``ts``, ``resume``, ``quiet``,
        ``workers``, ``scheduler``, ``validation_share``, ``validate``, ``select``,
        ``prune_tolerance``, ``no_prune``, ``time_column``, ``role`` (a list
        of ``COL=ROLE``), ``axis``.

    Returns
    -------
    int
        0 when done (also at the time limit), 130 when interrupted (the best
        result so far is written anyway, and the checkpoint kept).
    """
    from edm_sym.core.result import save_result
    from edm_sym.engines.abstraction.checkpoint import stray_checkpoints
    from edm_sym.engines.abstraction.parallel import Parallel
    from edm_sym.engines.abstraction.run import abstract
    from edm_sym.engines.abstraction.searches import checkpoint_files

    config, columns, target, inputs, axis = _options(args)
    names = getattr(args, "columns", None) or config.column_names
    logs, validate = _read_logs(args, config, columns, names, target=target, inputs=inputs)
    data = logs[0] if len(logs) == 1 else logs
    previous = None
    if getattr(args, "initial", None):
        from edm_sym.core.result import load_result
        from edm_sym.engines.abstraction.schedule import inherit

        previous = load_result(args.initial)
        ts = float(logs[0].ts)
        config = inherit(config, previous, inputs=inputs, axis=axis, ts=ts,
                         t_sum=max(len(log) for log in logs) * ts)
    if validate is not None:
        validate = validate()
    output = Path(args.output)
    ckpt = checkpoint_path(output)
    count = args.searches if getattr(args, "searches", None) is not None else config.searches
    if args.resume and not any(f.exists() for f in checkpoint_files(ckpt, max(1, count))) \
            and not stray_checkpoints(ckpt, max(1, count)):
        print(f"edm abstract: no checkpoint {ckpt}; starting from the beginning",
              file=sys.stderr)
    from edm_sym.application.progress import ProgressReporter

    # Ctrl-C and SIGTERM (both a KeyboardInterrupt: cli._interruptible) end the search;
    # abstract() returns the best so far and keeps the checkpoint, and it is written below.
    # An error naming a parameter (scheduler, searches, ...) is printed naming its option.
    with ProgressReporter("edm abstract", quiet=args.quiet, unit=_unit(args)) as reporter:
        result = abstract(data, target=target, inputs=inputs, config=config,
                          seed=args.seed, time_limit=args.time_limit,
                          callback=reporter.abstraction,
                          checkpoint=ckpt, resume=args.resume,
                          validate=validate, select=getattr(args, "select", None), axis=axis,
                          validation_share=getattr(args, "validation_share", None),
                          searches=getattr(args, "searches", None),
                          parallel=Parallel(workers=args.workers,
                                            scheduler=getattr(args, "scheduler", None)))
    bandwidth = getattr(args, "observer_bandwidth", None)
    if bandwidth is not None:  # not in the log: the run cannot be repeated without it
        result = replace(result, provenance={**result.provenance, "observer_bandwidth": bandwidth})
    if previous is not None:  # what the model inherited
        result = replace(result, provenance={**result.provenance, "initial": {
            "file": Path(args.initial).name, "sha256": previous.sha256}})
    from edm_sym.application.summary import with_physics

    result, phys = with_physics(result, data)
    save_result(result, output)
    return _report(result, output, data, phys)


def _options(args: argparse.Namespace) -> tuple:
    """The config with the options over it, the column roles, target, inputs and axis.

    Raises
    ------
    ConfigError
        Naming the option (``--workers``, ``--seed``, ``--validation-share``, ...).
    """
    from edm_sym.engines.abstraction.schedule import default_config, load_config

    config = load_config(args.config) if args.config else default_config()
    columns, target, inputs = resolve_columns(args, config)
    axis = getattr(args, "axis", None) or config.axis or "rotary"
    if args.workers is not None and args.workers < 1:
        raise ConfigError("--workers", f"expected an integer >= 1, found {args.workers}")
    if args.seed < 0:
        raise ConfigError("--seed", f"expected an integer >= 0, found {args.seed}")
    share = getattr(args, "validation_share", None)
    if share is not None and getattr(args, "validate", None) is not None:
        raise ConfigError("--validation-share", f"expected no share with --validate (the "
                                                f"second log is held out whole), found {share}")
    if share is not None:
        try:
            config = replace(config, validation=replace(config.validation, share=share))
        except ConfigError as exc:
            raise ConfigError("--validation-share", exc.problem) from None
    return _parsimony_options(config, args), columns, target, inputs, axis


def _read_logs(args: argparse.Namespace, config, columns, names,  # noqa: ANN001
               *, target: str, inputs: tuple[str, ...]) -> tuple[list, Any]:
    """The logs of the run, decimated as the options say and checked (the target and inputs
    in each, one sample time and roles among them), before any work; and, with
    ``--validate``, a function that reads the held-out log the same way (read after
    ``--initial`` is checked)."""
    from edm_sym.core.data import decimate, decimation_factor
    from edm_sym.engines.sources import load_data

    logs = [load_data(spec, ts=args.ts, columns=columns, names=names)
            for spec in _specs(args, config)]
    factor = getattr(args, "decimate", None)
    period = getattr(args, "decimate_to", None)
    if factor is not None and period is not None:
        raise ConfigError("--decimate-to", f"expected either --decimate or --decimate-to, "
                                           f"found both (--decimate {factor})")

    def told(log):  # noqa: ANN001, ANN202
        g = getattr(args, "observer_bandwidth", None)  # over the log's own scalar
        return log if g is None else replace(log, scalars={**log.scalars, "observer_bandwidth": g})

    def decimated(log):  # noqa: ANN001, ANN202
        if period is not None:  # each log's own factor: logs of several rates meet at one
            return decimate(log, decimation_factor(log, period, where="--decimate-to"),
                            where="--decimate-to")
        return decimate(log, factor, where="--decimate") if factor is not None else log

    logs = [told(decimated(log)) for log in logs]
    for log in logs:
        log.column(target, role="target column")
        log.stack(inputs)
    if len(logs) > 1:
        from edm_sym.core.data import join_logs

        join_logs(logs, [target, *inputs])  # one sample time and roles, before any work
    path = getattr(args, "validate", None)
    if path is None:
        return logs, None
    return logs, lambda: told(decimated(load_data(path, ts=args.ts, require=[target, *inputs],
                                                  columns=columns, names=names)))


def _report(result: EdmResult, output: Path, data, phys) -> int:  # noqa: ANN001
    """What the run wrote and found (``phys``: the physics it measured, or None), then how
    it ended; the exit status."""
    from edm_sym.application.summary import physics_line

    reason = result.provenance.get("stop_reason")
    print(f"wrote {output}")
    print(f"fitness {result.fitness:.10g}" if result.fitness is not None else "fitness inf")
    for line in summary_lines(result.validation):
        print(line)
    par = result.parsimony
    if par:
        member = par["front"][par["selected"] - 1]
        print(f"parsimony: complexity {par['search_complexity']} -> {member['complexity']} "
              f"(front member {par['selected']} of {len(par['front'])}, {par['select']})")
        for line in (start_line(par), clock_line(par)):
            if line:
                print(line)
    line = searches_line(result.provenance, par)
    if line:
        print(line)
    line = physics_line(phys)
    if line:
        print(line)
    _warn_flags(result, output, data)
    # How the run ended is the last line, after the summary's flags.
    if reason == "interrupted":
        print(f"edm abstract: interrupted; wrote the best so far to {output} "
              f"(continue with --resume)", file=sys.stderr)
    elif reason == "time_limit":
        print("edm abstract: time limit reached; wrote the best so far", file=sys.stderr)
    return 130 if reason == "interrupted" else 0


def _specs(args: argparse.Namespace, config) -> list[str]:  # noqa: ANN001
    """The logs of ``edm abstract``: DATA on the command line, else the config's ``data`` list
    (paths relative to the config file)."""
    given = args.data if isinstance(args.data, list) else [args.data] if args.data else []
    if given:
        return [str(d) for d in given]
    if config.data:
        from edm_sym.core.data import is_plant_spec

        base = Path(args.config).parent
        return [d if is_plant_spec(d) else str(base / d) for d in config.data]
    raise ConfigError("DATA", "expected one or more logs (edm abstract DATA [DATA ...], or data = "
                              "[...] in the config), found none")


def start_line(par: dict) -> str | None:
    """How the search's model was chosen, in one line (None: the result does not say).

    ``search's model: step 2 best, refitted (whole-log RMSE 0.0503 N m, held out 0.0607 N m;
    tied within 2 % with 1 other candidate: the held-out RMSE chose)``.
    """
    cands = par.get("start_candidates")
    if not cands:
        return None
    (c,) = (c for c in cands if c["chosen"])
    others = sum(1 for d in cands if d["tied"]) - 1

    def q(v: list) -> str:
        return "--" if v[0] is None else f"{v[0]:.4g} {v[1]}"

    held = "" if c["held_out_rmse"][0] is None else f", held out {q(c['held_out_rmse'])}"
    why = (f"tied within {100 * par['start_tie']:g} % with {others} other candidate"
           f"{'s' if others > 1 else ''}: the held-out RMSE chose" if others
           else f"the lowest whole-log RMSE of {len(cands)} candidates")
    return (f"search's model: step {c['step']} best{', refitted' if c['refitted'] else ''} "
            f"(whole-log RMSE {q(c['whole_rmse'])}{held}; {why})")


def clock_line(par: dict) -> str | None:
    """The rows the candidates for the search's model lost as functions of a clock, in one
    line (None: none)."""
    rows = par.get("clock_rows") or []
    cands = par.get("start_candidates") or []
    lost = [c for c in cands if c.get("clock_rows")]
    if not (rows or lost):
        return None
    parts = []
    if lost:
        parts.append(f"{len(lost)} of {len(cands)} candidates for the search's model lost "
                     f"{sum(c['clock_rows'] for c in lost)} row(s) in all")
    if rows:
        names = ", ".join(sorted({r["row"]["input"] for r in rows}))
        changes = ", ".join("--" if r["change"] is None else f"{100 * r['change']:.2g} %"
                            for r in rows)
        parts.append(f"the chosen one lost {len(rows)} on {names} (each changes by {changes} of the "
                     "target's RMS when the angle is shifted by a turn)")
    else:
        parts.append("the chosen one lost none")
    return ("clock rows: " + "; ".join(parts) + ": a function of an angle that only moves one "
            "way reads the run's time, not the axis "
            "(docs/abstraction.md#clocks-rows-that-read-time-from-the-angle)")


def searches_line(provenance: dict, par: dict) -> str | None:
    """The searches of a run with several, in one line (None: one search).

    ``searches: 2; the model is search 1's (seed 3381174520779030); lowest
    whole-log RMSE of each: 0.04995, 0.04999 N m``: how far the searches agree.
    """
    found = provenance.get("searches")
    if not found:
        return None
    (chosen,) = (s for s in found if s["chosen"])
    out = (f"searches: {len(found)}; the model is search {chosen['search']}'s "
           f"(seed {chosen['seed']})")
    cands = (par or {}).get("start_candidates") or []
    best: dict[int, float] = {}
    unit = ""
    for c in cands:
        v = c["whole_rmse"][0]
        if v is not None and "search" in c:
            best[c["search"]] = min(best.get(c["search"], v), v)
            unit = c["whole_rmse"][1]
    if best:
        out += ("; lowest whole-log RMSE of each: "
                + ", ".join(f"{best[k]:.4g}" if k in best else "--" for k in range(len(found)))
                + f" {unit}")
    return out


def _unit(args: argparse.Namespace) -> str:
    """The target's unit, for the progress lines (the axis option, when there is one)."""
    from edm_sym.core.units import axis_units

    try:
        return axis_units(getattr(args, "axis", None) or "rotary").force
    except ValueError:
        return ""


def resolve_columns(args: argparse.Namespace, config):  # noqa: ANN001, ANN201
    """The column roles, target and inputs of ``edm abstract``.

    ``--time-column`` and ``--role`` go over the config's ``[columns]``;
    ``--target`` and ``--inputs`` name the target and the inputs, or, when not
    given, the columns with the role ``target`` and the input roles
    (docs/data.md#columns-and-roles).

    Returns
    -------
    tuple
        (ColumnRoles, target, list of inputs).

    Raises
    ------
    DataFormatError, ConfigError
        A role given twice, or no target or no inputs named either way.
    """
    from edm_sym.core.data import ColumnRoles
    from edm_sym.core.result import target_name_problem

    given = ColumnRoles.parse(getattr(args, "role", None) or (),
                              time_column=getattr(args, "time_column", None), where="--role")
    columns = given.over(getattr(config, "columns", None))
    target = args.target or columns.target
    if target is None:
        raise ConfigError("--target", "expected the target column (--target COL, --role COL=target "
                                      "or [columns] in the config), found none")
    problem = target_name_problem(target)
    if problem:
        raise ConfigError("--target" if args.target else "target", f"{target!r}: {problem}")
    columns = columns.with_role(target, "target")
    if args.inputs is not None:
        inputs = [name.strip() for name in str(args.inputs).split(",")]
        if not all(inputs):
            raise ConfigError("--inputs", f"expected comma-separated column names, found "
                                          f"{args.inputs!r}")
    else:
        inputs = list(columns.inputs)
        if not inputs:
            raise ConfigError("--inputs", "expected the input columns (--inputs COL,COL, --role "
                                          "COL=position|velocity|acceleration|input or [columns] "
                                          "in the config), found none")
    if target in inputs:
        raise ConfigError("--inputs", TARGET_AS_INPUT.format(target=target))
    return columns, target, inputs


def _parsimony_options(config, args: argparse.Namespace):  # noqa: ANN001, ANN202
    from edm_sym.engines.abstraction.parsimony import check_select

    # The options change their own keys only: the config's criterion, start, refit, tie stay.
    par = config.parsimony
    tol = getattr(args, "prune_tolerance", None)
    if tol is not None:
        try:
            par = replace(par, tolerance=tol)
        except ConfigError as exc:
            raise ConfigError("--prune-tolerance", exc.problem) from None
    if getattr(args, "no_prune", False):
        par = replace(par, prune=False)
    if getattr(args, "select", None) is not None:
        check_select(args.select, "--select")
    return replace(config, parsimony=par)


def summary_lines(validation: dict) -> list[str]:
    """Closing lines of ``edm abstract``: what was held out and both scores.

    Parameters
    ----------
    validation : dict
        The ``validation`` entry of a result.

    Returns
    -------
    list of str
        E.g. ``held out: rows 800-1000 of the log (last 20 %)`` and one line
        per part with eq. 8 and the RMSE.
    """
    if not validation:
        return []
    held = validation["held_out"]
    if held["kind"] == "segment":
        out = [f"held out: rows {held['rows'][0]}-{held['rows'][1]} of the log "
               f"(last {100 * held['share']:g} %)"]
    elif held["kind"] == "blocks":
        spans = ", ".join(f"{a}-{b}" for a, b in held["blocks"][:2])
        out = [f"held out: {100 * held['share']:g} % of the log in {held['count']} blocks, one in "
               f"the middle of each {100 / held['count']:g} % (rows {spans}, ...)"]
    elif held["kind"] == "file":
        out = [f"held out: {held['file']} ({held['samples']} samples)"]
    else:
        out = ["held out: nothing (training scores only)"]
    for part in ("training", "validation"):
        score = validation.get(part)
        if score is None:
            continue
        (fit, unit), (rmse, _) = score["fitness"], score["rmse"]
        fit_text = "n/a (Lambda = 0 there)" if fit is None else f"{fit:.6g} {unit}"
        rmse_text = "inf" if rmse is None else f"{rmse:.6g} {unit}"
        out.append(f"{part}: fitness (eq. 8) {fit_text}, rmse {rmse_text}")
    return out
